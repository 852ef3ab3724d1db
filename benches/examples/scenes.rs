//! The BVH benchmark of issues 14 and 20: meshes of 10^3 to 10^6 triangles and a field of
//! 10^5 spheres, traced by every contender with the same rays in one run, single thread (and
//! raylane's fastest contenders again on every core, in a table of their own).
//!
//! ```text
//! cargo run --release -p raylane-bench --features peers \
//!     --example scenes [-- --runs N] [--only NAME]...      (or: ./scripts/bench.sh scenes)
//! ```
//!
//! Scenes ([`raylane_bench::meshes`]): the vendored bunny (3,674 triangles) and its Loop
//! subdivisions (×1, ×2, ×3, ×4 = 940,544 triangles), spot, fandisk and the Stanford bunny
//! from `../shared/meshes` when present, 10^5 spheres. Rays: 640×480 primary rays from an eye
//! framing the scene; one cosine-weighted diffuse bounce (seeded) and one shadow ray to a point
//! light (any-hit) from every primary hit. The primary rays go in tiles of 16 × 16 pixels
//! made of 4 × 4 blocks, so that packets of 16 (8) consecutive rays are blocks of 4 × 4 (4 × 2)
//! pixels for every contender; raylane's camera tiles (`tree.closest(&cam.tile(x, y))`, 8 × 8
//! and 16 × 16) make the same rays inside the call.
//!
//! Contenders: Embree 3 (`rtcIntersect1/8/16`, `rtcOccluded1/8`, one-thread device), obvhs
//! (CWBVH), parry3d (`TriMesh`), raylane brute force with bounding spheres (parts of about
//! √n/2 triangles: `Watertight` x8, and the focal cache x8/x16 for primary rays with the cache
//! built inside each timed frame), and raylane's BVH once merged. Before timing, every
//! contender's answers are compared with the reference (raylane's scalar `Watertight` over the
//! parts, i.e. exact brute force; for the spheres, scalar `Robust` brute force on every 61st
//! ray): hit/miss disagreements and `t` differences beyond 10^-3 relative are counted, and a
//! contender with more than 10^-4 of its rays differing is reported and not timed.
//!
//! Each frame is run `--runs` times (default 7; 3 above 10^5 triangles), the contenders of one
//! kind of ray in turn (round robin, so that the machine's load drifts over all of them
//! alike), and the median kept.
//! The tables (markdown) go to stdout: scenes, build time and bytes per triangle, rays/s per
//! kind of ray with the ratio to Embree, rays/s against the triangle count, and the goals.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::time::Instant;

use glam::Vec3;
use raylane::bvh::bake::Baked;
use raylane::bvh::{Bvh, Leaf, Tri4};
use raylane::sphere::Robust;
use raylane::triangle::Moller;
use raylane::{Lane, Pinhole, Query, Ray, RayPacket};
use raylane_bench::bvh_peers::{
    EmbreeBvh, EmbreeRays, ObvhsBvh, ParryMesh, obvhs_rays, parry_rays,
};
use raylane_bench::bvh_raylane as rl;
use raylane_bench::cpu;
use raylane_bench::meshes::{self, Answers, MeshData, SurfaceHit, Workload};
use raylane_bench::parts::{self, Parts};
use wide::{f32x8, f32x16};

/// The three kinds of rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Primary,
    Diffuse,
    Shadow,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Primary => "primary",
            Kind::Diffuse => "diffuse (incoherent)",
            Kind::Shadow => "shadow (any hit)",
        }
    }
}

/// One contender on one kind of ray: its frame and its answers.
struct Job<'a> {
    name: String,
    /// Rays its frame traces.
    rays: usize,
    /// True when it traces every ray (its answers are then thinned to the reference's
    /// sample); false when it traces the sample only.
    full: bool,
    run: Box<dyn Fn() -> u32 + 'a>,
    answers: Box<dyn Fn() -> Answers + 'a>,
}

fn job<'a>(
    name: impl Into<String>,
    (rays, full): (usize, bool),
    run: impl Fn() -> u32 + 'a,
    answers: impl Fn() -> Answers + 'a,
) -> Job<'a> {
    Job {
        name: name.into(),
        rays,
        full,
        run: Box::new(run),
        answers: Box::new(answers),
    }
}

fn collect(f: impl FnOnce(Option<&mut Answers>) -> u32) -> Answers {
    let mut out = Vec::new();
    f(Some(&mut out));
    out
}

/// What was measured.
#[derive(Default)]
struct Results {
    /// (scene, triangles or spheres, hit fraction, diffuse rays, shadow rays, note).
    scenes: Vec<(String, usize, f64, usize, usize, String)>,
    /// (scene, contender) → (build seconds, bytes per primitive).
    builds: BTreeMap<(String, String), (f64, f64)>,
    /// (kind, scene, contender) → rays/s.
    speed: BTreeMap<(Kind, String, String), f64>,
    /// (kind, scene, contender) → rays/s on one thread and on every core, timed together.
    cores: BTreeMap<(Kind, String, String), (f64, f64)>,
    /// Scene order and sizes.
    order: Vec<(String, usize)>,
    /// Check failures.
    failed: Vec<String>,
    /// The engine's frame (issue 30): the table's rows and notes.
    game: Option<Game>,
}

struct Opts {
    runs: Option<usize>,
    only: Vec<String>,
}

/// The median of some timings.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Compares answers with the reference: (rays differing, largest |Δt|/t where both hit).
fn check(got: &Answers, want: &Answers) -> (usize, f64) {
    let mut bad = got.len().abs_diff(want.len());
    let mut worst = 0f64;
    for (g, w) in got.iter().zip(want) {
        match (g, w) {
            (Some((a, _)), Some((b, _))) => {
                let d = (*a as f64 - *b as f64).abs() / (*b as f64).abs().max(1e-30);
                if d > 1e-3 {
                    bad += 1;
                } else {
                    worst = worst.max(d);
                }
            }
            (None, None) => {}
            _ => bad += 1,
        }
    }
    (bad, worst)
}

/// Checks and times the jobs of one kind of ray; `want` answers every `stride`-th ray.
fn run_jobs(
    res: &mut Results,
    scene: &str,
    kind: Kind,
    (want, stride): (&Answers, usize),
    jobs: Vec<Job>,
    runs: usize,
) {
    println!("  {} rays (reference: {} rays)", kind.name(), want.len());
    let mut timed = Vec::new();
    for j in jobs {
        let got = (j.answers)();
        let got: Answers = if j.full {
            got.into_iter().step_by(stride).collect()
        } else {
            got
        };
        let (bad, worst) = check(&got, want);
        // At most one ray in 10^4 (and at least one) may differ: grazing rays between two
        // triangles, where kernels of different rounding legitimately disagree.
        if bad <= (want.len() / 10_000).max(1) {
            timed.push((
                j,
                format!("{bad} differ, max |Δt|/t {worst:.1e}"),
                Vec::new(),
            ));
        } else {
            println!(
                "    {:<44} {bad} rays differ, max |Δt|/t {worst:.1e}  FAILED: not timed",
                j.name
            );
            res.failed.push(format!(
                "{scene} / {} / {}: {bad} of {} rays differ",
                kind.name(),
                j.name,
                want.len()
            ));
        }
    }
    // Round robin: every contender once per round, so that the machine's load drifts over
    // all of them alike; the median of the rounds.
    for _ in 0..runs {
        for (j, _, secs) in &mut timed {
            let s = Instant::now();
            std::hint::black_box((j.run)());
            secs.push(s.elapsed().as_secs_f64());
        }
    }
    for (j, checked, mut secs) in timed {
        secs.sort_by(f64::total_cmp);
        let rps = j.rays as f64 / secs[secs.len() / 2];
        println!(
            "    {:<44} {checked}  {:>9} rays/s ({} rays)",
            j.name,
            si(rps),
            j.rays
        );
        res.speed
            .insert((kind, scene.to_string(), j.name.clone()), rps);
    }
}

