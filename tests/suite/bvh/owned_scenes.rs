//! The engine's scene (issue 30): an `OwnedScene` of meshes and sphere sets, instances added,
//! moved, re-layered and removed over several frames, answers every query as brute force
//! over its committed instances (every instance × every primitive, with the same layer masks
//! and filter, the tie rule `(t, instance, index)`), bit for bit, for one ray and packets of
//! 1, 4, 8 and 16 lanes each with its own mask, and for camera tiles; refit and rebuild give
//! the same answers. Bad input: removed and stale handles, NaN, infinite and singular
//! transforms, an empty scene and one emptied during a frame; a scene shared by threads.

use crate::bvh::equals_brute_force::{flat, soup, v3};
use crate::sets::bunny_visible_surface::load_bin;
use crate::sets::masks_and_filters::{Want, candidate, check_against, filters, sight_of};
use crate::sets::query_records_every_width::bits;
use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bvh::{Commit, Instance, InstanceId, ObjectId, OwnedBvh, OwnedScene, SceneError};
use raylane::hit::Candidate;
use raylane::mesh::Mesh;
use raylane::set::Filtered;
use raylane::sphere::Sphere;
use raylane::triangle::Triangle;
use raylane::{Hit, Pinhole, Query, Ray, RayPacket};
use wide::{f32x8, f32x16};

/// An object's primitives, for brute force.
enum Flat {
    Tris(Vec<Triangle>),
    Balls(Vec<Sphere>),
}

type Rows = [[f32; 4]; 3];

/// Every hit of a flat set of `P` for a ray, passed to a callback (a kernel and culling).
type Every<'a, P> = &'a dyn Fn(&[P], &Ray, &mut dyn FnMut(Hit));

/// The scene and a model of it: per slot, the committed `(object, transform, mask)`.
struct World {
    flats: Vec<Flat>,
    objects: Vec<ObjectId>,
    scene: OwnedScene,
    live: Vec<InstanceId>,
    staged: Vec<Option<(u32, Rows, u32)>>,
    committed: Vec<Option<(u32, Rows, u32)>>,
}

impl World {
    fn new(rng: &mut SmallRng) -> World {
        let m = load_bin(include_bytes!("../../data/bunny.bin"));
        let bunny: Vec<Triangle> = flat(&Mesh::new(&m.pos, &m.idx))
            .into_iter()
            .map(|t| {
                // The bunny spans about 0.15 units: made about 1 unit.
                Triangle::new(t.a() * 6.0, t.b() * 6.0, t.c() * 6.0)
            })
            .collect();
        let balls: Vec<Sphere> = (0..120)
            .map(|_| Sphere::new(v3(rng, 1.0), rng.random_range(0.03..0.3)))
            .collect();
        let flats = vec![
            Flat::Tris(soup(rng, 250)),
            Flat::Balls(balls),
            Flat::Tris(bunny),
        ];
        let mut scene = OwnedScene::new();
        let objects = flats
            .iter()
            .map(|f| match f {
                Flat::Tris(t) => scene.add_object(OwnedBvh::new(&t[..]).unwrap()),
                Flat::Balls(b) => scene.add_object(OwnedBvh::new(&b[..]).unwrap()),
            })
            .collect();
        World {
            flats,
            objects,
            scene,
            live: Vec::new(),
            staged: Vec::new(),
            committed: Vec::new(),
        }
    }

    fn add(&mut self, object: u32, rows: Rows, mask: u32) -> InstanceId {
        let id = self
            .scene
            .add(self.objects[object as usize], rows, mask)
            .unwrap();
        let s = id.slot() as usize;
        if self.staged.len() <= s {
            self.staged.resize(s + 1, None);
        }
        self.staged[s] = Some((object, rows, mask));
        self.live.push(id);
        id
    }

    fn remove(&mut self, k: usize) {
        let id = self.live.swap_remove(k);
        self.scene.remove(id).unwrap();
        self.staged[id.slot() as usize] = None;
    }

    fn commit(&mut self) -> Commit {
        self.committed = self.staged.clone();
        self.scene.commit()
    }

    /// Brute force for ray `r` on the layers `mask` with the filter `keep`.
    fn brute(&self, r: &Ray, mask: u32, keep: &dyn Fn(&Candidate) -> bool) -> Want {
        self.brute_ignoring(r, (mask, u32::MAX), keep)
    }

