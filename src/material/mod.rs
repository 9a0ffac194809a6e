//! Constitutive laws (physics only: stresses and tangents from a deformation gradient).
//!
//! Both laws are isotropic, given by Young's modulus `E` and Poisson's ratio `nu`, with the Lamé
//! parameters
//!
//! ```text
//! lambda = E nu / ((1 + nu)(1 - 2 nu)),      mu = E / (2 (1 + nu)).
//! ```
//!
//! Index conventions: `F_iJ = dx_i / dX_J`; the first Piola-Kirchhoff stress `P_iJ = dW / dF_iJ`
//! and its tangent `A_iJkL = dP_iJ / dF_kL` are stored as a 9x9 matrix with row `3 i + J` and
//! column `3 k + L`. `A` has major symmetry `A_iJkL = A_kLiJ` since it is a second derivative of
//! `W`.
//!
//! # Linear elasticity (small strain)
//!
//! ```text
//! eps   = sym(F - I)
//! W     = lambda/2 (tr eps)^2 + mu eps : eps
//! P     = sigma = lambda tr(eps) I + 2 mu eps
//! A_ijkl = lambda d_ij d_kl + mu (d_ik d_jl + d_il d_jk)
//! ```
//!
//! The Cauchy stress is `sigma = P` (no distinction between configurations).
//!
//! # Compressible Neo-Hookean
//!
//! With `C = F^T F` and `J = det F > 0`:
//!
//! ```text
//! W = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2
//! P = mu (F - F^-T) + lambda ln J F^-T
//! ```
//!
//! Using `d(ln J)/dF_kL = F^-T_kL` and `d(F^-T)_iJ / dF_kL = -F^-1_Li F^-1_Jk`:
//!
//! ```text
//! A_iJkL = mu d_ik d_JL + (mu - lambda ln J) F^-1_Li F^-1_Jk + lambda F^-T_iJ F^-T_kL
//! ```
//!
//! The Cauchy stress is `sigma = P F^T / J = (mu (b - I) + lambda ln J I) / J` with `b = F F^T`.
//! For `F = I + H` with small `H` the law reduces to linear elasticity to first order in `H`.

use nalgebra::{Matrix3, SMatrix};

/// An isotropic constitutive law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Small-strain linear elasticity.
    LinearElastic { young: f64, poisson: f64 },
    /// Compressible Neo-Hookean hyperelasticity.
    NeoHookean { young: f64, poisson: f64 },
}

/// The 9x9 tangent `dP/dF`.
pub type Tangent = SMatrix<f64, 9, 9>;

/// The tangent of both laws in factored form
///
/// ```text
/// A_iJkL = alpha d_ik d_JL + beta M_Li M_Jk + gamma M_Ji M_Lk
/// ```
///
/// (linear: `M = I`, `alpha = beta = mu`, `gamma = lambda`; Neo-Hookean: `M = F^-1`,
/// `alpha = mu`, `beta = mu - lambda ln J`, `gamma = lambda`). With the spatial gradients
/// `g_a = M^T dN_a/dX` the element stiffness block is
/// `K_ab = alpha (dN_a . dN_b) I + beta g_b g_a^T + gamma g_a g_b^T`, far cheaper than contracting
/// the 9x9 matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsoTangent {
    pub m: Matrix3<f64>,
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
}

impl IsoTangent {
    /// The full 9x9 matrix (row `3 i + J`, column `3 k + L`).
    pub fn to_matrix(&self) -> Tangent {
        let m = &self.m;
        let mut a = Tangent::zeros();
        for i in 0..3 {
            for jj in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        let mut v = self.beta * m[(l, i)] * m[(jj, k)]
                            + self.gamma * m[(jj, i)] * m[(l, k)];
                        if i == k && jj == l {
                            v += self.alpha;
                        }
                        a[(3 * i + jj, 3 * k + l)] = v;
                    }
                }
            }
        }
        a
    }
}

impl Material {
    /// Young's modulus and Poisson's ratio.
    fn params(&self) -> (f64, f64) {
        match *self {
            Material::LinearElastic { young, poisson }
            | Material::NeoHookean { young, poisson } => (young, poisson),
        }
    }

