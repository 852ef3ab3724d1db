//! The precision envelope of every sphere method in f32, plotted to `docs/precision.svg`.
//!
//! ```text
//! cargo run --release -p raylane-tools --example precision [-- --rays N] [--out FILE]
//! ```
//!
//! For c/r = 2^4, 2^4.5, …, 2^24 it draws `N` seeded rays (default 50,000): a random eye
//! (a quarter of them at the origin, the rest in [−10, 10]³), a random unit direction (f32
//! `normalize`), a radius in [0.01, 10] and a sphere whose centre lies `c` along the ray and
//! `l` to its side, with the miss distance `l` uniform in [0, 2r] — so half the rays hit, and
//! the fraction of rays within `δ` of the rim is `δ/2r`. Each ray is decided by `quadratic`,
//! `quadratic-unit`, `geometric`, `robust`, `focal` and `focal-unguarded` (one ray at a time,
//! the scalar `f32` lane; every packet width gives the same bits) and compared with the exact
//! answer for the f32 inputs.
//!
//! **Exact answers.** The ray hits when its line passes closer than `r` to the centre (the
//! sphere lies far ahead of the eye): the sign of `S = r²|d|² − |T × d|²` with `T = C − E`.
//! Every input is an f32, i.e. an integer times a power of two, so `S` is computed exactly in
//! big integers (`num-bigint`): no rounding at all. Rays with `S = 0` would be excluded (none
//! occur).
//!
//! The plot also shows, dashed, the fraction of rays whose exact answer could change under
//! 2-ulp moves of the inputs (the band `tests/suite/kernels/focal_sphere_guard.rs` excludes): where a
//! method's curve meets it, its errors are as large as the inputs' own rounding.

use std::cmp::Ordering;
use std::path::PathBuf;

use glam::Vec3;
use num_bigint::BigInt;
use plotters::prelude::*;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::sphere::focal::{Focal, FocalKernel, FocalUnguarded};
use raylane::sphere::{
    FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Sphere, SphereKernel, SpherePacket,
};
use raylane::{Ray, RayPacket};

const METHODS: [&str; 6] = [
    "quadratic",
    "quadratic-unit",
    "geometric",
    "robust",
    "focal",
    "focal-unguarded",
];

/// An exact dyadic rational `m·2^e`.
#[derive(Clone, Debug)]
struct Dy {
    m: BigInt,
    e: i32,
}

impl Dy {
    /// The exact value of a finite f32.
    fn of(x: f32) -> Dy {
        let x = x as f64; // exact, and normal in f64
        if x == 0.0 {
            return Dy {
                m: BigInt::from(0),
                e: 0,
            };
        }
        let bits = x.to_bits();
        let e = ((bits >> 52) & 0x7ff) as i32 - 1075;
        let m = ((bits & ((1u64 << 52) - 1)) | (1u64 << 52)) as i64;
        Dy {
            m: BigInt::from(if x < 0.0 { -m } else { m }),
            e,
        }
    }

    /// Both mantissas at the smaller exponent.
    fn align(&self, o: &Dy) -> (BigInt, BigInt, i32) {
        let e = self.e.min(o.e);
        (
            &self.m << (self.e - e) as usize,
            &o.m << (o.e - e) as usize,
            e,
        )
    }

    fn add(&self, o: &Dy) -> Dy {
        let (a, b, e) = self.align(o);
        Dy { m: a + b, e }
    }

    fn sub(&self, o: &Dy) -> Dy {
        let (a, b, e) = self.align(o);
        Dy { m: a - b, e }
    }

    fn mul(&self, o: &Dy) -> Dy {
        Dy {
            m: &self.m * &o.m,
            e: self.e + o.e,
        }
    }

    fn sign(&self) -> Ordering {
        self.m.sign().cmp(&num_bigint::Sign::NoSign)
    }
}

