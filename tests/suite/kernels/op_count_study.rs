//! The operation-count study's table (issue 13): the library's counts
//! ([`raylane_lab::study::entries`]) with each method's accuracy per input class (from the vector
//! files, by [`raylane_lab::vectors::accuracy`]) and its leaks and double hits on the closed meshes
//! of the watertight harness. `examples/opcount.rs` includes this file to print the table;
//! the test pins the copy in `docs/opcounts.md`.

use raylane_lab::study::{self, Entry, Insns, Measured};
use raylane_lab::vectors::accuracy::{self, CLASSES};
use raylane_lab::vectors::{Case, Kind, Outcome};

use super::watertight_no_leaks as watertight;

/// The markers around the table in `docs/opcounts.md`.
pub const BEGIN: &str = "<!-- opstudy:begin -->\n";
/// The end marker.
pub const END: &str = "<!-- opstudy:end -->";

/// The instruction counts `scripts/count-study.sh` measured: `(target, shape, method, path)`
/// to instructions per test.
fn insns() -> Vec<(String, String, String, String, f64)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/study-insns.txt");
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(
                w.len(),
                5,
                "{path}: `target shape method path insns`, got {l:?}"
            );
            let n = w[4]
                .parse()
                .unwrap_or_else(|e| panic!("{path}: {l:?}: {e}"));
            (w[0].into(), w[1].into(), w[2].into(), w[3].into(), n)
        })
        .collect()
}

/// The table, measured now.
pub fn report() -> String {
    let insns = insns();
    let lookup = |target: &str, e: &Entry| -> Option<Insns> {
        let shape = e.shape.name();
        let get = |path: &str| {
            insns
                .iter()
                .find(|r| r.0 == target && r.1 == shape && r.2 == e.method && r.3 == path)
                .map(|r| r.4)
        };
        Some(Insns {
            miss: get("miss")?,
            hit: get("hit")?,
            precompute: get("precompute"),
        })
    };
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/vectors");
    let texts: Vec<String> = CLASSES
        .iter()
        .map(|c| {
            let path = format!("{dir}/{}.txt", c.file);
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
        })
        .collect();
    let mut cases = vec![Case::default(); 4096];
    let mut out = vec![Outcome::default(); 4096];
    let mut measured = |e: &Entry| {
        let kind: Kind = e.shape;
        let method = e.kernel.method();
        let mut m = Measured::default();
        let classes = CLASSES.iter().enumerate().filter(|(_, c)| c.kind == kind);
        for (slot, (k, c)) in m.accuracy.iter_mut().zip(classes) {
            let errors = accuracy::measure_text(method, 1, &texts[k], &mut cases, &mut out)
                .unwrap_or_else(|| panic!("{}: cannot be evaluated", c.file));
            *slot = Some((errors.t, errors.wrong));
        }
        m.watertight = watertight::methods()
            .find(|w| kind == Kind::Triangle && w.method().name() == e.method)
            .map(|w| {
                let t = watertight::totals(w);
                (t.rays, t.leaks, t.doubles)
            });
        m.x86 = lookup("x86-64-v3", e);
        m.m4f = lookup("cortex-m4f", e);
        m
    };
    let mut table = String::new();
    study::write_table(&mut table, &study::entries(), &mut measured)
        .expect("a String accepts any text");
    table
}

/// Where the copy of the table lies in `doc` (the text of `docs/opcounts.md`).
pub fn doc_section(doc: &str) -> (usize, usize) {
    let start = doc
        .find(BEGIN)
        .expect("docs/opcounts.md has the opstudy:begin marker")
        + BEGIN.len();
    let stop = doc[start..]
        .find(END)
        .expect("docs/opcounts.md has the opstudy:end marker")
        + start;
    (start, stop)
}

#[test]
fn docs_study_table_is_the_report() {
    let doc = include_str!("../../../docs/opcounts.md");
    let (start, stop) = doc_section(doc);
    assert_eq!(
        &doc[start..stop],
        report(),
        "regenerate the study table of docs/opcounts.md: `cargo run --example opcount -- --write`"
    );
}

#[test]
fn the_entries_are_the_registry_kernels_of_triangles_then_spheres() {
    use raylane_lab::registry::{Kernel, Prim};
    let kernels: Vec<Kernel> = [Prim::Triangle, Prim::Sphere]
        .into_iter()
        .flat_map(Kernel::of)
        .collect();
    assert_eq!(study::KERNELS.to_vec(), kernels);
    for (e, k) in study::entries().iter().zip(study::KERNELS) {
        assert_eq!(e.kernel, k);
        assert_eq!(
            (e.method, e.shape, e.source),
            (k.method().name(), k.prim(), k.source())
        );
    }
}

#[test]
fn the_timed_loops_hit_and_miss_as_announced() {
    use raylane_lab::registry::Kernel;
    use raylane_lab::study::{KERNELS, Path, Precompute, entries, precomputes, repeat, units};
    use wide::f32x8;
    for (k, e) in KERNELS.into_iter().zip(entries()) {
        let m = k.name();
        assert_eq!(repeat::<f32>(k, Path::Miss, 3), Some(0), "{m}");
        assert_eq!(repeat::<f32>(k, Path::Hit, 3), Some(3), "{m}");
        assert_eq!(repeat::<f32x8>(k, Path::Hit, 2), Some(16), "{m}");
        assert_eq!(precomputes(k), e.pre != Precompute::None, "{m}");
        let built = if precomputes(k) {
            2 * units::<f32x8>(k, Path::Precompute)
        } else {
            0
        };
        assert_eq!(
            repeat::<f32x8>(k, Path::Precompute, 2),
            Some(built as u32),
            "{m}"
        );
    }
    // The plane tests are not methods of the study.
    for k in [Kernel::Plane, Kernel::PlaneFocal] {
        assert!(!KERNELS.contains(&k) && !precomputes(k));
        for (path, _) in study::PATHS {
            assert_eq!(repeat::<f32>(k, path, 1), None, "{}", k.name());
        }
    }
}

#[test]
fn every_method_has_its_instruction_counts() {
    let insns = insns();
    for target in ["x86-64-v3", "cortex-m4f"] {
        for k in study::KERNELS {
            let (shape, method) = (k.prim().name(), k.method().name());
            for (path, name) in study::PATHS {
                let n = insns
                    .iter()
                    .filter(|r| r.0 == target && r.1 == shape && r.2 == method && r.3 == name)
                    .count();
                let want = usize::from(path != study::Path::Precompute || study::precomputes(k));
                assert_eq!(
                    n, want,
                    "{target} {shape} {method} {name} in docs/study-insns.txt"
                );
            }
        }
    }
}
