//! Hit filters and layer masks (issue 30) on every set: a query through
//! [`Filtered`](raylane::set::Filtered) answers as brute force over every candidate of the
//! unfiltered set (`all`: every triangle hit, every root of a sphere) with the same filter,
//! under the tie rule `(t, set, index)`, bit for bit, for one ray and packets of 1, 4, 8 and
//! 16 lanes (each with its own mask), in flat slices, BVHs and tuples; `any` agrees and `all`
//! reports exactly the kept candidates. Also: the unfiltered `Filtered` is the set itself, a
//! lane whose mask is 0 sees nothing, and `closest` with a filter never loses a winner to the
//! kernels' relaxed pruning (a rejected near hit must not shrink `t_max`).

use crate::bvh::equals_brute_force::{centroids, owned, rays, soup, v3};
use crate::sets::query_records_every_width::bits;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bvh::Bvh;
use raylane::hit::Candidate;
use raylane::set::Filtered;
use raylane::sphere::Sphere;
use raylane::{Hit, Lane, Mask, Query, Ray, RayPacket};
use wide::{f32x4, f32x8, f32x16};

/// A candidate as a filter sees it, from the record `all` reports: for spheres `u` marks an
/// exit root (`front` false).
pub(crate) fn candidate(h: &Hit, sphere: bool) -> Candidate {
    Candidate {
        set: h.set,
        index: h.index,
        t: h.t,
        u: if sphere {
            f32::from(u8::from(!h.front))
        } else {
            h.u
        },
        v: h.v,
        lane: 0,
    }
}

/// Brute force over every hit `all` reports of `flat` (no filter): the kept candidates, and
/// the smallest of them by `(t, set, index)`.
pub(crate) fn brute(
    flat: &(impl Query + ?Sized),
    r: &Ray,
    sphere: bool,
    keep: &impl Fn(&Candidate) -> bool,
) -> (Vec<(u32, u32, u32)>, Option<Hit>) {
    let mut kept = Vec::new();
    let mut best: Option<Hit> = None;
    flat.all(r, |h| {
        if keep(&candidate(&h, sphere)) {
            kept.push((h.set, h.index, h.t.to_bits()));
            if best.is_none_or(|b| (h.t, h.set, h.index) < (b.t, b.set, b.index)) {
                best = Some(h);
            }
        }
    });
    kept.sort_unstable();
    (kept, best)
}

/// What brute force expects of one ray: the kept candidates `(set, index, t bits)`, sorted,
/// and the closest of them.
pub(crate) struct Want {
    pub kept: Vec<(u32, u32, u32)>,
    pub best: Option<Hit>,
}

/// A record's fields brute force fixes, bit for bit (the normal aside where it is made in
/// another space: world records of instances).
fn key(h: Option<Hit>) -> Option<[u32; 9]> {
    h.map(|h| {
        [
            h.t.to_bits(),
            h.set,
            h.index,
            h.u.to_bits(),
            h.v.to_bits(),
            u32::from(h.front),
            h.point.x.to_bits(),
            h.point.y.to_bits(),
            h.point.z.to_bits(),
        ]
    })
}

/// A query made for lanes with these masks and ignored sets.
pub(crate) type Make<'a, Q> = &'a dyn Fn(&[u32], &[u32]) -> Q;

/// `q` (a filtered query) against brute force over `flat` with `keep`, one ray at a time and
/// in packets of every width with each lane's mask and ignored set from `sight_of` (a lane
/// whose mask is 0 misses; sets without masks see every other mask; the ignored set's
/// candidates do not count). Returns the number of hits.
pub(crate) fn check<Q: Query>(
    make: Make<'_, Q>,
    flat: &(impl Query + ?Sized),
    rays: &[Ray],
    sphere: bool,
    keep: &impl Fn(&Candidate) -> bool,
    sight_of: &dyn Fn(usize) -> (u32, u32),
) -> usize {
    let want: Vec<Want> = rays
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let (mask, ignored) = sight_of(i);
            if mask == 0 {
                Want {
                    kept: Vec::new(),
                    best: None,
                }
            } else {
                let (kept, best) = brute(flat, r, sphere, &|c| c.set != ignored && keep(c));
                Want { kept, best }
            }
        })
        .collect();
    check_against(make, rays, &want, sight_of, true)
}

