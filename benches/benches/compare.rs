//! raylane side by side with its peers, on the same scenes and the same rays:
//!
//! ```text
//! cargo bench -p raylane-bench --features peers --bench compare
//! ```
//!
//! Scenes: N = 16, 64, 256, 1024 spheres or triangles ([`Frame`]), seen by coherent primary rays
//! from a pinhole camera or by incoherent random rays; every frame is about 2^18 ray–primitive
//! tests. Every contender answers the same closest-hit query for every ray:
//!
//! * raylane: ray packets over the slice (N rays × 1 primitive, `xW`) and one ray over
//!   primitives packed in lanes (1 ray × N, `xW-soa`); focal caches for coherent rays, the
//!   general kernels for both.
//! * parry3d (`Ball`, `Triangle`), bevy (`sphere_intersection_at`), obvhs (`Triangle::intersect`):
//!   one ray against one primitive, in the same brute-force loop.
//! * raylane with its bounding spheres (coherent triangles): the triangles split into parts of
//!   16 with a bounding sphere each ([`raylane_bench::parts`]), as a user holds a scene; like
//!   Embree it skips most primitives, so it is compared in rays per second.
//! * Embree 3: its BVH over the scene (sphere points, a triangle mesh), single rays and 8-ray
//!   packets; it does not test every primitive, so it is compared in rays per second.
//!
//! Set-up is not timed: neither raylane's focal caches (built once per eye) nor Embree's BVH
//! (built once per scene), nor any conversion to a peer's types. Embree runs with flush-to-zero
//! and denormals-are-zero, as it asks; everything else with IEEE denormals.
//!
//! Before timing, every contender's answers are checked against raylane's reference (`robust`
//! or `watertight`, scalar): the same rays hit, with `t` within 1e-4 relative. A contender that
//! fails is reported and not timed.
//!
//! After criterion's report (about 4 minutes), a summary prints the CPU, one table per kind of
//! scene (contenders × N, rays/s and the ratio to raylane's best), every measurement with its
//! tests/s, and the goals of issue 5.

mod common;

use common::{Record, records, si, timed};
use criterion::{Criterion, Throughput};
use raylane::Lane;
use raylane_bench::embree;
use raylane_bench::parts::{self, Parts};
use raylane_bench::peers::{BevySpheres, ObvhsTriangles, ParryBalls, ParryTriangles, Peer};
use raylane_bench::{Frame, Kernel, Lanes, Prim, Rays, SIZES, Shape, answers, cpu, run};

/// Triangles per part (bounding sphere) in the culled contender.
const PART: usize = 16;

/// Relative tolerance on `t` in the checks.
const TOL: f64 = 1e-4;

/// One contender in one scene.
struct Contender<'a> {
    name: String,
    /// False for Embree (a BVH: rays/s only).
    brute_force: bool,
    run: Box<dyn Fn() -> u32 + 'a>,
    answers: Vec<Option<f32>>,
}

fn ts<T>(v: Vec<Option<(f32, T)>>) -> Vec<Option<f32>> {
    v.into_iter().map(|h| h.map(|(t, _)| t)).collect()
}

fn raylane<'a, L: Lane<Scalar = f32>>(
    k: Kernel,
    shape: Shape,
    f: &'a Frame,
    l: &'a Lanes<L>,
) -> Contender<'a> {
    Contender {
        name: format!("raylane {} x{}{}", k.name(), L::LANES, shape.suffix()),
        brute_force: true,
        run: Box::new(move || run(k, shape, f, l)),
        answers: answers(k, shape, f, l)
            .into_iter()
            .map(|h| h.map(|h| h.t))
            .collect(),
    }
}

fn peer<'a>(
    name: &str,
    run: impl Fn() -> u32 + 'a,
    answers: Vec<Option<(f32, u32)>>,
) -> Contender<'a> {
    Contender {
        name: name.to_string(),
        brute_force: true,
        run: Box::new(run),
        answers: ts(answers),
    }
}

fn embree<'a>(
    name: &str,
    run: impl Fn() -> u32 + 'a,
    answers: Vec<Option<(f32, u32)>>,
) -> Contender<'a> {
    Contender {
        brute_force: false,
        ..peer(name, run, answers)
    }
}

/// Group name of a scene.
fn group(prim: Prim, kind: Rays, n: usize) -> String {
    format!("{}/{}/N={n}", prim.plural(), kind.name())
}

