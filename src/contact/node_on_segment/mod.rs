//! Node-on-segment contact (Hallquist, Goudreau and Benson 1985): the baseline the paper
//! compares mortar contact against (docs/theory.md section 8). Geometry and the node's forces
//! with their exact derivatives; the enforcement laws are those of mortar contact
//! (`contact::law`), so the two methods differ only in how gap and slip are measured.
//!
//! # Per secondary node A with its primary segment (face) S
//!
//! ```text
//! xi     = argmin |x_A - x_S(xi)|            closest point (Newton), on S or its extension
//! n      = outward unit normal of S at xi    (points out of the primary body)
//! nu     = -n                                (from the secondary body toward the primary one)
//! gh     = nu . (x_A - x_S(xi))              penetration, > 0 when A is inside the primary body
//! dsh    = P(nu) (x_A - x_S'(xi'))           slip of the step: S', xi' the segment and point of
//!                                            the last converged step, at current positions
//! p, t_T = the laws of contact::law          (penalty plus Uzawa, Coulomb return map)
//! t      = p nu + t_T
//! F_A   += a_A t,   F_i -= a_A N_i(xi) t     (residual: internal minus external forces)
//! ```
//!
//! `a_A` is the node's share of the secondary surface (the integral of its shape function over
//! the secondary faces, reference configuration), so `p` and `t` are tractions as in mortar
//! contact and the penalties `alpha E / h_A` mean the same. `dsh` vanishes under a rigid motion
//! of the pair: at the last converged step `x_A - x_S'(xi')` was normal to S' (the closest
//! point), and a rigid motion turns it with the normal.
//!
//! # Derivatives
//!
//! Forward-mode automatic differentiation (`num_dual`) over the node and the current segment's
//! nodes: the closest point is found in floats, then one Newton step in dual numbers,
//! `xi = xi* - H^-1 r(xi*, x)`, `r_a = (x_S(xi) - x_A) . x_S,a`, carries its exact derivative
//! (`H = dr/dxi`, itself from dual numbers in `xi`). Contact forces come only from points on a face
//! or its [`EXTENSION`], where this is exact; a point clamped onto the face boundary would be held
//! fixed (a defensive branch, not reached by `contact::frictional`). The slip is linear in the old
//! segment's nodes (`N_i(xi')` fixed); the law's derivatives come from `contact::law` and are
//! chained by hand.

mod pass;

pub use pass::{NTS_MARGIN, NTS_PATTERN_MARGIN};

use num_dual::DualSVec64;

use crate::contact::law::{
    normal_pressure_touching, tangential_law, FrictionResult, LawParams, NodeHistory,
};
use crate::fe::shape::{face_normal_at, face_point_at, face_tangents_at};
use crate::fe::FaceType;
use crate::vec3::dot;

/// Dual numbers over the node and at most 9 segment nodes (3 coordinates each).
const SLOTS: usize = 30;
type D = DualSVec64<SLOTS>;
type DXi = DualSVec64<2>;

/// Closest-point iterations; the projection stops earlier when the step is below
/// [`PROJECTION_TOL`].
const PROJECTION_ITERATIONS: usize = 30;
/// Parametric step below which the closest-point Newton stops.
const PROJECTION_TOL: f64 = 1e-14;
/// Segment extension: a projection within this parametric distance outside the face still
/// counts as on it (and keeps its unclamped point), so that a node on the common edge of
/// two faces, or on the boundary edge of the primary surface, does not drop in and out of
/// contact with round-off (the usual tolerance of node-on-segment codes; 1 % of a side).
pub const EXTENSION: f64 = 0.02;

/// A face at the current positions (node coordinates in the face's order).
#[derive(Clone, Copy, Debug)]
pub struct Segment<'a> {
    pub kind: FaceType,
    pub x: &'a [[f64; 3]],
}

/// The closest point of a point on a segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Parametric coordinates: the closest point when inside, else clamped into the face.
    pub xi: [f64; 2],
    /// The closest point lies on the face or within its [`EXTENSION`].
    pub inside: bool,
    /// Distance from the point to `x_S(xi)`.
    pub distance: f64,
}