    /// Brute force for ray `r` on the layers `sight.0`, ignoring instance `sight.1`, with the
    /// filter `keep`.
    fn brute_ignoring(
        &self,
        r: &Ray,
        sight: (u32, u32),
        keep: &dyn Fn(&Candidate) -> bool,
    ) -> Want {
        self.brute_with(r, sight, keep, &|t, l, f| t.all(l, f), &|b, l, f| {
            b.all(l, f)
        })
    }

    /// Brute force as [`brute_ignoring`](Self::brute_ignoring) with the triangles' and
    /// spheres' every hit from `tris` and `balls` (another kernel, culling).
    fn brute_with(
        &self,
        r: &Ray,
        (mask, ignored): (u32, u32),
        keep: &dyn Fn(&Candidate) -> bool,
        tris: Every<'_, Triangle>,
        balls: Every<'_, Sphere>,
    ) -> Want {
        let mut kept = Vec::new();
        let mut best: Option<Hit> = None;
        for (slot, e) in self.committed.iter().enumerate() {
            let Some((object, rows, m)) = *e else {
                continue;
            };
            if m & mask == 0 || slot as u32 == ignored {
                continue;
            }
            let inst = Instance::new(object, rows);
            let local = inst.ray_to_object(r);
            let mut visit = |h: Hit, sphere: bool| {
                let mut c = candidate(&h, sphere);
                c.set = slot as u32;
                if !keep(&c) {
                    return;
                }
                kept.push((slot as u32, h.index, h.t.to_bits()));
                let w = Hit {
                    set: slot as u32,
                    point: r.at(h.t),
                    front: h.front != inst.mirror,
                    ..h
                };
                if best.is_none_or(|b| (w.t, w.set, w.index) < (b.t, b.set, b.index)) {
                    best = Some(w);
                }
            };
            match &self.flats[object as usize] {
                Flat::Tris(t) => tris(t, &local, &mut |h| visit(h, false)),
                Flat::Balls(b) => balls(b, &local, &mut |h| visit(h, true)),
            }
        }
        kept.sort_unstable();
        Want { kept, best }
    }

    /// Every query of `rays` (every filter, lane masks and ignored instances from `sight_of`)
    /// against brute force;
    /// the unfiltered scene against `Filtered::new` at every width. Returns the hits.
    fn check(&self, rays: &[Ray], least: usize) -> usize {
        let mut hits = 0;
        for (name, f) in filters() {
            let f = &*f;
            let want: Vec<Want> = rays
                .iter()
                .enumerate()
                .map(|(i, r)| self.brute_ignoring(r, sight_of(i), f))
                .collect();
            let got = check_against(
                &|m, i| self.scene.filtered(f).masks(m).ignores(i),
                rays,
                &want,
                &sight_of,
                false,
            );
            assert!(name == "nothing" || got >= least, "{name}: {got} hits");
            hits += got;
        }
        // No mask, no filter: brute force with every bit, and the plain scene.
        let want: Vec<Want> = rays
            .iter()
            .map(|r| self.brute(r, u32::MAX, &|_| true))
            .collect();
        check_against(
            &|_, _| Filtered::new(&self.scene),
            rays,
            &want,
            &|_| (u32::MAX, u32::MAX),
            false,
        );
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(
                bits(self.scene.closest(r)),
                bits(Filtered::new(&self.scene).closest(r)),
                "ray {i}"
            );
            assert_eq!(self.scene.any(r), want[i].best.is_some());
        }
        for chunk in rays.chunks(16) {
            let p = RayPacket::<f32x16>::from_rays(chunk);
            let (a, b) = (
                self.scene.closest(&p),
                Filtered::new(&self.scene).closest(&p),
            );
            for j in 0..chunk.len() {
                assert_eq!(bits(a.lane(j)), bits(b.lane(j)));
            }
        }
        hits
    }
}

