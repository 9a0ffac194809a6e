//! Helpers shared by the integration tests: write a scene into a fresh folder, run the `mortar`
//! binary (alone, or under `mpirun -n N --timeout`), and read what it wrote.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A case text whose first interface splits its overlaps into fans of pallets
/// (`pallets = "fan"`).
pub fn with_fan_pallets(text: &str) -> String {
    with_pallets(text, "fan")
}

/// A case text whose first interface splits its overlaps into pallets as `split` says
/// (`pallets = "<split>"`), for a case text that does not choose.
pub fn with_pallets(text: &str, split: &str) -> String {
    assert!(
        !text.contains("\npallets ="),
        "the case already chooses its pallets"
    );
    let out = text.replacen(
        "[[interface]]\n",
        &format!("[[interface]]\npallets = \"{split}\"\n"),
        1,
    );
    assert_ne!(out, text, "no interface to split into pallets");
    out
}

/// The folder of the shipped scene `cases/<scene>`.
fn scene_dir(scene: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(scene)
}

/// The case text of the shipped scene `cases/<scene>`.
pub fn scene_text(scene: &str) -> String {
    std::fs::read_to_string(scene_dir(scene).join("case.toml")).unwrap()
}

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
    let mut c = Command::new(env!("CARGO_BIN_EXE_mortar"));
    mpi_env(&mut c);
    c
}

