//! The watertight test of Woop, Benthin and Wald (JCGT 2(1), 2013).

use super::{Cull, TriangleKernel, TrianglePacket, resolve};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// Woop, Benthin & Wald, "Watertight Ray/Triangle Intersection" (JCGT 2(1), 2013).
///
/// Per ray ([`Shear`], computed once per packet): `kz` is the axis of the largest `|d|`, `kx`,
/// `ky` follow it cyclically and are swapped when `d[kz] < 0` (to keep the winding), and the
/// shear `Sx = d[kx]/d[kz]`, `Sy = d[ky]/d[kz]`, `Sz = 1/d[kz]` maps the ray onto the third
/// axis. Per triangle, with the vertices relative to the origin and permuted:
///
/// ```text
/// Ax = A[kx] − Sx·A[kz],  Ay = A[ky] − Sy·A[kz]        (same for B, C)
/// U = Cx·By − Cy·Bx   V = Ax·Cy − Ay·Cx   W = Bx·Ay − By·Ax
/// det = U + V + W     T = U·(Sz·A[kz]) + V·(Sz·B[kz]) + W·(Sz·C[kz])
/// ```
///
/// `U`, `V`, `W` are the 2-D edge functions of the origin against the projected triangle
/// (scaled barycentrics of A, B, C: `u = V/det`, `v = W/det`); a hit needs them all `≥ 0` or all
/// `≤ 0` (front faces have `det > 0`), `det ≠ 0`, and `0 < T < t_max·|det|` with the sign of
/// `det` folded in. **Why it is watertight:** a 2×2 determinant `a·b − c·d` of f32 values has
/// the sign of its exact value or is zero (rounding is monotonic), and where one is exactly
/// zero all three are recomputed in `f64`, where the products are exact — so every edge test
/// is exact for the projected vertices, which are the same bits for every triangle sharing a
/// vertex. Edges count as inside from both sides: no ray slips through a closed mesh, and a
/// ray through a shared edge or vertex may be reported by each triangle that owns it.
///
/// **Operation count per lane** (measured by `examples/opcount.rs`): per ray
/// `ops watertight/per ray: 3 div, 4 cmp` ([`Shear::new`]); per triangle
/// `ops watertight/miss: 12 mul, 18 add, 6 cmp`,
/// `ops watertight/hit: 19 mul, 22 add, 1 div, 15 cmp`; a lane with an exactly zero edge
/// function adds 6 mul and 3 add in `f64`
/// (`ops watertight/zero edge: 25 mul, 25 add, 1 div, 21 cmp`).
///
/// **Edge cases.** `det = 0` (a ray parallel to the triangle, or a degenerate projection) is a
/// miss; NaN fails the compares; a zero direction never reaches the kernel (rays are
/// sanitised).
///
/// **Range.** Watertight for meshes of size `2^-40…2^30` (`U`, `V`, `W` and `T` are products
/// of two and three coordinates: beyond that range they under- or overflow and rays leak);
/// tested at both ends by `tests/suite/kernels/watertight_range_ends.rs`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Watertight;

/// The per-ray constants of [`Watertight`]: the axis permutation (as lane masks: per permuted
/// axis, "is x" and "is y", z otherwise), the permuted origin and the shear.
#[derive(Clone, Copy, Debug)]
pub struct Shear<L: Lane> {
    kx: (L::Mask, L::Mask),
    ky: (L::Mask, L::Mask),
    kz: (L::Mask, L::Mask),
    origin: V3<L>,
    sx: L,
    sy: L,
    sz: L,
}

impl<L: Lane> Shear<L> {
    /// The permutation and shear of each ray lane: 3 div, 3 cmp (plus one for the sign).
    #[inline(always)]
    #[must_use]
    pub fn new(ray: &RayPacket<L>) -> Self {
        let d = ray.dir;
        // 1. kz: the axis of the largest |d| (x before y before z on ties, as max_dim does).
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        let z_x = ax.gt(ay) & ax.gt(az);
        let z_y = !z_x & ay.gt(az);
        let z_z = !(z_x | z_y);
        // 2. kx, ky follow cyclically: kz = x → (y, z); y → (z, x); z → (x, y).
        let kx0 = (z_z, z_x);
        let ky0 = (z_y, z_z);
        let kz = (z_x, z_y);
        let dz = pick(kz, d);
        // 3. Swap kx and ky when d[kz] < 0, to keep the winding.
        let neg = dz.lt(L::from_f32(0.0));
        let kx = choose::<L>(neg, ky0, kx0);
        let ky = choose::<L>(neg, kx0, ky0);
        // 4. The shear constants.
        let s = Shear {
            kx,
            ky,
            kz,
            origin: ray.origin,
            sx: L::from_f32(0.0),
            sy: L::from_f32(0.0),
            sz: L::from_f32(0.0),
        };
        let dp = s.permute(d);
        Shear {
            origin: s.permute(ray.origin),
            sx: dp.x / dp.z,
            sy: dp.y / dp.z,
            sz: L::from_f32(1.0) / dp.z,
            ..s
        }
    }

    /// `(v[kx], v[ky], v[kz])` per lane.
    #[inline(always)]
    fn permute(&self, v: V3<L>) -> V3<L> {
        V3::new(pick(self.kx, v), pick(self.ky, v), pick(self.kz, v))
    }
}

/// `p` in the lanes of `neg`, `q` in the others, for an axis given as masks (`Shear::new`).
/// (Functions, not closures, here and in [`signs`]: a closure may be left out of line, and so
/// run without the target features of a level's copy.)
#[inline(always)]
fn choose<L: Lane>(
    neg: L::Mask,
    p: (L::Mask, L::Mask),
    q: (L::Mask, L::Mask),
) -> (L::Mask, L::Mask) {
    (
        (neg & p.0) | q.0.and_not(neg),
        (neg & p.1) | q.1.and_not(neg),
    )
}

