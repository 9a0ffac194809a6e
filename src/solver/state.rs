//! The mutable state of a run: where the load stands, the step size after cuts, and the
//! counters the progress lines and the summary report.

use crate::case::Scene;

/// The load path so far.
#[derive(Debug)]
pub(super) struct RunState {
    /// The load factor of the last finished step.
    pub t: f64,
    /// The size of the next step (halved by cuts, doubled back after a converged step).
    pub dt: f64,
    /// `1 / steps.count`.
    pub dt_nominal: f64,
    /// The smallest step allowed (a hair below the nominal one halved `max_cuts` times).
    pub dt_min: f64,
    /// Cuts of the current step in a row.
    pub cuts_in_row: usize,
    /// Finished steps.
    pub step: usize,
    pub counts: Counts,
    /// The signal the ranks agreed to stop on ([`crate::interrupt`]), once they have: at a
    /// step's start, or in a Jacobian evaluation, which ends the solve under way (any later
    /// solve of the step returns at once).
    pub stop: std::cell::Cell<Option<i32>>,
    /// The next step's first solve starts with the fallback line search instead of full
    /// steps: the last step's first solve needed it (its full steps failed, or, started with
    /// it, it shortened a step). See [`super::Run::attempt`]; a stopped step puts back the
    /// value it started with.
    pub lead_with_fallback: bool,
}

/// Counters over the whole run.
#[derive(Debug, Default)]
pub(super) struct Counts {
    /// Steps whose Uzawa loop stopped at its cap.
    pub uzawa_capped: usize,
    /// Solves redone with the fallback line search.
    pub fallbacks: usize,
    /// [`Counts::fallbacks`] before the current step (for its progress line).
    pub fallbacks_before: usize,
    /// Steps accepted without convergence (`steps.on_failure = "continue"`).
    pub unconverged: usize,
    /// Newton iterations of every attempt, failed ones included (the last line).
    pub newton: usize,
    /// Every cut.
    pub cuts: usize,
}

impl RunState {
    /// The state of a run that has not begun.
    pub fn new(scene: &Scene) -> RunState {
        let dt_nominal = 1.0 / scene.steps as f64;
        RunState {
            t: 0.0,
            dt: dt_nominal,
            dt_nominal,
            dt_min: dt_nominal * 0.5f64.powi(scene.max_cuts as i32) * (1.0 - 1e-12),
            cuts_in_row: 0,
            step: 0,
            counts: Counts::default(),
            stop: std::cell::Cell::new(None),
            lead_with_fallback: false,
        }
    }

    /// Whether the load path is complete.
    pub fn finished(&self) -> bool {
        self.t >= 1.0 - 1e-12
    }

    /// The load factor the next step aims at (the end of the load within 1e-9 of it).
    pub fn next_load(&self) -> f64 {
        if self.t + self.dt > 1.0 - 1e-9 {
            1.0
        } else {
            self.t + self.dt
        }
    }

    /// A step finished at load `t`.
    pub fn advance(&mut self, t: f64) {
        self.step += 1;
        self.t = t;
    }

    /// After a finished step's outputs: the cut count and the step size start afresh.
    pub fn close_step(&mut self) {
        self.cuts_in_row = 0;
        self.counts.fallbacks_before = self.counts.fallbacks;
        self.dt = (2.0 * self.dt).min(self.dt_nominal);
    }

    /// The size of the step under way: [`Self::dt`], or less where the end of the load
    /// clamps it.
    pub fn taken(&self) -> f64 {
        self.next_load() - self.t
    }

    /// A failed step is cut: the same step again at half the size it took (not half the
    /// nominal size, which for a last step clamped at the end of the load may retry the very
    /// same load).
    pub fn cut(&mut self) {
        self.dt = 0.5 * self.taken();
        self.cuts_in_row += 1;
        self.counts.cuts += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(steps: usize) -> RunState {
        let dt_nominal = 1.0 / steps as f64;
        RunState {
            t: 0.0,
            dt: dt_nominal,
            dt_nominal,
            dt_min: dt_nominal / 4.0,
            cuts_in_row: 0,
            step: 0,
            counts: Counts::default(),
            stop: std::cell::Cell::new(None),
            lead_with_fallback: false,
        }
    }

    /// Three steps, the first cut once: the steps end at 1/6, 1/2, 5/6 and the fourth is
    /// clamped to the last sixth; cut, it retries at 11/12, not at the same load 1.
    #[test]
    fn a_cut_halves_the_step_taken() {
        let mut s = state(3);
        s.cut();
        assert!((s.next_load() - 1.0 / 6.0).abs() < 1e-15);
        for end in [1.0 / 6.0, 0.5, 5.0 / 6.0] {
            assert!(
                (s.next_load() - end).abs() < 1e-12,
                "{} {end}",
                s.next_load()
            );
            s.advance(s.next_load());
            s.close_step();
        }
        assert_eq!(s.next_load(), 1.0);
        assert!((s.taken() - 1.0 / 6.0).abs() < 1e-12);
        s.cut();
        assert!(
            (s.next_load() - 11.0 / 12.0).abs() < 1e-12,
            "{}",
            s.next_load()
        );
        assert_eq!(s.counts.cuts, 2);
    }
}
