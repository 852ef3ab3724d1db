//! Renders the lectures' scenes with the packet kernels and the focal caches, to PNG files.
//!
//! ```text
//! cargo run --release --example render [-- OPTIONS]
//!
//!   --out DIR          where the PNG files go (default out/)
//!   --scene NAME       precision | ground | mesh | mix | bunny | million (repeatable; default
//!                      all six)
//!   --obj FILE         render a Wavefront OBJ through the BVH (alone, unless scenes are named)
//!   --size WxH         panel size (default per scene)
//!   --lanes N          rays per packet: 1, 4, 8 or 16 (default: the run-time SIMD level's)
//!   --threads N        worker threads (default: every core)
//!   --ppm FILE         write one scene as a binary PPM instead (the firmware comparison)
//!   --scene bunny-fw   (not among the six) the firmware `bvh`'s picture: the vendored bunny's
//!                      primary rays through the BVH, one thread (`raylane_lab::demo::bunny`)
//! ```
//!
//! 1. `1-precision.png`: the precision lecture's unit sphere 100 units (top row) and 4100 units
//!    (bottom row) in front of an orthographic camera, with `quadratic`, `geometric`, `robust`
//!    and `focal` from left to right. The orthographic rays do not share an origin, so `focal`
//!    builds its cache per ray with the ray's own origin: it shows the guard, not the speed.
//! 2. `2-ground.png`: small spheres on a ground sphere of radius 2^20 seen from 1 unit above it
//!    (the near-root cancellation scene), `quadratic`, `geometric` / `robust`, `focal`.
//! 3. `3-mesh.png`: a closed icosphere of 5120 triangles over shared vertices, in 80 parts of 64
//!    (a quarter of a face of the icosahedron each) with a bounding sphere each, shaded by
//!    normal, back faces culled: a crack would show the background; there is none.
//! 4. `4-mix.png`: spheres, an icosahedron, a cube and a checkered plane (the firmware's scene).
//! 5. `5-bunny.png`: the vendored Stanford bunny (3,674 triangles) through raylane's BVH, with
//!    one shadow ray per pixel to a point light (`render/bvh.rs`);
//! 6. `6-million.png`: the bunny after 4 Loop subdivision steps, 940,544 triangles, the same
//!    way. `--obj FILE` renders any OBJ file this way (`obj.png`).
//!
//! Scenes 5 and 6 print the BVH's build time and size, and Mrays/s of the primary rays and of
//! the shadow rays, each pass timed on every core.
//!
//! Panels are labelled with their method (and distance). Tiles of 32×8 pixels are shared out
//! to one thread per core; a progress line appears on stderr when a scene takes more than a
//! second. Per scene it prints the image size, the time, rays/s, ray–primitive tests/s
//! (counted per ray lane, bounding spheres included) and the triangle tests that bounding
//! spheres saved.

use std::io::{BufWriter, Write as _};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;
use raylane::Lane;
use raylane::bvh::OwnedBvh;
use raylane::plane::FocalPlane;
use raylane::sphere::FocalSphere;
use raylane::triangle::FocalTriangle;
use raylane_lab::demo::{
    self, Frame, Part, Scene, Stats, Storage, Tile,
    scenes::{self, Ground, Mix, Precision},
};
use raylane_lab::registry::Kernel;
use wide::{f32x4, f32x8, f32x16};

#[path = "render/bvh.rs"]
mod bvh;
#[path = "../benches/src/subdivide.rs"]
mod subdivide;

const TILE: (u32, u32) = (32, 8);

/// Caller storage for one frame's caches.
struct Store {
    spheres: Vec<FocalSphere<f32>>,
    planes: Vec<FocalPlane>,
    triangles: Vec<FocalTriangle<f32>>,
}

impl Store {
    fn for_scene(s: &Scene) -> Store {
        let tris = s.parts.iter().map(|p| p.count as usize).sum();
        Store {
            spheres: vec![demo::empty_sphere(); s.spheres.len()],
            planes: vec![demo::empty_plane(); s.planes.len()],
            triangles: vec![FocalTriangle::never(); tris],
        }
    }

    fn storage(&mut self) -> Storage<'_> {
        Storage {
            spheres: &mut self.spheres,
            planes: &mut self.planes,
            triangles: &mut self.triangles,
        }
    }
}

