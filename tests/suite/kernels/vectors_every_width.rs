//! The shared test vectors, on the host: every method at every lane width passes every case
//! inside its documented limits, and every width returns the same bits (equal digests).

use raylane_lab::vectors::{self, Case, Digest, Kind, Method, Outcome, Verdict};

/// Every vector file: (stem, text).
pub(crate) const FILES: &[(&str, &str)] = &[
    (
        "sphere_lecture",
        include_str!("../../vectors/sphere_lecture.txt"),
    ),
    (
        "sphere_random",
        include_str!("../../vectors/sphere_random.txt"),
    ),
    ("sphere_far", include_str!("../../vectors/sphere_far.txt")),
    (
        "sphere_ground",
        include_str!("../../vectors/sphere_ground.txt"),
    ),
    (
        "sphere_special",
        include_str!("../../vectors/sphere_special.txt"),
    ),
    ("sphere_bad", include_str!("../../vectors/sphere_bad.txt")),
    (
        "plane_random",
        include_str!("../../vectors/plane_random.txt"),
    ),
    ("plane_bad", include_str!("../../vectors/plane_bad.txt")),
    (
        "triangle_random",
        include_str!("../../vectors/triangle_random.txt"),
    ),
    (
        "triangle_special",
        include_str!("../../vectors/triangle_special.txt"),
    ),
    (
        "triangle_bad",
        include_str!("../../vectors/triangle_bad.txt"),
    ),
    (
        "triangle_far",
        include_str!("../../vectors/triangle_far.txt"),
    ),
    (
        "triangle_needle",
        include_str!("../../vectors/triangle_needle.txt"),
    ),
    (
        "triangle_grazing",
        include_str!("../../vectors/triangle_grazing.txt"),
    ),
    (
        "triangle_offset",
        include_str!("../../vectors/triangle_offset.txt"),
    ),
    (
        "triangle_grid",
        include_str!("../../vectors/triangle_grid.txt"),
    ),
    (
        "sphere_grazing",
        include_str!("../../vectors/sphere_grazing.txt"),
    ),
    (
        "sphere_offset",
        include_str!("../../vectors/sphere_offset.txt"),
    ),
    ("sphere_tiny", include_str!("../../vectors/sphere_tiny.txt")),
    ("sphere_huge", include_str!("../../vectors/sphere_huge.txt")),
    (
        "plane_grazing",
        include_str!("../../vectors/plane_grazing.txt"),
    ),
    (
        "plane_offset",
        include_str!("../../vectors/plane_offset.txt"),
    ),
];

fn load(text: &str) -> Vec<Case> {
    vectors::cases(text)
        .map(|(line, r)| r.unwrap_or_else(|e| panic!("line {line}: {e:?}")))
        .collect()
}

/// (passed, failed, skipped) and the digest of one method at one width over one file.
fn run(m: Method, lanes: usize, cases: &[Case]) -> (usize, usize, usize, u64, Vec<String>) {
    let mut out = vec![Outcome::default(); cases.len()];
    assert!(vectors::evaluate(m, lanes, cases, &mut out));
    let mut d = Digest::new();
    let (mut p, mut f, mut s) = (0, 0, 0);
    let mut fails = Vec::new();
    for (c, o) in cases.iter().zip(&out) {
        d.update(o);
        match vectors::compare(m, c, o) {
            Verdict::Pass => p += 1,
            Verdict::Fail => {
                f += 1;
                fails.push(format!(
                    "line {}: expected {}, got {}",
                    c.line, c.expect, o.values
                ));
            }
            Verdict::Skip(_) => s += 1,
        }
    }
    (p, f, s, d.value(), fails)
}

#[test]
fn every_method_every_width_passes_inside_its_limits() {
    for (name, text) in FILES {
        let cases = load(text);
        for m in Method::ALL {
            let mut digests = Vec::new();
            for lanes in [1, 4, 8, 16] {
                let (p, f, s, d, fails) = run(m, lanes, &cases);
                assert_eq!(
                    f,
                    0,
                    "{name} {} x{lanes}: {p} passed, {f} failed, {s} skipped\n{}",
                    m.name(),
                    fails.join("\n")
                );
                digests.push(d);
            }
            assert!(
                digests.iter().all(|d| *d == digests[0]),
                "{name} {}: lane widths differ: {digests:x?}",
                m.name()
            );
        }
    }
}

/// The limits must not hide a method: each passes a minimum of the cases it applies to.
#[test]
fn limits_leave_enough_cases() {
    let count = |file: &str, m: Method| {
        let text = FILES.iter().find(|f| f.0 == file).unwrap().1;
        run(m, 8, &load(text)).0
    };
    // Focal: every unit-direction case of every sphere file, including c/r up to 2^20 and the
    // ground sphere, inside its limits and passing.
    assert_eq!(count("sphere_far", Method::Focal), 680);
    assert_eq!(count("sphere_ground", Method::Focal), 60);
    assert_eq!(count("sphere_bad", Method::Focal), load(FILES[5].1).len());
    // The others pass what their documented limits admit.
    assert!(count("sphere_random", Method::Quadratic) >= 250);
    assert!(count("sphere_random", Method::Robust) >= 280);
    assert!(count("sphere_far", Method::Robust) >= 400);
    assert!(count("sphere_random", Method::Geometric) >= 100);
    assert!(count("plane_random", Method::Plane) == count("plane_random", Method::Focal));
}

/// Where the textbook forms fail (outside their limits) the focal guard does not.
#[test]
fn far_spheres_separate_the_methods() {
    let cases = load(FILES[2].1);
    let wrong = |m: Method| {
        let mut out = vec![Outcome::default(); cases.len()];
        vectors::evaluate(m, 8, &cases, &mut out);
        cases
            .iter()
            .zip(&out)
            .filter(|(c, o)| c.kind == Kind::Sphere && !vectors::matches(c, &o.values))
            .count()
    };
    assert_eq!(wrong(Method::Focal), 0);
    assert!(
        wrong(Method::Quadratic) > 100,
        "the textbook quadratic should fail far rim cases"
    );
    assert!(wrong(Method::FocalUnguarded) > 100);
}
