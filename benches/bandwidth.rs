//! What a second core adds on this machine: the ceiling of the speedup from 1 to 2 ranks for
//! work that streams through memory, beside work that does not.
//!
//! # What is measured
//!
//! - `triad`: `c = a + 1.5 b` over arrays of [`TRIAD_LEN`] doubles (320 MB each, far beyond
//!   any cache), [`TRIAD_SWEEPS`] sweeps: memory bound, like the sparse matrix products, the
//!   multigrid's smoothers and the copies of field matrices of the iterative path.
//! - `compute`: eight independent chains of multiply-adds in registers, [`COMPUTE_STEPS`]
//!   steps in all: bound by the core alone.
//!
//! Each is run on one thread alone, then on two threads at once (each with its own arrays),
//! alternated over [`ROUNDS`] rounds. Printed per kernel: the median throughput of one thread
//! alone and of each of two at once (GB/s for the triad, counting three arrays of traffic per
//! sweep; Gflop/s for the loop), and the speedup `2 t_1 / t_2` that two ranks could reach on
//! it (2.0: the second core doubles the throughput; below 1: two together are slower than
//! one). Threads share the memory system as two ranks on the machine do.
//!
//! Run: `cargo bench --bench bandwidth` (about 15 s; 2 GB of memory).

use std::hint::black_box;
use std::thread;
use std::time::Instant;

/// Doubles per triad array.
const TRIAD_LEN: usize = 40_000_000;
/// Sweeps of the triad per timing.
const TRIAD_SWEEPS: usize = 10;
/// Multiply-add steps of the compute loop per timing.
const COMPUTE_STEPS: usize = 400_000_000;
/// Alternated rounds (one thread, then two) per kernel.
const ROUNDS: usize = 5;

/// Seconds of one triad timing over its own arrays.
fn triad() -> f64 {
    let a = vec![1.0_f64; TRIAD_LEN];
    let b = vec![2.0_f64; TRIAD_LEN];
    let mut c = vec![0.5_f64; TRIAD_LEN];
    let started = Instant::now();
    for _ in 0..TRIAD_SWEEPS {
        for ((c, a), b) in c.iter_mut().zip(&a).zip(&b) {
            *c = a + 1.5 * b;
        }
        black_box(&mut c);
    }
    started.elapsed().as_secs_f64()
}

/// Seconds of one compute timing: eight independent multiply-add chains.
fn compute() -> f64 {
    let mut x = black_box([1.0_f64, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7]);
    let (scale, shift) = black_box((0.999_999_9, 1e-7));
    let started = Instant::now();
    for _ in 0..COMPUTE_STEPS / x.len() {
        for v in &mut x {
            *v = *v * scale + shift;
        }
    }
    black_box(x);
    started.elapsed().as_secs_f64()
}

/// The seconds of `kernel` alone and of each of two at once (the slower), one per round.
fn timings(kernel: fn() -> f64) -> (Vec<f64>, Vec<f64>) {
    let (mut alone, mut together) = (Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        alone.push(kernel());
        let pair = thread::scope(|s| {
            let one = s.spawn(kernel);
            let two = s.spawn(kernel);
            [one.join(), two.join()]
        });
        let slower = pair
            .into_iter()
            .map(|t| t.expect("bench thread"))
            .fold(0.0, f64::max);
        together.push(slower);
    }
    (alone, together)
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Prints one kernel's line: `work` units per timing, named `unit`.
fn report(name: &str, kernel: fn() -> f64, work: f64, unit: &str) {
    let (alone, together) = timings(kernel);
    let (t1, t2) = (median(alone), median(together));
    println!(
        "{name:<8} one thread {:>7.2} {unit}   each of two {:>7.2} {unit}   speedup 2 t1 / t2 = {:.2}",
        work / t1,
        work / t2,
        2.0 * t1 / t2
    );
}

fn main() {
    // `cargo test --benches` runs bench targets with `--bench` absent: do nothing then.
    if !std::env::args().any(|a| a == "--bench") {
        return;
    }
    let triad_bytes = (3 * 8 * TRIAD_LEN * TRIAD_SWEEPS) as f64 / 1e9;
    report("triad", triad, triad_bytes, "GB/s");
    report(
        "compute",
        compute,
        2.0 * COMPUTE_STEPS as f64 / 1e9,
        "Gflop/s",
    );
}