fn scene(c: &mut Criterion, prim: Prim, kind: Rays, n: usize) {
    let f = Frame::new(n, kind);
    let (l1, l8, l16) = (
        Lanes::<f32>::new(&f, n),
        Lanes::<wide::f32x8>::new(&f, n),
        Lanes::<wide::f32x16>::new(&f, n),
    );
    let coherent = kind == Rays::Coherent;
    let (reference, general) = match prim {
        Prim::Sphere => (Kernel::Robust, Kernel::Robust),
        _ => (Kernel::Watertight, Kernel::Watertight),
    };
    let want: Vec<Option<f32>> = answers(reference, Shape::Packets, &f, &l1)
        .into_iter()
        .map(|h| h.map(|h| h.t))
        .collect();
    let (parry_b, parry_t, bevy, obvhs);
    let ebr = match prim {
        Prim::Sphere => embree::Scene::spheres(&f.spheres, &f.rays, coherent),
        _ => embree::Scene::triangles(&f.tris, &f.rays, coherent),
    };
    let parts = Parts::new(&f.tris, PART);
    let mut storage = parts.storage();
    let meshes;
    let mut all: Vec<Contender> = Vec::new();
    let fast = match (prim, coherent) {
        (Prim::Sphere, true) => Kernel::Focal,
        (Prim::Sphere, false) => Kernel::Robust,
        (_, true) => Kernel::TriangleFocal,
        (_, false) => Kernel::Watertight,
    };
    all.push(raylane(fast, Shape::Packets, &f, &l8));
    all.push(raylane(fast, Shape::Packets, &f, &l16));
    all.push(raylane(fast, Shape::Soa, &f, &l8));
    all.push(raylane(fast, Shape::Packets, &f, &l1));
    match (prim, coherent) {
        (Prim::Sphere, true) => all.push(raylane(general, Shape::Packets, &f, &l8)),
        (Prim::Sphere, false) => all.push(raylane(Kernel::Geometric, Shape::Packets, &f, &l8)),
        (_, true) => {
            all.push(raylane(Kernel::Watertight, Shape::Packets, &f, &l8));
            all.push(raylane(Kernel::Moller, Shape::Packets, &f, &l8));
            // The scene as a user would hold it: parts with bounding spheres.
            meshes = parts.focus(f.cam.eye, &mut storage);
            let (m, p8, p16) = (&meshes, &l8.packets, &l16.packets);
            let label =
                |w: usize| format!("raylane triangle-focal x{w} + bounding spheres ({PART})");
            all.push(Contender {
                name: label(8),
                brute_force: false,
                run: Box::new(move || parts::frame(p8, m)),
                answers: parts::answers(p8, m, f.rays.len()),
            });
            all.push(Contender {
                name: label(16),
                brute_force: false,
                run: Box::new(move || parts::frame(p16, m)),
                answers: parts::answers(p16, m, f.rays.len()),
            });
        }
        (_, false) => {
            all.push(raylane(Kernel::Moller, Shape::Packets, &f, &l8));
            all.push(raylane(Kernel::Moller, Shape::Soa, &f, &l8));
        }
    }
    match prim {
        Prim::Sphere => {
            parry_b = ParryBalls::new(&f);
            bevy = BevySpheres::new(&f);
            all.push(peer(
                "parry3d Ball::cast_local_ray",
                || parry_b.frame(),
                parry_b.answers(),
            ));
            all.push(peer(
                "bevy RayCast3d::sphere_intersection_at",
                || bevy.frame(),
                bevy.answers(),
            ));
        }
        _ => {
            parry_t = ParryTriangles::new(&f);
            obvhs = ObvhsTriangles::new(&f);
            all.push(peer(
                "parry3d Triangle::cast_local_ray",
                || parry_t.frame(),
                parry_t.answers(),
            ));
            all.push(peer(
                "obvhs Triangle::intersect",
                || obvhs.frame(),
                obvhs.answers(),
            ));
        }
    }
    all.push(embree(
        "Embree rtcIntersect1",
        || ebr.frame1(),
        ebr.answers1(),
    ));
    all.push(embree(
        "Embree rtcIntersect8",
        || ebr.frame8(),
        ebr.answers8(),
    ));

    let name = group(prim, kind, n);
    let hits = want.iter().filter(|h| h.is_some()).count();
    println!(
        "check {name}: {} rays, {hits} hit; reference raylane {} x1",
        want.len(),
        reference.name()
    );
    if prim == Prim::Triangle && ebr.backface_culling() {
        println!("  note: this Embree build culls back faces");
    }
    let mut timed_ok = Vec::new();
    for k in all {
        let (bad, worst) = raylane_bench::compare(&k.answers, &want);
        let ok = bad == 0 && worst <= TOL;
        println!(
            "  {:<44} {} hit/miss differ, max |Δt|/t {:.1e}{}",
            k.name,
            bad,
            worst,
            if ok { "" } else { "  FAILED: not timed" }
        );
        if ok {
            timed_ok.push(k);
        }
    }
    let mut g = c.benchmark_group(&name);
    let (tests, rays) = (f.tests() as u64, f.rays.len() as u64);
    for k in &timed_ok {
        g.throughput(Throughput::Elements(if k.brute_force {
            tests
        } else {
            rays
        }));
        g.bench_function(&k.name, |b| {
            timed(
                b,
                (&name, &k.name),
                if k.brute_force { tests } else { 0 },
                rays,
                &k.run,
            )
        });
    }
    g.finish();
}

