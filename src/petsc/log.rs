//! PETSc log stages, so `-log_view` shows where time goes, and wall-clock timers for
//! `summary.json`.

use std::collections::BTreeMap;
use std::time::Instant;

use petsc_ffi as p;

use super::chk;
use crate::error::Result;

/// A registered PETSc log stage.
#[derive(Clone, Copy, Debug)]
pub struct Stage(p::PetscLogStage);

impl Stage {
    /// The stage called `name` (shown by `-log_view`), registered on first use; PETSc refuses a
    /// name twice, so a second run in the same process reuses the first registration.
    pub fn register(name: &str) -> Result<Stage> {
        let c = std::ffi::CString::new(name).expect("stage names have no NUL");
        let mut id: p::PetscLogStage = -1;
        chk!(PetscLogStageGetId(c.as_ptr(), &mut id))?;
        if id < 0 {
            chk!(PetscLogStageRegister(c.as_ptr(), &mut id))?;
        }
        Ok(Stage(id))
    }

    /// Pushes the stage; it is popped when the guard drops.
    pub fn push(self) -> Result<StageGuard> {
        chk!(PetscLogStagePush(self.0))?;
        Ok(StageGuard)
    }
}

/// Pops the current log stage on drop.
pub struct StageGuard;

impl Drop for StageGuard {
    fn drop(&mut self) {
        // SAFETY: paired with the push in `Stage::push`.
        let code = unsafe { p::PetscLogStagePop() };
        if code != 0 {
            crate::error::print_warning(format_args!(
                "PetscLogStagePop returned error code {code}"
            ));
        }
    }
}

/// Named phases, each a PETSc log stage and an accumulated wall-clock time.
#[derive(Debug, Default)]
pub struct Phases {
    stages: BTreeMap<&'static str, Stage>,
    seconds: BTreeMap<&'static str, f64>,
}

impl Phases {
    /// Registers one stage per phase name.
    pub fn new(names: &[&'static str]) -> Result<Phases> {
        let mut ph = Phases::default();
        for &n in names {
            ph.stages.insert(n, Stage::register(n)?);
            ph.seconds.insert(n, 0.0);
        }
        Ok(ph)
    }

    /// Runs `f` inside phase `name`, timing it.
    pub fn run<R>(&mut self, name: &'static str, f: impl FnOnce() -> R) -> Result<R> {
        let guard = match self.stages.get(name) {
            Some(s) => Some(s.push()?),
            None => None,
        };
        let t = Instant::now();
        let out = f();
        *self.seconds.entry(name).or_insert(0.0) += t.elapsed().as_secs_f64();
        drop(guard);
        Ok(out)
    }

    /// Pushes the PETSc log stage of phase `name` (popped when the guard drops); time it with
    /// [`Phases::add`].
    pub fn push(&self, name: &'static str) -> Result<Option<StageGuard>> {
        self.stages.get(name).map(|s| s.push()).transpose()
    }

    /// The PETSc log stage of phase `name`, to push where the phase runs inside callbacks.
    pub fn stage(&self, name: &'static str) -> Option<Stage> {
        self.stages.get(name).copied()
    }

    /// Adds time measured elsewhere to a phase.
    pub fn add(&mut self, name: &'static str, seconds: f64) {
        *self.seconds.entry(name).or_insert(0.0) += seconds;
    }

    /// Seconds per phase so far, by name (`summary.json`'s `timings`).
    pub fn timings(&self) -> BTreeMap<String, f64> {
        self.seconds
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect()
    }
}

/// One timed section of work that runs inside another phase's callbacks (the contact search
/// inside the residual evaluation, say): a PETSc log stage pushed while it runs, so
/// `-log_view` reports it apart, and its accumulated wall-clock seconds. Interior mutability:
/// the code it times holds only shared references.
#[derive(Clone, Debug)]
pub struct Section {
    stage: Option<Stage>,
    seconds: std::cell::Cell<f64>,
}

impl Section {
    /// The section logged as stage `name`. Without PETSc (unit tests of the kernels), or if
    /// PETSc refuses the stage, it is only timed.
    pub fn new(name: &str) -> Section {
        let stage = if super::is_initialized() {
            Stage::register(name).ok()
        } else {
            None
        };
        Section {
            stage,
            seconds: std::cell::Cell::new(0.0),
        }
    }

    /// Runs `f` inside the section.
    pub fn time<R>(&self, f: impl FnOnce() -> R) -> R {
        let guard = self.stage.and_then(|s| s.push().ok());
        let t = Instant::now();
        let out = f();
        self.seconds
            .set(self.seconds.get() + t.elapsed().as_secs_f64());
        drop(guard);
        out
    }

    /// Seconds spent in the section so far.
    pub fn seconds(&self) -> f64 {
        self.seconds.get()
    }
}
