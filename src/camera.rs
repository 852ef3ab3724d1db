//! A pinhole camera: primary rays that all start at one focal point.
//!
//! The image plane is given by the centre of pixel (0, 0) minus half a pixel (`corner`) and
//! the vectors `du`, `dv` that step one pixel right and down. Pixel `(x, y)`'s ray starts at
//! the focal point `eye` and has the unit direction of `corner + (x + ½)·du + (y + ½)·dv − eye`.
//! Every ray of the camera shares its origin, which is what the focal-point caches
//! ([`FocalSpheres`](crate::sphere::FocalSphere), [`FocalPlane`](crate::plane::FocalPlane))
//! exploit.

use core::marker::PhantomData;

use glam::Vec3;

use crate::lane::Lane;
use crate::ray::RayPacket;
use crate::vec3::V3;

/// A pinhole camera with a focal point and an image plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pinhole {
    /// The focal point: origin of every primary ray.
    pub eye: Vec3,
    /// Corner of the image plane (the outer corner of pixel (0, 0)).
    pub corner: Vec3,
    /// One pixel to the right.
    pub du: Vec3,
    /// One pixel down.
    pub dv: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// `v / |v|` with the crate's square root (`vsqrt.f32` on Cortex-M, not glam's software
/// `libm` root), or zero for a zero or non-finite vector.
fn unit(v: Vec3) -> Vec3 {
    let w = V3::<f32>::from(v);
    let n = w.length_squared().sqrt();
    if n > 0.0 && n.is_finite() {
        w.div_by(n).into()
    } else {
        Vec3::ZERO
    }
}

impl Pinhole {
    /// A camera at `eye` looking at `target`, with `up` roughly up, a vertical field of view
    /// of `vfov_degrees`, and an image of `width × height` pixels (square pixels).
    #[must_use]
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vfov_degrees: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let forward = unit(target - eye);
        let right = unit(forward.cross(up));
        let down = forward.cross(right);
        let half_h = libm::tanf(vfov_degrees.to_radians() * 0.5);
        let pixel = 2.0 * half_h / height.max(1) as f32;
        let du = right * pixel;
        let dv = down * pixel;
        let corner = eye + forward - du * (width as f32 * 0.5) - dv * (height as f32 * 0.5);
        Pinhole {
            eye,
            corner,
            du,
            dv,
            width,
            height,
        }
    }

    /// The rays of pixels `(x, y) … (x + L::LANES − 1, y)` of one image row, unit directions,
    /// interval `(0, +inf)`.
    ///
    /// **Pixels outside the image** (`x + i ≥ width` or `y ≥ height`, including columns past
    /// `u32::MAX`, which are counted without wrapping) get the empty interval `(+inf, −inf)`:
    /// they never hit, whatever their direction, and never alias another pixel. No input
    /// panics.
    #[must_use]
    pub fn row_packet<L: Lane>(&self, x: u32, y: u32) -> RayPacket<L> {
        self.packet(x, y, L::LANES)
    }

    /// The rays of the block of pixels at `(x, y)` whose shape [`block`] gives for `L` (lane
    /// `i` is pixel `(x + i mod w, y + i div w)`): 4 × 2 pixels for 8 lanes, 4 × 4 for 16. A
    /// block's rays are closer together than a row's, so a packet's frustum is tighter (in
    /// callgrind, x86-64-v3, the vendored bunny: 413 instructions per primary ray in 4 × 2
    /// blocks against 450 in rows of 8, 409 in 4 × 4 against 511 in rows of 16). Pixel `(x,
    /// y)`'s ray is the same, bit for bit, in a row, a block or a [`Tile`]; outside the image
    /// as [`row_packet`](Self::row_packet).
    #[must_use]
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub fn block_packet<L: Lane>(&self, x: u32, y: u32) -> RayPacket<L> {
        self.packet(x, y, block::<L>().0)
    }

    /// The tile of `W × H` pixels from `(x, y)`, for [`Query`](crate::Query): one call traces
    /// it in [`block_packet`](Self::block_packet)s of `L` and answers per pixel.
    #[must_use]
    pub fn tile<L: Lane, const W: usize, const H: usize>(
        &self,
        x: u32,
        y: u32,
    ) -> Tile<'_, L, W, H> {
        Tile {
            camera: self,
            x,
            y,
            lanes: PhantomData,
        }
    }

    /// Pixels `(x + i mod w, y + i div w)` in lane `i` (see [`row_packet`](Self::row_packet)).
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn packet<L: Lane>(&self, x: u32, y: u32, w: usize) -> RayPacket<L> {
        // Column and row of lane i, in u64 so that they cannot wrap (x, y ≤ u32::MAX, i < 2^32).
        let col = |i: usize| u64::from(x) + offset(i, w).0 as u64;
        let row = |i: usize| u64::from(y) + offset(i, w).1 as u64;
        let h = L::LANES.div_ceil(w);
        // A packet inside the image (so below 2^24 in both coordinates, where every integer
        // is an f32): its columns are `x + (i mod w)` added as f32 (exact, so the same bits
        // as lane by lane), and every lane is inside.
        let whole = u64::from(x) + w as u64 <= u64::from(self.width)
            && u64::from(y) + h as u64 <= u64::from(self.height)
            && self.width <= 1 << 24
            && self.height <= 1 << 24;
        let (px, py) = if whole {
            let (dx, dy) = (
                L::from_f32_fn(|i| offset(i, w).0 as f32),
                L::from_f32_fn(|i| offset(i, w).1 as f32),
            );
            let half = L::from_f32(0.5);
            (
                (L::from_f32(x as f32) + dx) + half,
                (L::from_f32(y as f32) + dy) + half,
            )
        } else {
            (
                L::from_f32_fn(|i| col(i) as f32 + 0.5),
                L::from_f32_fn(|i| row(i) as f32 + 0.5),
            )
        };
        let corner = V3::<L>::splat(self.corner);
        let target = corner + V3::splat(self.du).scale(px) + V3::splat(self.dv).scale(py);
        let d = target - V3::splat(self.eye);
        let dir = d.div_by(d.length_squared().sqrt());
        let inside = if whole {
            L::from_f32(f32::INFINITY)
        } else {
            L::from_f32_fn(|i| {
                if col(i) < u64::from(self.width) && row(i) < u64::from(self.height) {
                    f32::INFINITY
                } else {
                    0.0
                }
            })
        };
        RayPacket::new(V3::splat(self.eye), dir, L::from_f32(0.0), inside)
    }
}

