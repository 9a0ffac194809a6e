//! Averaged nodal normals `nu_A` of a contact surface and their exact linearization
//! (docs/theory.md section 2).
//!
//! # Definition
//!
//! For a face `f` around node `A` (faces in the ordering of [`crate::fe::element`]: corners
//! counter-clockwise seen from outside), evaluate at the **parent coordinates of `A` in that face**
//! (so quadratic faces use their curved geometry):
//!
//! ```text
//! t1 = x_,xi  = sum_a dN_a/dxi  x_a,      t2 = x_,eta = sum_a dN_a/deta x_a,
//! n~_f = t1 x t2,                          n_f = n~_f / |n~_f|.
//! ```
//!
//! The nodal normal is the normalized sum of the **unit** face normals, i.e. every face around the
//! node counts equally, whatever its size (the average is **not area-weighted**); with the symmetry
//! projection `P` (the identity with the diagonal entries of the constrained axes set to zero):
//!
//! ```text
//! s = sum_f n_f,      s' = P s,      nu_A = s' / |s'|.
//! ```
//!
//! The orientation follows the faces: for outward-ordered faces of the secondary body, `nu_A` is
//! the outward normal of that body, i.e. it points from the secondary toward the primary body as
//! docs/theory.md section 1 requires.
//!
//! # Linearization
//!
//! With the skew matrix `[v]_x w = v x w`, and since `d(t1 x t2) = dt1 x t2 + t1 x dt2` with
//! `dt1 = dN_a/dxi dx_a`, `dt2 = dN_a/deta dx_a` and `dt1 x t2 = -[t2]_x dt1`:
//!
//! ```text
//! d n~_f / d x_a = [t1]_x dN_a/deta - [t2]_x dN_a/dxi,
//! d n_f          = (I - n_f n_f^T) / |n~_f|  d n~_f,
//! d nu_A         = (I - nu_A nu_A^T) / |s'|  P  sum_f d n_f.
//! ```
//!
//! `nu_A` therefore depends on every node of every face around `A` (and on nothing else); a node
//! that appears in several of these faces collects the contributions of all of them.
//! [`NodalNormals::derivative`] returns these blocks, sorted by node.
//!
//! # Failures
//!
//! [`NodalNormals::compute`] returns `Err` naming the node (never a NaN) when
//! - a face around the node is degenerate there (`|n~_f| = 0`) or a coordinate is not finite;
//! - the projected sum vanishes, `|s'| <= 1e-10 k` with `k` the number of faces around the node
//!   (faces folded back onto each other, or a normal lying along a symmetry axis): the direction is
//!   undefined and its derivative, which scales as `1 / |s'|`, unbounded.
//!
//! Symmetry entries `(node, axis)` whose node is not on the surface are ignored (a symmetry
//! boundary condition usually covers more than the contact surface); an axis above 2 is an error.
//!
//! # Cost
//!
//! Every Newton iteration recomputes the normals, so the work is in flat arrays: the incidence
//! (node -> faces) in compressed rows, the derivative blocks of all nodes in one vector with
//! offsets, and the shape-function gradients at the face nodes tabulated once per process; nothing
//! is allocated per node. [`NodalNormals::update`] recomputes into the arrays of an existing object,
//! so repeated iterations allocate nothing at all (its cost per node: docs/performance.md).

use std::sync::OnceLock;

use crate::fe::FaceType;
use crate::vec3::{cross, norm};

/// A face of the surface: its type and global node ids (face order).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceFace<'a> {
    pub kind: FaceType,
    pub nodes: &'a [usize],
}

/// A 3x3 matrix, row-major: `m[i][j]`.
pub type Mat3 = [[f64; 3]; 3];

/// Marks "no entry" in the dense global-to-local maps.
const NONE: usize = usize::MAX;

/// Largest number of nodes of a face (Quad9).
const MAX_FACE_NODES: usize = 9;

/// The projected sum of unit normals vanishes when `|s'| <= VANISHING * (faces around the node)`.
const VANISHING: f64 = 1e-10;

/// `GRAD[t][i][a] = (dN_a/dxi, dN_a/deta)` of face type `FaceType::ALL[t]` at its node `i`.
type GradTable = [[[[f64; 2]; MAX_FACE_NODES]; MAX_FACE_NODES]; 5];

/// Shape-function gradients of every face type at its own nodes, computed once.
fn grad_table() -> &'static GradTable {
    static TABLE: OnceLock<GradTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut table = [[[[0.0; 2]; MAX_FACE_NODES]; MAX_FACE_NODES]; 5];
        for (t, ft) in FaceType::ALL.iter().enumerate() {
            let nn = ft.num_nodes();
            for (i, xi) in ft.node_coords().into_iter().enumerate() {
                ft.shape_grad(xi, &mut table[t][i][..nn]);
            }
        }
        table
    })
}