/// A transform: rotation, scale (some mirrored), translation within `spread`.
fn place(rng: &mut SmallRng, spread: f32) -> Rows {
    let axis = v3(rng, 1.0).normalize_or(Vec3::Z);
    let q = glam::Quat::from_axis_angle(axis, rng.random_range(0.0..std::f32::consts::TAU));
    let s = [0.5, 1.0, 2.0][rng.random_range(0..3)];
    let mut m = glam::Mat3::from_quat(q) * s;
    if rng.random_range(0..6) == 0 {
        m *= glam::Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
    }
    let t = v3(rng, spread);
    [0, 1, 2].map(|r| [m.col(0)[r], m.col(1)[r], m.col(2)[r], t[r]])
}

/// Rays at the instances (their origins, jittered) and random ones.
fn shots(rng: &mut SmallRng, world: &World, n: usize) -> Vec<Ray> {
    let aim: Vec<Vec3> = world
        .committed
        .iter()
        .flatten()
        .map(|(_, rows, _)| Vec3::new(rows[0][3], rows[1][3], rows[2][3]))
        .collect();
    (0..n)
        .map(|i| {
            let o = v3(rng, 12.0);
            let d = if i % 4 != 3 && !aim.is_empty() {
                aim[i % aim.len()] + v3(rng, 0.5) - o
            } else {
                v3(rng, 1.0)
            };
            if i % 7 == 0 {
                Ray::with_interval(o, d, 0.0, rng.random_range(0.3..1.2))
            } else {
                Ray::new(o, d)
            }
        })
        .collect()
}

const LAYERS: [u32; 6] = [1, 2, 4, 3, u32::MAX, 0];

fn new_world(rng: &mut SmallRng) -> World {
    World::new(rng)
}

#[test]
fn owned_scenes_equal_brute_force_frame_by_frame() {
    let mut rng = SmallRng::seed_from_u64(300);
    let mut world = new_world(&mut rng);
    for i in 0..40u32 {
        let rows = place(&mut rng, 8.0);
        let object = [0, 1, 2, 0, 1][i as usize % 5];
        world.add(object, rows, LAYERS[i as usize % LAYERS.len()]);
    }
    assert_eq!(world.commit(), Commit::Rebuild);
    let mut hits = world.check(&shots(&mut rng, &world, 160), 10);
    for frame in 0..3 {
        // Move everything a little, remove a few, add a few (into the freed slots), re-layer one.
        let ids = world.live.clone();
        for id in ids {
            let mut rows = world.scene.transform(id).unwrap();
            for row in &mut rows {
                row[3] += rng.random_range(-0.5..0.5);
            }
            world.scene.set_transform(id, rows).unwrap();
            let s = world.staged[id.slot() as usize].as_mut().unwrap();
            s.1 = rows;
        }
        for _ in 0..3 {
            let k = rng.random_range(0..world.live.len());
            world.remove(k);
        }
        for i in 0..3 {
            world.add(
                i,
                place(&mut rng, 8.0),
                LAYERS[(frame + i as usize) % LAYERS.len()],
            );
        }
        let id = world.live[0];
        world.scene.set_mask(id, 4).unwrap();
        world.staged[id.slot() as usize].as_mut().unwrap().2 = 4;
        let how = world.commit();
        assert_ne!(how, Commit::Unchanged, "frame {frame}");
        hits += world.check(&shots(&mut rng, &world, 120), 10);
    }
    assert!(hits > 2000, "{hits}");
    assert_eq!(world.scene.commit(), Commit::Unchanged);
}

/// Refit and rebuild: the same answers (only the tree differs); far moves make a refit's tree
/// costly enough to rebuild.
#[test]
fn refit_and_rebuild_give_the_same_answers() {
    let mut rng = SmallRng::seed_from_u64(301);
    let mut world = new_world(&mut rng);
    for i in 0..300u32 {
        world.add(i % 2, place(&mut rng, 20.0), u32::MAX);
    }
    world.commit();
    // Small moves: refits.
    let ids = world.live.clone();
    for &id in &ids {
        let mut rows = world.scene.transform(id).unwrap();
        rows[0][3] += 0.01;
        world.scene.set_transform(id, rows).unwrap();
        world.staged[id.slot() as usize].as_mut().unwrap().1 = rows;
    }
    assert_eq!(world.commit(), Commit::Refit);
    let rays = shots(&mut rng, &world, 300);
    let refit: Vec<_> = rays.iter().map(|r| bits(world.scene.closest(r))).collect();
    assert_eq!(world.scene.commit_rebuilt(), Commit::Rebuild);
    let rebuilt: Vec<_> = rays.iter().map(|r| bits(world.scene.closest(r))).collect();
    assert_eq!(refit, rebuilt);
    // Shuffle every instance across the world: the refitted tree is far worse, so rebuilt.
    for &id in &ids {
        let rows = place(&mut rng, 20.0);
        world.scene.set_transform(id, rows).unwrap();
        world.staged[id.slot() as usize].as_mut().unwrap().1 = rows;
    }
    assert_eq!(world.commit(), Commit::Rebuild);
    world.check(&shots(&mut rng, &world, 60), 3);
}

