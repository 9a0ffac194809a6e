//! Mesh tying of dissimilar meshes: the vector weighted-gap constraint, by penalty plus Uzawa
//! augmented Lagrangian (docs/theory.md sections 1, 4 and 8).
//!
//! # The constraint
//!
//! For every traction node A of the secondary side, with the mortar weights of
//! `contact::mortar` computed **once, on the reference configuration** (so the constraint is
//! linear),
//!
//! `g_A = sum_B n1_AB u1_B - sum_C n2_AC u2_C`   (a vector, units length x area),
//!
//! written on displacements rather than positions, so that the small initial mismatch of two
//! faceted discretizations of one curved surface is not "closed" as a prestress. The tied
//! traction is `t_A = lambda_A + eps_A g_A / a_A` with `a_A = sum_B n1_AB`, the penalty
//! `eps_A = alpha E / h_A` (`alpha` the interface's `penalty`, E the secondary body's Young's
//! modulus, `h_A = sqrt(a_A)`), and the Uzawa multiplier `lambda_A`, fixed inside a Newton solve.
//!
//! # Residual and tangent
//!
//! With the terms of row A written as `(node k, w_k)` (`w = +n1_AB` for secondary nodes,
//! `-n2_AC` for primary nodes), the penalty energy `sum_A eps_A |g_A|^2 / (2 a_A)` plus
//! `lambda_A . g_A` gives the residual contribution `F_k += w_k t_A` and the (symmetric,
//! constant) tangent `K_kl += (eps_A / a_A) w_k w_l I`. A secondary node thus receives
//! `-sum_A n1_AB t_A` as a force and a primary node `+sum_A n2_AC t_A`: equal and opposite in
//! total, because `sum_B n1_AB = sum_C n2_AC` (linear momentum).
//!
//! # Uzawa
//!
//! After a converged Newton solve: if some `|g_A| / a_A > uzawa_tol h_A`, every
//! `lambda_A += eps_A g_A / a_A` and the step is solved again, at most `uzawa_max` times.
//! Plain penalty is `uzawa_max = 0`.
//!
//! # Two passes
//!
//! Pass 2 swaps the sides (the primary faces carry tractions too) and its rows are added to
//! those of pass 1.
//!
//! # Prescribed dofs on the interface
//!
//! A row keeps all three components even where its traction node has a prescribed component
//! (a symmetry plane crossing the interface). Dropping those components would also drop the
//! coupling they give to nearby free primary nodes, and the tied patch test would fail; the
//! proper remedy, a multiplier basis modified at Dirichlet boundaries, is not done. Where the
//! kept components over-constrain (a fine secondary side of Hex8 on symmetry planes), the Uzawa
//! loop cannot meet its tolerance, stops at `uzawa_max` and says so (a warning, and
//! `uzawa_capped_steps` in the summary); docs/verification.md gives the effect measured on the
//! solution.
//!
//! # Parallel layout
//!
//! Each rank integrates the secondary faces whose element it owns (against every primary face:
//! the mesh is replicated), then the weight triplets are all-gathered, so every rank knows every
//! row (interface data only: it grows like the surface). The owner of node A hands out row A's
//! residual and tangent blocks over its terms' nodes, whatever ranks own their rows; every rank
//! hands out the couplings of every row, for the pattern of the rows it owns. Every rank
//! gathers the displacements of every interface node.

mod setup;

use std::collections::BTreeMap;

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use crate::case::{InterfaceKind, Scene};
use crate::contact::mortar::TractionScheme;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::mesh::FaceRef;
use crate::model::{
    Augmentation, Augmented, Contribution, DomainIssue, ForceSink, Output, RowField, State,
    StateSink, StateSource, SurfaceOutput, TangentSink,
};
use crate::vec3::norm;

pub(crate) use setup::young_by_node;

/// One constraint row: traction node A and its terms.
#[derive(Clone, Debug)]
pub struct Row {
    /// The traction node A.
    pub node: usize,
    /// a_A = sum_B n1_AB.
    pub area: f64,
    /// Penalty eps_A.
    pub eps: f64,
    /// h_A = sqrt(a_A).
    pub h: f64,
    /// (node, weight): +n1_AB for secondary nodes B, -n2_AC for primary nodes C.
    pub terms: Vec<(usize, f64)>,
    /// Uzawa multiplier (meaningful on the owner of `node`).
    pub lambda: [f64; 3],
}