/// Closest point of `p` on `seg`: Newton on `r(xi) = (x_S(xi) - p) . x_S,xi = 0` from the face
/// centre; a point beyond the face's [`EXTENSION`] is clamped into the face. `None` for a
/// degenerate face or a diverging iteration.
pub fn project(seg: &Segment, p: [f64; 3]) -> Option<Projection> {
    let quad = matches!(
        seg.kind,
        FaceType::Quad4 | FaceType::Quad8 | FaceType::Quad9
    );
    let mut xi = if quad { [0.0, 0.0] } else { [1.0 / 3.0; 2] };
    for _ in 0..PROJECTION_ITERATIONS {
        let (r, h) = residual_and_hessian(seg, p, xi);
        let step = solve2(h, r)?;
        xi = [xi[0] - step[0], xi[1] - step[1]];
        if !(xi[0].is_finite() && xi[1].is_finite()) || xi[0].abs() > 1e3 || xi[1].abs() > 1e3 {
            return None;
        }
        if step[0].abs().max(step[1].abs()) < PROJECTION_TOL {
            break;
        }
    }
    let clamped = clamp(quad, xi);
    let inside = (clamped[0] - xi[0]).abs().max((clamped[1] - xi[1]).abs()) <= EXTENSION;
    let xi = if inside { xi } else { clamped };
    let q: [f64; 3] = face_point_at(seg.kind, seg.x, xi);
    let distance = (0..3).map(|d| (p[d] - q[d]).powi(2)).sum::<f64>().sqrt();
    Some(Projection {
        xi,
        inside,
        distance,
    })
}

/// The closest segment of `p` among `candidates` (index, segment): the nearest of the inside
/// projections, or, if none is inside, the nearest clamped one. Ties go to the first.
pub fn closest<'a>(
    candidates: impl IntoIterator<Item = (usize, Segment<'a>)>,
    p: [f64; 3],
) -> Option<(usize, Projection)> {
    let mut best: Option<(usize, Projection)> = None;
    for (i, seg) in candidates {
        let Some(pr) = project(&seg, p) else { continue };
        let better = match &best {
            None => true,
            Some((_, b)) => {
                (pr.inside && !b.inside) || (pr.inside == b.inside && pr.distance < b.distance)
            }
        };
        if better {
            best = Some((i, pr));
        }
    }
    best
}

/// `r_a = (x_S(xi) - p) . x_S,a` and `H = dr/dxi` at `xi`.
fn residual_and_hessian(seg: &Segment, p: [f64; 3], xi: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let x: Vec<[DXi; 3]> = seg.x.iter().map(|v| v.map(DXi::from_re)).collect();
    let xd = [
        DXi::from_re(xi[0]).derivative(0),
        DXi::from_re(xi[1]).derivative(1),
    ];
    let q = face_point_at(seg.kind, &x, xd);
    let (t1, t2) = face_tangents_at(seg.kind, &x, xd);
    let diff: [DXi; 3] = std::array::from_fn(|d| q[d] - p[d]);
    let r = [dot(diff, t1), dot(diff, t2)];
    let grad = |v: &DXi| -> [f64; 2] { v.eps.0.as_ref().map_or([0.0; 2], |m| m.data.0[0]) };
    ([r[0].re, r[1].re], [grad(&r[0]), grad(&r[1])])
}

/// `H^-1 r` for a 2x2 `H`, `None` when singular.
fn solve2(h: [[f64; 2]; 2], r: [f64; 2]) -> Option<[f64; 2]> {
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    let scale = h[0][0].abs().max(h[1][1].abs()).max(f64::MIN_POSITIVE);
    if det.abs() <= 1e-14 * scale * scale || !det.is_finite() {
        return None;
    }
    Some([
        (h[1][1] * r[0] - h[0][1] * r[1]) / det,
        (h[0][0] * r[1] - h[1][0] * r[0]) / det,
    ])
}

/// `xi` clamped into the reference quadrilateral `[-1, 1]^2` or triangle.
fn clamp(quad: bool, xi: [f64; 2]) -> [f64; 2] {
    if quad {
        return xi.map(|v| v.clamp(-1.0, 1.0));
    }
    let (mut a, mut b) = (xi[0].max(0.0), xi[1].max(0.0));
    let s = a + b;
    if s > 1.0 {
        a /= s;
        b /= s;
    }
    [a, b]
}