/// raylane's best rays/s among the records of one group.
fn best_raylane(rows: &[(&String, &Record)]) -> f64 {
    rows.iter()
        .filter(|(id, _)| id.starts_with("raylane"))
        .map(|(_, r)| r.rays_per_sec())
        .fold(0.0, f64::max)
}

fn summary() {
    let recs = records();
    if recs.is_empty() {
        return;
    }
    println!("\n## Side by side with peers\n");
    println!("CPU: {}\n", cpu());
    println!(
        "Every frame is about 2^18 ray–primitive tests (N = 16: 128×128 rays … N = 1024: \
         16×16). tests/s counts every ray against every primitive (brute force); Embree \
         traverses its BVH and raylane's `+ bounding spheres` contender culls parts of 16 \
         triangles, so these two are compared in rays/s. Ratio: rays/s over raylane's best \
         in the same scene.\n"
    );
    pivot(&recs);
    println!("\n### Every measurement\n");
    println!("| scene | contender | tests/s | rays/s | × raylane's best |");
    println!("| --- | --- | ---: | ---: | ---: |");
    let mut groups: Vec<String> = recs.keys().map(|(g, _)| g.clone()).collect();
    groups.dedup();
    for g in &groups {
        let mut rows: Vec<(&String, &Record)> = recs
            .iter()
            .filter(|((gg, _), _)| gg == g)
            .map(|((_, id), r)| (id, r))
            .collect();
        rows.sort_by(|a, b| b.1.rays_per_sec().total_cmp(&a.1.rays_per_sec()));
        let best = best_raylane(&rows);
        for (id, r) in rows {
            let t = if r.tests > 0 {
                si(r.tests_per_sec())
            } else {
                "—".into()
            };
            println!(
                "| {g} | {id} | {t} | {} | {:.3} |",
                si(r.rays_per_sec()),
                r.rays_per_sec() / best
            );
        }
    }
    goals(&recs);
}

/// One table per kind of scene: contenders × N, rays/s and the ratio to raylane's best.
fn pivot(recs: &std::collections::BTreeMap<(String, String), Record>) {
    for prim in [Prim::Sphere, Prim::Triangle] {
        for kind in [Rays::Coherent, Rays::Incoherent] {
            let best: Vec<f64> = SIZES
                .iter()
                .map(|&n| {
                    let g = group(prim, kind, n);
                    let rows: Vec<(&String, &Record)> = recs
                        .iter()
                        .filter(|((gg, _), _)| *gg == g)
                        .map(|((_, id), r)| (id, r))
                        .collect();
                    best_raylane(&rows)
                })
                .collect();
            let mut names: Vec<&String> = recs
                .iter()
                .filter(|((g, _), _)| g.starts_with(&format!("{}/{}/", prim.plural(), kind.name())))
                .map(|((_, id), _)| id)
                .collect();
            if names.is_empty() {
                continue;
            }
            names.sort();
            names.dedup();
            // Fastest first, by the mean of the ratios over the sizes.
            let score = |id: &String| -> f64 {
                let r: Vec<f64> = SIZES
                    .iter()
                    .zip(&best)
                    .filter_map(|(&n, b)| {
                        get(recs, &group(prim, kind, n), id).map(|r| r.rays_per_sec() / b)
                    })
                    .collect();
                r.iter().sum::<f64>() / r.len().max(1) as f64
            };
            names.sort_by(|a, b| score(b).total_cmp(&score(a)));
            println!(
                "**{}, {} rays**: rays/s (× raylane's best in the same scene)\n",
                prim.plural(),
                kind.name()
            );
            let mut head = String::from("| contender |");
            let mut rule = String::from("| --- |");
            for n in SIZES {
                head += &format!(" N = {n} |");
                rule += " ---: |";
            }
            println!("{head}\n{rule}");
            for id in names {
                let mut row = format!("| {id} |");
                for (&n, b) in SIZES.iter().zip(&best) {
                    match get(recs, &group(prim, kind, n), id) {
                        Some(r) => {
                            row += &format!(
                                " {} ({:.2}) |",
                                si(r.rays_per_sec()),
                                r.rays_per_sec() / b
                            )
                        }
                        None => row += " — |",
                    }
                }
                println!("{row}");
            }
            println!();
        }
    }
}

