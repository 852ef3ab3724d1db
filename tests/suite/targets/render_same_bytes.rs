//! The demo renderer's pictures, checked (feature `demo`):
//!
//! * every scene renders to the same bytes at every lane width (1, 4, 8, 16), and the images'
//!   FNV-1a digests are pinned (the suite runs on x86-64, x86-64-v3, the native CPU and
//!   AArch64: the same digests everywhere);
//! * the precision lecture's sphere at 100 and 4100 units: pixel counts per method, and every
//!   pixel of `robust` and `focal` equal to the exact answer for its ray unless 2-ulp moves of
//!   the inputs could change that answer;
//! * the closed icosphere has no crack: every pixel whose ray passes inside the sphere
//!   inscribed in the mesh (decided in f64 from the ray's f32 origin and direction) shows a
//!   triangle, and no pixel outside the circumscribed sphere does.
//!
//! Run with `--nocapture` to see the counts and digests.

use glam::Vec3;
use raylane::Cull;
use raylane::plane::FocalPlane;
use raylane::sphere::FocalSphere;
use raylane::triangle::FocalTriangle;
use raylane::{Lane, RayPacket, V3};
use raylane_lab::demo::{
    self, Camera, Frame, ID_NONE, ID_SPHERE, ID_TRIANGLE, Part, Scene, Storage,
    scenes::{self, Ground, Mix, Precision},
    shapes,
};
use raylane_lab::registry::Kernel;
use wide::{f32x4, f32x8, f32x16};

/// Caches for one frame.
struct Store {
    spheres: Vec<FocalSphere<f32>>,
    planes: Vec<FocalPlane>,
    triangles: Vec<FocalTriangle<f32>>,
}

