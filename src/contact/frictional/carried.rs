//! What the contact interfaces carry from one step to the next, written to a checkpoint and
//! read back at a restart ([`crate::model::Contribution::write_state`]): per traction node the
//! Uzawa multipliers, the last converged tangential traction and its normal, the penalties, the
//! weighted gap and the node-on-segment face of the last converged step; per interface the
//! penalty scale, the segment-pair counts and each pass's law states at the last tangent
//! evaluation (from which the next step counts its state changes); and the positions, force
//! sums and state changes of the committed steps. Every value is kept bit for bit.

use crate::contact::mortar::RejectStats;
use crate::error::{Error, Result};
use crate::model::{StateSink, StateSource};

use super::pass::NodeState;
use super::{ContactInterfaces, FORCE_SUMS};

/// Values per traction node in the record `contact node states`.
pub(super) const NODE_VALUES: usize = 20;

/// `segment_old` absent.
pub(super) const NO_SEGMENT: u64 = u64::MAX;

impl ContactInterfaces {
    pub(super) fn write_carried(&self, out: &mut dyn StateSink) {
        out.f64s("contact positions", self.x_old.as_flattened());
        let sums: Vec<f64> = self.history.iter().flatten().flatten().copied().collect();
        out.f64s("contact force sums", &sums);
        out.u64s("contact step changes", &self.step_changes);
        for iface in &self.interfaces {
            out.f64s("contact penalty scale", &[iface.penalty_scale]);
            let counts = iface.stats.borrow().counts().map(|c| c as u64);
            out.u64s("contact pair counts", &counts);
            for pass in &iface.passes {
                let values: Vec<f64> = pass.state.iter().flat_map(node_values).collect();
                out.f64s("contact node states", &values);
                let faces: Vec<u64> = pass
                    .state
                    .iter()
                    .map(|s| s.segment_old.map_or(NO_SEGMENT, |(f, _)| f as u64))
                    .collect();
                out.u64s("contact node faces", &faces);
                let log = pass.state_log.borrow();
                out.u64s("contact law states", &log.to_codes());
            }
        }
    }

    pub(super) fn read_carried(&mut self, from: &mut dyn StateSource) -> Result<()> {
        let x = from.f64s("contact positions")?;
        if x.len() != 3 * self.x_old.len() {
            return Err(mismatch("positions"));
        }
        self.x_old = x.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let sums = from.f64s("contact force sums")?;
        let per_step = self.interfaces.len() * FORCE_SUMS;
        if per_step > 0 && sums.len() % per_step != 0 {
            return Err(mismatch("force sums"));
        }
        self.history = sums
            .chunks_exact(per_step.max(1))
            .map(|step| {
                step.chunks_exact(FORCE_SUMS)
                    .map(|s| std::array::from_fn(|k| s[k]))
                    .collect()
            })
            .collect();
        self.step_changes = from.u64s("contact step changes")?;
        if self.step_changes.len() > self.interfaces.len() {
            return Err(mismatch("state changes"));
        }
        for iface in &mut self.interfaces {
            iface.penalty_scale = one(from.f64s("contact penalty scale")?, "penalty scale")?;
            let counts = from.u64s("contact pair counts")?;
            let counts: [u64; 8] = counts.try_into().map_err(|_| mismatch("pair counts"))?;
            *iface.stats.borrow_mut() = RejectStats::from_counts(counts.map(|c| c as usize));
            for pass in &mut iface.passes {
                let values = from.f64s("contact node states")?;
                let faces = from.u64s("contact node faces")?;
                let n = pass.state.len();
                let primary_faces = pass.pri_faces.len() as u64;
                let face_fits = |&f: &u64| f == NO_SEGMENT || f < primary_faces;
                if values.len() != NODE_VALUES * n
                    || faces.len() != n
                    || !faces.iter().all(face_fits)
                {
                    return Err(mismatch("node states"));
                }
                for ((st, v), &face) in pass
                    .state
                    .iter_mut()
                    .zip(values.chunks_exact(NODE_VALUES))
                    .zip(&faces)
                {
                    set_node_values(st, v, face);
                }
                let codes = from.u64s("contact law states")?;
                pass.state_log
                    .borrow_mut()
                    .set_codes(&codes)
                    .map_err(|()| mismatch("law states"))?;
            }
            iface.last_violation = f64::INFINITY;
        }
        Ok(())
    }
}

/// A node's state as [`NODE_VALUES`] numbers (its face of `segment_old` apart).
pub(super) fn node_values(s: &NodeState) -> [f64; NODE_VALUES] {
    let h = &s.history;
    let gap = s.gap_old.unwrap_or_default();
    let xi = s.segment_old.map_or([0.0; 2], |(_, xi)| xi);
    [
        h.lambda_n,
        h.lambda_t[0],
        h.lambda_t[1],
        h.lambda_t[2],
        h.normal_old[0],
        h.normal_old[1],
        h.normal_old[2],
        h.traction_t_old[0],
        h.traction_t_old[1],
        h.traction_t_old[2],
        s.eps_n,
        s.eps_t,
        s.h,
        s.a_full,
        if s.gap_old.is_some() { 1.0 } else { 0.0 },
        gap[0],
        gap[1],
        gap[2],
        xi[0],
        xi[1],
    ]
}

/// The inverse of [`node_values`].
pub(super) fn set_node_values(s: &mut NodeState, v: &[f64], face: u64) {
    let h = &mut s.history;
    h.lambda_n = v[0];
    h.lambda_t = [v[1], v[2], v[3]];
    h.normal_old = [v[4], v[5], v[6]];
    h.traction_t_old = [v[7], v[8], v[9]];
    (s.eps_n, s.eps_t, s.h, s.a_full) = (v[10], v[11], v[12], v[13]);
    s.gap_old = (v[14] != 0.0).then_some([v[15], v[16], v[17]]);
    s.segment_old = (face != NO_SEGMENT).then_some((face as usize, [v[18], v[19]]));
}

fn one(values: Vec<f64>, what: &str) -> Result<f64> {
    match values[..] {
        [v] => Ok(v),
        _ => Err(mismatch(what)),
    }
}

fn mismatch(what: &str) -> Error {
    Error::Restart(format!(
        "the checkpoint's contact {what} do not fit this case's contact interfaces"
    ))
}
