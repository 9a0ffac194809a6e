//! Rough contact search: [`candidate_pairs`] between two facing flat surfaces.
//!
//! # What is measured
//!
//! Two flat square surfaces of side 1 face each other across a small gap, each meshed with about
//! `n` bilinear quadrilateral segments, `n` = 1e3, 1e4, 1e5:
//!
//! - secondary: `k x k` squares in the plane `z = 0`, `k = round(sqrt(n))`;
//! - primary: a `(k + 1) x (k - 1)` grid of the same square, rotated by 2 degrees about its
//!   centre (in plane) and lifted to `z = gap`, so that no grid line of one side coincides with
//!   one of the other and the primary boxes are not aligned with the secondary ones.
//!
//! Every segment's box is the box of its four corners ([`Aabb::of_points`]); the search distance
//! is `margin = 0.1 h` with `h = 1 / k` and the gap `0.05 h`, so each secondary segment has a few
//! (about five) candidates. Boxes are built outside the timed loop.
//!
//! - `search_candidate_pairs/<n>`: one call of [`candidate_pairs`] (tree bulk-loaded over the
//!   primary boxes, one query per secondary box, sorted output), what a fresh search costs.
//! - `search_query/<n>`: the queries only, against a [`PrimaryTree`] built once (what a search
//!   reusing its tree costs).
//!
//! Criterion's throughput (`Throughput::Elements(n)`, `n` the number of secondary segments) is
//! printed in segments per second.
//!
//! # Scaling report
//!
//! After the criterion benchmarks, in bench mode only (`cargo bench`, not `cargo test`) and only
//! if the name filter selected a `search_candidate_pairs` benchmark, the bench times
//! [`candidate_pairs`] and [`PrimaryTree::new`] itself (median of repeated calls) and prints to
//! stderr a plain-text table: time per call, time per secondary segment, `t / (n ln n)` (about
//! constant if the search is `O(n log n)`), and the least-squares slope of `ln t` against `ln n`
//! (1 for linear; `n ln n` over 1e3..1e5 shows as slightly above 1, about 1.11).
//!
//! Run: `cargo bench --bench search -- --warm-up-time 1 --measurement-time 3` (or
//! `benches/report.sh`).

use std::hint::black_box;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use criterion::{criterion_group, BenchmarkId, Criterion, SamplingMode, Throughput};

use mortar::contact::search::{candidate_pairs, Aabb, PrimaryTree};

/// Set when criterion runs a `search_candidate_pairs` benchmark (not filtered out, not `--list`).
static SEARCH_RAN: AtomicBool = AtomicBool::new(false);

/// Numbers of segments per side.
const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

/// The two surfaces of one problem size, as segment boxes.
struct Surfaces {
    secondary: Vec<Aabb>,
    primary: Vec<Aabb>,
    margin: f64,
}

/// Boxes of the `nx x ny` quadrilaterals of the unit square, each corner mapped by `map`.
fn grid_boxes(nx: usize, ny: usize, map: impl Fn(f64, f64) -> [f64; 3]) -> Vec<Aabb> {
    let mut boxes = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let corner = |a: usize, b: usize| map(a as f64 / nx as f64, b as f64 / ny as f64);
            boxes.push(Aabb::of_points(&[
                corner(i, j),
                corner(i + 1, j),
                corner(i + 1, j + 1),
                corner(i, j + 1),
            ]));
        }
    }
    boxes
}

/// The two facing surfaces for about `n` segments per side.
fn surfaces(n: usize) -> Surfaces {
    let k = (n as f64).sqrt().round() as usize;
    let h = 1.0 / k as f64;
    let gap = 0.05 * h;
    let (sin, cos) = 2.0f64.to_radians().sin_cos();
    let secondary = grid_boxes(k, k, |x, y| [x, y, 0.0]);
    let primary = grid_boxes(k + 1, k - 1, |x, y| {
        let (u, v) = (x - 0.5, y - 0.5);
        [0.5 + cos * u - sin * v, 0.5 + sin * u + cos * v, gap]
    });
    Surfaces {
        secondary,
        primary,
        margin: 0.1 * h,
    }
}