impl Store {
    fn new(s: &Scene) -> Store {
        Store {
            spheres: vec![demo::empty_sphere(); s.spheres.len()],
            planes: vec![demo::empty_plane(); s.planes.len()],
            triangles: vec![FocalTriangle::never(); s.indices.len()],
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

/// RGB and ids of a frame with `L` lanes.
fn render_with<L: Lane<Scalar = f32>>(f: &Frame) -> (Vec<u8>, Vec<u8>) {
    let n = (f.camera().width() * f.camera().height()) as usize;
    let (mut rgb, mut ids) = (vec![0u8; 3 * n], vec![0u8; n]);
    f.render::<L>(&mut rgb, Some(&mut ids));
    (rgb, ids)
}

/// RGB and ids of a frame, the same at every lane width (checked), and with tiles.
fn render(f: &Frame) -> (Vec<u8>, Vec<u8>) {
    let one = render_with::<f32>(f);
    assert!(render_with::<f32x4>(f) == one, "x4 differs from x1");
    assert!(render_with::<f32x8>(f) == one, "x8 differs from x1");
    assert!(render_with::<f32x16>(f) == one, "x16 differs from x1");
    // Tiles of 16×4 rendered apart give the same image.
    let (w, h) = (f.camera().width(), f.camera().height());
    let mut rgb = vec![0u8; one.0.len()];
    for t in demo::tiles(w, h, 16, 4) {
        let mut px = vec![0u8; 3 * t.pixels()];
        f.render_tile::<f32x8>(t, &mut px, None);
        for row in 0..t.height as usize {
            let at = 3 * ((t.y as usize + row) * w as usize + t.x as usize);
            let len = 3 * t.width as usize;
            rgb[at..at + len].copy_from_slice(&px[row * len..(row + 1) * len]);
        }
    }
    assert!(rgb == one.0, "tiles differ from the whole image");
    one
}

fn ulp(x: f32) -> f64 {
    let a = x.abs();
    f64::from(a.next_up()) - f64::from(a)
}

/// `v` as an exact `f64` vector.
fn w(v: Vec3) -> V3<f64> {
    V3::splat(v)
}

/// Distance² from `c` to the line `o + t·d` and the position of the foot along the unit
/// direction, in f64 from the f32 inputs (error ~2^-50·|c − o|², far below the band below).
fn line(o: Vec3, d: Vec3, c: Vec3) -> (f64, f64) {
    let (o, d, c) = (w(o), w(d), w(c));
    let t = c - o;
    let u = d.div_by(d.dot(d).sqrt());
    let s = t.dot(u);
    let p = t - u.scale(s);
    (p.dot(p), s)
}

/// The ray of pixel `(x, y)`: origin and direction, as the renderer's lanes compute them.
fn ray(cam: &Camera, x: u32, y: u32) -> (Vec3, Vec3) {
    let r: RayPacket<f32> = cam.row_packet(x, y);
    (r.origin().lane(0), r.dir().lane(0))
}

/// The exact answer for the ray of a pixel against a sphere ahead of it, or `None` when 2-ulp
/// moves of the origin, direction, centre or radius could change it (first-order bound on
/// `r² − l²`, as in `focal_precision.rs`).
fn exact_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32) -> Option<bool> {
    let (l2, s) = line(o, d, c);
    let l = l2.sqrt();
    let mut band = 2.0 * r as f64 * 2.0 * ulp(r);
    for i in 0..3 {
        band += 2.0 * l * 2.0 * (ulp(o[i]) + ulp(c[i]));
        band += 2.0 * l * s.abs() * 2.0 * ulp(d[i]) / w(d).dot(w(d)).sqrt();
    }
    let margin = (r as f64) * (r as f64) - l2;
    (margin.abs() > 1.5 * band).then_some(margin > 0.0)
}

#[test]
fn precision_sphere_pixels_per_method() {
    let (size, ball_r) = (64u32, 1.0f32);
    println!("sphere pixels at {size}x{size} (analytic disc: {:.0})", {
        // The view is 4 units tall: a unit sphere covers π·(size/4)² pixels.
        core::f64::consts::PI * (size as f64 / 4.0).powi(2)
    });
    let mut counts = Vec::new();
    for d in Precision::DISTANCES {
        let p = Precision::new(d);
        let cam = Precision::camera(size, size);
        let center = p.scene().spheres[0].center();
        for m in demo::sphere_kernels() {
            let f = <Frame>::new(p.scene(), cam, m, Storage::none()).unwrap();
            let (_, ids) = render(&f);
            let hits = ids.iter().filter(|&&i| i == ID_SPHERE).count();
            // Pixels whose exact answer is certain and differs from the picture.
            let mut wrong = 0;
            let mut decided = 0;
            for y in 0..size {
                for x in 0..size {
                    let (o, dir) = ray(&cam, x, y);
                    if let Some(hit) = exact_sphere(o, dir, center, ball_r) {
                        decided += 1;
                        wrong += (hit != (ids[(y * size + x) as usize] == ID_SPHERE)) as usize;
                    }
                }
            }
            println!(
                "{d:>6} units  {:<16} {hits:5} pixels, {wrong:4} of {decided} decidable pixels wrong",
                m.name()
            );
            counts.push((d, m, hits, wrong));
        }
    }
    let get = |d: f32, m: Kernel| counts.iter().find(|c| c.0 == d && c.1 == m).unwrap();
    for m in demo::sphere_kernels() {
        let near = get(100.0, m);
        assert!(
            near.2 > 700 && near.3 == 0,
            "{} at 100 units: {:?}",
            m.name(),
            near
        );
    }
    for m in [
        Kernel::Robust,
        Kernel::Focal,
        Kernel::Pbrt,
        Kernel::EmbreeSphere,
    ] {
        let far = get(4100.0, m);
        assert!(far.2 > 700, "{} lost the sphere at 4100 units", m.name());
        assert_eq!(far.3, 0, "{} misclassified pixels at 4100 units", m.name());
    }
    // Every count at 4100 units, pinned as rendered: the textbook methods lose the sphere in
    // noise (quadratic and geometric hit far beyond the disc, the unguarded focal test loses
    // half of it), robust, focal, pbrt and embree draw the disc of 100 units.
    let pinned: [(Kernel, usize); 8] = [
        (Kernel::Quadratic, 2528),
        (Kernel::QuadraticUnit, 2528),
        (Kernel::Geometric, 1340),
        (Kernel::Robust, 812),
        (Kernel::Focal, 812),
        (Kernel::FocalUnguarded, 374),
        (Kernel::Pbrt, 812),
        (Kernel::EmbreeSphere, 812),
    ];
    let got: Vec<(Kernel, usize)> = demo::sphere_kernels()
        .map(|m| (m, get(4100.0, m).2))
        .collect();
    assert_eq!(got, pinned, "sphere pixels at 4100 units changed");
}

/// The icosphere scene's data, built into vectors.
fn icosphere(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<Part>) {
    let mut pos = vec![Vec3::ZERO; shapes::icosphere_vertices(n)];
    let mut idx = vec![[0u32; 3]; shapes::icosphere_triangles(n)];
    let mut parts = vec![
        Part {
            first: 0,
            count: 0,
            paint: demo::Paint::Normal,
            cull: Cull::Back,
        };
        scenes::ICOSPHERE_PARTS
    ];
    let s = scenes::icosphere(n, &mut pos, &mut idx, &mut parts).unwrap();
    let k = s.parts.len();
    parts.truncate(k);
    (pos, idx, parts)
}

#[test]
fn icosphere_is_closed_and_wound_outward() {
    for n in [1, 2, 3, 8, 16] {
        let (pos, idx, parts) = icosphere(n);
        assert_eq!(idx.len(), 20 * (n * n) as usize);
        assert_eq!(pos.len(), 10 * (n * n) as usize + 2);
        // Parts tile the index triples in order.
        let mut next = 0;
        for p in &parts {
            assert_eq!(p.first, next);
            next += p.count;
        }
        assert_eq!(next as usize, idx.len());
        // Every directed edge once, its twin once: closed and consistently wound.
        let mut edges = std::collections::HashMap::new();
        for t in &idx {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &c) in &edges {
            assert_eq!(c, 1, "n = {n}: edge {a}-{b} twice");
            assert_eq!(
                edges.get(&(b, a)),
                Some(&1),
                "n = {n}: edge {a}-{b} has no twin"
            );
        }
        // Every vertex is used and lies on the unit sphere; normals point outward.
        let mut used = vec![false; pos.len()];
        for t in &idx {
            for &i in t {
                used[i as usize] = true;
            }
            let [a, b, c] = t.map(|i| w(pos[i as usize]));
            let nrm = (b - a).cross(c - a);
            assert!(nrm.dot(a) > 0.0, "n = {n}: a triangle faces inward");
        }
        assert!(used.iter().all(|&u| u), "n = {n}: unused vertex");
        for p in &pos {
            assert!((p.length() - 1.0).abs() < 1e-6);
        }
    }
}

#[test]
fn icosphere_render_has_no_cracks() {
    let n = scenes::FREQUENCY;
    let (pos, idx, parts) = icosphere(n);
    let scene = Scene {
        spheres: &[],
        sphere_paints: &[],
        planes: &[],
        plane_paints: &[],
        positions: &pos,
        indices: &idx,
        parts: &parts,
        light: scenes::LIGHT,
    };
    // The largest sphere inside the mesh: the smallest distance from the centre to a face's
    // plane (f64 from the f32 positions), and the smallest one outside it.
    let mut inradius = f64::INFINITY;
    for t in &idx {
        let [a, b, c] = t.map(|i| w(pos[i as usize]));
        let nrm = (b - a).cross(c - a);
        inradius = inradius.min(nrm.dot(a) / nrm.dot(nrm).sqrt());
    }
    let outradius = pos
        .iter()
        .map(|p| w(*p))
        .map(|p| p.dot(p).sqrt())
        .fold(0.0, f64::max);
    let (width, height) = (160, 120);
    let cam = scenes::icosphere_camera(width, height);
    let mut store = Store::new(&scene);
    let f = <Frame>::new(scene, cam, Kernel::Focal, store.storage()).unwrap();
    let (_, ids) = render_with::<f32x16>(&f);
    let (mut inside, mut cracks, mut stray) = (0, 0, 0);
    for y in 0..height {
        for x in 0..width {
            let (o, d) = ray(&cam, x, y);
            let (l2, _) = line(o, d, Vec3::ZERO);
            let id = ids[(y * width + x) as usize];
            if l2.sqrt() < inradius * (1.0 - 1e-6) {
                inside += 1;
                cracks += (id != ID_TRIANGLE) as usize;
            } else if l2.sqrt() > outradius * (1.0 + 1e-6) {
                stray += (id != ID_NONE) as usize;
            }
        }
    }
    println!(
        "icosphere n = {n} ({} triangles, {} parts), {width}x{height}: inradius {inradius:.6}, \
         {inside} pixels inside the silhouette, {cracks} crack pixels, {stray} stray",
        idx.len(),
        parts.len()
    );
    assert!(
        inside > 5000,
        "the silhouette must cover the picture ({inside})"
    );
    assert_eq!(cracks, 0, "crack pixels inside the closed mesh");
    assert_eq!(stray, 0, "pixels outside the mesh hit a triangle");
    // Every lane width gives the same picture (a smaller copy, to keep the test quick).
    let cam = scenes::icosphere_camera(48, 32);
    let mut store = Store::new(&scene);
    render(&<Frame>::new(scene, cam, Kernel::Focal, store.storage()).unwrap());
}

#[test]
fn image_digests_are_pinned() {
    let mut got = Vec::new();
    // 1. Precision: eight 24×24 panels.
    let mut bytes = Vec::new();
    for d in Precision::DISTANCES {
        let p = Precision::new(d);
        for m in Precision::METHODS {
            let f = <Frame>::new(p.scene(), Precision::camera(24, 24), m, Storage::none()).unwrap();
            bytes.extend(render(&f).0);
        }
    }
    got.push(("precision 8 x 24x24", demo::fnv1a(&bytes)));
    // 2. Ground: four 40×30 panels.
    let g = Ground::new();
    let mut bytes = Vec::new();
    for m in Ground::METHODS {
        let mut store = Store::new(&g.scene());
        let f = <Frame>::new(g.scene(), Ground::camera(40, 30), m, store.storage()).unwrap();
        bytes.extend(render(&f).0);
    }
    got.push(("ground 4 x 40x30", demo::fnv1a(&bytes)));
    // 3. The icosphere.
    let (pos, idx, parts) = icosphere(scenes::FREQUENCY);
    let scene = Scene {
        spheres: &[],
        sphere_paints: &[],
        planes: &[],
        plane_paints: &[],
        positions: &pos,
        indices: &idx,
        parts: &parts,
        light: scenes::LIGHT,
    };
    let mut store = Store::new(&scene);
    let f = <Frame>::new(
        scene,
        scenes::icosphere_camera(40, 30),
        Kernel::Focal,
        store.storage(),
    )
    .unwrap();
    got.push(("mesh 40x30", demo::fnv1a(&render(&f).0)));
    // 4. The mix, at the firmware's size (the firmware prints the same digest).
    let m = Mix::new();
    let (w, h) = Mix::FIRMWARE_SIZE;
    let mut store = Store::new(&m.scene());
    let f = <Frame>::new(m.scene(), Mix::camera(w, h), Kernel::Focal, store.storage()).unwrap();
    got.push(("mix 64x48", demo::fnv1a(&render(&f).0)));
    for (name, d) in &got {
        println!("{name:<22} {d:#018x}");
    }
    let pinned: [(&str, u64); 4] = [
        ("precision 8 x 24x24", 0x7561_7969_a9aa_9a41),
        ("ground 4 x 40x30", 0xa26d_4484_0774_8c5d),
        ("mesh 40x30", 0x96e7_b2dc_b17e_bff3),
        ("mix 64x48", 0xbea2_667c_0c75_3492),
    ];
    assert_eq!(got, pinned, "image digests changed");
}

#[test]
fn frames_refuse_short_storage_and_render_into_short_buffers() {
    let m = Mix::new();
    let cam = Mix::camera(16, 8);
    let mut store = Store::new(&m.scene());
    store.triangles.truncate(Mix::TRIANGLES - 1);
    assert_eq!(
        <Frame>::new(m.scene(), cam, Kernel::Focal, store.storage()).err(),
        Some(demo::SetupError::TriangleStorage)
    );
    let mut store = Store::new(&m.scene());
    store.spheres.clear();
    assert_eq!(
        <Frame>::new(m.scene(), cam, Kernel::Focal, store.storage()).err(),
        Some(demo::SetupError::SphereStorage)
    );
    // Non-focal methods need no sphere entries.
    let f = <Frame>::new(m.scene(), cam, Kernel::Robust, store.storage());
    assert!(f.is_ok());
    // A buffer too short for the image: the whole pixels that fit are written, no panic.
    let mut store = Store::new(&m.scene());
    let f = <Frame>::new(m.scene(), cam, Kernel::Focal, store.storage()).unwrap();
    let mut short = vec![0u8; 3 * 16 * 8 - 5];
    let stats = f.render::<f32x8>(&mut short, None);
    assert_eq!(stats.rays, 16 * 8);
    let mut full = vec![0u8; 3 * 16 * 8];
    f.render::<f32>(&mut full, None);
    let whole = short.len() / 3 * 3;
    assert_eq!(short[..whole], full[..whole]);
    assert!(short[whole..].iter().all(|&b| b == 0));
    // The PPM header the firmware writes.
    let mut head = [0u8; 32];
    let k = demo::ppm_header(64, 48, &mut head).unwrap();
    assert_eq!(&head[..k], b"P6\n64 48\n255\n");
    assert_eq!(demo::ppm_header(64, 48, &mut head[..5]), None);
}

/// The firmware `bvh`'s picture (`raylane_lab::demo::bunny`, `targets/src/bin/bvh.rs`): the vendored
/// bunny loads, and the 64×48 render gives the same bytes at every lane width, through a tree
/// built in RAM and through the tree baked for flash, pinned by the digest every board prints.
#[test]
fn bunny_fw_render_is_pinned_at_every_width_and_layout() {
    use raylane::bvh::bake::{Baked, bake};
    use raylane::bvh::{self, Node, Packed, Scratch, Tri4};
    use raylane::mesh::Mesh;
    use raylane::triangle::Triangle;
    use raylane::{Pinhole, Query};
    use raylane_lab::demo::bunny;
    let bin = include_bytes!("../../data/bunny.bin");
    let mut tris = vec![Triangle::never(); bunny::TRIANGLES];
    assert_eq!(bunny::load(bin, &mut tris), Some(bunny::TRIANGLES));
    assert_eq!(bunny::load(&bin[..bin.len() - 1], &mut tris), None);
    assert_eq!(bunny::load(bin, &mut tris[..10]), None);
    let need = bvh::TriangleBvh::needed(tris.len());
    let mut nodes = vec![Node::EMPTY; need.nodes];
    let mut leaves = vec![<Tri4 as Packed>::EMPTY; need.leaves];
    let mut scratch = vec![Scratch::default(); need.scratch];
    let tree =
        bvh::Bvh::build(&tris[..], &mut nodes[..], &mut leaves[..], &mut scratch[..]).unwrap();
    let m = crate::sets::bunny_visible_surface::load_bin(bin);
    let baked_bytes = bake(&Mesh::new(&m.pos, &m.idx)).unwrap();
    let baked = Baked::open(&baked_bytes).unwrap();
    let (w, h) = bunny::SIZE;
    let cam = bunny::camera(&tris, w, h);
    let from_baked = bunny::camera_of(
        (0..baked.len()).filter_map(|i| baked.get(i)).map(|t| t.1),
        w,
        h,
    );
    assert_eq!(format!("{cam:?}"), format!("{from_baked:?}"));
    fn image<L: raylane::Lane<Scalar = f32>, Q: Query + ?Sized>(q: &Q, cam: &Pinhole) -> Vec<u8> {
        let (w, h) = (cam.width, cam.height);
        let mut rgb = vec![0u8; 3 * (w * h) as usize];
        assert_eq!(bunny::render::<L, Q>(q, cam, &mut rgb), Some(979));
        assert_eq!(bunny::render::<L, Q>(q, cam, &mut rgb[1..]), None);
        rgb
    }
    let one = image::<f32, _>(&tree, &cam);
    assert_eq!(demo::fnv1a(&one), 0xc4c0_3850_74ed_2589);
    assert_eq!(image::<f32x4, _>(&tree, &cam), one);
    assert_eq!(image::<f32x8, _>(&tree, &cam), one);
    assert_eq!(image::<f32x16, _>(&tree, &cam), one);
    assert_eq!(image::<f32, _>(&baked, &cam), one);
    assert_eq!(image::<f32x4, _>(&baked, &cam), one);
    assert_eq!(image::<f32x8, _>(&baked, &cam), one);
    assert_eq!(image::<f32x16, _>(&baked, &cam), one);
}
