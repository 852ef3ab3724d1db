//! Triangle tests that run on data computed once per triangle.

use super::{Cull, Triangle, TrianglePacket};
use crate::kernel::LaneHit;
use crate::lane::Lane;
use crate::ray::RayPacket;

/// A ray–triangle method that reads a record computed once per triangle (a plane, a
/// projection, an affine transform) instead of the three vertices.
///
/// [`precompute`](Self::precompute) is one generic body over [`Lane`], like the test itself:
/// lane `i` of the record is the record of the triangle in lane `i`, the same bits at every
/// width (a record computed from a splat packet is a splat), and under
/// [`Counted`](crate::opcount::Counted) it measures the precomputation's own operation count.
/// Every implementor is also a [`TriangleKernel`](super::TriangleKernel) that precomputes on the fly, so the entry
/// points, the checker and the tests run it unchanged; store records with [`precompute_all`]
/// and test them with [`test`](Self::test) to pay the precomputation once.
///
/// ```
/// use glam::Vec3;
/// use raylane::triangle::{PrecomputedKernel, Triangle, TrianglePacket, Wald};
/// use raylane::{Cull, RayPacket};
///
/// let tri = Triangle::new(Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0));
/// let rec = Wald::precompute(&TrianglePacket::<f32>::splat(&tri)); // once per triangle
/// let ray = raylane::Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
/// let hit = Wald::test(&RayPacket::<f32>::splat(&ray), &rec, Cull::None).unwrap().normalized();
/// assert_eq!((hit.t, hit.u, hit.v), (5.0, 0.25, 1.0 / 3.0));
/// ```
pub trait PrecomputedKernel {
    /// Bytes of the record per triangle, as the method stores it in memory.
    const BYTES: usize;
    /// The record, one triangle per lane.
    type Prim<L: Lane>: Copy;
    /// The records of the triangles in `tri`'s lanes.
    fn precompute<L: Lane>(tri: &TrianglePacket<L>) -> Self::Prim<L>;
    /// The hit of each ray lane on the record in the same lane (as
    /// [`TriangleKernel::intersect`](super::TriangleKernel::intersect): `u`, `v` may be
    /// deferred, see [`LaneHit::normalized`]).
    /// `None` when every lane failed one of its tests (its early exits).
    fn test<L: Lane>(ray: &RayPacket<L>, pre: &Self::Prim<L>, cull: Cull) -> Option<LaneHit<L>>;
}

/// Implements [`TriangleKernel`] for a [`PrecomputedKernel`] by precomputing on the fly, with
/// the checker's name.
macro_rules! precomputed_triangle_kernel {
    ($k:ty, $name:literal) => {
        impl $crate::triangle::TriangleKernel for $k {
            const NAME: &'static str = $name;
            type Rays<L: $crate::lane::Lane> = ();

            #[inline(always)]
            fn prepare<L: $crate::lane::Lane>(_: &$crate::ray::RayPacket<L>) -> Self::Rays<L> {}

            #[inline(always)]
            fn maybe_intersect<L: $crate::lane::Lane>(
                ray: &$crate::ray::RayPacket<L>,
                _: &(),
                tri: &$crate::triangle::TrianglePacket<L>,
                cull: $crate::triangle::Cull,
            ) -> Option<$crate::kernel::LaneHit<L>> {
                use $crate::triangle::PrecomputedKernel as _;
                <$k>::test(ray, &<$k>::precompute(tri), cull)
            }
        }
    };
}
pub(crate) use precomputed_triangle_kernel;

/// The axis of the largest `|n|` component, as masks ("is x", "is y"; z otherwise), x before
/// y before z on ties: 3 cmp.
#[inline(always)]
pub(crate) fn dominant<L: Lane>(n: crate::vec3::V3<L>) -> (L::Mask, L::Mask) {
    let (ax, ay, az) = (n.x.abs(), n.y.abs(), n.z.abs());
    let is_x = ax.ge(ay) & ax.ge(az);
    let is_y = !is_x & ay.ge(az);
    (is_x, is_y)
}

/// `(v[k], v[k+1], v[k+2])` (indices mod 3) per lane, for `k` given as masks: the projection
/// axis first, then the two axes of the projection plane in cyclic order (no arithmetic).
#[inline(always)]
pub(crate) fn cyclic<L: Lane>(k: (L::Mask, L::Mask), v: crate::vec3::V3<L>) -> crate::vec3::V3<L> {
    let s = |x: L, y: L, z: L| L::select(k.0, x, L::select(k.1, y, z));
    crate::vec3::V3::new(s(v.x, v.y, v.z), s(v.y, v.z, v.x), s(v.z, v.x, v.y))
}

/// Records of `tris` into `out`, one per triangle, each in every lane (from
/// [`TrianglePacket::splat`]); returns the number written (at most `out.len()`). Build them
/// once; [`PrecomputedKernel::test`] reads them.
pub fn precompute_all<K: PrecomputedKernel, L: Lane>(
    tris: &[Triangle],
    out: &mut [K::Prim<L>],
) -> usize {
    let mut n = 0;
    for (t, slot) in tris.iter().zip(out.iter_mut()) {
        *slot = K::precompute(&TrianglePacket::splat(t));
        n += 1;
    }
    n
}