/// One panel of a picture: a frame and where it goes.
struct Panel<'a> {
    frame: Frame<'a>,
    x: u32,
    y: u32,
    label: String,
}

/// A rendered picture.
struct Picture {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
    stats: Stats,
    time: Duration,
}

/// Renders every tile of every panel on `threads` threads with `L` lanes per packet.
fn render<L: Lane<Scalar = f32>>(
    name: &str,
    panels: &[Panel],
    width: u32,
    height: u32,
    threads: usize,
) -> Picture {
    let work: Vec<(usize, Tile)> = panels
        .iter()
        .enumerate()
        .flat_map(|(k, p)| {
            let c = p.frame.camera();
            demo::tiles(c.width(), c.height(), TILE.0, TILE.1).map(move |t| (k, t))
        })
        .collect();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let start = Instant::now();
    type Done = (Vec<(usize, Vec<u8>)>, Stats, Duration);
    let results: Vec<Done> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    let mut stats = Stats::default();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&(k, tile)) = work.get(i) else { break };
                        let mut rgb = vec![0u8; 3 * tile.pixels()];
                        let st = panels[k].frame.render_tile::<L>(tile, &mut rgb, None);
                        stats.add(&st);
                        out.push((i, rgb));
                        done.fetch_add(1, Ordering::Relaxed);
                    }
                    (out, stats, start.elapsed())
                })
            })
            .collect();
        // Progress, once the scene has taken more than a second.
        let mut shown = false;
        while done.load(Ordering::Relaxed) < work.len() {
            std::thread::sleep(Duration::from_millis(50));
            if start.elapsed() > Duration::from_secs(1) {
                let d = done.load(Ordering::Relaxed);
                eprint!(
                    "\r{name}: {:3}% ({d}/{} tiles, {:.1} s)",
                    100 * d / work.len().max(1),
                    work.len(),
                    start.elapsed().as_secs_f64()
                );
                shown = true;
            }
        }
        if shown {
            eprint!("\r{:60}\r", "");
        }
        workers
            .into_iter()
            .map(|w| w.join().expect("a render thread panicked"))
            .collect()
    });
    // The time until the last worker finished (the progress loop polls every 50 ms).
    let time = results.iter().map(|r| r.2).max().unwrap_or_default();
    let mut rgb = vec![0u8; 3 * width as usize * height as usize];
    let mut stats = Stats::default();
    for (tiles, st, _) in results {
        stats.add(&st);
        for (i, px) in tiles {
            let (k, t) = work[i];
            let (ox, oy) = (panels[k].x + t.x, panels[k].y + t.y);
            for row in 0..t.height as usize {
                let src = &px[3 * row * t.width as usize..3 * (row + 1) * t.width as usize];
                let at = 3 * ((oy as usize + row) * width as usize + ox as usize);
                rgb[at..at + src.len()].copy_from_slice(src);
            }
        }
    }
    let mut pic = Picture {
        width,
        height,
        rgb,
        stats,
        time,
    };
    for p in panels {
        label(&mut pic, p.x + 4, p.y + 4, &p.label);
    }
    pic
}

fn render_lanes(
    lanes: usize,
    name: &str,
    panels: &[Panel],
    width: u32,
    height: u32,
    threads: usize,
) -> Picture {
    match lanes {
        1 => render::<f32>(name, panels, width, height, threads),
        4 => render::<f32x4>(name, panels, width, height, threads),
        8 => render::<f32x8>(name, panels, width, height, threads),
        _ => render::<f32x16>(name, panels, width, height, threads),
    }
}

