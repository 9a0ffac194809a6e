//! What a contact interface shows of itself: the nodal fields of its passes (the interface
//! output), and the force sums of a step (the history).

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use crate::case::ContactMethod;
use crate::contact::law::Status;
use crate::contact::mortar::RejectStats;
use crate::model::{Output, RowField, State, SurfaceOutput};
use crate::vec3::{dot, norm};

use super::{ContactInterfaces, FORCE_SUMS};

/// What a node looks like at one state: the fields written to the interface output.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeFields {
    /// `a_A` (0 without overlap).
    pub area: f64,
    /// The full integral of A's traction function over the current secondary faces around
    /// it (mortar nodes with traction; the reference one for node-on-segment; 0 otherwise).
    pub full_area: f64,
    /// Normalized gap `gh_A` (positive in penetration; 0 without overlap).
    pub gap: f64,
    /// Contact pressure `p_A >= 0`.
    pub pressure: f64,
    /// Normalized slip increment of the step `dsh_A`, tangential part.
    pub slip: [f64; 3],
    /// Tangential traction `t_T` (as applied: times the fade of a fading node).
    pub traction_t: [f64; 3],
    /// The return map's `t_T` before the fade: the history of the next step (not in
    /// `pass_fields`).
    pub law_traction_t: [f64; 3],
    /// Unit nodal normal.
    pub normal: [f64; 3],
    /// 0 open (no overlap, open, or inside the touching band), 1 stick, 2 slip.
    pub status: u8,
    /// The weighted gap vector `g_A` (zero without overlap; not in `pass_fields`).
    pub weighted_gap: [f64; 3],
    /// Node-on-segment: the primary face and closest point (not in `pass_fields`).
    pub segment: Option<(usize, [f64; 2])>,
}

impl ContactInterfaces {
    /// Fields of every traction node of one pass at displacements `u`, on every rank (holders
    /// compute, all sum).
    pub fn pass_fields(
        &self,
        at: &State,
        interface: usize,
        pass: usize,
        world: &SimpleCommunicator,
    ) -> Vec<NodeFields> {
        let local = self.local_fields(at, interface, pass);
        let pass_ref = &self.interfaces[interface].passes[pass];
        let mut flat = vec![0.0; 15 * pass_ref.nodes.len()];
        for (i, f) in local {
            let v = &mut flat[15 * i..15 * i + 15];
            v[0] = f.area;
            v[1] = f.gap;
            v[2] = f.pressure;
            v[3..6].copy_from_slice(&f.slip);
            v[6..9].copy_from_slice(&f.traction_t);
            v[9..12].copy_from_slice(&f.normal);
            v[12] = f.status as f64;
            v[13] = f.full_area;
        }
        let mut all = vec![0.0; flat.len()];
        world.all_reduce_into(&flat[..], &mut all[..], SystemOperation::sum());
        all.chunks(15)
            .map(|v| NodeFields {
                area: v[0],
                gap: v[1],
                pressure: v[2],
                slip: [v[3], v[4], v[5]],
                traction_t: [v[6], v[7], v[8]],
                normal: [v[9], v[10], v[11]],
                status: v[12] as u8,
                full_area: v[13],
                law_traction_t: [0.0; 3],
                weighted_gap: [0.0; 3],
                segment: None,
            })
            .collect()
    }

    /// Fields of the held traction nodes of one pass, `(index into nodes, fields)`.
    pub(crate) fn local_fields(
        &self,
        at: &State,
        interface: usize,
        pass: usize,
    ) -> Vec<(usize, NodeFields)> {
        let iface = &self.interfaces[interface];
        let p = &iface.passes[pass];
        if p.held.is_empty() {
            return Vec::new();
        }
        let x = at.positions();
        let ctx = iface.context(self.modes.get(), &x, &self.x_old);
        if p.method == ContactMethod::NodeOnSegment {
            let tree = p.primary_tree(&x);
            return p
                .held
                .iter()
                .map(|&a| (a, p.nts_node(&ctx, &tree, a, false).1))
                .collect();
        }
        let Ok(normals) = p.normals(&x) else {
            return Vec::new();
        };
        let pairs = p.values_at(&ctx, None, &mut RejectStats::default());
        let by_node = p.pairs_by_node(&pairs, &p.held);
        p.held
            .iter()
            .map(|&a| {
                let fields = match by_node.get(&a) {
                    Some(terms) => {
                        let kin = p.kinematics(&ctx, terms);
                        p.node_block(&ctx, &normals, a, &kin, terms, false).1
                    }
                    None => NodeFields {
                        normal: normals.normal(p.nodes[a]).unwrap_or_default(),
                        ..Default::default()
                    },
                };
                (a, fields)
            })
            .collect()
    }

