//! Verification figures against exact solutions (docs/theory.md section 9), and for every scene
//! `max_displacement`, the largest nodal displacement (a value to compare runs by where there
//! is no exact solution).
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
//! contact interfaces (`contact::frictional`, its metrics).
//!
//! # Hertz
//!
//! A sphere of radius R pressed on a flat (or two spheres, `1/R = 1/R1 + 1/R2`) by a total
//! force F along the z axis, both linear elastic, frictionless, small strain (Hertz 1882;
//! Johnson, *Contact Mechanics*, 1985, section 4.2; docs/theory.md section 9):
//!
//! ```text
//! 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2
//! a    = (3 F R / (4 E*))^(1/3)                  contact radius
//! p0   = 3 F / (2 pi a^2)                        peak pressure, at the centre
//! p(r) = p0 sqrt(1 - r^2 / a^2)                  for r <= a, 0 beyond
//! ```
//!
//! **Measured from the run**, at the last converged step, on the secondary side of the
//! verification's contact interface (one pass), with `r` the current distance from the z axis:
//!
//! - The force, from the nodal forces: `F = |sum_A a_A p_A nu_A,z| / f`, with `a_A` the overlap
//!   integral of node A's traction function, `nu_A` its unit normal and `f` the share of the
//!   whole contact the mesh models (`model_fraction`: 0.25 for a quarter model, whose symmetry
//!   planes take the horizontal components). Hertz's `a_H` and `p0_H` follow from it.
//! - The pressure field `p_h = sum_A p_A Phi_A` (the interface's traction functions) integrated
//!   over the current secondary faces ([`PressurePoint`]: a Gauss rule on every sub-segment of
//!   every face that carries a pressure): `M0 = int p_h dA`, `M2 = int p_h r^2 dA`.
//! - The contact radius from the second moment: for Hertz's field `M2 / M0 = (2/5) a^2`, so
//!   `a = sqrt(5 M2 / (2 M0))` ([`hertz_measure`]).
//! - The peak pressure from the mean pressure over the central disc `r < a/2` (a measured as
//!   above): Hertz's field has the mean `f(kappa) p0` over `r < kappa a`, with
//!   `f(kappa) = 2 (1 - (1 - kappa^2)^(3/2)) / (3 kappa^2)` (`f(1/2) = 0.9346`), so
//!   `p0 = mean(p_h over r < a/2) / f(1/2)` ([`hertz_disc_mean_factor`]).
//!
//! Why these. The nodal pressures of a mortar contact between non-matching meshes scatter
//! around the exact field at the scale of the elements (by up to +-25-30 % on the coarse meshes of
//! the Hertz scene, most near the edge of the contact, where the exact pressure has an infinite
//! slope and a node's pressure is a weighted mean over its support), and the outermost pressed
//! node lies anywhere within one element of the edge. So any one node, the outermost pressed one
//! included (even interpolated with the next), converges erratically, and a least-squares fit of
//! `p^2 = p0^2 (1 - r^2/a^2)` over the pressed nodes, whose slope rests on the edge nodes, gave
//! contact radii 5 to 55 % off on those meshes. Integrals average the scatter out: the moments
//! of `p_h` are weighted means over the whole contact, and the central disc holds several
//! elements where the field is flattest (at `r = a/2` it is still 0.87 p0). Integrating the
//! interpolated field rather than summing `a_A p_A r_A^2` matters: the nodal sum drops the
//! spread of each node's support (about `(5/12) (h/a)^2` of a, 3 to 5 % on a coarse mesh). Both
//! measures are exact for Hertz's field (to the quadrature; unit tests) and use Hertz's shape
//! only through a factor (5/2, `f(1/2)`): what the scene checks is that the run's field has
//! Hertz's extent and height for its own force. Both converge with the mesh as `p_h` does.
//!
//! Metrics: `contact_force` (F), `contact_radius` and `peak_pressure` (measured),
//! `hertz_contact_radius` and `hertz_peak_pressure` (Hertz for F), `rel_error_contact_radius`
//! = |a - a_H| / a_H, `rel_error_peak_pressure` = |p0 - p0_H| / p0_H, `rel_error_hertz` the
//! larger of the two, `max_pressure` (the largest nodal pressure), `hertz_contact_nodes` (the
//! pressed nodes). Every rank computes them from the same gathered nodal fields and positions,
//! so they depend on the partition only through the round-off of the solution.
//!
//! Hertz's assumptions (a << R, small strain, half-spaces) hold to about 1 % in the scene
//! (a/R = 0.15, bodies of size R; see `cases/hertz/README.md`).

