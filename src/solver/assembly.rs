//! The model's blocks into PETSc: the residual vector, the tangent matrix, and the matrix
//! pattern.
//!
//! Contributions hand out blocks over mesh nodes ([`crate::model`]); here they become global
//! dof indices ([`DofMap::global`]: constrained dofs are -1, which PETSc ignores):
//!
//! - residual blocks go to `VecSetValues` (`ADD_VALUES`; entries of rows another rank owns go
//!   through PETSc's stash and are summed at the vector's assembly);
//! - tangent blocks go straight into the stored rows this rank owns
//!   ([`crate::petsc::OwnedRows`]: the sums of `MatSetValues`, without its per-entry search),
//!   and through PETSc's stash for the rows of other ranks.
//!
//! The contributions are summed in the model's order (the bulk first), block by block in the
//! order each hands them out, so that a rank's sums do not depend on anything else.
//!
//! The matrix pattern ([`Pattern`]) is kept node by node: every set of nodes a contribution
//! couples (an element, a constraint row, a contact stencil) is a dense block, and the rows
//! of a node this rank owns hold the free dofs of every node coupled to it. The dof pattern of
//! the matrix follows from it ([`Pattern::sparsity`]).

use crate::dofs::DofMap;
use crate::error::Result;
use crate::model::{
    merge_ascending, Contribution, DomainIssue, ForceSink, Model, NodalForces, State, TangentSink,
};
use crate::petsc::{Matrix, OwnedRows, PetscInt, Sparsity, Vector};

/// Residual blocks into a PETSc vector.
struct VectorSink<'a> {
    dofs: &'a DofMap,
    f: &'a mut Vector,
    idx: Vec<PetscInt>,
}

impl ForceSink for VectorSink<'_> {
    fn add_forces(&mut self, nodes: &[usize], forces: &[f64]) -> Result<()> {
        self.dofs.element_dofs(nodes, &mut self.idx);
        self.f.set_values(&self.idx, forces, true)
    }
}

/// Tangent blocks into the rows of a PETSc matrix.
struct MatrixSink<'a, 'm> {
    dofs: &'a DofMap,
    owned: &'a mut OwnedRows<'m>,
    rows: Vec<PetscInt>,
    cols: Vec<PetscInt>,
}

impl TangentSink for MatrixSink<'_, '_> {
    fn add_block(&mut self, rows: &[usize], cols: &[usize], values: &[f64]) -> Result<()> {
        self.dofs.element_dofs(rows, &mut self.rows);
        if self.rows.iter().all(|&g| g < 0) {
            return Ok(());
        }
        self.dofs.element_dofs(cols, &mut self.cols);
        self.owned.add(&self.rows, &self.cols, values)
    }
}

/// `F(u; t)` of every contribution into `f` (zeroed, assembled); the first domain issue of
/// the model's parts, in their order (every part is evaluated).
pub fn residual(
    model: &Model,
    at: &State,
    dofs: &DofMap,
    f: &mut Vector,
) -> Result<Option<DomainIssue>> {
    f.set_all(0.0)?;
    let mut sink = VectorSink {
        dofs,
        f,
        idx: Vec::new(),
    };
    let mut issue = None;
    for part in model.parts() {
        let found = part.residual(at, &mut sink)?;
        issue = issue.or(found);
    }
    f.assemble()?;
    Ok(issue)
}

/// `dF/du` of every contribution into `jac` (zeroed, assembled); the first domain issue.
pub fn jacobian(
    model: &Model,
    at: &State,
    dofs: &DofMap,
    jac: &mut Matrix,
) -> Result<Option<DomainIssue>> {
    jac.zero_entries()?;
    let issue = jac.with_owned_rows(|owned| {
        let mut sink = MatrixSink {
            dofs,
            owned,
            rows: Vec::new(),
            cols: Vec::new(),
        };
        let mut issue = None;
        for part in model.parts() {
            let found = part.jacobian(at, &mut sink)?;
            issue = issue.or(found);
        }
        Ok(issue)
    })?;
    jac.assemble()?;
    Ok(issue)
}

