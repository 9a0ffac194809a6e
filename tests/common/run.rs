//! Running `mortar`: a case written into a fresh folder, the binary started alone or under
//! `mpirun -n N --timeout`, a run stopped by a signal while it runs.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Output};

use super::scenes::scene_dir;

/// Seconds `mpirun --timeout` gives a run of the tests before it ends the job.
const MPIRUN_TIMEOUT: u32 = 300;

/// Writes `text` (a shipped scene's case, edited) as `case.toml` into a fresh folder named
/// `name`, with the scene's PETSc options file beside it, and returns its path.
pub fn write_scene_copy(name: &str, scene: &str, text: &str) -> PathBuf {
    let case = write_case(name, text);
    let options = scene_dir(scene).join("petscrc");
    std::fs::copy(options, case.with_file_name("petscrc")).unwrap();
    case
}

/// A fresh, empty folder under cargo's temporary test directory.
pub fn fresh_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `case.toml` into a fresh folder named `name` and returns its path.
pub fn write_case(name: &str, toml: &str) -> PathBuf {
    let dir = fresh_dir(name);
    let path = dir.join("case.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

/// The `mortar` binary, with the MPI environment every run needs here.
pub fn mortar_command() -> Command {
    let mut c = one_process();
    mpi_env(&mut c);
    c
}

/// The `mortar` binary as one process (no mpirun), started with SIGINT's default action: a
/// test suite started in the background by a script inherits SIGINT ignored, which `mortar`
/// keeps ignoring (`src/interrupt.rs`), and the tests of Ctrl-C would find it ignored. The
/// process is `env`'s, which then becomes `mortar` (same pid).
fn one_process() -> Command {
    let mut c = Command::new("env");
    c.arg("--default-signal=INT")
        .arg(env!("CARGO_BIN_EXE_mortar"));
    c
}

/// The MPI environment every run needs here (see docs/guide.md, "System set-up"), and one
/// OpenMP thread per rank: SuperLU_DIST otherwise starts a thread per core in every rank,
/// which under `--bind-to none` oversubscribes the cores, slows it many times over and makes its
/// factorization differ from run to run.
pub fn mpi_env(cmd: &mut Command) -> &mut Command {
    cmd.env("OMP_NUM_THREADS", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_mpi_yield_when_idle", "1")
}

/// `mpirun -n RANKS --oversubscribe --bind-to none --timeout SECONDS`, the program to start
/// still to be added (and the MPI environment, [`mpi_env`]).
pub fn mpirun(ranks: usize, timeout_seconds: u32) -> Command {
    let mut c = Command::new("mpirun");
    c.args([
        "-n",
        &ranks.to_string(),
        "--oversubscribe",
        "--bind-to",
        "none",
    ])
    .args(["--timeout", &timeout_seconds.to_string()]);
    c
}

/// Runs `mortar run CASE --out OUT ARGS` on `ranks` ranks (1: without mpirun). Panics with the
/// output if the run fails.
pub fn run_case(case: &Path, ranks: usize, args: &[&str]) -> (PathBuf, String) {
    let out_dir = case.parent().unwrap().join(format!("out_{ranks}"));
    let out = run_raw(case, ranks, &out_dir, args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "mortar failed on {} ({ranks} ranks)\nstdout:\n{stdout}\nstderr:\n{}",
        case.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    (out_dir, stdout)
}

/// Runs `mortar run` and returns its raw output, whatever the exit status.
pub fn run_raw(case: &Path, ranks: usize, out_dir: &Path, args: &[&str]) -> Output {
    run_subcommand("run", case, ranks, out_dir, args)
}

/// Runs `mortar SUBCOMMAND FILE --out OUT ARGS` on `ranks` ranks (1: without mpirun) and
/// returns its raw output, whatever the exit status.
pub fn run_subcommand(
    subcommand: &str,
    file: &Path,
    ranks: usize,
    out_dir: &Path,
    args: &[&str],
) -> Output {
    self::subcommand(subcommand, file, ranks, out_dir, args)
        .output()
        .expect("cannot start mortar (or mpirun)")
}

/// Runs `mortar SUBCOMMAND cases/<scene>/<file> --out OUT ARGS` on one rank, its progress on
/// this terminal, into the fresh folder `out_name` ([`fresh_dir`]); returns the folder and the
/// exit status.
pub fn run_shipped(
    subcommand: &str,
    scene: &str,
    file: &str,
    out_name: &str,
    args: &[&str],
) -> (PathBuf, ExitStatus) {
    let out = fresh_dir(out_name);
    let status = self::subcommand(subcommand, &scene_dir(scene).join(file), 1, &out, args)
        .status()
        .expect("cannot start mortar");
    (out, status)
}

/// The command of [`run_subcommand`], not started.
pub fn subcommand(
    subcommand: &str,
    file: &Path,
    ranks: usize,
    out_dir: &Path,
    args: &[&str],
) -> Command {
    let mut cmd = if ranks == 1 {
        one_process()
    } else {
        let mut c = mpirun(ranks, MPIRUN_TIMEOUT);
        c.arg(env!("CARGO_BIN_EXE_mortar"));
        c
    };
    mpi_env(&mut cmd)
        .arg(subcommand)
        .arg(file)
        .arg("--out")
        .arg(out_dir)
        .args(args);
    cmd
}

/// A command started, its stdout read up to a line ([`start_until`]).
pub struct Started {
    child: std::process::Child,
    stdout: std::io::BufReader<std::process::ChildStdout>,
    /// The stdout read so far.
    seen: String,
    is_mpirun: bool,
}

/// Starts `command` (a run or study, its progress on stdout) and waits for a progress line that
/// starts with `after` (`"  step 2 "`).
pub fn start_until(mut command: Command, after: &str) -> Started {
    use std::io::BufRead;
    let mut child = command
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot start mortar (or mpirun)");
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut seen = String::new();
    loop {
        let mut line = String::new();
        let n = stdout.read_line(&mut line).unwrap();
        seen.push_str(&line);
        assert!(n > 0, "the run ended before a line {after:?}:\n{seen}");
        if line.starts_with(after) {
            break;
        }
    }
    let is_mpirun = command.get_program() == "mpirun";
    Started {
        child,
        stdout,
        seen,
        is_mpirun,
    }
}

impl Started {
    /// The process of rank `rank` (the command's own when it is not mpirun), still running: a
    /// run that ended already would make a test of what happens while it runs prove nothing.
    pub fn running_process(&self, rank: usize) -> u32 {
        let pid = if self.is_mpirun {
            rank_process(self.child.id(), rank)
        } else {
            self.child.id()
        };
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
        let state = stat.rsplit(')').next().unwrap_or("").trim_start();
        assert!(
            !state.is_empty() && !state.starts_with('Z'),
            "the process ended too early:\n{}",
            self.seen
        );
        pid
    }

    /// Sends `signal` (a name `kill` knows: `INT`, `TERM`, `STOP`, `CONT`) to the running
    /// process of rank `rank`.
    pub fn signal(&self, rank: usize, signal: &str) {
        let pid = self.running_process(rank);
        let sent = Command::new("kill")
            .args([format!("-{signal}"), pid.to_string()])
            .status()
            .unwrap();
        assert!(sent.success(), "kill -{signal} {pid}");
    }

    /// Waits for the end; the output with the whole stdout.
    pub fn finish(mut self) -> Output {
        use std::io::Read;
        self.stdout.read_to_string(&mut self.seen).unwrap();
        let mut out = self.child.wait_with_output().unwrap();
        out.stdout = self.seen.into_bytes();
        out
    }
}

/// Starts `command` as [`start_until`] does, sends `signal` (a name `kill` knows: `INT`,
/// `TERM`) to the process of rank `rank` (the command's own process when it is not mpirun),
/// and returns the output.
pub fn run_and_signal(command: Command, after: &str, signal: &str, rank: usize) -> Output {
    let started = start_until(command, after);
    started.signal(rank, signal);
    started.finish()
}

/// The process of rank `rank` among the children of mpirun's process `mpirun`.
fn rank_process(mpirun: u32, rank: usize) -> u32 {
    let wanted = format!("OMPI_COMM_WORLD_RANK={rank}");
    let tasks = std::fs::read_dir(format!("/proc/{mpirun}/task")).unwrap();
    for task in tasks {
        let children = std::fs::read_to_string(task.unwrap().path().join("children"));
        for pid in children.unwrap_or_default().split_whitespace() {
            let environ = std::fs::read(format!("/proc/{pid}/environ")).unwrap_or_default();
            if environ.split(|&b| b == 0).any(|v| v == wanted.as_bytes()) {
                return pid.parse().unwrap();
            }
        }
    }
    panic!("no process of rank {rank} under mpirun {mpirun}")
}

/// Runs `case` on `ranks` with `-log_view` and returns its output folder and the load-step
/// predictor's factorizations ([`predictor_factorizations`]).
pub fn run_counting_predictor_factorizations(case: &Path, ranks: usize) -> (PathBuf, usize) {
    let log = case.parent().unwrap().join(format!("log_{ranks}.txt"));
    let view = format!(":{}", log.display());
    let (out, _) = run_case(case, ranks, &["-q", "-log_view", &view]);
    (out, predictor_factorizations(&log))
}

/// The numerical factorizations in the main stage of a `-log_view` file: those outside the
/// solver's stages, which are the load-step predictor's.
fn predictor_factorizations(log: &Path) -> usize {
    let text = std::fs::read_to_string(log).unwrap();
    let main_stage = text
        .split("--- Event Stage 0:")
        .nth(1)
        .and_then(|rest| rest.split("--- Event Stage 1:").next())
        .unwrap_or_else(|| panic!("no event stages in {}", log.display()));
    main_stage
        .lines()
        .filter(|l| l.starts_with("MatLUFactorNum "))
        .map(|l| {
            l.split_whitespace()
                .nth(1)
                .unwrap()
                .parse::<usize>()
                .unwrap()
        })
        .sum()
}