use nalgebra::{Matrix3, Vector3};

use crate::case::{Scene, Verification};
use crate::solid::gather_nodes;
use crate::solid::{for_each_point, ElementGeometry};

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
    // Every scene: the largest nodal displacement (the size of a cantilever's tip's), a value to
    // compare runs by where there is no exact solution (a study's `finest_reference`).
    let largest = local_nodes
        .iter()
        .map(|&n| Vector3::new(u[3 * n], u[3 * n + 1], u[3 * n + 2]).norm())
        .fold(0.0, f64::max);
    out.maxima.push(("max_displacement", largest));
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
        // Measured on the contact interface (contact::frictional, its metrics).
        Verification::Hertz { .. } => {}
    }
    out
}

/// Hertz's contact radius and peak pressure `(a, p0)` for the total force `force`, the
/// (effective) radius `radius` and the contact modulus `e_star` (module docs, "Hertz").
pub fn hertz(force: f64, radius: f64, e_star: f64) -> (f64, f64) {
    let a = (3.0 * force * radius / (4.0 * e_star)).cbrt();
    let p0 = 3.0 * force / (2.0 * std::f64::consts::PI * a * a);
    (a, p0)
}

/// The share of Hertz's peak pressure that is the mean pressure over the central disc
/// `r < kappa a`: `f(kappa) = 2 (1 - (1 - kappa^2)^(3/2)) / (3 kappa^2)` (1 at the centre).
pub fn hertz_disc_mean_factor(kappa: f64) -> f64 {
    let k2 = kappa * kappa;
    2.0 * (1.0 - (1.0 - k2).powf(1.5)) / (3.0 * k2)
}

/// The central disc `r < HERTZ_CENTRAL_DISC a` whose mean pressure measures the peak.
pub const HERTZ_CENTRAL_DISC: f64 = 0.5;

/// One quadrature point of the interpolated contact pressure field `p_h` on the contact
/// surface: its squared distance from the axis, `p_h` there, and its weight (area).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PressurePoint {
    pub r2: f64,
    pub pressure: f64,
    pub weight: f64,
}

/// What [`hertz_measure`] found: the contact radius and the peak pressure of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HertzMeasure {
    /// `a = sqrt(5 M2 / (2 M0))`.
    pub contact_radius: f64,
    /// The mean of `p_h` over `r < a / 2` over `f(1/2)`.
    pub peak_pressure: f64,
}

