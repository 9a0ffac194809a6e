//! Agreement between ranks: the lowest rank with something to say, its text on every rank,
//! and one domain error for a state that some rank cannot evaluate.

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, Root};

use crate::error::{Error, Result};
use crate::model::DomainIssue;
use crate::petsc::CallbackError;

/// *Collective*: the lowest rank for which `flag` holds, or the number of ranks if none.
pub fn lowest_rank_with(world: &SimpleCommunicator, flag: bool) -> i32 {
    let mine = if flag { world.rank() } else { world.size() };
    let mut lowest = 0;
    world.all_reduce_into(&mine, &mut lowest, SystemOperation::min());
    lowest
}

/// *Collective*: whether `flag` holds on some rank.
pub(crate) fn any_rank(world: &SimpleCommunicator, flag: bool) -> bool {
    lowest_rank_with(world, flag) < world.size()
}

/// *Collective*: the sum of a count over the ranks.
pub(crate) fn sum_over_ranks(world: &SimpleCommunicator, mine: u64) -> u64 {
    let mut all = 0;
    world.all_reduce_into(&mine, &mut all, SystemOperation::sum());
    all
}

/// *Collective*: the `text` of the lowest rank that has one, on every rank (`None` when no
/// rank has one).
pub(crate) fn first_rank_text(world: &SimpleCommunicator, text: Option<&str>) -> Option<String> {
    let first = lowest_rank_with(world, text.is_some());
    if first == world.size() {
        return None;
    }
    let mut bytes = match text {
        Some(t) if world.rank() == first => t.as_bytes().to_vec(),
        _ => Vec::new(),
    };
    let root = world.process_at_rank(first);
    let mut len = bytes.len() as u64;
    root.broadcast_into(&mut len);
    bytes.resize(len as usize, 0);
    root.broadcast_into(&mut bytes[..]);
    Some(String::from_utf8_lossy(&bytes).into_owned())
}

/// *Collective*: every rank returns `Ok` when `mine` is `Ok` on every rank, else the error of
/// the lowest failing rank as [`Error::Output`] (its message sent to all).
pub(crate) fn agree_on(world: &SimpleCommunicator, mine: Result<()>) -> Result<()> {
    let message = mine.err().map(|e| e.to_string());
    match first_rank_text(world, message.as_deref()) {
        Some(m) => Err(Error::Output(m)),
        None => Ok(()),
    }
}

/// *Collective*: turns a local domain issue (an inverted element, a failed contact
/// evaluation) into the same domain error on every rank.
pub(super) fn domain_check(
    world: &SimpleCommunicator,
    issue: Option<DomainIssue>,
) -> Result<(), CallbackError> {
    // The lowest inverted element of all ranks (each rank's first is its lowest: elements are
    // visited in ascending order), with its det F from its owner; else the contact failure of
    // the lowest rank that has one: the message does not depend on the partition.
    let element = match &issue {
        Some(DomainIssue::Inverted(i)) => i.element as i64,
        _ => i64::MAX,
    };
    let mut lowest = i64::MAX;
    world.all_reduce_into(&element, &mut lowest, SystemOperation::min());
    if lowest != i64::MAX {
        let det = match &issue {
            Some(DomainIssue::Inverted(i)) if i.element as i64 == lowest => i.det,
            _ => 0.0,
        };
        let mut owner_det = 0.0;
        world.all_reduce_into(&det, &mut owner_det, SystemOperation::sum());
        return Err(CallbackError::Domain(format!(
            "element {lowest} inverted (det F = {owner_det:.3e})"
        )));
    }
    let mine = match &issue {
        Some(DomainIssue::Contact(m)) => Some(m.as_str()),
        _ => None,
    };
    match first_rank_text(world, mine) {
        Some(m) => Err(CallbackError::Domain(format!("contact: {m}"))),
        None => Ok(()),
    }
}