/// A 5×7 bitmap font for the labels (the few characters they use).
fn glyph(c: char) -> [&'static str; 7] {
    match c {
        'a' => [
            ".....", ".....", ".###.", "....#", ".####", "#...#", ".####",
        ],
        'b' => [
            "#....", "#....", "####.", "#...#", "#...#", "#...#", "####.",
        ],
        'c' => [
            ".....", ".....", ".###.", "#....", "#....", "#...#", ".###.",
        ],
        'd' => [
            "....#", "....#", ".####", "#...#", "#...#", "#...#", ".####",
        ],
        'e' => [
            ".....", ".....", ".###.", "#...#", "#####", "#....", ".###.",
        ],
        'f' => [
            "..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#...",
        ],
        'g' => [
            ".....", ".....", ".####", "#...#", ".####", "....#", ".###.",
        ],
        'i' => [
            "..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###.",
        ],
        'l' => [
            ".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        'm' => [
            ".....", ".....", "##.#.", "#.#.#", "#.#.#", "#...#", "#...#",
        ],
        'n' => [
            ".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#",
        ],
        'o' => [
            ".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###.",
        ],
        'q' => [
            ".....", ".....", ".####", "#...#", ".####", "....#", "....#",
        ],
        'r' => [
            ".....", ".....", "#.##.", "##..#", "#....", "#....", "#....",
        ],
        's' => [
            ".....", ".....", ".####", "#....", ".###.", "....#", "####.",
        ],
        't' => [
            ".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##.",
        ],
        'u' => [
            ".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#",
        ],
        '0' => [
            ".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###.",
        ],
        '1' => [
            "..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        '4' => [
            "...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#.",
        ],
        '-' => [
            ".....", ".....", ".....", "#####", ".....", ".....", ".....",
        ],
        _ => ["....."; 7],
    }
}

/// Writes `text` at `(x, y)` in white on a darkened box, 2× scale.
fn label(p: &mut Picture, x: u32, y: u32, text: &str) {
    if text.is_empty() {
        return;
    }
    let s = 2;
    let (w, h) = (text.chars().count() as u32 * 6 * s + 2 * s, 9 * s);
    let mut put = |px: u32, py: u32, f: &dyn Fn(u8) -> u8| {
        if px < p.width && py < p.height {
            let at = 3 * (py as usize * p.width as usize + px as usize);
            for c in &mut p.rgb[at..at + 3] {
                *c = f(*c);
            }
        }
    };
    for dy in 0..h {
        for dx in 0..w {
            put(x + dx, y + dy, &|c| c / 3);
        }
    }
    for (k, ch) in text.chars().enumerate() {
        for (row, bits) in glyph(ch).iter().enumerate() {
            for (col, b) in bits.bytes().enumerate() {
                if b == b'#' {
                    for sy in 0..s {
                        for sx in 0..s {
                            let gx = x + s + (k as u32 * 6 + col as u32) * s + sx;
                            let gy = y + s + row as u32 * s + sy;
                            put(gx, gy, &|_| 255);
                        }
                    }
                }
            }
        }
    }
}