/// `q` against `want` (per ray, for its mask and ignored set `sight_of(i)`): one ray at a time (the record's
/// fields brute force fixes; with `normals` every bit), then packets of 1, 4, 8 and 16 lanes,
/// each lane with its own mask, equal to the one-ray records bit for bit; `any` and `all`
/// agree. Returns the number of hits.
pub(crate) fn check_against<Q: Query>(
    make: Make<'_, Q>,
    rays: &[Ray],
    want: &[Want],
    sight_of: &dyn Fn(usize) -> (u32, u32),
    normals: bool,
) -> usize {
    let mut hits = 0;
    let mut one = Vec::new();
    for (i, r) in rays.iter().enumerate() {
        let (mask, ignored) = sight_of(i);
        let q = make(&[mask], &[ignored]);
        let w = &want[i];
        hits += usize::from(w.best.is_some());
        let got = q.closest(r);
        assert_eq!(key(got), key(w.best), "ray {i}: {r:?}");
        if normals {
            assert_eq!(bits(got), bits(w.best), "ray {i}: {r:?}");
        } else if let Some(g) = got {
            assert!((g.normal.length() - 1.0).abs() < 1e-5 && g.normal.dot(r.dir()) <= 0.0);
        }
        assert_eq!(q.any(r), w.best.is_some(), "any, ray {i}: {r:?}");
        let mut all = Vec::new();
        q.all(r, |h| all.push((h.set, h.index, h.t.to_bits())));
        all.sort_unstable();
        assert_eq!(all, w.kept, "all, ray {i}: {r:?}");
        one.push(got);
    }
    packets::<f32, Q>(make, rays, want, &one, sight_of);
    packets::<f32x4, Q>(make, rays, want, &one, sight_of);
    packets::<f32x8, Q>(make, rays, want, &one, sight_of);
    packets::<f32x16, Q>(make, rays, want, &one, sight_of);
    hits
}

fn packets<L: Lane<Scalar = f32>, Q: Query>(
    make: Make<'_, Q>,
    rays: &[Ray],
    want: &[Want],
    one: &[Option<Hit>],
    sight_of: &dyn Fn(usize) -> (u32, u32),
) {
    for (c, chunk) in rays.chunks(L::LANES).enumerate() {
        let (masks, ignored): (Vec<u32>, Vec<u32>) =
            (0..chunk.len()).map(|i| sight_of(c * L::LANES + i)).unzip();
        let q = make(&masks, &ignored);
        let p = RayPacket::<L>::from_rays(chunk);
        let got = q.closest(&p);
        let any = q.any(&p);
        let mut all = vec![Vec::new(); L::LANES];
        q.all(&p, |h| {
            for (j, lane) in all.iter_mut().enumerate() {
                if let Some(h) = h.lane(j) {
                    lane.push((h.set, h.index, h.t.to_bits()));
                }
            }
        });
        for (j, r) in chunk.iter().enumerate() {
            let k = c * L::LANES + j;
            let w = &want[k];
            assert_eq!(
                bits(got.lane(j)),
                bits(one[k]),
                "{} lanes, ray {k}: {r:?}",
                L::LANES
            );
            assert_eq!(
                any.test(j),
                w.best.is_some(),
                "{} lanes, any, ray {k}",
                L::LANES
            );
            all[j].sort_unstable();
            assert_eq!(all[j], w.kept, "{} lanes, all, ray {k}", L::LANES);
        }
    }
}

/// Filters of every kind: glass (some primitives let rays through), a pseudo-random alpha
/// test per primitive, one-sided (barycentric cut-outs; spheres: exit roots only), near hits
/// ignored (`t` below a bound, a rejected near hit before an accepted far one).
/// A filter of the tests.
pub(crate) type Keep = Box<dyn Fn(&Candidate) -> bool>;

pub(crate) fn filters() -> Vec<(&'static str, Keep)> {
    vec![
        ("everything", Box::new(|_: &Candidate| true)),
        (
            "glass",
            Box::new(|c: &Candidate| !c.index.is_multiple_of(3)),
        ),
        (
            "alpha",
            Box::new(|c: &Candidate| {
                !(c.index.wrapping_mul(2_654_435_761) ^ c.set).is_multiple_of(5)
            }),
        ),
        ("cut-out", Box::new(|c: &Candidate| c.u < 0.4 || c.v > 0.2)),
        (
            "exit roots",
            Box::new(|c: &Candidate| c.u == 1.0 || c.v > 0.0),
        ),
        ("far", Box::new(|c: &Candidate| c.t > 0.98)),
        ("nothing", Box::new(|_: &Candidate| false)),
    ]
}

/// Lane masks (mostly all bits, some 0: nothing seen, some single layers) and ignored sets
/// (mostly none; sets 0, 1 and 3 sometimes).
pub(crate) fn sight_of(i: usize) -> (u32, u32) {
    let mask = [u32::MAX, 1, 0, 6, u32::MAX, 2][i % 6];
    let ignored = [u32::MAX, u32::MAX, 1, u32::MAX, 3, u32::MAX, u32::MAX, 0][i % 8];
    (mask, ignored)
}