/// What one node contributes: fields, and forces and tangent on its local dofs, ordered
/// `[x_A, segment nodes, old segment nodes]` (3 per node).
#[derive(Clone, Debug)]
pub struct NodeContribution {
    pub nu: [f64; 3],
    pub gh: f64,
    pub pressure: f64,
    pub dp_dgh: f64,
    pub slip: [f64; 3],
    pub friction: FrictionResult,
    /// `a_A t`, the force on the secondary node's residual.
    pub force: Vec<f64>,
    /// Row-major `L x L` tangent (empty when not asked for), `L = force.len()`.
    pub tangent: Vec<f64>,
}

/// The node's segment now and (friction) the old segment with the old closest point.
#[derive(Clone, Copy, Debug)]
pub struct NodeGeometry<'a> {
    pub x_node: [f64; 3],
    pub segment: Segment<'a>,
    pub projection: Projection,
    pub old: Option<(Segment<'a>, [f64; 2])>,
}

/// The laws' inputs that do not depend on the geometry.
#[derive(Clone, Copy, Debug)]
pub struct NodeLaw<'a> {
    pub history: &'a NodeHistory,
    pub params: LawParams,
    /// Gaps within `touch` of closing count as touching (closed tangent, zero pressure).
    pub touch: f64,
    /// `a_A`.
    pub area: f64,
    /// Every pressed node sticks (the stick predictor).
    pub stick_all: bool,
}

/// Forces (and, with `tangent`, their derivatives) of one secondary node on its segment.
/// `None` when the segment is degenerate at the projection.
pub fn node_contribution(
    geo: &NodeGeometry,
    law: &NodeLaw,
    tangent: bool,
) -> Option<NodeContribution> {
    let np = geo.segment.kind.num_nodes();
    let npo = geo.old.map_or(0, |(s, _)| s.kind.num_nodes());
    let l = 3 * (1 + np + npo);

    // Current segment in dual numbers over [x_A, segment nodes].
    let xa: [D; 3] = std::array::from_fn(|d| D::from_re(geo.x_node[d]).derivative(d));
    let xs: Vec<[D; 3]> = geo
        .segment
        .x
        .iter()
        .enumerate()
        .map(|(i, v)| std::array::from_fn(|d| D::from_re(v[d]).derivative(3 + 3 * i + d)))
        .collect();
    let xi = dual_closest_point(geo, &xa, &xs);
    let q = face_point_at(geo.segment.kind, &xs, xi);
    let (n, jac) = face_normal_at(geo.segment.kind, &xs, xi);
    if jac.re <= 0.0 {
        return None;
    }
    let nu: [D; 3] = n.map(|v| -v);
    let diff: [D; 3] = std::array::from_fn(|d| xa[d] - q[d]);
    let gh = dot(nu, diff);
    let mut shape = vec![D::from_re(0.0); np];
    geo.segment.kind.shape_at(xi, &mut shape);

    // Slip against the old closest point, at current positions.
    let (slip, d_slip) = slip_and_derivative(geo, &nu, l);

    let nu_re = nu.map(|v| v.re);
    let (p, dp_dgh) =
        normal_pressure_touching(law.history.lambda_n, law.params.eps_n, gh.re, law.touch);
    let band = (law.touch, law.stick_all);
    let friction = tangential_law(law.history, &law.params, nu_re, (p, dp_dgh), slip, band);
    let t: [f64; 3] = std::array::from_fn(|c| p * nu_re[c] + friction.traction[c]);
    let n_re: Vec<f64> = shape.iter().map(|v| v.re).collect();
    let mut force = vec![0.0; l];
    for c in 0..3 {
        force[c] = law.area * t[c];
        for (i, ni) in n_re.iter().enumerate() {
            force[3 + 3 * i + c] = -law.area * ni * t[c];
        }
    }
    let mut out = NodeContribution {
        nu: nu_re,
        gh: gh.re,
        pressure: p,
        dp_dgh,
        slip,
        friction,
        force,
        tangent: Vec::new(),
    };
    if tangent && dp_dgh > 0.0 {
        out.tangent = node_tangent(&out, law, &nu, &gh, &shape, &d_slip, l);
    }
    Some(out)
}

