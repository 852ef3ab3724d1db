//! The world of `examples/game`: its shapes (the vendored bunny and generated ones), 10,000
//! actors on an arena, how they move, and the rays of a frame. Deterministic (seeded), and
//! shared with the scenes benchmark (`benches/examples/scenes.rs` includes this file), so that
//! raylane and Embree are timed on the same instances, moves and queries.

#![allow(dead_code)] // each includer uses part of it

use raylane::Ray;
use raylane::glam::Vec3;
use raylane::sphere::Sphere;
use raylane::triangle::Triangle;

/// Layers (instance masks): the ground, static props, moving props, agents.
pub const GROUND: u32 = 1;
/// Rocks and pillars.
pub const STATIC: u32 = 2;
/// Crates and bunnies.
pub const PROPS: u32 = 4;
/// The agents (they see each other past themselves: sight lines use every layer but this).
pub const AGENTS: u32 = 8;

/// Half the arena's side.
pub const ARENA: f32 = 200.0;

/// A shape's primitives, in object space (base on `y = 0`).
pub enum Prims {
    /// A triangle mesh.
    Mesh(Vec<Triangle>),
    /// A set of spheres.
    Balls(Vec<Sphere>),
}

/// A shape instances share.
pub struct Shape {
    pub name: &'static str,
    pub prims: Prims,
}

/// An actor: an instance of a shape that moves.
#[derive(Clone, Copy, Debug)]
pub struct Actor {
    pub shape: usize,
    pub layer: u32,
    pub pos: Vec3,
    pub vel: Vec3,
    pub angle: f32,
    pub spin: f32,
    pub scale: f32,
}

/// splitmix64: a small seeded generator (no dependency).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// `tests/data/bunny.bin` (u32 vertex count, u32 triangle count, f32 x y z per vertex, u16 a
/// b c per triangle, little-endian).
fn bunny() -> Vec<Triangle> {
    let b: &[u8] = include_bytes!("../../tests/data/bunny.bin");
    let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as usize;
    let f32_at = |o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    let (nv, nt) = (u32_at(0), u32_at(4));
    let v = |i: usize| Vec3::new(f32_at(8 + 12 * i), f32_at(12 + 12 * i), f32_at(16 + 12 * i));
    let base = 8 + 12 * nv;
    let ix = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]) as usize;
    (0..nt)
        .map(|k| {
            let o = base + 6 * k;
            Triangle::new(v(ix(o)), v(ix(o + 2)), v(ix(o + 4)))
        })
        .collect()
}

/// Triangles scaled to `height`, centred on the y axis, base on `y = 0`.
fn stand(tris: Vec<Triangle>, height: f32) -> Vec<Triangle> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in &tris {
        for p in [t.a(), t.b(), t.c()] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let s = height / (hi.y - lo.y);
    let base = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
    let f = |p: Vec3| (p - base) * s;
    tris.iter()
        .map(|t| Triangle::new(f(t.a()), f(t.b()), f(t.c())))
        .collect()
}

/// A box `[-x, x] × [0, 2y] × [-z, z]` (12 triangles, outward).
fn cuboid(x: f32, y: f32, z: f32) -> Vec<Triangle> {
    let p = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { -x } else { x },
            if i & 2 == 0 { 0.0 } else { 2.0 * y },
            if i & 4 == 0 { -z } else { z },
        )
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    quads
        .iter()
        .flat_map(|q| {
            [
                Triangle::new(p(q[0]), p(q[1]), p(q[2])),
                Triangle::new(p(q[0]), p(q[2]), p(q[3])),
            ]
        })
        .collect()
}

