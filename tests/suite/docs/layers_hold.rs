//! ARCHITECTURE.md's layers hold: no module of `src/` names a module of a higher layer, and
//! the modules of one layer import each other without a circle. Read from the `crate::` paths
//! of every source file (its unit tests, after `#[cfg(test)]`, excepted).

use std::collections::BTreeMap;
use std::path::Path;

/// The layers, lowest first, as ARCHITECTURE.md draws them.
const LAYERS: [&[&str]; 6] = [
    &["lane", "opcount", "simd"],
    &["vec3", "ray", "camera"],
    &["kernel", "sphere", "plane", "triangle", "bounds"],
    &["hit"],
    &["set", "mesh", "focal", "bvh"],
    &["query"],
];

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// The top-level modules each file under `src/` names through `crate::` (lib.rs excepted).
fn imports() -> BTreeMap<String, Vec<(String, String)>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let rel = p
                .strip_prefix(&src)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            if rel == "lib.rs" || !rel.ends_with(".rs") {
                continue;
            }
            let module = rel.split(['/', '.']).next().unwrap().to_string();
            let text = std::fs::read_to_string(&p).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap();
            for line in code.lines() {
                let l = line.trim_start();
                if l.starts_with("//") {
                    continue;
                }
                let mut rest = l;
                while let Some(i) = rest.find("crate::") {
                    rest = &rest[i + 7..];
                    let name: String = rest
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .collect();
                    if !name.is_empty() && name != module && layer(&name).is_some() {
                        out.entry(module.clone())
                            .or_default()
                            .push((name, rel.clone()));
                    }
                }
            }
        }
    }
    out
}

#[test]
fn every_module_has_a_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for e in std::fs::read_dir(src).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().replace(".rs", "");
        assert!(
            name == "lib" || layer(&name).is_some(),
            "src/{name} has no layer in ARCHITECTURE.md (tests/suite/docs/layers_hold.rs)"
        );
    }
}

#[test]
fn no_module_imports_from_a_layer_above_it() {
    // The reading sees the imports (the BVH asks the collectors, queries ask the sets).
    let all = imports();
    let names = |m: &str| all.get(m).into_iter().flatten().map(|(n, _)| n.as_str());
    assert!(names("bvh").any(|n| n == "hit") && names("query").any(|n| n == "set"));
    let mut wrong = Vec::new();
    for (module, names) in imports() {
        let own = layer(&module).unwrap();
        for (name, file) in names {
            if layer(&name).unwrap() > own {
                wrong.push(format!(
                    "src/{file} ({module}, layer {own}) names crate::{name}"
                ));
            }
        }
    }
    wrong.sort();
    wrong.dedup();
    assert!(
        wrong.is_empty(),
        "imports that run up:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn no_circles_within_a_layer() {
    let edges: BTreeMap<String, Vec<String>> = imports()
        .into_iter()
        .map(|(m, names)| {
            let own = layer(&m);
            let mut to: Vec<String> = names
                .into_iter()
                .map(|(n, _)| n)
                .filter(|n| layer(n) == own)
                .collect();
            to.sort();
            to.dedup();
            (m, to)
        })
        .collect();
    // Depth-first search for a back edge.
    fn visit(
        m: &str,
        edges: &BTreeMap<String, Vec<String>>,
        path: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == m) {
            let mut circle = path[i..].to_vec();
            circle.push(m.to_string());
            return Some(circle);
        }
        if done.iter().any(|d| d == m) {
            return None;
        }
        path.push(m.to_string());
        for n in edges.get(m).into_iter().flatten() {
            if let Some(c) = visit(n, edges, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.push(m.to_string());
        None
    }
    let mut done = Vec::new();
    for m in edges.keys() {
        if let Some(c) = visit(m, &edges, &mut Vec::new(), &mut done) {
            panic!("a circle of imports: {}", c.join(" -> "));
        }
    }
}