fn si(x: f64) -> String {
    if x >= 1e9 {
        format!("{:.2} G", x / 1e9)
    } else if x >= 1e6 {
        format!("{:.2} M", x / 1e6)
    } else if x >= 1e3 {
        format!("{:.1} k", x / 1e3)
    } else {
        format!("{x:.0}")
    }
}

/// Geometric normal of triangle `i`.
fn normal(m: &MeshData, i: u32) -> Vec3 {
    let [a, b, c] = m.indices[i as usize];
    let p = |k: u32| m.positions[k as usize];
    (p(b) - p(a)).cross(p(c) - p(a))
}

/// raylane's BVH's name in the build table.
const BVH: &str = "raylane BVH";
/// The baked tree's name in the build table.
const BAKED: &str = "raylane baked";

/// Scenes above this many primitives are checked, and traced by raylane's brute force, on
/// every [`STRIDE`]-th ray only (every ray otherwise).
const SAMPLED_ABOVE: usize = 50_000;
/// The stride of the sample.
const STRIDE: usize = 61;

/// The peers' jobs on every ray of one kind (`shadow`: any-hit queries).
fn peer_jobs<'a>(
    shadow: bool,
    rays: &[Ray],
    e: &'a EmbreeBvh,
    ob: &'a ObvhsBvh,
    pa: Option<&'a ParryMesh>,
    keep: &'a Keep,
) -> Vec<Job<'a>> {
    let er: &'a EmbreeRays = keep.put(EmbreeRays::new(rays));
    let orays: &'a Vec<obvhs::ray::Ray> = keep.put(obvhs_rays(rays));
    let all = (rays.len(), true);
    let mut jobs = Vec::new();
    if shadow {
        jobs.push(job(
            "Embree rtcOccluded1",
            all,
            move || e.occluded1(er, None),
            move || collect(|o| e.occluded1(er, o)),
        ));
        jobs.push(job(
            "Embree rtcOccluded8",
            all,
            move || e.occluded8(er, None),
            move || collect(|o| e.occluded8(er, o)),
        ));
        jobs.push(job(
            "obvhs ray_traverse_miss",
            all,
            move || ob.occluded(orays, None),
            move || collect(|o| ob.occluded(orays, o)),
        ));
    } else {
        jobs.push(job(
            "Embree rtcIntersect1",
            all,
            move || e.intersect1(er, None),
            move || collect(|o| e.intersect1(er, o)),
        ));
        jobs.push(job(
            "Embree rtcIntersect8",
            all,
            move || e.intersect8(er, None),
            move || collect(|o| e.intersect8(er, o)),
        ));
        jobs.push(job(
            "Embree rtcIntersect16",
            all,
            move || e.intersect16(er, None),
            move || collect(|o| e.intersect16(er, o)),
        ));
        jobs.push(job(
            "obvhs ray_traverse",
            all,
            move || ob.closest(orays, None),
            move || collect(|o| ob.closest(orays, o)),
        ));
    }
    if let Some(pa) = pa {
        let prays: &'a Vec<(parry3d::query::Ray, f32)> = keep.put(parry_rays(rays));
        if shadow {
            jobs.push(job(
                "parry3d intersects_local_ray",
                all,
                move || pa.occluded(prays, None),
                move || collect(|o| pa.occluded(prays, o)),
            ));
        } else {
            jobs.push(job(
                "parry3d cast_local_ray",
                all,
                move || pa.closest(prays, None),
                move || collect(|o| pa.closest(prays, o)),
            ));
        }
    }
    jobs
}

/// raylane's BVH on every ray of one kind: single rays and packets of 8 and 16.
fn bvh_jobs<'a, P: Leaf + 'static>(
    shadow: bool,
    all: &'a [Ray],
    t: &'a Bvh<'a, P>,
    keep: &'a Keep,
) -> Vec<Job<'a>> {
    let b8: &Vec<RayPacket<f32x8>> = keep.put(rl::packets::<f32x8>(all));
    let b16: &Vec<RayPacket<f32x16>> = keep.put(rl::packets::<f32x16>(all));
    let (n, every) = (all.len(), (all.len(), true));
    if shadow {
        vec![
            job(
                "raylane BVH any x1",
                every,
                move || rl::bvh_any1(t, all, None),
                move || collect(|o| rl::bvh_any1(t, all, o)),
            ),
            job(
                "raylane BVH any x8",
                every,
                move || rl::bvh_any(t, b8, n, None),
                move || collect(|o| rl::bvh_any(t, b8, n, o)),
            ),
            job(
                "raylane BVH any x16",
                every,
                move || rl::bvh_any(t, b16, n, None),
                move || collect(|o| rl::bvh_any(t, b16, n, o)),
            ),
        ]
    } else {
        vec![
            job(
                "raylane BVH x1",
                every,
                move || rl::bvh_closest1(t, all, None),
                move || collect(|o| rl::bvh_closest1(t, all, o)),
            ),
            job(
                "raylane BVH x8",
                every,
                move || rl::bvh_closest(t, b8, n, None),
                move || collect(|o| rl::bvh_closest(t, b8, n, o)),
            ),
            job(
                "raylane BVH x16",
                every,
                move || rl::bvh_closest(t, b16, n, None),
                move || collect(|o| rl::bvh_closest(t, b16, n, o)),
            ),
        ]
    }
}

/// The BVH with the Möller–Trumbore kernel instead of the watertight default (not watertight,
/// as Embree's default triangle test is not): `tree.using::<Moller>()`, the same tree.
fn moller_jobs<'a>(
    shadow: bool,
    all: &'a [Ray],
    t: &'a Bvh<'a, Tri4>,
    keep: &'a Keep,
) -> Vec<Job<'a>> {
    let b8: &Vec<RayPacket<f32x8>> = keep.put(rl::packets::<f32x8>(all));
    let b16: &Vec<RayPacket<f32x16>> = keep.put(rl::packets::<f32x16>(all));
    let (n, every) = (all.len(), (all.len(), true));
    let m = move || t.using::<Moller>();
    if shadow {
        vec![
            job(
                "raylane BVH Möller any x8",
                every,
                move || rl::bvh_any(&m(), b8, n, None),
                move || collect(|o| rl::bvh_any(&m(), b8, n, o)),
            ),
            job(
                "raylane BVH Möller any x16",
                every,
                move || rl::bvh_any(&m(), b16, n, None),
                move || collect(|o| rl::bvh_any(&m(), b16, n, o)),
            ),
        ]
    } else {
        vec![
            job(
                "raylane BVH Möller x1",
                every,
                move || rl::bvh_closest1(&m(), all, None),
                move || collect(|o| rl::bvh_closest1(&m(), all, o)),
            ),
            job(
                "raylane BVH Möller x16",
                every,
                move || rl::bvh_closest(&m(), b16, n, None),
                move || collect(|o| rl::bvh_closest(&m(), b16, n, o)),
            ),
        ]
    }
}

