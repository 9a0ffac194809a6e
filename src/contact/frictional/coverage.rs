//! How much of a traction node's support the primary surface covers, and what follows from it
//! (module docs, "Coverage", "Coverage scale" and "Nodes sliding off").
//!
//! The full integral `a_full_A = int Phi_A dA` over the secondary faces carrying A, in the
//! current configuration, with its gradient; the coverage `c_A = a_A / a_full_A`; the scale
//! `s_A` of a partly covered node's penalties and the fade `r(c_A)` of a node sliding off.

use std::rc::Rc;

use crate::case::Scene;
use crate::contact::mortar::{sub_segments, traction_shape_on, TractionScheme};
use crate::fe::shape::{normal_from_tangents, tangents_from_grad};
use crate::fe::FaceType;
use crate::vec3::cross;

use super::evaluate::EvalContext;
use super::pass::{ContactPass, FaceData};

/// A node carries traction only if its overlap integral `a_A` is at least this fraction of its
/// full integral `a_full_A` (its coverage). It also bounds the coverage scaling of the
/// penalties ([`coverage_scale`]) at `1 / MIN_COVERAGE`.
pub const MIN_COVERAGE: f64 = 1e-3;

/// Between [`MIN_COVERAGE`] and this coverage a node's traction fades out
/// ([`coverage_fade`]); such a node takes no Uzawa update and is not held to the tolerances.
pub const FADE_COVERAGE: f64 = 0.05;

/// The factor `r` on the traction of a node of coverage `c`, with `dr/dc`: 0 below
/// [`MIN_COVERAGE`], 1 from [`FADE_COVERAGE`] on, and the smooth step `u^2 (3 - 2 u)`,
/// `u = (c - MIN_COVERAGE) / (FADE_COVERAGE - MIN_COVERAGE)`, between (continuous with its
/// first derivative, so that a node's force vanishes smoothly as it slides off).
pub fn coverage_fade(coverage: f64) -> (f64, f64) {
    let width = FADE_COVERAGE - MIN_COVERAGE;
    let u = ((coverage - MIN_COVERAGE) / width).clamp(0.0, 1.0);
    (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u) / width)
}

/// A node whose overlap integral is within this fraction of its full integral counts as
/// covered: the pallets' quadrature and the full integral's differ in the last digits (and
/// more on curved faces), and without the margin covered nodes would hover about the kink of
/// the scale at coverage 1 (docs/performance.md, "Uzawa augmentations").
pub const COVERED_TOL: f64 = 1e-6;

/// The factor `s_A = (1 - COVERED_TOL) a_full_A / a_A` (continuous at the margin) by which the
/// penalties of a partly covered node are multiplied (`a_full_A` over the current faces
/// carrying A), `None` for a covered node (`a_A >= (1 - COVERED_TOL) a_full_A`: factor 1).
/// With it, the penalty *force* of a node per unit normalized gap, `a_A s_A eps`, is that of a
/// fully covered node whatever its coverage (module docs, "Coverage scale"). Called for nodes
/// with `a_A >= MIN_COVERAGE a_full_A`, so `s_A <= 1 / MIN_COVERAGE`.
pub fn coverage_scale(area: f64, a_full: f64) -> Option<f64> {
    let covered = (1.0 - COVERED_TOL) * a_full;
    (area > 0.0 && area < covered).then(|| covered / area)
}

impl ContactPass {
    /// The full integral of traction node `a`'s function over the secondary faces carrying
    /// it at positions `x` ([`traction_integrals`]), with its gradient if asked.
    pub(crate) fn full_integral(
        &self,
        ctx: &EvalContext,
        a: usize,
        gradient: bool,
    ) -> FullIntegral {
        let mut full = FullIntegral {
            value: 0.0,
            gradient: Vec::new(),
        };
        for &(f, k) in &self.node_faces[a] {
            let face = &self.sec_faces[f];
            let n = face.nodes.len();
            let cached = ctx.face_integrals.borrow().get(&f).cloned();
            let integrals = match cached {
                Some(i) if !gradient || !i.gradient.is_empty() => i,
                _ => {
                    let xf: Vec<[f64; 3]> = face.nodes.iter().map(|&m| ctx.x[m]).collect();
                    let scheme = self.method.carrier_scheme(ctx.scheme);
                    let i = Rc::new(traction_integrals(
                        face.kind,
                        scheme,
                        &xf,
                        gradient,
                        |_, _| {},
                    ));
                    ctx.face_integrals.borrow_mut().insert(f, Rc::clone(&i));
                    i
                }
            };
            full.value += integrals.value[k];
            if gradient {
                let per_node = &integrals.gradient[k * n..(k + 1) * n];
                full.gradient
                    .extend(face.nodes.iter().copied().zip(per_node.iter().copied()));
            }
        }
        full
    }
}