fn get<'a>(
    recs: &'a std::collections::BTreeMap<(String, String), Record>,
    g: &str,
    id: &str,
) -> Option<&'a Record> {
    recs.get(&(g.to_string(), id.to_string()))
}

fn goals(recs: &std::collections::BTreeMap<(String, String), Record>) {
    println!("\n## Goals (issue 5)\n");
    println!("| goal | scene | raylane | peer | ratio | met |");
    println!("| --- | --- | ---: | ---: | ---: | --- |");
    let pairs = [
        (
            "focal sphere x8 ≥ 10× parry3d Ball (tests/s)",
            Prim::Sphere,
            "raylane focal x8",
            "parry3d Ball::cast_local_ray",
            10.0,
        ),
        (
            "focal triangle x8 ≥ 8× parry3d Triangle (tests/s)",
            Prim::Triangle,
            "raylane triangle-focal x8",
            "parry3d Triangle::cast_local_ray",
            8.0,
        ),
    ];
    for (goal, prim, ours, theirs, want) in pairs {
        for n in SIZES {
            let g = group(prim, Rays::Coherent, n);
            if let (Some(a), Some(b)) = (get(recs, &g, ours), get(recs, &g, theirs)) {
                let r = a.tests_per_sec() / b.tests_per_sec();
                println!(
                    "| {goal} | {g} | {} | {} | {r:.1}× | {} |",
                    si(a.tests_per_sec()),
                    si(b.tests_per_sec()),
                    if r >= want { "yes" } else { "**no**" }
                );
            }
        }
    }
    for prim in [Prim::Sphere, Prim::Triangle] {
        for n in SIZES {
            let g = group(prim, Rays::Coherent, n);
            let rows: Vec<(&String, &Record)> = recs
                .iter()
                .filter(|((gg, _), _)| *gg == g)
                .map(|((_, id), r)| (id, r))
                .collect();
            let best = best_raylane(&rows);
            let who = rows
                .iter()
                .filter(|(id, _)| id.starts_with("raylane"))
                .max_by(|a, b| a.1.rays_per_sec().total_cmp(&b.1.rays_per_sec()))
                .map(|(id, _)| id.trim_start_matches("raylane ").to_string())
                .unwrap_or_default();
            if let Some(e) = get(recs, &g, "Embree rtcIntersect8")
                && best > 0.0
            {
                let r = best / e.rays_per_sec();
                let goal = if n <= 256 {
                    "primary rays/s > Embree rtcIntersect8 (N ≤ 256)"
                } else {
                    "(beyond the goal) primary rays/s vs Embree rtcIntersect8"
                };
                println!(
                    "| {goal} | {g} | {} ({who}) | {} | {r:.2}× | {} |",
                    si(best),
                    si(e.rays_per_sec()),
                    if n > 256 {
                        "—"
                    } else if r > 1.0 {
                        "yes"
                    } else {
                        "**no**"
                    }
                );
            }
        }
    }
}

fn main() {
    let mut c = common::criterion(1000);
    println!("CPU: {}", cpu());
    for prim in [Prim::Sphere, Prim::Triangle] {
        for kind in [Rays::Coherent, Rays::Incoherent] {
            for n in SIZES {
                scene(&mut c, prim, kind, n);
            }
        }
    }
    c.final_summary();
    summary();
}
