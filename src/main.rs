//! The `mortar` command line.
//!
//! ```text
//! mortar run CASE.toml [--out DIR | --restart DIR] [--quiet] [PETSc options...]
//! mortar check CASE.toml
//! mortar study STUDY.toml [--out DIR] [--quiet] [PETSc options...]
//! mortar scaling LOG_1 LOG_2 ... [--out DIR]
//! mortar family RUN_DIR ... [--out DIR]
//! ```
//!
//! Options with two dashes are ours; everything after the case file that is not ours goes to
//! PETSc's options database unchanged (`-snes_monitor`, `-ksp_type gmres`, `-log_view`, ...).
//! Run under `mpirun -n N` for N ranks; without mpirun it is one rank. Any error ends with one
//! line on stderr (from rank 0, or from the rank that failed) and exit code 1; a run or study
//! stopped by SIGINT or SIGTERM ([`mortar::interrupt`]) with 128 + the signal.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use mpi::collective::{CommunicatorCollectives, Root};
use mpi::topology::{Communicator, SimpleCommunicator};

use mortar::case::Scene;
use mortar::error::{print_error, print_warning};
use mortar::petsc::Petsc;
use mortar::solver::{run, RunOptions};
use mortar::study::{Study, StudyReport};
use mortar::{Error, Result};

#[derive(Parser, Debug)]
#[command(
    name = "mortar",
    version,
    about = "Mortar frictional contact on PETSc and MPI"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Runs a scene. PETSc options may follow the case file.
    Run {
        /// The case file (case.toml).
        case: PathBuf,
        /// Output folder. Default: out/<case name>.
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress lines.
        #[arg(long, short)]
        quiet: bool,
        /// Do not run the scene's figure study (`output.figure`) after the scene.
        #[arg(long)]
        no_figure: bool,
        /// Go on from the last checkpoint of the run in this output folder, writing into it
        /// (`output.checkpoint_every`).
        #[arg(long, value_name = "DIR")]
        restart: Option<PathBuf>,
        /// PETSc options, passed to PETSc unchanged.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        petsc: Vec<String>,
    },
    /// Validates a scene and its mesh; solves nothing.
    Check {
        /// The case file (case.toml).
        case: PathBuf,
    },
    /// Runs a convergence study: one scene over refinements and variants (see `mortar::study`).
    /// PETSc options may follow the study file.
    Study {
        /// The study file (study.toml).
        study: PathBuf,
        /// Output folder. Default: out/<folder>_<stem> of the study file (out/hertz_study for
        /// cases/hertz/study.toml).
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress lines.
        #[arg(long, short)]
        quiet: bool,
        /// PETSc options, passed to PETSc unchanged.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        petsc: Vec<String>,
    },
    /// Strong scaling of one scene from the PETSc logs of its runs on different numbers of
    /// ranks (`-log_view :FILE`): a table of the phases' times and speedups, scaling.csv and
    /// a plot. The last line is `speedup: X` (the last run's over the first's).
    Scaling {
        /// The `-log_view` files of one scene, by strictly increasing rank count (the
        /// reference run, fewest ranks, first).
        #[arg(required = true, num_args = 2..)]
        logs: Vec<PathBuf>,
        /// Output folder. Default: out/scaling.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// What refinement costs, from the output folders of runs of a refinement family
    /// (cases/refinement): per run the dofs, Newton and linear iterations, seconds per phase
    /// and peak memory; the exponents of the costs between sizes; the speedups between rank
    /// counts of a size; family.csv.
    Family {
        /// The runs' output folders (each with summary.json and history.csv).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Output folder. Default: out/family.
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    mortar::interrupt::note_ignored_signals();
    let args: Vec<String> = std::env::args().collect();
    let program = args.first().cloned().unwrap_or_else(|| "mortar".into());
    let args = match pull_our_options(&args) {
        Ok(a) => a,
        Err(msg) => {
            print_error(msg);
            return ExitCode::FAILURE;
        }
    };
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) if !e.use_stderr() => {
            // --help, --version
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            print_error(format_args!("{}", clap_one_line(&e)));
            return ExitCode::FAILURE;
        }
    };
    match execute(cli, program) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if !matches!(e, Error::Reported) {
                print_error(e);
            }
            failure_status()
        }
    }
}