    /// Name used in messages.
    pub fn name(&self) -> &'static str {
        match self {
            Material::LinearElastic { .. } => "linear_elastic",
            Material::NeoHookean { .. } => "neo_hookean",
        }
    }

    /// Checks 1e-100 <= E <= 1e100 and -1 < nu < 0.5; the error message names the offending
    /// parameter and value.
    pub fn validate(&self) -> Result<(), String> {
        // Any unit system puts a solid's modulus well inside these bounds.
        const MIN_YOUNG: f64 = 1.0 / crate::MAX_MAGNITUDE;
        const MAX_YOUNG: f64 = crate::MAX_MAGNITUDE;
        let (e, nu) = self.params();
        if !(MIN_YOUNG..=MAX_YOUNG).contains(&e) {
            return Err(format!(
                "young = {e} is invalid for {}: Young's modulus must lie in \
                 [{MIN_YOUNG:e}, {MAX_YOUNG:e}] (beyond, stresses and stiffnesses over- or \
                 underflow)",
                self.name()
            ));
        }
        if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
            return Err(format!(
                "poisson = {nu} is invalid for {}: Poisson's ratio must satisfy -1 < nu < 0.5",
                self.name()
            ));
        }
        Ok(())
    }

    /// Young's modulus E.
    pub fn young(&self) -> f64 {
        self.params().0
    }

    /// Poisson's ratio nu.
    pub fn poisson(&self) -> f64 {
        self.params().1
    }

    /// Lamé parameters `(lambda, mu)`.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = self.params();
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        (lambda, mu)
    }

    /// First Piola-Kirchhoff stress P and its tangent A = dP/dF as a 9x9 matrix with row 3*i+J for
    /// P_iJ and column 3*k+L for F_kL. Err(J) when det F <= 0 for the Neo-Hookean law.
    pub fn first_piola(&self, f: &Matrix3<f64>) -> Result<(Matrix3<f64>, Tangent), f64> {
        let (p, t) = self.first_piola_iso(f)?;
        Ok((p, t.to_matrix()))
    }

    /// First Piola-Kirchhoff stress and its tangent in the factored isotropic form of
    /// [`IsoTangent`] (no 9x9 matrix: what the element kernels use). Err(J) when det F <= 0 for
    /// the Neo-Hookean law.
    pub fn first_piola_iso(&self, f: &Matrix3<f64>) -> Result<(Matrix3<f64>, IsoTangent), f64> {
        let (lambda, mu) = self.lame();
        match self {
            Material::LinearElastic { .. } => {
                let eps = 0.5 * (f + f.transpose()) - Matrix3::identity();
                let p = Matrix3::identity() * (lambda * eps.trace()) + eps * (2.0 * mu);
                let t = IsoTangent {
                    m: Matrix3::identity(),
                    alpha: mu,
                    beta: mu,
                    gamma: lambda,
                };
                Ok((p, t))
            }
            Material::NeoHookean { .. } => {
                let det = f.determinant();
                if det.is_nan() || det <= 0.0 {
                    return Err(det);
                }
                let finv = f.try_inverse().ok_or(det)?;
                let fit = finv.transpose();
                let lnj = det.ln();
                let p = (f - fit) * mu + fit * (lambda * lnj);
                let t = IsoTangent {
                    m: finv,
                    alpha: mu,
                    beta: mu - lambda * lnj,
                    gamma: lambda,
                };
                Ok((p, t))
            }
        }
    }

    /// Cauchy stress. For the Neo-Hookean law with det F <= 0 the result is NaN.
    pub fn cauchy(&self, f: &Matrix3<f64>) -> Matrix3<f64> {
        match self {
            Material::LinearElastic { .. } => {
                self.first_piola_iso(f)
                    .expect("linear elasticity never fails")
                    .0
            }
            Material::NeoHookean { .. } => {
                let (lambda, mu) = self.lame();
                let det = f.determinant();
                if det.is_nan() || det <= 0.0 {
                    return Matrix3::from_element(f64::NAN);
                }
                let b = f * f.transpose();
                ((b - Matrix3::identity()) * mu + Matrix3::identity() * (lambda * det.ln())) / det
            }
        }
    }

    /// Strain energy density per reference volume (for the FD check of P). Infinite for the
    /// Neo-Hookean law when det F <= 0.
    pub fn strain_energy(&self, f: &Matrix3<f64>) -> f64 {
        let (lambda, mu) = self.lame();
        match self {
            Material::LinearElastic { .. } => {
                let eps = 0.5 * (f + f.transpose()) - Matrix3::identity();
                0.5 * lambda * eps.trace().powi(2) + mu * eps.component_mul(&eps).sum()
            }
            Material::NeoHookean { .. } => {
                let det = f.determinant();
                if det.is_nan() || det <= 0.0 {
                    return f64::INFINITY;
                }
                let lnj = det.ln();
                let trc = f.component_mul(f).sum();
                0.5 * mu * (trc - 3.0) - mu * lnj + 0.5 * lambda * lnj * lnj
            }
        }
    }
}

