//! Every raylane kernel at every lane width, in tests per second:
//!
//! ```text
//! cargo bench -p raylane-bench --bench kernels                 # the whole matrix (~5 min)
//! cargo bench -p raylane-bench --bench kernels -- triangles/   # a criterion filter
//! ```
//!
//! Groups `kernels/{spheres,triangles,planes}/{coherent,incoherent}/N={16,64,256,1024}`, one
//! benchmark per kernel and width (`x1`, `x4`, `x8`, `x16`): closest hits of ray packets over
//! the slice (N rays × 1 primitive). At N = 256 also the other shape, one ray over primitives
//! packed in lanes (`xW-soa`). Focal kernels run on coherent rays only (they need rays from
//! the camera's eye). Every frame is about 2^18 ray–primitive tests; throughput is in tests.
//!
//! Before timing, each kernel's hit count at every width and shape is checked against its
//! scalar packets (bit-exact lanes are the crate's own tests; this guards the harness).
//!
//! The summary after criterion's report tabulates tests/s per kernel × width (N = 256) and
//! per kernel × N (x8).

mod common;

use common::{records, si, timed};
use criterion::{Criterion, Throughput};
use raylane::Lane;
use raylane_bench::{
    BenchKernel, Frame, Kernel, Lanes, Prim, Rays, SIZES, Shape, WIDTHS, cpu, run,
};

/// N of the width and shape table.
const TABLE_N: usize = 256;

fn group(prim: Prim, kind: Rays, n: usize) -> String {
    format!("kernels/{}/{}/N={n}", prim.plural(), kind.name())
}

fn id(k: Kernel, w: usize, shape: Shape) -> String {
    format!("{} x{w}{}", k.name(), shape.suffix())
}

fn bench_width<L: Lane<Scalar = f32>>(
    c: &mut Criterion,
    f: &Frame,
    prim: Prim,
    reference: &[(Kernel, u32)],
) {
    let lanes = Lanes::<L>::new(f, f.n);
    let name = group(prim, f.kind, f.n);
    let mut g = c.benchmark_group(&name);
    let tests = f.tests() as u64;
    g.throughput(Throughput::Elements(tests));
    for &(k, want) in reference {
        let mut shapes = vec![Shape::Packets];
        if f.n == TABLE_N && k.has_soa() {
            shapes.push(Shape::Soa);
        }
        for shape in shapes {
            let got = run(k, shape, f, &lanes);
            assert_eq!(
                got,
                want,
                "{name}: {} hits {got} rays, scalar packets {want}",
                id(k, L::LANES, shape)
            );
            let bid = id(k, L::LANES, shape);
            g.bench_function(&bid, |b| {
                timed(b, (&name, &bid), tests, f.rays.len() as u64, || {
                    run(k, shape, f, &lanes)
                })
            });
        }
    }
    g.finish();
}

fn main() {
    let mut c = common::criterion(400);
    println!("CPU: {}", cpu());
    for prim in [Prim::Sphere, Prim::Triangle, Prim::Plane] {
        for kind in [Rays::Coherent, Rays::Incoherent] {
            for n in SIZES {
                let f = Frame::new(n, kind);
                let kernels: Vec<Kernel> = Kernel::ALL
                    .into_iter()
                    .filter(|k| k.prim() == prim && k.runs_on(kind))
                    .collect();
                let l1 = Lanes::<f32>::new(&f, n);
                let reference: Vec<(Kernel, u32)> = kernels
                    .iter()
                    .map(|&k| (k, run(k, Shape::Packets, &f, &l1)))
                    .collect();
                for w in WIDTHS {
                    raylane_bench::with_width!(w, L => bench_width::<L>(&mut c, &f, prim, &reference));
                }
            }
        }
    }
    c.final_summary();
    summary();
}

fn summary() {
    let recs = records();
    if recs.is_empty() {
        return;
    }
    let get = |g: &str, id: &str| recs.get(&(g.to_string(), id.to_string()));
    println!("\n## Every kernel at every width\n");
    println!("CPU: {}\n", cpu());
    println!(
        "Ray–primitive tests per second, closest hit over N = {TABLE_N} primitives \
         ({s}×{s} rays). `xW`: packets of W rays over the slice (N rays × 1 primitive); \
         `xW-soa`: one ray over primitives packed W to a lane value (1 ray × N).\n",
        s = raylane_bench::image_side(TABLE_N)
    );
    let mut head = String::from("| kernel | rays |");
    let mut rule = String::from("| --- | --- |");
    for shape in [Shape::Packets, Shape::Soa] {
        for w in WIDTHS {
            head += &format!(" x{w}{} |", shape.suffix());
            rule += " ---: |";
        }
    }
    println!("{head}\n{rule}");
    for kind in [Rays::Coherent, Rays::Incoherent] {
        for k in Kernel::ALL {
            let g = group(k.prim(), kind, TABLE_N);
            let mut row = format!("| {} | {} |", k.name(), kind.name());
            let mut any = false;
            for shape in [Shape::Packets, Shape::Soa] {
                for w in WIDTHS {
                    match get(&g, &id(k, w, shape)) {
                        Some(r) => {
                            row += &format!(" {} |", si(r.tests_per_sec()));
                            any = true;
                        }
                        None => row += " — |",
                    }
                }
            }
            if any {
                println!("{row}");
            }
        }
    }
    println!("\n### x8 packets over N\n");
    println!("Tests per second (rays per second = tests/s ÷ N).\n");
    let mut head = String::from("| kernel | rays |");
    let mut rule = String::from("| --- | --- |");
    for n in SIZES {
        head += &format!(" N={n} |");
        rule += " ---: |";
    }
    println!("{head}\n{rule}");
    for kind in [Rays::Coherent, Rays::Incoherent] {
        for k in Kernel::ALL {
            let mut row = format!("| {} | {} |", k.name(), kind.name());
            let mut any = false;
            for n in SIZES {
                match get(&group(k.prim(), kind, n), &id(k, 8, Shape::Packets)) {
                    Some(r) => {
                        row += &format!(" {} |", si(r.tests_per_sec()));
                        any = true;
                    }
                    None => row += " — |",
                }
            }
            if any {
                println!("{row}");
            }
        }
    }
}
