//! A singular tangent where no factorization reports it: the rigid motions of the bodies that
//! the tangent does not resist.
//!
//! The direct solve reports a singular tangent by MUMPS's null pivots. An iterative solve has no
//! pivots: GMRES either stalls, and the step's cuts end in a misleading error (an inverted
//! element), or converges to an arbitrary rigid shift. The tangent's null space is checked
//! instead against the rigid body modes, the near null space the multigrid already holds:
//! with `R` the six modes of every body as columns (three translations, three rotations about
//! its centroid, on its free dofs: `DofMap::rigid_body_modes`), the rigid motions `R v` of
//! least stiffness `s = |J R v| / |R v|` are the generalized eigenvectors of
//!
//! ```text
//! G v = s^2 M v,   G = (J R)^T (J R),   M = R^T R,
//! ```
//!
//! whose entries are all-reduced dot products, so that every rank finds the same. One pencil
//! holds every body's modes, so that two bodies tied or pressed together and held by nothing
//! else move together in one of its motions. A combination of modes that the constraints
//! remove entirely (a component held on every node of a body) is zero on the free dofs; the
//! pencil is solved on the range of `M` only. `G` squares the stiffnesses, so its least
//! eigenvalues carry the round-off of the stiffest motions (a penalty contact's, many orders
//! above the bulk's): each soft motion's `s` is measured again from the products `J r_i`
//! themselves, which resolve it down to about `1e-16` of the stiffest. The scale is the
//! geometric mean of `|J_ii|` over the bodies' rows, which a few penalty rows many orders
//! larger move by little. A motion with `s` below [`NULL_RATIO`] times it is free, and the
//! bodies holding at least [`BODY_SHARE`] of it are reported: a body held by its constraints or
//! by a contact resists every rigid motion with a ratio of about the square root of the share
//! of its nodes that are held, a free one with round-off (measured: docs/verification.md,
//! "Singular model"). The translations are exact null modes at any deformation; the rotations
//! about the reference axes only approach a deformed body's null rotations, so a free rotation
//! of a much deformed body may go unreported; the error this check can make is to miss a free
//! body, not to stop a held one.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use crate::error::Result;
use crate::petsc::{Matrix, Vector};

/// The least stiffness of a rigid motion, over the bodies' stiffness scale, below which the
/// motion counts as free.
pub(super) const NULL_RATIO: f64 = 1e-8;

/// An eigenvalue of `M` below this fraction of its largest marks a combination of the modes
/// that the constraints remove (zero on the free dofs).
const REMOVED_MODE: f64 = 1e-12;

/// A body takes part in a free motion when at least this share of the motion's squared norm
/// lies on its dofs.
const BODY_SHARE: f64 = 1e-3;

/// The names of the bodies that move in a rigid motion `jac` does not resist; `modes`: six per
/// body, in the order of `bodies`, on the owned free dofs. Empty when `jac` is not assembled.
/// Collective.
pub(super) fn free_bodies(
    jac: &Matrix,
    modes: &[Vec<f64>],
    bodies: &[String],
) -> Result<Vec<String>> {
    if !jac.is_assembled()? {
        return Ok(Vec::new());
    }
    let owned = modes.first().map_or(0, Vec::len);
    let mut diagonal = Vector::new_mpi(owned)?;
    jac.diagonal(&mut diagonal)?;
    let scale = stiffness_scale(&diagonal.to_local_vec()?, modes)?;
    if scale <= 0.0 {
        return Ok(Vec::new());
    }
    let r = modes
        .iter()
        .map(|m| vector_of(m))
        .collect::<Result<Vec<_>>>()?;
    let mut jr = Vec::with_capacity(r.len());
    for v in &r {
        let mut w = v.duplicate()?;
        jac.mult(v, &mut w)?;
        jr.push(w);
    }
    let (g, m) = (gram(&jr)?, gram(&r)?);
    let mut free = vec![false; modes.len().div_ceil(6)];
    for v in softest_motions(&g, &m) {
        // `|J R v|` from the products themselves, not from `G`, whose least eigenvalues the
        // stiffest motions' round-off covers; `|R v|^2 = v^T M v` (M is well conditioned on
        // its range).
        let motion = (v.transpose() * &m * &v)[(0, 0)].sqrt();
        if norm_of_combination(&jr, &v)? < NULL_RATIO * scale * motion {
            for (b, share) in body_shares(&m, &v).into_iter().enumerate() {
                free[b] |= share >= BODY_SHARE;
            }
        } else {
            break;
        }
    }
    Ok(free
        .iter()
        .enumerate()
        .filter(|(_, &f)| f)
        .map(|(b, _)| bodies.get(b).cloned().unwrap_or_else(|| format!("{b}")))
        .collect())
}

/// The geometric mean of `|J_ii|` over the rows the modes' translations touch, 0 when there
/// are none or all are zero. Collective.
fn stiffness_scale(diagonal: &[f64], modes: &[Vec<f64>]) -> Result<f64> {
    let translations: Vec<&Vec<f64>> = modes
        .chunks(6)
        .flat_map(|body| body.iter().take(3))
        .collect();
    let (mut logs, mut rows) = (vec![0.0; diagonal.len()], vec![0.0; diagonal.len()]);
    for (i, d) in diagonal.iter().enumerate() {
        if translations.iter().any(|t| t[i] != 0.0) && d.abs() > 0.0 {
            (logs[i], rows[i]) = (d.abs().ln(), 1.0);
        }
    }
    let (logs, rows) = (vector_of(&logs)?, vector_of(&rows)?);
    let count = rows.dot(&rows)?;
    Ok(if count > 0.0 {
        (logs.dot(&rows)? / count).exp()
    } else {
        0.0
    })
}

