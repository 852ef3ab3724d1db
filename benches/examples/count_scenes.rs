//! Instructions per ray through whole scenes, counted by callgrind (`scripts/count-scenes.sh`):
//! raylane's BVH (one ray, packets of 8 and 16, camera tiles, the baked flash layout) and
//! Embree (`rtcIntersect1/8/16`, `rtcOccluded1/8`) over the same rays of the vendored bunny
//! (3,674 triangles) framed as in the scenes benchmark: 640 × 480 primary rays in tiles of
//! 4 × 4 blocks, one diffuse bounce and one shadow ray per primary hit.
//!
//! `count_scenes measure` runs each frame once as one call of the out-of-line `scene_frame`
//! and prints a line per call, `NAME RAYS`; the script collects inside those calls only and
//! dumps after each one, so dump k holds the instructions of call k.
//! `count_scenes table FILE` turns `NAME RAYS INSTRUCTIONS` lines into the Markdown table.

use std::hint::black_box;

use raylane::bvh::{Bvh, OwnedBvh, Tri4};
use raylane::hit::Closest;
use raylane::mesh::Mesh;
use raylane::set::Trace;
use raylane::simd::{self, Packets};
use raylane::triangle::Moller;
use raylane::{Lane, Mask, Pinhole, Query, Ray, RayPacket};
use raylane_bench::bvh_peers::{EmbreeBvh, EmbreeRays};
use raylane_bench::bvh_raylane as rl;
use raylane_bench::meshes::{self, SurfaceHit, Workload};
use wide::{f32x8, f32x16};

/// One frame, out of line: the only code callgrind counts.
#[inline(never)]
fn scene_frame(f: &dyn Fn() -> u32) -> u32 {
    f()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("measure") => measure(),
        Some("table") => table(&args[2], args.get(3).map_or("", String::as_str)),
        _ => {
            eprintln!("usage: count_scenes measure | table FILE [TITLE]");
            std::process::exit(2);
        }
    }
}

fn measure() {
    let m = meshes::vendored_bunny();
    let (centre, radius) = m.bounds();
    let cam = meshes::framing(centre, radius);
    let mesh = Mesh::new(&m.positions, &m.indices);
    let owned = OwnedBvh::<Tri4>::new(&mesh).expect("the bunny builds");
    let tree = owned.view();
    let bytes = raylane::bvh::bake::bake(&mesh).expect("the bunny bakes");
    let words: Vec<u32> = bytes
        .chunks(4)
        .map(|c| {
            let mut b = [0u8; 4];
            b[..c.len()].copy_from_slice(c);
            u32::from_le_bytes(b)
        })
        .collect();
    let view: &[u8] = bytemuck_bytes(&words, bytes.len());
    let baked = raylane::bvh::bake::Baked::open(view).expect("a bake opens");
    // The secondary rays from raylane's primary hits (the same as Embree's: the scenes
    // benchmark checks that they agree).
    let primary = Workload::primary(&cam);
    let hits: Vec<SurfaceHit> = primary
        .iter()
        .map(|r| tree.closest(r).map(|h| (h.t, h.normal)))
        .collect();
    let mut w = Workload::new(cam, &hits, centre, radius);
    w.primary = Workload::tiled(&w.cam);
    let mut ebr = EmbreeBvh::mesh(&m, true);
    let (p, d, s) = (&w.primary[..], &w.diffuse[..], &w.shadow[..]);
    let (p8, p16) = (rl::packets::<f32x8>(p), rl::packets::<f32x16>(p));
    let (d8, s8) = (rl::packets::<f32x8>(d), rl::packets::<f32x8>(s));
    let (ep, ed, es) = (EmbreeRays::new(p), EmbreeRays::new(d), EmbreeRays::new(s));
    let run = |name: &str, rays: usize, f: &dyn Fn() -> u32| {
        println!("{} {rays}", name.replace(' ', "_"));
        black_box(scene_frame(f));
    };
    let cam = &w.cam;
    run("primary raylane BVH x1", p.len(), &|| {
        rl::bvh_closest1(&tree, p, None)
    });
    run("primary raylane BVH x8", p.len(), &|| {
        rl::bvh_closest(&tree, &p8, p.len(), None)
    });
    run("primary raylane BVH x16", p.len(), &|| {
        rl::bvh_closest(&tree, &p16, p.len(), None)
    });
    run("primary raylane BVH tiles 16×16 x16", p.len(), &|| {
        rl::bvh_tiles::<f32x16, 16>(&tree, cam, (0, 1), None)
    });
    // Where a primary packet's instructions go: the same blocks of 16 at the SIMD level, made
    // from the camera alone, traced without records, and traced with records.
    for part in [Part::Rays, Part::Load, Part::Trace, Part::Records] {
        run(part.name(), p.len(), &|| {
            simd::with_lanes(
                16,
                Split {
                    tree: &tree,
                    cam,
                    rays: p,
                    part,
                },
            )
        });
    }
    let m = tree.using::<Moller>();
    run("primary raylane BVH Möller x1", p.len(), &|| {
        rl::bvh_closest1(&m, p, None)
    });
    run("primary raylane BVH Möller x16", p.len(), &|| {
        rl::bvh_closest(&m, &p16, p.len(), None)
    });
    run("primary raylane baked x1", p.len(), &|| {
        rl::bvh_closest1(&baked, p, None)
    });
    run("primary Embree rtcIntersect1", p.len(), &|| {
        ebr.intersect1(&ep, None)
    });
    run("primary Embree rtcIntersect8", p.len(), &|| {
        ebr.intersect8(&ep, None)
    });
    run("primary Embree rtcIntersect16", p.len(), &|| {
        ebr.intersect16(&ep, None)
    });
    ebr.set_coherent(false);
    run("diffuse raylane BVH x1", d.len(), &|| {
        rl::bvh_closest1(&tree, d, None)
    });
    run("diffuse raylane BVH x8", d.len(), &|| {
        rl::bvh_closest(&tree, &d8, d.len(), None)
    });
    run("diffuse raylane BVH Möller x1", d.len(), &|| {
        rl::bvh_closest1(&m, d, None)
    });
    run("diffuse Embree rtcIntersect1", d.len(), &|| {
        ebr.intersect1(&ed, None)
    });
    run("shadow raylane BVH any x1", s.len(), &|| {
        rl::bvh_any1(&tree, s, None)
    });
    run("shadow raylane BVH any x8", s.len(), &|| {
        rl::bvh_any(&tree, &s8, s.len(), None)
    });
    run("shadow raylane BVH Möller any x8", s.len(), &|| {
        rl::bvh_any(&m, &s8, s.len(), None)
    });
    run("shadow Embree rtcOccluded1", s.len(), &|| {
        ebr.occluded1(&es, None)
    });
    run("shadow Embree rtcOccluded8", s.len(), &|| {
        ebr.occluded8(&es, None)
    });
}

