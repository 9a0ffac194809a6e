//! Checkpoints and restarts: a run killed (SIGKILL) in the middle of a step and restarted from
//! its last checkpoint ends with the same files, bit for bit, as the run that was never
//! stopped, on 1 and on 2 ranks; a restart that cannot go on (another case file, no
//! checkpoint, a truncated one, another rank count) says so in one line and touches nothing.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

/// On 2 ranks MUMPS's factorization is not reproducible from run to run (its dynamic
/// scheduling orders the sums differently): two runs that were never stopped differ at
/// round-off already. SuperLU_DIST's is, so the 2-rank comparison uses it.
const REPRODUCIBLE_ON_RANKS: &[&str] = &["-pc_factor_mat_solver_type", "superlu_dist"];

/// The steps between checkpoints that [`full_run`] tries, in order.
const CHECKPOINT_EVERY: std::ops::RangeInclusive<usize> = 2..=3;

/// A frictional slide (Hex8, mu 0.3) in 9 steps, of which some are cut (newton.max_it = 3)
/// and all augmented (Uzawa), with a checkpoint every `every` steps.
fn case(name: &str, linear_solver: &str, every: usize) -> PathBuf {
    let toml = common::slide_case(9)
        .replace("[3, 2, 1]", "[9, 6, 2]")
        .replace("[2, 2, 1]", "[6, 6, 2]")
        + &format!("[newton]\nmax_it = 3\nlinear_solver = \"{linear_solver}\"\n")
        + &format!("[output]\ncheckpoint_every = {every}\n");
    common::write_case(name, &toml)
}

fn args(ranks: usize) -> &'static [&'static str] {
    if ranks == 1 {
        &[]
    } else {
        REPRODUCIBLE_ON_RANKS
    }
}

/// Every file of a run's output folder (the checkpoints aside), by path relative to it; the
/// history without its timing columns, the summary without its timings and memory.
fn outputs(dir: &Path) -> BTreeMap<String, String> {
    let mut files = BTreeMap::new();
    for sub in ["", "vtu"] {
        for entry in std::fs::read_dir(dir.join(sub)).unwrap() {
            let path = entry.unwrap().path();
            if !path.is_file() || path.extension().is_some_and(|e| e == "lock") {
                continue;
            }
            let name = path.strip_prefix(dir).unwrap().display().to_string();
            let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
            let text = match name.as_str() {
                "history.csv" => without_timings(&text),
                "summary.json" => {
                    let mut s: serde_json::Value = serde_json::from_str(&text).unwrap();
                    let o = s.as_object_mut().unwrap();
                    for k in ["timings", "peak_memory_mb", "contact_seconds_per_rank"] {
                        o.remove(k);
                    }
                    s.to_string()
                }
                _ => text,
            };
            files.insert(name, text);
        }
    }
    files
}

