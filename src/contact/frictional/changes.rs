//! How many traction nodes change their law state (open, stick, slip) from one Newton
//! iteration to the next: the measure of how far a Newton iterate still is from the active set
//! of the solution, where full Newton steps cycle.
//!
//! Every tangent evaluation (one per Newton iteration, and the predictor's) records the state
//! of each node this rank holds, as the residual's branch of the law gave it ([`status_code`]:
//! a node without traction is open). The change from the previous tangent evaluation is counted
//! four ways: closed (open to pressed), opened (pressed to open), slipped (stick to slip) and
//! stuck (slip to stick). The counts of the last evaluation feed the `-contact_monitor` lines;
//! their sum over a load step's evaluations (its last attempt: the count restarts when a cut
//! step starts again) is the history column `contact_<name>_state_changes`.
//!
//! [`status_code`]: super::status_code

use std::collections::BTreeMap;
use std::ops::AddAssign;

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use super::{ContactInterfaces, ContactPass};

/// Nodes whose law state changed between two tangent evaluations, by kind of change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StateChanges {
    /// Open to pressed (stick or slip).
    pub closed: u64,
    /// Pressed to open.
    pub opened: u64,
    /// Stick to slip.
    pub slipped: u64,
    /// Slip to stick.
    pub stuck: u64,
}

impl StateChanges {
    /// Every change, whatever its kind.
    pub fn total(&self) -> u64 {
        self.closed + self.opened + self.slipped + self.stuck
    }

    /// The change of one node from state `old` to `new` ([`super::status_code`]).
    fn of(old: u8, new: u8) -> StateChanges {
        let mut c = StateChanges::default();
        match (old, new) {
            (a, b) if a == b => {}
            (0, _) => c.closed = 1,
            (_, 0) => c.opened = 1,
            (1, _) => c.slipped = 1,
            _ => c.stuck = 1,
        }
        c
    }

    /// As the four counts, for a reduction over ranks.
    pub(crate) fn to_array(self) -> [u64; 4] {
        [self.closed, self.opened, self.slipped, self.stuck]
    }

    pub(crate) fn from_array(a: [u64; 4]) -> StateChanges {
        StateChanges {
            closed: a[0],
            opened: a[1],
            slipped: a[2],
            stuck: a[3],
        }
    }
}

impl AddAssign for StateChanges {
    fn add_assign(&mut self, o: StateChanges) {
        self.closed += o.closed;
        self.opened += o.opened;
        self.slipped += o.slipped;
        self.stuck += o.stuck;
    }
}

/// The law states of one pass's held nodes at its last tangent evaluation, and the changes
/// counted so far.
#[derive(Clone, Debug, Default)]
pub(crate) struct StateLog {
    /// Per traction node of the pass: its state code (written for the held nodes at each
    /// tangent evaluation, for every node at a new deal).
    states: Vec<u8>,
    /// The changes of the last tangent evaluation.
    pub(crate) last: StateChanges,
    /// Their sum since [`StateLog::start_step`].
    pub(crate) step: StateChanges,
    /// Nodes sticking and slipping at the last tangent evaluation.
    pub(crate) pressed: [u64; 2],
}

impl StateLog {
    /// Records a tangent evaluation: `now` holds `(node, state code)` of every held node.
    pub(crate) fn record(&mut self, nodes: usize, now: impl IntoIterator<Item = (usize, u8)>) {
        self.states.resize(nodes, 0);
        let mut changes = StateChanges::default();
        let mut pressed = [0u64; 2];
        for (a, code) in now {
            changes += StateChanges::of(self.states[a], code);
            if code > 0 {
                pressed[usize::from(code - 1)] += 1;
            }
            self.states[a] = code;
        }
        self.last = changes;
        self.step += changes;
        self.pressed = pressed;
    }

    /// The states of the last tangent evaluation, then the pressed counts (a checkpoint).
    pub(crate) fn to_codes(&self) -> Vec<u64> {
        let mut codes: Vec<u64> = self.states.iter().map(|&c| u64::from(c)).collect();
        codes.extend(self.pressed);
        codes
    }

    /// The inverse of [`StateLog::to_codes`] (a restart); an error when they are not codes.
    pub(crate) fn set_codes(&mut self, codes: &[u64]) -> Result<(), ()> {
        let (states, pressed) = codes.split_at(codes.len().checked_sub(2).ok_or(())?);
        self.states = states
            .iter()
            .map(|&c| u8::try_from(c).map_err(|_| ()))
            .collect::<Result<_, ()>>()?;
        self.pressed = [pressed[0], pressed[1]];
        Ok(())
    }