/// The pixel block `(w, h)` of a packet of `L` in [`Pinhole::block_packet`]: `w` the power of
/// two at or above `√LANES` (1 × 1, 2 × 2, 4 × 2, 4 × 4).
#[must_use]
pub const fn block<L: Lane>() -> (usize, usize) {
    let mut w = 1;
    while w * w < L::LANES {
        w *= 2;
    }
    (w, L::LANES / w)
}

/// Lane `i`'s pixel in a block of `L` ([`block`]): `(i mod w, i div w)`.
#[must_use]
pub const fn block_lane<L: Lane>(i: usize) -> (usize, usize) {
    offset(i, block::<L>().0)
}

/// Lane `i`'s pixel in a packet `w` pixels wide.
const fn offset(i: usize, w: usize) -> (usize, usize) {
    (i % w, i / w)
}

/// A camera tile: `W × H` pixels from `(x, y)` of a [`Pinhole`] ([`Pinhole::tile`]), asked as
/// one query: `tree.closest(&camera.tile::<f32x8, 16, 16>(x, y))` gives `[[Option<Hit>; W];
/// H]`, `any` gives `[[bool; W]; H]`, `all` calls back with `(x, y, hit)` per hit. Every
/// answer equals that of the pixel's own ray ([`Pinhole::row_packet`] at one lane), bit for
/// bit. `W` and `H` are multiples of the [`block`] of `L` (refused when the program is
/// compiled otherwise); pixels outside the image have no hit.
#[derive(Clone, Copy, Debug)]
pub struct Tile<'c, L: Lane, const W: usize, const H: usize> {
    camera: &'c Pinhole,
    x: u32,
    y: u32,
    lanes: PhantomData<L>,
}

impl<L: Lane, const W: usize, const H: usize> Tile<'_, L, W, H> {
    /// Each block of the tile, row by row: its offset in the tile and its packet.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub fn packets(&self) -> impl Iterator<Item = (usize, usize, RayPacket<L>)> + '_ {
        (0..Self::BLOCKS).map(|k| self.block_in::<L>(k))
    }

    /// How many blocks of `L` it holds.
    pub(crate) const BLOCKS: usize = {
        let (bw, bh) = block::<L>();
        assert!(
            W.is_multiple_of(bw) && H.is_multiple_of(bh),
            "a tile is whole blocks of its lane type"
        );
        (W / bw) * (H / bh)
    };

    /// Block `k` of [`packets`](Self::packets) (row by row) in lanes `M` of `L`'s width (the
    /// same rays, bit for bit): a query made in the [SIMD level](crate::simd)'s own lanes
    /// makes its rays there too. (`M` of another width is not refused, as the level's
    /// branches for other widths are instantiated though never run; its packets would be the
    /// wrong shape.)
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub(crate) fn block_in<M: Lane>(&self, k: usize) -> (usize, usize, RayPacket<M>) {
        let (bw, bh) = block::<L>();
        let (dx, dy) = ((k % (W / bw)) * bw, (k / (W / bw)) * bh);
        let (x, y) = (self.x as u64 + dx as u64, self.y as u64 + dy as u64);
        // Blocks past u32::MAX are outside the image: its last column or row.
        let (x, y) = (
            u32::try_from(x).unwrap_or(u32::MAX),
            u32::try_from(y).unwrap_or(u32::MAX),
        );
        (dx, dy, self.camera.block_packet::<M>(x, y))
    }

    /// The tile's corner pixel.
    #[must_use]
    pub fn origin(&self) -> (u32, u32) {
        (self.x, self.y)
    }
}