/// The edge functions' signs: which are below zero, which above.
#[inline(always)]
fn signs<L: Lane>(zero: L, u: L, v: L, w: L) -> ([L::Mask; 3], [L::Mask; 3]) {
    (
        [u.lt(zero), v.lt(zero), w.lt(zero)],
        [u.gt(zero), v.gt(zero), w.gt(zero)],
    )
}

/// Lane 0's axis `k` (given as masks: "is x", "is y") as an index.
#[inline(always)]
fn axis<L: Lane>(k: (L::Mask, L::Mask)) -> usize {
    if k.0.test(0) {
        0
    } else if k.1.test(0) {
        1
    } else {
        2
    }
}

/// `v[k]` per lane, for `k` given as masks ("is x", "is y").
#[inline(always)]
fn pick<L: Lane>(k: (L::Mask, L::Mask), v: V3<L>) -> L {
    L::select(k.0, v.x, L::select(k.1, v.y, v.z))
}

impl TriangleKernel for Watertight {
    const NAME: &'static str = "watertight";
    type Rays<L: Lane> = Shear<L>;

    #[inline(always)]
    fn prepare<L: Lane>(rays: &RayPacket<L>) -> Shear<L> {
        Shear::new(rays)
    }

    #[inline(always)]
    fn maybe_intersect<L: Lane>(
        ray: &RayPacket<L>,
        sh: &Shear<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        // 1. Vertices relative to the origin, permuted so that the ray runs along the third axis.
        let a = sh.permute(tri.a) - sh.origin;
        let b = sh.permute(tri.b) - sh.origin;
        let c = sh.permute(tri.c) - sh.origin;
        sheared(ray, sh, a, b, c, cull)
    }

    /// Lane 0's `kx`, `ky`, `kz`.
    #[inline(always)]
    fn order<L: Lane>(sh: &Shear<L>) -> [usize; 3] {
        [axis::<L>(sh.kx), axis::<L>(sh.ky), axis::<L>(sh.kz)]
    }

    /// One ray, the triangles given in its axis order: step 1 selects nothing.
    #[inline(always)]
    fn maybe_intersect_one<L: Lane>(
        ray: &RayPacket<L>,
        sh: &Shear<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        let (a, b, c) = (tri.a - sh.origin, tri.b - sh.origin, tri.c - sh.origin);
        sheared(ray, sh, a, b, c, cull)
    }
}

/// Steps 2–6 of [`Watertight`], from the permuted relative vertices.
#[inline(always)]
fn sheared<L: Lane>(
    ray: &RayPacket<L>,
    sh: &Shear<L>,
    a: V3<L>,
    b: V3<L>,
    c: V3<L>,
    cull: Cull,
) -> Option<LaneHit<L>> {
    let zero = L::from_f32(0.0);
    // 2. Shear x and y (z is scaled in step 5, only for lanes that pass the edges).
    let (ax, ay) = (a.x - sh.sx * a.z, a.y - sh.sy * a.z);
    let (bx, by) = (b.x - sh.sx * b.z, b.y - sh.sy * b.z);
    let (cx, cy) = (c.x - sh.sx * c.z, c.y - sh.sy * c.z);
    // 3. Edge functions: scaled barycentrics of A, B and C.
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    // 4. An exactly zero edge function may hide the sign: recompute in f64 (exact products).
    let (mut lt, mut gt) = signs(zero, u, v, w);
    // (A loop, not an iterator chain: its closures may be left out of line, and so run without
    // the target features of a level's copy.)
    let mut redo = L::Mask::splat(false);
    let e = [u, v, w];
    for k in 0..3 {
        redo = redo | e[k].is_finite().and_not(lt[k] | gt[k]);
    }
    if redo.any() {
        (u, v, w) = precise(redo, [ax, ay, bx, by, cx, cy], u, v, w);
        (lt, gt) = signs(zero, u, v, w);
    }
    // 5. Edge tests: all ≥ 0 (front face, det > 0) or, two-sided, all ≤ 0.
    let front = !(lt[0] | lt[1] | lt[2]);
    let mut mask = if cull.back() {
        front
    } else {
        front | !(gt[0] | gt[1] | gt[2])
    };
    if mask.none() {
        return None;
    }
    let det = u + v + w;
    let back = det.lt(zero);
    let ad = L::select(back, -det, det);
    mask = mask & ad.gt(zero);
    if mask.none() {
        return None;
    }
    // 6. Hit distance from the scaled z of the vertices; the interval, then the one division.
    let t = u * (sh.sz * a.z) + v * (sh.sz * b.z) + w * (sh.sz * c.z);
    let sgn = |x: L| L::select(back, -x, x);
    resolve(ray, mask, sgn(t), sgn(v), sgn(w), ad)
}

/// Recomputes `U`, `V`, `W` of the `redo` lanes in `L::Precise` (`f64`), where the products of
/// f32 values are exact, then rounds them back.
#[inline(never)]
fn precise<L: Lane>(redo: L::Mask, p: [L; 6], mut u: L, mut v: L, mut w: L) -> (L, L, L) {
    let mut bits = redo.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        let [ax, ay, bx, by, cx, cy] = p.map(|x| x.precise_lane(i));
        let back = |x: L::Precise| L::Scalar::from_f64(x.lane(0).to_f64());
        u = u.with_lane(i, back(cx * by - cy * bx));
        v = v.with_lane(i, back(ax * cy - ay * cx));
        w = w.with_lane(i, back(bx * ay - by * ax));
        bits &= bits - 1;
    }
    (u, v, w)
}
