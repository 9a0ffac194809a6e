//! Reference geometry, internal force and tangent, stresses (see the module docs of
//! [`crate::solid`] for the formulas).

use nalgebra::{DMatrix, Matrix3};

use crate::fe::quadrature::Rule3;
use crate::fe::ElementType;
use crate::material::{von_mises, Material};

/// The largest number of nodes of an element (Hex27): the size of stack buffers.
pub const MAX_NODES: usize = 27;

/// A non-positive reference Jacobian determinant.
///
/// `point < n` (with `n` the number of points of the quadrature rule given to
/// [`ElementGeometry::new`]) names quadrature point `point`; `point >= n` names element node
/// `point - n` (the corners and mid-nodes are checked too, which catches badly shaped elements
/// whose quadrature points still look fine).
#[derive(Debug, Clone, PartialEq)]
pub struct InvertedElement {
    pub det: f64,
    pub point: usize,
}

impl InvertedElement {
    /// The element node at which the determinant was found, if it was not a quadrature point.
    pub fn node(&self, num_points: usize) -> Option<usize> {
        self.point.checked_sub(num_points)
    }

    /// A one-line description, e.g. `"det J0 = -0.5 at quadrature point 3"`.
    pub fn describe(&self, num_points: usize) -> String {
        match self.node(num_points) {
            Some(n) => format!("det J0 = {} at node {n} (element-local)", self.det),
            None => format!("det J0 = {} at quadrature point {}", self.det, self.point),
        }
    }
}

/// Reference geometry of one element at its quadrature points, precomputed once: per point the
/// reference gradients `dN/dX` (`num_nodes x 3`), the values `N`, the weight `w det J0` and the
/// reference position `X`.
#[derive(Debug, Clone)]
pub struct ElementGeometry {
    kind: ElementType,
    num_nodes: usize,
    /// `dN_a/dX` at point `q`: entry `q * num_nodes + a`.
    dndx: Vec<[f64; 3]>,
    /// `N_a` at point `q`: entry `q * num_nodes + a`.
    n: Vec<f64>,
    /// `w det J0` per point.
    wdet: Vec<f64>,
    /// Reference position per point.
    x: Vec<[f64; 3]>,
}

/// Reference Jacobian `J0_ij = sum_a X_ai dN_a/dxi_j`.
fn jacobian(x_ref: &[[f64; 3]], dn: &[[f64; 3]]) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for (xa, da) in x_ref.iter().zip(dn) {
        for i in 0..3 {
            for jj in 0..3 {
                j[(i, jj)] += xa[i] * da[jj];
            }
        }
    }
    j
}

impl ElementGeometry {
    /// Err(InvertedElement { point, det }) if det J0 <= 0 at any quadrature point or, after
    /// those, at any node (see [`InvertedElement`] for the numbering). `x_ref` are the element's
    /// node coordinates (VTK order).
    ///
    /// # Panics
    /// If `x_ref.len() != kind.num_nodes()` or the rule's points and weights differ in length.
    pub fn new(
        kind: ElementType,
        rule: &Rule3,
        x_ref: &[[f64; 3]],
    ) -> Result<Self, InvertedElement> {
        let nn = kind.num_nodes();
        assert_eq!(x_ref.len(), nn, "ElementGeometry: wrong number of nodes");
        assert_eq!(
            rule.points.len(),
            rule.weights.len(),
            "ElementGeometry: bad rule"
        );
        let np = rule.points.len();
        let mut geom = ElementGeometry {
            kind,
            num_nodes: nn,
            dndx: Vec::with_capacity(np * nn),
            n: vec![0.0; np * nn],
            wdet: Vec::with_capacity(np),
            x: Vec::with_capacity(np),
        };
        let mut dn = [[0.0; 3]; MAX_NODES];
        let dn = &mut dn[..nn];
        for (q, (&xi, &w)) in rule.points.iter().zip(&rule.weights).enumerate() {
            kind.shape_grad(xi, dn);
            let j0 = jacobian(x_ref, dn);
            let det = j0.determinant();
            // NaN (a degenerate node set) is rejected too.
            if det.is_nan() || det <= 0.0 {
                return Err(InvertedElement { det, point: q });
            }
            let jinv = j0.try_inverse().ok_or(InvertedElement { det, point: q })?;
            for d in dn.iter() {
                let mut g = [0.0; 3];
                for (cap_j, gj) in g.iter_mut().enumerate() {
                    *gj =
                        d[0] * jinv[(0, cap_j)] + d[1] * jinv[(1, cap_j)] + d[2] * jinv[(2, cap_j)];
                }
                geom.dndx.push(g);
            }
            let nq = &mut geom.n[q * nn..(q + 1) * nn];
            kind.shape(xi, nq);
            let mut xq = [0.0; 3];
            for (na, xa) in nq.iter().zip(x_ref) {
                for d in 0..3 {
                    xq[d] += na * xa[d];
                }
            }
            geom.x.push(xq);
            geom.wdet.push(w * det);
        }
        for (a, xi) in kind.node_coords().into_iter().enumerate() {
            kind.shape_grad(xi, dn);
            let det = jacobian(x_ref, dn).determinant();
            if det.is_nan() || det <= 0.0 {
                return Err(InvertedElement { det, point: np + a });
            }
        }
        Ok(geom)
    }