/// Row of a face type in [`GradTable`].
fn type_index(ft: FaceType) -> usize {
    match ft {
        FaceType::Quad4 => 0,
        FaceType::Quad8 => 1,
        FaceType::Quad9 => 2,
        FaceType::Tri3 => 3,
        FaceType::Tri6 => 4,
    }
}

/// `[v]_x`, the matrix of `w -> v x w`.
fn skew(v: [f64; 3]) -> Mat3 {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

/// `(I - u u^T) / len` for a unit vector `u`.
fn tangent_projector(u: [f64; 3], len: f64) -> Mat3 {
    let inv = 1.0 / len;
    std::array::from_fn(|i| {
        std::array::from_fn(|j| ((if i == j { 1.0 } else { 0.0 }) - u[i] * u[j]) * inv)
    })
}

fn matmul(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j])
    })
}

/// Nodal normals `nu_A` of every node of a surface and their derivatives `d nu_A / d x_B`
/// (definitions in the module docs).
#[derive(Clone, Debug, Default)]
pub struct NodalNormals {
    /// Surface nodes (global ids), ascending.
    nodes: Vec<usize>,
    /// Global id -> position in `nodes`, or [`NONE`].
    local: Vec<usize>,
    /// Unit normal of each surface node.
    nu: Vec<[f64; 3]>,
    /// Derivative blocks of node `nodes[k]` are `deriv[offsets[k]..offsets[k + 1]]`.
    offsets: Vec<usize>,
    /// `(B, d nu_A / d x_B)`, sorted by `B` within each node.
    deriv: Vec<(usize, Mat3)>,
    /// Work arrays kept for [`NodalNormals::update`].
    scratch: Scratch,
}

/// Work arrays of [`NodalNormals::update`], kept so that repeated updates do not allocate.
#[derive(Clone, Debug, Default)]
struct Scratch {
    /// Incidence rows: the faces around `nodes[k]` are `inc[inc_off[k]..inc_off[k + 1]]`.
    inc_off: Vec<usize>,
    /// `(face, position of the node in the face)`.
    inc: Vec<(usize, usize)>,
    /// Bit `axis` set: that normal component of `nodes[k]` is zeroed (symmetry).
    mask: Vec<u8>,
    /// Global id -> position in `deriv` while one node is processed, else [`NONE`].
    pos: Vec<usize>,
}

impl NodalNormals {
    /// Nodal normals of the surface made of `faces` at current coordinates `x` (indexed by global
    /// node), with the normal components `(node, axis)` of `symmetry` zeroed before normalizing.
    ///
    /// # Errors
    /// A face with the wrong number of nodes or a node id outside `x`; a symmetry axis above 2; a
    /// face degenerate at one of its nodes or non-finite coordinates; a vanishing (projected) sum
    /// of the face normals at a node. The message names the node (or face).
    pub fn compute(
        faces: &[SurfaceFace],
        x: &[[f64; 3]],
        symmetry: &[(usize, usize)],
    ) -> Result<NodalNormals, String> {
        let mut normals = NodalNormals::default();
        normals.update(faces, x, symmetry)?;
        Ok(normals)
    }

    /// Same as [`NodalNormals::compute`], reusing this object's storage (for every Newton
    /// iteration: no allocation once the arrays have grown to size). On `Err` the object is left
    /// empty (no node, no normal).
    ///
    /// # Errors
    /// As [`NodalNormals::compute`].
    pub fn update(
        &mut self,
        faces: &[SurfaceFace],
        x: &[[f64; 3]],
        symmetry: &[(usize, usize)],
    ) -> Result<(), String> {
        let result = self.fill(faces, x, symmetry);
        if result.is_err() {
            self.nodes.clear();
            self.local.clear();
            self.nu.clear();
            self.offsets.clear();
            self.deriv.clear();
        }
        result
    }

    fn fill(
        &mut self,
        faces: &[SurfaceFace],
        x: &[[f64; 3]],
        symmetry: &[(usize, usize)],
    ) -> Result<(), String> {
        check_faces(faces, x.len())?;
        let NodalNormals {
            nodes,
            local,
            nu,
            offsets,
            deriv,
            scratch,
        } = self;
        number_surface_nodes(faces, x.len(), local, nodes);
        let n = nodes.len();
        scratch.build_incidence(faces, local, n);
        scratch.build_mask(symmetry, local, n)?;
        deriv.clear();
        nu.clear();
        offsets.clear();
        offsets.push(0);
        scratch.pos.clear();
        scratch.pos.resize(x.len(), NONE);
        for (la, &a_glob) in nodes.iter().enumerate() {
            let start = deriv.len();
            let incident = &scratch.inc[scratch.inc_off[la]..scratch.inc_off[la + 1]];
            let s = sum_face_normals(faces, x, incident, a_glob, deriv, &mut scratch.pos)?;
            let mask = scratch.mask[la];
            let nu_a = normalize(s, mask, incident.len(), a_glob, &mut deriv[start..])?;
            nu.push(nu_a);
            offsets.push(deriv.len());
        }
        Ok(())
    }

