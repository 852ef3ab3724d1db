//! Watertightness, measured: closed meshes with shared vertices, rays aimed exactly at shared
//! edges and vertices (axis-aligned and oblique, from outside and inside), and random rays.
//!
//! For every ray the expected number of surface crossings is known by construction: a ray from
//! outside is aimed through a surface point `P` and then through a point `Q` strictly inside
//! the (convex) mesh, so it crosses twice; a ray from an inside point crosses once. Hits are
//! grouped by `t` (relative gap 1e-5): a **leak** is a ray with fewer groups than crossings,
//! a **double hit** a group reported by more than one triangle. Required: no leak for `plucker`,
//! `watertight` and `focal`, and no double hit for `focal`; the counts of `moller` and `cramer`
//! are printed (`cargo test --test watertight -- --nocapture`).

use std::collections::HashMap;

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::V3;
use raylane::mesh::Mesh;
use raylane::sphere::SphereKernel;
use raylane::sphere::focal::FocalKernel;
use raylane::triangle::{FocalTriangle, TriangleKernel};
use raylane::{Ray, RayPacket};
use raylane_lab::demo::shapes;
use raylane_lab::registry::{Kernel, Prim, Visitor};

pub(crate) struct Shape {
    name: &'static str,
    pub(crate) pos: Vec<Vec3>,
    pub(crate) idx: Vec<[u32; 3]>,
    center: Vec3,
    size: f32,
}

/// `v` as an exact `f64` vector.
fn w(v: Vec3) -> V3<f64> {
    V3::splat(v)
}

impl Shape {
    /// Orients every triangle outward (the shapes are convex about `center`).
    fn new(
        name: &'static str,
        pos: Vec<Vec3>,
        mut idx: Vec<[u32; 3]>,
        center: Vec3,
        size: f32,
    ) -> Shape {
        for t in &mut idx {
            let [a, b, c] = t.map(|i| w(pos[i as usize]));
            if (b - a).cross(c - a).dot(a - w(center)) < 0.0 {
                t.swap(1, 2);
            }
        }
        // Closed and manifold: every directed edge once, its twin once.
        let mut edges = HashMap::new();
        for t in &idx {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "{name}: edge {a}-{b} used twice in one direction");
            assert_eq!(
                edges.get(&(b, a)),
                Some(&1),
                "{name}: edge {a}-{b} has no twin"
            );
        }
        Shape {
            name,
            pos,
            idx,
            center,
            size,
        }
    }

    /// Strictly inside, by a margin relative to the size.
    fn inside(&self, q: V3<f64>) -> bool {
        self.idx.iter().all(|t| {
            let [a, b, c] = t.map(|i| w(self.pos[i as usize]));
            let n = (b - a).cross(c - a);
            let len = n.dot(n).sqrt();
            n.dot(q - a) < -1e-4 * len * self.size as f64
        })
    }
}

/// The demo's icosphere of frequency `n` (a geodesic sphere over shared vertices), radius 2
/// about an off-axis centre.
fn icosphere(n: u32) -> Shape {
    let mut pos = vec![Vec3::ZERO; shapes::icosphere_vertices(n)];
    let mut idx = vec![[0; 3]; shapes::icosphere_triangles(n)];
    assert!(shapes::icosphere(n, &mut pos, &mut idx).is_some());
    let center = Vec3::new(0.3, -0.2, 0.1);
    let r = 2.0;
    let pos = pos.into_iter().map(|p| center + p * r).collect();
    Shape::new("icosphere", pos, idx, center, r)
}

fn cube() -> Shape {
    let c = Vec3::new(0.25, 0.5, -0.75);
    let h = 1.5;
    let pos: Vec<Vec3> = (0..8)
        .map(|i| {
            let s = |b: u32| if i >> b & 1 == 1 { h } else { -h };
            c + Vec3::new(s(0), s(1), s(2))
        })
        .collect();
    // Two triangles per face, split along alternating diagonals.
    let idx = vec![
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5], // z = ∓h
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6], // y = ∓h
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3], // x = ∓h
    ];
    Shape::new("cube", pos, idx, c, h)
}

