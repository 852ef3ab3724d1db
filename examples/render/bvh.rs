//! Scenes 5 and 6 and `--obj FILE`: triangle meshes traced through raylane's BVH
//! ([`raylane::bvh`]), one primary ray and one shadow ray (any hit, to a point light) per
//! pixel, packets of `L` rays, rows shared out to every core.
//!
//! 5. `5-bunny.png`: the vendored Stanford bunny (`tests/data/bunny.bin`, 3,674 triangles);
//! 6. `6-million.png`: the same bunny after 4 Loop subdivision steps (940,544 triangles,
//!    `benches/src/subdivide.rs`), made here in about a second;
//!
//! and `--obj FILE` any Wavefront OBJ (loaded with `tobj`, a dev-dependency used only here).
//! The tree is built on one thread ([`raylane::bvh::OwnedBvh`]); primary rays and shadow rays
//! are timed as two separate passes, each on every core, and reported in Mrays/s.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;
use raylane::bvh::TriangleBvh;
use raylane::triangle::Triangle;
use raylane::{Lane, Pinhole, Query, Ray, RayPacket};

use super::subdivide;

/// An indexed triangle mesh.
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub indices: Vec<[u32; 3]>,
}

impl MeshData {
    /// The vendored bunny.
    pub fn bunny() -> Self {
        let (positions, indices) =
            subdivide::load_bunny_bin(include_bytes!("../../tests/data/bunny.bin"))
                .expect("tests/data/bunny.bin is well formed");
        MeshData { positions, indices }
    }

    /// The vendored bunny after `steps` Loop subdivision steps.
    pub fn subdivided_bunny(steps: u32) -> Self {
        let b = Self::bunny();
        let (positions, indices) = subdivide::loop_subdivide(&b.positions, &b.indices, steps);
        MeshData { positions, indices }
    }

    /// Every triangle of an OBJ file (polygons triangulated, all models).
    pub fn obj(path: &Path) -> Result<Self, String> {
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(path, &opts).map_err(|e| e.to_string())?;
        let mut m = MeshData {
            positions: Vec::new(),
            indices: Vec::new(),
        };
        for model in models {
            let base = m.positions.len() as u32;
            let p = &model.mesh.positions;
            m.positions
                .extend(p.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
            m.indices.extend(
                model
                    .mesh
                    .indices
                    .chunks_exact(3)
                    .map(|c| [base + c[0], base + c[1], base + c[2]]),
            );
        }
        if m.indices.is_empty() {
            return Err("no triangles".into());
        }
        Ok(m)
    }

    /// The triangles (an index out of range gives a triangle that is never hit).
    pub fn triangles(&self) -> Vec<Triangle> {
        let p = |i: u32| self.positions.get(i as usize).copied();
        self.indices
            .iter()
            .map(|&[a, b, c]| match (p(a), p(b), p(c)) {
                (Some(a), Some(b), Some(c)) => Triangle::new(a, b, c),
                _ => Triangle::never(),
            })
            .collect()
    }
}

/// The camera framing a mesh from the front (+z), slightly above and to the right.
pub fn framing(m: &MeshData, width: u32, height: u32) -> (Pinhole, Vec3, f32) {
    let (lo, hi) = m.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let (centre, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let fov = 40f32;
    let dist = radius / (fov.to_radians() * 0.5).sin() * 0.75;
    let dir = Vec3::new(0.25, 0.3, 1.0).normalize();
    let cam = Pinhole::look_at(centre + dir * dist, centre, Vec3::Y, fov, width, height);
    (cam, centre, radius)
}

/// What one render measured.
pub struct Shot {
    /// The image, RGB.
    pub rgb: Vec<u8>,
    /// Primary rays traced and their wall time.
    pub primary: (u64, Duration),
    /// Shadow rays traced and their wall time.
    pub shadow: (u64, Duration),
}

/// Runs `f(row)` for every row on `threads` threads; returns the rows' results in order and
/// the wall time.
fn rows<T: Send>(height: u32, threads: usize, f: impl Fn(u32) -> T + Sync) -> (Vec<T>, Duration) {
    let next = AtomicUsize::new(0);
    let start = Instant::now();
    let mut all: Vec<(u32, T)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let y = next.fetch_add(1, Ordering::Relaxed) as u32;
                        if y >= height {
                            break;
                        }
                        out.push((y, f(y)));
                    }
                    out
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a render thread panicked"))
            .collect()
    });
    let time = start.elapsed();
    all.sort_by_key(|r| r.0);
    (all.into_iter().map(|r| r.1).collect(), time)
}