    /// The element type.
    pub fn kind(&self) -> ElementType {
        self.kind
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.num_nodes
    }

    /// Number of quadrature points.
    pub fn num_points(&self) -> usize {
        self.wdet.len()
    }

    /// Reference volume `sum_q w det J0`.
    pub fn volume(&self) -> f64 {
        self.wdet.iter().sum()
    }

    /// `dN_a/dX` of every node at point `q`.
    pub fn shape_grads(&self, q: usize) -> &[[f64; 3]] {
        &self.dndx[q * self.num_nodes..(q + 1) * self.num_nodes]
    }

    /// `N_a` of every node at point `q`.
    pub fn shape_values(&self, q: usize) -> &[f64] {
        &self.n[q * self.num_nodes..(q + 1) * self.num_nodes]
    }

    /// `w det J0` at point `q`.
    pub fn weight(&self, q: usize) -> f64 {
        self.wdet[q]
    }

    /// Reference position of point `q`.
    pub fn point(&self, q: usize) -> [f64; 3] {
        self.x[q]
    }
}

/// `F = I + sum_a u_a (dN_a/dX)^T`.
#[inline]
fn deformation_gradient(dn: &[[f64; 3]], u: &[[f64; 3]]) -> Matrix3<f64> {
    let mut f = Matrix3::identity();
    for (ua, da) in u.iter().zip(dn) {
        for i in 0..3 {
            for cap_j in 0..3 {
                f[(i, cap_j)] += ua[i] * da[cap_j];
            }
        }
    }
    f
}