/// What [`Split`] runs for each block of 16 primary rays.
#[derive(Clone, Copy)]
enum Part {
    /// The block's rays made from the camera (`Pinhole::block_packet`).
    Rays,
    /// The block's rays loaded from the frame's rays (`RayPacket::from_rays`), what the next
    /// two parts start with.
    Load,
    /// The block traced into a closest-hit collector (`Trace::trace`), no records.
    Trace,
    /// The same, then the winners' records (`Trace::records`).
    Records,
}

impl Part {
    fn name(self) -> &'static str {
        match self {
            Part::Rays => "primary raylane x16 split: rays made from the camera",
            Part::Load => "primary raylane x16 split: rays loaded",
            Part::Trace => "primary raylane x16 split: rays loaded, BVH traced, no records",
            Part::Records => "primary raylane x16 split: rays loaded, BVH traced, records",
        }
    }
}

/// A primary frame's blocks of 16 at the SIMD level, in parts (see [`Part`]): the BVH x16
/// row's instructions are the traced packets', their records', and the query's entry.
struct Split<'a> {
    tree: &'a Bvh<'a, Tri4>,
    cam: &'a Pinhole,
    rays: &'a [Ray],
    part: Part,
}

impl Packets for Split<'_> {
    type Output = u32;
    #[inline(always)]
    fn run<L: Lane<Scalar = f32>>(self) -> u32 {
        let mut n = 0;
        match self.part {
            Part::Rays => {
                let (w, h) = (self.cam.width / 4, self.cam.height / 4);
                for k in 0..w * h {
                    let r = self.cam.block_packet::<L>((k % w) * 4, (k / w) * 4);
                    black_box(&r);
                    n += 1;
                }
            }
            Part::Load => {
                for chunk in self.rays.chunks(16) {
                    black_box(RayPacket::<L>::from_rays(chunk));
                    n += 1;
                }
            }
            Part::Trace | Part::Records => {
                for chunk in self.rays.chunks(16) {
                    let r = black_box(RayPacket::<L>::from_rays(chunk));
                    let mut c = Closest::new(&r);
                    self.tree.trace(&r, 0, &mut c);
                    let w = c.finish();
                    if let Part::Records = self.part {
                        let h = self.tree.records(&r, 0, &w);
                        n += h.mask.bits().count_ones();
                        black_box(&h);
                    } else {
                        black_box(&w);
                        n += 1;
                    }
                }
            }
        }
        n
    }
}

/// `words` as its first `len` bytes.
fn bytemuck_bytes(words: &[u32], len: usize) -> &[u8] {
    // SAFETY: u32 storage viewed as bytes (u8 has no alignment), len ≤ 4·words.len().
    unsafe { std::slice::from_raw_parts(words.as_ptr().cast::<u8>(), len.min(4 * words.len())) }
}

fn table(file: &str, title: &str) {
    let text = std::fs::read_to_string(file).expect("the counts file");
    println!(
        "Instructions per ray, {title}: the vendored bunny (3,674 triangles), 640 × 480 primary rays in 4 × 4 blocks, one diffuse and one shadow ray per primary hit; each frame one call, counted by callgrind.\n"
    );
    println!("| rays | contender | rays traced | instructions per ray |");
    println!("| --- | --- | ---: | ---: |");
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        let [name, rays, n] = f[..] else { continue };
        let (rays, n): (f64, f64) = (
            rays.parse().unwrap_or(f64::NAN),
            n.parse().unwrap_or(f64::NAN),
        );
        let name = name.replace('_', " ");
        let (kind, who) = name.split_once(' ').unwrap_or(("", &name));
        println!("| {kind} | {who} | {rays} | {:.0} |", n / rays);
    }
}