/// This rank's `f_int - f_ext + f_tie + f_contact` at every dof (constrained ones included),
/// dof-indexed: the nodal forces of the reactions.
pub fn nodal_forces(model: &Model, at: &State) -> Result<Vec<f64>> {
    let mut out = vec![0.0; at.u.len()];
    let mut sink = NodalForces(&mut out);
    for part in model.parts() {
        part.residual(at, &mut sink)?;
    }
    Ok(out)
}

/// The matrix pattern of the rows this rank owns, node by node (module docs).
#[derive(Clone, PartialEq)]
pub struct Pattern {
    /// Per node: the nodes (with a free dof) coupled to it, sorted; empty for nodes whose rows
    /// this rank does not own.
    rows: Vec<Vec<usize>>,
}

impl Pattern {
    /// An empty pattern for the nodes of `dofs`.
    pub fn new(dofs: &DofMap) -> Pattern {
        Pattern {
            rows: vec![Vec::new(); dofs.node_owner.len()],
        }
    }

    /// The pattern as numbers (a checkpoint): per node with a row, the node, its number of
    /// coupled nodes, and those.
    pub fn to_codes(&self) -> Vec<u64> {
        let mut codes = Vec::new();
        for (n, coupled) in self.rows.iter().enumerate().filter(|(_, c)| !c.is_empty()) {
            codes.extend([n as u64, coupled.len() as u64]);
            codes.extend(coupled.iter().map(|&m| m as u64));
        }
        codes
    }

    /// The pattern of [`Pattern::to_codes`], for the nodes of `dofs`; `None` if the codes do
    /// not fit them.
    pub fn from_codes(dofs: &DofMap, codes: &[u64]) -> Option<Pattern> {
        let nodes = dofs.node_owner.len();
        let mut rows = vec![Vec::new(); nodes];
        let mut rest = codes;
        while let [n, len, tail @ ..] = rest {
            let (n, len) = (usize::try_from(*n).ok()?, usize::try_from(*len).ok()?);
            let coupled = tail.get(..len)?;
            let row: Vec<usize> = coupled.iter().map(|&m| m as usize).collect();
            let ascending = row.windows(2).all(|w| w[0] < w[1]);
            let owned = n < nodes && dofs.node_owner[n] == dofs.rank;
            if !owned || !ascending || row.last().is_some_and(|&m| m >= nodes) {
                return None;
            }
            *rows.get_mut(n)? = row;
            rest = &tail[len..];
        }
        rest.is_empty().then_some(Pattern { rows })
    }

