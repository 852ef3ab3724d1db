//! The operation counts are measured by the counting lane, and pinned here.

use raylane::opcount::OpCounts;
use raylane_lab::opcount::table;

fn get(kernel: &str, path: &str) -> OpCounts {
    table()
        .iter()
        .find(|r| r.kernel == kernel && r.path == path)
        .unwrap_or_else(|| panic!("no row {kernel}/{path}"))
        .counts
}

/// `OpCounts::new(mul, add, div, sqrt, cmp)`.
const fn c(mul: u32, add: u32, div: u32, sqrt: u32, cmp: u32) -> OpCounts {
    OpCounts::new(mul, add, div, sqrt, cmp)
}

#[test]
fn brute_force_quadratic_matches_the_lecture() {
    // Lecture 000: "8 multiplies/squares, 9 additions/subtractions, 1 square root" for the
    // discriminant μ² − T·T + r² and its root, with unit direction; the two roots μ ± √δ add
    // the 2 additions the lecture's tally leaves out.
    let miss = get("quadratic-unit", "miss");
    let hit = get("quadratic-unit", "hit");
    assert_eq!(miss, c(8, 9, 0, 0, 1));
    // The hit adds the two roots' interval compares (4) and the range guard (3: r² in
    // [2^-60, 2^60], T·T ≤ 2^60), which sends lanes outside f32's safe range to f64.
    assert_eq!(hit, c(8, 11, 0, 1, 1 + 4 + 3));
    assert_eq!((hit.mul, hit.add - 2, hit.sqrt), (8, 9, 1));
    // "The point adds 3 multiplies and 3 additions."
    assert_eq!(get("sphere-point", "hit"), c(3, 3, 0, 0, 0));
}

#[test]
fn geometric_miss_is_v_plus_the_test() {
    // v = T·U: 3 mul, 2 add; the test r² ≥ c² − v²: 1 mul, 1 sub, 1 compare.
    assert_eq!(get("geometric-prepared", "miss"), c(3 + 1, 2 + 1, 0, 0, 1));
    // The hit adds the half chord (1 sub, 1 sqrt), the two roots v ∓ d (2 add), their
    // interval compares (4) and the range guard (3 cmp).
    assert_eq!(get("geometric-prepared", "hit"), c(4, 6, 0, 1, 1 + 4 + 3));
    // Unprepared, T = C − E (3 add), c² (3 mul, 2 add) and r² (1 mul) come first.
    assert_eq!(get("geometric", "miss"), c(8, 8, 0, 0, 1));
}

#[test]
fn focal_miss_within_four_mul_two_add() {
    let miss = get("focal", "miss");
    assert!(miss.mul <= 4 && miss.add <= 2, "{miss}");
    assert_eq!(miss, c(4, 2, 0, 0, 1));
    // The guard costs nothing on the miss path: the unguarded test is the same.
    assert_eq!(get("focal-unguarded", "miss"), miss);
    // A certain hit: perpendicular form (6 mul, 5 add), half chord (1 add, 1 sqrt), roots.
    assert_eq!(get("focal", "hit"), c(10, 10, 0, 1, 9));
    assert_eq!(get("focal-unguarded", "hit"), c(4, 5, 0, 1, 5));
}

#[test]
fn every_other_count_is_pinned() {
    let want = [
        ("quadratic", "miss", c(12, 11, 0, 0, 1)),
        // Hits: + 4 interval compares + the range guard (5 cmp with a = d·d, 3 without).
        ("quadratic", "hit", c(12, 13, 2, 1, 1 + 4 + 5)),
        ("geometric", "hit", c(8, 11, 0, 1, 1 + 4 + 3)),
        ("robust", "miss", c(14, 13, 1, 0, 1)),
        // The sign, 4 interval compares, the ascending order (1) and the range guard (5).
        ("robust", "hit", c(17, 17, 3, 1, 1 + 1 + 4 + 1 + 5)),
        // The f64 Robust of a doubtful lane includes its order compare (no range guard).
        ("focal", "doubtful", c(27, 27, 3, 2, 16)),
        // The normal's range check (2 cmp) sends points within 2^-50 or beyond 2^50 of the
        // centre to f64.
        ("sphere-surface", "hit", c(9, 10, 3, 1, 2)),
        // The line test (2 cmp) and the direction range (2 cmp).
        ("bound", "per mesh", c(17, 16, 1, 0, 4)),
        ("plane", "miss", c(6, 7, 1, 0, 2)),
        ("plane", "hit", c(6, 7, 1, 0, 2)),
        ("plane-focal", "miss", c(3, 2, 1, 0, 2)),
        ("plane-focal", "hit", c(3, 2, 1, 0, 2)),
    ];
    for (k, p, n) in want {
        assert_eq!(get(k, p), n, "{k}/{p}");
    }
}