impl Row {
    /// g_A for the displacements `u` (dof-indexed).
    pub fn gap(&self, u: &[f64]) -> [f64; 3] {
        let mut g = [0.0; 3];
        for &(k, w) in &self.terms {
            for c in 0..3 {
                g[c] += w * u[3 * k + c];
            }
        }
        g
    }

    /// t_A = lambda_A + eps_A g_A / a_A.
    pub fn traction(&self, u: &[f64]) -> [f64; 3] {
        let g = self.gap(u);
        let s = self.eps / self.area;
        [
            self.lambda[0] + s * g[0],
            self.lambda[1] + s * g[1],
            self.lambda[2] + s * g[2],
        ]
    }

    /// The nodes of the row's terms.
    fn nodes(&self) -> Vec<usize> {
        self.terms.iter().map(|t| t.0).collect()
    }
}

/// The rows of one pass of one interface.
#[derive(Clone, Debug, Default)]
pub struct Pass {
    /// Faces that carried the tractions in this pass.
    pub secondary: Vec<FaceRef>,
    pub rows: Vec<Row>,
}

/// One tied interface.
#[derive(Clone, Debug)]
pub struct Tied {
    pub name: String,
    pub scheme: TractionScheme,
    pub passes: Vec<Pass>,
    pub uzawa_tol: f64,
    pub uzawa_max: usize,
    /// Rejected and integrated segment pairs by kind, summed over passes and ranks.
    pub stats: BTreeMap<String, usize>,
}

/// Every tied interface of a scene, as this rank sees it.
#[derive(Clone, Debug, Default)]
pub struct TiedInterfaces {
    pub interfaces: Vec<Tied>,
    rank: usize,
    node_owner: Vec<usize>,
    /// The multipliers a cut step returns to ([`Contribution::save`]).
    saved: Vec<[f64; 3]>,
}

impl TiedInterfaces {
    /// Integrates the mortar weights of every interface on the reference configuration
    /// (*collective*).
    pub fn new(scene: &Scene, dofs: &DofMap, world: &SimpleCommunicator) -> Result<TiedInterfaces> {
        let mut interfaces = Vec::new();
        for iface in scene
            .interfaces
            .iter()
            .filter(|i| i.kind == InterfaceKind::Tied)
        {
            let mut passes = Vec::new();
            let mut stats: BTreeMap<String, usize> = BTreeMap::new();
            for pass in 0..iface.passes {
                let (sec, pri) = crate::contact::pass_sides(iface, pass);
                let (local, local_stats) = setup::integrate_side(scene, dofs, iface, sec, pri);
                for (k, v) in setup::reduce_stats(&local_stats, world) {
                    *stats.entry(k).or_insert(0) += v;
                }
                let all = setup::all_gather(&local, world);
                let rows = setup::build_rows(scene, iface, &all);
                setup::check_coverage(scene, iface, pass, sec, &rows, world)?;
                passes.push(Pass {
                    secondary: sec.to_vec(),
                    rows,
                });
            }
            interfaces.push(Tied {
                name: iface.name.clone(),
                scheme: iface.scheme,
                passes,
                uzawa_tol: iface.uzawa_tol,
                uzawa_max: iface.uzawa_max,
                stats,
            });
        }
        Ok(TiedInterfaces {
            interfaces,
            rank: dofs.rank,
            node_owner: dofs.node_owner.clone(),
            saved: Vec::new(),
        })
    }

    /// True when the scene has no tied interface.
    pub fn is_empty(&self) -> bool {
        self.interfaces.is_empty()
    }

    fn rows(&self) -> impl Iterator<Item = &Row> {
        self.interfaces
            .iter()
            .flat_map(|i| i.passes.iter())
            .flat_map(|p| p.rows.iter())
    }

    fn owned_rows(&self) -> impl Iterator<Item = &Row> {
        self.rows().filter(|r| self.node_owner[r.node] == self.rank)
    }