/// The contact radius and peak pressure of a pressure field given at quadrature points (module
/// docs, "Hertz"); `None` without pressure, or without a point in the central disc.
pub fn hertz_measure(points: &[PressurePoint]) -> Option<HertzMeasure> {
    let (mut m0, mut m2) = (0.0, 0.0);
    for q in points {
        m0 += q.pressure * q.weight;
        m2 += q.pressure * q.r2 * q.weight;
    }
    if !(m0 > 0.0 && m2 > 0.0) {
        return None;
    }
    let a = (2.5 * m2 / m0).sqrt();
    let disc = (HERTZ_CENTRAL_DISC * a).powi(2);
    let (mut force, mut area) = (0.0, 0.0);
    for q in points.iter().filter(|q| q.r2 < disc) {
        force += q.pressure * q.weight;
        area += q.weight;
    }
    if area <= 0.0 {
        return None;
    }
    Some(HertzMeasure {
        contact_radius: a,
        peak_pressure: force / area / hertz_disc_mean_factor(HERTZ_CENTRAL_DISC),
    })
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
    if let Some(d) = maxima.get("max_displacement") {
        m.push(("max_displacement".to_string(), *d));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hertz's formulas: F = 4 E* a^3 / (3 R), and p0 = 3 F / (2 pi a^2) = 2 E* a / (pi R).
    #[test]
    fn hertz_formulas_are_consistent() {
        let (e_star, radius) = (1000.0 / (2.0 * (1.0 - 0.09)), 1.0);
        for a in [0.05, 0.1, 0.2] {
            let f = 4.0 * e_star * a * a * a / (3.0 * radius);
            let (ah, p0) = hertz(f, radius, e_star);
            assert!((ah - a).abs() < 1e-14 * a);
            let p0_alt = 2.0 * e_star * a / (std::f64::consts::PI * radius);
            assert!((p0 - p0_alt).abs() < 1e-12 * p0);
        }
    }

    /// The central disc factor: the mean of sqrt(1 - s^2) over the disc s < kappa, by a
    /// midpoint rule, and its limits.
    #[test]
    fn disc_mean_factor_matches_a_quadrature() {
        for kappa in [0.25, 0.5, 1.0] {
            let n = 200_000;
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                let s = kappa * (i as f64 + 0.5) / n as f64;
                num += (1.0 - s * s).sqrt() * s;
                den += s;
            }
            let f = hertz_disc_mean_factor(kappa);
            assert!(
                (num / den - f).abs() < 1e-8,
                "{kappa}: {} vs {f}",
                num / den
            );
        }
        assert!((hertz_disc_mean_factor(1.0) - 2.0 / 3.0).abs() < 1e-15);
        assert!((hertz_disc_mean_factor(1e-4) - 1.0).abs() < 1e-8);
    }

    /// Hertz's pressure on a quarter disc, sampled at the Gauss points of a graded polar grid
    /// (and zero outside the contact): the measure returns a and p0, to the accuracy of the
    /// quadrature, and no measure without pressure.
    #[test]
    fn hertz_measure_recovers_an_exact_profile() {
        let (a, p0) = (0.12, 45.0);
        let profile = |r: f64| p0 * (1.0 - (r / a).powi(2)).max(0.0).sqrt();
        let g = [
            (0.5 - 0.5 * (3.0f64 / 5.0).sqrt(), 5.0 / 18.0),
            (0.5, 8.0 / 18.0),
            (0.5 + 0.5 * (3.0f64 / 5.0).sqrt(), 5.0 / 18.0),
        ];
        // Rings graded toward the centre, 0 <= r <= 0.3; an edge of the rings at r = a, so
        // the quadrature meets the square root where it is.
        let mut edges: Vec<f64> = (0..=40).map(|i| a * (i as f64 / 40.0).sqrt()).collect();
        edges.extend((1..=30).map(|i| a + (0.3 - a) * i as f64 / 30.0));
        let mut points = Vec::new();
        for w in edges.windows(2) {
            for (sr, wr) in g {
                let r = w[0] + sr * (w[1] - w[0]);
                points.push(PressurePoint {
                    r2: r * r,
                    pressure: profile(r),
                    weight: wr * (w[1] - w[0]) * r * std::f64::consts::FRAC_PI_2,
                });
            }
        }
        let m = hertz_measure(&points).unwrap();
        assert!((m.contact_radius - a).abs() < 1e-3 * a, "{m:?}");
        assert!((m.peak_pressure - p0).abs() < 2e-3 * p0, "{m:?}");
        // Hertz's formulas for the force of this field give the same pair.
        let force = 4.0 * points.iter().map(|q| q.pressure * q.weight).sum::<f64>();
        let e_star = 1000.0;
        let radius = 4.0 * e_star * a.powi(3) / (3.0 * force);
        let (ah, p0h) = hertz(force, radius, e_star);
        assert!(
            (ah - a).abs() < 1e-3 * a && (p0h - p0).abs() < 3e-3 * p0,
            "{ah} {p0h}"
        );
        // A flat (uniform) pressure of the same force is told apart: its second moment gives
        // sqrt(5/4) times its radius.
        let flat: Vec<PressurePoint> = points
            .iter()
            .map(|q| PressurePoint {
                pressure: if q.r2 < a * a { p0 } else { 0.0 },
                ..*q
            })
            .collect();
        let m = hertz_measure(&flat).unwrap();
        assert!(
            (m.contact_radius / a - 1.25f64.sqrt()).abs() < 1e-2,
            "{m:?}"
        );
        let none: Vec<PressurePoint> = points
            .iter()
            .map(|q| PressurePoint {
                pressure: 0.0,
                ..*q
            })
            .collect();
        assert_eq!(hertz_measure(&none), None);
    }

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