    /// Sets the state codes of every node (before a new deal of the nodes to the ranks).
    pub(crate) fn set_states(&mut self, codes: &[u64]) {
        self.states = codes.iter().map(|&c| c as u8).collect();
    }

    /// The state code of node `a` (open when none was recorded).
    pub(crate) fn state(&self, a: usize) -> u64 {
        self.states.get(a).map_or(0, |&c| u64::from(c))
    }

    /// The nodes this rank holds are now `held` (a new deal): the last evaluation's changes
    /// and pressed counts become those of the held nodes, so that their sums over the ranks
    /// stay those of every node (no rank keeps counts of nodes it gave away).
    pub(crate) fn dealt(&mut self, held: &[usize]) {
        self.last = StateChanges::default();
        let mut pressed = [0u64; 2];
        for &a in held {
            match self.state(a) {
                0 => {}
                code => pressed[(code - 1) as usize] += 1,
            }
        }
        self.pressed = pressed;
    }

    /// A load step (or a cut step's new attempt) starts: its count restarts.
    pub(crate) fn start_step(&mut self) {
        self.step = StateChanges::default();
    }
}

impl ContactPass {
    /// Records a tangent evaluation's law states: `evaluated` holds `(node, state code)` of the
    /// nodes it evaluated; the other held nodes are open.
    pub(crate) fn record_states(&self, evaluated: Vec<(usize, u8)>) {
        let mut codes: BTreeMap<usize, u8> = evaluated.into_iter().collect();
        let now = self
            .held
            .iter()
            .map(|&a| (a, codes.remove(&a).unwrap_or(0)));
        self.state_log.borrow_mut().record(self.nodes.len(), now);
    }
}

impl ContactInterfaces {
    /// Calls `f` with the state log of every pass.
    pub(crate) fn for_each_log(&self, mut f: impl FnMut(&mut StateLog)) {
        for pass in self.passes() {
            f(&mut pass.state_log.borrow_mut());
        }
    }

    /// Per interface, over every rank (*collective*): the changes `of` picks from each pass's
    /// log, summed over the passes, and the nodes sticking and slipping at the last tangent
    /// evaluation.
    pub(crate) fn state_changes(
        &self,
        world: &SimpleCommunicator,
        of: impl Fn(&StateLog) -> StateChanges,
    ) -> Vec<(StateChanges, [u64; 2])> {
        let local: Vec<u64> = self
            .interfaces
            .iter()
            .flat_map(|i| {
                let mut sum = [0u64; 6];
                for log in i.passes.iter().map(|p| p.state_log.borrow()) {
                    let counts = of(&log).to_array().into_iter().chain(log.pressed);
                    sum.iter_mut().zip(counts).for_each(|(s, c)| *s += c);
                }
                sum
            })
            .collect();
        let mut total = vec![0u64; local.len()];
        world.all_reduce_into(&local[..], &mut total[..], SystemOperation::sum());
        total
            .chunks(6)
            .map(|c| {
                let changes = StateChanges::from_array([c[0], c[1], c[2], c[3]]);
                (changes, [c[4], c[5]])
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_of_change_is_counted_once_per_node() {
        let mut log = StateLog::default();
        log.record(4, [(0, 0), (1, 1), (2, 2), (3, 1)]);
        assert_eq!(log.last.closed, 3, "from open");
        assert_eq!(log.pressed, [2, 1]);
        log.record(4, [(0, 2), (1, 2), (2, 1), (3, 0)]);
        let expected = StateChanges {
            closed: 1,
            opened: 1,
            slipped: 1,
            stuck: 1,
        };
        assert_eq!(log.last, expected);
        assert_eq!(log.step.total(), 7);
        log.start_step();
        log.record(4, [(0, 2), (1, 2), (2, 1), (3, 0)]);
        assert_eq!(log.last.total(), 0);
        assert_eq!(log.step.total(), 0);
        assert_eq!(StateChanges::from_array(expected.to_array()), expected);
    }

    /// After a new deal a rank counts only the nodes it holds now: over two ranks, every
    /// pressed node once, and no change left over from nodes given away.
    #[test]
    fn a_new_deal_counts_the_pressed_nodes_held_now() {
        let mut log = StateLog::default();
        log.record(4, [(0, 1), (1, 2), (2, 2), (3, 0)]);
        assert_eq!((log.pressed, log.last.total()), ([1, 2], 3));
        let mut other = log.clone();
        log.dealt(&[0, 3]);
        other.dealt(&[1, 2]);
        assert_eq!((log.pressed, other.pressed), ([1, 0], [0, 2]));
        assert_eq!(log.last.total() + other.last.total(), 0);
        assert_eq!(log.step.total(), 3, "the step's count is kept");
        assert_eq!((log.state(2), log.state(9)), (2, 0));
    }
}