/// An icosphere of `steps` subdivisions, radii jittered by `rng` (a rock), base on `y = 0`.
fn rock(steps: u32, rng: &mut Rng) -> Vec<Triangle> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..steps {
        let mut mid = std::collections::HashMap::new();
        let mut half = |a: usize, b: usize, v: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a] + v[b]) * 0.5).normalize());
                v.len() - 1
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let (ab, bc, ca) = (half(a, b, &mut v), half(b, c, &mut v), half(c, a, &mut v));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    for p in &mut v {
        *p *= rng.range(0.8, 1.1);
    }
    stand(
        f.iter()
            .map(|&[a, b, c]| Triangle::new(v[a], v[b], v[c]))
            .collect(),
        1.2,
    )
}

/// The ground: a grid of `n × n` quads over the arena, gently rolling.
fn ground(n: usize) -> Vec<Triangle> {
    let h = |x: f32, z: f32| 0.4 * (x * 0.05).sin() * (z * 0.07).cos() - 0.5;
    let at = |i: usize, j: usize| {
        let x = -ARENA + 2.0 * ARENA * i as f32 / n as f32;
        let z = -ARENA + 2.0 * ARENA * j as f32 / n as f32;
        Vec3::new(x, h(x, z), z)
    };
    let mut out = Vec::with_capacity(2 * n * n);
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            out.push(Triangle::new(a, c, b));
            out.push(Triangle::new(a, d, c));
        }
    }
    out
}

/// An agent: a body and a head (two spheres).
fn agent() -> Vec<Sphere> {
    vec![
        Sphere::new(Vec3::new(0.0, 0.6, 0.0), 0.45),
        Sphere::new(Vec3::new(0.0, 1.35, 0.0), 0.3),
    ]
}

/// The shapes: 0 ground, 1 bunny, 2 crate, 3 rock, 4 pillar, 5 agent, 6 a cluster of balls.
pub fn shapes() -> Vec<Shape> {
    let mut rng = Rng::new(7);
    let balls = (0..24)
        .map(|_| {
            let c = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(0.2, 1.8),
                rng.range(-1.0, 1.0),
            );
            Sphere::new(c, rng.range(0.1, 0.35))
        })
        .collect();
    vec![
        Shape {
            name: "ground",
            prims: Prims::Mesh(ground(96)),
        },
        Shape {
            name: "bunny",
            prims: Prims::Mesh(stand(bunny(), 1.5)),
        },
        Shape {
            name: "crate",
            prims: Prims::Mesh(cuboid(0.6, 0.6, 0.6)),
        },
        Shape {
            name: "rock",
            prims: Prims::Mesh(rock(2, &mut rng)),
        },
        Shape {
            name: "pillar",
            prims: Prims::Mesh(cuboid(0.4, 2.0, 0.4)),
        },
        Shape {
            name: "agent",
            prims: Prims::Balls(agent()),
        },
        Shape {
            name: "balls",
            prims: Prims::Balls(balls),
        },
    ]
}

/// The shape of agents.
pub const AGENT: usize = 5;
/// The shape made of glass (the ball clusters): picking sees through it.
pub const GLASS: usize = 6;

/// The actors: the ground, then `n − 1` others, a tenth of them agents.
pub fn actors(n: usize, seed: u64) -> Vec<Actor> {
    let mut rng = Rng::new(seed);
    let mut out = vec![Actor {
        shape: 0,
        layer: GROUND,
        pos: Vec3::ZERO,
        vel: Vec3::ZERO,
        angle: 0.0,
        spin: 0.0,
        scale: 1.0,
    }];
    for i in 1..n {
        // Agents, bunnies, crates, rocks, pillars, balls: 10, 20, 30, 20, 15, 5 %.
        let k = i % 20;
        let (shape, layer, speed) = match k {
            0 | 1 => (AGENT, AGENTS, 4.0),
            2..=5 => (1, PROPS, 1.5),
            6..=11 => (2, PROPS, 1.5),
            12..=15 => (3, STATIC, 0.2),
            16..=18 => (4, STATIC, 0.2),
            _ => (6, PROPS, 1.0),
        };
        let a = rng.range(0.0, std::f32::consts::TAU);
        let v = rng.range(0.2, 1.0) * speed;
        out.push(Actor {
            shape,
            layer,
            pos: Vec3::new(rng.range(-ARENA, ARENA), 0.0, rng.range(-ARENA, ARENA)),
            vel: Vec3::new(v * a.cos(), 0.0, v * a.sin()),
            angle: rng.range(0.0, std::f32::consts::TAU),
            spin: rng.range(-1.0, 1.0),
            scale: if shape == AGENT || shape == 0 {
                1.0
            } else {
                rng.range(0.7, 1.6)
            },
        });
    }
    out
}

