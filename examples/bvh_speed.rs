//! A quick speed check of the BVH (one thread): build time, bytes per triangle, tree depth and
//! SAH cost, and 640×480 primary rays per second on the vendored bunny (3.7k triangles) and,
//! when present, the meshes in `../shared/meshes` (skipped when absent).
//!
//! `cargo run --release --example bvh_speed` (add `RUSTFLAGS="-C target-cpu=native"` for the
//! host's widest lanes). Wall-clock figures: compare ratios within one run, not across runs.

use std::time::Instant;

use glam::Vec3;
use raylane::Pinhole;
use raylane::bvh::{self, Bvh, FocalLeaf, FocalNode, Node, Scratch, Tri4};
use raylane::mesh::Mesh;
use raylane::{Lane, Mask, Query};
use wide::{f32x4, f32x8, f32x16};

struct Model {
    name: String,
    pos: Vec<Vec3>,
    idx: Vec<[u32; 3]>,
}

fn load_bin(name: &str, b: &[u8]) -> Model {
    let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let (nv, nt) = (u32_at(0) as usize, u32_at(4) as usize);
    let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let pos = (0..nv)
        .map(|i| Vec3::new(f(8 + 12 * i), f(12 + 12 * i), f(16 + 12 * i)))
        .collect();
    let base = 8 + 12 * nv;
    let h = |o: usize| u16::from_le_bytes(b[o..o + 2].try_into().unwrap()) as u32;
    let idx = (0..nt)
        .map(|i| [h(base + 6 * i), h(base + 6 * i + 2), h(base + 6 * i + 4)])
        .collect();
    Model {
        name: name.into(),
        pos,
        idx,
    }
}

/// `v` and `f` lines of a Wavefront OBJ (polygons fanned into triangles).
fn load_obj(name: &str, text: &str) -> Model {
    let mut m = Model {
        name: name.into(),
        pos: Vec::new(),
        idx: Vec::new(),
    };
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f32> = w.take(3).filter_map(|x| x.parse().ok()).collect();
                if c.len() == 3 {
                    m.pos.push(Vec3::new(c[0], c[1], c[2]));
                }
            }
            Some("f") => {
                let i: Vec<u32> = w
                    .filter_map(|x| x.split('/').next()?.parse::<u32>().ok())
                    .map(|i| i - 1)
                    .collect();
                for k in 1..i.len().saturating_sub(1) {
                    m.idx.push([i[0], i[k], i[k + 1]]);
                }
            }
            _ => {}
        }
    }
    m
}

fn frame(m: &Model) -> Pinhole {
    let (lo, hi) = m.pos.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(l, h), &p| (l.min(p), h.max(p)),
    );
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let eye = c + Vec3::new(0.3, 0.25, 1.0).normalize() * (r * 1.7);
    Pinhole::look_at(eye, c, Vec3::Y, 45.0, 640, 480)
}

/// Rays per second of `f` over the frame's packets of `L`, and the fraction that hit.
fn run<L: Lane<Scalar = f32>>(
    cam: &Pinhole,
    mut f: impl FnMut(&raylane::RayPacket<L>) -> u32,
) -> (f64, f64) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..3 {
        hits = 0;
        let t = Instant::now();
        for y in 0..cam.height {
            for x in (0..cam.width).step_by(L::LANES) {
                hits += f(&cam.row_packet::<L>(x, y));
            }
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    let n = (cam.width * cam.height) as f64;
    (n / best / 1e6, hits as f64 / n)
}

fn packet<L: Lane<Scalar = f32>>(tree: &Bvh<Tri4>, cam: &Pinhole) -> (f64, f64) {
    run::<L>(cam, |p| tree.closest(p).mask.bits().count_ones())
}

/// Rays per second through a [`FocalBvh`] focused on the camera's eye, the focus (every node's
/// planes, and the leaves filled lazily) counted in every frame; and the leaves filled.
fn focal<L: Lane<Scalar = f32>>(
    tree: &Bvh<Tri4>,
    cam: &Pinhole,
    fnodes: &mut [FocalNode],
    fleaves: &mut [FocalLeaf<Tri4>],
) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut filled = 0;
    for _ in 0..3 {
        let t = Instant::now();
        let f = tree.focus(cam.eye, fnodes, fleaves).unwrap();
        let mut hits = 0u32;
        for y in 0..cam.height {
            for x in (0..cam.width).step_by(L::LANES) {
                let p = cam.row_packet::<L>(x, y);
                hits += if L::LANES == 1 {
                    f.closest(&p.ray(0)).is_some() as u32
                } else {
                    f.closest(&p).mask.bits().count_ones()
                };
            }
        }
        best = best.min(t.elapsed().as_secs_f64());
        filled = f.filled();
        std::hint::black_box(hits);
    }
    ((cam.width * cam.height) as f64 / best / 1e6, filled)
}

