//! One whole load step of a finite-strain scene: [`mortar::solver::run`] with a single step.
//!
//! # What is measured
//!
//! A Neo-Hookean Hex8 box `[0, 1]^3` of 8x8x8 elements (729 nodes, 1863 free dofs), `zmin`
//! clamped, compressed by 10% in one load step (a prescribed `u_z = -0.1` on `zmax`, lateral
//! motion free). One benchmark iteration is a complete [`run`] of that scene on one rank:
//!
//! - setup: dof numbering, sparsity, PETSc matrix and vectors, SNES (Newton with a direct solve,
//!   the project default: MUMPS LU);
//! - the Newton solve of the step: residual and tangent assembly, factorization and solve per
//!   iteration;
//! - output: reactions, history, the final displacements, metrics and `summary.json`, plus the
//!   VTU/PVTU/PVD files in the `vtu` variant.
//!
//! Benchmarks:
//!
//! - `newton_step/hex8_8x8x8/novtu`: `[output] vtu_every = 0` (no VTU: the solve and its setup);
//! - `newton_step/hex8_8x8x8/vtu`: `vtu_every = 1` (the VTU of the step is written too).
//!
//! The Newton iteration count of the step is printed on stderr as
//! `newton-its <benchmark id> <iterations>` (with the per-phase wall times of the last run), so
//! the time per Newton iteration is the step time divided by it (`benches/report.sh` does this).
//!
//! # One MPI per process
//!
//! MPI can be initialized only once per process, so this bench has its own `main`: one [`Petsc`]
//! guard for the whole process, created before the benchmarks and dropped after the last one.
//! The case files and the outputs live in a fresh folder under [`std::env::temp_dir`], removed
//! at the end.
//!
//! Calling [`run`] repeatedly in one process needs `run` to be re-entrant. The first benchmark
//! therefore probes with two runs: if the second fails (PETSc 3.18 refuses to register the log
//! stages of `run` a second time, "Duplicate stage name given"), the bench says so on stderr and
//! falls back to timing each iteration in a child process (this executable, re-run in worker
//! mode with its own MPI and PETSc). Either way only the call to [`run`] is timed (by the child
//! in the fallback, so process start and MPI/PETSc initialization are excluded); a child's run
//! is the first of its process, so its caches are cold.
//!
//! Run: `cargo bench --bench newton -- --noplot` (or `benches/report.sh`).

use std::cell::{OnceCell, RefCell};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion};

use mortar::case::Scene;
use mortar::io::output::Summary;
use mortar::petsc::Petsc;
use mortar::solver::{run, RunOptions};

/// Elements per axis of the box.
const DIVISIONS: usize = 8;

/// Environment variable that turns this executable into a worker: its value is the case file to
/// run once (see [`worker`]).
const WORKER_CASE: &str = "MORTAR_BENCH_NEWTON_CASE";

/// Prefix of the worker's report line on stdout, followed by the seconds [`run`] took.
const WORKER_TAG: &str = "mortar-bench-worker";

/// The case file of the benchmark scene; `vtu_every` selects whether VTU files are written.
fn case_toml(vtu_every: usize) -> String {
    format!(
        r#"# Benchmark: Neo-Hookean Hex8 box compressed 10% in one load step.
name = "bench_newton_box"

[[mesh]]
body = "box"
generator = "box"
element = "hex8"
divisions = [{n}, {n}, {n}]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 1.0]

[[material]]
model = "neo_hookean"
young = 1000.0
poisson = 0.3

[[dirichlet]]
set = "box.zmin"
components = ["x", "y", "z"]

[[dirichlet]]
set = "box.zmax"
components = ["z"]
value = [-0.1]

[steps]
count = 1

[output]
vtu_every = {vtu_every}
"#,
        n = DIVISIONS
    )
}

/// Writes the case file for `vtu_every` into `dir`; returns its path.
fn write_case(dir: &Path, vtu_every: usize) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    let path = dir.join("case.toml");
    std::fs::write(&path, case_toml(vtu_every))
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
    path
}

/// The output folder of a case: `out` next to the case file.
fn out_dir(case: &Path) -> PathBuf {
    case.parent().unwrap_or(Path::new(".")).join("out")
}

/// How each benchmark iteration runs the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    /// [`run`] in this process, with the bench's [`Petsc`].
    InProcess,
    /// [`run`] in a child process (this executable in worker mode).
    Child,
}

/// Runs `scene` twice in this process: [`Mode::InProcess`] if both runs succeed,
/// [`Mode::Child`] (with a warning) if only the first does.
///
/// # Panics
/// If the first run fails: the scene itself is broken.
fn probe(scene: &Scene, petsc: &Petsc, opts: &RunOptions) -> Mode {
    run(scene, petsc, opts).unwrap_or_else(|e| panic!("benchmark scene does not run: {e}"));
    match run(scene, petsc, opts) {
        Ok(_) => Mode::InProcess,
        Err(e) => {
            eprintln!(
                "warning: mortar::solver::run cannot run twice in one process ({e}); \
                 timing each run in a child process instead"
            );
            Mode::Child
        }
    }
}