    /// Total contact force per interface, summed over passes and ranks:
    /// `[normal, tangential, fx, fy, fz, stick, slip, dissipation, max_slip]`, with
    /// `normal = sum_A a_A p_A`,
    /// `tangential = |sum_A a_A t_T,A|`, `f = sum_A a_A t_A` (the force on the primary side of
    /// the first pass; the second pass's terms enter with the opposite sign, its sides being
    /// swapped), the numbers of sticking and slipping nodes, and the frictional work of the
    /// step `sum_A a_A t_T,A . dsh_A` (non-negative: friction dissipates), and the largest
    /// step slip `|dsh_A|` of a pressed node.
    pub fn force_sums(&self, at: &State, world: &SimpleCommunicator) -> Vec<[f64; FORCE_SUMS]> {
        let mut local = Vec::new();
        let mut local_max = Vec::new();
        for i in 0..self.interfaces.len() {
            let mut v = [0.0; 10];
            let mut max_slip = 0.0f64;
            for p in 0..self.interfaces[i].passes.len() {
                // Forces on the primary side of the first pass: the second pass's primary is
                // the first pass's secondary.
                let sign = if p == 0 { 1.0 } else { -1.0 };
                for (_, nf) in self.local_fields(at, i, p) {
                    v[0] += nf.area * nf.pressure;
                    for c in 0..3 {
                        v[1 + c] += sign * nf.area * nf.traction_t[c];
                        v[4 + c] +=
                            sign * nf.area * (nf.pressure * nf.normal[c] + nf.traction_t[c]);
                    }
                    match nf.status {
                        1 => v[7] += 1.0,
                        2 => v[8] += 1.0,
                        _ => {}
                    }
                    v[9] += nf.area * dot(nf.traction_t, nf.slip);
                    if nf.pressure > 0.0 {
                        max_slip = max_slip.max(norm(nf.slip));
                    }
                }
            }
            local.extend(v);
            local_max.push(max_slip);
        }
        let mut all = vec![0.0; local.len()];
        world.all_reduce_into(&local[..], &mut all[..], SystemOperation::sum());
        let mut all_max = vec![0.0; local_max.len()];
        world.all_reduce_into(&local_max[..], &mut all_max[..], SystemOperation::max());
        all.chunks(10)
            .zip(all_max)
            .map(|(v, m)| {
                [
                    v[0],
                    norm([v[1], v[2], v[3]]),
                    v[4],
                    v[5],
                    v[6],
                    v[7],
                    v[8],
                    v[9],
                    m,
                ]
            })
            .collect()
    }

    /// Every pass of every interface as an interface piece (module docs of
    /// `solver::results`): `pressure`, `gap`, `slip`, `traction_t`, `traction`, `status`, `a`.
    pub(crate) fn surface_output(&self, at: &State, world: &SimpleCommunicator) -> Vec<Output> {
        let mut out = Vec::new();
        for (i, iface) in self.interfaces.iter().enumerate() {
            for (p, pass) in iface.passes.iter().enumerate() {
                let nf = self.pass_fields(at, i, p, world);
                out.push(Output::Surface(SurfaceOutput {
                    name: format!("{}_pass{}", iface.name, p + 1),
                    scheme: iface.scheme,
                    faces: pass.secondary.clone(),
                    rows: pass.nodes.clone(),
                    fields: row_fields(&nf),
                }));
            }
        }
        out
    }
}

/// The output fields of a pass's nodes.
fn row_fields(nf: &[NodeFields]) -> Vec<RowField> {
    let vec3 =
        |f: &dyn Fn(&NodeFields) -> [f64; 3]| -> Vec<f64> { nf.iter().flat_map(f).collect() };
    let scalar = |f: &dyn Fn(&NodeFields) -> f64| -> Vec<f64> { nf.iter().map(f).collect() };
    let traction = |f: &NodeFields| -> [f64; 3] {
        std::array::from_fn(|c| f.pressure * f.normal[c] + f.traction_t[c])
    };
    vec![
        RowField::new("pressure", 1, scalar(&|f| f.pressure), true),
        RowField::new("gap", 1, scalar(&|f| f.gap), false),
        RowField::new("slip", 3, vec3(&|f| f.slip), false),
        RowField::new("traction_t", 3, vec3(&|f| f.traction_t), true),
        RowField::new("traction", 3, vec3(&traction), true),
        RowField::new("status", 1, scalar(&|f| f.status as f64), false).absent_as(-1.0),
        RowField::new("a", 1, scalar(&|f| f.area), false),
    ]
}

/// The output code of a node's state: 0 open, 1 stick, 2 slip.
pub(crate) fn status_code(status: Status) -> u8 {
    match status {
        Status::Open => 0,
        Status::Stick => 1,
        Status::Slip => 2,
    }
}