/// Camera tiles asked in one call (primary rays: `tree.closest(&cam.tile::<L, S, S>(x, y))`,
/// 8 × 8 and 16 × 16 pixels in packets of 8 and 16, the rays made inside the call).
fn tile_jobs<'a, P: Leaf + 'static>(
    kind: Kind,
    all: &'a [Ray],
    t: &'a Bvh<'a, P>,
    cam: &'a Pinhole,
) -> Vec<Job<'a>> {
    if kind != Kind::Primary {
        return Vec::new();
    }
    vec![
        tile_job::<f32x8, 8, P>(all.len(), t, cam),
        tile_job::<f32x8, 16, P>(all.len(), t, cam),
        tile_job::<f32x16, 8, P>(all.len(), t, cam),
        tile_job::<f32x16, 16, P>(all.len(), t, cam),
    ]
}

/// The camera's tiles of `S × S` pixels in packets of `L`, each tile one call.
fn tile_job<'a, L: Lane<Scalar = f32>, const S: usize, P: Leaf + 'static>(
    rays: usize,
    t: &'a Bvh<'a, P>,
    cam: &'a Pinhole,
) -> Job<'a> {
    job(
        format!("raylane BVH tiles {S}×{S} x{}", L::LANES),
        (rays, true),
        move || rl::bvh_tiles::<L, S>(t, cam, (0, 1), None),
        move || collect(|o| rl::bvh_tiles::<L, S>(t, cam, (0, 1), o)),
    )
}

/// Frames of one kind of ray traced by `f(first, step)` (every `step`-th tile or chunk from
/// `first`): on one thread, and on every core ([`rl::on_cores`]).
type Split<'a> = Box<dyn Fn(usize, usize) -> u32 + Sync + 'a>;

/// raylane's BVH on every core, beside the same frames on one thread: tiles of 16 × 16 at
/// x16 (primary), single rays (diffuse), packets of 8 (shadow).
fn core_frames<'a, P: Leaf + Sync + 'static>(
    kind: Kind,
    all: &'a [Ray],
    t: &'a Bvh<'a, P>,
    cam: &'a Pinhole,
    keep: &'a Keep,
) -> (&'static str, Split<'a>) {
    match kind {
        Kind::Primary => (
            "raylane BVH tiles 16×16 x16",
            Box::new(move |k, n| rl::bvh_tiles::<f32x16, 16>(t, cam, (k, n), None)),
        ),
        Kind::Diffuse => (
            "raylane BVH x1",
            Box::new(move |k, n| {
                let chunks = all.chunks(1024).skip(k).step_by(n);
                chunks.map(|c| rl::bvh_closest1(t, c, None)).sum()
            }),
        ),
        Kind::Shadow => {
            let b8: &Vec<RayPacket<f32x8>> = keep.put(rl::packets::<f32x8>(all));
            (
                "raylane BVH any x8",
                Box::new(move |k, n| {
                    let chunks = b8.chunks(128).skip(k).step_by(n);
                    chunks.map(|c| rl::bvh_any(t, c, 8 * c.len(), None)).sum()
                }),
            )
        }
    }
}

/// Times [`core_frames`] for every kind of ray on one thread and on every core, round robin,
/// after the scene's Embree device is gone (a live device, even a one-thread one, halves the
/// second core's share here: 1.2–1.4× instead of 1.8–1.9× on 2 cores, measured); the hit
/// counts of the two must agree.
fn time_on_cores(
    res: &mut Results,
    scene: &str,
    frames: Vec<(Kind, usize, &str, Split)>,
    runs: usize,
) {
    for (kind, rays, name, f) in frames {
        let (one, every) = (f(0, 1), rl::on_cores(&f));
        if one != every {
            res.failed.push(format!(
                "{scene} / {} / {name} on every core: {every} hits, {one} on one thread",
                kind.name()
            ));
            continue;
        }
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for _ in 0..runs {
            let s = Instant::now();
            std::hint::black_box(f(0, 1));
            a.push(s.elapsed().as_secs_f64());
            let s = Instant::now();
            std::hint::black_box(rl::on_cores(&f));
            b.push(s.elapsed().as_secs_f64());
        }
        let (a, b) = (rays as f64 / median(a), rays as f64 / median(b));
        println!(
            "    {name} on {} threads: {} rays/s ({} on one thread)",
            rl::cores(),
            si(b),
            si(a)
        );
        res.cores
            .insert((kind, scene.to_string(), name.to_string()), (a, b));
    }
}

/// The mesh baked for flash, traced on the host: single rays and packets of 8.
fn baked_jobs<'a>(shadow: bool, all: &'a [Ray], t: &'a Baked<'a>, keep: &'a Keep) -> Vec<Job<'a>> {
    let b8: &Vec<RayPacket<f32x8>> = keep.put(rl::packets::<f32x8>(all));
    let (n, every) = (all.len(), (all.len(), true));
    if shadow {
        vec![
            job(
                "raylane baked any x1",
                every,
                move || rl::bvh_any1(t, all, None),
                move || collect(|o| rl::bvh_any1(t, all, o)),
            ),
            job(
                "raylane baked any x8",
                every,
                move || rl::bvh_any(t, b8, n, None),
                move || collect(|o| rl::bvh_any(t, b8, n, o)),
            ),
        ]
    } else {
        vec![
            job(
                "raylane baked x1",
                every,
                move || rl::bvh_closest1(t, all, None),
                move || collect(|o| rl::bvh_closest1(t, all, o)),
            ),
            job(
                "raylane baked x8",
                every,
                move || rl::bvh_closest(t, b8, n, None),
                move || collect(|o| rl::bvh_closest(t, b8, n, o)),
            ),
        ]
    }
}

/// Keeps the converted rays of a scene alive while its jobs borrow them.
#[derive(Default)]
struct Keep(RefCell<Vec<Box<dyn std::any::Any>>>);

impl Keep {
    fn put<T: 'static>(&self, v: T) -> &T {
        let b = Box::new(v);
        let p: *const T = &*b;
        self.0.borrow_mut().push(b);
        // SAFETY: the box is never dropped or moved out before `self` is dropped, and its heap
        // allocation does not move when the vector grows.
        unsafe { &*p }
    }
}

/// Every `stride`-th ray.
fn thin(rays: &[Ray], stride: usize) -> Vec<Ray> {
    rays.iter().step_by(stride).copied().collect()
}

