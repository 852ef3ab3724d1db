//! The op-count table of `docs/opcounts.md` is the report's output (`cargo run --example opcount`,
//! `-- --write` rewrites it).

#[test]
fn docs_op_count_table_is_the_report() {
    let doc = include_str!("../../../docs/opcounts.md");
    let begin = "<!-- opcount:begin -->\n";
    let end = "<!-- opcount:end -->";
    let start = doc
        .find(begin)
        .expect("docs/opcounts.md has the opcount:begin marker")
        + begin.len();
    let stop = doc[start..]
        .find(end)
        .expect("docs/opcounts.md has the opcount:end marker")
        + start;
    let mut want = String::new();
    raylane_lab::opcount::write_report(&mut want, &raylane_lab::opcount::table(), false).unwrap();
    assert_eq!(
        &doc[start..stop],
        want,
        "regenerate the table in docs/opcounts.md with `cargo run --example opcount -- --write`"
    );
}
