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
//! coupling they give to nearby free primary nodes (measured: the tied patch test then fails by
//! 5 %); the proper remedy, a multiplier basis modified at Dirichlet boundaries, is not done. Where
//! the kept components over-constrain (a fine secondary side of Hex8 on symmetry planes), the
//! Uzawa loop cannot meet its tolerance, stops at `uzawa_max` and says so (a warning, and
//! `uzawa_capped_steps` in the summary); the effect on the solution was measured at about 3e-4
//! of the energy error.
//!
//! # Parallel layout
//!
//! Each rank integrates the secondary faces whose element it owns (against every primary face:
//! the mesh is replicated), then the weight triplets are all-gathered, so every rank knows every
//! row (interface data only: it grows like the surface). The owner of node A assembles row A's
//! residual and tangent into whatever matrix rows its terms have; every rank knows the
//! sparsity of the rows it owns. Every rank gathers the displacements of every interface node.

use std::collections::BTreeMap;

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::datatype::PartitionMut;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::Count;

use crate::case::{Interface, InterfaceKind, Scene};
use crate::contact::mortar::{
    integrate_pair, traction_nodes, FaceGeom, IntegrationOptions, RejectStats,
};
use crate::contact::search::{Aabb, PrimaryTree};
use crate::dofs::DofMap;
use crate::error::Result;
use crate::mesh::FaceRef;
use crate::petsc::{Matrix, PetscInt, Sparsity, Vector};
use crate::vec3::norm;

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
    pub scheme: crate::contact::mortar::TractionScheme,
    pub passes: Vec<Pass>,
    pub uzawa_tol: f64,
    pub uzawa_max: usize,
    /// Rejected and integrated segment pairs by kind, summed over passes and ranks.
    pub stats: BTreeMap<String, usize>,
}

/// What one Uzawa step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Augmented {
    /// Every interface meets its tolerance (or is plain penalty): nothing changed.
    Converged,
    /// Some multipliers were updated: solve again.
    Updated,
    /// An interface is above its tolerance with no augmentations left.
    CapReached,
}

/// Every tied interface of a scene, as this rank sees it.
#[derive(Clone, Debug, Default)]
pub struct TiedInterfaces {
    pub interfaces: Vec<Tied>,
    rank: usize,
    node_owner: Vec<usize>,
}

