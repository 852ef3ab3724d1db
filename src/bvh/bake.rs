//! Trees baked on a host and traced from flash: a triangle mesh's BVH in 4-wide quantized
//! nodes ([`Node4`]) over indexed triangles (shared vertices, 16-bit indices where the mesh
//! allows), written once by `bake` (feature `alloc`, on the host) into a versioned,
//! little-endian byte format that a microcontroller links as it is
//! ([`include_baked!`](crate::include_baked)) and opens without copying ([`Baked::open`]): the
//! bytes are checked once and then viewed in place, so a query needs no RAM beside its stack:
//! [`STACK4`] node references (196 bytes) and its frames, about 1 KB in all (measured by
//! stack painting on the six QEMU boards: 736 B on rv32imafc to 916 B on the Cortex-M0).
//!
//! ```
//! use raylane::bvh::bake::{Baked, bake};
//! use raylane::glam::Vec3;
//! use raylane::mesh::Mesh;
//! use raylane::{Query, Ray};
//!
//! let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
//! let indices = [[0u32, 1, 2], [1, 3, 2]];
//! let mesh = Mesh::new(&positions, &indices);
//! let bytes = bake(&mesh).unwrap(); // on the host, at build time
//! let tree = Baked::open(&bytes).unwrap(); // on the device, from flash
//! let ray = Ray::new(Vec3::new(0.75, 0.75, 1.0), Vec3::NEG_Z);
//! assert_eq!(tree.closest(&ray), mesh.closest(&ray)); // the mesh's answer, bit for bit
//! ```
//!
//! **Why bytes, not generated Rust.** A firmware developer bakes with the rest of the assets
//! (a `build.rs` or the `bake` example) and links the file with `include_bytes!`: no large
//! generated source to compile, the same file for every target and toolchain, and a version and
//! a check that refuse a file this crate cannot trace. Opening reads the bytes in linear time, no
//! allocation, no copy.
//!
//! **The format** (version 1; every field little-endian; the sections back to back in the
//! table's order, each at the first 4-byte boundary after the one before, zero bytes between):
//!
//! | bytes | field |
//! | --- | --- |
//! | 0–3 | magic `RLBV` |
//! | 4–5, 6–7 | version (1), flags (bit 0: 32-bit indices, else 16-bit) |
//! | 8–11, 12–15, 16–19 | nodes, triangles, vertices |
//! | 20–23 | the tree's depth, exactly (the root alone is 1; at most [`MAX_DEPTH4`]) |
//! | 24–27, 28–31, 32–35, 36–39 | offsets: the nodes (64), the triangles, the ids, the vertices |
//! | 40–43 | total length: the end of the vertices |
//! | 44–63 | zero |
//! | nodes | [`Node4`], 56 bytes each, depth-first preorder (the root first), each with a child |
//! | triangles | vertex indices A, B, C per triangle (`u16` or `u32`), in leaf order |
//! | ids | the triangle's index in the mesh that was baked (`u16` or `u32`), the index hits report |
//! | vertices | `f32` x, y, z |
//!
//! **What opening checks** ([`Baked::open`]: the header, the vertices, then one depth-first
//! pass over the tree, its stack the traversal's), in this order, each with its [`OpenError`]:
//!
//! 1. The host is little-endian ([`BigEndian`](OpenError::BigEndian)).
//! 2. The bytes hold the header ([`Truncated`](OpenError::Truncated)) and start at a 4-byte
//!    boundary ([`Misaligned`](OpenError::Misaligned)).
//! 3. The magic ([`Magic`](OpenError::Magic)) and the version
//!    ([`Version`](OpenError::Version)).
//! 4. No unknown flag, bytes 44–63 zero ([`Header`](OpenError::Header)).
//! 5. The total length is the number of bytes ([`Truncated`](OpenError::Truncated)).
//! 6. At least one node ([`Order(0)`](OpenError::Order)).
//! 7. The depth field from 1 to [`MAX_DEPTH4`] ([`TooDeep`](OpenError::TooDeep)).
//! 8. Each offset the one the counts give, the bytes between sections zero
//!    ([`Header`](OpenError::Header)), and the bytes ending with the vertices: fewer are
//!    [`Truncated`](OpenError::Truncated), more [`Header`](OpenError::Header).
//! 9. Every vertex finite, whether a triangle uses it or not ([`Vertex`](OpenError::Vertex)):
//!    a NaN or an infinity anywhere is a sign of corruption.
//! 10. From the root, depth first: each node the next one in preorder, so every node is reached
//!     exactly once (a tree: none reached twice, none left out, every child after its parent;
//!     [`Order`](OpenError::Order)); its pad zero, its origin finite, its exponents in
//!     −126…127, its unused slots canonical (`lo` 255, `hi` 0), a child unless it is the root
//!     ([`Node`](OpenError::Node)); no inner child below depth [`MAX_DEPTH4`]
//!     ([`TooDeep`](OpenError::TooDeep)); each leaf 1 to 4 triangles, the next ones in order,
//!     none skipped or shared ([`Leaf`](OpenError::Leaf)); each triangle's vertex indices in
//!     range ([`Triangle`](OpenError::Triangle)); and each of its vertices inside the decoded
//!     box of every node above it ([`Outside`](OpenError::Outside)), so that the traversal's
//!     answers are brute force's over the baked triangles.
//! 11. No node ([`Order`](OpenError::Order)) and no triangle ([`Leaf`](OpenError::Leaf)) left
//!     over.
//! 12. The depth field is the depth the walk reached ([`Depth`](OpenError::Depth)), so that
//!     [`Baked::depth`] is the tree's.
//!
//! Any other input is an error value, never a panic, an out-of-bounds read or a loop. So these
//! are refused: bytes after the last section, sections that overlap or leave a gap (or a
//! nonzero byte in the padding between them), and nodes without children, but for the root of
//! a tree of no triangles (as `bake` writes it for an empty mesh): `bake` writes none of them,
//! and each is a sign of corruption. Allowed: vertices no triangle uses (if finite), and any
//! ids, repeated ones too (a check would need scratch memory or quadratic time): two triangles
//! with one id tied at one `t` go to the earlier one in leaf order, at every width (the tie
//! rule's last key, [`crate::hit`]).

