//! Shading: Lambert's law under one light, checkerboards, the sky, gamma 2 (see the
//! [module docs](super)).

use glam::Vec3;

use super::render::Best;
use super::scene::unit;
use super::{Frame, ID_PLANE, ID_SPHERE, ID_TRIANGLE, Paint};
use raylane::lane::sqrt_f32;
use raylane::vec3::V3;

impl<const P: usize> Frame<'_, P> {
    /// The colour of lane `i` (origin `o`, direction `d`), as RGB8.
    pub(super) fn shade(&self, o: Vec3, d: Vec3, best: &Best, i: usize) -> [u8; 3] {
        let (o, d) = (V3::<f32>::from(o), V3::<f32>::from(d));
        let grey = Paint::Flat([0.7; 3]);
        let t = best.t[i];
        let p = o + d.scale(t);
        let (n, paint) = match best.id[i] {
            ID_SPHERE => {
                let j = best.index[i] as usize;
                let Some(s) = self.scene.spheres.get(j) else {
                    return to_rgb(sky(d));
                };
                let paint = self.scene.sphere_paints.get(j).copied().unwrap_or(grey);
                ((p - V3::from(s.center())).div_by(s.radius()), paint)
            }
            ID_PLANE => {
                let j = best.index[i] as usize;
                let Some(pl) = self.scene.planes.get(j) else {
                    return to_rgb(sky(d));
                };
                let paint = self.scene.plane_paints.get(j).copied().unwrap_or(grey);
                (V3::from(unit(pl.normal)), paint)
            }
            ID_TRIANGLE => {
                let piece = self.pieces.get(best.part[i] as usize).copied().flatten();
                let tri = piece.and_then(|pc| pc.mesh().triangle(best.index[i] as usize));
                let (Some(pc), Some(tri)) = (piece, tri) else {
                    return to_rgb(sky(d));
                };
                let (a, b, c) = (V3::from(tri.a()), V3::from(tri.b()), V3::from(tri.c()));
                let n = V3::from(unit((b - a).cross(c - a).into()));
                (n, pc.paint)
            }
            _ => return to_rgb(sky(d)),
        };
        // Face the viewer.
        let n = if n.dot(d) > 0.0 { -n } else { n };
        let base = match paint {
            Paint::Flat(c) => c,
            Paint::Checker { a, b, size } => {
                if floor(p.x / size).wrapping_add(floor(p.z / size)) & 1 == 0 {
                    a
                } else {
                    b
                }
            }
            Paint::Normal => {
                // The usual normal-map colours, stored as they are (no gamma).
                let c = |x: f32| ((x * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                return [c(n.x), c(n.y), c(n.z)];
            }
        };
        let lambert = n.dot(self.scene.light.into()).max(0.0);
        let k = 0.2 + 0.8 * lambert;
        to_rgb([base[0] * k, base[1] * k, base[2] * k])
    }
}

/// `⌊x⌋` by truncation (exact), saturating.
fn floor(x: f32) -> i32 {
    let i = x as i32;
    if (i as f32) > x { i.wrapping_sub(1) } else { i }
}

/// The sky for a ray that hits nothing: white at the horizon to blue overhead.
fn sky(d: V3<f32>) -> [f32; 3] {
    let a = d.y.max(0.0);
    let b = 1.0 - a;
    [0.95 * b + 0.35 * a, 0.97 * b + 0.55 * a, 1.0 * b + 0.9 * a]
}

/// Linear RGB in `[0, 1]` to RGB8 with a gamma of 2 (a square root).
pub(super) fn to_rgb(c: [f32; 3]) -> [u8; 3] {
    c.map(|x| (sqrt_f32(x.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
}