/// The exact answer (true: the line passes closer than `r` to the centre), or `None` on the
/// rim itself.
fn exact(eye: Vec3, dir: Vec3, c: Vec3, r: f32) -> Option<bool> {
    let t: Vec<Dy> = (0..3).map(|i| Dy::of(c[i]).sub(&Dy::of(eye[i]))).collect();
    let d: Vec<Dy> = (0..3).map(|i| Dy::of(dir[i])).collect();
    let cross = [
        t[1].mul(&d[2]).sub(&t[2].mul(&d[1])),
        t[2].mul(&d[0]).sub(&t[0].mul(&d[2])),
        t[0].mul(&d[1]).sub(&t[1].mul(&d[0])),
    ];
    let sq = |v: &[Dy]| v[0].mul(&v[0]).add(&v[1].mul(&v[1])).add(&v[2].mul(&v[2]));
    let r = Dy::of(r);
    let s = r.mul(&r).mul(&sq(&d)).sub(&sq(&cross));
    match s.sign() {
        Ordering::Greater => Some(true),
        Ordering::Less => Some(false),
        Ordering::Equal => None,
    }
}

fn ulp(x: f32) -> f64 {
    let a = x.abs();
    if a == 0.0 {
        f64::from(f32::from_bits(1))
    } else {
        f64::from(a.next_up()) - f64::from(a)
    }
}

/// True when 2-ulp moves of the inputs could change the answer (first-order bound on
/// `r² − l²`, as in `tests/suite/kernels/focal_sphere_guard.rs`).
fn in_band(eye: Vec3, dir: Vec3, c: Vec3, r: f32) -> bool {
    let e = [eye.x as f64, eye.y as f64, eye.z as f64];
    let u = [dir.x as f64, dir.y as f64, dir.z as f64];
    let t = [c.x as f64 - e[0], c.y as f64 - e[1], c.z as f64 - e[2]];
    let n = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let uh = [u[0] / n, u[1] / n, u[2] / n];
    let s = t[0] * uh[0] + t[1] * uh[1] + t[2] * uh[2];
    let p = [t[0] - s * uh[0], t[1] - s * uh[1], t[2] - s * uh[2]];
    let d = (r as f64) * (r as f64) - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    let mut band = 2.0 * r as f64 * 2.0 * ulp(r);
    for i in 0..3 {
        band += 2.0 * p[i].abs() * 2.0 * (ulp(c[i]) + ulp(eye[i]));
        band += 2.0 * (s * p[i] / n).abs() * 2.0 * ulp(dir[i]);
    }
    d.abs() <= 1.5 * band
}

/// One seeded ray and sphere at c/r = `ratio`, miss distance uniform in [0, 2r].
fn case(rng: &mut SmallRng, ratio: f64) -> (Vec3, Vec3, Sphere) {
    let eye = if rng.random_range(0..4) == 0 {
        Vec3::ZERO
    } else {
        Vec3::new(
            rng.random_range(-10.0..10.0),
            rng.random_range(-10.0..10.0),
            rng.random_range(-10.0..10.0),
        )
    };
    let dir = loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if (0.01..=1.0).contains(&v.length_squared()) {
            break v.normalize();
        }
    };
    let r = rng.random_range(0.01..10.0f32);
    let side = dir.any_orthonormal_vector();
    let side = (side * rng.random_range(-1.0..1.0f32)
        + dir.cross(side) * rng.random_range(-1.0..1.0f32))
    .normalize();
    let l = rng.random_range(0.0..2.0f32);
    let dist = (r as f64 * ratio) as f32;
    (eye, dir, Sphere::new(eye + dir * dist + side * (l * r), r))
}

/// Each method's answer (hit or miss) for one ray.
fn answers(eye: Vec3, dir: Vec3, s: &Sphere) -> [bool; 6] {
    let rp = RayPacket::<f32>::splat(&Ray::new(eye, dir));
    let sp = SpherePacket::splat(s);
    [
        Quadratic::roots(&rp, &sp).any(),
        QuadraticUnit::roots(&rp, &sp).any(),
        Geometric::roots(&rp, &sp).any(),
        Robust::roots(&rp, &sp).any(),
        Focal::roots(&rp, &FocalSphere::splat(&FocalSphere::new(eye, s))).any(),
        FocalUnguarded::roots(&rp, &FocalSphere::splat(&FocalSphere::unguarded(eye, s))).any(),
    ]
}