/// 128 + the signal for a run or study stopped by one (as a shell reports a process the signal
/// ended: 130 for SIGINT, 143 for SIGTERM), else 1.
fn failure_status() -> ExitCode {
    match mortar::interrupt::stopped_by().and_then(|s| u8::try_from(128 + s).ok()) {
        Some(status) => ExitCode::from(status),
        None => ExitCode::FAILURE,
    }
}

/// clap's message without its usage block, on one line.
fn clap_one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    text.lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:"))
        .filter(|l| !l.is_empty())
        .map(|l| l.trim_start_matches("error: "))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Moves `--out DIR` and `--quiet` (and for `run` `--no-figure`) found among the PETSc options
/// (after the case or study file) in front of that file, so clap sees them whatever their
/// position.
fn pull_our_options(args: &[String]) -> Result<Vec<String>, String> {
    let Some(run_at) = args.iter().position(|a| a == "run" || a == "study") else {
        return Ok(args.to_vec());
    };
    let is_run = args[run_at] == "run";
    let mut head: Vec<String> = args[..=run_at].to_vec();
    let mut rest: Vec<String> = Vec::new();
    let mut it = args[run_at + 1..].iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" | "--restart" if is_run || a == "--out" => {
                head.push(a.clone());
                match it.next() {
                    Some(v) if !v.starts_with('-') => head.push(v.clone()),
                    _ => return Err(format!("{a} needs a folder ({a} DIR)")),
                }
            }
            s if s.starts_with("--out=") || matches!(s, "--quiet" | "-q") => head.push(a.clone()),
            s if is_run && s.starts_with("--restart=") => head.push(a.clone()),
            "--no-figure" if is_run => head.push(a.clone()),
            _ => rest.push(a.clone()),
        }
    }
    head.extend(rest);
    Ok(head)
}

/// The words after the case or study file are PETSc options, each a `-name` with perhaps one
/// value after it (`petsc::options::parse_words`); a stray word (a second file, say) would be
/// ignored by PETSc without a word.
fn check_petsc_args(petsc: &[String]) -> Result<()> {
    mortar::petsc::options::parse_words(petsc.iter().map(String::as_str))
        .map(|_| ())
        .map_err(|e| Error::Other(format!("command line after the file: {e}")))
}

fn execute(cli: Cli, program: String) -> Result<()> {
    match cli.command {
        Command::Check { case } => {
            let scene = Scene::load(&case)?;
            print_report(&format!(
                "mortar: {} is valid: {} nodes, {} elements, {} bodies, {} constrained dofs\n",
                case.display(),
                scene.mesh.num_nodes(),
                scene.mesh.num_elements(),
                scene.mesh.bodies.len(),
                scene.constraints.len()
            ))
        }
        Command::Run {
            case,
            out,
            quiet,
            no_figure,
            restart,
            petsc,
        } => {
            let mut launch = Launch::new(out, quiet, program, petsc);
            launch.restart_from(restart)?;
            run_command(&case, !no_figure, launch)
        }
        Command::Study {
            study,
            out,
            quiet,
            petsc,
        } => study_command(&study, Launch::new(out, quiet, program, petsc)),
        Command::Scaling { logs, out } => {
            let scaling = mortar::scaling::Scaling::read(&logs)?;
            let out = out.unwrap_or_else(|| PathBuf::from("out/scaling"));
            mortar::io::plot::print_warnings(scaling.write(&out)?);
            let mut report = scaling.table();
            report += &format!(
                "mortar: scaling.csv, scaling.png and scaling.svg in {}\n",
                out.display()
            );
            let last = scaling.runs.len() - 1;
            if let Some(s) = scaling.speedup_per_newton_iteration(last) {
                report += &format!("speedup per Newton iteration: {s:.2}\n");
            }
            report += &format!("speedup: {:.2}\n", scaling.speedup(last));
            print_report(&report)
        }
        Command::Family { runs, out } => {
            let family = mortar::family::Family::read(&runs)?;
            let out = out.unwrap_or_else(|| PathBuf::from("out/family"));
            let csv = family.write(&out)?;
            print_report(&format!("{}mortar: {}\n", family.report(), csv.display()))
        }
    }
}

