//! A graceful stop on SIGINT (Ctrl-C) and SIGTERM (a batch system's time limit, `kill`,
//! `mpirun --timeout`).
//!
//! The first such signal only sets a flag. A run polls it at the start of every load step and of
//! every Jacobian evaluation (once per Newton iteration), **collectively**: every rank takes part
//! ([`agreed`]), so all ranks stop at the same point even when the signal reached one of them
//! only. A Newton solve under way ends as not converged (the Jacobian reports a domain error, so
//! PETSc ends the solve cleanly), and the run ends as a failed run does, at its last finished
//! step: the steps finished on disk, `displacement.csv` and the metrics of the last one,
//! `summary.json` saying why (`"message": "interrupted by SIGINT after step 20 ..."`), one line
//! on stderr from rank 0, and exit status 128 + the signal (130, 143), as a shell reports a
//! process the signal ended. A study ends once the run it was in stops, with the runs that
//! finished in its `study.csv`. A signal before the first step stops the run there (one while
//! MPI and PETSc start, before [`watch`], ends the process); one after the last step changes
//! nothing (the run is complete).
//!
//! A second signal ends the process at once (the signal's default action). A signal that was
//! ignored when the program started (SIGINT in a background job of a script) stays ignored.
//!
//! Under `mpirun`, Open MPI answers a Ctrl-C by sending SIGTERM to every rank about a second
//! later and SIGKILL about a second after that (Open MPI 4.1.4): a run stops in time when one
//! Newton iteration takes less than that. The exit status is then mpirun's (1).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

/// The signal received (0: none), shared with the signal handlers.
static RECEIVED: OnceLock<Arc<AtomicUsize>> = OnceLock::new();

/// The signal the ranks agreed to stop on (0: none): the exit status's.
static AGREED: AtomicUsize = AtomicUsize::new(0);

/// The signals that stop a run.
const STOP_SIGNALS: [i32; 2] = [SIGINT, SIGTERM];

/// Those of [`STOP_SIGNALS`] ignored when the program started.
static IGNORED_AT_START: OnceLock<Vec<i32>> = OnceLock::new();

/// Notes which stop signals are ignored, before anything (PETSc) installs handlers: call it
/// first thing in `main`.
pub fn note_ignored_signals() -> &'static [i32] {
    IGNORED_AT_START.get_or_init(|| {
        STOP_SIGNALS
            .into_iter()
            .filter(|&s| crate::petsc::signal_is_ignored(s))
            .collect()
    })
}

/// Installs the handlers (once; later calls do nothing), after PETSc's start: a handler PETSc
/// installed for these signals (a PETSc built without Open MPI does, for SIGTERM) is dropped
/// first, or it would run too (signal-hook calls the handler it replaces) and abort the job.
///
/// # Errors
/// If the system refuses a handler: the run then goes on without a graceful stop.
pub fn watch() -> std::io::Result<()> {
    if RECEIVED.get().is_some() {
        return Ok(());
    }
    let ignored = note_ignored_signals();
    let received = Arc::new(AtomicUsize::new(0));
    // Set by the first signal; a signal that finds it set takes the default action.
    let armed = Arc::new(AtomicBool::new(false));
    for signal in STOP_SIGNALS {
        if ignored.contains(&signal) {
            continue;
        }
        crate::petsc::default_signal(signal);
        // The actions of one signal run in the order they were registered.
        flag::register_conditional_default(signal, Arc::clone(&armed))?;
        flag::register(signal, Arc::clone(&armed))?;
        flag::register_usize(signal, Arc::clone(&received), signal as usize)?;
    }
    let _ = RECEIVED.set(received);
    Ok(())
}

/// The signal this process received, if any (local: see [`agreed`]).
fn received() -> Option<i32> {
    let signal = RECEIVED.get()?.load(Ordering::SeqCst);
    (signal != 0).then_some(signal as i32)
}

/// Collective over `world`: the signal any of its ranks received (the largest number if they
/// differ), on every rank alike.
pub fn agreed(world: &SimpleCommunicator) -> Option<i32> {
    let mine = received().unwrap_or(0);
    let mut any = 0i32;
    world.all_reduce_into(&mine, &mut any, SystemOperation::max());
    if any == 0 {
        return None;
    }
    AGREED.store(any as usize, Ordering::SeqCst);
    Some(any)
}

/// The signal a run or study stopped on ([`agreed`] found one), for the exit status.
pub fn stopped_by() -> Option<i32> {
    let signal = AGREED.load(Ordering::SeqCst);
    (signal != 0).then_some(signal as i32)
}

/// The signal's name: `SIGINT`, `SIGTERM`, else `signal N`.
pub fn name(signal: i32) -> String {
    match signal {
        SIGINT => "SIGINT".into(),
        SIGTERM => "SIGTERM".into(),
        n => format!("signal {n}"),
    }
}
