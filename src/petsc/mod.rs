//! The safe PETSc layer: the only unsafe code outside `ffi/`.
//!
//! - [`Petsc`] is the one initialization guard: rsmpi initializes MPI, then `PetscInitialize`
//!   receives the real argv (so `-snes_monitor`, `-ksp_type ...` reach PETSc's options database)
//!   and the scene's options file; dropping it calls `PetscFinalize`, then MPI is finalized.
//! - Every PETSc object ([`Vector`], [`Matrix`], [`Scatter`], [`Ksp`], [`Snes`]) is destroyed in
//!   `Drop`, and none can be created outside the life of the guard.
//! - Every PETSc error code becomes an [`Error::Petsc`](crate::Error::Petsc) carrying PETSc's own
//!   message (captured by an error handler pushed at start-up, which keeps PETSc from printing its
//!   traceback: the error is reported once, in one line) and the Rust location of the call.
//! - SNES residual and Jacobian are Rust closures; a panic inside one is caught at the C boundary
//!   and re-raised after `SNESSolve` returns (see [`snes`]).
//!
//! The bindings assume 32-bit `PetscInt` and 64-bit real `PetscScalar`; [`Petsc::initialize`]
//! asserts both against what PETSc was compiled with.

mod coarse;
mod error;
mod index_set;
mod init;
mod ksp;
pub mod log;
mod matrix;
pub mod options;
mod owned_rows;
mod scatter;
pub mod snes;
mod vector;

pub use error::check;
pub use index_set::IndexSet;
pub use init::{start_mpi, Petsc};
pub use ksp::{Ksp, KspOutcome, LinearPath};
pub use matrix::{Matrix, NullSpace, Sparsity};
pub use owned_rows::OwnedRows;
pub use scatter::Scatter;
pub use snes::{CallbackError, Snes, SnesOutcome, UpdateCheck};
pub use vector::Vector;

/// PETSc's index type (32-bit in Debian's build; asserted at start-up).
pub type PetscInt = petsc_ffi::PetscInt;

/// Calls a PETSc function and turns its error code into a `Result` naming the function and the
/// Rust location: `chk!(VecSetValues(v, n, idx, vals, mode))?`.
macro_rules! chk {
    ($fun:ident ( $($arg:expr),* $(,)? )) => {
        $crate::petsc::check(
            #[allow(unused_unsafe)]
            unsafe { petsc_ffi::$fun($($arg),*) },
            stringify!($fun),
        )
    };
}
pub(crate) use chk;

/// A slice view of PETSc's array `ptr` of `n` items, which may be null for zero length.
///
/// # Safety
/// For `n > 0`, `ptr` points to `n` valid items that outlive `'a`.
pub(crate) unsafe fn slice_or_empty<'a, T>(ptr: *const T, n: usize) -> &'a [T] {
    if n == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(ptr, n)
    }
}

/// Converts a count or index to `PetscInt`, failing clearly past 2^31.
pub fn to_petsc_int(n: usize) -> crate::Result<PetscInt> {
    PetscInt::try_from(n).map_err(|_| {
        crate::Error::Other(format!(
            "index {n} exceeds PetscInt (32-bit in this PETSc build)"
        ))
    })
}

/// Fails unless PETSc is initialized (and not yet finalized): every constructor calls this, so
/// no PETSc object can be made outside the life of the [`Petsc`] guard.
pub(crate) fn ensure_initialized() -> crate::Result<()> {
    let mut init = petsc_ffi::PetscBool::PETSC_FALSE;
    chk!(PetscInitialized(&mut init))?;
    if init != petsc_ffi::PetscBool::PETSC_TRUE || is_finalized() {
        return Err(crate::Error::Other(
            "PETSc object created outside the life of the Petsc guard".into(),
        ));
    }
    Ok(())
}