use glam::Vec3;
use wide::f32x4;

use super::leaf::triangle_boxes;
use super::node::{Layout, MAX_DEPTH4, Node4, SIMD, STACK4};
use super::{EMPTY, LEAF, split, traverse};
use crate::hit::{At, Collector, Hits, Record, Winners, alone};
use crate::kernel::{Cull, Kernel, LaneHit, admit, admits};
use crate::lane::{Lane, Mask};
use crate::ray::{Ray, RayPacket};
use crate::set::{Set, mine};
use crate::triangle::{Triangle, TrianglePacket, Watertight};
use crate::vec3::V3;

/// The first four bytes of a baked tree.
pub const MAGIC: [u8; 4] = *b"RLBV";
/// The version this crate writes and opens.
pub const VERSION: u16 = 1;
/// Bytes of the header.
pub const HEADER: usize = 64;
/// Flag: vertex indices and ids are `u32` (else `u16`).
const WIDE: u16 = 1;

/// Why [`Baked::open`] refused its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpenError {
    /// Fewer bytes than the header or the sections need.
    Truncated,
    /// The bytes do not start at a 4-byte boundary (link them with
    /// [`include_baked!`](crate::include_baked)).
    Misaligned,
    /// Not a baked tree (the magic).
    Magic,
    /// Another version of the format.
    Version(u16),
    /// Unknown flags, a nonzero reserved field or byte between sections, a section not where
    /// the format puts it (overlapping another, or after a gap), or bytes after the last one.
    Header,
    /// The host this runs on is big-endian (the format is little-endian).
    BigEndian,
    /// Node `.0` is not where a tree in preorder puts it, or is reached twice or not at all.
    Order(u32),
    /// Node `.0` has a non-finite origin, an exponent out of range, a nonzero pad, a
    /// non-canonical empty slot, or no child (allowed at the root alone).
    Node(u32),
    /// The tree is deeper than [`MAX_DEPTH4`], or the depth field is 0 or more than it.
    TooDeep,
    /// The depth field is not the tree's depth, `.0`.
    Depth(u32),
    /// A leaf of node `.0` holds no triangle, more than 4, or not the next ones.
    Leaf(u32),
    /// Triangle `.0` has a vertex index out of range.
    Triangle(u32),
    /// Vertex `.0` is not finite (NaN or infinite), whether a triangle uses it or not.
    Vertex(u32),
    /// Triangle `.0` lies outside the box of a node above it.
    Outside(u32),
}

impl core::fmt::Display for OpenError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "not a valid baked tree: {self:?}")
    }
}