fn write_png(path: &Path, p: &Picture) -> std::io::Result<()> {
    let file = BufWriter::new(std::fs::File::create(path)?);
    let mut enc = png::Encoder::new(file, p.width, p.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(std::io::Error::other)?;
    w.write_image_data(&p.rgb).map_err(std::io::Error::other)?;
    w.finish().map_err(std::io::Error::other)
}

fn write_ppm(path: &Path, p: &Picture) -> std::io::Result<()> {
    let mut head = [0u8; 32];
    let n = demo::ppm_header(p.width, p.height, &mut head).expect("a short header");
    let mut f = BufWriter::new(std::fs::File::create(path)?);
    f.write_all(&head[..n])?;
    f.write_all(&p.rgb)?;
    f.flush()
}

fn millions(x: f64) -> String {
    if x >= 1e9 {
        format!("{:.2} G", x / 1e9)
    } else {
        format!("{:.1} M", x / 1e6)
    }
}

fn report(file: &str, p: &Picture, panels: usize) {
    let s = &p.stats;
    let secs = p.time.as_secs_f64().max(1e-9);
    let saved = if s.triangle_tests + s.triangle_tests_saved == 0 {
        "no triangles".to_string()
    } else {
        let all = (s.triangle_tests + s.triangle_tests_saved) as f64;
        format!(
            "{} of {} ({:.1} %)",
            s.triangle_tests_saved,
            s.triangle_tests + s.triangle_tests_saved,
            100.0 * s.triangle_tests_saved as f64 / all
        )
    };
    let size = if panels > 1 {
        format!("{}x{} ({panels} panels)", p.width, p.height)
    } else {
        format!("{}x{}", p.width, p.height)
    };
    println!(
        "{file:<16} {size:<22} {:>7.3} s  {:>9}rays/s  {:>9}tests/s  triangle tests saved by bounding spheres: {saved}",
        secs,
        millions(s.rays as f64 / secs),
        millions(s.tests() as f64 / secs),
    );
}

struct Options {
    out: PathBuf,
    scenes: Vec<String>,
    size: Option<(u32, u32)>,
    lanes: usize,
    threads: usize,
    ppm: Option<PathBuf>,
    obj: Option<PathBuf>,
}

/// The packet width for the SIMD level the queries run at (chosen when the program runs,
/// `raylane::simd`): 8 with AVX2 or AVX-512, else 4 (SSE2, NEON). Every width gives the same
/// image. Measured on this machine's AVX-512 Xeon (best of 5, 2 threads, M rays/s primary /
/// shadow): bunny 29.0 / 17.9 in packets of 8, 22.8 / 15.4 in packets of 16; the million
/// 17.2 / 5.3 and 13.5 / 4.8. Scenes 1–4 take the same time at 8 and 16.
fn default_lanes() -> usize {
    raylane::simd::level().lanes().clamp(4, 8)
}

/// The scenes, in order.
const SCENES: [&str; 6] = ["precision", "ground", "mesh", "mix", "bunny", "million"];

fn parse() -> Result<Options, String> {
    let mut o = Options {
        out: PathBuf::from("out"),
        scenes: Vec::new(),
        size: None,
        lanes: default_lanes(),
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        ppm: None,
        obj: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--out" => o.out = value()?.into(),
            "--scene" => o.scenes.push(value()?),
            "--size" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or("--size WxH")?;
                let (w, h) = (w.parse(), h.parse());
                match (w, h) {
                    (Ok(w), Ok(h)) if w > 0 && h > 0 => o.size = Some((w, h)),
                    _ => return Err(format!("bad size {v}")),
                }
            }
            "--lanes" => {
                o.lanes = value()?.parse().map_err(|_| "bad --lanes")?;
                if ![1, 4, 8, 16].contains(&o.lanes) {
                    return Err("--lanes must be 1, 4, 8 or 16".into());
                }
            }
            "--threads" => o.threads = value()?.parse().map_err(|_| "bad --threads")?,
            "--ppm" => o.ppm = Some(value()?.into()),
            "--obj" => o.obj = Some(value()?.into()),
            "-h" | "--help" => return Err(String::new()),
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    if o.scenes.is_empty() && o.obj.is_none() {
        o.scenes = SCENES.map(String::from).to_vec();
    }
    if o.obj.is_some() {
        o.scenes.push("obj".into());
    }
    for s in &o.scenes {
        if !SCENES.contains(&s.as_str()) && s != "obj" && s != "bunny-fw" {
            return Err(format!("unknown scene {s}"));
        }
    }
    if o.ppm.is_some() && o.scenes.len() != 1 {
        return Err("--ppm needs exactly one --scene".into());
    }
    Ok(o)
}

fn main() -> ExitCode {
    let o = match parse() {
        Ok(o) => o,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("render: {e}");
            }
            eprintln!(
                "usage: render [--out DIR] [--scene precision|ground|mesh|mix|bunny|million]... \
                 [--obj FILE] [--size WxH] [--lanes 1|4|8|16] [--threads N] [--ppm FILE]"
            );
            return if e.is_empty() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(2)
            };
        }
    };
    if o.ppm.is_none() {
        if let Err(e) = std::fs::create_dir_all(&o.out) {
            eprintln!("render: {}: {e}", o.out.display());
            return ExitCode::FAILURE;
        }
        println!(
            "{} threads, SIMD level {} (chosen at run time), {} rays per packet, tiles of {}x{}",
            o.threads,
            raylane::simd::level(),
            o.lanes,
            TILE.0,
            TILE.1
        );
    }
    for name in &o.scenes {
        let (file, pic, panels) = match name.as_str() {
            "precision" => precision(&o),
            "ground" => ground(&o),
            "mesh" => mesh(&o),
            "mix" => mix(&o),
            "bunny-fw" => bunny_fw(&o),
            _ => match traced(&o, name) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("render: {e}");
                    return ExitCode::FAILURE;
                }
            },
        };
        let result = match &o.ppm {
            Some(path) => write_ppm(path, &pic),
            None => write_png(&o.out.join(file), &pic),
        };
        if let Err(e) = result {
            eprintln!("render: {file}: {e}");
            return ExitCode::FAILURE;
        }
        if o.ppm.is_some() {
            println!(
                "{name} {}x{} x{}: fnv1a {:016x}",
                pic.width,
                pic.height,
                o.lanes,
                demo::fnv1a(&pic.rgb)
            );
        } else if panels > 0 {
            report(file, &pic, panels);
        }
    }
    ExitCode::SUCCESS
}