/// Von Mises equivalent stress of a (symmetric) stress tensor.
pub fn von_mises(s: &Matrix3<f64>) -> f64 {
    let d = [
        s[(0, 0)] - s[(1, 1)],
        s[(1, 1)] - s[(2, 2)],
        s[(2, 2)] - s[(0, 0)],
    ];
    let sh = s[(0, 1)].powi(2) + s[(1, 2)].powi(2) + s[(2, 0)].powi(2);
    (0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 3.0 * sh).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    const MATS: [Material; 4] = [
        Material::LinearElastic {
            young: 210.0,
            poisson: 0.3,
        },
        Material::NeoHookean {
            young: 210.0,
            poisson: 0.3,
        },
        Material::NeoHookean {
            young: 3.0,
            poisson: 0.49,
        },
        Material::NeoHookean {
            young: 1.0,
            poisson: -0.4,
        },
    ];

    /// A fixed, well-conditioned, non-symmetric deformation gradient with det F > 0.
    fn sample_f() -> Matrix3<f64> {
        Matrix3::new(1.1, 0.2, -0.05, -0.1, 0.95, 0.15, 0.07, -0.12, 1.2)
    }

    fn max_abs<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> f64 {
        m.iter().fold(0.0f64, |a, &x| a.max(x.abs()))
    }

    /// Central differences (step 1e-6) of `g` in each entry `(k, l)` of `f`:
    /// `visit(k, l, dg/dF_kl)`.
    fn central_differences<T>(
        f: &Matrix3<f64>,
        g: impl Fn(&Matrix3<f64>) -> T,
        mut visit: impl FnMut(usize, usize, T),
    ) where
        T: std::ops::Sub<Output = T> + std::ops::Div<f64, Output = T>,
    {
        let h = 1e-6;
        for k in 0..3 {
            for l in 0..3 {
                let (mut fp, mut fm) = (*f, *f);
                fp[(k, l)] += h;
                fm[(k, l)] -= h;
                visit(k, l, (g(&fp) - g(&fm)) / (2.0 * h));
            }
        }
    }

    #[test]
    fn piola_matches_fd_of_energy() {
        for m in MATS {
            for f in [sample_f(), Matrix3::identity(), sample_f().transpose()] {
                let (p, _) = m.first_piola(&f).unwrap();
                let mut p_fd = Matrix3::zeros();
                central_differences(&f, |f| m.strain_energy(f), |k, l, d| p_fd[(k, l)] = d);
                let scale = max_abs(&p).max(m.lame().1);
                assert!(
                    max_abs(&(p - p_fd)) < 1e-6 * scale,
                    "{m:?}: P = {p}, FD = {p_fd}"
                );
            }
        }
    }

    #[test]
    fn tangent_matches_fd_of_piola() {
        for m in MATS {
            let f = sample_f();
            let (_, a) = m.first_piola(&f).unwrap();
            let mut a_fd = Tangent::zeros();
            let piola = |f: &Matrix3<f64>| m.first_piola(f).unwrap().0;
            central_differences(&f, piola, |k, l, dp| {
                for i in 0..3 {
                    for j in 0..3 {
                        a_fd[(3 * i + j, 3 * k + l)] = dp[(i, j)];
                    }
                }
            });
            assert!(
                max_abs(&(a - a_fd)) < 1e-6 * max_abs(&a),
                "{m:?}: A = {a}, FD = {a_fd}"
            );
        }
    }

    #[test]
    fn tangent_has_major_symmetry() {
        for m in MATS {
            let (_, a) = m.first_piola(&sample_f()).unwrap();
            assert!(max_abs(&(a - a.transpose())) < 1e-12 * max_abs(&a), "{m:?}");
        }
    }

    #[test]
    fn neo_hookean_reduces_to_linear_for_small_strain() {
        let g = Matrix3::new(0.3, -1.0, 0.5, 0.8, -0.2, 0.4, -0.6, 0.9, 1.0);
        let f = Matrix3::identity() + g * 1e-7;
        let (e, nu) = (210.0, 0.3);
        let lin = Material::LinearElastic {
            young: e,
            poisson: nu,
        };
        let nh = Material::NeoHookean {
            young: e,
            poisson: nu,
        };
        let (pl, al) = lin.first_piola(&f).unwrap();
        let (pn, an) = nh.first_piola(&f).unwrap();
        // The difference is second order in the strain: ~ E * 1e-14.
        assert!(max_abs(&(pl - pn)) < 1e-4 * max_abs(&pl), "{pl} vs {pn}");
        assert!(max_abs(&(al - an)) < 1e-5 * max_abs(&al));
        let sl = lin.cauchy(&f);
        let sn = nh.cauchy(&f);
        assert!(max_abs(&(sl - sn)) < 1e-4 * max_abs(&sl));
        // And at F = I both give zero stress.
        assert_eq!(
            max_abs(&nh.first_piola(&Matrix3::identity()).unwrap().0),
            0.0
        );
    }

    #[test]
    fn cauchy_is_symmetric_and_consistent_with_piola() {
        for m in MATS {
            let f = sample_f();
            let s = m.cauchy(&f);
            assert!(max_abs(&(s - s.transpose())) < 1e-12 * max_abs(&s), "{m:?}");
            if let Material::NeoHookean { .. } = m {
                let (p, _) = m.first_piola(&f).unwrap();
                let s2 = p * f.transpose() / f.determinant();
                assert!(max_abs(&(s - s2)) < 1e-12 * max_abs(&s));
            }
        }
    }

    #[test]
    fn neo_hookean_rejects_inverted_f() {
        let m = MATS[1];
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, -0.5));
        assert_eq!(m.first_piola(&f).unwrap_err(), -0.5);
        assert!(m.first_piola(&Matrix3::zeros()).is_err());
        assert!(MATS[0].first_piola(&f).is_ok());
    }

    #[test]
    fn lame_parameters() {
        let (l, mu) = Material::LinearElastic {
            young: 2.6,
            poisson: 0.3,
        }
        .lame();
        assert!((mu - 1.0).abs() < 1e-15);
        assert!((l - 2.6 * 0.3 / (1.3 * 0.4)).abs() < 1e-14);
    }

    #[test]
    fn validate_checks_parameters() {
        let ok = |e, nu| Material::NeoHookean {
            young: e,
            poisson: nu,
        };
        assert!(ok(1.0, 0.3).validate().is_ok());
        assert!(ok(1.0, -0.99).validate().is_ok());
        for (e, nu, word) in [
            (0.0, 0.3, "young"),
            (-1.0, 0.3, "young"),
            (f64::NAN, 0.3, "young"),
            (1e-320, 0.3, "young"),
            (1e308, 0.3, "young"),
            (1.0, 0.5, "poisson"),
            (1.0, 0.7, "poisson"),
            (1.0, -1.0, "poisson"),
            (1.0, -1.5, "poisson"),
        ] {
            let err = ok(e, nu).validate().unwrap_err();
            assert!(err.contains(word), "{err}");
            let val = if word == "young" { e } else { nu };
            assert!(err.contains(&format!("{val}")), "{err}");
        }
        assert!(Material::LinearElastic {
            young: -2.0,
            poisson: 0.2
        }
        .validate()
        .is_err());
    }

    #[test]
    fn von_mises_of_uniaxial_and_shear() {
        let s = Matrix3::from_diagonal(&nalgebra::Vector3::new(5.0, 0.0, 0.0));
        assert!((von_mises(&s) - 5.0).abs() < 1e-14);
        let t = Matrix3::new(0.0, 2.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!((von_mises(&t) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
        let h = Matrix3::identity() * 7.0;
        assert!(von_mises(&h).abs() < 1e-14);
    }
}
