//! raylane's contenders in the BVH benchmark (`examples/scenes.rs`), over the same rays as
//! the peers of [`crate::bvh_peers`]:
//!
//! * brute force with bounding spheres: the mesh in parts of a few hundred triangles with a
//!   bounding sphere each ([`crate::parts`]), every part's sphere tested per packet, the
//!   triangles only of parts a lane may hit: `Watertight` for every kind of ray (closest and
//!   any), and the focal cache for the primary rays (built per eye, inside the timing);
//! * the reference tracer every contender is checked against: the same parts with the scalar
//!   `Watertight` kernel (exact brute force, with each hit's triangle index);
//! * raylane's BVH ([`Tree`], [`raylane::bvh`]): built from the indexed mesh or the spheres,
//!   single rays (`closest`, `any`) and packets of 8 and 16 (`closest_packet`, `any_packet`);
//! * the same mesh baked for flash ([`BakedTree`], [`raylane::bvh::bake`]: 4-wide quantized
//!   nodes over indexed triangles), traced on the host.
//!
//! Every function returns the number of rays hit and, when `out` is given, pushes one answer
//! per ray (`(t, triangle)`; `(0, 0)` for an occluded shadow ray).

use std::hint::black_box;
use std::time::{Duration, Instant};

use glam::Vec3;
use raylane::bvh::{self, Bvh, Leaf, Node, Primitives, Scratch, Sphere4, Tri4};
use raylane::focal::FocalMesh;
use raylane::mesh::Mesh;
use raylane::set::Sets;
use raylane::sphere::Sphere;
use raylane::{Lane, Mask, Pinhole, Query, Ray, RayPacket};

use crate::meshes::Answers;

/// Triangles per part for a mesh of `n` triangles: about √n / 2, a power of two in
/// [16, 512], which balances the sphere tests (n / size per packet) against the triangles of
/// the parts hit.
pub fn part_size(n: usize) -> usize {
    ((n as f64).sqrt() / 2.0)
        .clamp(16.0, 512.0)
        .log2()
        .round()
        .exp2() as usize
}

/// Ray packets of `L::LANES` rays (the last one padded with rays that never hit).
pub fn packets<L: Lane<Scalar = f32>>(rays: &[Ray]) -> Vec<RayPacket<L>> {
    rays.chunks(L::LANES).map(RayPacket::from_rays).collect()
}

/// Closest hits over the parts with `Watertight`, one query per packet over the parts
/// ([`Sets`]); `ids[p][i]` is the input index of triangle `i` of part `p`.
#[inline(never)]
pub fn closest<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[Mesh],
    ids: &[Vec<u32>],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let h = Sets(meshes).closest(black_box(p));
        n += h.mask.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| {
                h.lane(i)
                    .map(|r| (r.t, ids[r.set as usize][r.index as usize]))
            }));
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// Any hit over the parts with `Watertight`, one query per packet over the parts (it stops
/// when every lane is occluded).
#[inline(never)]
pub fn any<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[Mesh],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let occ = Sets(meshes).any(black_box(p));
        n += occ.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| occ.test(i).then_some((0.0, 0))));
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// Closest hits of primary rays over focal parts (the caches are built by the caller, per
/// eye, inside the timing); `t` only (index 0).
pub fn focal_answers<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[FocalMesh],
    rays: usize,
) -> Answers {
    crate::parts::answers(packets, meshes, rays)
        .into_iter()
        .map(|t| t.map(|t| (t, 0)))
        .collect()
}

/// Brute force over spheres (`Robust`, packets over the slice).
#[inline(never)]
pub fn spheres_closest<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    spheres: &[Sphere],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let h = spheres.closest(black_box(p));
        n += h.mask.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| h.lane(i).map(|r| (r.t, r.index))));
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// raylane's BVH over caller storage, built on one thread (sized by [`bvh::needed`], the
/// leaves by a first guess; trimmed to what the build used).
pub struct Tree<P: Leaf> {
    nodes: Vec<Node>,
    leaves: Vec<P>,
    /// Build time: storage allocation and [`bvh::build`].
    pub build: Duration,
}

