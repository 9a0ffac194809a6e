//! The safe PETSc layer: what happens at the C boundary.
//!
//! MPI can be initialized once per process, so every check runs inside one test function, in
//! order, under one `Petsc` guard (cargo runs each integration-test file as its own process).
//!
//! Checked:
//! - a SNES solve of a small nonlinear system (x_i^2 = i + 1) converges to sqrt(i + 1) with
//!   Newton's quadratic rate;
//! - a panic inside the residual closure is caught at the C boundary and re-raised after
//!   `SNESSolve` returns, with its payload, and the solver is usable afterwards;
//! - an error returned by the Jacobian closure comes back as that error;
//! - a domain error ends the solve with `DIVERGED_FUNCTION_DOMAIN` and carries the message;
//! - a linear solve through the KSP wrapper;
//! - a PETSc error (a nonzero outside the preallocated pattern) comes back as `Error::Petsc`
//!   with PETSc's own message and the Rust call site;
//! - blocks added straight into the stored rows (`Matrix::with_owned_rows`) give the matrix of
//!   `MatSetValues` bit for bit, on one rank and (`petsc_layer_two_ranks.rs`, under `mpirun`)
//!   on two, where the stash and the off-diagonal blocks come in.

use std::panic::{catch_unwind, AssertUnwindSafe};

use mortar::petsc::snes::Tolerances;
use mortar::petsc::{CallbackError, Ksp, LinearPath, Matrix, Petsc, Snes, Sparsity, Vector};
use mortar::Error;

#[path = "petsc_checks/owned_rows.rs"]
mod owned_rows;
use owned_rows::owned_rows_match_set_values;

const N: usize = 4;

fn diagonal_pattern() -> Sparsity {
    Sparsity {
        row_start: 0,
        rows: (0..N as i32).map(|i| vec![i]).collect(),
    }
}

fn tolerances() -> Tolerances {
    Tolerances {
        atol: 1e-14,
        rtol: 1e-12,
        stol: 1e-16,
        max_it: 20,
    }
}

/// F_i(x) = x_i^2 - (i + 1).
fn residual(x: &Vector, f: &mut Vector) -> Result<(), CallbackError> {
    let xs = x.to_local_vec()?;
    f.with_local_mut(|fs| {
        for (i, v) in fs.iter_mut().enumerate() {
            *v = xs[i] * xs[i] - (i as f64 + 1.0);
        }
    })?;
    Ok(())
}

/// J = diag(2 x_i).
fn jacobian(x: &Vector, j: &mut Matrix) -> Result<(), CallbackError> {
    let xs = x.to_local_vec()?;
    j.zero_entries()?;
    for (i, xi) in xs.iter().enumerate() {
        j.add_values(&[i as i32], &[i as i32], &[2.0 * xi])?;
    }
    j.assemble()?;
    Ok(())
}

fn start(x: &mut Vector) {
    x.set_all(1.0).unwrap();
}

#[test]
fn petsc_layer_boundary_behaviour() {
    let petsc = Petsc::initialize(&["petsc_layer".to_string()], None).unwrap();
    assert_eq!(petsc.size(), 1);
    let mut x = Vector::new_mpi(N).unwrap();
    let mut jac = Matrix::new_aij(&diagonal_pattern()).unwrap();
    let mut snes = Snes::new(tolerances(), "test", "basic", LinearPath::Direct).unwrap();

    converging_solve(&mut snes, &mut x, &mut jac);
    panic_in_the_residual_is_reraised(&mut snes, &mut x, &mut jac);
    jacobian_error_is_returned(&mut snes, &mut x, &mut jac);
    domain_error_ends_the_solve(&mut snes, &mut x, &mut jac);
    new_nonzero_is_a_petsc_error(&mut jac);
    preallocated_pattern_survives_an_empty_assembly();
    linear_solve(&mut x);

    // Check 8: blocks added straight into the stored rows (`Matrix::with_owned_rows`) give the
    // matrix of `MatSetValues`, bit for bit: rows of node-like column runs, constrained
    // (negative) indices, columns in any order, and entries outside the pattern (kept aside,
    // then added through `MatSetValues`).
    owned_rows_match_set_values(&petsc);
    preallocated_again_holds_the_new_pattern();

    drop(snes);
    drop(jac);
    drop(x);
    drop(petsc);
}

/// Check 1: a converging solve, at Newton's quadratic rate.
fn converging_solve(snes: &mut Snes, x: &mut Vector, jac: &mut Matrix) {
    start(x);
    let out = snes.solve(x, jac, &mut residual, &mut jacobian).unwrap();
    assert!(out.converged, "{}", out.reason);
    let xs = x.to_local_vec().unwrap();
    for (i, v) in xs.iter().enumerate() {
        assert!((v - (i as f64 + 1.0).sqrt()).abs() < 1e-12);
    }
    let h = &out.residual_history;
    let n = h.len();
    assert!(n >= 4, "history {h:?}");
    let order = (h[n - 2] / h[n - 3]).ln() / (h[n - 3] / h[n - 4]).ln();
    assert!(order > 1.8, "Newton order {order} from {h:?}");
}

/// Check 2: a panic in the residual is re-raised after the solve, with its payload, and the
/// solver still works after it.
fn panic_in_the_residual_is_reraised(snes: &mut Snes, x: &mut Vector, jac: &mut Matrix) {
    start(x);
    let mut calls = 0;
    let mut panicking = |x: &Vector, f: &mut Vector| -> Result<(), CallbackError> {
        calls += 1;
        if calls == 2 {
            panic!("residual exploded");
        }
        residual(x, f)
    };
    let caught = catch_unwind(AssertUnwindSafe(|| {
        snes.solve(x, jac, &mut panicking, &mut jacobian)
    }));
    let payload = caught.expect_err("the panic must be re-raised");
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .unwrap_or_default();
    assert_eq!(msg, "residual exploded");

    // The solver still works after a caught panic.
    start(x);
    let out = snes.solve(x, jac, &mut residual, &mut jacobian).unwrap();
    assert!(out.converged);
}