    /// Position of a global node in the surface arrays.
    fn local_index(&self, node: usize) -> Option<usize> {
        self.local.get(node).copied().filter(|&l| l != NONE)
    }

    /// Unit normal `nu_A` of global node `node`, or `None` if it is not on the surface.
    pub fn normal(&self, node: usize) -> Option<[f64; 3]> {
        self.local_index(node).map(|l| self.nu[l])
    }

    /// `d nu_A / d x_B` for every node `B` that influences `nu_A` (all nodes of all faces around
    /// `A`), as `(B, matrix)` with entry `(i, j) = d nu_A,i / d x_B,j`, sorted by `B`. Empty if
    /// `node` is not on the surface.
    pub fn derivative(&self, node: usize) -> &[(usize, [[f64; 3]; 3])] {
        match self.local_index(node) {
            Some(l) => &self.deriv[self.offsets[l]..self.offsets[l + 1]],
            None => &[],
        }
    }

    /// The surface nodes (global ids), ascending.
    pub fn nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.nodes.iter().copied()
    }

    /// Number of surface nodes.
    pub fn num_nodes(&self) -> usize {
        self.nodes.len()
    }
}

/// Checks that every face has its type's number of nodes, all of them below `nx`.
fn check_faces(faces: &[SurfaceFace], nx: usize) -> Result<(), String> {
    for (f, face) in faces.iter().enumerate() {
        let nn = face.kind.num_nodes();
        if face.nodes.len() != nn {
            return Err(format!(
                "surface face {f} ({}) has {} nodes, expected {nn}",
                face.kind.name(),
                face.nodes.len()
            ));
        }
        if let Some(&b) = face.nodes.iter().find(|&&b| b >= nx) {
            return Err(format!(
                "surface face {f} refers to node {b}, but only {nx} node coordinates are given"
            ));
        }
    }
    Ok(())
}

/// The surface nodes, ascending, into `nodes`, and the global -> local map of the `nx` nodes
/// into `local` ([`NONE`] off the surface).
fn number_surface_nodes(
    faces: &[SurfaceFace],
    nx: usize,
    local: &mut Vec<usize>,
    nodes: &mut Vec<usize>,
) {
    local.clear();
    local.resize(nx, NONE);
    for face in faces {
        for &b in face.nodes {
            local[b] = 0;
        }
    }
    nodes.clear();
    for (b, l) in local.iter_mut().enumerate() {
        if *l != NONE {
            *l = nodes.len();
            nodes.push(b);
        }
    }
}

impl Scratch {
    /// The incidence (node -> faces) of the `n` surface nodes numbered by `local`, in
    /// compressed rows.
    fn build_incidence(&mut self, faces: &[SurfaceFace], local: &[usize], n: usize) {
        let Scratch { inc_off, inc, .. } = self;
        // Filled with `inc_off[k]` as the cursor of row `k`, which leaves `inc_off[k]` at the end
        // of row `k`, i.e. the start of row `k + 1`.
        inc_off.clear();
        inc_off.resize(n + 1, 0);
        for face in faces {
            for &b in face.nodes {
                inc_off[local[b] + 1] += 1;
            }
        }
        for k in 0..n {
            inc_off[k + 1] += inc_off[k];
        }
        inc.clear();
        inc.resize(inc_off[n], (0, 0));
        for (f, face) in faces.iter().enumerate() {
            for (i, &b) in face.nodes.iter().enumerate() {
                let l = local[b];
                inc[inc_off[l]] = (f, i);
                inc_off[l] += 1;
            }
        }
        for k in (1..=n).rev() {
            inc_off[k] = inc_off[k - 1];
        }
        if n > 0 {
            inc_off[0] = 0;
        }
    }

    /// The symmetry mask of the `n` surface nodes numbered by `local`: bit `axis` of `mask[k]`
    /// zeroes that component of the normal of node `k`. Entries off the surface are ignored.
    fn build_mask(
        &mut self,
        symmetry: &[(usize, usize)],
        local: &[usize],
        n: usize,
    ) -> Result<(), String> {
        let mask = &mut self.mask;
        mask.clear();
        mask.resize(n, 0);
        for &(b, axis) in symmetry {
            if axis > 2 {
                return Err(format!(
                    "symmetry condition on node {b}: axis {axis} is not 0, 1 or 2"
                ));
            }
            if let Some(&l) = local.get(b) {
                if l != NONE {
                    mask[l] |= 1 << axis;
                }
            }
        }
        Ok(())
    }
}

