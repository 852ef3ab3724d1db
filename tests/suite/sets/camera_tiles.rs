//! A camera tile asked as one query (`tree.closest(&camera.tile::<L, W, H>(x, y))`) answers
//! every pixel as that pixel's own ray does: closest, any and all, at 1, 4, 8 and 16 lanes,
//! for tiles inside the image, across its edges, wholly outside it and at the last `u32`
//! columns; rows, blocks and tiles give each pixel the same ray, bit for bit.

use glam::Vec3;
use raylane::bvh::{OwnedBvh, Tri4};
use raylane::camera::block;
use raylane::mesh::Mesh;
use raylane::{Hit, Lane, Pinhole, Query, Ray};
use wide::{f32x4, f32x8, f32x16};

use crate::sets::bunny_visible_surface::load_bin;

/// Pixel `(x, y)`'s own ray.
fn ray(cam: &Pinhole, x: u32, y: u32) -> Ray {
    cam.row_packet::<f32>(x, y).ray(0)
}

fn check<L: Lane<Scalar = f32>, const W: usize, const H: usize>(
    cam: &Pinhole,
    tree: &OwnedBvh<Tri4>,
    corners: &[(u32, u32)],
) -> usize {
    let mut hits = 0;
    for &(x, y) in corners {
        let tile = cam.tile::<L, W, H>(x, y);
        let closest = tree.closest(&tile);
        let any = tree.any(&tile);
        let mut all: Vec<(u32, u32, Hit)> = Vec::new();
        tree.all(&tile, |h| all.push(h));
        let mut want_all = Vec::new();
        for dy in 0..H {
            for dx in 0..W {
                let (px, py) = (x.checked_add(dx as u32), y.checked_add(dy as u32));
                let (want, occluded) = match (px, py) {
                    (Some(px), Some(py)) => {
                        let r = ray(cam, px, py);
                        tree.all(&r, |h| want_all.push((px, py, h)));
                        (tree.closest(&r), tree.any(&r))
                    }
                    _ => (None, false),
                };
                assert_eq!(
                    closest[dy][dx],
                    want,
                    "{} lanes, pixel {dx},{dy} of tile {x},{y}",
                    L::LANES
                );
                assert_eq!(any[dy][dx], occluded);
                hits += usize::from(want.is_some());
            }
        }
        // `all`: the same hits per pixel (a packet may visit them in another order).
        let key = |h: &(u32, u32, Hit)| (h.1, h.0, h.2.t.to_bits(), h.2.index);
        all.sort_by_key(key);
        want_all.sort_by_key(key);
        assert_eq!(
            all.len(),
            want_all.len(),
            "{} lanes, tile {x},{y}",
            L::LANES
        );
        assert!(all == want_all, "{} lanes, tile {x},{y}", L::LANES);
    }
    hits
}

#[test]
fn tiles_answer_as_their_pixels() {
    let m = load_bin(include_bytes!("../../data/bunny.bin"));
    let tree = OwnedBvh::new(&Mesh::new(&m.pos, &m.idx)).unwrap();
    let (lo, hi) = m
        .pos
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), &p| (a.min(p), b.max(p)));
    let c = (lo + hi) * 0.5;
    let cam = Pinhole::look_at(
        c + Vec3::new(0.3, 0.2, 1.0) * (hi - lo).length(),
        c,
        Vec3::Y,
        40.0,
        90,
        70,
    );
    let corners = [
        (0, 0),
        (32, 16),
        (40, 24),
        (80, 64),
        (88, 68),
        (200, 200),
        (u32::MAX - 5, 30),
        (40, u32::MAX - 3),
    ];
    let n1 = check::<f32, 8, 8>(&cam, &tree, &corners);
    let n4 = check::<f32x4, 8, 8>(&cam, &tree, &corners);
    let n8 = check::<f32x8, 8, 8>(&cam, &tree, &corners);
    let n16 = check::<f32x16, 16, 16>(&cam, &tree, &corners);
    check::<f32x16, 8, 8>(&cam, &tree, &corners);
    assert!(n1 > 50 && n1 == n4 && n4 == n8, "{n1} {n4} {n8}");
    assert!(n16 > n8, "{n16}");
    assert_eq!(block::<f32>(), (1, 1));
    assert_eq!(block::<f32x4>(), (2, 2));
    assert_eq!(block::<f32x8>(), (4, 2));
    assert_eq!(block::<f32x16>(), (4, 4));
}

/// A pixel's ray is one ray, whichever packet carries it.
#[test]
fn rows_blocks_and_tiles_share_rays() {
    let cam = Pinhole::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 55.0, 37, 29);
    for y in (0..32).step_by(2) {
        for x in (0..40).step_by(4) {
            let p = cam.block_packet::<f32x8>(x, y);
            for i in 0..8 {
                let (px, py) = (x + i as u32 % 4, y + i as u32 / 4);
                let (a, b) = (p.ray(i), ray(&cam, px, py));
                assert_eq!(
                    (
                        a.origin(),
                        a.dir(),
                        a.t_min().to_bits(),
                        a.t_max().to_bits()
                    ),
                    (
                        b.origin(),
                        b.dir(),
                        b.t_min().to_bits(),
                        b.t_max().to_bits()
                    ),
                    "pixel {px},{py}"
                );
            }
        }
    }
}