fn mesh_scene(res: &mut Results, m: &MeshData, opts: &Opts) {
    let n = m.len();
    let runs = opts.runs.unwrap_or(if n > 100_000 { 3 } else { 7 });
    let stride = if n > SAMPLED_ABOVE { STRIDE } else { 1 };
    let name = m.name.clone();
    println!(
        "\n### {name}: {n} triangles, {} vertices",
        m.positions.len()
    );
    let (centre, radius) = m.bounds();
    let cam = meshes::framing(centre, radius);
    let tris = m.triangles();

    // Every structure is built `runs` times, round robin, and the median build time kept
    // (the last build of each is used).
    let size = rl::part_size(n);
    let label_bf = "raylane brute force + spheres".to_string();
    let mut times: [Vec<f64>; 7] = Default::default();
    let mut built = None;
    for _ in 0..runs {
        let start = Instant::now();
        let parts = Parts::new(&tris, size);
        times[0].push(start.elapsed().as_secs_f64());
        let ebr = EmbreeBvh::mesh(m, true);
        times[1].push(ebr.build.as_secs_f64());
        let obv = ObvhsBvh::mesh(m);
        times[2].push(obv.build.as_secs_f64());
        let par = ParryMesh::new(m);
        times[3].push(par.build.as_secs_f64());
        let tree = rl::Tree::mesh(&m.positions, &m.indices);
        times[4].push(tree.build.as_secs_f64());
        times[6].push(rl::owned_build(&m.positions, &m.indices).as_secs_f64());
        let baked = rl::BakedTree::mesh(&m.positions, &m.indices);
        times[5].push(baked.as_ref().map_or(f64::NAN, |b| b.build.as_secs_f64()));
        built = Some((parts, ebr, obv, par, tree, baked));
    }
    let (parts, mut ebr, obv, par, tree, baked) = built.expect("at least one run");
    let [t_bf, t_e, t_o, t_p, t_t, t_b, t_all] = times.map(median);
    let bounded = parts.meshes();
    let ids = parts.ids();
    let bf_bytes = (36 + 12 + 88) as f64 + 20.0 * parts.len() as f64 / n as f64;
    let e_bytes = ebr.bytes.saturating_sub(ebr.buffer_bytes) as f64 / n as f64;
    for (c, v) in [
        (label_bf.clone(), (t_bf, bf_bytes)),
        ("Embree".into(), (t_e, e_bytes)),
        ("obvhs".into(), (t_o, obv.bytes() as f64 / n as f64)),
        ("parry3d".into(), (t_p, f64::NAN)),
        (BVH.to_string(), (t_t, tree.bytes() as f64 / n as f64)),
        (
            format!("{BVH} on every core ({} threads)", rl::cores()),
            (t_all, tree.bytes() as f64 / n as f64),
        ),
        (
            BAKED.to_string(),
            (
                t_b,
                baked
                    .as_ref()
                    .map_or(f64::NAN, |b| b.bytes() as f64 / n as f64),
            ),
        ),
    ] {
        res.builds.insert((name.clone(), c), v);
    }
    let tb = tree.bvh();
    let opened = baked.as_ref().map(|b| b.open());

    // The secondary rays start from Embree's primary hits (checked below like every other
    // answer).
    let primary = Workload::primary(&cam);
    let e_hits = collect(|o| ebr.intersect1(&EmbreeRays::new(&primary), o));
    let hits: Vec<SurfaceHit> = e_hits
        .iter()
        .map(|h| h.map(|(t, i)| (t, normal(m, i))))
        .collect();
    let mut w = Workload::new(cam, &hits, centre, radius);
    w.primary = Workload::tiled(&w.cam);
    let frac = e_hits.iter().filter(|h| h.is_some()).count() as f64 / primary.len() as f64;
    res.scenes
        .push((name.clone(), n, frac, w.diffuse.len(), w.shadow.len(), {
            let st = tb.stats();
            let fill = format!(
                "BVH: {:.2} children per node, {:.2} triangles per leaf, depth {}",
                st.children_per_node(),
                st.primitives_per_leaf(),
                st.depth
            );
            if stride > 1 {
                format!(
                    "parts of {size}; reference and brute force on every {stride}st ray; {fill}"
                )
            } else {
                format!("parts of {size}; {fill}")
            }
        }));
    res.order.push((name.clone(), n));

    let keep = Keep::default();
    let store = RefCell::new(parts.storage());
    for kind in [Kind::Primary, Kind::Diffuse, Kind::Shadow] {
        let all: &[Ray] = match kind {
            Kind::Primary => &w.primary,
            Kind::Diffuse => &w.diffuse,
            Kind::Shadow => &w.shadow,
        };
        let shadow = kind == Kind::Shadow;
        // The reference: scalar Watertight over the parts (exact brute force).
        let sample = thin(all, stride);
        let p1 = rl::packets::<f32>(&sample);
        let want = if shadow {
            collect(|o| rl::any(&p1, &bounded, sample.len(), o))
        } else {
            collect(|o| rl::closest(&p1, &bounded, ids, sample.len(), o))
        };
        ebr.set_coherent(kind == Kind::Primary);
        let mut jobs = peer_jobs(shadow, all, &ebr, &obv, Some(&par), &keep);
        let s8: &Vec<RayPacket<f32x8>> = keep.put(rl::packets::<f32x8>(&sample));
        let (b, ns) = (&bounded, sample.len());
        let few = (ns, false);
        if shadow {
            jobs.push(job(
                format!("{label_bf} any x8"),
                few,
                move || rl::any(s8, b, ns, None),
                move || collect(|o| rl::any(s8, b, ns, o)),
            ));
        } else {
            jobs.push(job(
                format!("{label_bf} x8"),
                few,
                move || rl::closest(s8, b, ids, ns, None),
                move || collect(|o| rl::closest(s8, b, ids, ns, o)),
            ));
        }
        jobs.extend(bvh_jobs(shadow, all, &tb, &keep));
        jobs.extend(moller_jobs(shadow, all, &tb, &keep));
        jobs.extend(tile_jobs(kind, all, &tb, &w.cam));
        if let Some(bk) = opened.as_ref() {
            jobs.extend(baked_jobs(shadow, all, bk, &keep));
        }
        if kind == Kind::Primary {
            // The focal parts over every primary ray, the cache built for the eye inside
            // every frame.
            let (eye, pp, st, nr) = (w.cam.eye, &parts, &store, all.len());
            let p8: &Vec<RayPacket<f32x8>> = keep.put(rl::packets::<f32x8>(all));
            let p16: &Vec<RayPacket<f32x16>> = keep.put(rl::packets::<f32x16>(all));
            let every = (nr, true);
            jobs.push(job(
                "raylane focal + spheres x8",
                every,
                move || {
                    let mut s = st.borrow_mut();
                    parts::frame(p8, &pp.focus(eye, &mut s))
                },
                move || {
                    let mut s = st.borrow_mut();
                    rl::focal_answers(p8, &pp.focus(eye, &mut s), nr)
                },
            ));
            jobs.push(job(
                "raylane focal + spheres x16",
                every,
                move || {
                    let mut s = st.borrow_mut();
                    parts::frame(p16, &pp.focus(eye, &mut s))
                },
                move || {
                    let mut s = st.borrow_mut();
                    rl::focal_answers(p16, &pp.focus(eye, &mut s), nr)
                },
            ));
        }
        run_jobs(res, &name, kind, (&want, stride), jobs, runs);
    }
    drop(ebr);
    time_on_cores(res, &name, every_core(&w, &tb, &keep), runs);
}

