//! Every method's accuracy against the exact answers, per class of input, pinned.
//!
//! The measurement is `raylane_lab::vectors::accuracy` (one place): over the generated vector file
//! of each class, the largest relative `t` error and absolute `u`, `v` error of every method
//! against the exact answers, and the same over each case's recorded conditioning. The figures
//! are deterministic and bit-identical at every lane width and on every target (the digests
//! show it), so they are pinned exactly at their printed precision (two significant digits, or
//! two decimals for ratios below 10): no slack beyond the printing. After a kernel change,
//! `cargo run --release --example accuracy -- --write` rewrites the pin
//! (`tests/suite/kernels/accuracy_pinned.md`) and the tables between the `accuracy` markers of
//! `docs/accuracy.md`.

use raylane_lab::vectors::accuracy::{self, Class, Errors};
use raylane_lab::vectors::{Case, Method, Outcome};

fn text(c: &Class) -> &'static str {
    crate::kernels::vectors_every_width::FILES
        .iter()
        .find(|f| f.0 == c.file)
        .unwrap_or_else(|| panic!("no file for class {}", c.file))
        .1
}

fn errors(m: Method, c: &Class, lanes: usize) -> Errors {
    let mut cases = vec![Case::default(); 4096];
    let mut out = vec![Outcome::default(); 4096];
    accuracy::measure_text(m, lanes, text(c), &mut cases, &mut out)
        .unwrap_or_else(|| panic!("{}: cannot be read", c.file))
}

fn report(lanes: usize) -> String {
    let mut s = String::new();
    accuracy::write_report(&mut s, |m, c| errors(m, c, lanes)).unwrap();
    s
}

/// The measured tables (`cargo run --release --example accuracy`).
const PINNED: &str = include_str!("accuracy_pinned.md");

#[test]
fn every_class_has_a_file() {
    for c in &accuracy::CLASSES {
        text(c);
    }
}

#[test]
fn accuracy_is_the_same_at_every_width() {
    for c in &accuracy::CLASSES {
        for m in accuracy::methods(c.kind) {
            let one = errors(m, c, 1);
            for lanes in [4, 8, 16] {
                assert_eq!(errors(m, c, lanes), one, "{} {} x{lanes}", c.file, m.name());
            }
        }
    }
}

#[test]
fn accuracy_is_pinned() {
    let now = report(1);
    assert!(
        now == PINNED,
        "the measured accuracy changed; if that is intended, run `cargo run --release \
         --example accuracy -- --write` (it writes tests/suite/kernels/accuracy_pinned.md and the \
         tables of docs/accuracy.md). The new tables:\n{now}"
    );
}

#[test]
fn docs_accuracy_tables_are_the_report() {
    let doc = include_str!("../../../docs/accuracy.md");
    let begin = "<!-- accuracy:begin -->\n";
    let end = "<!-- accuracy:end -->";
    let start = doc
        .find(begin)
        .expect("docs/accuracy.md has the accuracy:begin marker")
        + begin.len();
    let stop = doc[start..]
        .find(end)
        .expect("docs/accuracy.md has the accuracy:end marker")
        + start;
    assert_eq!(
        &doc[start..stop],
        PINNED,
        "the tables of docs/accuracy.md differ from tests/suite/kernels/accuracy_pinned.md"
    );
}

/// The kernel tables (README.md, docs/accuracy.md): `robust`, the sphere `focal` and the plane
/// are within their conditioning on every class; the textbook sphere forms are 10 to 1000× off
/// somewhere and get hit/miss wrong on far spheres; `cramer` and `moller` lose `t` on needles.
#[test]
fn kernel_table_claims_hold() {
    use raylane_lab::vectors::Kind;
    let worst = |m: Method, kind: Kind, f: fn(&Errors) -> f64| {
        accuracy::CLASSES
            .iter()
            .filter(|c| c.kind == kind)
            .map(|c| f(&errors(m, c, 8)))
            .fold(0.0f64, f64::max)
    };
    for (m, kind) in [
        (Method::Robust, Kind::Sphere),
        (Method::Focal, Kind::Sphere),
        (Method::Plane, Kind::Plane),
        (Method::Focal, Kind::Plane),
    ] {
        assert!(worst(m, kind, |e| e.t_cond) <= 1.0, "{}", m.name());
        assert_eq!(worst(m, kind, |e| e.wrong as f64), 0.0, "{}", m.name());
    }
    for m in [Method::Quadratic, Method::QuadraticUnit, Method::Geometric] {
        let r = worst(m, Kind::Sphere, |e| e.t_cond);
        assert!((10.0..=10_000.0).contains(&r), "{}: {r}", m.name());
        assert!(
            worst(m, Kind::Sphere, |e| e.wrong as f64) > 0.0,
            "{}",
            m.name()
        );
    }
    let needle = accuracy::CLASSES
        .iter()
        .find(|c| c.file == "triangle_needle")
        .unwrap();
    for m in [Method::Cramer, Method::Moller] {
        let e = errors(m, needle, 8);
        assert!(e.t_cond > 100.0 && e.t <= 2.0 * 1e4 / 16_777_216.0, "{e:?}");
    }
}

/// Issue 10, item 1: on every triangle class the focal path's largest `t` error and `u`, `v`
/// error are at most 2× Möller–Trumbore's, it gets no hit/miss wrong, and wherever a 2-ulp move
/// of the inputs changes `t` by less than 2^-18 (relative) its `t` is within 2^-16.
#[test]
fn focal_triangles_as_accurate_as_moller() {
    use raylane_lab::vectors::{self, Kind};
    let mut bad = Vec::new();
    for c in accuracy::CLASSES
        .iter()
        .filter(|c| c.kind == Kind::Triangle)
    {
        let (f, m) = (errors(Method::Focal, c, 8), errors(Method::Moller, c, 8));
        if f.wrong > 0 || f.t > 2.0 * m.t || f.uv > 2.0 * m.uv {
            bad.push(format!(
                "{}: focal t {:.1e} u,v {:.1e} ({} wrong); moller t {:.1e} u,v {:.1e}",
                c.file, f.t, f.uv, f.wrong, m.t, m.uv
            ));
        }
        let mut cases = vec![Case::default(); 4096];
        let n = vectors::load(text(c), &mut cases).unwrap();
        let cases = &cases[..n];
        let mut out = vec![Outcome::default(); n];
        assert!(vectors::evaluate(Method::Focal, 8, cases, &mut out));
        for (k, o) in cases.iter().zip(&out) {
            let well = k.cond.n == 3 && (k.cond.v[0] as f64) < 1.0 / 262_144.0;
            if well && o.values.n == 3 {
                let (e, g) = (k.expect.v[0] as f64, o.values.v[0] as f64);
                if (e - g).abs() > e.abs() / 65_536.0 {
                    bad.push(format!("{}:{}: t {g}, exact {e}", c.file, k.line));
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{} failures:\n{}",
        bad.len(),
        bad.join("\n")
    );
}
