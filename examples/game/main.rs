//! An engine's frame (issue 30): a scene of 10,000 instances of 7 shapes (the vendored bunny,
//! generated crates, rocks, pillars, ball clusters, two-sphere agents and a ground of 18,432
//! triangles) that all move every frame, and the questions a game asks of it each frame:
//!
//! * **picking**: what is under the cursor (one ray through a moving cursor, `closest`, with
//!   a hit filter that sees through glass);
//! * **line of sight** between 1,000 pairs of agents, on every layer but the agents' own
//!   (`any` with a layer mask: the agents look past each other);
//! * **10,000 bullets** (`closest`, each from inside its shooter's body, ignoring the shooter:
//!   `scene.ignoring(shooter)`, or `--filter` for the same job as a hit filter closure);
//! * **shadow rays** from every bullet's impact to one light (`any`).
//!
//! It prints, per frame, the milliseconds to stage the moves (`set_transform` of every
//! instance), to commit them (the top level refitted or rebuilt), and for each kind of query,
//! then the medians. One thread.
//!
//! ```sh
//! cargo run --release --example game [-- --frames N] [--instances N]
//!     [--rebuild auto|always|never|RATIO] [--packets] [--filter] [--speed N]
//! ```
//!
//! `--rebuild` picks the commit's rule (the default, `auto`, is `OwnedScene`'s: refit until
//! the tree's SAH cost passes `REBUILD_RATIO` times its cost at the last rebuild; a number
//! sets another ratio); `--packets` traces bullets
//! and sight lines in packets of 8 (each lane ignoring its own shooter); `--speed N` runs the
//! game N times faster (frames of N/60 s: the long run of a refitted tree, in few frames).

mod world;

use std::time::Instant;

use raylane::bvh::{Commit, InstanceId, OwnedBvh, OwnedScene};
use raylane::glam::Vec3;
use raylane::set::Filtered;
use raylane::wide::f32x8;
use raylane::{Hit, Mask, Pinhole, Query, Ray, RayPacket};
use world::{AGENTS, Prims, Rng};

struct Opts {
    frames: usize,
    instances: usize,
    rebuild: f64,
    packets: bool,
    filter: bool,
    /// Game seconds per frame, in 60ths.
    speed: f32,
}

fn opts() -> Opts {
    let mut o = Opts {
        frames: 30,
        instances: 10_000,
        rebuild: raylane::bvh::owned_scene::REBUILD_RATIO,
        packets: false,
        filter: false,
        speed: 1.0,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut num = || args.next().and_then(|v| v.parse().ok());
        match a.as_str() {
            "--frames" => o.frames = num().unwrap_or(o.frames),
            "--instances" => o.instances = num().unwrap_or(o.instances).max(2),
            "--packets" => o.packets = true,
            "--filter" => o.filter = true,
            "--speed" => o.speed = num().map_or(o.speed, |x: usize| x as f32),
            "--rebuild" => {
                o.rebuild = match args.next().as_deref() {
                    Some("always") => 0.0,
                    Some("never") => f64::INFINITY,
                    Some(x) => x.parse().unwrap_or(o.rebuild),
                    None => o.rebuild,
                }
            }
            _ => {
                eprintln!(
                    "usage: game [--frames N] [--instances N] [--rebuild auto|always|never|RATIO] [--packets] [--filter] [--speed N]"
                );
                std::process::exit(2);
            }
        }
    }
    o
}

