//! Degrees of freedom: which rank assembles which element, who owns which node, and the PETSc
//! global number of every unconstrained dof.
//!
//! # Design
//!
//! - The mesh is replicated on every rank (see `crate::mesh`); METIS splits the elements
//!   (`mesh::partition`), and every rank computes the same numbering from the same data, so no
//!   numbering is communicated.
//! - A node belongs to the lowest rank among the elements around it; its three dofs
//!   (`3 * node + component`) get consecutive global numbers in ascending node order within each
//!   rank, ranks in order, so each rank owns one contiguous block of rows.
//! - Constrained dofs (prescribed displacements, symmetry planes) are **eliminated**: they get
//!   the index -1, which PETSc ignores in `VecSetValues`/`MatSetValues`, and their values come
//!   from the load curve. The matrix holds only free dofs, stays well conditioned, and reactions
//!   are the internal forces at the constrained dofs (summed over elements, then over ranks).
//! - Ghost values: each rank gathers the free dofs of the nodes of its own elements with a PETSc
//!   `VecScatter` (`petsc::Scatter`).
//! - The sparsity of every owned row is exact: the free dofs of every node that shares an element
//!   with the row's node, over the whole mesh (the mesh is known everywhere).

use crate::mesh::Mesh;
use crate::petsc::{PetscInt, Sparsity};

/// Ownership and numbering of the dofs of one rank.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// This rank and the number of ranks.
    pub rank: usize,
    pub ranks: usize,
    /// Rank that assembles each element.
    pub element_rank: Vec<usize>,
    /// Elements this rank assembles, ascending.
    pub local_elements: Vec<usize>,
    /// Rank that owns each node.
    pub node_owner: Vec<usize>,
    /// PETSc global index of each dof `3 * node + c`, or -1 when constrained.
    pub global: Vec<PetscInt>,
    /// First owned global index and the number of owned free dofs.
    pub owned_start: usize,
    pub owned_count: usize,
    /// Total number of free dofs.
    pub total_free: usize,
    /// Nodes of this rank's elements, ascending.
    pub local_nodes: Vec<usize>,
    /// Free dofs (`3 * node + c`) of `local_nodes`, ascending, and their global indices: the
    /// entries this rank gathers from the distributed solution.
    pub gathered_dofs: Vec<usize>,
    pub gathered_global: Vec<PetscInt>,
}

impl DofMap {
    /// Numbers the dofs for `ranks` ranks, given each element's rank and which dofs are
    /// constrained (`constrained[3 * node + c]`).
    pub fn new(
        mesh: &Mesh,
        element_rank: Vec<usize>,
        rank: usize,
        ranks: usize,
        constrained: &[bool],
    ) -> DofMap {
        let n = mesh.num_nodes();
        let node_owner = crate::mesh::partition::node_owners(mesh, &element_rank, ranks);
        let mut global = vec![-1 as PetscInt; 3 * n];
        let mut next: PetscInt = 0;
        let (mut owned_start, mut owned_count) = (0, 0);
        for r in 0..ranks {
            if r == rank {
                owned_start = next as usize;
            }
            for v in (0..n).filter(|&v| node_owner[v] == r) {
                for c in 0..3 {
                    if !constrained[3 * v + c] {
                        global[3 * v + c] = next;
                        next += 1;
                    }
                }
            }
            if r == rank {
                owned_count = next as usize - owned_start;
            }
        }
        let local_elements: Vec<usize> = (0..mesh.num_elements())
            .filter(|&e| element_rank[e] == rank)
            .collect();
        let mut local_nodes: Vec<usize> = local_elements
            .iter()
            .flat_map(|&e| mesh.element_nodes(e).iter().copied())
            .collect();
        local_nodes.sort_unstable();
        local_nodes.dedup();
        let gathered_dofs: Vec<usize> = local_nodes
            .iter()
            .flat_map(|&v| (0..3).map(move |c| 3 * v + c))
            .filter(|&d| global[d] >= 0)
            .collect();
        let gathered_global = gathered_dofs.iter().map(|&d| global[d]).collect();
        DofMap {
            rank,
            ranks,
            element_rank,
            local_elements,
            node_owner,
            global,
            owned_start,
            owned_count,
            total_free: next as usize,
            local_nodes,
            gathered_dofs,
            gathered_global,
        }
    }

