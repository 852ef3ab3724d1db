//! README.md's "In firmware" section quotes the example crate as it is: every Rust and TOML
//! code block of the section is a contiguous run of lines of a file of `examples/firmware/`
//! (the same lines in the same order; a block may drop an indentation the file's lines share),
//! so the section cannot drift from the crate that `scripts/test.sh` builds and runs.

use std::path::{Path, PathBuf};

/// The section's fenced blocks: (info string, lines).
fn blocks(readme: &str) -> Vec<(String, Vec<String>)> {
    let start = readme
        .find("\n## In firmware\n")
        .expect("README.md has a \"## In firmware\" section");
    let rest = &readme[start + 1..];
    let section = match rest[3..].find("\n## ") {
        Some(end) => &rest[..end + 3],
        None => rest,
    };
    let mut out = Vec::new();
    let mut open: Option<(String, Vec<String>)> = None;
    for line in section.lines() {
        match (line.strip_prefix("```"), open.take()) {
            (Some(info), None) => open = Some((info.trim().to_string(), Vec::new())),
            (Some(_), Some(block)) => out.push(block),
            (None, Some((info, mut lines))) => {
                lines.push(line.trim_end().to_string());
                open = Some((info, lines));
            }
            (None, None) => {}
        }
    }
    assert!(
        open.is_none(),
        "README.md: a code block of the section is not closed"
    );
    out
}

/// Every file of the example crate but its build output.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let p = e.unwrap().path();
        if p.is_dir() {
            if p.file_name().is_none_or(|n| n != "target") {
                files(&p, out);
            }
        } else {
            out.push(p);
        }
    }
}

/// Whether `block` is a run of `file`'s lines, each with the same indentation prepended (blank
/// lines blank in both).
fn quotes(file: &[&str], block: &[String]) -> bool {
    let first = block.first().expect("an empty code block");
    (0..file.len()).any(|at| {
        let Some(indent) = file[at].trim_end().strip_suffix(first.as_str()) else {
            return false;
        };
        if !indent.chars().all(|c| c == ' ') || at + block.len() > file.len() {
            return false;
        }
        block.iter().zip(&file[at..]).all(|(b, f)| {
            let f = f.trim_end();
            if b.is_empty() {
                f.is_empty()
            } else {
                f.strip_prefix(indent) == Some(b.as_str())
            }
        })
    })
}

#[test]
fn readme_firmware_section_quotes_the_example_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let mut paths = Vec::new();
    files(&root.join("examples/firmware"), &mut paths);
    paths.sort();
    let texts: Vec<(PathBuf, String)> = paths
        .into_iter()
        .filter_map(|p| Some((p.clone(), std::fs::read_to_string(&p).ok()?)))
        .collect();
    let mut checked = Vec::new();
    for (info, block) in blocks(&readme) {
        let lang = info.split(',').next().unwrap_or("");
        if lang != "rust" && lang != "toml" {
            continue;
        }
        let found = texts.iter().find(|(_, text)| {
            let lines: Vec<&str> = text.lines().collect();
            quotes(&lines, &block)
        });
        let Some((path, _)) = found else {
            panic!(
                "README.md's \"In firmware\" block ```{info} is not in examples/firmware/ as \
                 written:\n{}",
                block.join("\n")
            );
        };
        checked.push(path.strip_prefix(root).unwrap().display().to_string());
    }
    // The dependencies, the bake (build.rs) and the link and trace (src/main.rs) at least.
    for want in ["Cargo.toml", "build.rs", "main.rs"] {
        assert!(
            checked.iter().any(|c| c.ends_with(want)),
            "no block of README.md's \"In firmware\" quotes examples/firmware's {want} \
             (quoted: {checked:?})"
        );
    }
}
