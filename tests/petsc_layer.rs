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
//!   `MatSetValues` bit for bit, on one rank and (`owned_rows_on_two_ranks`, under `mpirun`)
//!   on two, where the stash and the off-diagonal blocks come in.

use std::panic::{catch_unwind, AssertUnwindSafe};

use mortar::petsc::snes::Tolerances;
use mortar::petsc::{CallbackError, Ksp, Matrix, Petsc, Snes, Sparsity, Vector};
use mortar::Error;

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
    let mut snes = Snes::new(tolerances(), "test", "basic").unwrap();

    // 1. A converging solve.
    start(&mut x);
    let out = snes
        .solve(&mut x, &mut jac, &mut residual, &mut jacobian)
        .unwrap();
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

    // 2. A panic in the residual is re-raised after the solve, with its payload.
    start(&mut x);
    let mut calls = 0;
    let mut panicking = |x: &Vector, f: &mut Vector| -> Result<(), CallbackError> {
        calls += 1;
        if calls == 2 {
            panic!("residual exploded");
        }
        residual(x, f)
    };
    let caught = catch_unwind(AssertUnwindSafe(|| {
        snes.solve(&mut x, &mut jac, &mut panicking, &mut jacobian)
    }));
    let payload = caught.expect_err("the panic must be re-raised");
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .unwrap_or_default();
    assert_eq!(msg, "residual exploded");

    // The solver still works after a caught panic.
    start(&mut x);
    let out = snes
        .solve(&mut x, &mut jac, &mut residual, &mut jacobian)
        .unwrap();
    assert!(out.converged);

    // 3. An error from the Jacobian closure is returned as that error.
    start(&mut x);
    let mut failing = |_: &Vector, _: &mut Matrix| -> Result<(), CallbackError> {
        Err(CallbackError::Fatal(Error::Solve(
            "tangent unavailable".into(),
        )))
    };
    match snes.solve(&mut x, &mut jac, &mut residual, &mut failing) {
        Err(Error::Solve(m)) => assert_eq!(m, "tangent unavailable"),
        other => panic!("expected the closure's error, got {other:?}"),
    }

    // 4. A domain error ends the solve as DIVERGED_FUNCTION_DOMAIN, with the message kept.
    start(&mut x);
    let mut outside = |x: &Vector, f: &mut Vector| -> Result<(), CallbackError> {
        residual(x, f)?;
        Err(CallbackError::Domain("element 7 inverted".into()))
    };
    let out = snes
        .solve(&mut x, &mut jac, &mut outside, &mut jacobian)
        .unwrap();
    assert!(!out.converged);
    assert_eq!(out.reason, "DIVERGED_FUNCTION_DOMAIN");
    assert_eq!(out.domain_error.as_deref(), Some("element 7 inverted"));

    // 5. A nonzero outside the preallocated pattern is a PETSc error with PETSc's message.
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

    // 6. The whole preallocated pattern survives an assembly that leaves part of it empty (a
    // contact block before the bodies touch): a later entry there is no new nonzero, though new
    // nonzeros are errors.
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

    // 7. A linear solve through the KSP wrapper: diag(2 x) y = 1 with x = 2, so y = 1/4.
    let mut b = Vector::new_mpi(N).unwrap();
    b.set_all(1.0).unwrap();
    let mut y = Vector::new_mpi(N).unwrap();
    let mut ksp = Ksp::new().unwrap();
    let mut a = Matrix::new_aij(&diagonal_pattern()).unwrap();
    x.set_all(2.0).unwrap();
    jacobian(&x, &mut a).unwrap();
    let out = ksp.solve(&a, &b, &mut y).unwrap();
    assert!(out.converged);
    for (i, v) in y.to_local_vec().unwrap().iter().enumerate() {
        assert!((v - 0.25).abs() < 1e-15, "y[{i}] = {v}");
    }

    // 8. Blocks added straight into the stored rows (`Matrix::with_owned_rows`) give the
    // matrix of `MatSetValues`, bit for bit: rows of node-like column runs, constrained
    // (negative) indices, columns in any order, and entries outside the pattern (kept aside,
    // then added through `MatSetValues`).
    owned_rows_match_set_values(&petsc);

    drop(ksp);
    drop(a);
    drop(snes);
    drop(jac);
    drop(x);
    drop(petsc);
}

