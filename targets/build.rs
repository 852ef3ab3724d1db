//! Picks memory.x for the board of the target, and embeds every file of ../tests/vectors,
//! parsed here by raylane's own parser into a compact binary form (see `raylane_fw::Cases`).
use std::{env, fmt::Write as _, fs, path::PathBuf};

use raylane_lab::vectors::{self, Case, Kind};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    let target = env::var("TARGET").unwrap();
    let mem = match target.as_str() {
        "thumbv6m-none-eabi" => "memory/microbit.x", // Cortex-M0
        "thumbv7m-none-eabi" => "memory/mps2-an385.x", // Cortex-M3
        "thumbv7em-none-eabihf" => "memory/mps2-an386.x", // Cortex-M4F
        "thumbv8m.main-none-eabihf" => "memory/mps2-an505.x", // Cortex-M33
        "riscv32imac-unknown-none-elf" | "riscv32imafc-unknown-none-elf" => "memory/riscv-virt.x",
        t => panic!(
            "raylane-fw: no board for target {t}; use thumbv6m-none-eabi, thumbv7m-none-eabi, \
             thumbv7em-none-eabihf, thumbv8m.main-none-eabihf, riscv32imac-unknown-none-elf \
             or riscv32imafc-unknown-none-elf"
        ),
    };
    fs::copy(mem, out.join("memory.x")).unwrap();
    // The micro:bit's 256 KB of flash hold every vector and the scalar (x1) runner, not the
    // packet widths too: `vectors` runs x1 only there (`scalar_only`).
    println!("cargo::rustc-check-cfg=cfg(scalar_only)");
    if target == "thumbv6m-none-eabi" {
        println!("cargo::rustc-cfg=scalar_only");
    }
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
    // The Cortex-M0's flash holds the subset listed in m0-vectors.txt (test.sh compares the
    // board's digests with the host's over the same files).
    if target == "thumbv6m-none-eabi" {
        let list = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("m0-vectors.txt");
        println!("cargo:rerun-if-changed={}", list.display());
        let list = fs::read_to_string(&list).expect("targets/m0-vectors.txt");
        let keep: Vec<&str> = list
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .collect();
        files.retain(|p| keep.contains(&p.file_stem().unwrap().to_str().unwrap()));
    }
    let mut src = String::from(
        "/// Every vector file: (name, encoded cases), in name order.\n\
         pub static FILES: &[(&str, raylane_fw::Cases)] = &[\n",
    );
    for p in &files {
        println!("cargo:rerun-if-changed={}", p.display());
        let name = p.file_stem().unwrap().to_str().unwrap();
        let text = fs::read_to_string(p).unwrap();
        let mut buf = vec![Case::default(); 1 << 16];
        let n = vectors::load(&text, &mut buf)
            .unwrap_or_else(|(line, e)| panic!("{}:{line}: {e:?}", p.display()));
        let bin = out.join(format!("{name}.bin"));
        fs::write(&bin, encode(&buf[..n])).unwrap();
        writeln!(
            src,
            "    ({name:?}, raylane_fw::Cases(include_bytes!({:?}))),",
            bin.display().to_string()
        )
        .unwrap();
    }
    src.push_str("];\n");
    fs::write(out.join("files.rs"), src).unwrap();

    // The vendored bunny, baked for flash (the `bvh` binary links it with include_baked!).
    let bunny =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("../tests/data/bunny.bin");
    println!("cargo:rerun-if-changed={}", bunny.display());
    let (positions, indices) = load_bunny(&fs::read(&bunny).expect("tests/data/bunny.bin"));
    let mesh = raylane::mesh::Mesh::new(&positions, &indices);
    let baked = raylane::bvh::bake::bake(&mesh).expect("the bunny bakes");
    fs::write(out.join("bunny.rlbv"), baked).unwrap();
}

/// `tests/data/bunny.bin`: u32 vertex count, u32 triangle count, f32 x, y, z per vertex, u16
/// a, b, c per triangle, little-endian.
fn load_bunny(b: &[u8]) -> (Vec<raylane::glam::Vec3>, Vec<[u32; 3]>) {
    let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let f32_at = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let (nv, nt) = (u32_at(0) as usize, u32_at(4) as usize);
    let pos = (0..nv)
        .map(|i| {
            raylane::glam::Vec3::new(f32_at(8 + 12 * i), f32_at(12 + 12 * i), f32_at(16 + 12 * i))
        })
        .collect();
    let base = 8 + 12 * nv;
    let h = |o: usize| u32::from(u16::from_le_bytes(b[o..o + 2].try_into().unwrap()));
    let idx = (0..nt)
        .map(|i| [h(base + 6 * i), h(base + 6 * i + 2), h(base + 6 * i + 4)])
        .collect();
    (pos, idx)
}

/// Per case, little-endian: kind (u8: 0 sphere, 1 plane, 2 triangle), the number of expected
/// values (low nibble) and of their conditioning values (high nibble) (u8), line (u16), the
/// kind's inputs, the expected values, their conditioning (f32 bits).
fn encode(cases: &[Case]) -> Vec<u8> {
    let mut b = Vec::new();
    for c in cases {
        let kind = match c.kind {
            Kind::Sphere => 0u8,
            Kind::Plane => 1,
            Kind::Triangle => 2,
        };
        b.push(kind);
        // The low nibble counts the expected values, the high nibble their conditioning.
        b.push(c.expect.n | (c.cond.n << 4));
        b.extend_from_slice(&u16::try_from(c.line).expect("line < 65536").to_le_bytes());
        for x in &c.input[..c.kind.inputs()] {
            b.extend_from_slice(&x.to_bits().to_le_bytes());
        }
        for x in c.expect.as_slice().iter().chain(c.cond.as_slice()) {
            b.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    b
}
