//! Verification figures against exact solutions (ALGORITHM.md section 9).
//!
//! # Lamé's thick sphere
//!
//! Inner radius a, outer radius b, inner pressure p, linear elasticity (E, nu). With
//! `C = p a^3 / (E (b^3 - a^3))`:
//!
//! - `u_r = C [ (1 - 2 nu) r + (1 + nu) b^3 / (2 r^2) ]`,
//! - `eps_rr = du_r/dr = C [ (1 - 2 nu) - (1 + nu) b^3 / r^3 ]`, `eps_tt = u_r / r`,
//! - `sigma_rr = -p a^3 (b^3 - r^3) / (r^3 (b^3 - a^3))`,
//!   `sigma_tt = p a^3 (b^3 + 2 r^3) / (2 r^3 (b^3 - a^3))`.
//!
//! In Cartesian components, with `n = X / r`: `eps = eps_rr n n + eps_tt (I - n n)` (likewise
//! sigma). The relative energy-norm error is
//! `sqrt( int (sigma_h - sigma) : (eps_h - eps) dV / int sigma : eps dV )`, integrated with each
//! element's stiffness rule over the reference (small-strain) volume.
//!
//! # Uniform strain (patch test)
//!
//! u = G X: the largest nodal displacement error relative to the largest |G X|, and the largest
//! stress error at any quadrature point relative to |sigma(I + G)| (Frobenius norms).
//!
//! # Contact patch test
//!
//! A uniform Cauchy stress `sigma` everywhere: `max_rel_stress_error` is the largest
//! `|sigma_h - sigma|` at any quadrature point relative to `|sigma|` (Frobenius). The contact
//! figures (every nodal pressure equal to p0, the contact forces summing to zero) come from the
//! contact interfaces (`solver::results`).

use nalgebra::{Matrix3, Vector3};

use crate::case::{Scene, Verification};
use crate::solid::{for_each_point, ElementGeometry};
use crate::solver::bulk::gather_nodes;