/// `a_full` of every traction node (the integral of its traction function over every
/// secondary face, reference configuration) and `h_A` (the mean square root of the areas of
/// the faces around it).
pub(crate) fn full_integrals(
    scene: &Scene,
    scheme: TractionScheme,
    faces: &[FaceData],
    carriers: &[Vec<usize>],
    count: usize,
) -> (Vec<f64>, Vec<f64>) {
    let mut a = vec![0.0; count];
    let (mut size_sum, mut size_count) = (vec![0.0; count], vec![0.0; count]);
    for (f, car) in faces.iter().zip(carriers) {
        let x: Vec<[f64; 3]> = f.nodes.iter().map(|&n| scene.mesh.coords[n]).collect();
        // Summed point by point into `a` (the node-on-segment baseline, whose path is
        // sensitive to round-off, normalizes its gaps by these values).
        let integrals = traction_integrals(f.kind, scheme, &x, false, |k, v| a[car[k]] += v);
        for &node in car {
            size_sum[node] += integrals.area.sqrt();
            size_count[node] += 1.0;
        }
    }
    let h = size_sum
        .iter()
        .zip(&size_count)
        .map(|(s, c)| s / c)
        .collect();
    (a, h)
}

/// The full integral of one traction node over the current faces carrying it.
pub(crate) struct FullIntegral {
    pub(crate) value: f64,
    /// `(node, d value / d x_node)`, one entry per node of each face (a node shared by faces
    /// appears once per face).
    pub(crate) gradient: Vec<(usize, [f64; 3])>,
}

/// The integrals of a face's traction functions over the whole face at node positions `x`.
pub(crate) struct TractionIntegrals {
    /// The face's area.
    pub(crate) area: f64,
    /// `int Phi_k dA` for the face's k-th traction node.
    pub(crate) value: Vec<f64>,
    /// With the gradient: `d value[k] / d x_b` at `k * x.len() + b` (empty without).
    pub(crate) gradient: Vec<[f64; 3]>,
}

/// [`TractionIntegrals`] of a face: per sub-segment, so that scheme 3's piecewise functions
/// are integrated exactly, with a degree-6 rule. With `gradient`, also the derivatives with
/// respect to the face's node coordinates: `J = |x_,xi x x_,eta|` varies as
/// `dJ = (x_,eta x n) . dx_,xi + (n x x_,xi) . dx_,eta`, `dx_,i = sum_b N_b,i dx_b`.
/// `add(k, v)` also receives every quadrature point's term `v` of `value[k]`.
pub(crate) fn traction_integrals(
    kind: FaceType,
    scheme: TractionScheme,
    x: &[[f64; 3]],
    gradient: bool,
    mut add: impl FnMut(usize, f64),
) -> TractionIntegrals {
    let mut out = TractionIntegrals {
        area: 0.0,
        value: Vec::new(),
        gradient: Vec::new(),
    };
    let mut phi = Vec::new();
    let mut dn = vec![[0.0; 2]; x.len()];
    for seg in sub_segments(kind) {
        let rule = seg.linear_kind().quadrature(6);
        let jac = seg.parent_jacobian();
        for (q, w) in rule.points.iter().zip(&rule.weights) {
            let xi = seg.to_parent(*q);
            kind.shape_grad(xi, &mut dn);
            let (t1, t2) = tangents_from_grad(x, &dn);
            let (n, j_face) = normal_from_tangents(t1, t2);
            traction_shape_on(kind, scheme, &seg, xi, &mut phi);
            if out.value.is_empty() {
                out.value = vec![0.0; phi.len()];
                if gradient {
                    out.gradient = vec![[0.0; 3]; phi.len() * x.len()];
                }
            }
            out.area += w * jac * j_face;
            for (k, &phi_k) in phi.iter().enumerate() {
                let v = w * jac * j_face * phi_k;
                out.value[k] += v;
                add(k, v);
            }
            if gradient {
                let (a1, a2) = (cross(t2, n), cross(n, t1));
                for (b, g) in dn.iter().enumerate() {
                    let dj: [f64; 3] = std::array::from_fn(|c| g[0] * a1[c] + g[1] * a2[c]);
                    for (k, &phi_k) in phi.iter().enumerate() {
                        let slot = &mut out.gradient[k * x.len() + b];
                        for c in 0..3 {
                            slot[c] += w * jac * phi_k * dj[c];
                        }
                    }
                }
            }
        }
    }
    out
}