/// The closest point as a dual number: one Newton step from the converged float point (exact
/// derivative), or the clamped point held fixed when the node is beyond the segment.
fn dual_closest_point(geo: &NodeGeometry, xa: &[D; 3], xs: &[[D; 3]]) -> [D; 2] {
    let xi0 = geo.projection.xi;
    let fixed = [D::from_re(xi0[0]), D::from_re(xi0[1])];
    if !geo.projection.inside {
        return fixed;
    }
    let (_, h) = residual_and_hessian(&geo.segment, geo.x_node, xi0);
    let q = face_point_at(geo.segment.kind, xs, fixed);
    let (t1, t2) = face_tangents_at(geo.segment.kind, xs, fixed);
    let diff: [D; 3] = std::array::from_fn(|d| q[d] - xa[d]);
    let r = [dot(diff, t1), dot(diff, t2)];
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    if det == 0.0 || !det.is_finite() {
        return fixed;
    }
    let s0 = (r[0] * h[1][1] - r[1] * h[0][1]) / det;
    let s1 = (r[1] * h[0][0] - r[0] * h[1][0]) / det;
    [fixed[0] - s0, fixed[1] - s1]
}

/// `dsh = P(nu) (x_A - x_S'(xi'))` and its derivative rows (3 x L) over the local dofs; zero
/// without an old segment.
fn slip_and_derivative(geo: &NodeGeometry, nu: &[D; 3], l: usize) -> ([f64; 3], Vec<Vec<f64>>) {
    let mut d = vec![vec![0.0; l]; 3];
    let Some((old, xi_old)) = geo.old else {
        return ([0.0; 3], d);
    };
    let np = geo.segment.kind.num_nodes();
    let npo = old.kind.num_nodes();
    let mut n_old = vec![0.0; npo];
    old.kind.shape_at(xi_old, &mut n_old);
    let mut v = geo.x_node;
    for (ni, xi) in n_old.iter().zip(old.x) {
        for c in 0..3 {
            v[c] -= ni * xi[c];
        }
    }
    let nr = nu.map(|x| x.re);
    let nv = nr[0] * v[0] + nr[1] * v[1] + nr[2] * v[2];
    let slip: [f64; 3] = std::array::from_fn(|c| v[c] - nr[c] * nv);
    // d(P v) = P dv - (d nu (nu . v) + nu (d nu . v)).
    let proj = |c: usize, k: usize| if c == k { 1.0 } else { 0.0 } - nr[c] * nr[k];
    let first_old = 3 * (1 + np);
    for (c, row) in d.iter_mut().enumerate() {
        for k in 0..3 {
            row[k] += proj(c, k);
            for (i, ni) in n_old.iter().enumerate() {
                row[first_old + 3 * i + k] -= ni * proj(c, k);
            }
        }
        let dnu_c = grad(&nu[c]);
        for (j, r) in row.iter_mut().enumerate().take(3 * (1 + np)) {
            let dnu_dot_v: f64 = (0..3).map(|k| grad(&nu[k])[j] * v[k]).sum();
            *r -= dnu_c[j] * nv + nr[c] * dnu_dot_v;
        }
    }
    (slip, d)
}

/// The derivative of a dual number over the [`SLOTS`] seeds.
fn grad(v: &D) -> [f64; SLOTS] {
    v.eps.0.as_ref().map_or([0.0; SLOTS], |m| m.data.0[0])
}