/// Partial sums of one rank; reduced over ranks by the caller (sums added, maxima maxed).
#[derive(Clone, Debug, Default)]
pub struct LocalFigures {
    /// Summed figures (name, value).
    pub sums: Vec<(&'static str, f64)>,
    /// Maximum figures (name, value).
    pub maxima: Vec<(&'static str, f64)>,
}

/// Exact Lamé strain and stress at reference point `x`.
pub fn lame_fields(
    x: [f64; 3],
    a: f64,
    b: f64,
    p: f64,
    young: f64,
    nu: f64,
) -> (Matrix3<f64>, Matrix3<f64>) {
    let xv = Vector3::from(x);
    let r = xv.norm();
    let n = xv / r;
    let nn = n * n.transpose();
    let ip = Matrix3::identity() - nn;
    let (a3, b3, r3) = (a.powi(3), b.powi(3), r.powi(3));
    let c = p * a3 / (young * (b3 - a3));
    let eps_rr = c * ((1.0 - 2.0 * nu) - (1.0 + nu) * b3 / r3);
    let eps_tt = c * ((1.0 - 2.0 * nu) + (1.0 + nu) * b3 / (2.0 * r3));
    let s_rr = -p * a3 * (b3 - r3) / (r3 * (b3 - a3));
    let s_tt = p * a3 * (b3 + 2.0 * r3) / (2.0 * r3 * (b3 - a3));
    (nn * eps_rr + ip * eps_tt, nn * s_rr + ip * s_tt)
}

/// This rank's contribution to the scene's verification figures.
pub fn local_figures(
    scene: &Scene,
    elements: &[(usize, ElementGeometry)],
    local_nodes: &[usize],
    u: &[f64],
) -> LocalFigures {
    let mut out = LocalFigures::default();
    let Some(v) = &scene.verification else {
        return out;
    };
    let mut ue = Vec::new();
    match *v {
        Verification::LameSphere {
            inner_radius: a,
            outer_radius: b,
            pressure: p,
        } => {
            let (mut err2, mut norm2) = (0.0, 0.0);
            for (e, geom) in elements {
                let mat = &scene.materials[scene.mesh.body[*e]];
                let (young, nu) = (mat.young(), mat.poisson());
                gather_nodes(u, scene.mesh.element_nodes(*e), &mut ue);
                for_each_point(geom, &ue, |x, f, w| {
                    let eps_h = (f + f.transpose()) * 0.5 - Matrix3::identity();
                    let sig_h = mat.cauchy(f);
                    let (eps, sig) = lame_fields(x, a, b, p, young, nu);
                    err2 += w * (sig_h - sig).component_mul(&(eps_h - eps)).sum();
                    norm2 += w * sig.component_mul(&eps).sum();
                });
            }
            out.sums.push(("energy_error_sq", err2));
            out.sums.push(("energy_norm_sq", norm2));
        }
        Verification::UniformStrain { gradient } => {
            let g = Matrix3::from_row_slice(&gradient.concat());
            let (mut du, mut umax, mut ds) = (0.0f64, 0.0f64, 0.0f64);
            for &n in local_nodes {
                let x = Vector3::from(scene.mesh.coords[n]);
                let exact = g * x;
                let got = Vector3::new(u[3 * n], u[3 * n + 1], u[3 * n + 2]);
                du = du.max((got - exact).norm());
                umax = umax.max(exact.norm());
            }
            let mut smax = 0.0f64;
            for (e, geom) in elements {
                let mat = &scene.materials[scene.mesh.body[*e]];
                let exact = mat.cauchy(&(Matrix3::identity() + g));
                smax = smax.max(exact.norm());
                gather_nodes(u, scene.mesh.element_nodes(*e), &mut ue);
                for_each_point(geom, &ue, |_, f, _| {
                    ds = ds.max((mat.cauchy(f) - exact).norm());
                });
            }
            out.maxima.push(("displacement_error_abs", du));
            out.maxima.push(("displacement_scale", umax));
            out.maxima.push(("stress_error_abs", ds));
            out.maxima.push(("stress_scale", smax));
        }
        Verification::ContactPatch { stress, .. } => {
            let exact = Matrix3::from_row_slice(&stress.concat());
            let mut ds = 0.0f64;
            for (e, geom) in elements {
                let mat = &scene.materials[scene.mesh.body[*e]];
                gather_nodes(u, scene.mesh.element_nodes(*e), &mut ue);
                for_each_point(geom, &ue, |_, f, _| {
                    ds = ds.max((mat.cauchy(f) - exact).norm() / exact.norm());
                });
            }
            out.maxima.push(("rel_stress_error", ds));
        }
    }
    out
}

/// Turns reduced partial figures into the scene's metrics.
pub fn metrics(
    sums: &std::collections::BTreeMap<&'static str, f64>,
    maxima: &std::collections::BTreeMap<&'static str, f64>,
) -> Vec<(String, f64)> {
    let mut m = Vec::new();
    if let (Some(e), Some(n)) = (sums.get("energy_error_sq"), sums.get("energy_norm_sq")) {
        m.push(("energy_error".to_string(), (e.max(0.0) / n).sqrt()));
    }
    if let (Some(d), Some(s)) = (
        maxima.get("displacement_error_abs"),
        maxima.get("displacement_scale"),
    ) {
        m.push((
            "max_displacement_error".to_string(),
            d / s.max(f64::MIN_POSITIVE),
        ));
    }
    if let (Some(d), Some(s)) = (maxima.get("stress_error_abs"), maxima.get("stress_scale")) {
        m.push(("max_stress_error".to_string(), d / s.max(f64::MIN_POSITIVE)));
    }
    if let Some(d) = maxima.get("rel_stress_error") {
        m.push(("max_rel_stress_error".to_string(), *d));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact fields satisfy the boundary conditions sigma_rr(a) = -p, sigma_rr(b) = 0 and
    /// Hooke's law sigma = lambda tr(eps) I + 2 mu eps.
    #[test]
    fn lame_fields_meet_boundary_conditions_and_hooke() {
        let (a, b, p, e, nu) = (1.0, 2.0, 3.0, 100.0, 0.3);
        let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        for r in [a, 1.3, 1.7, b] {
            let x = [r / 3f64.sqrt(); 3];
            let (eps, sig) = lame_fields(x, a, b, p, e, nu);
            let hooke = Matrix3::identity() * (lam * eps.trace()) + eps * (2.0 * mu);
            assert!((hooke - sig).norm() < 1e-12 * sig.norm());
            let n = Vector3::from(x).normalize();
            let srr = (n.transpose() * sig * n)[0];
            if r == a {
                assert!((srr + p).abs() < 1e-12);
            }
            if r == b {
                assert!(srr.abs() < 1e-12);
            }
        }
    }
}