impl<P: Leaf> Tree<P> {
    fn new<Q: Primitives<Leaf = P> + ?Sized>(prims: &Q) -> Self {
        let start = Instant::now();
        let need = bvh::TriangleBvh::needed(prims.count());
        let mut nodes = vec![Node::EMPTY; need.nodes];
        // A third of the bound: real meshes fill their leaves (3.7–3.8 of 4); a short slice is
        // answered with the exact count, and the build runs again (never on these meshes).
        let mut leaves = vec![P::EMPTY; need.leaves / 3 + 1];
        let mut scratch = vec![Scratch::default(); need.scratch];
        let (n, l) = loop {
            match bvh::Bvh::build(prims, &mut nodes, &mut leaves, &mut scratch) {
                Ok(t) => break (t.nodes().len(), t.leaves().len()),
                Err(bvh::BuildError::Leaves(t)) => leaves.resize(t.needed, P::EMPTY),
                Err(e) => panic!("storage from bvh::needed: {e}"),
            }
        };
        let build = start.elapsed();
        nodes.truncate(n);
        leaves.truncate(l);
        Tree {
            nodes,
            leaves,
            build,
        }
    }

    /// The tree.
    pub fn bvh(&self) -> Bvh<'_, P> {
        Bvh::from_parts(&self.nodes, &self.leaves).expect("a tree bvh::build made")
    }

    /// Bytes of the nodes and leaves.
    pub fn bytes(&self) -> usize {
        size_of_val(&self.nodes[..]) + size_of_val(&self.leaves[..])
    }
}

/// A mesh baked for flash ([`bvh::bake::bake`]), in 4-byte-aligned storage as
/// `include_baked!` links it.
pub struct BakedTree {
    words: Vec<u32>,
    len: usize,
    /// Bake time (the build and the conversion).
    pub build: Duration,
}

impl BakedTree {
    /// Bakes an indexed mesh; `None` when it cannot be baked (too deep, too many triangles).
    pub fn mesh(positions: &[Vec3], indices: &[[u32; 3]]) -> Option<Self> {
        let start = Instant::now();
        let bytes = bvh::bake::bake(&Mesh::new(positions, indices)).ok()?;
        let build = start.elapsed();
        let mut words = vec![0u32; bytes.len().div_ceil(4)];
        for (w, c) in words.iter_mut().zip(bytes.chunks(4)) {
            let mut b = [0u8; 4];
            b[..c.len()].copy_from_slice(c);
            *w = u32::from_le_bytes(b);
        }
        Some(BakedTree {
            words,
            len: bytes.len(),
            build,
        })
    }

    /// The tree, opened in place (checked).
    pub fn open(&self) -> bvh::bake::Baked<'_> {
        // SAFETY: u32 storage viewed as its bytes (any alignment is fine for u8), len ≤ 4·words.
        let bytes =
            unsafe { std::slice::from_raw_parts(self.words.as_ptr().cast::<u8>(), self.len) };
        bvh::bake::Baked::open(bytes).expect("a tree bake made")
    }

    /// Bytes of the baked tree (nodes, triangles, ids, vertices).
    pub fn bytes(&self) -> usize {
        self.len
    }
}

impl Tree<Tri4> {
    /// Over an indexed mesh (`Mesh::new(positions, indices)`).
    pub fn mesh(positions: &[Vec3], indices: &[[u32; 3]]) -> Self {
        Self::new(&Mesh::new(positions, indices))
    }
}

impl Tree<Sphere4> {
    /// Over spheres.
    pub fn spheres(spheres: &[Sphere]) -> Self {
        Self::new(spheres)
    }
}

