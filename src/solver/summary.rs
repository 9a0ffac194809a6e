//! What a run says of itself: the progress lines' notes, the summary's metrics of the run, the
//! last line's totals, and the message of a stopped run.

use crate::case::Scene;
use crate::error::{Error, Result};
use crate::interrupt;
use crate::io::output::Summary;
use crate::petsc::SnesOutcome;

use super::state::RunState;

/// A load factor in messages and progress lines: as asked (`{:.6}`), or with `{}` to 12
/// decimals without trailing zeros (the load accumulates its steps, `0.1 + 0.2` reads `0.3`,
/// not `0.30000000000000004`), or in scientific notation when it is tiny (a step cut many
/// times), where the plain forms would run to a hundred digits or show only zeros.
pub(super) struct Load(pub f64);

impl std::fmt::Display for Load {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = self.0 + 0.0; // (-0 prints as 0)
        match f.precision() {
            _ if t != 0.0 && t.abs() < 1e-4 => write!(f, "{t:.6e}"),
            Some(digits) => write!(f, "{t:.digits$}"),
            None => {
                let fixed = format!("{t:.12}");
                write!(f, "{}", fixed.trim_end_matches('0').trim_end_matches('.'))
            }
        }
    }
}

/// The progress line's note on a step's cuts and line-search retries (empty when none).
pub(super) fn retries_note(cuts: usize, retries: usize, line_search: Option<&str>) -> String {
    let mut parts = Vec::new();
    if cuts > 0 {
        parts.push(format!("{cuts} cut(s)"));
    }
    if retries > 0 {
        parts.push(format!(
            "{retries} retry(ies) with {}",
            line_search.unwrap_or_default()
        ));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(", after {}", parts.join(" and "))
    }
}

/// The run's own metrics in the summary: Uzawa and line-search counts (scenes with
/// interfaces), unconverged steps (`steps.on_failure = "continue"`), Newton iterations and the
/// free dofs.
pub(super) fn add_run_metrics(
    summary: &mut Summary,
    scene: &Scene,
    state: &RunState,
    (augmented, fallback): (bool, bool),
    free_dofs: usize,
) {
    let steps = &summary.steps;
    let most = |f: fn(&crate::io::output::StepRecord) -> usize| {
        steps.iter().map(f).max().unwrap_or(0) as f64
    };
    let mut metrics = vec![
        ("max_newton_its", most(|s| s.newton_its)),
        (
            "total_newton_its",
            steps.iter().map(|s| s.newton_its).sum::<usize>() as f64,
        ),
        ("free_dofs", free_dofs as f64),
    ];
    if augmented {
        metrics.push(("uzawa_capped_steps", state.counts.uzawa_capped as f64));
        metrics.push(("max_augmentations_per_step", most(|s| s.augmentations)));
        if fallback {
            metrics.push(("line_search_fallbacks", state.counts.fallbacks as f64));
        }
    }
    if scene.continue_on_failure {
        metrics.push(("unconverged_steps", state.counts.unconverged as f64));
    }
    for (k, v) in metrics {
        summary.metrics.insert(k.to_string(), v);
    }
}

/// The run's totals for its last progress line: `50 steps, 160 Newton its, 2 cuts, 4.21 s`
/// (Newton iterations and cuts of every attempt, failed ones included; cuts and the Uzawa
/// augmentations of the finished steps when there were any).
pub(super) fn totals(summary: &Summary, state: &RunState, seconds: f64) -> String {
    let count = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    let mut parts = vec![
        count(summary.steps.len(), "step"),
        format!("{} Newton its", state.counts.newton),
    ];
    if state.counts.cuts > 0 {
        parts.push(count(state.counts.cuts, "cut"));
    }
    let augmentations: usize = summary.steps.iter().map(|s| s.augmentations).sum();
    if augmentations > 0 {
        parts.push(count(augmentations, "Uzawa augmentation"));
    }
    parts.push(format!("{seconds:.2} s"));
    parts.join(", ")
}

/// The outcome of a solve not started because the run is stopping on `signal`.
pub(super) fn not_started(signal: i32) -> SnesOutcome {
    SnesOutcome {
        converged: false,
        reason: "INTERRUPTED",
        iterations: 0,
        linear_iterations: 0,
        residual_history: Vec::new(),
        domain_error: Some(format!("interrupted by {}", interrupt::name(signal))),
        shortened: false,
        second_solves: 0,
        second_solves_kept: 0,
    }
}

/// What a run stopped by `signal` (its name) leaves: `interrupted by SIGINT after step 20 (load
/// 0.4): ...`.
pub(super) fn interruption(signal: &str, summary: &Summary, out_dir: &std::path::Path) -> String {
    match summary.steps.last() {
        Some(last) => format!(
            "interrupted by {signal} after step {} (load {:.6}): the outputs in {} hold the {} \
             step(s) finished",
            last.step,
            Load(last.load),
            out_dir.display(),
            summary.steps.len()
        ),
        None => format!("interrupted by {signal} before the first step finished"),
    }
}

