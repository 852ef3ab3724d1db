//! A scene's triangles split into parts with a bounding sphere each (raylane's [`Mesh`] and
//! [`FocalMesh`]): how a user of the crate holds a scene of more than a few dozen triangles,
//! and raylane's answer to a BVH at these sizes.
//!
//! The split is a median split along the longest axis of the centroids, repeated until each
//! part holds at most `size` triangles (set-up, not timed, as Embree's BVH build is not). Per
//! packet of primary rays, every part's bounding sphere is tested with the focal sphere test,
//! and the triangles (focal test) only of parts some lane may hit; the closest hit is merged
//! across parts.

use std::hint::black_box;

use glam::Vec3;
use raylane::focal::FocalMesh;
use raylane::mesh::Mesh;
use raylane::set::Sets;
use raylane::triangle::{FocalTriangle, Triangle};
use raylane::{Lane, Mask, Query, RayPacket};

/// Triangles in parts, each part its own vertex and index arrays (unshared vertices).
pub struct Parts {
    positions: Vec<Vec<Vec3>>,
    indices: Vec<Vec<[u32; 3]>>,
    /// The input index of each part's triangles.
    ids: Vec<Vec<u32>>,
}

impl Parts {
    /// Splits `tris` into parts of at most `size` triangles.
    pub fn new(tris: &[Triangle], size: usize) -> Self {
        let mut order: Vec<usize> = (0..tris.len()).collect();
        let centroid = |i: usize| (tris[i].a() + tris[i].b() + tris[i].c()) / 3.0;
        let mut groups = Vec::new();
        split(&mut order, size.max(1), &centroid, &mut groups);
        let mut parts = Parts {
            positions: Vec::new(),
            indices: Vec::new(),
            ids: Vec::new(),
        };
        for g in groups {
            parts.ids.push(g.iter().map(|&i| i as u32).collect());
            let mut pos = Vec::with_capacity(3 * g.len());
            let mut idx = Vec::with_capacity(g.len());
            for i in g {
                let k = pos.len() as u32;
                pos.extend([tris[i].a(), tris[i].b(), tris[i].c()]);
                idx.push([k, k + 1, k + 2]);
            }
            parts.positions.push(pos);
            parts.indices.push(idx);
        }
        parts
    }

    /// Number of parts.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True when there are no parts.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The input index of each part's triangles (`ids()[p][i]` for triangle `i` of part `p`).
    pub fn ids(&self) -> &[Vec<u32>] {
        &self.ids
    }

    /// The parts as meshes with their bounding spheres (Ritter), for rays from anywhere.
    pub fn meshes(&self) -> Vec<Mesh<'_>> {
        self.positions
            .iter()
            .zip(&self.indices)
            .map(|(p, i)| Mesh::bounded(p, i))
            .collect()
    }

    /// Storage for the focal caches of every part.
    pub fn storage(&self) -> Vec<Vec<FocalTriangle<f32>>> {
        let empty = FocalTriangle::new(Vec3::ZERO, &Triangle::new(Vec3::X, Vec3::Y, Vec3::Z));
        self.indices.iter().map(|i| vec![empty; i.len()]).collect()
    }

    /// The parts as focal meshes for rays from `eye`, each with its bounding sphere (Ritter).
    pub fn focus<'c>(
        &'c self,
        eye: Vec3,
        storage: &'c mut [Vec<FocalTriangle<f32>>],
    ) -> Vec<FocalMesh<'c>> {
        self.positions
            .iter()
            .zip(&self.indices)
            .zip(storage.iter_mut())
            .map(|((p, i), out)| {
                let mesh = Mesh::bounded(p, i);
                raylane::focal::FocalMesh::new(&mesh, eye, out)
                    .expect("storage() sizes every cache")
            })
            .collect()
    }
}

/// Median split of `order` (triangle indices) along the longest axis of their centroids.
fn split(
    order: &mut [usize],
    size: usize,
    centroid: &impl Fn(usize) -> Vec3,
    groups: &mut Vec<Vec<usize>>,
) {
    if order.len() <= size {
        groups.push(order.to_vec());
        return;
    }
    let (lo, hi) = order.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &i| (lo.min(centroid(i)), hi.max(centroid(i))),
    );
    let e = hi - lo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    order.sort_by(|&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
    let (l, r) = order.split_at_mut(order.len() / 2);
    split(l, size, centroid, groups);
    split(r, size, centroid, groups);
}

/// One frame: the closest hit of every packet over the parts, one query over them ([`Sets`]:
/// each part's bounding sphere first, then its triangles; ties keep the earlier part); returns
/// the number of lanes hit.
#[inline(never)]
pub fn frame<L: Lane>(packets: &[RayPacket<L>], meshes: &[FocalMesh]) -> u32 {
    let mut n = 0;
    for p in packets {
        let h = Sets(meshes).closest(black_box(p));
        n += h.mask.bits().count_ones();
        black_box(&h);
    }
    n
}

/// The closest hit of every ray (`t` only is meaningful for the checks), first `rays` lanes.
pub fn answers<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[FocalMesh],
    rays: usize,
) -> Vec<Option<f32>> {
    packets
        .iter()
        .flat_map(|p| {
            let h = Sets(meshes).closest(p);
            (0..L::LANES).map(move |i| h.mask.test(i).then(|| h.t.lane(i)))
        })
        .take(rays)
        .collect()
}