/// Restarts `case` on `ranks` with `args` into `killed`, which must say it went on from the
/// checkpoint of `step` and end with the files of `full`.
fn restarted_matches(
    case: &Path,
    (ranks, args): (usize, &[&str]),
    killed: &Path,
    full: &Path,
    step: usize,
) {
    let out = common::run_raw(case, ranks, killed, args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let said = format!("restarted from the checkpoint of step {step} (");
    assert!(stdout.contains(&said), "{stdout}");
    assert_same_outputs(full, killed);
}

/// The runs in `full` and `restarted` left the same files with the same contents ([`outputs`]).
fn assert_same_outputs(full: &Path, restarted: &Path) {
    let (want, got) = (outputs(full), outputs(restarted));
    assert_eq!(
        want.keys().collect::<Vec<_>>(),
        got.keys().collect::<Vec<_>>()
    );
    for (name, text) in &want {
        assert!(text == &got[name], "{name} differs after the restart");
    }
}

/// The CSV without its `seconds_*` columns.
fn without_timings(csv: &str) -> String {
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !header[i].starts_with("seconds_"))
        .collect();
    csv.lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Runs the case into `out` and SIGKILLs it (rank 0 under mpirun, which then ends the job) in
/// the middle of step `step`, which the slide cuts: in the attempt that follows the first
/// progress line of that step (its cut).
fn run_and_kill(case: &Path, ranks: usize, out: &Path, step: usize) -> Output {
    let run = common::subcommand("run", case, ranks, out, args(ranks));
    let started = common::start_until(run, &format!("  step {step} "));
    started.signal(0, "KILL");
    started.finish()
}

/// The first checkpoint of the run in `full` after which the slide augments the next step
/// without a cut and then augments and cuts the step after: the steps redone after the
/// restart are augmented, the one killed is cut, and the first is not, so that its predictor
/// would reuse the factorization of the step before (module docs of `solver::checkpoint`).
fn checkpoint_before_a_cut(full: &Path, every: usize) -> Option<usize> {
    let history = common::History::read(full);
    let (cuts, augmentations) = (history.column("cuts"), history.column("augmentations"));
    let rows = history.rows();
    (every..rows.len() - 1).step_by(every).find(|&c| {
        // rows[c] is step c + 1.
        let (first, killed) = (&rows[c], &rows[c + 1]);
        first[augmentations] > 0.0
            && first[cuts] == 0.0
            && killed[augmentations] > 0.0
            && killed[cuts] > 0.0
    })
}

/// The slide's run never stopped, with the first spacing of checkpoints in
/// [`CHECKPOINT_EVERY`] that puts one before an augmented step and a cut one
/// ([`checkpoint_before_a_cut`]): which steps the slide cuts moves with every change of its
/// Newton path, and the spacing is part of the run (it goes on after a checkpoint with a new
/// Newton solver, as a restart does). Returns the case, the run's folder and the checkpoint.
fn full_run(ranks: usize, linear_solver: &str) -> (PathBuf, PathBuf, usize) {
    for every in CHECKPOINT_EVERY {
        let name = format!("restart_{ranks}_{linear_solver}_{every}");
        let case = case(&name, linear_solver, every);
        let full = case.parent().unwrap().join("full");
        let done = common::run_raw(&case, ranks, &full, args(ranks));
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
        if let Some(checkpoint) = checkpoint_before_a_cut(&full, every) {
            return (case, full, checkpoint);
        }
    }
    panic!(
        "no spacing in {CHECKPOINT_EVERY:?} puts a checkpoint before an augmented and a cut step"
    )
}

fn killed_and_restarted_match_the_run_never_stopped(ranks: usize, linear_solver: &str) {
    let (case, full, checkpoint) = full_run(ranks, linear_solver);
    let dir = case.parent().unwrap();
    let killed = dir.join("killed");
    let out = run_and_kill(&case, ranks, &killed, checkpoint + 2);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        !out.status.success(),
        "the kill came after the end:\n{stdout}"
    );
    let latest = std::fs::read_to_string(killed.join("checkpoint/latest")).unwrap();
    assert_eq!(latest, format!("step {checkpoint}\nranks {ranks}\n"));
    assert!(
        common::History::read(&killed).rows().len() == checkpoint + 1,
        "{stdout}"
    );
    let mut restart = args(ranks).to_vec();
    let killed_text = killed.display().to_string();
    restart.extend(["--restart", &killed_text]);
    restarted_matches(&case, (ranks, &restart), &killed, &full, checkpoint);
}

#[test]
fn a_killed_run_restarts_to_the_same_files_bit_for_bit() {
    killed_and_restarted_match_the_run_never_stopped(1, "direct");
}

#[test]
fn a_killed_run_restarts_to_the_same_files_bit_for_bit_on_two_ranks() {
    killed_and_restarted_match_the_run_never_stopped(2, "direct");
}

/// The iterative path (GMRES, the interface split, multigrid on the bulk), whose multigrid
/// PETSc would keep from one setup to the next: the run goes on after a checkpoint with a new
/// Newton solver, as a restart does.
#[test]
fn a_killed_run_on_the_iterative_path_restarts_to_the_same_files_bit_for_bit() {
    killed_and_restarted_match_the_run_never_stopped(1, "iterative");
}

/// A tied pair of blocks (Hex8, of `model`), its top pressed and sheared over `steps` steps.
fn tied_blocks(model: &str, steps: usize) -> String {
    common::stacked_blocks("hex8", [3, 3, 2], [4, 5, 2], model, 1000.0)
        + &common::symmetry(&[("low.zmin", "z"), ("low.xmin", "x"), ("low.ymin", "y")])
        + &format!(
            r#"
[[dirichlet]]
set = "up.zmax"
components = ["x", "z"]
value = [0.05, -0.05]
[[interface]]
name = "glue"
kind = "tied"
secondary = "low.zmax"
primary = "up.zmin"
[steps]
count = {steps}
"#
        )
}