/// Milliseconds since `t`.
fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let o = opts();
    let shapes = world::shapes();
    let mut scene = OwnedScene::new();
    scene.set_rebuild_ratio(o.rebuild);
    let t = Instant::now();
    let objects: Vec<_> = shapes
        .iter()
        .map(|s| match &s.prims {
            Prims::Mesh(t) => scene.add_object(OwnedBvh::new(&t[..]).unwrap()),
            Prims::Balls(b) => scene.add_object(OwnedBvh::new(&b[..]).unwrap()),
        })
        .collect();
    let built = ms(t);
    let mut actors = world::actors(o.instances, 1);
    let ids: Vec<InstanceId> = actors
        .iter()
        .map(|a| {
            scene
                .add(objects[a.shape], world::rows(a), a.layer)
                .unwrap()
        })
        .collect();
    let t = Instant::now();
    scene.commit();
    let first = ms(t);
    let agents = world::agents(&actors);
    // Per slot (instances are never removed here, so slot = actor): glass or not.
    let glass: Vec<bool> = actors.iter().map(|a| a.shape == world::GLASS).collect();
    let shape_list: Vec<String> = shapes
        .iter()
        .map(|s| match &s.prims {
            Prims::Mesh(t) => format!("{} ({} triangles)", s.name, t.len()),
            Prims::Balls(b) => format!("{} ({} spheres)", s.name, b.len()),
        })
        .collect();
    println!(
        "{} instances of {} objects: {}; objects built in {built:.1} ms, first commit {first:.1} ms",
        ids.len(),
        shapes.len(),
        shape_list.join(", ")
    );
    println!(
        "{} agents; per frame: 1 pick, 1,000 sight lines, 10,000 bullets, a shadow ray per impact; {}",
        agents.len(),
        match (o.packets, o.filter) {
            (true, _) => "packets of 8",
            (false, true) => "one ray per query, bullets through a filter closure",
            (false, false) => "one ray per query",
        }
    );
    let cam = Pinhole::look_at(
        Vec3::new(0.0, 90.0, 140.0),
        Vec3::ZERO,
        Vec3::Y,
        60.0,
        1280,
        720,
    );
    let mut rng = Rng::new(2);
    let mut rows = Vec::new();
    let mut kinds = (0, 0);
    println!(
        "\nframe  stage ms  commit ms         pick ms  sight ms  bullets ms  shadows ms  |   SAH  picked, in sight, bullets hit, impacts lit"
    );
    for frame in 0..o.frames {
        world::step(&mut actors, o.speed / 60.0);
        // The frame's rays (not timed: a game has them from its own state).
        let lines = world::sight_lines(&actors, &agents, 1000, &mut rng);
        let shots = world::bullets(&actors, &agents, 10_000, &mut rng);
        let (cx, cy) = (
            640 + (500.0 * (frame as f32 * 0.05).cos()) as u32,
            360 + (300.0 * (frame as f32 * 0.07).sin()) as u32,
        );
        let cursor = cam.row_packet::<f32>(cx, cy).ray(0);

        // The engine moves every instance, then commits the frame.
        let t = Instant::now();
        for (id, a) in ids.iter().zip(&actors) {
            scene.set_transform(*id, world::rows(a)).unwrap();
        }
        let stage = ms(t);
        let t = Instant::now();
        let how = scene.commit();
        let commit = ms(t);
        match how {
            Commit::Refit => kinds.0 += 1,
            Commit::Rebuild => kinds.1 += 1,
            Commit::Unchanged => {}
        }

        // Picking, through glass.
        let t = Instant::now();
        let picked = scene.filtered(|c| !glass[c.set as usize]).closest(&cursor);
        let pick = ms(t);

        // Line of sight on every layer but the agents'.
        let t = Instant::now();
        let in_sight = if o.packets {
            sight_packets(&scene, &lines)
        } else {
            let seen = scene.masked(!AGENTS);
            lines.iter().filter(|(_, _, r)| !seen.any(r)).count()
        };
        let sight = ms(t);

        // Bullets: the closest hit that is not the shooter.
        let t = Instant::now();
        let impacts: Vec<Hit> = if o.packets {
            bullet_packets(&scene, &ids, &shots)
        } else if o.filter {
            shots
                .iter()
                .filter_map(|(s, r)| {
                    let me = ids[*s].slot();
                    scene.filtered(|c| c.set != me).closest(r)
                })
                .collect()
        } else {
            shots
                .iter()
                .filter_map(|(s, r)| scene.ignoring(ids[*s]).closest(r))
                .collect()
        };
        let bullets = ms(t);

        // Shadows: is each impact lit?
        let t = Instant::now();
        let lit = impacts
            .iter()
            .filter(|h| !scene.any(&world::shadow(h.point)))
            .count();
        let shadows = ms(t);

        println!(
            "{frame:5}  {stage:8.2}  {commit:5.2} {:7}  {pick:7.3}  {sight:8.2}  {bullets:10.2}  {shadows:10.2}  | {:5.2}  {}, {in_sight}, {}, {lit}",
            format!("{how:?}").to_lowercase(),
            scene.stats().sah,
            picked.map_or("nothing".to_string(), |h| {
                let id = scene.instance(h.set).unwrap();
                let a = &actors[ids.iter().position(|&i| i == id).unwrap()];
                shapes[a.shape].name.to_string()
            }),
            impacts.len(),
        );
        rows.push([stage, commit, pick, sight, bullets, shadows]);
    }
    let col = |k: usize| median(rows.iter().map(|r| r[k]).collect());
    let mean = rows.iter().map(|r| r.iter().sum::<f64>()).sum::<f64>() / rows.len() as f64;
    println!(
        "\nmedian ms over {} frames: stage {:.2}, commit {:.2} ({} refits, {} rebuilds), pick {:.3}, sight lines {:.2}, bullets {:.2}, shadows {:.2}; frame {:.1} (mean {mean:.1})",
        rows.len(),
        col(0),
        col(1),
        kinds.0,
        kinds.1,
        col(2),
        col(3),
        col(4),
        col(5),
        (0..6).map(col).sum::<f64>()
    );
    println!(
        "top level: {:.2} SAH cost, depth {}",
        scene.stats().sah,
        scene.stats().depth
    );
}

/// Sight lines in packets of 8, every lane on every layer but the agents'.
fn sight_packets(scene: &OwnedScene, lines: &[(usize, usize, Ray)]) -> usize {
    let seen = scene.masked(!AGENTS);
    let mut n = 0;
    let mut rays = [Ray::new(Vec3::ZERO, Vec3::X); 8];
    for chunk in lines.chunks(8) {
        for (r, (_, _, l)) in rays.iter_mut().zip(chunk) {
            *r = *l;
        }
        let blocked = seen.any(&RayPacket::<f32x8>::from_rays(&rays[..chunk.len()]));
        n += (0..chunk.len()).filter(|&i| !blocked.test(i)).count();
    }
    n
}

/// Bullets in packets of 8, each lane ignoring its own shooter.
fn bullet_packets(scene: &OwnedScene, ids: &[InstanceId], shots: &[(usize, Ray)]) -> Vec<Hit> {
    let mut out = Vec::with_capacity(shots.len());
    for chunk in shots.chunks(8) {
        let mut me = [u32::MAX; 8];
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::X); 8];
        for (k, (s, r)) in chunk.iter().enumerate() {
            me[k] = ids[*s].slot();
            rays[k] = *r;
        }
        let hits = Filtered::new(scene)
            .ignores(&me)
            .closest(&RayPacket::<f32x8>::from_rays(&rays[..chunk.len()]));
        out.extend((0..chunk.len()).filter_map(|i| hits.lane(i)));
    }
    out
}
