//! The README's op-count table is the report's output (`cargo run --example opcount`).

#[test]
fn readme_op_count_table_is_the_report() {
    let readme = include_str!("../../README.md");
    let begin = "<!-- opcount:begin -->\n";
    let end = "<!-- opcount:end -->";
    let start = readme
        .find(begin)
        .expect("README has the opcount:begin marker")
        + begin.len();
    let stop = readme[start..]
        .find(end)
        .expect("README has the opcount:end marker")
        + start;
    let mut want = String::new();
    raylane_lab::opcount::write_report(&mut want, &raylane_lab::opcount::table(), false).unwrap();
    assert_eq!(
        &readme[start..stop],
        want,
        "regenerate the README table with `cargo run --example opcount`"
    );
}