#[test]
fn a_panicking_measurement_releases_the_lock() {
    use raylane::opcount::{Counted, measure};
    use std::sync::mpsc;
    use std::time::Duration;

    let panicked = std::panic::catch_unwind(|| {
        measure(|| {
            let _ = Counted(1.0f32) + Counted(2.0);
            panic!("a measured closure panics");
        })
    });
    assert!(panicked.is_err());
    // A later measurement (on another thread, so that a lock left taken fails the test
    // instead of hanging it) gets the lock and counts.
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let ((), c) = measure(|| {
            let _ = Counted(1.0f32) * Counted(2.0);
        });
        let _ = tx.send(c);
    });
    let c = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("the lock was released by the panicking measurement");
    assert_eq!(c.mul, 1);
}

#[test]
fn published_methods_counts_are_pinned() {
    use raylane_lab::study::{Precompute, entries};
    let get = |m: &str, shape: raylane_lab::study::Shape| {
        entries()
            .into_iter()
            .find(|e| e.method == m && e.shape == shape)
            .unwrap_or_else(|| panic!("no study entry {m}"))
    };
    let tri = raylane_lab::study::Shape::Triangle;
    // (method, miss, hit, behind, precomputation)
    let want = [
        (
            "badouel",
            c(14, 17, 3, 0, 6),
            c(14, 17, 3, 0, 6),
            c(6, 5, 1, 0, 2),
            Some(c(9, 11, 0, 0, 3)),
        ),
        (
            "plucker",
            c(28, 44, 0, 0, 6),
            c(41, 53, 1, 0, 20),
            c(40, 53, 0, 0, 15),
            None,
        ),
        (
            "wald",
            c(11, 12, 1, 0, 5),
            c(11, 12, 1, 0, 5),
            c(5, 5, 1, 0, 2),
            Some(c(20, 13, 1, 0, 4)),
        ),
        (
            "havel-herout",
            c(20, 16, 0, 0, 5),
            c(21, 16, 1, 0, 12),
            c(20, 16, 0, 0, 7),
            Some(c(36, 23, 1, 0, 0)),
        ),
        (
            "kensler-shirley",
            c(23, 22, 1, 0, 3),
            c(27, 24, 1, 0, 5),
            c(27, 24, 1, 0, 5),
            None,
        ),
        (
            "baldwin-weber",
            c(15, 15, 1, 0, 5),
            c(15, 15, 1, 0, 5),
            c(6, 5, 1, 0, 2),
            Some(c(22, 15, 1, 0, 3)),
        ),
    ];
    for (m, miss, hit, behind, pre) in want {
        let e = get(m, tri);
        assert_eq!((e.miss, e.hit, e.behind), (miss, hit, Some(behind)), "{m}");
        let got = match e.pre {
            Precompute::Counted(p) => Some(p),
            _ => None,
        };
        assert_eq!(got, pre, "{m} precomputation");
    }
    let ball = raylane_lab::study::Shape::Sphere;
    let pbrt = get("pbrt", ball);
    assert_eq!(
        (pbrt.miss, pbrt.hit),
        (c(21, 17, 1, 1, 1), c(22, 18, 3, 2, 7))
    );
    let embree = get("embree", ball);
    assert_eq!(
        (embree.miss, embree.hit),
        (c(14, 12, 1, 0, 1), c(15, 15, 1, 1, 5))
    );
    // The claim of the README: focal needs the fewest flops per triangle miss, and no more
    // than any other per hit (Wald's test ties it there); Wald's plane-first test beats it on
    // a triangle behind the origin.
    let focal = get("focal", tri);
    for e in entries()
        .iter()
        .filter(|e| e.shape == tri && e.method != "focal")
    {
        assert!(focal.miss.flops() < e.miss.flops(), "{} miss", e.method);
        assert!(focal.hit.flops() <= e.hit.flops(), "{} hit", e.method);
    }
    assert_eq!(focal.hit.flops(), get("wald", tri).hit.flops());
    let wald = get("wald", tri);
    assert!(wald.behind.unwrap().flops() < focal.behind.unwrap().flops());
}

#[test]
fn every_registry_kernel_is_in_the_report() {
    use raylane_lab::registry::Kernel;
    let t = table();
    assert!(
        t.len() < raylane_lab::opcount::MAX_ROWS,
        "the report may be truncated"
    );
    for k in Kernel::ALL {
        assert!(
            t.iter().any(|r| r.kernel == k.name() && r.path == "miss"),
            "{} has no miss row",
            k.name()
        );
        assert!(
            t.iter().any(|r| r.kernel == k.name() && r.path == "hit"),
            "{} has no hit row",
            k.name()
        );
    }
}
