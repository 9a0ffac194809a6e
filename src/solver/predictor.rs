//! The consistent load-step predictor.
//!
//! From the converged state x_n at t_n, the first Newton iterate of the step to t_{n+1} is
//! `x_0 = x_n - K(x_n; t_n)^-1 [ F(x_n; t_n) + dF/dt (t_{n+1} - t_n) ]`: the increment of every
//! load and prescribed displacement enters linearized, through the tangent of the converged
//! state, instead of all at once into the boundary layer of elements (where a large prescribed
//! increment can invert elements on the first iterate). `dF/dt` is a one-sided difference with
//! `t_n + 1e-6 (t_{n+1} - t_n)`; loads are linear in their curves, prescribed displacements enter
//! nonlinearly, and the predictor is only a starting point for Newton, so its accuracy is
//! ample. For a pure load increment it equals the first Newton step.
//!
//! With `steps.predictor_tangent = "last_newton"` (the default) the solve reuses the
//! factorization of the last step's last Newton iteration, `K(x_n^(k-1))`, as PETSc's linear
//! solver still holds it (the matrix is untouched since, so nothing is refactorized): no
//! assembly and no factorization, a prediction that differs from the consistent one by the
//! effect of the last Newton correction on the tangent. It is used only when that
//! factorization is one of the last step's converged Newton solve ([`NewtonTangent`]).

use crate::error::Result;
use crate::petsc::{Matrix, Snes, Vector};

use super::evaluation::Evaluation;

/// What the linear solver's factorization holds when a step begins (for the predictor's
/// `steps.predictor_tangent = "last_newton"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NewtonTangent {
    /// The tangent of the last Newton iteration of the last step, which converged.
    OfLastConvergedStep,
    /// Anything else: nothing yet, a failed attempt's, an unconverged step's, a step whose
    /// final solve took no Newton iteration (the factorization is then an earlier solve's), or
    /// a new matrix.
    Other,
}

/// The tangent the linear solver holds, as the predictor sees it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Tangent {
    /// A constant tangent (a linear scene) is assembled and factorized for good.
    pub ready: bool,
    pub newton: NewtonTangent,
}

/// Moves `x` from x_n at `t0` to the predicted first iterate of the step to `t1`; leaves it
/// unchanged when the tangent or the residual at x_n is not available (an inverted element:
/// Newton will report it) or the linear solve fails. `reuse_newton_tangent` marks the last
/// Newton factorization as the one to solve with (module docs). Returns whether `x` moved.
pub(super) fn predict(
    ev: &Evaluation,
    (x, jac, snes): (&mut Vector, &mut Matrix, &mut Snes),
    (t0, t1): (f64, f64),
    tangent: &mut Tangent,
    reuse_newton_tangent: bool,
) -> Result<bool> {
    const EPS: f64 = 1e-6;
    let f0 = ev.residual_at(x, t0)?;
    let f1 = ev.residual_at(x, t0 + EPS * (t1 - t0))?;
    let (Some(f0), Some(mut rhs)) = (f0, f1) else {
        return Ok(false);
    };
    // rhs = f0 + (f1 - f0) / eps
    rhs.axpy(-1.0, &f0)?;
    rhs.scale(1.0 / EPS)?;
    rhs.axpy(1.0, &f0)?;
    if !tangent.ready && !reuse_newton_tangent {
        ev.cx.evaluator.borrow_mut().t = t0;
        if ev.jacobian(x, jac)?.is_err() {
            return Ok(false);
        }
        tangent.ready = ev.cx.scene.is_linear();
    }
    let mut dx = x.duplicate()?;
    dx.set_all(0.0)?;
    let solved = snes.linear_solve(jac, &rhs, &mut dx)?;
    if tangent.ready {
        // The factorization just made is the one Newton would make: keep it for good.
        snes.reuse_jacobian()?;
    }
    if solved {
        x.axpy(-1.0, &dx)?;
    }
    Ok(solved)
}