/// A double cone: two fans of 8 triangles around the apexes, over a convex octagon with
/// dyadic coordinates (so points at dyadic fractions of every edge are exact in f32).
fn double_cone() -> Shape {
    let c = Vec3::new(0.25, -0.5, 0.125);
    let ring = [
        (2.0, 0.0),
        (1.5, 1.5),
        (0.0, 2.0),
        (-1.5, 1.5),
        (-2.0, 0.0),
        (-1.5, -1.5),
        (0.0, -2.0),
        (1.5, -1.5),
    ];
    let mut pos = vec![c + Vec3::new(0.0, 0.0, 2.0), c + Vec3::new(0.0, 0.0, -2.0)];
    pos.extend(ring.iter().map(|&(x, y)| c + Vec3::new(x, y, 0.0)));
    let mut idx = Vec::new();
    for i in 0..8u32 {
        let (a, b) = (2 + i, 2 + (i + 1) % 8);
        idx.push([0, a, b]);
        idx.push([1, b, a]);
    }
    Shape::new("double cone", pos, idx, c, 2.0)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Target {
    Vertex,
    EdgeExact,
    EdgeMidpoint,
    Interior,
}

/// A ray and the number of surface crossings it must report.
pub(crate) struct Case {
    pub(crate) ray: Ray,
    pub(crate) crossings: usize,
    target: Target,
    axis: bool,
}

/// Points to aim at: every vertex, exact dyadic points of every edge (kept only when the f32
/// arithmetic is exact), every edge midpoint rounded to f32, and random interior points.
fn targets(s: &Shape, rng: &mut SmallRng) -> Vec<(Vec3, Target)> {
    let mut out: Vec<(Vec3, Target)> = s.pos.iter().map(|&p| (p, Target::Vertex)).collect();
    let mut seen = HashMap::new();
    for t in &s.idx {
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            if seen.insert((i.min(j), i.max(j)), ()).is_some() {
                continue;
            }
            let (a, b) = (s.pos[i as usize], s.pos[j as usize]);
            out.push(((a + b) * 0.5, Target::EdgeMidpoint));
            for f in [0.25f32, 0.375, 0.75] {
                let p = a + (b - a) * f;
                // Exact when a + f(b − a) equals the real point (checked in f64).
                let e = w(a) + (w(b) - w(a)).scale(f as f64);
                if w(p) == e {
                    out.push((p, Target::EdgeExact));
                }
            }
        }
    }
    for t in &s.idx {
        let [a, b, c] = t.map(|i| s.pos[i as usize]);
        // One random interior point per triangle: the control group (no method leaks there).
        for _ in 0..1 {
            let (u, v) = (rng.random_range(0.0..1.0f32), rng.random_range(0.0..1.0f32));
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            out.push((a + (b - a) * u + (c - a) * v, Target::Interior));
        }
    }
    out
}

pub(crate) fn cases(s: &Shape, seed: u64) -> Vec<Case> {
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut out = Vec::new();
    for (p, target) in targets(s, &mut rng) {
        // Oblique: through an interior point Q near the centre.
        for _ in 0..2 {
            let q = s.center
                + Vec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                ) * (0.3 * s.size);
            if !s.inside(w(q)) {
                continue;
            }
            let o = p + (p - q) * rng.random_range(1.5..4.0f32);
            out.push(Case {
                ray: Ray::new(o, p - o),
                crossings: 2,
                target,
                axis: false,
            });
            out.push(Case {
                ray: Ray::new(q, p - q),
                crossings: 1,
                target,
                axis: false,
            });
        }
        // Axis-aligned: the line through P along ±x, ±y, ±z, when it enters the interior.
        for k in 0..3 {
            for sign in [1.0f32, -1.0] {
                let mut v = Vec3::ZERO;
                v[k] = sign;
                let q = p + v * (0.25 * s.size);
                if !s.inside(w(q)) {
                    continue;
                }
                // Only coordinate k changes, so the lines pass exactly through P.
                let o = p - v * (3.0 * s.size);
                out.push(Case {
                    ray: Ray::new(o, v),
                    crossings: 2,
                    target,
                    axis: true,
                });
                out.push(Case {
                    ray: Ray::new(q, -v),
                    crossings: 1,
                    target,
                    axis: true,
                });
            }
        }
    }
    out
}

/// The methods compared: every triangle kernel of the registry (named as the checker and the
/// study table name them: `focal` for the triangle focal cache).
pub type Method = Kernel;

/// Every triangle kernel of the registry.
pub fn methods() -> impl Iterator<Item = Method> {
    Kernel::of(Prim::Triangle)
}

/// All hits `(t, triangle)` of one ray.
fn hits(m: Method, s: &Shape, ray: &Ray, cache: &mut [FocalTriangle<f32>]) -> Vec<(f32, u32)> {
    let mesh = Mesh::new(&s.pos, &s.idx);
    let rp = RayPacket::<f32>::splat(ray);
    let mut out = Vec::new();
    let push = |h: raylane::Hit| {
        assert!(h.t.is_finite() && h.u.is_finite() && h.v.is_finite());
        out.push((h.t, h.index));
    };
    struct All<'a, F> {
        mesh: &'a Mesh<'a>,
        rp: &'a RayPacket<f32>,
        eye: Vec3,
        cache: &'a mut [FocalTriangle<f32>],
        push: F,
    }
    impl<F: FnMut(raylane::Hit)> Visitor for All<'_, F> {
        type Output = ();
        fn triangle<K: TriangleKernel>(self, _: Kernel) {
            let ray = self.rp.ray(0);
            raylane::Query::all(
                &raylane::set::Using::<_, K>::new(self.mesh),
                &ray,
                self.push,
            );
        }
        fn focal_triangle(self, _: Kernel) {
            if let Ok(fm) = raylane::focal::FocalMesh::new(self.mesh, self.eye, self.cache) {
                raylane::Query::all(&fm, &self.rp.ray(0), self.push);
            }
        }
        fn sphere<K: SphereKernel>(self, k: Kernel) {
            unreachable!("{} is not a triangle kernel", k.name())
        }
        fn focal_sphere<K: FocalKernel>(self, k: Kernel, _: bool) {
            unreachable!("{} is not a triangle kernel", k.name())
        }
        fn plane(self, k: Kernel) {
            unreachable!("{} is not a triangle kernel", k.name())
        }
        fn focal_plane(self, k: Kernel) {
            unreachable!("{} is not a triangle kernel", k.name())
        }
    }
    m.visit(All {
        mesh: &mesh,
        rp: &rp,
        eye: ray.origin(),
        cache,
        push,
    });
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Rays shot, and how many leaked, were hit twice at one crossing, or had extra crossings.
#[derive(Default, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tally {
    pub rays: usize,
    pub leaks: usize,
    pub doubles: usize,
    pub extra: usize,
}