/// The sum `s = sum_f n_f` of the unit normals of the faces around node `a_glob` at the node
/// (`incident`: each face and the node's position in it), with `sum_f d n_f / d x_b` of every
/// node `b` of those faces appended to `deriv` (one block per node; `pos` maps a node to its
/// block while the node is processed, and is [`NONE`] again on success).
fn sum_face_normals(
    faces: &[SurfaceFace],
    x: &[[f64; 3]],
    incident: &[(usize, usize)],
    a_glob: usize,
    deriv: &mut Vec<(usize, Mat3)>,
    pos: &mut [usize],
) -> Result<[f64; 3], String> {
    let table = grad_table();
    let start = deriv.len();
    let mut s = [0.0; 3];
    for &(f, ia) in incident {
        let face = &faces[f];
        let nn = face.kind.num_nodes();
        let g = &table[type_index(face.kind)][ia][..nn];
        let mut t1 = [0.0; 3];
        let mut t2 = [0.0; 3];
        for (&b, gb) in face.nodes.iter().zip(g) {
            for d in 0..3 {
                t1[d] += gb[0] * x[b][d];
                t2[d] += gb[1] * x[b][d];
            }
        }
        let c = cross(t1, t2);
        let len = norm(c);
        if !(len > 0.0 && len.is_finite()) {
            return Err(format!(
                "nodal normal of node {a_glob}: surface face {f} ({}) is degenerate or \
                 not finite there (|x_,xi x x_,eta| = {len:e})",
                face.kind.name()
            ));
        }
        let nf = c.map(|v| v / len);
        for d in 0..3 {
            s[d] += nf[d];
        }
        add_face_normal_derivative(face.nodes, g, [t1, t2], nf, len, deriv, pos);
    }
    for e in &deriv[start..] {
        pos[e.0] = NONE;
    }
    Ok(s)
}

/// Adds `d n_f / d x_b = Q ([t1]_x dN_b/deta - [t2]_x dN_b/dxi)`, `Q = (I - n n^T) / |n~|`, of
/// the face with nodes `nodes` and gradients `g` at the node (tangents `t`, unit normal `nf`,
/// `len = |n~|`) to the blocks of its nodes in `deriv` (see [`sum_face_normals`]).
fn add_face_normal_derivative(
    nodes: &[usize],
    g: &[[f64; 2]],
    t: [[f64; 3]; 2],
    nf: [f64; 3],
    len: f64,
    deriv: &mut Vec<(usize, Mat3)>,
    pos: &mut [usize],
) {
    let q = tangent_projector(nf, len);
    let q1 = matmul(&q, &skew(t[0]));
    let q2 = matmul(&q, &skew(t[1]));
    for (&b, gb) in nodes.iter().zip(g) {
        let p = if pos[b] == NONE {
            pos[b] = deriv.len();
            deriv.push((b, [[0.0; 3]; 3]));
            pos[b]
        } else {
            pos[b]
        };
        let m = &mut deriv[p].1;
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += gb[1] * q1[i][j] - gb[0] * q2[i][j];
            }
        }
    }
}

