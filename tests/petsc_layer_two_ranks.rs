//! The PETSc layer's check 8 (blocks added straight into the stored rows give the matrix of
//! `MatSetValues`, `petsc_layer.rs`) on two ranks, where the stash and the off-diagonal blocks
//! come in.
//!
//! A test binary of its own: the test launches itself under `mpirun`, and the launching
//! process must not have started MPI. A single-process `MPI_Init` (any other test of the same
//! binary, running in a parallel thread) writes Open MPI's and PMIx's variables into the
//! environment that `mpirun` would then inherit.

mod common;

use mortar::petsc::Petsc;

#[path = "petsc_checks/owned_rows.rs"]
mod owned_rows;
use owned_rows::owned_rows_match_set_values;

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
    let mut mpirun = common::mpirun(2, 120);
    let out = common::mpi_env(&mut mpirun)
        .arg(std::env::current_exe().unwrap())
        .args(["owned_rows_on_two_ranks", "--exact", "--nocapture"])
        .env(WORKER, "1")
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