/// The MPI environment every run needs here (see docs/guide.md, "System set-up").
pub fn mpi_env(cmd: &mut Command) -> &mut Command {
    cmd.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_mpi_yield_when_idle", "1")
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

/// The command of [`run_subcommand`], not started.
pub fn subcommand(
    subcommand: &str,
    file: &Path,
    ranks: usize,
    out_dir: &Path,
    args: &[&str],
) -> Command {
    let exe = env!("CARGO_BIN_EXE_mortar");
    let mut cmd = if ranks == 1 {
        Command::new(exe)
    } else {
        let mut c = Command::new("mpirun");
        c.args([
            "-n",
            &ranks.to_string(),
            "--oversubscribe",
            "--bind-to",
            "none",
        ])
        .args(["--timeout", "300", exe]);
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

/// summary.json as JSON.
pub fn summary(out_dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Newton iterations of every step of a run that must have converged.
pub fn converged_newton_its(out_dir: &Path) -> Vec<u64> {
    let s = summary(out_dir);
    assert_eq!(s["converged"], true, "{}", out_dir.display());
    s["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|st| st["newton_its"].as_u64().unwrap())
        .collect()
}

/// A metric from summary.json.
pub fn metric(out_dir: &Path, name: &str) -> f64 {
    summary(out_dir)["metrics"][name]
        .as_f64()
        .unwrap_or_else(|| panic!("no metric {name} in {}", out_dir.display()))
}

/// displacement.csv as rows of `[x, y, z, ux, uy, uz]`, by node.
pub fn displacements(out_dir: &Path) -> Vec<[f64; 6]> {
    let text = std::fs::read_to_string(out_dir.join("displacement.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').skip(1).map(|s| s.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3], v[4], v[5]]
        })
        .collect()
}

/// Largest displacement difference relative to the largest displacement.
pub fn max_rel_difference(a: &[[f64; 6]], b: &[[f64; 6]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a
        .iter()
        .flat_map(|r| r[3..].iter().map(|v| v.abs()))
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .flat_map(|(r, s)| (3..6).map(move |k| (r[k] - s[k]).abs()))
        .fold(0.0, f64::max);
    diff / scale
}

/// The residual norms printed by `-snes_monitor`, one list per solve.
pub fn snes_monitor_histories(stdout: &str) -> Vec<Vec<f64>> {
    let mut all: Vec<Vec<f64>> = Vec::new();
    for line in stdout.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.len() == 5 && t[1] == "SNES" && t[3] == "norm" {
            let k: usize = t[0].parse().unwrap();
            let r: f64 = t[4].parse().unwrap();
            if k == 0 {
                all.push(Vec::new());
            }
            all.last_mut().unwrap().push(r);
        }
    }
    all
}

/// A Lamé thick-sphere octant scene (E = 1000, nu = 0.3, a = 1, b = 2, p = 1, dead load).
pub fn thick_sphere_case(element: &str, n: usize) -> String {
    format!(
        r#"
name = "thick_sphere"
[[mesh]]
body = "sphere"
generator = "thick_sphere_octant"
element = "{element}"
n_circ = {n}
n_rad = {n}
inner_radius = 1.0
outer_radius = 2.0
[[material]]
model = "linear_elastic"
young = 1000.0
poisson = 0.3
[[symmetry]]
set = "sphere.symx"
normal = "x"
[[symmetry]]
set = "sphere.symy"
normal = "y"
[[symmetry]]
set = "sphere.symz"
normal = "z"
[[pressure]]
set = "sphere.inner"
value = 1.0
follower = false
[verification]
kind = "lame_sphere"
inner_radius = 1.0
outer_radius = 2.0
pressure = 1.0
"#
    )
}

/// [`compressed_block`] with the load-step predictor off, so that the whole prescribed
/// increment reaches the first Newton iterate (what the step-cutting tests need) and Newton
/// takes enough iterations for its asymptotic order to show.
pub fn compressed_block_no_predictor(element: &str, strain: f64, steps: usize) -> String {
    compressed_block(element, strain, steps).replace("[steps]\n", "[steps]\npredictor = false\n")
}

/// A Neo-Hookean block, compressed by `strain` along z in `steps` steps, free to expand sideways
/// (symmetry planes on xmin, ymin, zmin).
pub fn compressed_block(element: &str, strain: f64, steps: usize) -> String {
    format!(
        r#"
[[mesh]]
body = "b"
generator = "box"
element = "{element}"
divisions = [3, 3, 3]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 1.0]
[[material]]
model = "neo_hookean"
young = 100.0
poisson = 0.3
[[symmetry]]
set = "b.xmin"
normal = "x"
[[symmetry]]
set = "b.ymin"
normal = "y"
[[symmetry]]
set = "b.zmin"
normal = "z"
[[dirichlet]]
set = "b.zmax"
components = ["z"]
value = [-{strain}]
[steps]
count = {steps}
"#
    )
}

/// A small frictional slide (Hex8, one pass, mu = 0.3): compressed, then the upper block pushed
/// sideways, with the upper block narrower than the lower one so that its edges slide over the
/// lower surface.
pub fn slide_case(steps: usize) -> String {
    format!(
        r#"
[[mesh]]
body = "low"
generator = "box"
element = "hex8"
divisions = [3, 2, 1]
lo = [0.0, 0.0, 0.0]
hi = [1.5, 1.0, 0.5]
[[mesh]]
body = "up"
generator = "box"
element = "hex8"
divisions = [2, 2, 1]
lo = [0.25, 0.1, 0.5]
hi = [0.95, 0.9, 1.0]
[[material]]
body = "low"
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[material]]
body = "up"
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[symmetry]]
set = "low.zmin"
normal = "z"
[[symmetry]]
set = "low.xmin"
normal = "x"
[[symmetry]]
set = "low.ymin"
normal = "y"
[[symmetry]]
set = "up.ymin"
normal = "y"
[[dirichlet]]
set = "up.zmax"
components = ["z"]
value = [-0.02]
curve = {{ kind = "table", table = [[0.0, 0.0], [0.3, 1.0], [1.0, 1.0]] }}
[[dirichlet]]
set = "up.zmax"
components = ["x"]
value = [0.2]
curve = {{ kind = "table", table = [[0.0, 0.0], [0.3, 0.0], [1.0, 1.0]] }}
[[interface]]
name = "slide"
kind = "contact"
secondary = "up.zmin"
primary = "low.zmax"
friction = 0.3
[steps]
count = {steps}
"#
    )
}

/// The cantilever of `cases/cantilever`: a 10 x 1 x 1 beam of `element`, clamped at x = 0, a
/// follower pressure 0.3 on its top face, compressible Neo-Hookean (E = 1000, nu = 0.3).
pub fn cantilever_case(element: &str, divisions: [usize; 3], steps: usize) -> String {
    format!(
        r#"
[[mesh]]
body = "beam"
generator = "beam"
element = "{element}"
divisions = [{}, {}, {}]
length = 10.0
width = 1.0
height = 1.0
[[material]]
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[dirichlet]]
set = "beam.xmin"
components = ["x", "y", "z"]
[[pressure]]
set = "beam.zmax"
value = 0.3
[steps]
count = {steps}
"#,
        divisions[0], divisions[1], divisions[2]
    )
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