impl super::Run<'_> {
    /// Ends the run: whether it completed, the displacements and metrics of its last finished
    /// state, the summary, and the last line (*collective*). A run that stopped or failed
    /// returns its message as the error.
    pub(super) fn finish(&mut self) -> Result<()> {
        let summary = &mut self.summary;
        summary.completed = self.state.finished();
        summary.converged = summary.completed && self.state.counts.unconverged == 0;
        let interrupted = self.state.stop.get().map(interrupt::name);
        if let Some(signal) = &interrupted {
            summary.message = Some(interruption(signal, summary, &self.cx.opts.out_dir));
        }
        // Results describe the last converged state (x was restored after a failed attempt).
        let mut ev = self.cx.evaluator.borrow_mut();
        ev.t = self.state.t;
        ev.load(self.cx.scene, &self.cx.dofs, &self.linear.x)?;
        let at = ev.state(self.cx.scene);
        self.results
            .write_displacements(self.cx.scene, &self.cx.dofs, at.u, &self.cx.world);
        // The model's metrics describe a finished step: none before the first (the undeformed
        // state would pass for a result).
        if self.state.step > 0 {
            for (k, v) in self.model.metrics(&at, &self.cx.world) {
                self.summary.metrics.insert(k, v);
            }
        }
        drop(ev);
        let flags = (
            self.model.is_augmented(),
            self.fallback_line_search.is_some(),
        );
        add_run_metrics(
            &mut self.summary,
            self.cx.scene,
            &self.state,
            flags,
            self.cx.dofs.total_free,
        );
        self.summary.timings = self.phases.timings();
        self.summary.peak_memory_mb = peak_memory_of_ranks(&self.cx.world);
        self.summary.contact_seconds_per_rank =
            contact_seconds_of_ranks(&self.summary.timings, &self.cx.world);
        if self.cx.rank == 0 {
            self.results.write_summary(&self.summary);
        }
        self.results.agree(&self.cx.world)?;
        self.say(self.last_line(interrupted.is_some()));
        match &self.summary.message {
            Some(m) if interrupted.is_some() => Err(Error::Interrupted(m.clone())),
            Some(m) if !self.summary.completed => Err(Error::Solve(m.clone())),
            _ => Ok(()),
        }
    }

    /// `mortar: converged: 50 steps, 160 Newton its, 4.21 s -> out/sliding_blocks`.
    fn last_line(&self, interrupted: bool) -> String {
        let summary = &self.summary;
        let outcome = match (summary.completed, self.state.counts.unconverged) {
            (true, 0) => "converged".to_string(),
            (true, n) => format!(
                "completed with {n} unconverged step(s) accepted (steps.on_failure = \
                 \"continue\")"
            ),
            (false, _) if interrupted => "interrupted".to_string(),
            (false, _) => "FAILED".to_string(),
        };
        format!(
            "mortar: {outcome}: {} -> {}",
            totals(summary, &self.state, self.started.elapsed().as_secs_f64()),
            self.cx.opts.out_dir.display()
        )
    }
}

/// The peak resident memory of every rank, in MB (*collective*); empty when a rank cannot say.
fn peak_memory_of_ranks(world: &mpi::topology::SimpleCommunicator) -> Vec<f64> {
    let all = of_every_rank(crate::memory::peak_mb().unwrap_or(-1.0), world);
    if all.iter().any(|&m| m < 0.0) {
        Vec::new()
    } else {
        all
    }
}

/// The timings of the contact work: search, mortar integration and contact assembly.
const CONTACT_PHASES: [&str; 3] = ["contact_search", "contact_integration", "contact_assembly"];

/// Every rank's seconds in the [`CONTACT_PHASES`] of its `timings` (*collective*).
fn contact_seconds_of_ranks(
    timings: &std::collections::BTreeMap<String, f64>,
    world: &mpi::topology::SimpleCommunicator,
) -> Vec<f64> {
    let mine: f64 = CONTACT_PHASES.iter().filter_map(|p| timings.get(*p)).sum();
    of_every_rank(mine, world)
}

/// `mine` of every rank, by rank (*collective*).
fn of_every_rank(mine: f64, world: &mpi::topology::SimpleCommunicator) -> Vec<f64> {
    use mpi::collective::CommunicatorCollectives;
    use mpi::topology::Communicator;
    let mut all = vec![0.0; world.size() as usize];
    world.all_gather_into(&mine, &mut all[..]);
    all
}

#[cfg(test)]
mod tests {
    use super::Load;

    #[test]
    fn loads_print_as_asked_unless_tiny() {
        assert_eq!(format!("{:.6}", Load(0.5)), "0.500000");
        assert_eq!(format!("{}", Load(0.15625)), "0.15625");
        assert_eq!(format!("{}", Load(0.0)), "0");
        assert_eq!(format!("{}", Load(1.0)), "1");
        assert_eq!(format!("{}", Load(0.1 + 0.2)), "0.3");
        assert_eq!(format!("{}", Load(13.0 * 0.02)), "0.26");
        assert_eq!(format!("{}", Load(-0.0)), "0");
        // A step cut 483 times: not 150 digits, not zeros.
        let tiny = 0.5f64.powi(483);
        assert_eq!(format!("{}", Load(tiny)), format!("{tiny:.6e}"));
        assert_eq!(format!("{:.6}", Load(tiny)), format!("{tiny:.6e}"));
    }
}