/// `d F / d x` (row-major `L x L`), chaining the law's derivatives:
/// `dt = nu dp + p dnu + dt_T`, `dt_T = dt/ddsh ddsh + dt/dp dp + dt/dnu dnu`,
/// `dF_A = a dt`, `dF_i = -a (t dN_i + N_i dt)`.
fn node_tangent(
    c: &NodeContribution,
    law: &NodeLaw,
    nu: &[D; 3],
    gh: &D,
    shape: &[D],
    d_slip: &[Vec<f64>],
    l: usize,
) -> Vec<f64> {
    let cur = SLOTS.min(l);
    let pad = |g: [f64; SLOTS]| -> Vec<f64> {
        let mut v = vec![0.0; l];
        v[..cur].copy_from_slice(&g[..cur]);
        v
    };
    let d_nu: Vec<Vec<f64>> = nu.iter().map(|v| pad(grad(v))).collect();
    let d_p: Vec<f64> = pad(grad(gh)).iter().map(|g| c.dp_dgh * g).collect();
    let fr = &c.friction;
    // Inside the touching band (p = 0 or a round-off p) the law gave the stick tangent
    // (`touching_friction`); elsewhere a frictionless or open result has zero derivatives.
    let friction = law.params.mu > 0.0;
    let t: [f64; 3] = std::array::from_fn(|k| c.pressure * c.nu[k] + fr.traction[k]);
    let mut dt = vec![vec![0.0; l]; 3];
    for (k, row) in dt.iter_mut().enumerate() {
        for j in 0..l {
            let mut v = c.nu[k] * d_p[j] + c.pressure * d_nu[k][j];
            if friction {
                for m in 0..3 {
                    v += fr.d_dsh[k][m] * d_slip[m][j] + fr.d_nu[k][m] * d_nu[m][j];
                }
                v += fr.d_p[k] * d_p[j];
            }
            row[j] = v;
        }
    }
    let a = law.area;
    let mut out = vec![0.0; l * l];
    for k in 0..3 {
        for j in 0..l {
            out[k * l + j] = a * dt[k][j];
        }
    }
    for (i, ni) in shape.iter().enumerate() {
        let dn = pad(grad(ni));
        for k in 0..3 {
            let row = 3 + 3 * i + k;
            for j in 0..l {
                out[row * l + j] = -a * (t[k] * dn[j] + ni.re * dt[k][j]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::law::Status;

    fn quad(z: f64) -> Vec<[f64; 3]> {
        vec![
            [0.0, 0.0, z],
            [1.0, 0.0, z + 0.1],
            [1.1, 1.0, z],
            [0.0, 0.9, z - 0.05],
        ]
    }

    #[test]
    fn projection_of_a_point_on_a_flat_quad_is_exact() {
        let x = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
        ];
        let seg = Segment {
            kind: FaceType::Quad4,
            x: &x,
        };
        let pr = project(&seg, [1.5, 0.5, 0.3]).unwrap();
        assert!(pr.inside);
        assert!((pr.xi[0] - 0.5).abs() < 1e-13 && (pr.xi[1] + 0.5).abs() < 1e-13);
        assert!((pr.distance - 0.3).abs() < 1e-13);
        let out = project(&seg, [3.0, 1.0, 0.0]).unwrap();
        assert!(!out.inside);
        assert_eq!(out.xi, [1.0, 0.0]);
    }

    #[test]
    fn projection_on_a_warped_quad_is_a_stationary_point() {
        let x = quad(0.0);
        let seg = Segment {
            kind: FaceType::Quad4,
            x: &x,
        };
        let p = [0.6, 0.4, 0.2];
        let pr = project(&seg, p).unwrap();
        assert!(pr.inside);
        let (r, _) = residual_and_hessian(&seg, p, pr.xi);
        assert!(r[0].abs() < 1e-14 && r[1].abs() < 1e-14, "{r:?}");
    }

    /// A node inside the touching band, on either side of the surface: no tangential force,
    /// and the stick stiffness `area eps_t` in its tangential rows (the round-off sign of the
    /// gap must not decide the tangent).
    #[test]
    fn touching_band_gives_the_stick_tangent_on_both_sides() {
        let flat = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let history = NodeHistory::default();
        let law = NodeLaw {
            history: &history,
            params: LawParams {
                eps_n: 1000.0,
                eps_t: 300.0,
                mu: 0.3,
            },
            touch: 1e-3,
            area: 0.25,
            stick_all: false,
        };
        for z in [0.5e-3, -0.5e-3] {
            let node = [0.4, 0.6, z];
            let segment = Segment {
                kind: FaceType::Quad4,
                x: &flat,
            };
            let projection = project(&segment, node).unwrap();
            // Slip is measured from the old closest point: the node's own (no slip yet).
            let old = Segment {
                kind: FaceType::Quad4,
                x: &flat,
            };
            let geo = NodeGeometry {
                x_node: node,
                segment,
                projection,
                old: Some((old, projection.xi)),
            };
            let c = node_contribution(&geo, &law, true).unwrap();
            assert!(c.dp_dgh > 0.0, "z = {z}: not in the band");
            assert!(
                c.pressure <= law.params.eps_n * law.touch,
                "z = {z}: {}",
                c.pressure
            );
            assert_eq!(c.friction.traction, [0.0; 3], "z = {z}");
            let l = c.force.len();
            for k in 0..2 {
                let stiffness = c.tangent[k * l + k];
                assert!(
                    (stiffness - law.area * law.params.eps_t).abs() < 1e-9,
                    "z = {z}, axis {k}: {stiffness}"
                );
            }
        }
    }

    /// The tangent against central differences of the forces, in stick and in slip, on a
    /// warped primary segment (old segment = a different face).
    #[test]
    fn tangent_matches_central_differences() {
        for (mu, old_t, what) in [
            (0.0, [0.0; 3], "frictionless"),
            (0.3, [0.0, 0.0, 0.0], "stick"),
            (0.3, [40.0, -10.0, 0.0], "slip"),
        ] {
            check_tangent(mu, old_t, what);
        }
    }

    fn check_tangent(mu: f64, old_t: [f64; 3], what: &str) {
        let seg_x = quad(0.0);
        let old_x = quad(0.02);
        let node = [0.55, 0.45, 0.01];
        let history = NodeHistory {
            lambda_n: 0.5,
            lambda_t: [0.0; 3],
            normal_old: [0.0, 0.0, -1.0],
            traction_t_old: old_t,
        };
        let law = NodeLaw {
            history: &history,
            params: LawParams {
                eps_n: 1000.0,
                eps_t: 300.0,
                mu,
            },
            touch: 0.0,
            area: 0.25,
            stick_all: false,
        };
        // Inputs: node, current segment, old segment.
        // Stick: the old point is the node's own closest point on the old segment.
        let xi_old = if what == "stick" {
            let seg = Segment {
                kind: FaceType::Quad4,
                x: &old_x,
            };
            project(&seg, node).unwrap().xi
        } else {
            [0.1, -0.2]
        };
        let mut v: Vec<f64> = node.to_vec();
        v.extend(seg_x.iter().flatten());
        v.extend(old_x.iter().flatten());
        let eval = |v: &[f64], tangent: bool| -> NodeContribution {
            let node = [v[0], v[1], v[2]];
            let sx: Vec<[f64; 3]> = (0..4)
                .map(|i| [v[3 + 3 * i], v[4 + 3 * i], v[5 + 3 * i]])
                .collect();
            let ox: Vec<[f64; 3]> = (0..4)
                .map(|i| [v[15 + 3 * i], v[16 + 3 * i], v[17 + 3 * i]])
                .collect();
            let segment = Segment {
                kind: FaceType::Quad4,
                x: &sx,
            };
            let projection = project(&segment, node).unwrap();
            assert!(projection.inside);
            let geo = NodeGeometry {
                x_node: node,
                segment,
                projection,
                old: Some((
                    Segment {
                        kind: FaceType::Quad4,
                        x: &ox,
                    },
                    xi_old,
                )),
            };
            node_contribution(&geo, &law, tangent).unwrap()
        };
        let c = eval(&v, true);
        assert!(c.pressure > 0.0, "{what}: not pressed");
        let want = match what {
            "stick" => Status::Stick,
            "slip" => Status::Slip,
            _ => Status::Slip,
        };
        assert_eq!(c.friction.status, want, "{what}");
        let l = v.len();
        let h = 1e-6;
        let mut worst = 0.0f64;
        let scale = c.tangent.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for j in 0..l {
            let (mut vp, mut vm) = (v.clone(), v.clone());
            vp[j] += h;
            vm[j] -= h;
            let (fp, fm) = (eval(&vp, false).force, eval(&vm, false).force);
            for i in 0..l {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                worst = worst.max((fd - c.tangent[i * l + j]).abs());
            }
        }
        assert!(worst < 1e-6 * scale, "{what}: {worst:e} against {scale:e}");
    }
}