fn search(c: &mut Criterion) {
    let cases: Vec<Surfaces> = SIZES.iter().map(|&n| surfaces(n)).collect();

    let mut group = c.benchmark_group("search_candidate_pairs");
    for (&n, s) in SIZES.iter().zip(&cases) {
        group.throughput(Throughput::Elements(s.secondary.len() as u64));
        if n >= 100_000 {
            group.sampling_mode(SamplingMode::Flat);
        }
        group.bench_with_input(BenchmarkId::from_parameter(n), s, |b, s| {
            SEARCH_RAN.store(true, Ordering::Relaxed);
            b.iter(|| {
                candidate_pairs(black_box(&s.secondary), black_box(&s.primary), s.margin).len()
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("search_query");
    for (&n, s) in SIZES.iter().zip(&cases) {
        group.throughput(Throughput::Elements(s.secondary.len() as u64));
        if n >= 100_000 {
            group.sampling_mode(SamplingMode::Flat);
        }
        let tree = PrimaryTree::new(&s.primary);
        group.bench_with_input(BenchmarkId::from_parameter(n), s, |b, s| {
            let mut out = Vec::new();
            b.iter(|| {
                let mut hits = 0;
                for q in black_box(&s.secondary) {
                    tree.query(&q.inflated(s.margin), &mut out);
                    hits += out.len();
                }
                hits
            })
        });
    }
    group.finish();
}

/// Median wall time of `f`, over at least 5 calls and about `budget` in total (at most 1000).
fn median_time<R>(budget: Duration, mut f: impl FnMut() -> R) -> f64 {
    black_box(f());
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 5 || (start.elapsed() < budget && times.len() < 1000) {
        let t = Instant::now();
        black_box(f());
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Least-squares slope of `y` against `x`.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let m = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / m, y.iter().sum::<f64>() / m);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

fn format_time(s: f64) -> String {
    for (unit, scale) in [("s", 1.0), ("ms", 1e-3), ("us", 1e-6)] {
        if s >= scale {
            return format!("{:.3} {unit}", s / scale);
        }
    }
    format!("{:.1} ns", s * 1e9)
}

/// The plain-text scaling report (stderr).
fn report() {
    let budget = Duration::from_secs(1);
    eprintln!();
    eprintln!("search scaling report: candidate_pairs, two facing flat quad surfaces");
    eprintln!("(median of repeated calls; n = secondary segments, m = primary segments)");
    eprintln!(
        "{:>8} {:>8} {:>8} {:>9} {:>11} {:>11} {:>11} {:>14} {:>16}",
        "n",
        "m",
        "pairs",
        "pairs/seg",
        "t total",
        "t build",
        "t/segment",
        "t/(n ln n)",
        "total-build /n"
    );
    let (mut ln_n, mut ln_t) = (Vec::new(), Vec::new());
    for &size in &SIZES {
        let s = surfaces(size);
        let n = s.secondary.len();
        let pairs = candidate_pairs(&s.secondary, &s.primary, s.margin).len();
        assert!(
            pairs >= n,
            "every secondary segment should have a candidate"
        );
        let t = median_time(budget, || {
            candidate_pairs(&s.secondary, &s.primary, s.margin).len()
        });
        let t_build = median_time(budget, || PrimaryTree::new(&s.primary).len());
        let nf = n as f64;
        eprintln!(
            "{:>8} {:>8} {:>8} {:>9.2} {:>11} {:>11} {:>11} {:>14} {:>16}",
            n,
            s.primary.len(),
            pairs,
            pairs as f64 / nf,
            format_time(t),
            format_time(t_build),
            format_time(t / nf),
            format_time(t / (nf * nf.ln())),
            format_time((t - t_build) / nf),
        );
        ln_n.push(nf.ln());
        ln_t.push(t.ln());
    }
    eprintln!(
        "fitted exponent (least-squares slope of ln t vs ln n): {:.3}",
        slope(&ln_n, &ln_t)
    );
    let consecutive: Vec<String> = (1..ln_n.len())
        .map(|i| format!("{:.3}", (ln_t[i] - ln_t[i - 1]) / (ln_n[i] - ln_n[i - 1])))
        .collect();
    eprintln!(
        "slopes between consecutive sizes: {}",
        consecutive.join(", ")
    );
    let nlogn: Vec<f64> = ln_n.iter().map(|l| l + l.ln()).collect();
    eprintln!(
        "reference: pure n ln n over these sizes has slope {:.3}",
        slope(&ln_n, &nlogn)
    );
}

criterion_group!(benches, search);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    // Bench mode only (`cargo test --benches` runs each benchmark once without `--bench`), and
    // only if a name filter left a `search_candidate_pairs` benchmark in.
    if std::env::args().any(|a| a == "--bench") && SEARCH_RAN.load(Ordering::Relaxed) {
        report();
    }
}
