//! The operation-count study's table (issue 13): the library's counts
//! ([`raylane::study::entries`]) with each method's accuracy per input class (from the vector
//! files, by [`raylane::vectors::accuracy`]) and its leaks and double hits on the closed meshes
//! of the watertight harness. `examples/opcount.rs` includes this file to print the table;
//! the test pins the README's copy.

use raylane::study::{self, Entry, Measured, Shape};
use raylane::vectors::accuracy::{self, CLASSES};
use raylane::vectors::{Case, Kind, Method, Outcome};

use crate::watertight;

/// The README's markers around the table.
pub const BEGIN: &str = "<!-- opstudy:begin -->\n";
/// The end marker.
pub const END: &str = "<!-- opstudy:end -->";

/// The table, measured now.
pub fn report() -> String {
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
        let kind = match e.shape {
            Shape::Triangle => Kind::Triangle,
            Shape::Sphere => Kind::Sphere,
        };
        let method = Method::from_name(e.method).expect("every study method is in the checker");
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
        m
    };
    let mut table = String::new();
    study::write_table(&mut table, &study::entries(), &mut measured)
        .expect("a String accepts any text");
    table
}

/// The README's copy of the table.
pub fn readme_section(readme: &str) -> (usize, usize) {
    let start = readme
        .find(BEGIN)
        .expect("README has the opstudy:begin marker")
        + BEGIN.len();
    let stop = readme[start..]
        .find(END)
        .expect("README has the opstudy:end marker")
        + start;
    (start, stop)
}

#[test]
fn readme_study_table_is_the_report() {
    let readme = include_str!("../../README.md");
    let (start, stop) = readme_section(readme);
    assert_eq!(
        &readme[start..stop],
        report(),
        "regenerate the README's study table with `cargo run --example opcount -- --write`"
    );
}