/// Runs `case` in a child process; returns the time its [`run`] took and its summary.
fn run_child(case: &Path) -> (Duration, Summary) {
    let exe = std::env::current_exe().expect("path of the bench executable");
    let out = Command::new(exe)
        .env(WORKER_CASE, case)
        .output()
        .expect("cannot start the bench worker");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "bench worker failed on {}:\n{stdout}\n{}",
        case.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let seconds: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix(WORKER_TAG))
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("no '{WORKER_TAG} <seconds>' line in:\n{stdout}"));
    let summary_path = out_dir(case).join("summary.json");
    let summary = Summary::read(&summary_path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", summary_path.display()));
    (Duration::from_secs_f64(seconds), summary)
}

/// Worker mode: runs `case` once with a fresh MPI and PETSc and prints the seconds [`run`] took.
fn worker(case: &Path) {
    let petsc = Petsc::initialize(&["bench-worker".into()], None)
        .unwrap_or_else(|e| panic!("PETSc initialization failed: {e}"));
    let scene = Scene::load(case).unwrap_or_else(|e| panic!("benchmark scene does not load: {e}"));
    let opts = RunOptions::new(out_dir(case), true);
    let t = Instant::now();
    let summary = run(&scene, &petsc, &opts).unwrap_or_else(|e| panic!("run failed: {e}"));
    let seconds = t.elapsed().as_secs_f64();
    assert!(summary.converged, "the step did not converge");
    println!("{WORKER_TAG} {seconds:e}");
    drop(petsc);
}

/// Prints the Newton iterations of the runs of one benchmark and the phase times of the last.
fn report(id: &str, mode: Mode, its: &[usize], last: &Summary) {
    let (min, max) = (
        its.iter().copied().min().unwrap_or(0),
        its.iter().copied().max().unwrap_or(0),
    );
    if min != max {
        eprintln!("warning: {id}: Newton iterations varied between runs ({min}..{max})");
    }
    let phases: Vec<String> = last
        .timings
        .iter()
        .map(|(k, v)| format!("{k} {:.1} ms", 1e3 * v))
        .collect();
    eprintln!("newton-its {id} {max}");
    eprintln!(
        "  {id}: {max} Newton iterations per step, {} runs ({mode:?}); last run: {}",
        its.len(),
        phases.join(", ")
    );
}

/// Newton iterations of all steps of a run.
fn newton_its(summary: &Summary) -> usize {
    summary.steps.iter().map(|s| s.newton_its).sum()
}

fn newton_step(c: &mut Criterion, petsc: &Petsc, root: &Path) {
    let mode = OnceCell::new();
    let mut group = c.benchmark_group("newton_step");
    for (label, vtu_every) in [("novtu", 0), ("vtu", 1)] {
        let case = write_case(&root.join(label), vtu_every);
        let scene =
            Scene::load(&case).unwrap_or_else(|e| panic!("benchmark scene does not load: {e}"));
        let opts = RunOptions::new(out_dir(&case), true);
        let name = format!("hex8_{DIVISIONS}x{DIVISIONS}x{DIVISIONS}");
        let full_id = format!("newton_step/{name}/{label}");
        // Filled only when the benchmark actually runs (not for `--list` or a filtered-out id).
        let its = RefCell::new(Vec::new());
        let last = RefCell::new(None);
        let record = |summary: Summary| {
            assert!(summary.converged, "{full_id}: the step did not converge");
            its.borrow_mut().push(newton_its(&summary));
            *last.borrow_mut() = Some(summary);
        };
        group.bench_function(BenchmarkId::new(name, label), |b| {
            match *mode.get_or_init(|| probe(&scene, petsc, &opts)) {
                Mode::InProcess => b.iter(|| {
                    let summary = run(&scene, petsc, &opts)
                        .unwrap_or_else(|e| panic!("{full_id}: run failed: {e}"));
                    record(summary);
                }),
                Mode::Child => b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        let (elapsed, summary) = run_child(&case);
                        total += elapsed;
                        record(summary);
                    }
                    total
                }),
            }
        });
        if let (Some(summary), Some(&mode)) = (last.into_inner(), mode.get()) {
            report(&full_id, mode, &its.into_inner(), &summary);
        }
    }
    group.finish();
}

/// A fresh folder for the case files and outputs of this process.
fn work_dir() -> PathBuf {
    std::env::temp_dir().join(format!("mortar-bench-newton-{}", std::process::id()))
}

fn main() {
    if let Some(case) = std::env::var_os(WORKER_CASE) {
        worker(Path::new(&case));
        return;
    }
    let petsc = Petsc::initialize(&["bench".into()], None)
        .unwrap_or_else(|e| panic!("PETSc initialization failed: {e}"));
    // Each iteration is a full solve: few samples, short runs (command-line options override).
    let mut criterion = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5))
        .configure_from_args();
    let root = work_dir();
    newton_step(&mut criterion, &petsc, &root);
    criterion.final_summary();
    if let Err(e) = std::fs::remove_dir_all(&root) {
        eprintln!("warning: cannot remove {}: {e}", root.display());
    }
    // PETSc and MPI are finalized last, after every PETSc object is gone.
    drop(petsc);
}