    /// Also gathers the free dofs of `nodes` (e.g. the nodes of interfaces, whose constraints
    /// couple nodes of elements on other ranks).
    pub fn gather_also(&mut self, nodes: &[usize]) {
        let mut all: Vec<usize> = self.local_nodes.iter().chain(nodes).copied().collect();
        all.sort_unstable();
        all.dedup();
        self.gathered_dofs = all
            .iter()
            .flat_map(|&v| (0..3).map(move |c| 3 * v + c))
            .filter(|&d| self.global[d] >= 0)
            .collect();
        self.gathered_global = self.gathered_dofs.iter().map(|&d| self.global[d]).collect();
    }

    /// Global indices of the dofs of an element's nodes, `3 * a + c` order (-1 where constrained).
    pub fn element_dofs(&self, nodes: &[usize], out: &mut Vec<PetscInt>) {
        out.clear();
        for &v in nodes {
            out.extend_from_slice(&self.global[3 * v..3 * v + 3]);
        }
    }

    /// The rigid body modes of every body (three translations, three rotations about the
    /// centroid of its nodes, in the reference configuration), each on the owned free dofs of
    /// its body's nodes and zero elsewhere: the near null space of elasticity that algebraic
    /// multigrid needs, six per body. With constrained dofs eliminated they are only *near*
    /// null, which is what multigrid asks for. One set per body, not one for the mesh: where
    /// contact couples two bodies in the matrix, an aggregate may hold nodes of both, and only
    /// per-body modes let its coarse space move one body against the other (a slip).
    pub fn rigid_body_modes(&self, mesh: &Mesh) -> Vec<Vec<f64>> {
        let body_of = node_bodies(mesh);
        (0..mesh.bodies.len().max(1))
            .flat_map(|b| self.body_rigid_modes(mesh, |v| body_of[v] == Some(b)))
            .collect()
    }

    /// The six rigid body modes of the nodes `member` selects (see [`Self::rigid_body_modes`]).
    fn body_rigid_modes(&self, mesh: &Mesh, member: impl Fn(usize) -> bool) -> Vec<Vec<f64>> {
        let nodes: Vec<usize> = (0..mesh.num_nodes()).filter(|&v| member(v)).collect();
        let n = nodes.len().max(1) as f64;
        let mut centre = [0.0; 3];
        for &v in &nodes {
            (0..3).for_each(|c| centre[c] += mesh.coords[v][c] / n);
        }
        // Rotations in units of the body's size, so that all six modes are of one magnitude.
        let size = nodes
            .iter()
            .flat_map(|&v| (0..3).map(move |c| (mesh.coords[v][c] - centre[c]).abs()))
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut modes = vec![vec![0.0; self.owned_count]; 6];
        let owned = self.owned_start..self.owned_start + self.owned_count;
        for &v in &nodes {
            for c in 0..3 {
                let g = self.global[3 * v + c];
                if g < 0 || !owned.contains(&(g as usize)) {
                    continue;
                }
                let row = g as usize - self.owned_start;
                let r: [f64; 3] = std::array::from_fn(|k| (mesh.coords[v][k] - centre[k]) / size);
                modes[c][row] = 1.0;
                // Rotation about axis k: (e_k x r)_c.
                for k in 0..3 {
                    let e = std::array::from_fn::<f64, 3, _>(|i| if i == k { 1.0 } else { 0.0 });
                    let cross = [
                        e[1] * r[2] - e[2] * r[1],
                        e[2] * r[0] - e[0] * r[2],
                        e[0] * r[1] - e[1] * r[0],
                    ];
                    modes[3 + k][row] = cross[c];
                }
            }
        }
        modes
    }

    /// The exact nonzero pattern of the owned rows, from the element stencils of the whole mesh.
    pub fn bulk_sparsity(&self, mesh: &Mesh) -> Sparsity {
        let node_elements = node_to_elements(mesh);
        let mut rows = vec![Vec::new(); self.owned_count];
        let mut cols: Vec<PetscInt> = Vec::new();
        for v in (0..mesh.num_nodes()).filter(|&v| self.node_owner[v] == self.rank) {
            cols.clear();
            for &e in &node_elements[v] {
                for &w in mesh.element_nodes(e) {
                    cols.extend(self.global[3 * w..3 * w + 3].iter().filter(|&&g| g >= 0));
                }
            }
            cols.sort_unstable();
            cols.dedup();
            for c in 0..3 {
                let g = self.global[3 * v + c];
                if g >= 0 {
                    rows[g as usize - self.owned_start] = cols.clone();
                }
            }
        }
        Sparsity {
            row_start: self.owned_start,
            rows,
        }
    }
}