/// Check 3: an error from the Jacobian closure is returned as that error.
fn jacobian_error_is_returned(snes: &mut Snes, x: &mut Vector, jac: &mut Matrix) {
    start(x);
    let mut failing = |_: &Vector, _: &mut Matrix| -> Result<(), CallbackError> {
        Err(CallbackError::Fatal(Error::Solve(
            "tangent unavailable".into(),
        )))
    };
    match snes.solve(x, jac, &mut residual, &mut failing) {
        Err(Error::Solve(m)) => assert_eq!(m, "tangent unavailable"),
        other => panic!("expected the closure's error, got {other:?}"),
    }
}

/// Check 4: a domain error ends the solve as DIVERGED_FUNCTION_DOMAIN, with the message
/// kept.
fn domain_error_ends_the_solve(snes: &mut Snes, x: &mut Vector, jac: &mut Matrix) {
    start(x);
    let mut outside = |x: &Vector, f: &mut Vector| -> Result<(), CallbackError> {
        residual(x, f)?;
        Err(CallbackError::Domain("element 7 inverted".into()))
    };
    let out = snes.solve(x, jac, &mut outside, &mut jacobian).unwrap();
    assert!(!out.converged);
    assert_eq!(out.reason, "DIVERGED_FUNCTION_DOMAIN");
    assert_eq!(out.domain_error.as_deref(), Some("element 7 inverted"));
}

/// Check 5: a nonzero outside the preallocated pattern is a PETSc error with PETSc's
/// message.
fn new_nonzero_is_a_petsc_error(jac: &mut Matrix) {
    let err = jac
        .add_values(&[0], &[1], &[1.0])
        .expect_err("new nonzeros must be an error");
    match err {
        Error::Petsc {
            call,
            location,
            msg,
            ..
        } => {
            assert_eq!(call, "MatSetValues");
            assert!(location.file().ends_with("matrix.rs"), "{location}");
            assert!(msg.contains("New nonzero at (0,1)"), "{msg}");
            assert!(!msg.contains('\n'), "one line: {msg}");
        }
        other => panic!("expected a PETSc error, got {other:?}"),
    }
}

/// Check 6: the whole preallocated pattern survives an assembly that leaves part of it empty
/// (a contact block before the bodies touch): a later entry there is no new nonzero, though
/// new nonzeros are errors.
fn preallocated_pattern_survives_an_empty_assembly() {
    let mut wide = Sparsity {
        row_start: 0,
        rows: (0..N as i32).map(|i| vec![i]).collect(),
    };
    wide.rows[0].push(1);
    let mut m = Matrix::new_aij(&wide).unwrap();
    m.add_values(&[0], &[0], &[1.0]).unwrap();
    m.assemble().unwrap();
    m.add_values(&[0], &[1], &[2.0]).unwrap();
    m.assemble().unwrap();
    assert_eq!(m.get_values(&[0], &[0, 1]).unwrap(), vec![1.0, 2.0]);
    drop(m);
}

/// Check 9: a matrix preallocated anew in place (`Matrix::preallocate_again`, the same PETSc
/// object) stores exactly the new pattern, as zeros (its old values dropped); an entry of the
/// new pattern is no new nonzero, and one outside it is allowed now, stored and counted.
fn preallocated_again_holds_the_new_pattern() {
    let mut m = Matrix::new_aij(&diagonal_pattern()).unwrap();
    m.add_values(&[0], &[0], &[1.0]).unwrap();
    m.assemble().unwrap();
    let mut wider = diagonal_pattern();
    wider.rows[0].push(1);
    m.preallocate_again(&wider).unwrap();
    assert_eq!(m.stored_entries().unwrap(), N as u64 + 1);
    assert_eq!(m.get_values(&[0], &[0, 1]).unwrap(), vec![0.0, 0.0]);
    m.add_values(&[0], &[1], &[2.0]).unwrap();
    m.assemble().unwrap();
    assert_eq!(m.stored_entries().unwrap(), N as u64 + 1);
    m.add_values(&[1], &[0], &[3.0]).unwrap();
    m.assemble().unwrap();
    assert_eq!(m.stored_entries().unwrap(), N as u64 + 2);
    let values = m.get_values(&[0, 1], &[0, 1]).unwrap();
    assert_eq!(values, vec![0.0, 2.0, 3.0, 0.0]);
}

/// Check 7: a linear solve through the KSP wrapper: diag(2 x) y = 1 with x = 2, so y = 1/4.
fn linear_solve(x: &mut Vector) {
    let mut b = Vector::new_mpi(N).unwrap();
    b.set_all(1.0).unwrap();
    let mut y = Vector::new_mpi(N).unwrap();
    let mut ksp = Ksp::new().unwrap();
    let mut a = Matrix::new_aij(&diagonal_pattern()).unwrap();
    x.set_all(2.0).unwrap();
    jacobian(x, &mut a).unwrap();
    let out = ksp.solve(&a, &b, &mut y).unwrap();
    assert!(out.converged);
    for (i, v) in y.to_local_vec().unwrap().iter().enumerate() {
        assert!((v - 0.25).abs() < 1e-15, "y[{i}] = {v}");
    }
    drop(ksp);
    drop(a);
}