/// One step of `dt` seconds: everything moves, turns, and bounces off the arena's walls.
pub fn step(actors: &mut [Actor], dt: f32) {
    for a in actors.iter_mut() {
        a.pos += a.vel * dt;
        a.angle += a.spin * dt;
        for (p, v) in [(&mut a.pos.x, &mut a.vel.x), (&mut a.pos.z, &mut a.vel.z)] {
            if p.abs() > ARENA - 2.0 {
                *v = -v.abs() * p.signum();
            }
        }
    }
}

/// An actor's object→world transform: a turn about `y`, its scale, its position.
pub fn rows(a: &Actor) -> [[f32; 4]; 3] {
    let (s, c) = a.angle.sin_cos();
    let k = a.scale;
    [
        [c * k, 0.0, s * k, a.pos.x],
        [0.0, k, 0.0, a.pos.y],
        [-s * k, 0.0, c * k, a.pos.z],
    ]
}

/// The agents' eyes (their heads' centres).
pub fn eye(a: &Actor) -> Vec3 {
    a.pos + Vec3::new(0.0, 1.35, 0.0)
}

/// The agents among `actors` (indices).
pub fn agents(actors: &[Actor]) -> Vec<usize> {
    (0..actors.len())
        .filter(|&i| actors[i].shape == AGENT)
        .collect()
}

/// `n` sight lines between pairs of agents less than 60 units apart: `(from, to, ray)` with
/// the ray from one eye to the other over `(0, 1)`.
pub fn sight_lines(
    actors: &[Actor],
    agents: &[usize],
    n: usize,
    rng: &mut Rng,
) -> Vec<(usize, usize, Ray)> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let (a, b) = (
            agents[rng.below(agents.len())],
            agents[rng.below(agents.len())],
        );
        let (p, q) = (eye(&actors[a]), eye(&actors[b]));
        if a != b && (q - p).length() < 60.0 {
            out.push((a, b, Ray::with_interval(p, q - p, 0.0, 1.0)));
        }
    }
    out
}

/// `n` bullets: `(shooter, ray)`, each from inside its shooter's body, at another agent with
/// some spread, up to 150 units.
pub fn bullets(actors: &[Actor], agents: &[usize], n: usize, rng: &mut Rng) -> Vec<(usize, Ray)> {
    (0..n)
        .map(|_| {
            let s = agents[rng.below(agents.len())];
            let t = agents[rng.below(agents.len())];
            let from = actors[s].pos + Vec3::new(0.0, 0.9, 0.0);
            let aim = eye(&actors[t])
                + Vec3::new(
                    rng.range(-3.0, 3.0),
                    rng.range(-1.0, 0.5),
                    rng.range(-3.0, 3.0),
                );
            let d = (aim - from).normalize_or(Vec3::X);
            (s, Ray::with_interval(from, d, 0.0, 150.0))
        })
        .collect()
}

/// The light (a point high above the arena's corner).
pub const LIGHT: Vec3 = Vec3::new(150.0, 400.0, 100.0);

/// A shadow ray from `p` to the light, over `(2^-12, 1)` (off the surface it starts on).
pub fn shadow(p: Vec3) -> Ray {
    Ray::with_interval(p, LIGHT - p, 1.0 / 4096.0, 1.0)
}