/// For every node, the elements that contain it.
pub fn node_to_elements(mesh: &Mesh) -> Vec<Vec<usize>> {
    let mut adj = vec![Vec::new(); mesh.num_nodes()];
    for e in 0..mesh.num_elements() {
        for &v in mesh.element_nodes(e) {
            adj[v].push(e);
        }
    }
    adj
}

/// The per-body modes of [`DofMap::rigid_body_modes`] summed, body over body, into one set of
/// six. On any aggregate within one body they span what that body's own modes span, which is all
/// that multigrid needs where the matrix couples no two bodies (the bulk field of the iterative
/// path, whose interface dofs are split off), with six vectors instead of six per body.
pub fn one_set_of_six(modes: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut six = modes.iter().take(6).cloned().collect::<Vec<_>>();
    for body in modes.chunks(6).skip(1) {
        for (sum, mode) in six.iter_mut().zip(body) {
            sum.iter_mut().zip(mode).for_each(|(s, m)| *s += m);
        }
    }
    six
}

/// The body of every node (of its elements'); `None` for a node of no element.
fn node_bodies(mesh: &Mesh) -> Vec<Option<usize>> {
    let mut body = vec![None; mesh.num_nodes()];
    for e in 0..mesh.num_elements() {
        for &v in mesh.element_nodes(e) {
            body[v] = Some(mesh.body[e]);
        }
    }
    body
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fe::ElementType;

    /// Two Hex8 elements side by side sharing four nodes.
    fn two_hexes() -> Mesh {
        let mut m = Mesh::new();
        for i in 0..3 {
            for (y, z) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                m.coords.push([i as f64, y, z]);
            }
        }
        // node index = 4 * i + k with k over (y,z) corners; build VTK hex from x-slices i, i+1.
        for i in 0..2 {
            let a = 4 * i;
            let b = 4 * (i + 1);
            // bottom (z=0): (x0,y0),(x1,y0),(x1,y1),(x0,y1); top (z=1) likewise
            m.push_element(
                ElementType::Hex8,
                0,
                &[a, b, b + 1, a + 1, a + 3, b + 3, b + 2, a + 2],
            );
        }
        m.bodies.push("b".into());
        m
    }

    #[test]
    fn numbering_is_contiguous_per_rank_and_skips_constrained() {
        let m = two_hexes();
        let mut constrained = vec![false; 3 * m.num_nodes()];
        for v in 0..4 {
            constrained[3 * v] = true; // x fixed on the face x = 0
        }
        let parts = vec![0, 1];
        let d0 = DofMap::new(&m, parts.clone(), 0, 2, &constrained);
        let d1 = DofMap::new(&m, parts, 1, 2, &constrained);
        assert_eq!(d0.global, d1.global);
        assert_eq!(d0.total_free, 3 * 12 - 4);
        // Shared nodes (x = 1) belong to rank 0.
        assert_eq!(d0.owned_count, 8 * 3 - 4);
        assert_eq!(d1.owned_start, d0.owned_count);
        assert_eq!(d0.owned_count + d1.owned_count, d0.total_free);
        for v in 0..4 {
            assert_eq!(d0.global[3 * v], -1);
        }
    }

    /// The modes on the owned free dofs of two ranks: translations are 1 on their component,
    /// rotations `e_k x (x - centre) / size`; constrained dofs have no row.
    #[test]
    fn rigid_body_modes_are_translations_and_rotations_about_the_centroid() {
        let m = two_hexes();
        let mut constrained = vec![false; 3 * m.num_nodes()];
        constrained[0] = true;
        // Centroid (1, 0.5, 0.5); the largest distance from it along an axis is 1.
        let (centre, size) = ([1.0, 0.5, 0.5], 1.0);
        for rank in 0..2 {
            let d = DofMap::new(&m, vec![0, 1], rank, 2, &constrained);
            let modes = d.rigid_body_modes(&m);
            assert_eq!(modes.len(), 6);
            let mut seen = 0;
            for (dof, &g) in d.global.iter().enumerate() {
                let owned = d.owned_start..d.owned_start + d.owned_count;
                if g < 0 || !owned.contains(&(g as usize)) {
                    continue;
                }
                let row = g as usize - d.owned_start;
                seen += 1;
                let (v, c) = (dof / 3, dof % 3);
                let r: [f64; 3] = std::array::from_fn(|k| (m.coords[v][k] - centre[k]) / size);
                let rotations = [[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]];
                for k in 0..3 {
                    assert_eq!(modes[k][row], if k == c { 1.0 } else { 0.0 });
                    assert!((modes[3 + k][row] - rotations[k][c]).abs() < 1e-15);
                }
            }
            assert_eq!(seen, d.owned_count);
        }
    }

    /// Two bodies: six modes each, each zero on the other body's dofs and, on its own, the
    /// rigid motions about its own centroid.
    #[test]
    fn every_body_has_its_own_rigid_body_modes() {
        let mut m = two_hexes();
        // The second element becomes a body of its own, on nodes of its own.
        let first = m.num_nodes();
        for v in 4..12 {
            m.coords.push(m.coords[v]);
        }
        let second: Vec<usize> = m.element_nodes(1).iter().map(|&v| v - 4 + first).collect();
        let start = m.offsets[1];
        m.conn[start..start + 8].copy_from_slice(&second);
        m.body[1] = 1;
        m.bodies.push("c".into());
        let constrained = vec![false; 3 * m.num_nodes()];
        let d = DofMap::new(&m, vec![0, 0], 0, 1, &constrained);
        let modes = d.rigid_body_modes(&m);
        assert_eq!(modes.len(), 12);
        let six = one_set_of_six(&modes);
        assert_eq!(six.len(), 6);
        for (k, mode) in six.iter().enumerate() {
            for (row, &v) in mode.iter().enumerate() {
                assert_eq!(v, modes[k][row] + modes[6 + k][row]);
            }
        }
        // Centroids (0.5, 0.5, 0.5) and (1.5, 0.5, 0.5), half-size 0.5 along every axis.
        let centres = [[0.5, 0.5, 0.5], [1.5, 0.5, 0.5]];
        for v in 0..m.num_nodes() {
            let body = usize::from(v >= first);
            let r: [f64; 3] = std::array::from_fn(|k| (m.coords[v][k] - centres[body][k]) / 0.5);
            // (e_k x r)_c
            let rotation_of = |k: usize, c: usize| match (k, c) {
                (0, 1) => -r[2],
                (0, 2) => r[1],
                (1, 0) => r[2],
                (1, 2) => -r[0],
                (2, 0) => -r[1],
                (2, 1) => r[0],
                _ => 0.0,
            };
            let used = v < 8 || v >= first;
            for c in 0..3 {
                let row = d.global[3 * v + c] as usize;
                for b in 0..2 {
                    let own = b == body && used;
                    for k in 0..3 {
                        let translation = if own && k == c { 1.0 } else { 0.0 };
                        assert_eq!(modes[6 * b + k][row], translation, "node {v} body {b}");
                        let rotation = if own { rotation_of(k, c) } else { 0.0 };
                        assert!((modes[6 * b + 3 + k][row] - rotation).abs() < 1e-15);
                    }
                }
            }
        }
    }

    #[test]
    fn sparsity_rows_hold_every_element_neighbour() {
        let m = two_hexes();
        let constrained = vec![false; 3 * m.num_nodes()];
        let d = DofMap::new(&m, vec![0, 0], 0, 1, &constrained);
        let s = d.bulk_sparsity(&m);
        // A node on x = 0 touches one element (8 nodes), a node on x = 1 touches both (12 nodes).
        assert_eq!(s.rows[0].len(), 24);
        assert_eq!(s.rows[3 * 4].len(), 36);
        let (dn, on) = s.nnz();
        assert!(on.iter().all(|&o| o == 0));
        assert_eq!(
            dn.iter().map(|&x| x as usize).sum::<usize>(),
            s.num_nonzeros()
        );
    }
}