struct Row {
    log2: f64,
    rays: usize,
    wrong: [usize; 6],
    band: usize,
}

fn superscript(k: i32) -> String {
    let digits = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    format!(
        "2{}",
        k.to_string()
            .chars()
            .map(|c| digits[c as usize - '0' as usize])
            .collect::<String>()
    )
}

fn plot(rows: &[Row], out: &PathBuf) -> Result<(), Box<dyn std::error::Error>> {
    let floor = 1e-5;
    let root = SVGBackend::new(out, (960, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let n = rows.first().map_or(0, |r| r.rays);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "Sphere hit/miss in f32: misclassified rays ({n} per point, miss distance uniform in [0, 2r])"
            ),
            ("sans-serif", 24),
        )
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(4.0f64..24.0f64, (floor..1.0f64).log_scale())?;
    chart
        .configure_mesh()
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 16))
        .x_desc("c/r: distance from the ray origin to the centre, in radii")
        .y_desc("misclassified rays (log scale; none: on the bottom edge)")
        .x_labels(11)
        .x_label_formatter(&|x| superscript(x.round() as i32))
        .y_label_formatter(&|y| {
            let pct = 100.0 * y;
            if *y <= floor * 1.0001 {
                "0".to_string()
            } else if pct >= 1.0 {
                format!("{pct:.0} %")
            } else {
                format!("{} %", format!("{pct:.3}").trim_end_matches('0'))
            }
        })
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    let colors = [
        RGBColor(214, 39, 40),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
        RGBColor(140, 86, 75),
    ];
    let at = |w: usize, n: usize| (w as f64 / n.max(1) as f64).max(floor);
    let band: Vec<(f64, f64)> = rows.iter().map(|r| (r.log2, at(r.band, r.rays))).collect();
    chart
        .draw_series(DashedLineSeries::new(
            band,
            6,
            4,
            ShapeStyle::from(&RGBColor(120, 120, 120)).stroke_width(2),
        ))?
        .label("2-ulp input band")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(120, 120, 120)));
    for (k, name) in METHODS.iter().enumerate() {
        let c = colors[k];
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (r.log2, at(r.wrong[k], r.rays)))
            .collect();
        // focal sits on the bottom edge: draw it thicker, last, so it stays visible.
        let width = if *name == "focal" { 4 } else { 2 };
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(width)))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut rays = 50_000usize;
    let mut out = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/precision.svg"
    ));
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rays" => rays = args.next().ok_or("--rays N")?.parse()?,
            "--out" => out = args.next().ok_or("--out FILE")?.into(),
            _ => return Err(format!("unknown argument {a}").into()),
        }
    }
    println!(
        "c/r      rays   {}   2-ulp band",
        METHODS.map(|m| format!("{m:>16}")).join("")
    );
    let mut rows = Vec::new();
    for half in 8..=48u32 {
        let log2 = half as f64 / 2.0;
        let mut rng = SmallRng::seed_from_u64(0x5eed_0000 + half as u64);
        let mut row = Row {
            log2,
            rays: 0,
            wrong: [0; 6],
            band: 0,
        };
        for _ in 0..rays {
            let (eye, dir, s) = case(&mut rng, log2.exp2());
            let Some(want) = exact(eye, dir, s.center(), s.radius()) else {
                continue;
            };
            row.rays += 1;
            row.band += in_band(eye, dir, s.center(), s.radius()) as usize;
            for (w, got) in row.wrong.iter_mut().zip(answers(eye, dir, &s)) {
                *w += (got != want) as usize;
            }
        }
        println!(
            "2^{log2:<5} {:6} {} {:12.5}",
            row.rays,
            row.wrong
                .map(|w| format!("{:16.5}", w as f64 / row.rays as f64))
                .join(""),
            row.band as f64 / row.rays as f64
        );
        rows.push(row);
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    plot(&rows, &out)?;
    println!(
        "wrote {}",
        std::fs::canonicalize(&out).unwrap_or(out).display()
    );
    Ok(())
}