/// Internal force f_int (length 3*nn, index 3*a+i, overwritten) and, if `k` is Some, the tangent
/// (3nn x 3nn, overwritten; resized if its shape is wrong) for nodal displacements u.
/// Err(det F) if det F <= 0 at a point (an inverted element: the caller reports it as a domain
/// error); `f` and `k` are then unspecified.
///
/// Allocation-free (when `k` already has the right shape).
///
/// # Panics
/// If `u.len() != num_nodes` or `f.len() != 3 num_nodes`.
pub fn internal_force(
    geom: &ElementGeometry,
    mat: &Material,
    u: &[[f64; 3]],
    f: &mut [f64],
    mut k: Option<&mut DMatrix<f64>>,
) -> Result<(), f64> {
    let nn = geom.num_nodes;
    let n = 3 * nn;
    assert_eq!(u.len(), nn, "internal_force: wrong number of displacements");
    assert_eq!(f.len(), n, "internal_force: wrong force length");
    f.fill(0.0);
    if let Some(k) = k.as_deref_mut() {
        if k.shape() != (n, n) {
            *k = DMatrix::zeros(n, n);
        } else {
            k.fill(0.0);
        }
    }
    let mut g = [[0.0f64; 3]; MAX_NODES];
    for q in 0..geom.num_points() {
        let dn = geom.shape_grads(q);
        let w = geom.wdet[q];
        let fm = deformation_gradient(dn, u);
        let (p, t) = mat.first_piola_iso(&fm)?;
        let pw = p * w;
        for (fa, d) in f.chunks_exact_mut(3).zip(dn) {
            for (i, fai) in fa.iter_mut().enumerate() {
                *fai += pw[(i, 0)] * d[0] + pw[(i, 1)] * d[1] + pw[(i, 2)] * d[2];
            }
        }
        let Some(k) = k.as_deref_mut() else {
            continue;
        };
        // Spatial gradients g_a = M^T dN_a.
        let m = &t.m;
        for (ga, d) in g.iter_mut().zip(dn) {
            for (i, gi) in ga.iter_mut().enumerate() {
                *gi = m[(0, i)] * d[0] + m[(1, i)] * d[1] + m[(2, i)] * d[2];
            }
        }
        let (ca, cb, cg) = (w * t.alpha, w * t.beta, w * t.gamma);
        // Upper blocks a <= b, column-major: column 3b+kk holds rows 3a+i contiguously.
        let ks = k.as_mut_slice();
        for b in 0..nn {
            let db = dn[b];
            let gb = g[b];
            for kk in 0..3 {
                let col = &mut ks[(3 * b + kk) * n..(3 * b + kk) * n + 3 * (b + 1)];
                let x2 = cg * gb[kk];
                for ((kab, ga), da) in col.chunks_exact_mut(3).zip(&g[..=b]).zip(&dn[..=b]) {
                    // K_ab(i, kk) += beta g_b,i g_a,kk + gamma g_a,i g_b,kk (+ alpha s_ab d_i,kk)
                    let s = ca * (da[0] * db[0] + da[1] * db[1] + da[2] * db[2]);
                    let ya = cb * ga[kk];
                    kab[0] += ya * gb[0] + x2 * ga[0];
                    kab[1] += ya * gb[1] + x2 * ga[1];
                    kab[2] += ya * gb[2] + x2 * ga[2];
                    kab[kk] += s;
                }
            }
        }
    }
    if let Some(k) = k {
        // Mirror the upper blocks: K_(bk)(ai) = K_(ai)(bk).
        for c in 0..n {
            let first = 3 * (c / 3) + 3;
            for r in first..n {
                k[(r, c)] = k[(c, r)];
            }
        }
    }
    Ok(())
}

/// Deformation gradient at each quadrature point and the reference position and weight, for output
/// (Cauchy stress, von Mises) and error norms: calls visit(X, F, w_detJ0).
///
/// # Panics
/// If `u.len() != num_nodes`.
pub fn for_each_point(
    geom: &ElementGeometry,
    u: &[[f64; 3]],
    mut visit: impl FnMut([f64; 3], &Matrix3<f64>, f64),
) {
    assert_eq!(
        u.len(),
        geom.num_nodes,
        "for_each_point: wrong number of displacements"
    );
    for q in 0..geom.num_points() {
        let fm = deformation_gradient(geom.shape_grads(q), u);
        visit(geom.x[q], &fm, geom.wdet[q]);
    }
}

/// Volume-averaged Cauchy stress of an element and the von Mises stress of that average, for
/// output. The average is over the current volume (`dv = J dV0`) for the Neo-Hookean law and over
/// the reference volume for small-strain linear elasticity. NaN if the element is inverted
/// (Neo-Hookean).
pub fn element_stress(
    geom: &ElementGeometry,
    mat: &Material,
    u: &[[f64; 3]],
) -> (Matrix3<f64>, f64) {
    let mut sum = Matrix3::zeros();
    let mut vol = 0.0;
    let finite = matches!(mat, Material::NeoHookean { .. });
    for_each_point(geom, u, |_, fm, w| {
        let dv = if finite { w * fm.determinant() } else { w };
        sum += mat.cauchy(fm) * dv;
        vol += dv;
    });
    let s = sum / vol;
    (s, von_mises(&s))
}
