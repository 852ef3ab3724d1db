//! Docs that cannot drift: every operation count a doc comment quotes as a marker
//! `` `ops KERNEL/PATH: 4 mul, 2 add, 1 cmp` `` (omitted kinds are zero) equals the pinned
//! report's row (`raylane_lab::opcount::table`), and every kernel of the registry quotes its miss
//! and its hit that way (in `lab/src/registry.rs`, beside its row).

use std::path::Path;

use raylane::opcount::OpCounts;
use raylane_lab::opcount::table;
use raylane_lab::registry::Kernel;

/// One marker: where it is, the row it names and the counts it quotes.
#[derive(Debug)]
struct Marker {
    at: String,
    kernel: String,
    path: String,
    counts: Result<OpCounts, String>,
}

/// Parses `4 mul, 2 add, 1 cmp` (any order, omitted kinds zero).
fn counts(text: &str) -> Result<OpCounts, String> {
    let mut c = OpCounts::default();
    for part in text.split(',') {
        let mut w = part.split_whitespace();
        let (Some(n), Some(kind), None) = (w.next(), w.next(), w.next()) else {
            return Err(format!("bad count {part:?}"));
        };
        let n: u32 = n.parse().map_err(|_| format!("bad number {n:?}"))?;
        let slot = match kind {
            "mul" => &mut c.mul,
            "add" => &mut c.add,
            "div" => &mut c.div,
            "sqrt" => &mut c.sqrt,
            "cmp" => &mut c.cmp,
            _ => return Err(format!("unknown operation {kind:?}")),
        };
        *slot += n;
    }
    Ok(c)
}

/// Every marker in the doc comments (`///`, `//!`) of the `.rs` files under `dir`.
fn markers(dir: &Path, out: &mut Vec<Marker>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            markers(&p, out);
            continue;
        }
        if p.extension().is_none_or(|x| x != "rs") {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        for (i, line) in text.lines().enumerate() {
            let l = line.trim_start();
            if !(l.starts_with("///") || l.starts_with("//!")) {
                continue;
            }
            for piece in l.split("`ops ").skip(1) {
                let at = format!("{}:{}", p.display(), i + 1);
                let Some((body, _)) = piece.split_once('`') else {
                    out.push(Marker {
                        at,
                        kernel: String::new(),
                        path: String::new(),
                        counts: Err("marker not closed on its line".into()),
                    });
                    continue;
                };
                let (name, c) = body.split_once(':').unwrap_or((body, ""));
                let (kernel, path) = name.split_once('/').unwrap_or((name, ""));
                out.push(Marker {
                    at,
                    kernel: kernel.trim().to_string(),
                    path: path.trim().to_string(),
                    counts: counts(c),
                });
            }
        }
    }
}

#[test]
fn doc_op_counts_equal_the_pinned_table() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    markers(&root.join("src"), &mut found);
    markers(&root.join("lab/src"), &mut found);
    let rows = table();
    let mut wrong = Vec::new();
    for m in &found {
        let row = rows
            .iter()
            .find(|r| r.kernel == m.kernel && r.path == m.path);
        match (&m.counts, row) {
            (Err(e), _) => wrong.push(format!("{}: {e}", m.at)),
            (_, None) => wrong.push(format!("{}: no row {}/{}", m.at, m.kernel, m.path)),
            (Ok(c), Some(r)) if *c != r.counts => wrong.push(format!(
                "{}: {}/{} quotes {c}, the table has {}",
                m.at, m.kernel, m.path, r.counts
            )),
            _ => {}
        }
    }
    assert!(
        wrong.is_empty(),
        "doc op counts differ:\n{}",
        wrong.join("\n")
    );
    // Every kernel quotes its miss and its hit.
    for k in Kernel::ALL {
        for path in ["miss", "hit"] {
            assert!(
                found.iter().any(|m| m.kernel == k.name() && m.path == path),
                "no `ops {}/{path}: …` marker in the docs",
                k.name()
            );
        }
    }
    assert!(found.len() >= 2 * Kernel::ALL.len());
}

#[test]
fn marker_counts_parse() {
    assert_eq!(
        counts("4 mul, 2 add, 1 cmp"),
        Ok(OpCounts::new(4, 2, 0, 0, 1))
    );
    assert!(counts("4 mul, 2 adds").is_err());
    assert!(counts("four mul").is_err());
}