/// Prints a report to stdout. A reader that stops early (`mortar family ... | head`) ends it
/// quietly: the files, if any, are written by then.
fn print_report(report: &str) -> Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(report.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Error::Other(format!("writing the report to stdout: {e}")))
        }
        _ => Ok(()),
    }
}

/// The options `run` and `study` share.
struct Launch {
    /// Output folder; default: `out/<name>` of the scene or study.
    out: Option<PathBuf>,
    quiet: bool,
    /// Go on from the checkpoint in `out` (`run --restart`).
    restart: bool,
    /// The program's name and the PETSc options of the command line.
    program: String,
    petsc_options: Vec<String>,
}

impl Launch {
    fn new(out: Option<PathBuf>, quiet: bool, program: String, petsc: Vec<String>) -> Launch {
        Launch {
            out,
            quiet,
            restart: false,
            program,
            petsc_options: petsc,
        }
    }

    /// `run --restart DIR`: the run goes on in DIR, which `--out` may only repeat.
    fn restart_from(&mut self, dir: Option<PathBuf>) -> Result<()> {
        let Some(dir) = dir else {
            return Ok(());
        };
        if self.out.as_ref().is_some_and(|out| out != &dir) {
            return Err(Error::Other(format!(
                "--restart {} goes on in that folder: leave out --out",
                dir.display()
            )));
        }
        self.out = Some(dir);
        self.restart = true;
        Ok(())
    }
}

/// What `run` and `study` start from: a scene or a study.
trait Input {
    /// Names the default output folder.
    fn name(&self) -> &str;
    /// The PETSc options file, if any.
    fn petsc_options(&self) -> Option<&Path>;
}

impl Input for Scene {
    fn name(&self) -> &str {
        &self.name
    }
    fn petsc_options(&self) -> Option<&Path> {
        self.petsc_options.as_deref()
    }
}

impl Input for Study {
    fn name(&self) -> &str {
        &self.name
    }
    fn petsc_options(&self) -> Option<&Path> {
        self.petsc_options.as_deref()
    }
}

/// A started `run` or `study`: its input (a scene or a study) read on every rank, PETSc, the
/// world, and where and how to write.
struct Started<T> {
    input: T,
    petsc: Petsc,
    world: SimpleCommunicator,
    options: RunOptions,
}

/// `mortar run` under MPI, with the error policy of a parallel program:
///
/// - MPI starts first, then every rank reads the case, and the ranks agree (one allreduce) on
///   whether all succeeded; only the first failing rank prints, and every rank exits 1.
/// - An error every rank meets alike ([`Error::is_collective`]: non-convergence, a bad option)
///   is printed once, by rank 0, and every rank ends normally.
/// - Any other error may be one rank's alone while the others wait in a collective call: that
///   rank prints it with its rank and aborts the job (`MPI_Abort`), so a run never hangs.
///
/// With `output.figure` (and without `--no-figure`), the figure's study runs after the scene,
/// into `<out>/figure/`, sharing its PETSc; the scene's expectations are checked after the
/// scene, the study's after the study, and the study runs whatever the scene's verdict.
fn run_command(case: &Path, figure: bool, launch: Launch) -> Result<()> {
    let started = start(|| Scene::load(case), launch)?;
    let (scene, petsc, world) = (&started.input, &started.petsc, &started.world);
    let result = run(scene, petsc, &started.options).and_then(|summary| {
        let scene_verdict = check_expectations(world, &scene.expectations, &summary.metrics);
        let figure_verdict = match scene.figure.as_deref().filter(|_| figure) {
            Some(study) => run_figure(study, petsc, world, &started.options),
            None => Ok(()),
        };
        scene_verdict.and(figure_verdict)
    });
    if result.is_ok() && world.rank() == 0 {
        warn_unused_options(petsc);
    }
    started.finish(result)
}