    /// Every node that appears in a constraint (the displacements every rank gathers).
    pub fn nodes(&self) -> Vec<usize> {
        let mut n: Vec<usize> = self
            .rows()
            .flat_map(|r| r.terms.iter().map(|t| t.0))
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// The largest `|g_A| / (a_A h_A)` over the rows of interface `i` (*collective*).
    pub fn max_relative_gap_of(&self, i: usize, u: &[f64], world: &SimpleCommunicator) -> f64 {
        let local = self.interfaces[i]
            .passes
            .iter()
            .flat_map(|p| p.rows.iter())
            .filter(|r| self.node_owner[r.node] == self.rank)
            .map(|r| norm(r.gap(u)) / (r.area * r.h))
            .fold(0.0, f64::max);
        let mut global = 0.0;
        world.all_reduce_into(&local, &mut global, SystemOperation::max());
        global
    }

    /// The largest relative gap over every interface (*collective*).
    pub fn max_relative_gap(&self, u: &[f64], world: &SimpleCommunicator) -> f64 {
        (0..self.interfaces.len())
            .map(|i| self.max_relative_gap_of(i, u, world))
            .fold(0.0, f64::max)
    }

    /// One Uzawa step, interface by interface (*collective*): every interface whose gap exceeds
    /// its `uzawa_tol` and that has augmentations left (`done < uzawa_max`) gets
    /// `lambda_A += eps_A g_A / a_A` on its owned rows. Returns what happened and the largest
    /// relative gap.
    fn uzawa_step(
        &mut self,
        u: &[f64],
        done: usize,
        world: &SimpleCommunicator,
    ) -> (Augmented, f64) {
        let mut result = Augmented::Converged;
        let mut largest = 0.0f64;
        for i in 0..self.interfaces.len() {
            let gap = self.max_relative_gap_of(i, u, world);
            largest = largest.max(gap);
            let tied = &self.interfaces[i];
            if gap <= tied.uzawa_tol || tied.uzawa_max == 0 {
                continue;
            }
            if done >= tied.uzawa_max {
                result = result.and(Augmented::CapReached);
                continue;
            }
            let (rank, owner) = (self.rank, &self.node_owner);
            for row in self.interfaces[i]
                .passes
                .iter_mut()
                .flat_map(|p| p.rows.iter_mut())
                .filter(|r| owner[r.node] == rank)
            {
                row.lambda = row.traction(u);
            }
            result = Augmented::Updated;
        }
        (result, largest)
    }

    fn rows_mut(&mut self) -> impl Iterator<Item = &mut Row> {
        self.interfaces
            .iter_mut()
            .flat_map(|i| i.passes.iter_mut())
            .flat_map(|p| p.rows.iter_mut())
    }

    /// Tractions and gaps of every row of one pass, on every rank (owners compute, all sum;
    /// *collective*).
    pub fn pass_fields(
        &self,
        interface: usize,
        pass: usize,
        u: &[f64],
        world: &SimpleCommunicator,
    ) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let rows = &self.interfaces[interface].passes[pass].rows;
        let mut local = vec![0.0; 6 * rows.len()];
        for (i, r) in rows.iter().enumerate() {
            if self.node_owner[r.node] == self.rank {
                let t = r.traction(u);
                let g = r.gap(u);
                local[6 * i..6 * i + 3].copy_from_slice(&t);
                for c in 0..3 {
                    local[6 * i + 3 + c] = g[c] / r.area;
                }
            }
        }
        let mut all = vec![0.0; local.len()];
        world.all_reduce_into(&local[..], &mut all[..], SystemOperation::sum());
        all.chunks(6)
            .map(|c| ([c[0], c[1], c[2]], [c[3], c[4], c[5]]))
            .unzip()
    }

    /// One pass as an interface piece: `traction` (t_A), `weighted_gap` (g_A), `gap`
    /// (g_A / a_A) and `a` (a_A) at its traction nodes (*collective*).
    fn pass_output(&self, i: usize, p: usize, u: &[f64], world: &SimpleCommunicator) -> Output {
        let tied = &self.interfaces[i];
        let pass = &tied.passes[p];
        let (traction, gap) = self.pass_fields(i, p, u, world);
        let flat = |v: &[[f64; 3]]| -> Vec<f64> { v.iter().flatten().copied().collect() };
        let weighted: Vec<f64> = gap
            .iter()
            .zip(&pass.rows)
            .flat_map(|(g, r)| g.map(|v| v * r.area))
            .collect();
        let area: Vec<f64> = pass.rows.iter().map(|r| r.area).collect();
        Output::Surface(SurfaceOutput {
            name: format!("{}_pass{}", tied.name, p + 1),
            scheme: tied.scheme,
            faces: pass.secondary.clone(),
            rows: pass.rows.iter().map(|r| r.node).collect(),
            fields: vec![
                RowField::new("traction", 3, flat(&traction), true),
                RowField::new("weighted_gap", 3, weighted, false),
                RowField::new("gap", 3, flat(&gap), false),
                RowField::new("a", 1, area, false),
            ],
        })
    }
}