    /// Adds the couplings `parts` hand out at `at`, in the rows of the nodes this rank owns;
    /// returns true if a row gained a column.
    pub fn add<'a>(
        &mut self,
        dofs: &DofMap,
        at: &State,
        parts: impl Iterator<Item = &'a dyn Contribution>,
    ) -> bool {
        let free = |n: usize| dofs.global[3 * n..3 * n + 3].iter().any(|&g| g >= 0);
        let mut added: Vec<Vec<usize>> = vec![Vec::new(); self.rows.len()];
        let mut couple = |nodes: &[usize]| {
            for &n in nodes {
                if dofs.node_owner[n] == dofs.rank && free(n) {
                    added[n].extend(nodes.iter().copied().filter(|&m| free(m)));
                }
            }
        };
        for part in parts {
            part.couplings(at, &mut couple);
        }
        let mut grew = false;
        for (row, mut new) in self.rows.iter_mut().zip(added) {
            if new.is_empty() {
                continue;
            }
            new.sort_unstable();
            new.dedup();
            grew |= merge_ascending(row, &new);
        }
        grew
    }

    /// The dof pattern of the owned rows: every free dof of every node coupled to the row's
    /// node, sorted.
    pub fn sparsity(&self, dofs: &DofMap) -> Sparsity {
        let mut rows = vec![Vec::new(); dofs.owned_count];
        let mut cols: Vec<PetscInt> = Vec::new();
        for (n, coupled) in self.rows.iter().enumerate() {
            if coupled.is_empty() {
                continue;
            }
            cols.clear();
            for &m in coupled {
                cols.extend(dofs.global[3 * m..3 * m + 3].iter().filter(|&&g| g >= 0));
            }
            cols.sort_unstable();
            for &g in dofs.global[3 * n..3 * n + 3].iter().filter(|&&g| g >= 0) {
                rows[g as usize - dofs.owned_start] = cols.clone();
            }
        }
        Sparsity {
            row_start: dofs.owned_start,
            rows,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Pattern;
    use crate::case::Scene;
    use crate::contact::frictional::tests::{scene_of, PARTLY_COVERED};
    use crate::contact::frictional::ContactInterfaces;
    use crate::dofs::DofMap;
    use crate::model::{Contribution, State};
    use crate::solid::Bulk;

    /// The bulk's pattern is that of the element stencils ([`DofMap::bulk_sparsity`]), and the
    /// contact pattern added to it is the dof-by-dof one: every free dof of a stencil couples to
    /// every free dof of it, in the rows this rank owns; on each rank of a two-rank layout. A
    /// second addition at the same state adds nothing.
    #[test]
    fn contact_pattern_couples_every_dof_of_a_stencil() {
        // As shipped, then with constrained dofs on both contact faces (their columns and rows
        // left out), then node-on-segment.
        let constrained = PARTLY_COVERED.replace(
            "[[dirichlet]]",
            "[[symmetry]]\nset = \"low.xmin\"\nnormal = \"x\"\n[[symmetry]]\nset = \
             \"up.ymin\"\nnormal = \"y\"\n[[dirichlet]]",
        );
        let node_on_segment = PARTLY_COVERED.replace("scheme = 2", "method = \"node_on_segment\"");
        assert_eq!(check_contact_pattern(&scene_of(PARTLY_COVERED)), 0);
        assert!(check_contact_pattern(&scene_of(&constrained)) > 0);
        check_contact_pattern(&scene_of(&node_on_segment));
    }

    /// [`contact_pattern_couples_every_dof_of_a_stencil`] for one scene; returns how many
    /// constrained dofs the stencils held.
    fn check_contact_pattern(scene: &Scene) -> usize {
        let u = vec![0.0; 3 * scene.mesh.num_nodes()];
        let at = State {
            scene,
            u: &u,
            t: 0.0,
        };
        let mut constrained = 0;
        let half = scene.mesh.num_elements() / 2;
        for rank in 0..2 {
            let elements = (0..scene.mesh.num_elements())
                .map(|e| usize::from(e >= half))
                .collect();
            let dofs = DofMap::new(&scene.mesh, elements, rank, 2, &scene.constrained_mask());
            let bulk = Bulk::new(scene, &dofs).unwrap();
            let contact = ContactInterfaces::new(scene, &dofs).unwrap();
            let owned = dofs.owned_start..dofs.owned_start + dofs.owned_count;
            let mut expected = dofs.bulk_sparsity(&scene.mesh);
            let mut pattern = Pattern::new(&dofs);
            pattern.add(&dofs, &at, [&bulk as &dyn Contribution].into_iter());
            assert_eq!(
                pattern.sparsity(&dofs).rows,
                expected.rows,
                "rank {rank}: bulk"
            );
            let mut added = 0;
            contact.couplings(&at, &mut |nodes| {
                let mut all = Vec::new();
                dofs.element_dofs(nodes, &mut all);
                constrained += all.iter().filter(|&&g| g < 0).count();
                let cols: Vec<_> = all.into_iter().filter(|&g| g >= 0).collect();
                for &g in cols.iter().filter(|&&g| owned.contains(&(g as usize))) {
                    expected.rows[g as usize - dofs.owned_start].extend(&cols);
                    added += 1;
                }
            });
            assert!(added > 0, "rank {rank}: no contact rows owned");
            for row in &mut expected.rows {
                row.sort_unstable();
                row.dedup();
            }
            let parts = || [&contact as &dyn Contribution].into_iter();
            assert!(pattern.add(&dofs, &at, parts()));
            assert_eq!(pattern.sparsity(&dofs).rows, expected.rows, "rank {rank}");
            assert!(!pattern.add(&dofs, &at, parts()));
            // As a checkpoint keeps it.
            let codes = pattern.to_codes();
            let back = Pattern::from_codes(&dofs, &codes).unwrap();
            assert_eq!(back.rows, pattern.rows, "rank {rank}");
            assert!(Pattern::from_codes(&dofs, &codes[..codes.len() - 1]).is_none());
            let mut far = codes.clone();
            far[0] = dofs.node_owner.len() as u64;
            assert!(Pattern::from_codes(&dofs, &far).is_none());
        }
        constrained
    }
}