/// The scene's figure: its study run into `<out>/figure/` with the scene's PETSc, and the
/// study's verdict.
fn run_figure(
    study: &Path,
    petsc: &Petsc,
    world: &SimpleCommunicator,
    scene_options: &RunOptions,
) -> Result<()> {
    let options = RunOptions::new(scene_options.out_dir.join("figure"), scene_options.quiet);
    if world.rank() == 0 && !options.quiet {
        println!(
            "mortar: the scene's figure: {} -> {}",
            study.display(),
            options.out_dir.display()
        );
    }
    let study = Study::load(study)?;
    let report = study.run(petsc, &options)?;
    study_verdict(world, &study, report)
}

/// Starts MPI, loads the input on every rank (agreeing on success: only the first failing rank
/// reports), then starts PETSc with the input's options file.
fn start<T: Input>(load: impl FnOnce() -> Result<T>, launch: Launch) -> Result<Started<T>> {
    let universe = mortar::petsc::start_mpi()?;
    let world = universe.world();
    let (rank, size) = (world.rank(), world.size());
    let loaded = check_petsc_args(&launch.petsc_options).and_then(|()| load());
    let first_failure = mortar::solver::lowest_rank_with(&world, loaded.is_err());
    let input = match loaded {
        Ok(s) if first_failure == size => s,
        Err(e) if rank == first_failure => {
            return Err(report_once(&world, Some(ranked(e, rank, size))))
        }
        _ => return Err(report_once(&world, None)),
    };
    let options = RunOptions {
        out_dir: launch.out.unwrap_or_else(|| default_out(input.name())),
        quiet: launch.quiet,
        restart: launch.restart,
    };
    let mut petsc_args = vec![launch.program];
    petsc_args.extend(launch.petsc_options);
    match Petsc::start(universe, &petsc_args, input.petsc_options()) {
        Ok(petsc) => {
            // After PETSc's start, which installs signal handlers of its own.
            if let Err(e) = mortar::interrupt::watch() {
                if rank == 0 {
                    print_warning(format_args!(
                        "no graceful stop on SIGINT and SIGTERM (their handlers: {e})"
                    ));
                }
            }
            Ok(Started {
                input,
                petsc,
                world,
                options,
            })
        }
        Err(e) => Err(abort_unless_collective(&world, e, rank, size)),
    }
}

/// `mortar study`, with the error policy of `mortar run` ([`run_command`]): every rank reads and
/// validates the study, one PETSc serves every run, a failed run is recorded and the study goes
/// on, and the study's error (a failed run, a collective error) is printed once by rank 0.
fn study_command(path: &Path, launch: Launch) -> Result<()> {
    let started = start(|| Study::load(path), launch)?;
    let (study, petsc, world) = (&started.input, &started.petsc, &started.world);
    let result = study
        .run(petsc, &started.options)
        .and_then(|report| study_verdict(world, study, report));
    if world.rank() == 0 {
        warn_unused_options(petsc);
    }
    started.finish(result)
}

impl<T> Started<T> {
    /// Ends a run or study: PETSc and MPI after success, else the error by the policy of
    /// [`run_command`].
    fn finish(self, result: Result<()>) -> Result<()> {
        match result {
            Ok(()) => finalize(self.petsc, &self.world),
            Err(e) => Err(abort_unless_collective(
                &self.world,
                e,
                self.world.rank(),
                self.world.size(),
            )),
        }
    }
}

/// A finished study's verdict: its expectations are checked and printed with their values
/// (stdout), also when runs failed (measured on the runs that converged: a failed run has no
/// metrics); then the study fails with the failed runs' error if there is one (it says more
/// than a failed expectation about a run that is not there), else with the expectations'.
fn study_verdict(world: &SimpleCommunicator, study: &Study, report: StudyReport) -> Result<()> {
    let expected = check_expectations(world, &study.expectations, &report.summary.metrics);
    match report.failure {
        Some(failure) => Err(failure),
        None => expected,
    }
}