impl Contribution for TiedInterfaces {
    fn coupled_nodes(&self) -> Vec<usize> {
        self.nodes()
    }

    fn couplings(&self, _at: &State, couple: &mut dyn FnMut(&[usize])) {
        for row in self.rows() {
            couple(&row.nodes());
        }
    }

    /// `F_k += w_k t_A` of every owned row.
    fn residual(&self, at: &State, out: &mut dyn ForceSink) -> Result<Option<DomainIssue>> {
        let mut vals = Vec::new();
        for row in self.owned_rows() {
            let t = row.traction(at.u);
            vals.clear();
            for &(_, w) in &row.terms {
                vals.extend(t.iter().map(|tc| w * tc));
            }
            out.add_forces(&row.nodes(), &vals)?;
        }
        Ok(None)
    }

    /// `K_kl += (eps_A / a_A) w_k w_l I` of every owned row.
    fn jacobian(&self, _at: &State, out: &mut dyn TangentSink) -> Result<Option<DomainIssue>> {
        let mut block = Vec::new();
        for row in self.owned_rows() {
            let s = row.eps / row.area;
            let n = 3 * row.terms.len();
            block.clear();
            block.resize(n * n, 0.0);
            for (a, &(_, wa)) in row.terms.iter().enumerate() {
                for (b, &(_, wb)) in row.terms.iter().enumerate() {
                    for c in 0..3 {
                        block[(3 * a + c) * n + 3 * b + c] = s * wa * wb;
                    }
                }
            }
            let nodes = row.nodes();
            out.add_block(&nodes, &nodes, &block)?;
        }
        Ok(None)
    }

    fn is_augmented(&self) -> bool {
        true
    }

    fn takes_uzawa_updates(&self) -> bool {
        self.interfaces.iter().any(|t| t.uzawa_max > 0)
    }

    fn augment(&mut self, at: &State, done: usize, world: &SimpleCommunicator) -> Augmentation {
        let (outcome, gap) = self.uzawa_step(at.u, done, world);
        Augmentation {
            outcome,
            violation: format!("tied relative gap {gap:.3e}"),
        }
    }

    fn save(&mut self) {
        self.saved = self.rows().map(|r| r.lambda).collect();
    }

    fn restore(&mut self) {
        let saved = std::mem::take(&mut self.saved);
        for (row, &l) in self.rows_mut().zip(&saved) {
            row.lambda = l;
        }
        self.saved = saved;
    }

    fn write_state(&self, out: &mut dyn StateSink) {
        let lambda: Vec<f64> = self.rows().flat_map(|r| r.lambda).collect();
        out.f64s("tied multipliers", &lambda);
    }

    fn read_state(&mut self, from: &mut dyn StateSource) -> Result<()> {
        let lambda = from.f64s("tied multipliers")?;
        let rows = self.rows().count();
        if lambda.len() != 3 * rows {
            return Err(crate::Error::Restart(format!(
                "the checkpoint holds {} tied multipliers for {rows} tied rows",
                lambda.len() / 3
            )));
        }
        for (row, l) in self.rows_mut().zip(lambda.chunks_exact(3)) {
            row.lambda = [l[0], l[1], l[2]];
        }
        Ok(())
    }

    fn output(&self, at: &State, world: &SimpleCommunicator) -> Vec<Output> {
        let mut out = Vec::new();
        for (i, tied) in self.interfaces.iter().enumerate() {
            for p in 0..tied.passes.len() {
                out.push(self.pass_output(i, p, at.u, world));
            }
        }
        out
    }

    /// `interface_area_<name>` (the traction integral of its first pass), the segment pairs by
    /// kind (`pairs_<name>_<kind>`) and the largest relative gap (`max_relative_gap`).
    fn metrics(&self, at: &State, world: &SimpleCommunicator) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        for tied in &self.interfaces {
            let area: f64 = tied.passes[0].rows.iter().map(|r| r.area).sum();
            out.push((format!("interface_area_{}", tied.name), area));
            for (kind, count) in &tied.stats {
                out.push((format!("pairs_{}_{kind}", tied.name), *count as f64));
            }
        }
        out.push((
            "max_relative_gap".into(),
            self.max_relative_gap(at.u, world),
        ));
        out
    }
}