/// The triangles' vertex indices.
#[derive(Clone, Copy, Debug)]
enum Tris<'a> {
    Narrow(&'a [[u16; 3]]),
    Wide(&'a [[u32; 3]]),
}

/// The triangles' ids.
#[derive(Clone, Copy, Debug)]
enum Ids<'a> {
    Narrow(&'a [u16]),
    Wide(&'a [u32]),
}

/// A baked tree viewed in place (see the [module docs](self)): a [`Set`] of triangles like
/// every other (default kernel [`Watertight`], any other through `using`), whose hits report
/// the triangles' indices in the mesh that was baked.
#[derive(Clone, Copy, Debug)]
pub struct Baked<'a> {
    nodes: &'a [Node4],
    tris: Tris<'a>,
    ids: Ids<'a>,
    vertices: &'a [[f32; 3]],
    reach: f32,
    depth: u32,
}

/// Little-endian `u16` at `at`.
fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

/// Little-endian `u32` at `at`.
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// `bytes[start..start + n·size]` as `&[T]`, checked.
fn section<T: bytemuck::Pod>(bytes: &[u8], start: usize, n: u32) -> Result<&[T], OpenError> {
    let len = (n as usize).checked_mul(core::mem::size_of::<T>());
    let b = len
        .and_then(|len| bytes.get(start..start.checked_add(len)?))
        .ok_or(OpenError::Truncated)?;
    bytemuck::try_cast_slice(b).map_err(|_| OpenError::Misaligned)
}

/// Where the format puts the nodes, the triangles, the ids and the vertices, and where the
/// vertices end, for these counts and index `width` (bytes): back to back after the header,
/// each at the first 4-byte boundary after the one before; `None` past `usize`.
fn layout(n_nodes: u32, n_tris: u32, n_verts: u32, width: usize) -> Option<[usize; 5]> {
    let after = |at: usize, n: u32, size: usize| {
        at.checked_add((n as usize).checked_mul(size)?)?
            .checked_next_multiple_of(4)
    };
    let tris = after(HEADER, n_nodes, size_of::<Node4>())?;
    let ids = after(tris, n_tris, 3 * width)?;
    let verts = after(ids, n_tris, width)?;
    Some([HEADER, tris, ids, verts, after(verts, n_verts, 12)?])
}

impl<'a> Baked<'a> {
    /// Checks `bytes` (see the [module docs](self)) and views them as a tree.
    ///
    /// # Errors
    ///
    /// [`OpenError`] saying what is wrong.
    pub fn open(bytes: &'a [u8]) -> Result<Self, OpenError> {
        if cfg!(target_endian = "big") {
            return Err(OpenError::BigEndian);
        }
        if bytes.len() < HEADER {
            return Err(OpenError::Truncated);
        }
        if !(bytes.as_ptr() as usize).is_multiple_of(4) {
            return Err(OpenError::Misaligned);
        }
        let word = |i: usize| u32_at(bytes, 4 * i).unwrap_or(u32::MAX);
        if bytes.get(..4) != Some(&MAGIC[..]) {
            return Err(OpenError::Magic);
        }
        let version = u16_at(bytes, 4).unwrap_or(0);
        if version != VERSION {
            return Err(OpenError::Version(version));
        }
        let flags = u16_at(bytes, 6).unwrap_or(u16::MAX);
        if flags & !WIDE != 0 || (11..16).any(|i| word(i) != 0) {
            return Err(OpenError::Header);
        }
        let (n_nodes, n_tris, n_verts, depth) = (word(2), word(3), word(4), word(5));
        if word(10) as usize != bytes.len() {
            return Err(OpenError::Truncated);
        }
        if n_nodes == 0 {
            return Err(OpenError::Order(0));
        }
        if depth == 0 || depth > MAX_DEPTH4 {
            return Err(OpenError::TooDeep);
        }
        // The sections where the format puts them, zero bytes between, nothing after.
        let width = if flags & WIDE != 0 { 4 } else { 2 };
        let at = layout(n_nodes, n_tris, n_verts, width).ok_or(OpenError::Truncated)?;
        if (0..4).any(|k| word(6 + k) as usize != at[k]) {
            return Err(OpenError::Header);
        }
        if at[4] != bytes.len() {
            return Err(if at[4] > bytes.len() {
                OpenError::Truncated
            } else {
                OpenError::Header
            });
        }
        let n = n_tris as usize;
        let zero = |from: usize, to: usize| {
            bytes
                .get(from..to)
                .is_some_and(|b| b.iter().all(|&x| x == 0))
        };
        if !zero(at[1] + 3 * width * n, at[2]) || !zero(at[2] + width * n, at[3]) {
            return Err(OpenError::Header);
        }
        let nodes: &[Node4] = section(bytes, at[0], n_nodes)?;
        let (tris, ids) = if width == 4 {
            (
                Tris::Wide(section(bytes, at[1], n_tris)?),
                Ids::Wide(section(bytes, at[2], n_tris)?),
            )
        } else {
            (
                Tris::Narrow(section(bytes, at[1], n_tris)?),
                Ids::Narrow(section(bytes, at[2], n_tris)?),
            )
        };
        let vertices: &[[f32; 3]] = section(bytes, at[3], n_verts)?;
        if let Some(v) = vertices
            .iter()
            .position(|p| !p.iter().all(|x| x.is_finite()))
        {
            return Err(OpenError::Vertex(v as u32));
        }
        let mut tree = Baked {
            nodes,
            tris,
            ids,
            vertices,
            reach: 0.0,
            depth,
        };
        let deepest = tree.check()?;
        if deepest != depth {
            return Err(OpenError::Depth(deepest));
        }
        tree.reach = super::reach(&nodes[0]);
        Ok(tree)
    }

    /// The number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        match self.tris {
            Tris::Narrow(t) => t.len(),
            Tris::Wide(t) => t.len(),
        }
    }

    /// True when the tree holds no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The nodes (the root first, preorder).
    #[must_use]
    pub fn nodes(&self) -> &'a [Node4] {
        self.nodes
    }

    /// The tree's depth (the root alone is 1; the header's field, which opening compared with
    /// the tree's).
    #[must_use]
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Bytes of the nodes, the triangles (indices and ids) and the vertices.
    #[must_use]
    pub fn bytes(&self) -> (usize, usize, usize) {
        let t = match (self.tris, self.ids) {
            (Tris::Narrow(t), Ids::Narrow(i)) => size_of_val(t) + size_of_val(i),
            (Tris::Wide(t), Ids::Wide(i)) => size_of_val(t) + size_of_val(i),
            (Tris::Narrow(t), Ids::Wide(i)) => size_of_val(t) + size_of_val(i),
            (Tris::Wide(t), Ids::Narrow(i)) => size_of_val(t) + size_of_val(i),
        };
        (size_of_val(self.nodes), t, size_of_val(self.vertices))
    }

    /// Baked triangle `i` (in leaf order) and its index in the mesh that was baked.
    #[must_use]
    pub fn get(&self, i: usize) -> Option<(u32, Triangle)> {
        (i < self.len()).then(|| (self.id(i), self.triangle(i)))
    }

    /// Baked triangle `i`'s vertex indices.
    #[inline(always)]
    fn corners(&self, i: usize) -> Option<[usize; 3]> {
        match self.tris {
            Tris::Narrow(t) => t.get(i).map(|c| c.map(usize::from)),
            Tris::Wide(t) => t.get(i).map(|c| c.map(|x| x as usize)),
        }
    }

    /// Baked triangle `i` (a triangle that is never hit past the end).
    #[inline(always)]
    fn triangle(&self, i: usize) -> Triangle {
        let v = |k: usize| self.vertices.get(k).map(|p| Vec3::from_array(*p));
        match self.corners(i) {
            Some([a, b, c]) => match (v(a), v(b), v(c)) {
                (Some(a), Some(b), Some(c)) => Triangle::stored(a, b, c),
                _ => Triangle::never(),
            },
            None => Triangle::never(),
        }
    }

    /// Baked triangles `first .. first + count` in four lanes (lanes past `count`, and a
    /// triangle with a vertex index out of range, never hit: NaN).
    #[inline(always)]
    fn four(&self, first: usize, count: usize) -> TrianglePacket<f32x4> {
        let mut v = [[f32::NAN; 4]; 9];
        for (k, t) in (first..first + count.min(4)).enumerate() {
            let Some(c) = self.corners(t) else {
                continue;
            };
            if let (Some(a), Some(b), Some(c)) = (
                self.vertices.get(c[0]),
                self.vertices.get(c[1]),
                self.vertices.get(c[2]),
            ) {
                for (j, p) in [a, b, c].into_iter().enumerate() {
                    v[3 * j][k] = p[0];
                    v[3 * j + 1][k] = p[1];
                    v[3 * j + 2][k] = p[2];
                }
            }
        }
        let p = |j: usize| V3::new(f32x4::new(v[j]), f32x4::new(v[j + 1]), f32x4::new(v[j + 2]));
        TrianglePacket {
            a: p(0),
            b: p(3),
            c: p(6),
        }
    }

    /// Baked triangle `i`'s index in the mesh that was baked.
    #[inline(always)]
    fn id(&self, i: usize) -> u32 {
        match self.ids {
            Ids::Narrow(d) => d.get(i).map_or(u32::MAX, |&x| u32::from(x)),
            Ids::Wide(d) => d.get(i).copied().unwrap_or(u32::MAX),
        }
    }

    /// The tree pass of [`open`](Self::open): a depth-first walk in preorder with the
    /// intersection of the boxes above each node on the stack. Returns the tree's depth.
    fn check(&self) -> Result<u32, OpenError> {
        // (node, depth, the box every triangle under it must lie in)
        type Entry = (u32, u32, [f32; 3], [f32; 3]);
        let mut stack: [Entry; STACK4] = [(0, 0, [0.0; 3], [0.0; 3]); STACK4];
        stack[0] = (0, 1, [f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
        let mut sp = 1usize;
        let (mut next_node, mut next_tri, mut deepest) = (0u32, 0usize, 0u32);
        while sp > 0 {
            sp -= 1;
            let (i, d, lo, hi) = stack[sp];
            deepest = deepest.max(d);
            if i != next_node {
                return Err(OpenError::Order(i));
            }
            next_node += 1;
            let n = self.nodes.get(i as usize).ok_or(OpenError::Order(i))?;
            let bad = OpenError::Node(i);
            if n.pad != 0
                || !n.origin.iter().all(|x| x.is_finite())
                || !n.exp.iter().all(|e| (-126..=127).contains(e))
                || (i != 0 && n.child.iter().all(|&c| c == EMPTY))
            {
                return Err(bad);
            }
            // Children in slot order; inner children pushed last to first, so that they are
            // popped (and must be numbered) in slot order.
            let mut inner = [(0u32, [0.0f32; 3], [0.0f32; 3]); 4];
            let mut m = 0;
            for k in 0..4 {
                let c = n.child[k];
                if c == EMPTY {
                    if (0..3).any(|a| n.lo[a][k] != 255 || n.hi[a][k] != 0) {
                        return Err(bad);
                    }
                    continue;
                }
                // The child's box, within the boxes above.
                let (blo, bhi) = n.bounds(k);
                let clo = |a: usize| super::max(lo[a], blo[a]);
                let chi = |a: usize| super::min(hi[a], bhi[a]);
                let (clo, chi) = ([clo(0), clo(1), clo(2)], [chi(0), chi(1), chi(2)]);
                if c & LEAF == 0 {
                    inner[m] = (c, clo, chi);
                    m += 1;
                    continue;
                }
                let first = ((c & !LEAF) >> 2) as usize;
                let count = (c & 3) as usize + 1;
                if first != next_tri {
                    return Err(OpenError::Leaf(i));
                }
                for t in first..first + count {
                    let corners = self.corners(t).ok_or(OpenError::Leaf(i))?;
                    for v in corners {
                        // In range (every vertex is finite: `open` checked them all).
                        let p = self.vertices.get(v).ok_or(OpenError::Triangle(t as u32))?;
                        if (0..3).any(|a| !(p[a] >= clo[a] && p[a] <= chi[a])) {
                            return Err(OpenError::Outside(t as u32));
                        }
                    }
                }
                next_tri += count;
            }
            if m > 0 && d >= MAX_DEPTH4 {
                return Err(OpenError::TooDeep);
            }
            for &(c, clo, chi) in inner[..m].iter().rev() {
                let slot = stack.get_mut(sp).ok_or(OpenError::TooDeep)?;
                *slot = (c, d + 1, clo, chi);
                sp += 1;
            }
        }
        if next_node as usize != self.nodes.len() {
            return Err(OpenError::Order(next_node));
        }
        if next_tri != self.len() {
            return Err(OpenError::Leaf(u32::MAX));
        }
        Ok(deepest)
    }

    /// The triangles of the leaf `r` (`first << 2 | (count − 1)`): `(first, count)`.
    #[inline(always)]
    fn leaf(r: u32) -> (usize, usize) {
        (((r & !LEAF) >> 2) as usize, (r & 3) as usize + 1)
    }
}

impl Baked<'_> {
    /// One ray from the node reference `start` (0: the root) into `c`: the one-ray query, and
    /// the packets' lanes that continue alone.
    #[inline(always)]
    fn trace_from<K: Kernel<Triangle>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        start: u32,
        set: u32,
        c: &mut C,
    ) -> bool {
        if !SIMD {
            // Without SIMD lanes (Cortex-M, RISC-V 32) four triangles in lanes are four scalar
            // tests and more stack: one triangle at a time, the same bits.
            let r1 = RayPacket::<f32>::splat(ray);
            let mut pre = None;
            return traverse::one(
                self.nodes,
                self.reach,
                ray,
                start,
                c,
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |r_leaf, c| {
                    let (first, count) = Self::leaf(r_leaf);
                    if pre.is_none() {
                        pre = Some(K::prepare(&r1));
                    }
                    let Some(pre) = &pre else {
                        return false;
                    };
                    for t in first..first + count {
                        let r = r1.shrink(true, c.t_max());
                        let tri = TrianglePacket::splat(&self.triangle(t));
                        let Some(h) = K::first(&r, pre, &tri, cull) else {
                            continue;
                        };
                        let at = At {
                            set,
                            index: self.id(t),
                            loc: t as u32,
                        };
                        if h.mask && c.offer(&h, at, |_| Hits::miss()) {
                            return true;
                        }
                    }
                    false
                },
            );
        }
        let r4 = RayPacket::<f32x4>::splat(ray).shrink(Mask::splat(true), f32x4::splat(c.t_max()));
        let mut pre = None;
        traverse::one(
            self.nodes,
            self.reach,
            ray,
            start,
            c,
            #[inline(always)]
            |r_leaf, c| {
                let (first, count) = Self::leaf(r_leaf);
                let four = self.four(first, count);
                let r = if C::SHRINKS {
                    r4.shrink(Mask::splat(true), f32x4::splat(c.t_max()))
                } else {
                    r4
                };
                if pre.is_none() {
                    pre = Some(K::prepare(&r4));
                }
                let Some(pre) = &pre else {
                    return false;
                };
                let Some(h) = K::first(&r, pre, &four, cull) else {
                    return false;
                };
                let mut bits = h.mask.bits();
                while bits != 0 {
                    let j = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let one = LaneHit {
                        t: h.t.lane(j),
                        u: h.u.lane(j),
                        v: h.v.lane(j),
                        w: h.w.lane(j),
                        mask: true,
                    };
                    let at = At {
                        set,
                        index: self.id(first + j),
                        loc: (first + j) as u32,
                    };
                    if c.offer(&one, at, |_| Hits::miss()) {
                        return true;
                    }
                }
                false
            },
        )
    }
}