/// The closed meshes of the test: an icosphere, a cube and a double cone.
pub(crate) fn shapes() -> [Shape; 3] {
    [icosphere(4), cube(), double_cone()]
}

/// One method's totals over every mesh and ray of the test (the study table's columns).
pub fn totals(m: Method) -> Tally {
    let mut t = Tally::default();
    for (si, s) in shapes().iter().enumerate() {
        let mut cache = vec![FocalTriangle::never(); s.idx.len()];
        for c in &cases(s, 7 + si as u64) {
            judge(&hits(m, s, &c.ray, &mut cache), c.crossings, &mut t);
        }
    }
    t
}

/// Groups hits by `t` and compares with the expected crossings.
fn judge(h: &[(f32, u32)], crossings: usize, t: &mut Tally) {
    let mut groups: Vec<Vec<u32>> = Vec::new();
    let mut last = f32::NEG_INFINITY;
    for &(ti, tri) in h {
        if ti - last <= 1e-5 * ti.abs().max(1e-3) {
            groups.last_mut().unwrap().push(tri);
        } else {
            groups.push(vec![tri]);
        }
        last = ti;
    }
    t.rays += 1;
    if groups.len() < crossings {
        t.leaks += 1;
    }
    if groups.len() > crossings {
        t.extra += 1;
    }
    if groups.iter().any(|g| g.len() > 1) {
        t.doubles += 1;
    }
}

#[test]
fn closed_meshes_leak_and_double_hit_counts() {
    let shapes = shapes();
    let methods: Vec<Method> = methods().collect();
    let mut total: HashMap<(Method, Target), Tally> = HashMap::new();
    println!("watertightness: rays aimed at shared vertices/edges and random surface points");
    println!("| mesh | method | target | rays | leaks | double hits | extra hits |");
    println!("| --- | --- | --- | ---: | ---: | ---: | ---: |");
    for (si, s) in shapes.iter().enumerate() {
        let cs = cases(s, 7 + si as u64);
        let mut cache = vec![FocalTriangle::never(); s.idx.len()];
        let mut tally: HashMap<(Method, Target), Tally> = HashMap::new();
        let mut axis_rays = 0;
        for c in &cs {
            axis_rays += c.axis as usize;
            for &m in &methods {
                let h = hits(m, s, &c.ray, &mut cache);
                judge(&h, c.crossings, tally.entry((m, c.target)).or_default());
            }
        }
        let mut keys: Vec<_> = tally.keys().copied().collect();
        keys.sort();
        for k in keys {
            let t = tally[&k];
            println!(
                "| {} | {:?} | {:?} | {} | {} | {} | {} |",
                s.name, k.0, k.1, t.rays, t.leaks, t.doubles, t.extra
            );
            let e = total.entry(k).or_default();
            e.rays += t.rays;
            e.leaks += t.leaks;
            e.doubles += t.doubles;
            e.extra += t.extra;
        }
        println!(
            "| {} | ({} rays, {axis_rays} axis-aligned) | | | | | |",
            s.name,
            cs.len()
        );
    }
    println!("\ntotals per method:");
    for &m in &methods {
        let t = total
            .iter()
            .filter(|(k, _)| k.0 == m)
            .fold(Tally::default(), |a, (_, t)| Tally {
                rays: a.rays + t.rays,
                leaks: a.leaks + t.leaks,
                doubles: a.doubles + t.doubles,
                extra: a.extra + t.extra,
            });
        println!(
            "  {m:?}: {} rays, {} leaks, {} double hits, {} extra hits",
            t.rays, t.leaks, t.doubles, t.extra
        );
        match m {
            Kernel::Watertight | Kernel::Plucker => assert_eq!(t.leaks, 0, "{m:?} leaks"),
            Kernel::TriangleFocal => {
                assert_eq!(t.leaks, 0, "focal leaks");
                assert_eq!(t.doubles, 0, "focal double hits");
                assert_eq!(t.extra, 0, "focal extra hits");
            }
            _ => {}
        }
    }
}