/// A tied pair of blocks (Hex8, neo-Hookean), its top pressed and sheared over 40 steps, a
/// checkpoint every 5: killed after step 12, restarted, the same files as the run never
/// stopped (the tied multipliers carried by the checkpoint).
#[test]
fn a_killed_tied_run_restarts_to_the_same_files_bit_for_bit() {
    let toml = tied_blocks("neo_hookean", 40) + "[output]\ncheckpoint_every = 5\n";
    let case = common::write_case("restart_tied", &toml);
    let dir = case.parent().unwrap();
    let full = dir.join("full");
    let done = common::run_raw(&case, 1, &full, &[]);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let history = common::History::read(&full);
    let augmentations = history.column("augmentations");
    assert!(history.rows().iter().all(|r| r[augmentations] > 0.0));
    let killed = dir.join("killed");
    let run = common::subcommand("run", &case, 1, &killed, &[]);
    let started = common::start_until(run, "  step 12 ");
    started.signal(0, "KILL");
    let out = started.finish();
    assert!(!out.status.success(), "the kill came after the end");
    let killed_text = killed.display().to_string();
    restarted_matches(&case, (1, &["--restart", &killed_text]), &killed, &full, 10);
}

/// A linear scene (linear elastic, tied) factorizes its constant tangent once and keeps it:
/// after a checkpoint renews the matrix, it factorizes it again, and ends where the same run
/// without checkpoints does.
#[test]
fn a_linear_scene_goes_on_after_its_checkpoints() {
    let toml = tied_blocks("linear_elastic", 6);
    let plain = common::write_case("restart_linear", &toml);
    let with = plain.with_file_name("checkpoints.toml");
    std::fs::write(&with, toml + "[output]\ncheckpoint_every = 2\n").unwrap();
    let dir = plain.parent().unwrap();
    let (a, b) = (dir.join("plain"), dir.join("checkpoints"));
    for (case, out) in [(&plain, &a), (&with, &b)] {
        let done = common::run_raw(case, 1, out, &["-q"]);
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
    }
    let diff = common::max_rel_difference_of_runs(&a, &b);
    assert!(diff <= 1e-12, "{diff:e}");
}

/// Every file under `dir` with its bytes and modification time.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, (Vec<u8>, std::time::SystemTime)> {
    let mut all = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                todo.push(path);
            } else {
                let modified = std::fs::metadata(&path).unwrap().modified().unwrap();
                all.insert(path.clone(), (std::fs::read(&path).unwrap(), modified));
            }
        }
    }
    all
}

/// A restart that cannot go on ends with one line naming why, exit 1, and the output folder
/// as it was.
#[test]
fn a_restart_that_cannot_go_on_says_why_and_touches_nothing() {
    let case = common::write_case(
        "restart_refused",
        &(common::slide_case(6) + "[output]\ncheckpoint_every = 2\n"),
    );
    let dir = case.parent().unwrap();
    let out = dir.join("out");
    let run = common::subcommand("run", &case, 1, &out, &[]);
    let stopped = common::run_and_signal(run, "  step 3 ", "TERM", 0);
    assert_eq!(stopped.status.code(), Some(143), "{stopped:?}");
    let out_text = out.display().to_string();
    let restart = ["--restart", out_text.as_str()];
    let refused = |case: &Path, ranks: usize, what: &str, want: &str| {
        let before = snapshot(&out);
        let done = common::run_raw(case, ranks, &out, &restart);
        let line = common::the_error_line(&done, what);
        assert_eq!(done.status.code(), Some(1), "{what}");
        assert!(
            line.starts_with("mortar: error: restart: "),
            "{what}: {line}"
        );
        assert!(line.contains(want), "{what}: {line}");
        assert!(snapshot(&out) == before, "{what}: the folder changed");
    };
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        std::fs::read_to_string(&case)
            .unwrap()
            .replace("friction = 0.3", "friction = 0.25"),
    )
    .unwrap();
    refused(&other, 1, "another case file", "another case file");
    refused(
        &case,
        2,
        "another rank count",
        "written by 1 rank(s); this run has 2",
    );
    let latest = std::fs::read_to_string(out.join("checkpoint/latest")).unwrap();
    let step: usize = latest.lines().next().unwrap()[5..].parse().unwrap();
    let file = out.join(format!("checkpoint/step_{step:04}_r0.ckpt"));
    let whole = std::fs::read(&file).unwrap();
    std::fs::write(&file, &whole[..whole.len() / 2]).unwrap();
    refused(&case, 1, "a truncated checkpoint", "truncated");
    std::fs::remove_file(&file).unwrap();
    refused(
        &case,
        1,
        "a missing checkpoint file",
        "cannot read checkpoint file",
    );
    std::fs::remove_file(out.join("checkpoint/latest")).unwrap();
    refused(&case, 1, "no checkpoint", "no checkpoint in");
    // The stop at a signal wrote its last finished step.
    assert!(step >= 2, "{latest}");
}