/// Closest hits of single rays through the BVH.
#[inline(never)]
pub fn bvh_closest1(t: &impl Query, rays: &[Ray], mut out: Option<&mut Answers>) -> u32 {
    let mut n = 0;
    for r in rays {
        let h = t.closest(black_box(r));
        n += h.is_some() as u32;
        if let Some(o) = out.as_deref_mut() {
            o.push(h.map(|h| (h.t, h.index)));
        }
        black_box(&h);
    }
    n
}

/// Closest hits of ray packets through the BVH.
#[inline(never)]
pub fn bvh_closest<L: Lane<Scalar = f32>>(
    t: &impl Query,
    packets: &[RayPacket<L>],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let h = t.closest(black_box(p));
        n += h.mask.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| h.lane(i).map(|r| (r.t, r.index))));
        }
        black_box(&h);
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// Any hit of single rays through the BVH.
#[inline(never)]
pub fn bvh_any1(t: &impl Query, rays: &[Ray], mut out: Option<&mut Answers>) -> u32 {
    let mut n = 0;
    for r in rays {
        let h = t.any(black_box(r));
        n += h as u32;
        if let Some(o) = out.as_deref_mut() {
            o.push(h.then_some((0.0, 0)));
        }
    }
    n
}

/// Any hit of ray packets through the BVH.
#[inline(never)]
pub fn bvh_any<L: Lane<Scalar = f32>>(
    t: &impl Query,
    packets: &[RayPacket<L>],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let m = t.any(black_box(p));
        n += m.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| m.test(i).then_some((0.0, 0))));
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// Seconds `OwnedBvh::new` takes on every core (feature `std`) over an indexed mesh.
pub fn owned_build(positions: &[Vec3], indices: &[[u32; 3]]) -> Duration {
    let start = Instant::now();
    let t = bvh::OwnedBvh::new(&Mesh::new(positions, indices)).expect("a mesh under the limit");
    let d = start.elapsed();
    black_box(&t);
    d
}

/// Closest hits of the camera's tiles of `S × S` pixels in packets of `L`
/// (`tree.closest(&cam.tile::<L, S, S>(x, y))`), the tiles `first, first + step, …` (the
/// image's tiles row by row); with `out`, the answers in the order of
/// [`crate::meshes::tile_pixels`].
#[inline(never)]
pub fn bvh_tiles<L: Lane<Scalar = f32>, const S: usize>(
    t: &impl Query,
    cam: &Pinhole,
    (first, step): (usize, usize),
    out: Option<&mut Answers>,
) -> u32 {
    let (tw, th) = (cam.width as usize / S, cam.height as usize / S);
    let mut image = out
        .as_ref()
        .map(|_| vec![None; (cam.width * cam.height) as usize]);
    let mut n = 0;
    for k in (first..tw * th).step_by(step) {
        let (x, y) = ((k % tw) * S, (k / tw) * S);
        let hits = t.closest(black_box(&cam.tile::<L, S, S>(x as u32, y as u32)));
        for (j, row) in hits.iter().enumerate() {
            for (i, h) in row.iter().enumerate() {
                n += h.is_some() as u32;
                if let Some(img) = image.as_mut() {
                    img[(y + j) * cam.width as usize + x + i] = h.map(|h| (h.t, h.index));
                }
            }
        }
        black_box(&hits);
    }
    if let (Some(o), Some(img)) = (out, image) {
        o.extend(
            crate::meshes::tile_pixels(cam)
                .into_iter()
                .map(|(x, y)| img[(y * cam.width + x) as usize]),
        );
    }
    n
}

/// `f(first, step)` on every core: `f` handles the items `first, first + step, …` of a frame
/// (`step` = the number of threads); the hits summed.
pub fn on_cores(f: impl Fn(usize, usize) -> u32 + Sync) -> u32 {
    let cores = cores();
    std::thread::scope(|s| {
        let f = &f;
        let workers: Vec<_> = (0..cores).map(|k| s.spawn(move || f(k, cores))).collect();
        workers
            .into_iter()
            .map(|w| w.join().expect("a worker"))
            .sum()
    })
}

/// The number of threads [`on_cores`] runs.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |c| c.get())
}
