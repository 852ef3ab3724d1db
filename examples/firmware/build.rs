//! Runs on the host before the firmware compiles: bakes `mesh.obj` into `OUT_DIR/mesh.rlbv`
//! (`src/main.rs` links it) and picks the board's `memory.x` for cortex-m-rt's `link.x`.
use std::{env, fs, path::PathBuf};

use raylane::bvh::bake::bake;
use raylane::glam::Vec3;
use raylane::mesh::Mesh;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());

    // The mesh: the `v x y z` and `f a b c` lines of a Wavefront OBJ (indices from 1).
    let obj = fs::read_to_string("mesh.obj").unwrap();
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for line in obj.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let [x, y, z] = [(); 3].map(|_| words.next().unwrap().parse().unwrap());
                positions.push(Vec3::new(x, y, z));
            }
            Some("f") => {
                let [a, b, c] = [(); 3].map(|_| words.next().unwrap().parse::<u32>().unwrap());
                indices.push([a - 1, b - 1, c - 1]);
            }
            _ => {}
        }
    }

    // Bake: a tree over the triangles, as bytes the device checks once and reads in place.
    let mesh = Mesh::new(&positions, &indices);
    let baked = bake(&mesh).expect("the mesh bakes");
    fs::write(out.join("mesh.rlbv"), baked).unwrap();

    // The board's memory map: a binary that does not fit fails to link.
    let memory = match env::var("TARGET").unwrap().as_str() {
        "thumbv7em-none-eabihf" => "memory/mps2-an386.x", // Cortex-M4F
        "thumbv6m-none-eabi" => "memory/microbit.x",      // Cortex-M0
        t => panic!("no memory map for {t}: add one to memory/ and to build.rs"),
    };
    fs::copy(memory, out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=mesh.obj");
    println!("cargo:rerun-if-changed={memory}");
}