/// Prints every expectation with its measured values and fails when one does not hold, on
/// rank 0's metrics (a study's summary lives there); every rank shares the verdict, and only
/// rank 0 carries the message.
fn check_expectations(
    world: &SimpleCommunicator,
    expectations: &[mortar::expect::Expectation],
    metrics: &std::collections::BTreeMap<String, f64>,
) -> Result<()> {
    if expectations.is_empty() {
        return Ok(());
    }
    let (outcomes, failed) = mortar::expect::check_all(expectations, metrics);
    let mut verdict = i32::from(failed.is_some());
    world.process_at_rank(0).broadcast_into(&mut verdict);
    if world.rank() != 0 {
        // A collective error: `abort_unless_collective` keeps the other ranks quiet.
        return if verdict == 0 {
            Ok(())
        } else {
            Err(Error::Expectation(String::new()))
        };
    }
    for o in &outcomes {
        println!("mortar: {o}");
    }
    match failed {
        Some(msg) => Err(Error::Expectation(msg)),
        None => Ok(()),
    }
}

/// A collective error is printed by rank 0 (others stay quiet); any other error is printed with
/// its rank and the job is aborted.
fn abort_unless_collective(world: &SimpleCommunicator, e: Error, rank: i32, size: i32) -> Error {
    if size == 1 {
        return e;
    }
    if e.is_collective() {
        return report_once(world, (rank == 0).then_some(e));
    }
    print_error(mortar::error::abort_line(rank, &e));
    world.abort(1)
}

/// Ends PETSc, then MPI. A failure of PETSc's end (an unwritable `-log_view` file) may be one
/// rank's while the others wait inside it: the job is then aborted rather than left hanging.
fn finalize(mut petsc: Petsc, world: &SimpleCommunicator) -> Result<()> {
    petsc
        .finalize()
        .map_err(|e| abort_unless_collective(world, e, world.rank(), world.size()))
}

/// An error every rank has agreed on, printed by the one rank that holds it, before any rank
/// exits: all ranks wait for the print (a barrier), because mpirun kills the job as soon as one
/// rank exits non-zero and would otherwise lose the line of a slower rank.
fn report_once(world: &SimpleCommunicator, message: Option<Error>) -> Error {
    if let Some(e) = message {
        print_error(e);
    }
    world.barrier();
    Error::Reported
}

/// Prefixes the rank to an error when the job has several.
fn ranked(e: Error, rank: i32, size: i32) -> Error {
    if size > 1 && rank != 0 {
        Error::Other(format!("[rank {rank}] {e}"))
    } else {
        e
    }
}

fn warn_unused_options(petsc: &Petsc) {
    match petsc.unused_options() {
        Ok(0) => {}
        Ok(n) => print_warning(format_args!(
            "{n} PETSc option(s) were never used (a typo?); \
             rerun with -options_left to list them"
        )),
        Err(e) => print_warning(e),
    }
}

fn default_out(name: &str) -> PathBuf {
    Path::new("out").join(name)
}

#[cfg(test)]
mod tests {
    use super::pull_our_options;

    fn args(line: &str) -> Vec<String> {
        line.split_whitespace().map(String::from).collect()
    }

    /// Our flags after a PETSc option reach clap, not PETSc; PETSc options keep their order.
    #[test]
    fn our_flags_are_pulled_out_of_the_petsc_options() {
        let pulled = pull_our_options(&args(
            "mortar run c.toml -snes_monitor --no-figure -ksp_type preonly --out d -q",
        ))
        .unwrap();
        assert_eq!(
            pulled,
            args("mortar run --no-figure --out d -q c.toml -snes_monitor -ksp_type preonly")
        );
        assert!(pull_our_options(&args("mortar study s.toml --out -q")).is_err());
        // `study` has no `--no-figure`: left where it is.
        assert_eq!(
            pull_our_options(&args("mortar study s.toml --no-figure -q")).unwrap(),
            args("mortar study -q s.toml --no-figure")
        );
    }
}