/// A vector of the owned rows `values`. Collective.
fn vector_of(values: &[f64]) -> Result<Vector> {
    let mut v = Vector::new_mpi(values.len())?;
    v.with_local_mut(|x| x.copy_from_slice(values))?;
    Ok(v)
}

/// The Gram matrix of `vectors`. Collective.
fn gram(vectors: &[Vector]) -> Result<DMatrix<f64>> {
    let k = vectors.len();
    let mut g = DMatrix::zeros(k, k);
    for i in 0..k {
        for j in 0..=i {
            g[(i, j)] = vectors[i].dot(&vectors[j])?;
            g[(j, i)] = g[(i, j)];
        }
    }
    Ok(g)
}

/// `|sum_i v_i x_i|`. Collective.
fn norm_of_combination(vectors: &[Vector], v: &DVector<f64>) -> Result<f64> {
    let mut sum = vectors[0].duplicate()?;
    sum.set_all(0.0)?;
    for (x, &c) in vectors.iter().zip(v.iter()) {
        sum.axpy(c, x)?;
    }
    sum.norm2()
}

/// Each body's share of `|R v|^2`, from its diagonal block of `M`.
fn body_shares(m: &DMatrix<f64>, v: &DVector<f64>) -> Vec<f64> {
    let total = (v.transpose() * m * v)[(0, 0)];
    (0..v.len().div_ceil(6))
        .map(|b| {
            let range = 6 * b..(6 * b + 6).min(v.len());
            let (vb, mb) = (
                v.rows_range(range.clone()),
                m.view_range(range.clone(), range),
            );
            (vb.transpose() * mb * vb)[(0, 0)] / total
        })
        .collect()
}

/// The combinations `v` of the modes in the range of `M` (the motions the constraints
/// leave), the softest first: the generalized eigenvectors of `G v = s^2 M v`.
fn softest_motions(g: &DMatrix<f64>, m: &DMatrix<f64>) -> Vec<DVector<f64>> {
    let SymmetricEigen {
        eigenvalues,
        eigenvectors,
    } = SymmetricEigen::new(m.clone());
    let largest = eigenvalues.iter().copied().fold(0.0, f64::max);
    // An M-orthonormal basis of the range of M: q_i / sqrt(mu_i).
    let kept: Vec<DVector<f64>> = eigenvalues
        .iter()
        .zip(eigenvectors.column_iter())
        .filter(|(mu, _)| **mu > 0.0 && **mu > REMOVED_MODE * largest)
        .map(|(mu, q)| q.clone_owned() / mu.sqrt())
        .collect();
    if kept.is_empty() {
        return Vec::new();
    }
    let basis = DMatrix::from_columns(&kept);
    let reduced = SymmetricEigen::new(basis.transpose() * g * &basis);
    let mut order: Vec<usize> = (0..kept.len()).collect();
    order.sort_by(|&a, &b| reduced.eigenvalues[a].total_cmp(&reduced.eigenvalues[b]));
    order
        .into_iter()
        .map(|k| &basis * reduced.eigenvectors.column(k))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `|J R v| / |R v|` of the softest motion `v`, from the Gram matrices.
    fn least_stiffness(g: &DMatrix<f64>, m: &DMatrix<f64>) -> f64 {
        let v = &softest_motions(g, m)[0];
        ((v.transpose() * g * v)[(0, 0)] / (v.transpose() * m * v)[(0, 0)]).sqrt()
    }

    /// The softest motion: a held pencil gives its least `|J v| / |v|` whatever the modes'
    /// scaling, a free combination zero, and a mode the constraints remove is left out.
    #[test]
    fn the_softest_motion_is_the_least_stiff_combination() {
        // R = diag(1, 2, 3) (three modes), J R = diag(1, 2, 3) * diag(4, 5, 6): stiffness 4-6.
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 4.0, 9.0]));
        let g = DMatrix::from_diagonal(&DVector::from_vec(vec![16.0, 100.0, 324.0]));
        assert!((least_stiffness(&g, &m) - 4.0).abs() < 1e-12);
        // A combination of two modes free: J R singular along (1, -1, 0).
        let jr = DMatrix::from_row_slice(3, 3, &[1.0, 1.0, 0.0, 2.0, 2.0, 0.0, 0.0, 0.0, 5.0]);
        let g = jr.transpose() * &jr;
        let identity = DMatrix::<f64>::identity(3, 3);
        assert!(least_stiffness(&g, &identity) < 1e-12);
        let v = &softest_motions(&g, &identity)[0];
        assert!((v[0] + v[1]).abs() < 1e-12 && v[2].abs() < 1e-12, "{v}");
        // The third mode removed by the constraints (zero on the free dofs): left out, though G
        // is zero along it too.
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.0]));
        let g = DMatrix::from_diagonal(&DVector::from_vec(vec![9.0, 25.0, 0.0]));
        assert!((least_stiffness(&g, &m) - 3.0).abs() < 1e-12);
        assert_eq!(softest_motions(&g, &m).len(), 2);
        let none = DMatrix::zeros(2, 2);
        assert!(softest_motions(&none, &none).is_empty());
    }

    /// A motion's share per body (six modes each).
    #[test]
    fn body_shares_split_the_motion_by_body() {
        let m = DMatrix::<f64>::identity(12, 12);
        let mut v = DVector::zeros(12);
        (v[0], v[7]) = (3.0, 4.0);
        let shares = body_shares(&m, &v);
        assert!((shares[0] - 0.36).abs() < 1e-12 && (shares[1] - 0.64).abs() < 1e-12);
    }
}