#[test]
fn filtered_flat_sets_and_trees_equal_brute_force() {
    let mut rng = SmallRng::seed_from_u64(30);
    let tris = soup(&mut rng, 400);
    let rs = rays(&mut rng, 300, &centroids(&tris));
    let (nodes, leaves) = owned(&tris[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    for (name, f) in filters() {
        let f = &*f;
        let flat = check(
            &|m, i| Filtered::new(&tris[..]).masks(m).ignores(i).filter(f),
            &tris[..],
            &rs,
            false,
            &f,
            &sight_of,
        );
        let bvh = check(
            &|m, i| Filtered::new(&tree).masks(m).ignores(i).filter(f),
            &tris[..],
            &rs,
            false,
            &f,
            &sight_of,
        );
        assert_eq!(flat, bvh, "{name}");
        assert!(name == "nothing" || flat > 10, "{name}: {flat} hits");
    }
}

#[test]
fn filtered_spheres_see_exit_roots() {
    let mut rng = SmallRng::seed_from_u64(31);
    let spheres: Vec<Sphere> = (0..300)
        .map(|_| Sphere::new(v3(&mut rng, 1.0), rng.random_range(0.02..0.25)))
        .collect();
    let aim: Vec<_> = spheres.iter().map(|s| s.center()).collect();
    let rs = rays(&mut rng, 300, &aim);
    let (nodes, leaves) = owned(&spheres[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    for (name, f) in filters() {
        let f = &*f;
        let flat = check(
            &|m, i| Filtered::new(&spheres[..]).masks(m).ignores(i).filter(f),
            &spheres[..],
            &rs,
            true,
            &f,
            &sight_of,
        );
        let bvh = check(
            &|m, i| Filtered::new(&tree).masks(m).ignores(i).filter(f),
            &spheres[..],
            &rs,
            true,
            &f,
            &sight_of,
        );
        assert_eq!(flat, bvh, "{name}");
        assert!(name == "nothing" || flat > 10, "{name}: {flat} hits");
    }
    // Exit roots only: a ray through a lone sphere hits where it leaves it.
    let ball = [Sphere::new(glam::Vec3::new(0.0, 0.0, -5.0), 1.0)];
    let r = Ray::new(glam::Vec3::ZERO, glam::Vec3::NEG_Z);
    let exits = Filtered::new(&ball[..]).filter(|c| c.u == 1.0);
    let h = exits.closest(&r).unwrap();
    assert_eq!((h.t, h.front), (6.0, false));
    let p = exits.closest(&RayPacket::<f32x8>::splat(&r));
    assert_eq!(p.lane(7), Some(h));
}

/// Tuples: the filter sees each member's candidates with the member's `set`.
#[test]
fn filtered_tuples_equal_brute_force() {
    let mut rng = SmallRng::seed_from_u64(32);
    let tris = soup(&mut rng, 150);
    let spheres: Vec<Sphere> = (0..150)
        .map(|_| Sphere::new(v3(&mut rng, 1.0), rng.random_range(0.02..0.2)))
        .collect();
    let mut aim = centroids(&tris);
    aim.extend(spheres.iter().map(|s| s.center()));
    let rs = rays(&mut rng, 300, &aim);
    let scene = (&tris[..], &spheres[..]);
    // Set 1 (the spheres) is glass; every third triangle too.
    let keep = |c: &Candidate| c.set == 0 && !c.index.is_multiple_of(3);
    let hits = check(
        &|m, i| Filtered::new(&scene).masks(m).ignores(i).filter(keep),
        &scene,
        &rs,
        false,
        &keep,
        &sight_of,
    );
    assert!(hits > 20, "{hits}");
}

/// No mask, no filter: the set's own answers, bit for bit.
#[test]
fn unfiltered_is_the_set_itself() {
    let mut rng = SmallRng::seed_from_u64(33);
    let tris = soup(&mut rng, 200);
    let rs = rays(&mut rng, 200, &centroids(&tris));
    let (nodes, leaves) = owned(&tris[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let seen = Filtered::new(&tree);
    crate::bvh::equals_brute_force::check(&seen, &tree, &rs);
    let every_bit = Filtered::new(&tree).mask(u32::MAX);
    crate::bvh::equals_brute_force::check(&every_bit, &tree, &rs);
    let p = RayPacket::<f32x8>::from_rays(&rs[..8]);
    assert!(Filtered::new(&tree).mask(0).any(&p).none());
    assert!(Filtered::new(&tree).mask(0).closest(&p).mask.none());
}
