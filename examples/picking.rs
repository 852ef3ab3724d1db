//! Mouse picking: which surface is under the cursor, where, and which way it faces.
//!
//! A scene of the vendored Stanford bunny (`tests/data/bunny.bin`, 3,674 triangles) and three
//! spheres, a camera, one ray through the cursor, then a packet of eight rays (a row of pixels
//! from the cursor on), each printing the hit's point and normal.
//!
//! ```sh
//! cargo run --example picking
//! ```

use raylane::camera::Pinhole;
use raylane::glam::Vec3;
use raylane::mesh::Mesh;
use raylane::sphere::Sphere;
use raylane::wide::f32x8;
use raylane::{Hit, Query};

/// `bunny.bin`: u32 vertex count, u32 triangle count, f32 x, y, z per vertex, u16 a, b, c per
/// triangle, little-endian (see `tests/data/README.md`). `None` if the bytes are malformed.
fn load(b: &[u8]) -> Option<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let u32_at = |o: usize| Some(u32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    let f32_at = |o: usize| Some(f32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    let u16_at = |o: usize| Some(u16::from_le_bytes(b.get(o..o + 2)?.try_into().ok()?) as u32);
    let (nv, nt) = (u32_at(0)? as usize, u32_at(4)? as usize);
    let v = |i: usize| {
        Some(Vec3::new(
            f32_at(8 + 12 * i)?,
            f32_at(12 + 12 * i)?,
            f32_at(16 + 12 * i)?,
        ))
    };
    let positions = (0..nv).map(v).collect::<Option<Vec<_>>>()?;
    let base = 8 + 12 * nv;
    let t = |i: usize| {
        Some([
            u16_at(base + 6 * i)?,
            u16_at(base + 6 * i + 2)?,
            u16_at(base + 6 * i + 4)?,
        ])
    };
    let indices = (0..nt).map(t).collect::<Option<Vec<_>>>()?;
    Some((positions, indices))
}

fn show(what: &str, hit: Option<Hit>) {
    const SETS: [&str; 2] = ["bunny triangle", "sphere"];
    match hit {
        Some(h) => println!(
            "{what}: {} {} at t = {:.4}, point ({:.4}, {:.4}, {:.4}), normal ({:.3}, {:.3}, {:.3}), {} face",
            SETS[h.set as usize],
            h.index,
            h.t,
            h.point.x,
            h.point.y,
            h.point.z,
            h.normal.x,
            h.normal.y,
            h.normal.z,
            if h.front { "front" } else { "back" },
        ),
        None => println!("{what}: nothing"),
    }
}

fn main() {
    let Some((positions, indices)) = load(include_bytes!("../tests/data/bunny.bin")) else {
        eprintln!("tests/data/bunny.bin is malformed");
        return;
    };
    // The mesh borrows the slices and checks every triangle once, here.
    let bunny = Mesh::bounded(&positions, &indices);
    let spheres = [
        Sphere::new(Vec3::new(-6.5, 1.5, 0.0), 1.5),
        Sphere::new(Vec3::new(6.0, 1.2, 1.0), 1.2),
        Sphere::new(Vec3::new(0.5, 10.8, -1.0), 0.8),
    ];
    // A scene is a tuple of sets; `Hit::set` says which one was hit.
    let scene = (bunny, &spheres[..]);

    let (width, height) = (640, 480);
    let eye = Vec3::new(0.0, 5.0, 24.0);
    let camera = Pinhole::look_at(eye, Vec3::new(0.0, 4.5, 0.0), Vec3::Y, 40.0, width, height);
    let (mouse_x, mouse_y) = (300, 230);

    // One ray through the cursor.
    let ray = camera.row_packet::<f32>(mouse_x, mouse_y).ray(0);
    show("cursor", scene.closest(&ray));

    // Eight rays at once: the cursor's pixel and the seven to its right. Each lane's record
    // is the one the single ray would give, bit for bit.
    let packet = camera.row_packet::<f32x8>(mouse_x, mouse_y);
    let hits = scene.closest(&packet);
    for lane in 0..8 {
        show(
            &format!("pixel ({}, {mouse_y})", mouse_x + lane as u32),
            hits.lane(lane),
        );
    }
}