/// `nu_A = s' / |s'|` of node `a_glob` from the sum `s` of the unit normals of its `count`
/// faces, `s' = P s` with the symmetry `mask`; `blocks` hold `(b, sum_f d n_f / d x_b)` on entry
/// and `(b, d nu_A / d x_b)`, sorted by `b`, on return.
fn normalize(
    mut s: [f64; 3],
    mask: u8,
    count: usize,
    a_glob: usize,
    blocks: &mut [(usize, Mat3)],
) -> Result<[f64; 3], String> {
    for (d, sd) in s.iter_mut().enumerate() {
        if mask & (1 << d) != 0 {
            *sd = 0.0;
        }
    }
    let ls = norm(s);
    if !ls.is_finite() || ls <= VANISHING * count as f64 {
        return Err(format!(
            "nodal normal of node {a_glob} vanishes: the unit normals of the {count} faces \
             around it{} sum to |s| = {ls:e} (faces folded back onto each other?)",
            if mask != 0 {
                ", with the symmetry components zeroed,"
            } else {
                ""
            }
        ));
    }
    let nu_a = s.map(|v| v / ls);
    // d nu = R P ds with R = (I - nu nu^T)/|s'|: zero the constrained columns of R.
    let mut rp = tangent_projector(nu_a, ls);
    for row in rp.iter_mut() {
        for (d, v) in row.iter_mut().enumerate() {
            if mask & (1 << d) != 0 {
                *v = 0.0;
            }
        }
    }
    for e in blocks.iter_mut() {
        e.1 = matmul(&rp, &e.1);
    }
    blocks.sort_unstable_by_key(|e| e.0);
    Ok(nu_a)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_rng::Rng;

    /// A structured surface: `nc x nc` cells on a lattice of `(2 nc + 1)^2` points (mid-edge and
    /// centre points are used by the quadratic faces only), mapped from parameters `(u, v)` in
    /// `[-1, 1]^2`; faces are counter-clockwise in `(u, v)`, so their normal is `x_,u x x_,v`.
    struct Mesh {
        x: Vec<[f64; 3]>,
        faces: Vec<(FaceType, Vec<usize>)>,
        m: usize,
    }

    impl Mesh {
        /// `jitter` moves every lattice point in parameter space by up to that fraction of the
        /// lattice spacing (so flat maps stay flat but faces are distorted).
        fn new(
            kind: FaceType,
            nc: usize,
            jitter: f64,
            rng: &mut Rng,
            map: impl Fn(f64, f64) -> [f64; 3],
        ) -> Mesh {
            let m = 2 * nc + 1;
            let h = 2.0 / (m - 1) as f64;
            let mut x = Vec::with_capacity(m * m);
            for j in 0..m {
                for i in 0..m {
                    let u = -1.0 + h * i as f64 + jitter * h * rng.sym();
                    let v = -1.0 + h * j as f64 + jitter * h * rng.sym();
                    x.push(map(u, v));
                }
            }
            let id = |i: usize, j: usize| j * m + i;
            let mut faces = Vec::new();
            for cj in 0..nc {
                for ci in 0..nc {
                    let (i0, j0) = (2 * ci, 2 * cj);
                    let p = |di: usize, dj: usize| id(i0 + di, j0 + dj);
                    let (c0, c1, c2, c3) = (p(0, 0), p(2, 0), p(2, 2), p(0, 2));
                    match kind {
                        FaceType::Quad4 => faces.push((kind, vec![c0, c1, c2, c3])),
                        FaceType::Quad8 | FaceType::Quad9 => {
                            let mut f = vec![c0, c1, c2, c3, p(1, 0), p(2, 1), p(1, 2), p(0, 1)];
                            if kind == FaceType::Quad9 {
                                f.push(p(1, 1));
                            }
                            faces.push((kind, f));
                        }
                        FaceType::Tri3 => {
                            faces.push((kind, vec![c0, c1, c2]));
                            faces.push((kind, vec![c0, c2, c3]));
                        }
                        FaceType::Tri6 => {
                            faces.push((kind, vec![c0, c1, c2, p(1, 0), p(2, 1), p(1, 1)]));
                            faces.push((kind, vec![c0, c2, c3, p(1, 1), p(1, 2), p(0, 1)]));
                        }
                    }
                }
            }
            Mesh { x, faces, m }
        }

        fn surface(&self) -> Vec<SurfaceFace<'_>> {
            self.faces
                .iter()
                .map(|(kind, nodes)| SurfaceFace { kind: *kind, nodes })
                .collect()
        }

        fn id(&self, i: usize, j: usize) -> usize {
            j * self.m + i
        }

        fn compute(&self, x: &[[f64; 3]], sym: &[(usize, usize)]) -> NodalNormals {
            NodalNormals::compute(&self.surface(), x, sym).expect("normals")
        }
    }

    fn normalize(a: [f64; 3]) -> [f64; 3] {
        let l = norm(a);
        a.map(|v| v / l)
    }

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
        norm(cross(a, b)).atan2(dot(a, b))
    }

    /// Rotation by `angle` about `axis` (Rodrigues).
    fn rotation(axis: [f64; 3], angle: f64) -> Mat3 {
        let k = normalize(axis);
        let (s, c) = angle.sin_cos();
        let kx = skew(k);
        let kx2 = matmul(&kx, &kx);
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                (if i == j { 1.0 } else { 0.0 }) + s * kx[i][j] + (1.0 - c) * kx2[i][j]
            })
        })
    }

    fn apply(r: &Mat3, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
    }

    fn transpose(a: &Mat3) -> Mat3 {
        std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
    }

    /// A surface face of type `kind` with nodes `nodes`.
    fn face(kind: FaceType, nodes: &[usize]) -> SurfaceFace<'_> {
        SurfaceFace { kind, nodes }
    }

    /// The largest magnitude of an entry of derivative blocks.
    fn largest_entry(blocks: &[(usize, Mat3)]) -> f64 {
        blocks
            .iter()
            .flat_map(|(_, m)| m.iter().flatten())
            .fold(0.0f64, |acc, v| acc.max(v.abs()))
    }

    /// A tilted plane through `o` with orthonormal in-plane axes `e1, e2` and normal
    /// `e1 x e2 = nrm`.
    fn tilted_plane() -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3]) {
        let nrm = normalize([0.3, -0.4, 0.87]);
        let e1 = normalize(cross(nrm, [1.0, 0.2, 0.0]));
        let e2 = cross(nrm, e1);
        ([0.7, -1.1, 2.3], e1, e2, nrm)
    }

    /// Flat surfaces of every face type, distorted in their plane: every nodal normal is the plane
    /// normal, with the sign of the face orientation.
    #[test]
    fn flat_surfaces_give_the_plane_normal() {
        let (o, e1, e2, nrm) = tilted_plane();
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for kind in FaceType::ALL {
            for flip in [1.0, -1.0] {
                // flip = -1 mirrors the v axis: the faces turn clockwise, the normal flips.
                let mesh = Mesh::new(kind, 3, 0.1, &mut rng, |u, v| {
                    std::array::from_fn(|d| o[d] + 2.0 * u * e1[d] + 1.5 * flip * v * e2[d])
                });
                let nn = mesh.compute(&mesh.x, &[]);
                let expected = nrm.map(|v| flip * v);
                let mut count = 0;
                for a in nn.nodes() {
                    let nu = nn.normal(a).unwrap();
                    for d in 0..3 {
                        assert!(
                            (nu[d] - expected[d]).abs() < 1e-14,
                            "{kind:?} flip {flip}: node {a} normal {nu:?} vs {expected:?}"
                        );
                    }
                    count += 1;
                }
                let expected_count = match kind {
                    FaceType::Quad4 | FaceType::Tri3 => 16,
                    FaceType::Quad8 => 49 - 9,
                    FaceType::Quad9 | FaceType::Tri6 => 49,
                };
                assert_eq!(count, expected_count, "{kind:?}");
                assert_eq!(nn.num_nodes(), expected_count);
            }
        }
    }

    /// The average is of unit face normals, not area-weighted: at the ridge of two flat faces of
    /// very different sizes, the nodal normal is the exact bisector.
    #[test]
    fn ridge_normal_is_the_bisector_whatever_the_face_sizes() {
        let th = 0.4f64;
        let (c, s) = (th.cos(), th.sin());
        // Ridge along y through the origin; face L goes to x < 0 rising, face R (10x wider) to x > 0.
        let x = vec![
            [-c, 0.0, -s],
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-c, 1.0, -s],
            [10.0 * c, 0.0, -10.0 * s],
            [10.0 * c, 1.0, -10.0 * s],
        ];
        let faces = [
            face(FaceType::Quad4, &[0, 1, 2, 3]),
            face(FaceType::Quad4, &[1, 4, 5, 2]),
        ];
        let nn = NodalNormals::compute(&faces, &x, &[]).unwrap();
        for a in [1, 2] {
            let nu = nn.normal(a).unwrap();
            assert!((nu[0]).abs() < 1e-15 && (nu[1]).abs() < 1e-15, "{nu:?}");
            assert!((nu[2] - 1.0).abs() < 1e-15, "{nu:?}");
        }
        let nl = nn.normal(0).unwrap();
        assert!(
            (nl[0] + s).abs() < 1e-15 && (nl[2] - c).abs() < 1e-15,
            "{nl:?}"
        );
        assert_eq!(nn.normal(6), None);
        assert!(nn.derivative(6).is_empty());
        assert!(nn.derivative(1000).is_empty());
    }

    /// Largest angle between the nodal normal and the radius over the corner nodes of a patch of
    /// the unit sphere (a gnomonic "cube sphere" patch around +z, parameters distorted).
    fn sphere_corner_error(kind: FaceType, nc: usize) -> f64 {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mesh = Mesh::new(kind, nc, 0.0, &mut rng, |u, v| {
            let (a, b) = (0.6 * u, 0.6 * v);
            // A smooth non-uniform parametrization, so elements are not all alike.
            normalize([(a + 0.1 * a * b).tan(), (b + 0.05 * a * a).tan(), 1.0])
        });
        let nn = mesh.compute(&mesh.x, &[]);
        let mut err: f64 = 0.0;
        for j in (0..mesh.m).step_by(2) {
            for i in (0..mesh.m).step_by(2) {
                let a = mesh.id(i, j);
                let radial = normalize(mesh.x[a]);
                err = err.max(angle(nn.normal(a).unwrap(), radial));
            }
        }
        err
    }

    /// On a sphere, quadratic faces give nodal normals at the corners within O(h^2) of the radial
    /// direction. Tolerance: with `h = 1.2 / nc` the element width in radians, the largest corner
    /// angle error must stay below `0.25 h^2` and drop by more than 2.5 at each halving of `h`.
    #[test]
    fn sphere_patch_normals_converge_to_the_radius() {
        for kind in [FaceType::Quad8, FaceType::Quad9, FaceType::Tri6] {
            let ncs = [2usize, 4, 8, 16];
            let errs: Vec<f64> = ncs
                .iter()
                .map(|&nc| sphere_corner_error(kind, nc))
                .collect();
            println!("{kind:?}: corner-normal angle errors (rad) {errs:?}");
            for (&nc, &e) in ncs.iter().zip(&errs) {
                let h = 1.2 / nc as f64;
                assert!(e < 0.25 * h * h, "{kind:?} nc {nc}: {errs:?}");
            }
            for w in errs.windows(2) {
                assert!(
                    w[1] < w[0] / 2.5,
                    "{kind:?}: no O(h^2) convergence {errs:?}"
                );
            }
        }
    }

    /// A distorted curved mesh of `kind` (random node positions around a smooth surface).
    fn curved_mesh(kind: FaceType) -> Mesh {
        let mut rng = Rng(0xdead_beef_cafe_f00d ^ type_index(kind) as u64);
        let mut mesh = Mesh::new(kind, 2, 0.15, &mut rng, |u, v| {
            [
                1.1 * u + 0.1 * v,
                0.9 * v - 0.05 * u * u,
                0.3 * (1.3 * u).sin() + 0.2 * u * v + 0.1 * v * v,
            ]
        });
        for x in &mut mesh.x {
            for xd in x.iter_mut() {
                *xd += 0.03 * rng.sym();
            }
        }
        mesh
    }

    /// The derivative against central finite differences of `compute`, on a distorted curved mesh
    /// of every face type, with symmetry conditions. Every surface coordinate is perturbed and the
    /// change of every nodal normal compared, so entries missing from `derivative` are caught too.
    #[test]
    fn derivative_matches_finite_differences() {
        let h = 1e-7;
        for kind in FaceType::ALL {
            let mesh = curved_mesh(kind);
            // A corner on the edge u = -1 with its x component zeroed, the (-1, -1) corner with x and
            // y zeroed (its normal is then +-z and its derivative zero), a node at the edge v = -1
            // with y zeroed.
            let sym = vec![
                (mesh.id(0, 2), 0),
                (mesh.id(0, 0), 0),
                (mesh.id(0, 0), 1),
                (mesh.id(2, 0), 1),
                (mesh.id(0, 0), 0), // a repeated entry is harmless
            ];
            let nn = mesh.compute(&mesh.x, &sym);
            assert_eq!(nn.normal(mesh.id(0, 2)).unwrap()[0], 0.0);
            assert_eq!(nn.normal(mesh.id(2, 0)).unwrap()[1], 0.0);
            let corner = nn.normal(mesh.id(0, 0)).unwrap();
            assert_eq!((corner[0], corner[1], corner[2]), (0.0, 0.0, 1.0));

            let nodes: Vec<usize> = nn.nodes().collect();
            let global_max = nodes
                .iter()
                .map(|&a| largest_entry(nn.derivative(a)))
                .fold(0.0f64, f64::max);
            assert!(global_max > 0.1, "{kind:?}: derivative suspiciously small");
            let scale = |a: usize| {
                let s = largest_entry(nn.derivative(a));
                if s > 0.0 {
                    s
                } else {
                    global_max
                }
            };
            let analytic = |a: usize, b: usize, j: usize| -> [f64; 3] {
                match nn.derivative(a).binary_search_by_key(&b, |e| e.0) {
                    Ok(k) => std::array::from_fn(|i| nn.derivative(a)[k].1[i][j]),
                    Err(_) => [0.0; 3],
                }
            };

            let mut worst: f64 = 0.0;
            for &b in &nodes {
                for j in 0..3 {
                    let mut xp = mesh.x.clone();
                    xp[b][j] += h;
                    let mut xm = mesh.x.clone();
                    xm[b][j] -= h;
                    let np = mesh.compute(&xp, &sym);
                    let nm = mesh.compute(&xm, &sym);
                    for &a in &nodes {
                        let (p, m) = (np.normal(a).unwrap(), nm.normal(a).unwrap());
                        let fd: [f64; 3] = std::array::from_fn(|i| (p[i] - m[i]) / (2.0 * h));
                        let an = analytic(a, b, j);
                        for i in 0..3 {
                            let rel = (fd[i] - an[i]).abs() / scale(a);
                            worst = worst.max(rel);
                            assert!(
                                rel < 1e-6,
                                "{kind:?}: d nu_{a},{i} / d x_{b},{j}: analytic {} vs fd {}",
                                an[i],
                                fd[i]
                            );
                        }
                    }
                }
            }
            println!("{kind:?}: worst relative FD mismatch {worst:e}");

            // The listed influencing nodes are exactly the nodes of the faces around A.
            for &a in &nodes {
                let mut expected: Vec<usize> = mesh
                    .faces
                    .iter()
                    .filter(|(_, f)| f.contains(&a))
                    .flat_map(|(_, f)| f.iter().copied())
                    .collect();
                expected.sort_unstable();
                expected.dedup();
                let listed: Vec<usize> = nn.derivative(a).iter().map(|e| e.0).collect();
                assert_eq!(listed, expected, "{kind:?}: influencing nodes of {a}");
            }
        }
    }

    /// Rotating and translating all coordinates rotates the normals (`nu' = R nu`) and their
    /// derivatives (`D' = R D R^T`).
    #[test]
    fn normals_are_frame_indifferent() {
        let r = rotation([0.3, -1.0, 0.5], 2.1);
        let shift = [3.0, -2.0, 0.5];
        for kind in FaceType::ALL {
            let mesh = curved_mesh(kind);
            let xr: Vec<[f64; 3]> = mesh
                .x
                .iter()
                .map(|&p| {
                    let q = apply(&r, p);
                    std::array::from_fn(|d| q[d] + shift[d])
                })
                .collect();
            let n0 = mesh.compute(&mesh.x, &[]);
            let n1 = mesh.compute(&xr, &[]);
            for a in n0.nodes() {
                let expected = apply(&r, n0.normal(a).unwrap());
                let got = n1.normal(a).unwrap();
                for d in 0..3 {
                    assert!((got[d] - expected[d]).abs() < 1e-13, "{kind:?} node {a}");
                }
                let (d0, d1) = (n0.derivative(a), n1.derivative(a));
                assert_eq!(d0.len(), d1.len());
                let big = largest_entry(d0);
                for ((b0, m0), (b1, m1)) in d0.iter().zip(d1) {
                    assert_eq!(b0, b1);
                    let rot = matmul(&matmul(&r, m0), &transpose(&r));
                    for i in 0..3 {
                        for j in 0..3 {
                            assert!(
                                (rot[i][j] - m1[i][j]).abs() < 1e-12 * big,
                                "{kind:?} d nu_{a} / d x_{b0}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// Two faces folded back onto each other: the normals cancel at the shared nodes, and compute
    /// reports the node instead of producing NaN.
    #[test]
    fn folded_faces_are_reported_not_nan() {
        let (o, e1, e2, _) = tilted_plane();
        let p =
            |u: f64, v: f64| -> [f64; 3] { std::array::from_fn(|d| o[d] + u * e1[d] + v * e2[d]) };
        // Face 0 on [0, 1]^2 counter-clockwise; face 1 shares the edge 1-2 and folds back over it.
        let x = vec![
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(1.0, 1.0),
            p(0.0, 1.0),
            p(0.0, 0.0),
            p(0.0, 1.0),
        ];
        let faces = [
            face(FaceType::Quad4, &[0, 1, 2, 3]),
            face(FaceType::Quad4, &[1, 4, 5, 2]),
        ];
        let err = NodalNormals::compute(&faces, &x, &[]).unwrap_err();
        assert!(err.contains("node 1 "), "{err}");
        assert!(err.contains("vanishes"), "{err}");

        // Triangles folded the same way.
        let tri = [
            face(FaceType::Tri3, &[0, 1, 2]),
            face(FaceType::Tri3, &[2, 1, 4]),
        ];
        let err = NodalNormals::compute(&tri, &x, &[]).unwrap_err();
        assert!(err.contains("node 1 "), "{err}");

        // A symmetry axis along the only normal direction also leaves nothing to normalize.
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let err = NodalNormals::compute(&tri[..1], &flat, &[(2, 2)]).unwrap_err();
        assert!(err.contains("node 2 "), "{err}");

        // Non-finite coordinates and collapsed faces are errors too, never NaN normals.
        let mut bad = x.clone();
        bad[3][1] = f64::NAN;
        let err = NodalNormals::compute(&faces, &bad, &[]).unwrap_err();
        assert!(err.contains("node 0") || err.contains("node 2"), "{err}");
        let collapsed = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let err = NodalNormals::compute(&tri[..1], &collapsed, &[]).unwrap_err();
        assert!(err.contains("node 0"), "{err}");

        // Malformed input.
        assert!(NodalNormals::compute(&faces, &x[..4], &[]).is_err());
        assert!(NodalNormals::compute(&faces, &x, &[(1, 3)]).is_err());
        let short = [face(FaceType::Quad4, &[0, 1, 2])];
        assert!(NodalNormals::compute(&short, &x, &[]).is_err());
    }

    /// `update` reuses an object across surfaces and gives bit for bit the result of `compute`;
    /// after an error the object is empty instead of holding stale or NaN normals.
    #[test]
    fn update_matches_compute_and_clears_on_error() {
        let mut nn = NodalNormals::default();
        for kind in FaceType::ALL {
            let mesh = curved_mesh(kind);
            let sym = [(mesh.id(0, 2), 0)];
            nn.update(&mesh.surface(), &mesh.x, &sym).unwrap();
            let fresh = mesh.compute(&mesh.x, &sym);
            assert!(nn.nodes().eq(fresh.nodes()), "{kind:?}");
            for a in fresh.nodes() {
                assert_eq!(nn.normal(a), fresh.normal(a), "{kind:?}");
                assert_eq!(nn.derivative(a), fresh.derivative(a), "{kind:?}");
            }
        }
        let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let folded = [
            face(FaceType::Tri3, &[0, 1, 2]),
            face(FaceType::Tri3, &[0, 2, 1]),
        ];
        assert!(nn.update(&folded, &x, &[]).is_err());
        assert_eq!(nn.num_nodes(), 0);
        assert_eq!(nn.normal(0), None);
        assert!(nn.derivative(0).is_empty());
    }
}