/// A baked tree answers as the mesh it was baked from, with the same kernel and culling, bit
/// for bit; its hits carry the mesh's triangle indices.
impl Set for Baked<'_> {
    type Prim = Triangle;
    type Kernel = Watertight;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<Triangle>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        let rays = admit(rays, K::UNIT_DIRECTIONS);
        let pre = K::prepare(&rays);
        traverse::many(
            self.nodes,
            self.reach,
            &rays,
            c,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |r_leaf, r, cone, c| {
                let (first, count) = Self::leaf(r_leaf);
                // The triangles whose boxes the packet's cone may enter (as `leaf_many`).
                let keep = cone.map_or(u32::MAX, |f| {
                    f.enters(triangle_boxes(&self.four(first, count)))
                });
                let mut r = *r;
                for (k, t) in (first..first + count).enumerate() {
                    if keep & (1 << k) == 0 {
                        continue;
                    }
                    r.t_max = c.t_max();
                    let tri = self.triangle(t);
                    let at = At {
                        set,
                        index: self.id(t),
                        loc: t as u32,
                    };
                    let record = |w: &Winners<L>| Triangle::records(&rays, w, cull, |_| Some(tri));
                    let p = TrianglePacket::splat(&tri);
                    let stop = if C::EVERY {
                        K::each(&r, &pre, &p, cull, |h| c.offer(h, at, record))
                    } else {
                        K::first(&r, &pre, &p, cull)
                            .is_some_and(|h| h.mask.any() && c.offer(&h, at, record))
                    };
                    if stop {
                        return true;
                    }
                }
                false
            },
            split::<L, C>(),
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |start, i, c| {
                alone(
                    c,
                    i,
                    #[cfg_attr(target_arch = "x86_64", inline(always))]
                    |one| self.trace_from::<K, _>(cull, &rays.lane_ray(i), start, set, one),
                )
            },
        )
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray_with<K: Kernel<Triangle>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        if C::EVERY {
            return self.trace_with::<K, f32, C>(cull, &RayPacket::splat(ray), set, c);
        }
        if !admits(ray, K::UNIT_DIRECTIONS) {
            return false;
        }
        self.trace_from::<K, C>(cull, ray, 0, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L> {
        Triangle::records(
            rays,
            &mine(w, set),
            cull,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |loc| Some(self.triangle(loc as usize)),
        )
    }
}