/// Removed and stale handles are errors and change nothing; NaN, infinite and singular
/// transforms hide their instance; an empty scene and a scene emptied during a frame miss.
#[test]
fn bad_handles_transforms_and_empty_scenes() {
    let mut rng = SmallRng::seed_from_u64(302);
    let mut world = new_world(&mut rng);
    let ray = Ray::new(Vec3::new(0.0, 0.0, 10.0), Vec3::NEG_Z);
    let p = RayPacket::<f32x8>::splat(&ray);
    // Empty, before and after a commit.
    assert_eq!(world.scene.closest(&ray), None);
    assert!(!world.scene.any(&ray) && world.scene.any(&p).none());
    assert_eq!(world.scene.commit(), Commit::Unchanged);
    assert_eq!(world.scene.closest(&ray), None);
    assert!(world.scene.is_empty());

    let at = |z: f32| {
        [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, z],
        ]
    };
    let a = world.add(1, at(0.0), 1);
    let b = world.add(1, at(-4.0), 1);
    world.commit();
    let first = world.scene.closest(&ray).unwrap();
    assert_eq!(world.scene.instance(first.set), Some(a));

    // Stale handles: removed, then the slot reused.
    world.remove(0);
    assert_eq!(world.scene.remove(a), Err(SceneError::Stale));
    assert_eq!(
        world.scene.set_transform(a, at(1.0)),
        Err(SceneError::Stale)
    );
    assert_eq!(world.scene.set_mask(a, 1), Err(SceneError::Stale));
    assert_eq!(world.scene.transform(a), None);
    // Queries see the last commit until the next one.
    assert_eq!(
        world.scene.instance(world.scene.closest(&ray).unwrap().set),
        Some(a)
    );
    let c = world.add(1, at(2.0), 1);
    assert_eq!(c.slot(), a.slot());
    assert_ne!(c, a);
    assert!(!world.scene.contains(a) && world.scene.contains(c));
    assert_eq!(
        world.scene.set_transform(a, at(1.0)),
        Err(SceneError::Stale)
    );
    world.commit();
    let h = world.scene.closest(&ray).unwrap();
    assert_eq!(world.scene.instance(h.set), Some(c));
    world.check(&[ray], 0);

    // Transforms no query can use: NaN, infinite, singular. The instance hides; no panic.
    for bad in [
        [
            [f32::NAN, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        [
            [1.0, 0.0, 0.0, f32::INFINITY],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        [[0.0; 4]; 3],
        [
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
    ] {
        world.scene.set_transform(c, bad).unwrap();
        world.staged[c.slot() as usize].as_mut().unwrap().1 = bad;
        world.commit();
        let h = world.scene.closest(&ray).unwrap();
        assert_eq!(world.scene.instance(h.set), Some(b), "{bad:?}");
        assert_eq!(world.scene.instance(c.slot()), None);
        world.check(&[ray], 0);
        let hp = world.scene.closest(&p);
        assert_eq!(bits(hp.lane(3)), bits(Some(h)));
    }
    // Back to a finite transform: seen again.
    world.scene.set_transform(c, at(2.0)).unwrap();
    world.staged[c.slot() as usize].as_mut().unwrap().1 = at(2.0);
    world.commit();
    assert_eq!(
        world.scene.instance(world.scene.closest(&ray).unwrap().set),
        Some(c)
    );

    // An instance on no layer is seen by no query, masked or not.
    world.scene.set_mask(c, 0).unwrap();
    world.staged[c.slot() as usize].as_mut().unwrap().2 = 0;
    world.commit();
    assert_eq!(
        world.scene.instance(world.scene.closest(&ray).unwrap().set),
        Some(b)
    );
    assert_eq!(
        world.scene.masked(u32::MAX).closest(&ray).unwrap().set,
        b.slot()
    );
    assert_eq!(world.scene.masked(2).closest(&ray), None);

    // Emptied during a frame: still answering the last commit, then nothing.
    while !world.live.is_empty() {
        world.remove(0);
    }
    assert!(world.scene.is_empty());
    assert!(world.scene.any(&ray));
    world.commit();
    assert_eq!(world.scene.closest(&ray), None);
    assert!(world.scene.any(&p).none());
    assert!(world.scene.closest(&p).mask.none());
    let mut n = 0;
    world.scene.all(&ray, |_| n += 1);
    assert_eq!(n, 0);
    world.check(&[ray], 0);
    // And filled again.
    let d = world.add(1, at(0.0), 1);
    world.commit();
    assert_eq!(
        world.scene.instance(world.scene.closest(&ray).unwrap().set),
        Some(d)
    );
    // Another scene's object: refused.
    let mut other = OwnedScene::new();
    assert_eq!(
        other.add(world.objects[2], at(0.0), 1),
        Err(SceneError::NoObject)
    );
}

/// A camera's tiles through a masked, filtered scene: every pixel as its own ray.
#[test]
fn tiles_through_masks_and_filters() {
    let mut rng = SmallRng::seed_from_u64(303);
    let mut world = new_world(&mut rng);
    for i in 0..60u32 {
        world.add(i % 3, place(&mut rng, 6.0), LAYERS[i as usize % 5]);
    }
    world.commit();
    let cam = Pinhole::look_at(Vec3::new(0.0, 2.0, 18.0), Vec3::ZERO, Vec3::Y, 50.0, 64, 48);
    let keep = |c: &Candidate| c.set % 4 != 1 && c.index % 5 != 2;
    let seen = world.scene.filtered(keep).mask(1 | 4);
    let mut hits = 0;
    for (x, y) in [(0, 0), (16, 16), (48, 32), (56, 40)] {
        let tile = cam.tile::<f32x8, 16, 16>(x, y);
        let got = seen.closest(&tile);
        let any = seen.any(&tile);
        for (dy, row) in got.iter().enumerate() {
            for (dx, h) in row.iter().enumerate() {
                let r = cam.row_packet::<f32>(x + dx as u32, y + dy as u32).ray(0);
                assert_eq!(
                    bits(*h),
                    bits(seen.closest(&r)),
                    "pixel {dx},{dy} of {x},{y}"
                );
                let want = world.brute(&r, 1 | 4, &keep);
                assert_eq!(
                    h.map(|h| (h.t, h.set, h.index)),
                    want.best.map(|h| (h.t, h.set, h.index))
                );
                assert_eq!(any[dy][dx], want.best.is_some());
                hits += usize::from(h.is_some());
            }
        }
    }
    assert!(hits > 100, "{hits}");
}

/// `&OwnedScene` is shared by threads for queries: the same answers as on one thread.
#[test]
fn shared_by_threads() {
    fn sync<T: Sync + Send>(_: &T) {}
    let mut rng = SmallRng::seed_from_u64(304);
    let mut world = new_world(&mut rng);
    for i in 0..100u32 {
        world.add(
            i % 3,
            place(&mut rng, 8.0),
            LAYERS[i as usize % LAYERS.len()],
        );
    }
    world.commit();
    sync(&world.scene);
    let rays = shots(&mut rng, &world, 400);
    let scene = &world.scene;
    let one: Vec<_> = rays
        .iter()
        .map(|r| bits(scene.filtered(|c| c.set != 7).mask(3).closest(r)))
        .collect();
    let threads: Vec<Vec<_>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|_| {
                s.spawn(|| {
                    rays.iter()
                        .map(|r| bits(scene.filtered(|c| c.set != 7).mask(3).closest(r)))
                        .collect()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for t in threads {
        assert_eq!(t, one);
    }
}

/// A filter that rejects the nearest hit of every ray: `closest` continues to the next one,
/// with packets whose other lanes shrink their `t_max` (the rejected candidate must not): the
/// answers are those of the scene without the rejected instance.
#[test]
fn rejected_hits_do_not_shrink_the_interval() {
    let mut scene = OwnedScene::new();
    let ball = scene.add_object(OwnedBvh::new(&[Sphere::new(Vec3::ZERO, 1.0)][..]).unwrap());
    let at = |z: f32| {
        [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, z],
        ]
    };
    let ids: Vec<InstanceId> = (0..8)
        .map(|k| scene.add(ball, at(-3.0 * k as f32), u32::MAX).unwrap())
        .collect();
    scene.commit();
    let rays: Vec<Ray> = (0..16)
        .map(|i| {
            Ray::new(
                Vec3::new(0.04 * i as f32, 0.02 * i as f32, 5.0),
                Vec3::NEG_Z,
            )
        })
        .collect();
    let skip = ids[0].slot();
    let q = scene.filtered(move |c| c.set != skip);
    let one: Vec<Option<Hit>> = rays.iter().map(|r| q.closest(r)).collect();
    let p = q.closest(&RayPacket::<f32x16>::from_rays(&rays));
    let p8 = q.closest(&RayPacket::<f32x8>::from_rays(&rays[3..11]));
    for (i, h) in one.iter().enumerate() {
        assert_eq!(bits(p.lane(i)), bits(*h), "ray {i}");
        if (3..11).contains(&i) {
            assert_eq!(bits(p8.lane(i - 3)), bits(*h), "ray {i}");
        }
        assert_eq!(scene.instance(h.unwrap().set), Some(ids[1]));
    }
    // Ignoring the instance: the same answers (and the instance is not traced).
    let ig = scene.ignoring(ids[0]);
    let pi = ig.closest(&RayPacket::<f32x16>::from_rays(&rays));
    let lanes: Vec<u32> = (0..16).map(|_| skip).collect();
    let pl = Filtered::new(&scene)
        .ignores(&lanes)
        .closest(&RayPacket::<f32x16>::from_rays(&rays));
    for (i, r) in rays.iter().enumerate() {
        assert_eq!(bits(ig.closest(r)), bits(one[i]), "ray {i}");
        assert_eq!(bits(pi.lane(i)), bits(one[i]), "ray {i}");
        assert_eq!(bits(pl.lane(i)), bits(one[i]), "ray {i}");
    }
    // The same answers as the scene without the rejected instance.
    scene.remove(ids[0]).unwrap();
    scene.commit();
    for (i, r) in rays.iter().enumerate() {
        assert_eq!(bits(scene.closest(r)), bits(one[i]), "ray {i}");
    }
}

/// Other kernels and culling (`with_kernels`): the default pair is the scene itself; Möller
/// with back faces culled equals brute force with the same kernel and culling, with masks,
/// ignored instances and filters, at every width.
#[test]
fn other_kernels_and_culling() {
    use raylane::Cull;
    use raylane::sphere::Robust;
    use raylane::triangle::{Moller, Watertight};
    let mut rng = SmallRng::seed_from_u64(306);
    let mut world = new_world(&mut rng);
    for i in 0..40u32 {
        world.add(
            i % 3,
            place(&mut rng, 8.0),
            LAYERS[i as usize % LAYERS.len()],
        );
    }
    world.commit();
    let rays = shots(&mut rng, &world, 150);
    let same = world.scene.with_kernels::<Watertight, Robust>();
    for r in &rays {
        assert_eq!(bits(same.closest(r)), bits(world.scene.closest(r)));
    }
    let moller = world
        .scene
        .with_kernels::<Moller, Robust>()
        .culled(Cull::Back);
    let mut hits = 0;
    for (name, f) in filters() {
        let f = &*f;
        let want: Vec<Want> = rays
            .iter()
            .enumerate()
            .map(|(i, r)| {
                world.brute_with(
                    r,
                    sight_of(i),
                    f,
                    &|t, l, g| t.using::<Moller>().culled(Cull::Back).all(l, g),
                    &|b, l, g| b.culled(Cull::Back).all(l, g),
                )
            })
            .collect();
        let got = check_against(
            &|m, i| Filtered::new(&moller).masks(m).ignores(i).filter(f),
            &rays,
            &want,
            &sight_of,
            false,
        );
        assert!(name == "nothing" || got > 5, "{name}: {got}");
        hits += got;
    }
    assert!(hits > 100, "{hits}");
}