/// True between `PetscInitialize` and `PetscFinalize`.
pub(crate) fn is_initialized() -> bool {
    let mut init = petsc_ffi::PetscBool::PETSC_FALSE;
    // SAFETY: PetscInitialized only writes the flag; it is valid before and after init.
    unsafe { petsc_ffi::PetscInitialized(&mut init) };
    init == petsc_ffi::PetscBool::PETSC_TRUE && !is_finalized()
}

/// True once `PetscFinalize` has run: `Drop` impls then leave their (already freed) objects alone.
pub(crate) fn is_finalized() -> bool {
    let mut fin = petsc_ffi::PetscBool::PETSC_FALSE;
    // SAFETY: PetscFinalized only writes the flag; it is valid before and after init.
    unsafe { petsc_ffi::PetscFinalized(&mut fin) };
    fin == petsc_ffi::PetscBool::PETSC_TRUE
}

thread_local! {
    /// The communicator of a run on fewer ranks than the job ([`Petsc::on_first_ranks`]).
    static RUN_COMM: std::cell::Cell<Option<petsc_ffi::MPI_Comm>> =
        const { std::cell::Cell::new(None) };
}

/// The communicator parallel PETSc objects are created on: `PETSC_COMM_WORLD`, or the ranks
/// of a run on fewer ranks than the job ([`Petsc::on_first_ranks`]).
pub fn comm() -> petsc_ffi::MPI_Comm {
    RUN_COMM.with(|c| c.get()).unwrap_or_else(|| {
        // SAFETY: returns a constant handle; valid after MPI_Init.
        unsafe { petsc_ffi::petsc_ffi_comm_world() }
    })
}

/// The number of ranks of [`comm`].
pub fn comm_size() -> crate::Result<usize> {
    comm_query("MPI_Comm_size", petsc_ffi::MPI_Comm_size)
}

/// This rank's index in [`comm`].
pub fn comm_rank() -> crate::Result<usize> {
    comm_query("MPI_Comm_rank", petsc_ffi::MPI_Comm_rank)
}

/// The number `query` (`MPI_Comm_size`, `MPI_Comm_rank`) gives for [`comm`].
fn comm_query(
    name: &str,
    query: unsafe extern "C" fn(
        petsc_ffi::MPI_Comm,
        *mut std::os::raw::c_int,
    ) -> std::os::raw::c_int,
) -> crate::Result<usize> {
    ensure_initialized()?;
    let mut value: std::os::raw::c_int = 0;
    // SAFETY: MPI is running (rsmpi started it before PETSc, and `ensure_initialized` checked
    // that PETSc is up and not finalized), `comm()` is a valid communicator, and `value` is a
    // valid out-pointer.
    let code = unsafe { query(comm(), &mut value) };
    if code != 0 {
        // One rank's failure, not the job's (`Error::is_collective`): it must abort the job.
        return Err(crate::Error::Other(format!("{name} failed ({code})")));
    }
    Ok(usize::try_from(value).unwrap_or(0))
}

/// Sets (or, with `None`, unsets) the communicator returned by [`comm`].
fn set_run_comm(raw: Option<petsc_ffi::MPI_Comm>) {
    RUN_COMM.with(|c| c.set(raw));
}

/// Whether `signal` is ignored (`SIG_IGN`) in this process: a background job of a script
/// starts with SIGINT ignored. (C library calls live here with the project's other foreign
/// calls.)
pub fn signal_is_ignored(signal: std::os::raw::c_int) -> bool {
    // SAFETY: `sigaction` with a null new action only reads the current disposition.
    unsafe { petsc_ffi::petsc_ffi_signal_ignored(signal) != 0 }
}

/// Gives `signal` its default action again, dropping any handler (PETSc's).
pub fn default_signal(signal: std::os::raw::c_int) {
    // SAFETY: setting a signal's disposition to SIG_DFL has no memory-safety preconditions.
    unsafe { petsc_ffi::petsc_ffi_default_signal(signal) }
}

/// The self communicator.
pub fn comm_self() -> petsc_ffi::MPI_Comm {
    // SAFETY: returns a constant handle; valid after MPI_Init.
    unsafe { petsc_ffi::petsc_ffi_comm_self() }
}