/// The bytes of a baked tree linked into the program, aligned for [`Baked::open`]
/// (`include_bytes!` alone gives 1-byte alignment):
/// `let tree = Baked::open(raylane::include_baked!("bunny.rlbv"))?;`.
#[macro_export]
macro_rules! include_baked {
    ($path:expr) => {{
        #[repr(C, align(16))]
        struct Aligned<T: ?Sized>(T);
        static BYTES: &Aligned<[u8]> = &Aligned(*include_bytes!($path));
        &BYTES.0
    }};
}

/// Why `bake` (feature `alloc`) could not bake a mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BakeError {
    /// More triangles or vertices than the format counts (`2^29`).
    TooMany,
    /// The tree would be deeper than [`MAX_DEPTH4`] (a traversal's stack is fixed).
    TooDeep,
}

#[cfg(feature = "alloc")]
pub use alloc_only::bake;

#[cfg(feature = "alloc")]
mod alloc_only {
    use alloc::vec;
    use alloc::vec::Vec;

    use super::super::build::{fill, topology};
    use super::super::{Bvh, LEAF_WIDTH, Node, Packed, Scratch, Tri4, reach, sizes};
    use super::*;
    use crate::mesh::Mesh;

    /// Bakes `mesh` (see the [module docs](super)): its valid triangles (invalid ones are
    /// never hit, and left out) under a 4-wide binned-SAH tree with leaves of up to 4
    /// triangles, quantized to [`Node4`]s, the vertices the triangles use and 16-bit indices
    /// where they fit. Deterministic: the same bytes on every host.
    ///
    /// # Errors
    ///
    /// [`BakeError`] for a mesh of more than `2^29` triangles or vertices, or a tree deeper
    /// than [`MAX_DEPTH4`].
    pub fn bake(mesh: &Mesh) -> Result<Vec<u8>, BakeError> {
        // 1. The valid triangles, their ids and the vertices they use (renumbered in order of
        //    first use).
        let mut tris: Vec<Triangle> = Vec::new();
        let mut ids: Vec<u32> = Vec::new();
        let mut corners: Vec<[u32; 3]> = Vec::new();
        let mut remap = vec![u32::MAX; mesh.positions().len()];
        let mut verts: Vec<[f32; 3]> = Vec::new();
        for i in 0..mesh.len() {
            let Some(t) = mesh.triangle(i).filter(Triangle::is_valid) else {
                continue;
            };
            let Some(&idx) = mesh.indices().get(i) else {
                continue;
            };
            let c = idx.map(|k| {
                let slot = &mut remap[k as usize];
                if *slot == u32::MAX {
                    *slot = verts.len() as u32;
                    verts.push(mesh.positions()[k as usize].to_array());
                }
                *slot
            });
            tris.push(t);
            ids.push(i as u32);
            corners.push(c);
        }
        let limit = 1 << 29;
        if tris.len() >= limit || verts.len() >= limit || mesh.len() >= limit {
            return Err(BakeError::TooMany);
        }
        // 2. A 4-wide tree (the 8-wide builder limited to 4 children).
        let n = tris.len();
        let need = sizes(n);
        let mut nodes = vec![Node::EMPTY; n / 3 + 2];
        let mut scratch = vec![Scratch::default(); need.scratch];
        let (used, l) = topology(&tris[..], &mut nodes, &mut scratch, 4, LEAF_WIDTH, true)
            .map_err(|_| BakeError::TooMany)?;
        let mut leaves = vec![Tri4::EMPTY; l];
        fill(&tris[..], &scratch[..n], &mut leaves);
        let tree = Bvh {
            nodes: &nodes[..used],
            leaves: &leaves[..],
            reach: reach(&nodes[0]),
        };
        // 3. Preorder numbering, then the nodes, quantized, and the triangles in leaf order.
        let mut order = vec![u32::MAX; tree.nodes.len()];
        let mut pre = Vec::with_capacity(tree.nodes.len());
        let mut stack = vec![(0u32, 1u32)];
        let mut depth = 0;
        while let Some((i, d)) = stack.pop() {
            order[i as usize] = pre.len() as u32;
            pre.push(i);
            depth = depth.max(d);
            let node = &tree.nodes[i as usize];
            for k in (0..4).rev() {
                let c = node.child[k];
                if c != EMPTY && c & LEAF == 0 {
                    stack.push((c, d + 1));
                }
            }
        }
        if depth > MAX_DEPTH4 {
            return Err(BakeError::TooDeep);
        }
        let mut out_nodes = Vec::with_capacity(pre.len());
        let (mut out_corners, mut out_ids) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for &i in &pre {
            let node = &tree.nodes[i as usize];
            let mut q = Node4::EMPTY;
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for k in 0..4 {
                if node.child[k] != EMPTY {
                    let (l, h) = node.bounds(k);
                    for a in 0..3 {
                        lo[a] = lo[a].min(l[a]);
                        hi[a] = hi[a].max(h[a]);
                    }
                }
            }
            if lo[0] > hi[0] {
                (lo, hi) = ([0.0; 3], [0.0; 3]); // no children
            }
            q.origin = lo;
            for a in 0..3 {
                q.exp[a] = exponent(lo[a], hi[a]);
            }
            for k in 0..4 {
                let c = node.child[k];
                if c == EMPTY {
                    continue;
                }
                let (clo, chi) = node.bounds(k);
                for a in 0..3 {
                    q.lo[a][k] = quantize_down(&q, a, clo[a]);
                    q.hi[a][k] = quantize_up(&q, a, chi[a]);
                }
                q.child[k] = if c & LEAF == 0 {
                    order[c as usize]
                } else {
                    let leaf = &tree.leaves[(c & !LEAF) as usize];
                    let first = out_corners.len() as u32;
                    let mut count = 0;
                    for &t in leaf.indices().iter().take(LEAF_WIDTH) {
                        if t != EMPTY {
                            out_corners.push(corners[t as usize]);
                            out_ids.push(ids[t as usize]);
                            count += 1;
                        }
                    }
                    LEAF | first << 2 | (count - 1)
                };
            }
            out_nodes.push(q);
        }
        // 4. The bytes.
        let wide = verts.len() > usize::from(u16::MAX) || mesh.len() > usize::from(u16::MAX);
        let mut b = vec![0u8; HEADER];
        let align = |b: &mut Vec<u8>| b.resize(b.len().next_multiple_of(4), 0);
        let off_nodes = b.len();
        for q in &out_nodes {
            b.extend_from_slice(bytemuck::bytes_of(q));
        }
        let off_tris = b.len();
        for c in &out_corners {
            for &x in c {
                if wide {
                    b.extend_from_slice(&x.to_le_bytes());
                } else {
                    b.extend_from_slice(&(x as u16).to_le_bytes());
                }
            }
        }
        align(&mut b);
        let off_ids = b.len();
        for &x in &out_ids {
            if wide {
                b.extend_from_slice(&x.to_le_bytes());
            } else {
                b.extend_from_slice(&(x as u16).to_le_bytes());
            }
        }
        align(&mut b);
        let off_verts = b.len();
        for v in &verts {
            for x in v {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        let total = b.len();
        b[..4].copy_from_slice(&MAGIC);
        b[4..6].copy_from_slice(&VERSION.to_le_bytes());
        b[6..8].copy_from_slice(&(if wide { WIDE } else { 0 }).to_le_bytes());
        let words = [
            out_nodes.len(),
            out_corners.len(),
            verts.len(),
            depth as usize,
            off_nodes,
            off_tris,
            off_ids,
            off_verts,
            total,
        ];
        for (k, w) in words.iter().enumerate() {
            b[8 + 4 * k..12 + 4 * k].copy_from_slice(&(*w as u32).to_le_bytes());
        }
        Ok(b)
    }

    /// The smallest exponent `e` with `lo + 255·2^e ≥ hi` as the traversal decodes it.
    fn exponent(lo: f32, hi: f32) -> i8 {
        let mut q = Node4::EMPTY;
        q.origin = [lo, 0.0, 0.0];
        let ext = (f64::from(hi) - f64::from(lo)).max(0.0) / 255.0;
        // The binary exponent of `ext` (at most the smallest that fits).
        let mut e = if ext > 0.0 {
            ((((ext.to_bits() >> 52) & 0x7ff) as i32) - 1023).clamp(-126, 127)
        } else {
            -126
        };
        loop {
            q.exp[0] = e as i8;
            if q.decode(0, 255) >= hi || e >= 127 {
                return e as i8;
            }
            e += 1;
        }
    }

    /// The largest `q` whose decoding on axis `a` is at most `x`.
    fn quantize_down(n: &Node4, a: usize, x: f32) -> u8 {
        (0..=255u8)
            .rev()
            .find(|&q| n.decode(a, q) <= x)
            .unwrap_or(0)
    }

    /// The smallest `q` whose decoding on axis `a` is at least `x`.
    fn quantize_up(n: &Node4, a: usize, x: f32) -> u8 {
        (0..=255u8).find(|&q| n.decode(a, q) >= x).unwrap_or(255)
    }
}