/// [`core_frames`] for the three kinds of ray of a workload.
fn every_core<'a, P: Leaf + Sync + 'static>(
    w: &'a Workload,
    t: &'a Bvh<'a, P>,
    keep: &'a Keep,
) -> Vec<(Kind, usize, &'static str, Split<'a>)> {
    [
        (Kind::Primary, &w.primary),
        (Kind::Diffuse, &w.diffuse),
        (Kind::Shadow, &w.shadow),
    ]
    .into_iter()
    .map(|(kind, all)| {
        let (name, f) = core_frames(kind, all, t, &w.cam, keep);
        (kind, all.len(), name, f)
    })
    .collect()
}

/// The sphere field: the reference is scalar `Robust` brute force on every [`STRIDE`]-th
/// ray; the secondary rays start from Embree's primary hits.
fn sphere_scene(res: &mut Results, count: usize, opts: &Opts) {
    let runs = opts.runs.unwrap_or(3);
    let spheres = meshes::sphere_field(count);
    let name = format!("{count} spheres");
    println!("\n### {name}");
    let r = spheres.iter().map(|s| s.radius()).fold(0.0, f32::max);
    let (centre, radius) = (Vec3::ZERO, 3f32.sqrt() * (1.0 + r));
    let cam = meshes::framing(centre, radius);
    let primary = Workload::primary(&cam);
    let mut times: [Vec<f64>; 3] = Default::default();
    let mut built = None;
    for _ in 0..runs {
        let ebr = EmbreeBvh::spheres(&spheres, true);
        times[0].push(ebr.build.as_secs_f64());
        let obv = ObvhsBvh::spheres(&spheres);
        times[1].push(obv.build.as_secs_f64());
        let tree = rl::Tree::spheres(&spheres);
        times[2].push(tree.build.as_secs_f64());
        built = Some((ebr, obv, tree));
    }
    let (mut ebr, obv, tree) = built.expect("at least one run");
    let [t_e, t_o, t_t] = times.map(median);
    let e_bytes = ebr.bytes.saturating_sub(ebr.buffer_bytes) as f64 / count as f64;
    for (c, v) in [
        ("Embree".to_string(), (t_e, e_bytes)),
        ("obvhs".into(), (t_o, obv.bytes() as f64 / count as f64)),
        (BVH.to_string(), (t_t, tree.bytes() as f64 / count as f64)),
    ] {
        res.builds.insert((name.clone(), c), v);
    }
    let tb = tree.bvh();
    let e_hits = collect(|o| ebr.intersect1(&EmbreeRays::new(&primary), o));
    let hits: Vec<SurfaceHit> = primary
        .iter()
        .zip(&e_hits)
        .map(|(ray, h)| h.map(|(t, i)| (t, ray.at(t) - spheres[i as usize].center())))
        .collect();
    let mut w = Workload::new(cam, &hits, centre, radius);
    w.primary = Workload::tiled(&w.cam);
    let frac = e_hits.iter().filter(|h| h.is_some()).count() as f64 / primary.len() as f64;
    res.scenes.push((
        name.clone(),
        count,
        frac,
        w.diffuse.len(),
        w.shadow.len(),
        format!("reference and brute force on every {STRIDE}st ray"),
    ));
    res.order.push((name.clone(), count));
    let keep = Keep::default();
    for kind in [Kind::Primary, Kind::Diffuse, Kind::Shadow] {
        let all: &[Ray] = match kind {
            Kind::Primary => &w.primary,
            Kind::Diffuse => &w.diffuse,
            Kind::Shadow => &w.shadow,
        };
        let shadow = kind == Kind::Shadow;
        let sample = thin(all, STRIDE);
        let p1 = rl::packets::<f32>(&sample);
        let occluded = |mut a: Answers| {
            if shadow {
                a.iter_mut().for_each(|h| *h = h.map(|_| (0.0, 0)));
            }
            a
        };
        let want = occluded(collect(|o| {
            rl::spheres_closest(&p1, &spheres, sample.len(), o)
        }));
        ebr.set_coherent(kind == Kind::Primary);
        let mut jobs = peer_jobs(shadow, all, &ebr, &obv, None, &keep);
        let p16: &Vec<RayPacket<f32x16>> = keep.put(rl::packets::<f32x16>(&sample));
        let (sp, ns) = (&spheres, sample.len());
        jobs.push(job(
            "raylane brute force robust x16",
            (ns, false),
            move || rl::spheres_closest(p16, sp, ns, None),
            move || occluded(collect(|o| rl::spheres_closest(p16, sp, ns, o))),
        ));
        jobs.extend(bvh_jobs(shadow, all, &tb, &keep));
        jobs.extend(tile_jobs(kind, all, &tb, &w.cam));
        run_jobs(res, &name, kind, (&want, STRIDE), jobs, runs);
    }
    drop(ebr);
    time_on_cores(res, &name, every_core(&w, &tb, &keep), runs);
}

fn main() {
    let mut opts = Opts {
        runs: None,
        only: Vec::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--runs" => opts.runs = args.next().and_then(|v| v.parse().ok()),
            "--only" => opts.only.extend(args.next()),
            // cargo bench passes --bench
            "--bench" => {}
            _ => {
                eprintln!("usage: scenes [--runs N] [--only NAME]...");
                std::process::exit(2);
            }
        }
    }
    let wanted =
        |name: &str| opts.only.is_empty() || opts.only.iter().any(|o| name.contains(o.as_str()));
    let started = Instant::now();
    println!("CPU: {}", cpu());
    let mut res = Results::default();
    let mut list: Vec<MeshData> = vec![meshes::vendored_bunny()];
    list.extend(meshes::shared_meshes());
    if list.len() == 1 {
        println!("(../shared/meshes absent: spot, fandisk and the Stanford bunny skipped)");
    }
    for steps in 1..=4 {
        let name = format!("bunny Loop×{steps}");
        if wanted(&name) {
            let s = Instant::now();
            let m = meshes::subdivided_bunny(steps);
            println!("{name}: subdivided in {:.2} s", s.elapsed().as_secs_f64());
            list.push(m);
        }
    }
    list.sort_by_key(|m| m.len());
    // Warm-up: the process's first Embree device starts its task system and picks its ISA,
    // which would otherwise be counted in the first scene's build time.
    drop(EmbreeBvh::mesh(&list[0], true));
    for m in &list {
        if wanted(&m.name) {
            mesh_scene(&mut res, m, &opts);
        }
    }
    if wanted("spheres") {
        sphere_scene(&mut res, 100_000, &opts);
    }
    if wanted("game") {
        res.game = Some(game_frame(&opts));
    }
    report(&res);
    println!("\n(total {:.0} s)", started.elapsed().as_secs_f64());
}