/// Scenes 5 and 6 and `--obj`: a mesh through the BVH, with shadow rays (prints its own
/// report line; 0 panels).
fn traced(o: &Options, name: &str) -> Result<(&'static str, Picture, usize), String> {
    let (w, h) = o.size.unwrap_or((800, 600));
    let made = Instant::now();
    let (file, mesh) = match name {
        "bunny" => ("5-bunny.png", bvh::MeshData::bunny()),
        "million" => ("6-million.png", bvh::MeshData::subdivided_bunny(4)),
        _ => {
            let path = o.obj.as_deref().unwrap_or(Path::new(""));
            let m = bvh::MeshData::obj(path).map_err(|e| format!("{}: {e}", path.display()))?;
            ("obj.png", m)
        }
    };
    let made = made.elapsed();
    let tris = mesh.triangles();
    let built = Instant::now();
    let tree = OwnedBvh::new(&tris[..]).map_err(|e| e.to_string())?;
    let built = built.elapsed();
    let (cam, centre, radius) = bvh::framing(&mesh, w, h);
    let light = centre + Vec3::new(-1.0, 2.0, 1.5).normalize() * (3.0 * radius);
    let eps = 1e-4 * radius;
    let t = tree.view();
    let shot = match o.lanes {
        1 => bvh::render::<f32>(&t, &tris, &cam, light, eps, o.threads),
        4 => bvh::render::<f32x4>(&t, &tris, &cam, light, eps, o.threads),
        8 => bvh::render::<f32x8>(&t, &tris, &cam, light, eps, o.threads),
        _ => bvh::render::<f32x16>(&t, &tris, &cam, light, eps, o.threads),
    };
    let rate = |(n, d): (u64, Duration)| millions(n as f64 / d.as_secs_f64().max(1e-9));
    if o.ppm.is_none() {
        println!(
            "{file:<16} {:<22} {:>7.3} s  {:>9}rays/s primary, {:>9}rays/s shadow ({} rays)  {} triangles, BVH built in {:.3} s ({:.0} B/triangle){}",
            format!("{w}x{h}"),
            (shot.primary.1 + shot.shadow.1).as_secs_f64(),
            rate(shot.primary),
            rate(shot.shadow),
            shot.shadow.0,
            tris.len(),
            built.as_secs_f64(),
            t.stats().bytes as f64 / tris.len().max(1) as f64,
            if name == "million" {
                format!(", subdivided in {:.2} s", made.as_secs_f64())
            } else {
                String::new()
            }
        );
    }
    let pic = Picture {
        width: w,
        height: h,
        rgb: shot.rgb,
        stats: Stats::default(),
        time: shot.primary.1 + shot.shadow.1,
    };
    Ok((file, pic, 0))
}

/// Scene 1: rows 100 and 4100 units, columns quadratic, geometric, robust, focal.
fn precision(o: &Options) -> (&'static str, Picture, usize) {
    let (w, h) = o.size.unwrap_or((256, 256));
    let balls = Precision::DISTANCES.map(Precision::new);
    let mut cells = Vec::new();
    for (row, ball) in balls.iter().enumerate() {
        for (col, m) in Precision::METHODS.into_iter().enumerate() {
            let frame = Frame::new(ball.scene(), Precision::camera(w, h), m, Storage::none())
                .expect("no storage needed");
            let label = format!("{} {}", m.name(), Precision::DISTANCES[row]);
            cells.push(Panel {
                frame,
                x: col as u32 * w,
                y: row as u32 * h,
                label,
            });
        }
    }
    let pic = render_lanes(o.lanes, "precision", &cells, 4 * w, 2 * h, o.threads);
    ("1-precision.png", pic, cells.len())
}

