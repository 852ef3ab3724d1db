//! The [`Query`] implementation of the BVH: the same records as the flat sets, bit for bit.

use super::traverse::{View, World};
use super::{Bvh, LEAF_WIDTH, Leaf};
use crate::lane::{Lane, Mask};
use crate::query::{Hit, Hits, Query};
use crate::ray::{Ray, RayPacket};

/// A BVH answers like the flat set it was built over (triangles: [`Watertight`], spheres:
/// [`Robust`], culled as [`Bvh::with_cull`] says): `closest` gives the same [`Hit`] (`t`,
/// point, normal, face, index, `u`, `v`) bit for bit, for one ray (children in `f32x8`
/// lanes, leaves in `f32x4` lanes) and for packets of every width; `any` agrees; `all`
/// reports each hit primitive's records as the flat set does, in traversal order.
///
/// [`Watertight`]: crate::triangle::Watertight
/// [`Robust`]: crate::sphere::Robust
impl<P: Leaf> Query for Bvh<'_, P> {
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        closest_packet(self, &World, rays)
    }

    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        self.any_lanes(&World, rays)
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        self.all_lanes(&World, rays, f)
    }

    fn closest_ray(&self, ray: &Ray) -> Option<Hit> {
        closest_ray(self, &World, ray)
    }

    fn any_ray(&self, ray: &Ray) -> bool {
        self.any_one(&World, ray)
    }
}

/// The closest hits of a packet traversed in `view`, as records.
#[inline]
pub(crate) fn closest_packet<P: Leaf, V: View<P>, L: Lane>(
    bvh: &Bvh<'_, P>,
    view: &V,
    rays: &RayPacket<L>,
) -> Hits<L> {
    let (best, win) = bvh.closest_lanes(view, rays);
    P::records(rays, &best, bvh.cull, |i| {
        // The lanes that won with primitive `i` all point at the same leaf lane.
        let j =
            (0..L::LANES).find(|&j| best.mask.test(j) && best.index.as_ref().get(j) == Some(&i))?;
        let w = *win.get(j)? as usize;
        Some(bvh.leaves.get(w / LEAF_WIDTH)?.prim(w % LEAF_WIDTH))
    })
}

/// The closest hit of one ray traversed in `view`, as a record.
#[inline]
pub(crate) fn closest_ray<P: Leaf, V: View<P>>(
    bvh: &Bvh<'_, P>,
    view: &V,
    ray: &Ray,
) -> Option<Hit> {
    let (best, prim) = bvh.closest_one(view, ray)?;
    P::records(&RayPacket::<f32>::splat(ray), &best, bvh.cull, |_| {
        Some(prim)
    })
    .lane(0)
}
