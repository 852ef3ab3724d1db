//! Picks memory.x for the board of the target, and embeds every file of ../tests/vectors.
use std::{env, fmt::Write as _, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    let target = env::var("TARGET").unwrap();
    let mem = match target.as_str() {
        "thumbv7em-none-eabihf" => "memory/mps2-an386.x", // Cortex-M4F
        "thumbv8m.main-none-eabihf" => "memory/mps2-an505.x", // Cortex-M33
        t => panic!(
            "raylane-fw: no board for target {t}; use thumbv7em-none-eabihf or thumbv8m.main-none-eabihf"
        ),
    };
    fs::copy(mem, out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={mem}");
    println!("cargo:rerun-if-changed=build.rs");

    // Every vector file, in name order (the host's digest example uses the same order).
    let dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("../tests/vectors");
    let dir = dir.canonicalize().expect("tests/vectors exists");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut files: Vec<_> = fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    files.sort();
    let mut src = String::from(
        "/// Every vector file: (name, text), in name order.\npub static FILES: &[(&str, &str)] = &[\n",
    );
    for p in &files {
        println!("cargo:rerun-if-changed={}", p.display());
        let name = p.file_stem().unwrap().to_str().unwrap();
        writeln!(
            src,
            "    ({name:?}, include_str!({:?})),",
            p.display().to_string()
        )
        .unwrap();
    }
    src.push_str("];\n");
    fs::write(out.join("files.rs"), src).unwrap();
}