impl TiedInterfaces {
    /// Integrates the mortar weights of every interface on the reference configuration.
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
                let (sec, pri) = if pass == 0 {
                    (&iface.secondary, &iface.primary)
                } else {
                    (&iface.primary, &iface.secondary)
                };
                let (local, local_stats) = integrate_side(scene, dofs, iface, sec, pri);
                for (k, v) in reduce_stats(&local_stats, world) {
                    *stats.entry(k).or_insert(0) += v;
                }
                let all = all_gather(&local, world);
                let rows = build_rows(scene, iface, &all);
                check_coverage(scene, iface, pass, sec, &rows, world)?;
                passes.push(Pass {
                    secondary: sec.clone(),
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
        })
    }

    /// True when the scene has no interface.
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

    /// Adds the columns the constraints couple to the rows this rank owns.
    pub fn add_sparsity(&self, dofs: &DofMap, sparsity: &mut Sparsity) {
        let mut extra: BTreeMap<usize, Vec<PetscInt>> = BTreeMap::new();
        for row in self.rows() {
            let cols: Vec<PetscInt> = row
                .terms
                .iter()
                .flat_map(|&(l, _)| dofs.global[3 * l..3 * l + 3].iter().copied())
                .filter(|&g| g >= 0)
                .collect();
            for &(k, _) in &row.terms {
                for c in 0..3 {
                    let g = dofs.global[3 * k + c];
                    let owned = g >= 0
                        && (g as usize) >= dofs.owned_start
                        && (g as usize) < dofs.owned_start + dofs.owned_count;
                    if owned {
                        extra
                            .entry(g as usize - dofs.owned_start)
                            .or_default()
                            .extend(&cols);
                    }
                }
            }
        }
        for (r, cols) in extra {
            let row = &mut sparsity.rows[r];
            row.extend(cols);
            row.sort_unstable();
            row.dedup();
        }
    }

    /// Adds `w_k t_A` of every owned row into `f` (global dof numbering; not assembled).
    pub fn add_residual(&self, dofs: &DofMap, u: &[f64], f: &mut Vector) -> Result<()> {
        let mut idx = Vec::new();
        let mut vals = Vec::new();
        for row in self.owned_rows() {
            let t = row.traction(u);
            idx.clear();
            vals.clear();
            for &(k, w) in &row.terms {
                idx.extend_from_slice(&dofs.global[3 * k..3 * k + 3]);
                vals.extend(t.iter().map(|tc| w * tc));
            }
            f.set_values(&idx, &vals, true)?;
        }
        Ok(())
    }

    /// Adds `(eps_A / a_A) w_k w_l I` of every owned row into `jac` (not assembled).
    pub fn add_jacobian(&self, dofs: &DofMap, jac: &mut Matrix) -> Result<()> {
        let mut idx = Vec::new();
        let mut block = Vec::new();
        for row in self.owned_rows() {
            let s = row.eps / row.area;
            idx.clear();
            for &(k, _) in &row.terms {
                idx.extend_from_slice(&dofs.global[3 * k..3 * k + 3]);
            }
            let n = idx.len();
            block.clear();
            block.resize(n * n, 0.0);
            for (a, &(_, wa)) in row.terms.iter().enumerate() {
                for (b, &(_, wb)) in row.terms.iter().enumerate() {
                    for c in 0..3 {
                        block[(3 * a + c) * n + 3 * b + c] = s * wa * wb;
                    }
                }
            }
            jac.add_values(&idx, &idx, &block)?;
        }
        Ok(())
    }

    /// Adds the constraint forces at every dof (including constrained ones) of the owned rows
    /// into `out` (dof-indexed), for reactions.
    pub fn add_nodal_forces(&self, u: &[f64], out: &mut [f64]) {
        for row in self.owned_rows() {
            let t = row.traction(u);
            for &(k, w) in &row.terms {
                for c in 0..3 {
                    out[3 * k + c] += w * t[c];
                }
            }
        }
    }

    /// The largest `|g_A| / (a_A h_A)` over the rows of interface `i` (all ranks).
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

    /// The largest relative gap over every interface (all ranks).
    pub fn max_relative_gap(&self, u: &[f64], world: &SimpleCommunicator) -> f64 {
        (0..self.interfaces.len())
            .map(|i| self.max_relative_gap_of(i, u, world))
            .fold(0.0, f64::max)
    }

    /// One Uzawa step, interface by interface (collective): every interface whose gap exceeds
    /// its `uzawa_tol` and that has augmentations left (`done < uzawa_max`) gets
    /// `lambda_A += eps_A g_A / a_A` on its owned rows. Returns what happened.
    pub fn augment(&mut self, u: &[f64], done: usize, world: &SimpleCommunicator) -> Augmented {
        let mut result = Augmented::Converged;
        for i in 0..self.interfaces.len() {
            let gap = self.max_relative_gap_of(i, u, world);
            let tied = &self.interfaces[i];
            if gap <= tied.uzawa_tol || tied.uzawa_max == 0 {
                continue;
            }
            if done >= tied.uzawa_max {
                if result == Augmented::Converged {
                    result = Augmented::CapReached;
                }
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
        result
    }

    /// The multipliers of every row (to restore them when a step is cut).
    pub fn multipliers(&self) -> Vec<[f64; 3]> {
        self.rows().map(|r| r.lambda).collect()
    }

    /// Restores multipliers saved by [`TiedInterfaces::multipliers`].
    pub fn set_multipliers(&mut self, saved: &[[f64; 3]]) {
        for (row, &l) in self
            .interfaces
            .iter_mut()
            .flat_map(|i| i.passes.iter_mut())
            .flat_map(|p| p.rows.iter_mut())
            .zip(saved)
        {
            row.lambda = l;
        }
    }

    /// Tractions and gaps of every row of one pass, on every rank (owners compute, all sum).
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
}

/// An interface whose secondary side meets no primary face is an error; one covered by less
/// than 90 % of its area draws a warning (rank 0): tied faces are meant to lie on each other.
fn check_coverage(
    scene: &Scene,
    iface: &Interface,
    pass: usize,
    secondary: &[FaceRef],
    rows: &[Row],
    world: &SimpleCommunicator,
) -> Result<()> {
    let tied: f64 = rows.iter().map(|r| r.area).sum();
    let side = if pass == 0 {
        &iface.secondary_set
    } else {
        &iface.primary_set
    };
    if rows.is_empty() {
        return Err(crate::Error::Mesh(format!(
            "interface '{}' ties nothing: no face of '{side}' overlaps the other side (farther \
             apart than the search margin, 10 % of a face's size, or facing the same way)",
            iface.name
        )));
    }
    let total: f64 = secondary.iter().map(|&f| face_area(scene, f)).sum();
    if tied < 0.9 * total && world.rank() == 0 {
        crate::error::print_warning(format_args!(
            "interface '{}': only {:.1} % of '{side}' is tied",
            iface.name,
            100.0 * tied / total
        ));
    }
    Ok(())
}

/// The area of one face (reference configuration).
fn face_area(scene: &Scene, f: FaceRef) -> f64 {
    let kind = scene.mesh.face_type(f);
    let x: Vec<[f64; 3]> = scene
        .mesh
        .face_nodes(f)
        .iter()
        .map(|&n| scene.mesh.coords[n])
        .collect();
    let rule = kind.quadrature(kind.default_quadrature_degree());
    rule.points
        .iter()
        .zip(&rule.weights)
        .map(|(&xi, w)| w * crate::fe::face_normal(kind, &x, xi).1)
        .sum()
}

/// A weight of one row: (traction node A, node, weight, side: 1 secondary / 2 primary).
type Triplet = (usize, usize, f64, u8);

/// Integrates this rank's secondary faces against every primary face.
fn integrate_side(
    scene: &Scene,
    dofs: &DofMap,
    iface: &Interface,
    secondary: &[FaceRef],
    primary: &[FaceRef],
) -> (Vec<Triplet>, RejectStats) {
    let mesh = &scene.mesh;
    let coords = |f: FaceRef| -> Vec<[f64; 3]> {
        mesh.face_nodes(f).iter().map(|&n| mesh.coords[n]).collect()
    };
    let primary_x: Vec<Vec<[f64; 3]>> = primary.iter().map(|&f| coords(f)).collect();
    let boxes: Vec<Aabb> = primary_x.iter().map(|x| Aabb::of_points(x)).collect();
    let tree = PrimaryTree::new(&boxes);
    let mut stats = RejectStats::default();
    let mut out = Vec::new();
    let mut candidates = Vec::new();
    for &s in secondary
        .iter()
        .filter(|f| dofs.element_rank[f.element] == dofs.rank)
    {
        let sx = coords(s);
        let s_kind = mesh.face_type(s);
        let s_nodes = mesh.face_nodes(s);
        let carriers = traction_nodes(s_kind, iface.scheme).expect("validated with the scene");
        let sbox = Aabb::of_points(&sx);
        tree.query(&sbox.inflated(0.1 * sbox.diagonal()), &mut candidates);
        for &p in &candidates {
            let p_kind = mesh.face_type(primary[p]);
            let p_nodes = mesh.face_nodes(primary[p]);
            let degree = iface.quadrature_degree.unwrap_or(
                if s_kind == crate::fe::FaceType::Quad4 && p_kind == crate::fe::FaceType::Quad4 {
                    4
                } else {
                    8
                },
            );
            let opts = IntegrationOptions {
                scheme: iface.scheme,
                degree,
                pallets: iface.pallets,
            };
            let w = integrate_pair(
                &FaceGeom {
                    kind: s_kind,
                    x: &sx,
                },
                &FaceGeom {
                    kind: p_kind,
                    x: &primary_x[p],
                },
                &opts,
                &mut stats,
            );
            for &(k, b, v) in &w.n1 {
                out.push((s_nodes[carriers[k]], s_nodes[b], v, 1));
            }
            for &(k, c, v) in &w.n2 {
                out.push((s_nodes[carriers[k]], p_nodes[c], v, 2));
            }
        }
    }
    (out, stats)
}

/// Every rank's triplets, on every rank, in rank order.
fn all_gather(local: &[Triplet], world: &SimpleCommunicator) -> Vec<Triplet> {
    let flat: Vec<f64> = local
        .iter()
        .flat_map(|&(a, n, w, side)| [a as f64, n as f64, w, side as f64])
        .collect();
    let size = world.size() as usize;
    let mut counts = vec![0 as Count; size];
    world.all_gather_into(&(flat.len() as Count), &mut counts[..]);
    let displs: Vec<Count> = counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    let total = counts.iter().sum::<Count>() as usize;
    let mut all = vec![0.0; total];
    {
        let mut partition = PartitionMut::new(&mut all[..], counts, displs);
        world.all_gather_varcount_into(&flat[..], &mut partition);
    }
    all.chunks(4)
        .map(|c| (c[0] as usize, c[1] as usize, c[2], c[3] as u8))
        .collect()
}

/// Rejection counters summed over ranks.
fn reduce_stats(local: &RejectStats, world: &SimpleCommunicator) -> BTreeMap<String, usize> {
    let map = local.to_map();
    let keys: Vec<&String> = map.keys().collect();
    let vals: Vec<u64> = map.values().map(|&v| v as u64).collect();
    let mut sums = vec![0u64; vals.len()];
    world.all_reduce_into(&vals[..], &mut sums[..], SystemOperation::sum());
    keys.into_iter()
        .cloned()
        .zip(sums.into_iter().map(|v| v as usize))
        .collect()
}

/// Rows from all triplets: weights of one (A, node) pair summed, a_A and the penalty set.
fn build_rows(scene: &Scene, iface: &Interface, triplets: &[Triplet]) -> Vec<Row> {
    // Summed in a canonical order (not the ranks' order), so that the rows, and the results,
    // are bitwise the same on any number of ranks.
    let mut sorted = triplets.to_vec();
    sorted.sort_by_key(|x| (x.0, x.1, x.3, x.2.to_bits()));
    let mut by_a: BTreeMap<usize, BTreeMap<usize, f64>> = BTreeMap::new();
    let mut area: BTreeMap<usize, f64> = BTreeMap::new();
    for &(a, n, w, side) in &sorted {
        let signed = if side == 1 { w } else { -w };
        *by_a.entry(a).or_default().entry(n).or_insert(0.0) += signed;
        if side == 1 {
            *area.entry(a).or_insert(0.0) += w;
        }
    }
    let young = young_by_node(scene);
    let max_area = area.values().copied().fold(0.0, f64::max);
    by_a.into_iter()
        .filter_map(|(a, terms)| {
            let area = area.get(&a).copied().unwrap_or(0.0);
            // A node whose traction function barely meets the other side (a_A -> 0) would get
            // an unbounded eps_A / a_A: such rows are dropped (docs/theory.md section 10).
            if area <= 1e-12 * max_area {
                return None;
            }
            let h = area.sqrt();
            // Weights at round-off level (cancellations in the sums above) are dropped: they
            // change nothing but would widen the matrix.
            let largest = terms.values().fold(0.0f64, |m, w| m.max(w.abs()));
            Some(Row {
                node: a,
                area,
                eps: iface.penalty * young[a] / h,
                h,
                terms: terms
                    .into_iter()
                    .filter(|&(_, w)| w.abs() > 1e-12 * largest)
                    .collect(),
                lambda: [0.0; 3],
            })
        })
        .collect()
}

/// Young's modulus of the body of each node (the first element around it).
pub(crate) fn young_by_node(scene: &Scene) -> Vec<f64> {
    let mesh = &scene.mesh;
    let mut e = vec![0.0; mesh.num_nodes()];
    for el in (0..mesh.num_elements()).rev() {
        let young = scene.materials[mesh.body[el]].young();
        for &n in mesh.element_nodes(el) {
            e[n] = young;
        }
    }
    e
}