/// Renders `tris` through `tree` with `L`-ray packets on `threads` threads: primary rays,
/// then one shadow ray per hit pixel to `light`, then Lambert shading (white light, grey
/// ambient) by the geometric normal facing the eye.
pub fn render<L: Lane<Scalar = f32>>(
    tree: &TriangleBvh,
    tris: &[Triangle],
    cam: &Pinhole,
    light: Vec3,
    eps: f32,
    threads: usize,
) -> Shot {
    let (w, h) = (cam.width, cam.height);
    // Pass 1: primary rays in camera tiles of 16 × 4 pixels (blocks of `L`: rays closer
    // together than a row's, so the packets' frustums are tighter), a band of 4 rows per job;
    // per pixel `(ray, t, triangle)`.
    const TW: u32 = 16;
    const TH: u32 = 4;
    let (bands, t1) = rows(h.div_ceil(TH), threads, |band| {
        let y0 = band * TH;
        let mut rows = vec![Vec::with_capacity(w as usize); TH.min(h - y0) as usize];
        for x0 in (0..w).step_by(TW as usize) {
            let hit = tree.closest(&cam.tile::<L, { TW as usize }, { TH as usize }>(x0, y0));
            for (row, hits) in rows.iter_mut().zip(hit) {
                for (dx, r) in hits.iter().take((w - x0).min(TW) as usize).enumerate() {
                    row.push(r.map(|r| (r.t, r.index, x0 + dx as u32)));
                }
            }
        }
        rows
    });
    let hits: Vec<Vec<Option<(Ray, f32, u32)>>> = bands
        .into_iter()
        .flatten()
        .enumerate()
        .map(|(y, row)| {
            row.into_iter()
                .map(|px| {
                    px.map(|(t, index, x)| (cam.row_packet::<f32>(x, y as u32).ray(0), t, index))
                })
                .collect()
        })
        .collect();
    // Pass 2: shadow rays from every hit, `L` at a time; per pixel: lit or not.
    let surface = |ray: &Ray, t: f32, index: u32| {
        let tri = &tris[index as usize];
        let n = (tri.b() - tri.a())
            .cross(tri.c() - tri.a())
            .normalize_or_zero();
        let n = if n.dot(ray.dir()) > 0.0 { -n } else { n };
        (ray.at(t) + n * eps, n)
    };
    let (lit, t2) = rows(h, threads, |y| {
        let row = &hits[y as usize];
        let shadows: Vec<Ray> = row
            .iter()
            .flatten()
            .map(|&(ray, t, index)| {
                let (p, _) = surface(&ray, t, index);
                let to = light - p;
                let dist = to.length();
                Ray::with_interval(p, to / dist, 0.0, dist)
            })
            .collect();
        let mut blocked = Vec::with_capacity(shadows.len());
        for chunk in shadows.chunks(L::LANES) {
            let m = tree.any(&RayPacket::<L>::from_rays(chunk));
            blocked.extend((0..chunk.len()).map(|i| raylane::Mask::test(m, i)));
        }
        blocked
    });
    // Shading.
    let mut rgb = vec![0u8; 3 * w as usize * h as usize];
    let mut shadow_rays = 0u64;
    for (y, (row, lit)) in hits.iter().zip(&lit).enumerate() {
        shadow_rays += lit.len() as u64;
        let mut blocked = lit.iter();
        for (x, px) in row.iter().enumerate() {
            let c = match px {
                Some((ray, t, index)) => {
                    let (p, n) = surface(ray, *t, *index);
                    let l = (light - p).normalize_or_zero();
                    let direct = if *blocked.next().unwrap_or(&true) {
                        0.0
                    } else {
                        n.dot(l).max(0.0)
                    };
                    let k = 0.12 + 0.88 * direct;
                    Vec3::new(0.92, 0.85, 0.74) * k
                }
                None => {
                    let s = y as f32 / h as f32;
                    Vec3::new(0.16, 0.2, 0.28) * (1.0 - 0.5 * s)
                }
            };
            let at = 3 * (y * w as usize + x);
            for (k, v) in c.to_array().into_iter().enumerate() {
                rgb[at + k] = (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
            }
        }
    }
    Shot {
        rgb,
        primary: (u64::from(w) * u64::from(h), t1),
        shadow: (shadow_rays, t2),
    }
}