/// The contender whose rays/s the goals compare with the peers: raylane's fastest.
fn best_raylane(res: &Results, kind: Kind, scene: &str) -> Option<(String, f64)> {
    res.speed
        .iter()
        .filter(|((k, s, c), _)| *k == kind && s == scene && c.starts_with("raylane"))
        .map(|((_, _, c), v)| (c.clone(), *v))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

fn get(res: &Results, kind: Kind, scene: &str, c: &str) -> Option<f64> {
    res.speed
        .get(&(kind, scene.to_string(), c.to_string()))
        .copied()
}

fn report(res: &Results) {
    if res.order.is_empty() {
        // Only the engine's frame ran.
        if let Some(g) = &res.game {
            g.report();
        }
        return;
    }
    println!("\n## Scenes of 10^3 to 10^6 primitives (issues 14 and 20)\n");
    println!(
        "CPU: {}; one thread for every contender (Embree's device too) but the section \"On every core\". Primary rays in tiles of 16 × 16 pixels, 4 × 4 blocks inside: every packet of 16 (8) consecutive rays is a block of 4 × 4 (4 × 2) pixels, for every contender.\n",
        cpu()
    );
    println!("| scene | primitives | primary rays hit | diffuse rays | shadow rays | note |");
    println!("| --- | ---: | ---: | ---: | ---: | --- |");
    for (s, n, f, d, sh, note) in &res.scenes {
        println!("| {s} | {n} | {:.1} % | {d} | {sh} | {note} |", 100.0 * f);
    }

    println!("\n### Build time and size\n");
    println!(
        "Bytes per primitive: the acceleration structure and any copy of the primitives it needs, without the caller's vertex and index arrays (Embree: its memory monitor minus its buffers; raylane's parts: vertex copies, indices and the focal cache).\n"
    );
    let contenders: Vec<String> = {
        let mut c: Vec<String> = res.builds.keys().map(|(_, c)| c.clone()).collect();
        c.sort();
        c.dedup();
        c
    };
    let mut head = String::from("| scene |");
    let mut rule = String::from("| --- |");
    for c in &contenders {
        head += &format!(" {c} |");
        rule += " ---: |";
    }
    println!("{head}\n{rule}");
    for (s, _) in &res.order {
        let mut row = format!("| {s} |");
        for c in &contenders {
            match res.builds.get(&(s.clone(), c.clone())) {
                Some((t, b)) if b.is_finite() => row += &format!(" {:.1} ms, {b:.0} B |", 1e3 * t),
                Some((t, _)) => row += &format!(" {:.1} ms |", 1e3 * t),
                None => row += " — |",
            }
        }
        println!("{row}");
    }

    for kind in [Kind::Primary, Kind::Diffuse, Kind::Shadow] {
        let reference = match kind {
            Kind::Primary => "Embree rtcIntersect8",
            Kind::Diffuse => "Embree rtcIntersect1",
            Kind::Shadow => "Embree rtcOccluded8",
        };
        println!("\n### {} rays: rays/s (× {reference})\n", kind.name());
        let mut names: Vec<String> = res
            .speed
            .keys()
            .filter(|(k, _, _)| *k == kind)
            .map(|(_, _, c)| c.clone())
            .collect();
        names.sort();
        names.dedup();
        let scenes: Vec<&(String, usize)> = res.order.iter().collect();
        let mut head = String::from("| contender |");
        let mut rule = String::from("| --- |");
        for (s, n) in &scenes {
            head += &format!(" {s} ({}) |", short(*n));
            rule += " ---: |";
        }
        println!("{head}\n{rule}");
        for c in names {
            let mut row = format!("| {c} |");
            for (s, _) in &scenes {
                match (get(res, kind, s, &c), get(res, kind, s, reference)) {
                    (Some(v), Some(r)) => row += &format!(" {} ({:.2}) |", si(v), v / r),
                    (Some(v), None) => row += &format!(" {} |", si(v)),
                    _ => row += " — |",
                }
            }
            println!("{row}");
        }
    }

    println!("\n### On every core: rays/s (× the same frames on one thread, timed together)\n");
    println!(
        "raylane's BVH shared by {} threads (`Bvh` is `Sync`), each taking every n-th tile or chunk of rays; timed after the scene's Embree device is dropped (a live one-thread device cuts the second core's share: 1.2–1.4× instead of 1.8–1.9× here). Embree is not run on threads, so these rows have no Embree ratio.\n",
        rl::cores()
    );
    let mut head = String::from("| kind | contender |");
    let mut rule = String::from("| --- | --- |");
    for (s, n) in &res.order {
        head += &format!(" {s} ({}) |", short(*n));
        rule += " ---: |";
    }
    println!("{head}\n{rule}");
    for kind in [Kind::Primary, Kind::Diffuse, Kind::Shadow] {
        let names: std::collections::BTreeSet<&String> = res
            .cores
            .keys()
            .filter(|(k, _, _)| *k == kind)
            .map(|(_, _, c)| c)
            .collect();
        for c in names {
            let mut row = format!("| {} | {c} |", kind.name());
            for (s, _) in &res.order {
                match res.cores.get(&(kind, s.clone(), c.clone())) {
                    Some((one, every)) => row += &format!(" {} ({:.2}) |", si(*every), every / one),
                    None => row += " — |",
                }
            }
            println!("{row}");
        }
    }

    println!("\n### Primary rays/s against the number of primitives (fastest variant of each)\n");
    let families = [
        ("Embree", "Embree rtc"),
        ("obvhs", "obvhs"),
        ("parry3d", "parry3d"),
        ("raylane brute force + spheres", "raylane brute force"),
        ("raylane focal + spheres", "raylane focal"),
        ("raylane BVH", "raylane BVH"),
        ("raylane baked (flash layout)", "raylane baked"),
    ];
    let mut head = String::from("| scene | primitives |");
    let mut rule = String::from("| --- | ---: |");
    for (f, _) in families {
        head += &format!(" {f} |");
        rule += " ---: |";
    }
    println!("{head}\n{rule}");
    for (s, n) in &res.order {
        let mut row = format!("| {s} | {n} |");
        for (_, prefix) in families {
            let best = res
                .speed
                .iter()
                .filter(|((k, ss, c), _)| *k == Kind::Primary && ss == s && c.starts_with(prefix))
                .map(|(_, v)| *v)
                .fold(f64::NAN, f64::max);
            row += &if best.is_nan() {
                " — |".to_string()
            } else {
                format!(" {} |", si(best))
            };
        }
        println!("{row}");
    }

    println!(
        "\n## Goals (issue 20): raylane's fastest one-thread contender against Embree's fastest API for the kind of ray, one thread each\n"
    );
    println!("| goal | scene | raylane | Embree | factor | met |");
    println!("| --- | --- | --- | --- | ---: | --- |");
    // (goal, kind, Embree's APIs (the fastest is taken), factor)
    let intersect: &[&str] = &[
        "Embree rtcIntersect1",
        "Embree rtcIntersect8",
        "Embree rtcIntersect16",
    ];
    let goals = [
        ("primary ≥ 1.5× Embree", Kind::Primary, intersect, 1.5),
        (
            "incoherent ≥ 1.0× rtcIntersect1",
            Kind::Diffuse,
            &intersect[..1],
            1.0,
        ),
        (
            "shadow ≥ 1.0× Embree",
            Kind::Shadow,
            &["Embree rtcOccluded1", "Embree rtcOccluded8"][..],
            1.0,
        ),
    ];
    for (goal, kind, apis, want) in goals {
        for (s, _) in &res.order {
            let fastest = apis
                .iter()
                .filter_map(|c| Some((c.to_string(), get(res, kind, s, c)?)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let (Some((c, v)), Some((pc, p))) = (best_raylane(res, kind, s), fastest) {
                let f = v / p;
                println!(
                    "| {goal} | {s} | {c}: {} | {pc}: {} | {f:.2}× | {} |",
                    si(v),
                    si(p),
                    if f >= want {
                        "met".to_string()
                    } else {
                        format!("missed ({:.2}× short)", want / f)
                    }
                );
            }
        }
    }
    for (s, _) in &res.order {
        let e = res.builds.get(&(s.clone(), "Embree".to_string()));
        let ours = res.builds.get(&(s.clone(), BVH.to_string()));
        if let (Some(&(te, be)), Some(&(t, b))) = (e, ours) {
            let f = t / te;
            println!(
                "| build ≤ 1.0× Embree (one thread) | {s} | {BVH}: {:.1} ms | {:.1} ms | {f:.2}× | {} |",
                1e3 * t,
                1e3 * te,
                if f <= 1.0 {
                    "met".to_string()
                } else {
                    format!("missed ({f:.2}× over)")
                }
            );
            let f = b / be;
            println!(
                "| bytes per primitive ≤ Embree's BVH | {s} | {BVH}: {b:.0} B | {be:.0} B | {f:.2}× | {} |",
                if f <= 1.0 {
                    "met".to_string()
                } else {
                    format!("missed ({f:.2}× over)")
                }
            );
        }
    }
    if let Some(g) = &res.game {
        g.report();
    }
    if !res.failed.is_empty() {
        println!("\nNot timed (answers differ from the reference):\n");
        for f in &res.failed {
            println!("* {f}");
        }
    }
}

fn short(n: usize) -> String {
    if n >= 1_000_000 {
        format!("{:.2} M", n as f64 / 1e6)
    } else if n >= 1000 {
        format!("{:.1} k", n as f64 / 1e3)
    } else {
        n.to_string()
    }
}

#[path = "../../examples/game/world.rs"]
mod world;

/// The engine's frame of issue 30 against Embree's instance API: what was measured.
struct Game {
    frames: usize,
    instances: usize,
    /// (what, raylane ms, Embree ms with `RTC_SCENE_FLAG_DYNAMIC` + `LOW`, Embree ms default)
    rows: Vec<(String, f64, f64, f64)>,
    /// Rays whose answers differ from raylane's, per query kind (dynamic, default).
    differ: Vec<(String, usize, usize)>,
    masks: bool,
    /// raylane's commits: (refits, rebuilds).
    commits: (usize, usize),
}

/// The frame of `examples/game` (its world, included: the same shapes, 10,000 instances, the
/// same moves and rays), one thread each, raylane's `OwnedScene` against Embree 3's instance
/// API in two configurations of the top level. Every frame: everything moves; raylane's
/// `set_transform` of every instance and `commit` against Embree's `rtcSetGeometryTransform`
/// and `rtcCommitGeometry` of every instance and `rtcCommitScene`; then the queries (a pick,
/// 1,000 sight lines on every layer but the agents', 10,000 bullets ignoring their shooters,
/// by a filter closure and by `ignoring`, against Embree's filter callback, a shadow ray from
/// each of raylane's bullet impacts), one ray per call (`rtcIntersect1`, `rtcOccluded1`), the
/// contenders in turn (the order rotating by frame); the medians over the frames. Answers are
/// compared frame by frame (not timed): hit or miss, `t` (within 10^-3 relative, plus the
/// rounding of the origin's coordinates), and for bullets the instance hit.
fn game_frame(opts: &Opts) -> Game {
    use raylane::bvh::{OwnedBvh, OwnedScene};
    use raylane_bench::embree::{Instances, Shape};
    use world::{AGENTS, Prims};

    let frames = opts.runs.unwrap_or(15).max(3);
    let shapes = world::shapes();
    let mut actors = world::actors(10_000, 1);
    let agents = world::agents(&actors);
    println!(
        "\n### An engine's frame: {} instances of {} shapes, {frames} frames",
        actors.len(),
        shapes.len()
    );
    let mut scene = OwnedScene::new();
    let objects: Vec<_> = shapes
        .iter()
        .map(|s| match &s.prims {
            Prims::Mesh(t) => scene.add_object(OwnedBvh::new(&t[..]).unwrap()),
            Prims::Balls(b) => scene.add_object(OwnedBvh::new(&b[..]).unwrap()),
        })
        .collect();
    let ids: Vec<_> = actors
        .iter()
        .map(|a| {
            scene
                .add(objects[a.shape], world::rows(a), a.layer)
                .unwrap()
        })
        .collect();
    scene.commit();
    let eshapes: Vec<Shape> = shapes
        .iter()
        .map(|s| match &s.prims {
            Prims::Mesh(t) => Shape::Triangles(t),
            Prims::Balls(b) => Shape::Spheres(b),
        })
        .collect();
    let placed: Vec<_> = actors
        .iter()
        .map(|a| (a.shape, a.layer, world::rows(a)))
        .collect();
    let mut emb = [
        Instances::new(&eshapes, &placed, true),
        Instances::new(&eshapes, &placed, false),
    ];
    let masks = emb[0].ray_masks();
    println!(
        "  Embree ray masks: {}",
        if masks {
            "supported (instance masks)"
        } else {
            "not in this build: layers through an occlusion filter callback"
        }
    );
    // (step) -> per contender, the frame times.
    const STEPS: [&str; 8] = [
        "stage", "commit", "pick", "sight", "bullets", "ignore", "moller", "shadows",
    ];
    let mut times = vec![[Vec::new(), Vec::new(), Vec::new()]; STEPS.len()];
    let mut differ = [[0usize; 2]; 3];
    let mut commits = (0, 0);
    let mut rng = world::Rng::new(2);
    let cam = Pinhole::look_at(
        Vec3::new(0.0, 90.0, 140.0),
        Vec3::ZERO,
        Vec3::Y,
        60.0,
        1280,
        720,
    );
    // `t` agrees within 10^-3 of itself plus 2^-18 of the origin's largest coordinate over
    // `|d|` (hits a few hundredths from an origin 200 units out carry its rounding: an agent
    // standing inside a crate).
    let far = |r: &Ray, a: f32, b: f32| {
        let o = r.origin().abs().max_element() as f64 / r.dir().length() as f64;
        (a as f64 - b as f64).abs() > 1e-3 * (b as f64).abs() + o * (1.0 / 262_144.0)
    };
    for frame in 0..frames {
        world::step(&mut actors, 1.0 / 60.0);
        let rows: Vec<[[f32; 4]; 3]> = actors.iter().map(world::rows).collect();
        let lines = world::sight_lines(&actors, &agents, 1000, &mut rng);
        let shots = world::bullets(&actors, &agents, 10_000, &mut rng);
        let (cx, cy) = (
            640 + (500.0 * (frame as f32 * 0.05).cos()) as u32,
            360 + (300.0 * (frame as f32 * 0.07).sin()) as u32,
        );
        let cursor = cam.row_packet::<f32>(cx, cy).ray(0);
        // raylane's answers give the shadow rays of both.
        let impacts: Vec<raylane::Hit> = Vec::new();
        let mut impacts = Some(impacts);
        for turn in 0..3 {
            let who = (turn + frame) % 3;
            let mut tick =
                |step: usize, t: Instant| times[step][who].push(t.elapsed().as_secs_f64() * 1e3);
            if who == 0 {
                let t = Instant::now();
                for (id, r) in ids.iter().zip(&rows) {
                    scene.set_transform(*id, *r).unwrap();
                }
                tick(0, t);
                let t = Instant::now();
                let how = scene.commit();
                tick(1, t);
                match how {
                    raylane::bvh::Commit::Refit => commits.0 += 1,
                    raylane::bvh::Commit::Rebuild => commits.1 += 1,
                    raylane::bvh::Commit::Unchanged => {}
                }
                let t = Instant::now();
                std::hint::black_box(scene.closest(&cursor));
                tick(2, t);
                let t = Instant::now();
                let seen = scene.masked(!AGENTS);
                std::hint::black_box(lines.iter().filter(|(_, _, r)| !seen.any(r)).count());
                tick(3, t);
                let t = Instant::now();
                let hits: Vec<raylane::Hit> = shots
                    .iter()
                    .filter_map(|(s, r)| {
                        let me = ids[*s].slot();
                        scene.filtered(|c| c.set != me).closest(r)
                    })
                    .collect();
                tick(4, t);
                let t = Instant::now();
                let ignored: Vec<raylane::Hit> = shots
                    .iter()
                    .filter_map(|(s, r)| scene.ignoring(ids[*s]).closest(r))
                    .collect();
                tick(5, t);
                assert_eq!(ignored, hits, "ignore is the filter's job");
                let t = Instant::now();
                let moller = scene.with_kernels::<Moller, Robust>();
                std::hint::black_box(
                    shots
                        .iter()
                        .filter_map(|(s, r)| {
                            raylane::set::Filtered::new(&moller)
                                .ignore(ids[*s].slot())
                                .closest(r)
                        })
                        .count(),
                );
                tick(6, t);
                let t = Instant::now();
                std::hint::black_box(
                    hits.iter()
                        .filter(|h| !scene.any(&world::shadow(h.point)))
                        .count(),
                );
                tick(7, t);
                impacts = Some(hits);
            } else {
                let e = &mut emb[who - 1];
                let _ftz = raylane_bench::embree::FlushDenormals::on();
                let t = Instant::now();
                e.set_transforms(rows.iter());
                tick(0, t);
                let t = Instant::now();
                e.commit();
                tick(1, t);
                let t = Instant::now();
                std::hint::black_box(e.closest(&cursor, u32::MAX));
                tick(2, t);
                let t = Instant::now();
                std::hint::black_box(
                    lines
                        .iter()
                        .filter(|(_, _, r)| !e.occluded(r, !AGENTS))
                        .count(),
                );
                tick(3, t);
                let t = Instant::now();
                let hits: Vec<_> = shots.iter().map(|(s, r)| e.closest(r, *s as u32)).collect();
                let ms = t.elapsed().as_secs_f64() * 1e3;
                // One Embree run for both rows: its filter callback does either job.
                times[4][who].push(ms);
                times[5][who].push(ms);
                times[6][who].push(ms);
                std::hint::black_box(&hits);
            }
        }
        // The answers, compared (not timed).
        let _ftz = raylane_bench::embree::FlushDenormals::on();
        let ours = impacts.take().unwrap_or_default();
        for (k, e) in emb.iter().enumerate() {
            let seen = scene.masked(!AGENTS);
            differ[0][k] += lines
                .iter()
                .filter(|(_, _, r)| seen.any(r) != e.occluded(r, !AGENTS))
                .count();
            for (s, r) in &shots {
                let me = ids[*s].slot();
                let mine = scene.filtered(|c| c.set != me).closest(r);
                let theirs = e.closest(r, *s as u32);
                let bad = match (mine, theirs) {
                    (None, None) => false,
                    (Some(h), Some((t, inst, _))) => far(r, h.t, t) || h.set != inst,
                    _ => true,
                };
                differ[1][k] += usize::from(bad);
            }
            differ[2][k] += ours
                .iter()
                .filter(|h| {
                    let r = world::shadow(h.point);
                    scene.any(&r) != e.occluded(&r, u32::MAX)
                })
                .count();
        }
        // Embree's shadow rays, timed after its answers were checked (the same rays as ours).
        for (k, e) in emb.iter().enumerate() {
            let t = Instant::now();
            std::hint::black_box(
                ours.iter()
                    .filter(|h| !e.occluded(&world::shadow(h.point), u32::MAX))
                    .count(),
            );
            times[7][k + 1].push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    let names = [
        "stage the moves (10,000 transforms)",
        "commit",
        "pick (1 ray)",
        "sight lines (1,000, masked)",
        "bullets (10,000, a filter closure ignores the shooter)",
        "bullets (10,000, `ignoring(shooter)`)",
        "bullets (10,000, `ignoring(shooter)`, Möller–Trumbore as Embree)",
        "shadow rays (one per impact)",
    ];
    let rows = names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let m = |c: usize| median(times[k][c].clone());
            (n.to_string(), m(0), m(1), m(2))
        })
        .collect();
    let differ = ["sight lines", "bullets", "shadow rays"]
        .iter()
        .zip(differ)
        .map(|(n, d)| (n.to_string(), d[0], d[1]))
        .collect();
    Game {
        frames,
        instances: actors.len(),
        rows,
        differ,
        masks,
        commits,
    }
}

impl Game {
    fn report(&self) {
        println!(
            "\n## An engine's frame (issue 30): raylane's `OwnedScene` against Embree's instance API\n"
        );
        println!(
            "`examples/game`'s world: {} instances of 7 shapes (meshes and sphere sets), all moving every frame; medians of {} frames, one thread each, one ray per query. Embree's layers: {}; bullets ignore their shooter through an intersection filter callback. Factor: Embree's milliseconds over raylane's (above 1: raylane faster). raylane's commits: {} refits, {} rebuilds.\n",
            self.instances,
            self.frames,
            if self.masks {
                "instance and ray masks"
            } else {
                "this build has no ray masks (`RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED` is 0), so an occlusion filter callback rejects the agents' hits: the same job"
            },
            self.commits.0,
            self.commits.1
        );
        println!(
            "| per frame | raylane ms | Embree ms (dynamic, low) | factor | Embree ms (default) | factor |"
        );
        println!("| --- | ---: | ---: | ---: | ---: | ---: |");
        let mut total = [0.0; 3];
        for (k, (n, r, d, e)) in self.rows.iter().enumerate() {
            println!(
                "| {n} | {r:.3} | {d:.3} | {:.2} | {e:.3} | {:.2} |",
                d / r,
                e / r
            );
            // The frame: one row of bullets (`ignoring`, watertight: the game's).
            if k != 4 && k != 6 {
                total[0] += r;
                total[1] += d;
                total[2] += e;
            }
        }
        println!(
            "| the frame (bullets by `ignoring`) | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            total[0],
            total[1],
            total[1] / total[0],
            total[2],
            total[2] / total[0]
        );
        println!(
            "\nAnswers differing from raylane's over all frames (hit or miss; `t` beyond 10^-3 relative plus 2^-18 of the origin's largest coordinate over `|d|`; the bullet's instance):\n"
        );
        for (n, d, e) in &self.differ {
            println!("* {n}: {d} (dynamic), {e} (default)");
        }
    }
}