fn main() {
    let mut models = vec![load_bin(
        "vendored bunny",
        include_bytes!("../tests/data/bunny.bin"),
    )];
    for name in ["stanford-bunny", "spot", "fandisk"] {
        let path = format!("../shared/meshes/{name}.obj");
        match std::fs::read_to_string(&path) {
            Ok(text) => models.push(load_obj(name, &text)),
            Err(_) => println!("({path} absent: skipped)"),
        }
    }
    println!(
        "| mesh | triangles | build ms | bytes/tri | nodes | leaves | depth | SAH | 1 ray Mrays/s | x4 | x8 | x16 | any 1 ray | hit % |"
    );
    println!(
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    let mut focal_rows = Vec::new();
    for m in &models {
        let mesh = Mesh::new(&m.pos, &m.idx);
        let need = bvh::needed(m.idx.len());
        let mut nodes = vec![Node::EMPTY; need.nodes];
        let mut leaves = vec![<Tri4 as bvh::Packed>::EMPTY; need.leaves];
        let mut scratch = vec![Scratch::default(); need.scratch];
        let mut build_s = f64::INFINITY;
        let mut used = (0, 0);
        for _ in 0..3 {
            let t = Instant::now();
            let b = bvh::build(&mesh, &mut nodes, &mut leaves, &mut scratch).unwrap();
            build_s = build_s.min(t.elapsed().as_secs_f64());
            used = (b.nodes().len(), b.leaves().len());
        }
        let tree = Bvh::from_parts(&nodes[..used.0], &leaves[..used.1]).unwrap();
        let st = tree.stats();
        let cam = frame(m);
        let (single, frac) = run::<f32>(&cam, |p| tree.closest(&p.ray(0)).is_some() as u32);
        let (x4, _) = packet::<f32x4>(&tree, &cam);
        let (x8, _) = packet::<f32x8>(&tree, &cam);
        let (x16, _) = packet::<f32x16>(&tree, &cam);
        let (any1, _) = run::<f32>(&cam, |p| tree.any(&p.ray(0)) as u32);
        if m.idx.len() < 10_000 {
            // Brute force over the same rows (every 16th), same kernel, packets of 8.
            let tris: Vec<_> = (0..mesh.len()).filter_map(|i| mesh.triangle(i)).collect();
            let t = Instant::now();
            let mut n = 0u32;
            for y in (0..cam.height).step_by(16) {
                for x in (0..cam.width).step_by(8) {
                    n += tris[..]
                        .closest(&cam.row_packet::<f32x8>(x, y))
                        .mask
                        .bits()
                        .count_ones();
                }
            }
            let flat = (cam.width * cam.height / 16) as f64 / t.elapsed().as_secs_f64() / 1e6;
            println!(
                "({}: brute force x8 {flat:.3} Mrays/s, {n} hits; BVH x8 {x8:.2}: {:.0}x)",
                m.name,
                x8 / flat
            );
        }
        let (fn_, fl) = bvh::focal_needed(&tree);
        let mut fnodes = vec![FocalNode::EMPTY; fn_];
        let mut fleaves = vec![FocalLeaf::EMPTY; fl];
        let (f1, filled) = focal::<f32>(&tree, &cam, &mut fnodes, &mut fleaves);
        let (f4, _) = focal::<f32x4>(&tree, &cam, &mut fnodes, &mut fleaves);
        let (f8, _) = focal::<f32x8>(&tree, &cam, &mut fnodes, &mut fleaves);
        let (f16, _) = focal::<f32x16>(&tree, &cam, &mut fnodes, &mut fleaves);
        focal_rows.push(format!(
            "| {} | {single:.2} | {f1:.2} | {x4:.2} | {f4:.2} | {x8:.2} | {f8:.2} | {x16:.2} | {f16:.2} | {filled} of {} |",
            m.name,
            st.leaves
        ));
        println!(
            "| {} | {} | {:.1} | {:.1} | {} | {} | {} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} |",
            m.name,
            m.idx.len(),
            build_s * 1e3,
            st.bytes as f64 / m.idx.len() as f64,
            st.nodes,
            st.leaves,
            st.depth,
            st.sah,
            single,
            x4,
            x8,
            x16,
            any1,
            frac * 100.0
        );
    }
    println!(
        "\nFocal mode (focus counted in every frame), Mrays/s:\n\n| mesh | 1 ray | focal | x4 | focal x4 | x8 | focal x8 | x16 | focal x16 | leaves filled |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for r in &focal_rows {
        println!("{r}");
    }
}
