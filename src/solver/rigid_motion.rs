//! A singular tangent where no factorization reports it: the rigid motions of a body that the
//! tangent does not resist.
//!
//! The direct solve reports a singular tangent by MUMPS's null pivots. An iterative solve has no
//! pivots: GMRES either stalls, and the step's cuts end in a misleading error (an inverted
//! element), or converges to an arbitrary rigid shift. The tangent's null space is checked
//! instead against the rigid body modes of each body, the near null space the multigrid
//! already holds: with `R` a body's six modes (three translations, three rotations about its
//! centroid, on its free dofs: `DofMap::rigid_body_modes`), the least stiffness of a rigid
//! motion of it is
//!
//! ```text
//! s_min^2 = min_v |J R v|^2 / |R v|^2,
//! ```
//!
//! the least eigenvalue of the 6 x 6 pencil `(G, M)`, `G = (J R)^T (J R)`, `M = R^T R`, whose
//! entries are all-reduced dot products, so that every rank finds the same. A mode that the
//! constraints remove entirely (a component held on every node of the body) is zero on the
//! free dofs; the pencil is solved on the range of `M` only. The body's stiffness scale is the
//! geometric mean of `|J_ii|` over its rows, which a few penalty rows many orders larger move by
//! little. Against it a ratio `s_min / scale` below [`NULL_RATIO`] is a motion that nothing
//! holds: a body held by its constraints or by a contact resists every rigid motion with a
//! ratio of about the square root of the share of its nodes that are held, a free one with
//! round-off (measured: docs/verification.md, "Singular model"). The
//! translations are exact null modes at any deformation; the rotations about the reference
//! axes only approach the deformed body's null rotations, so a free rotation of a much
//! deformed body may go unreported; the error this check can make is to miss a free body,
//! not to stop a held one.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use crate::error::Result;
use crate::petsc::{Matrix, Vector};

/// The least stiffness of a body's rigid motions, over its stiffness scale, below which the
/// motion counts as free.
pub(super) const NULL_RATIO: f64 = 1e-8;

/// An eigenvalue of `M` below this fraction of its largest marks a combination of the modes
/// that the constraints remove (zero on the free dofs).
const REMOVED_MODE: f64 = 1e-12;

/// The names of the bodies whose rigid motions `jac` does not resist; `modes`: six per body,
/// in the order of `bodies`, on the owned free dofs. Empty when `jac` is not assembled.
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
    let diagonal = diagonal.to_local_vec()?;
    let mut free = Vec::new();
    for (b, body_modes) in modes.chunks(6).enumerate() {
        let scale = stiffness_scale(&diagonal, body_modes)?;
        let (g, m) = pencil(jac, body_modes)?;
        if scale > 0.0 && least_stiffness(&g, &m) < NULL_RATIO * scale {
            free.push(bodies.get(b).cloned().unwrap_or_else(|| format!("{b}")));
        }
    }
    Ok(free)
}

/// The geometric mean of `|J_ii|` over the body's rows (those its translations touch), 0 when
/// it has none or all are zero. Collective.
fn stiffness_scale(diagonal: &[f64], body_modes: &[Vec<f64>]) -> Result<f64> {
    let in_body = |i: usize| body_modes[..3].iter().any(|t| t[i] != 0.0);
    let (mut logs, mut rows) = (vec![0.0; diagonal.len()], vec![0.0; diagonal.len()]);
    for (i, d) in diagonal.iter().enumerate() {
        if in_body(i) && d.abs() > 0.0 {
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

/// `(G, M)`: the Gram matrices of `J R` and of `R` for the body's modes `R`. Collective.
fn pencil(jac: &Matrix, body_modes: &[Vec<f64>]) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let k = body_modes.len();
    let mut r = Vec::with_capacity(k);
    let mut jr = Vec::with_capacity(k);
    for mode in body_modes {
        let v = vector_of(mode)?;
        let mut w = v.duplicate()?;
        jac.mult(&v, &mut w)?;
        r.push(v);
        jr.push(w);
    }
    let (mut g, mut m) = (DMatrix::zeros(k, k), DMatrix::zeros(k, k));
    for i in 0..k {
        for j in 0..=i {
            g[(i, j)] = jr[i].dot(&jr[j])?;
            m[(i, j)] = r[i].dot(&r[j])?;
            (g[(j, i)], m[(j, i)]) = (g[(i, j)], m[(i, j)]);
        }
    }
    Ok((g, m))
}

/// `s_min = sqrt(min_v v^T G v / v^T M v)` over `v` in the range of `M` (the modes the
/// constraints leave); infinite when they leave none.
fn least_stiffness(g: &DMatrix<f64>, m: &DMatrix<f64>) -> f64 {
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
        return f64::INFINITY;
    }
    let basis = DMatrix::from_columns(&kept);
    let reduced = basis.transpose() * g * &basis;
    let least = SymmetricEigen::new(reduced)
        .eigenvalues
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    least.max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pencil's least stiffness: a free mode gives 0, a held pencil its least `|J v| / |v|`
    /// whatever the modes' scaling, and a mode the constraints remove is left out.
    #[test]
    fn least_stiffness_is_that_of_the_softest_combination() {
        // R = diag(1, 2, 3) (three modes), J R = diag(1, 2, 3) * diag(4, 5, 6): stiffness 4-6.
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 4.0, 9.0]));
        let g = DMatrix::from_diagonal(&DVector::from_vec(vec![16.0, 100.0, 324.0]));
        assert!((least_stiffness(&g, &m) - 4.0).abs() < 1e-12);
        // A combination of two modes free: G singular along (1, -1, 0) in the modes.
        let jr = DMatrix::from_row_slice(3, 3, &[1.0, 1.0, 0.0, 2.0, 2.0, 0.0, 0.0, 0.0, 5.0]);
        let r = DMatrix::<f64>::identity(3, 3);
        let g = jr.transpose() * &jr;
        assert!(least_stiffness(&g, &(r.transpose() * &r)) < 1e-12);
        // The third mode removed by the constraints (zero on the free dofs): left out, though G
        // is zero along it too.
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.0]));
        let g = DMatrix::from_diagonal(&DVector::from_vec(vec![9.0, 25.0, 0.0]));
        assert!((least_stiffness(&g, &m) - 3.0).abs() < 1e-12);
        let none = DMatrix::zeros(2, 2);
        assert_eq!(least_stiffness(&none, &none), f64::INFINITY);
    }
}