/// Scene 2: quadratic, geometric / robust, focal.
fn ground(o: &Options) -> (&'static str, Picture, usize) {
    let (w, h) = o.size.unwrap_or((480, 320));
    let g = Ground::new();
    let mut stores: Vec<Store> = Ground::METHODS
        .iter()
        .map(|_| Store::for_scene(&g.scene()))
        .collect();
    let cells: Vec<Panel> = Ground::METHODS
        .into_iter()
        .zip(stores.iter_mut())
        .enumerate()
        .map(|(k, (m, st))| Panel {
            frame: Frame::new(g.scene(), Ground::camera(w, h), m, st.storage())
                .expect("storage sized for the scene"),
            x: (k as u32 % 2) * w,
            y: (k as u32 / 2) * h,
            label: m.name().to_string(),
        })
        .collect();
    let pic = render_lanes(o.lanes, "ground", &cells, 2 * w, 2 * h, o.threads);
    ("2-ground.png", pic, cells.len())
}

/// Scene 3: the closed icosphere.
fn mesh(o: &Options) -> (&'static str, Picture, usize) {
    let (w, h) = o.size.unwrap_or((800, 600));
    let n = scenes::FREQUENCY;
    let mut positions = vec![Vec3::ZERO; demo::shapes::icosphere_vertices(n)];
    let mut indices = vec![[0u32; 3]; demo::shapes::icosphere_triangles(n)];
    let mut parts = [Part {
        first: 0,
        count: 0,
        paint: demo::Paint::Normal,
        cull: raylane::Cull::Back,
    }; scenes::ICOSPHERE_PARTS];
    let scene = scenes::icosphere(n, &mut positions, &mut indices, &mut parts)
        .expect("storage sized for the icosphere");
    let mut st = Store::for_scene(&scene);
    let frame = Frame::new(
        scene,
        scenes::icosphere_camera(w, h),
        Kernel::Focal,
        st.storage(),
    )
    .expect("storage sized for the scene");
    let cells = [Panel {
        frame,
        x: 0,
        y: 0,
        label: String::new(),
    }];
    let pic = render_lanes(o.lanes, "mesh", &cells, w, h, o.threads);
    ("3-mesh.png", pic, 1)
}

/// Scene 4: spheres, meshes and a plane.
/// The firmware `bvh`'s picture (`targets/src/bin/bvh.rs`): the vendored bunny's BVH built by
/// `raylane_lab::demo::bunny`'s code on one thread, primary rays only.
fn bunny_fw(o: &Options) -> (&'static str, Picture, usize) {
    use raylane_lab::demo::bunny;
    let (w, h) = o.size.unwrap_or(bunny::SIZE);
    let start = Instant::now();
    let mut tris = vec![raylane::triangle::Triangle::never(); bunny::TRIANGLES];
    let n = bunny::load(include_bytes!("../tests/data/bunny.bin"), &mut tris)
        .expect("tests/data/bunny.bin is well formed");
    tris.truncate(n);
    let owned = OwnedBvh::new(&tris[..]).expect("fewer than 2^30 triangles");
    let tree = owned.view();
    let cam = bunny::camera(&tris, w, h);
    let mut rgb = vec![0u8; 3 * w as usize * h as usize];
    let hits = match o.lanes {
        1 => bunny::render::<f32, _>(&tree, &cam, &mut rgb),
        4 => bunny::render::<f32x4, _>(&tree, &cam, &mut rgb),
        8 => bunny::render::<f32x8, _>(&tree, &cam, &mut rgb),
        _ => bunny::render::<f32x16, _>(&tree, &cam, &mut rgb),
    };
    debug_assert!(hits.is_some(), "the image buffer is sized for the camera");
    let pic = Picture {
        width: w,
        height: h,
        rgb,
        stats: Stats::default(),
        time: start.elapsed(),
    };
    ("bunny-fw.png", pic, 1)
}

fn mix(o: &Options) -> (&'static str, Picture, usize) {
    let (w, h) = o.size.unwrap_or((800, 600));
    let m = Mix::new();
    let mut st = Store::for_scene(&m.scene());
    let frame = Frame::new(m.scene(), Mix::camera(w, h), Kernel::Focal, st.storage())
        .expect("storage sized for the scene");
    let cells = [Panel {
        frame,
        x: 0,
        y: 0,
        label: String::new(),
    }];
    let pic = render_lanes(o.lanes, "mix", &cells, w, h, o.threads);
    ("4-mix.png", pic, 1)
}