/// Check 8 (see `petsc_layer_boundary_behaviour`), on this process's share of the rows (all
/// of them on one rank; `owned_rows_on_two_ranks` runs it on two).
fn owned_rows_match_set_values(petsc: &Petsc) {
    const ROWS: i32 = 30;
    let (rank, size) = (petsc.rank() as i32, petsc.size() as i32);
    // Contiguous ownership in whole nodes: 10 nodes of 3 rows, split between the ranks.
    let first = 3 * (10 * rank / size);
    let end = 3 * (10 * (rank + 1) / size);
    // Node-like pattern: rows in triples, each triple coupled to the triples within 2 of it.
    let pattern = Sparsity {
        row_start: first as usize,
        rows: (first..end)
            .map(|r| {
                let node = r / 3;
                (0..ROWS).filter(|c| (c / 3 - node).abs() <= 2).collect()
            })
            .collect(),
    };
    // A deterministic stream of values, the same on every rank.
    let mut seed = 12345u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    // Every rank adds every block: on two ranks half the rows of each are the other rank's
    // (they go through the stash) and the columns span both ranks (off-diagonal blocks).
    let mut blocks: Vec<(Vec<i32>, Vec<f64>)> = Vec::new();
    for first in 0..8 {
        // Three nodes, one dof constrained (-1), in a shuffled node order.
        let mut idx: Vec<i32> = [first + 2, first, first + 1]
            .iter()
            .flat_map(|&n| (0..3).map(move |c| 3 * n + c))
            .collect();
        idx[4] = -1;
        let vals = (0..idx.len() * idx.len()).map(|_| next()).collect();
        blocks.push((idx, vals));
    }
    // Outside the pattern: rows and columns {0, 1, 2, 27} (node 0 against a dof of node 9,
    // in another rank's columns on two ranks).
    let outside = (
        vec![0, 1, 27, 2],
        (0..16).map(|_| next()).collect::<Vec<f64>>(),
    );
    let build = |direct: bool| -> Vec<f64> {
        let mut m = Matrix::new_aij(&pattern).unwrap();
        m.allow_new_nonzeros().unwrap();
        for _ in 0..2 {
            // Twice: the second sum lands on the values of the first assembly. Within one
            // assembly the blocks come twice, the second time after the entries outside the
            // pattern were inserted (rows with gaps, on two ranks no off-diagonal column map):
            // `with_owned_rows` must then fall back to `MatSetValues`.
            for with_outside in [true, false] {
                if direct {
                    m.with_owned_rows(|rows| {
                        for (idx, vals) in &blocks {
                            rows.add(idx, idx, vals)?;
                        }
                        if with_outside {
                            rows.add(&outside.0, &outside.0, &outside.1)?;
                        }
                        Ok(())
                    })
                    .unwrap();
                } else {
                    for (idx, vals) in &blocks {
                        m.add_values(idx, idx, vals).unwrap();
                    }
                    if with_outside {
                        m.add_values(&outside.0, &outside.0, &outside.1).unwrap();
                    }
                }
            }
            m.assemble().unwrap();
        }
        let owned: Vec<i32> = (first..end).collect();
        let all: Vec<i32> = (0..ROWS).collect();
        m.get_values(&owned, &all).unwrap()
    };
    let (by_rows, by_set_values) = (build(true), build(false));
    assert!(by_set_values.iter().filter(|v| **v != 0.0).count() > 300 / size as usize);
    for (k, (a, b)) in by_rows.iter().zip(&by_set_values).enumerate() {
        let (row, col) = (first + k as i32 / ROWS, k as i32 % ROWS);
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "entry ({row}, {col}) on rank {rank}"
        );
    }
}

/// Set in the environment of the two-rank run of `owned_rows_on_two_ranks`.
const WORKER: &str = "MORTAR_PETSC_LAYER_WORKER";

/// Check 8 on two ranks: this test runs itself under `mpirun -n 2`, where each rank compares
/// its owned rows (stash, off-diagonal blocks and their column map included).
#[test]
fn owned_rows_on_two_ranks() {
    if std::env::var_os(WORKER).is_some() {
        let petsc = Petsc::initialize(&["petsc_layer".into()], None).unwrap();
        owned_rows_match_set_values(&petsc);
        // One whole line per rank: the test harness's own "... ok" is written in two pieces,
        // which mpirun may interleave between the ranks.
        println!(
            "owned rows checked on rank {} of {}",
            petsc.rank(),
            petsc.size()
        );
        drop(petsc);
        return;
    }
    let out = std::process::Command::new("mpirun")
        .args([
            "-n",
            "2",
            "--oversubscribe",
            "--bind-to",
            "none",
            "--timeout",
            "120",
        ])
        .arg(std::env::current_exe().unwrap())
        .args(["owned_rows_on_two_ranks", "--exact", "--nocapture"])
        .env(WORKER, "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_mpi_yield_when_idle", "1")
        .output()
        .expect("cannot start mpirun");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "two-rank run failed:\n{text}");
    for rank in 0..2 {
        assert!(
            text.contains(&format!("owned rows checked on rank {rank} of 2")),
            "rank {rank} ran the check:\n{text}"
        );
    }
}
