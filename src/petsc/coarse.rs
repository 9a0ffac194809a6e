//! The interface coarse correction: the shell part of a composite preconditioner whose other
//! part is the interface field split (`-pc_composite_pcs fieldsplit,shell`).
//!
//! The field split alone leaves the motion of one body against the other, across the
//! interface, to its block iteration between the interface and the bulk, which slows as the
//! mesh is refined (docs/performance.md, "The split, not the multigrid, sets the count"). This
//! correction spans it: with `P` the prolongator that is the bulk multigrid's first coarse
//! space on the bulk rows (GAMG's finest interpolation, rigid modes per aggregate) and the
//! identity on the interface rows,
//!
//! ```text
//!     P = [ P_bulk  0 ]   (bulk rows)
//!         [ 0       I ]   (interface rows)
//! ```
//!
//! (a picture by field: the rows and columns are numbered rank by rank, and within a rank's
//! columns the interface's come first, see [`interface_column`])
//!
//! it solves the Galerkin projection of the whole tangent exactly, `e = P (P^T A P)^-1 P^T r`
//! (LU through MUMPS, null-pivot detection on by default: an aggregate's dependent rigid modes
//! make the projection singular, and MUMPS then leaves those directions out). The interface
//! dofs stay at full resolution in it, so the contact's laws (open, stick, slip) enter it
//! exactly and no multigrid is asked to coarsen them; the split before it then needs only a
//! smoother on the interface (point Jacobi on the iterative path's default, `super::ksp`).
//! After the split's correction `x_1 = B r`, the composite applies this one to the residual
//! left, `x = x_1 + P (P^T A P)^-1 P^T (r - A x_1)`: a two-level method whose fine level is the
//! bulk's V-cycle and whose coarse level holds the interface whole.
//!
//! Set-up, at every set-up of the preconditioner (once per Newton iteration): `P` is gathered
//! from the split's bulk multigrid; where it and the tangent's pattern are unchanged (the
//! multigrid is kept whole through a load step), the symbolic product and factorization are
//! reused and only their numeric parts done again. With unsmoothed aggregation (the default's
//! `P_bulk`: every row in one aggregate, at most six entries) a row of `A P` has at most six
//! entries per aggregate that the row of `A` touches, and the projection stays cheap.

use std::os::raw::c_void;

use petsc_ffi as p;

use super::{chk, Matrix, PetscInt, Vector};
use crate::error::{Error, Result};

/// Makes the shell preconditioner `shell` the interface coarse correction of the field split
/// `split` (fields `interface` and `bulk`, the bulk by GAMG), a part of the same composite
/// before it (so that the split, set up when first applied, is set up before the shell). Its
/// LU takes the options of the prefix `coarse_` after the shell's own (`-sub_1_coarse_...` in
/// a composite); the iterative path sets its MUMPS options there (null-pivot detection and the
/// ordering: `super::ksp`'s `INTERFACE_COARSE`).
pub(crate) fn attach(shell: p::PC, split: p::PC) -> Result<()> {
    let mut comm = p::MPI_Comm(std::ptr::null_mut());
    chk!(PetscObjectGetComm(shell as p::PetscObject, &mut comm))?;
    let mut ksp: p::KSP = std::ptr::null_mut();
    chk!(KSPCreate(comm, &mut ksp))?;
    let correction = Box::new(Correction {
        split,
        ksp,
        prolongator: None,
        tangent: None,
        projected: None,
        work: None,
    });
    chk!(KSPSetType(ksp, c"preonly".as_ptr()))?;
    let mut lu: p::PC = std::ptr::null_mut();
    chk!(KSPGetPC(ksp, &mut lu))?;
    chk!(PCSetType(lu, c"lu".as_ptr()))?;
    chk!(PCFactorSetMatSolverType(lu, c"mumps".as_ptr()))?;
    let mut prefix: *const std::os::raw::c_char = std::ptr::null();
    chk!(PCGetOptionsPrefix(shell, &mut prefix))?;
    chk!(KSPSetOptionsPrefix(ksp, prefix))?;
    chk!(KSPAppendOptionsPrefix(ksp, c"coarse_".as_ptr()))?;
    chk!(KSPSetFromOptions(ksp))?;
    chk!(PCShellSetContext(
        shell,
        Box::into_raw(correction) as *mut c_void
    ))?;
    chk!(PCShellSetSetUp(shell, Some(set_up_trampoline)))?;
    chk!(PCShellSetApply(shell, Some(apply_trampoline)))?;
    chk!(PCShellSetDestroy(shell, Some(destroy_trampoline)))?;
    chk!(PCShellSetName(
        shell,
        c"interface coarse correction".as_ptr()
    ))
}

/// The shell's context.
struct Correction {
    /// The field split whose bulk multigrid gives `P_bulk` (not owned: the composite holds it).
    split: p::PC,
    /// The LU of `P^T A P`.
    ksp: p::KSP,
    prolongator: Option<Prolongator>,
    /// The tangent `A` of the last set-up (a reference, so that the same pointer is the same
    /// matrix), and its nonzero state then.
    tangent: Option<(Matrix, p::PetscObjectState)>,
    projected: Option<Matrix>,
    /// Vectors of the coarse layout: the restricted residual and the coarse solution.
    work: Option<(Vector, Vector)>,
}

/// `P`, and the entries it was made of (to tell whether the next set-up's is the same).
struct Prolongator {
    matrix: Matrix,
    entries: Entries,
}

/// The owned rows of `P`: their global rows, row lengths, columns and values.
#[derive(PartialEq)]
struct Entries {
    rows: Vec<PetscInt>,
    lengths: Vec<PetscInt>,
    cols: Vec<PetscInt>,
    vals: Vec<f64>,
    local_cols: PetscInt,
}

impl Drop for Correction {
    fn drop(&mut self) {
        if super::is_finalized() {
            return;
        }
        // SAFETY: `ksp` is the KSP this context created.
        unsafe { p::KSPDestroy(&mut self.ksp) };
    }
}

/// The context of the shell `pc`.
///
/// # Safety
/// `pc` is a shell whose context [`attach`] set, not yet destroyed.
unsafe fn context<'a>(pc: p::PC) -> Result<&'a mut Correction> {
    let mut ctx: *mut c_void = std::ptr::null_mut();
    chk!(PCShellGetContext(
        pc,
        &mut ctx as *mut *mut c_void as *mut c_void
    ))?;
    Ok(&mut *(ctx as *mut Correction))
}

/// `f`'s result as a PETSc error code; a failure's message (or a panic's) is printed once, and
/// PETSc's own error then ends the solve.
fn guarded(what: &str, f: impl FnOnce() -> Result<()>) -> p::PetscErrorCode {
    let failure = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(Ok(())) => return 0,
        Ok(Err(e)) => e.to_string(),
        Err(_) => "panicked".to_string(),
    };
    crate::error::print_warning(format_args!(
        "interface coarse correction, {what}: {failure}"
    ));
    p::PETSC_ERR_USER
}

unsafe extern "C" fn set_up_trampoline(pc: p::PC) -> p::PetscErrorCode {
    // SAFETY: PETSc calls this for the shell `attach` set up.
    guarded("set-up", || unsafe { set_up(pc) })
}

unsafe extern "C" fn apply_trampoline(pc: p::PC, r: p::Vec, e: p::Vec) -> p::PetscErrorCode {
    // SAFETY: as `set_up_trampoline`; `r` and `e` are PETSc's vectors for this call.
    guarded("apply", || unsafe { apply(pc, r, e) })
}

unsafe extern "C" fn destroy_trampoline(pc: p::PC) -> p::PetscErrorCode {
    // SAFETY: as `set_up_trampoline`; the context is dropped once, here.
    if let Ok(c) = unsafe { context(pc) } {
        drop(unsafe { Box::from_raw(c as *mut Correction) });
    }
    0
}

/// `e = P (P^T A P)^-1 P^T r`.
///
/// # Safety
/// As [`context`]; `r` and `e` are valid vectors of the tangent's layout.
unsafe fn apply(pc: p::PC, r: p::Vec, e: p::Vec) -> Result<()> {
    let c = context(pc)?;
    let (Some(prolongator), Some((restricted, solved))) = (&c.prolongator, &c.work) else {
        return Err(Error::Solve("applied before its set-up".into()));
    };
    let p_mat = prolongator.matrix.raw;
    chk!(MatMultTranspose(p_mat, r, restricted.raw))?;
    chk!(KSPSolve(c.ksp, restricted.raw, solved.raw))?;
    let mut reason = p::KSPConvergedReason(0);
    chk!(KSPGetConvergedReason(c.ksp, &mut reason))?;
    if reason.0 < 0 {
        chk!(PCSetFailedReason(pc, p::PCFailedReason::PC_SUBPC_ERROR))?;
    }
    chk!(MatMult(p_mat, solved.raw, e))
}

/// Gathers `P`, projects the tangent and factorizes the projection (see the module docs).
///
/// # Safety
/// As [`context`].
unsafe fn set_up(pc: p::PC) -> Result<()> {
    let c = context(pc)?;
    let (mut a, mut a_pre): (p::Mat, p::Mat) = (std::ptr::null_mut(), std::ptr::null_mut());
    chk!(PCGetOperators(pc, &mut a, &mut a_pre))?;
    let entries = prolongator_entries(c.split)?;
    let same_here = c
        .prolongator
        .as_ref()
        .is_some_and(|old| old.entries == entries);
    // The same on every rank: a new `P` is made collectively.
    let same_p = !counts_of_ranks(usize::from(!same_here))?
        .iter()
        .any(|&c| c > 0);
    if !same_p {
        let matrix = assemble_prolongator(a_pre, &entries)?;
        let (mut solved, mut restricted): (p::Vec, p::Vec) =
            (std::ptr::null_mut(), std::ptr::null_mut());
        chk!(MatCreateVecs(matrix.raw, &mut solved, std::ptr::null_mut()))?;
        chk!(MatCreateVecs(
            matrix.raw,
            &mut restricted,
            std::ptr::null_mut()
        ))?;
        c.work = Some((Vector { raw: restricted }, Vector { raw: solved }));
        c.prolongator = Some(Prolongator { matrix, entries });
        c.projected = None;
        // The coarse space may have another size: the LU starts afresh.
        chk!(KSPReset(c.ksp))?;
    }
    let Some(prolongator) = &c.prolongator else {
        return Err(Error::Solve("no prolongator after its set-up".into()));
    };
    let mut state: p::PetscObjectState = 0;
    chk!(MatGetNonzeroState(a_pre, &mut state))?;
    let same_a = c
        .tangent
        .as_ref()
        .is_some_and(|(m, s)| m.raw == a_pre && *s == state);
    if !same_a {
        c.tangent = Some((Matrix::from_borrowed(a_pre)?, state));
    }
    // The symbolic product again where the tangent's pattern (or `P`) changed.
    let mut projected = match (&c.projected, same_a) {
        (Some(m), true) => m.raw,
        _ => std::ptr::null_mut(),
    };
    let reuse = match projected.is_null() {
        true => p::MatReuse::MAT_INITIAL_MATRIX,
        false => p::MatReuse::MAT_REUSE_MATRIX,
    };
    chk!(MatPtAP(
        a_pre,
        prolongator.matrix.raw,
        reuse,
        2.0,
        &mut projected
    ))?;
    if reuse == p::MatReuse::MAT_INITIAL_MATRIX {
        c.projected = Some(Matrix { raw: projected });
    }
    chk!(KSPSetOperators(c.ksp, projected, projected))?;
    chk!(KSPSetUp(c.ksp))?;
    // A failed factorization (MUMPS's verdict, the same on every rank) ends the solve.
    let mut lu: p::PC = std::ptr::null_mut();
    chk!(KSPGetPC(c.ksp, &mut lu))?;
    let mut failed = p::PCFailedReason::PC_NOERROR;
    chk!(PCGetFailedReason(lu, &mut failed))?;
    match failed {
        p::PCFailedReason::PC_NOERROR => Ok(()),
        other => Err(Error::Solve(format!(
            "the LU of the projected tangent failed ({other:?})"
        ))),
    }
}

/// The entries of `P` from the split `split`'s fields and its bulk multigrid (set up).
///
/// # Safety
/// `split` is a field split set up with the fields `interface` and `bulk`, the bulk by GAMG.
unsafe fn prolongator_entries(split: p::PC) -> Result<Entries> {
    let bulk_p = bulk_interpolation(split)?;
    let interface = field_indices(split, c"interface")?;
    let bulk = field_indices(split, c"bulk")?;
    let (mut row_start, mut row_end): (PetscInt, PetscInt) = (0, 0);
    chk!(MatGetOwnershipRange(bulk_p, &mut row_start, &mut row_end))?;
    let (mut local_rows, mut coarse_local): (PetscInt, PetscInt) = (0, 0);
    chk!(MatGetLocalSize(bulk_p, &mut local_rows, &mut coarse_local))?;
    if local_rows as usize != bulk.len() {
        return Err(Error::Solve(
            "the bulk multigrid's rows are not the bulk field's".into(),
        ));
    }
    let mut coarse_starts: *const PetscInt = std::ptr::null();
    chk!(MatGetOwnershipRangesColumn(bulk_p, &mut coarse_starts))?;
    let ranks = super::comm_size()?;
    let coarse_starts = std::slice::from_raw_parts(coarse_starts, ranks + 1);
    // The columns of P, rank by rank: the rank's interface dofs, numbered in descending order,
    // then its coarse bulk columns (see [`interface_column`]).
    let interface_counts = counts_of_ranks(interface.len())?;
    let mut starts = Vec::with_capacity(ranks + 1);
    starts.push(0);
    for q in 0..ranks {
        let own = coarse_starts[q + 1] - coarse_starts[q] + interface_counts[q] as PetscInt;
        starts.push(starts[q] + own);
    }
    let rank = super::comm_rank()?;
    let mut e = Entries {
        rows: Vec::with_capacity(bulk.len() + interface.len()),
        lengths: Vec::with_capacity(bulk.len() + interface.len()),
        cols: Vec::new(),
        vals: Vec::new(),
        local_cols: starts[rank + 1] - starts[rank],
    };
    for (row, &global) in (row_start..row_end).zip(&bulk) {
        let mut n: PetscInt = 0;
        let mut cols: *const PetscInt = std::ptr::null();
        let mut vals: *const f64 = std::ptr::null();
        chk!(MatGetRow(bulk_p, row, &mut n, &mut cols, &mut vals))?;
        let (cols_s, vals_s) = (
            super::slice_or_empty(cols, n.max(0) as usize),
            super::slice_or_empty(vals, n.max(0) as usize),
        );
        for &col in cols_s {
            let q = coarse_starts[1..].partition_point(|&s| s <= col);
            e.cols
                .push(starts[q] + interface_counts[q] as PetscInt + col - coarse_starts[q]);
        }
        e.vals.extend_from_slice(vals_s);
        e.rows.push(global);
        e.lengths.push(n);
        chk!(MatRestoreRow(bulk_p, row, &mut n, &mut cols, &mut vals))?;
    }
    for (k, &global) in interface.iter().enumerate() {
        e.rows.push(global);
        e.lengths.push(1);
        e.cols
            .push(interface_column(starts[rank], interface.len(), k));
        e.vals.push(1.0);
    }
    Ok(e)
}

/// The column of `P` of the `k`-th of a rank's `count` interface dofs (the field's rows in
/// ascending order), whose columns start at `first`: the interface dofs come first among the
/// rank's columns, in descending order.
///
/// PETSc's symbolic product `A P` (3.18: the parallel `nonscalable` algorithm and the
/// sequential one, `PetscLLCondensedAddSorted` and `PetscLLAddSorted`) merges, row by row, the
/// columns of the rows of `P` that a row of `A` touches into a sorted linked list, walking it
/// from its head for every row of `P`. An interface row of `A` is long (a contact stencil) and
/// most of its columns are interface dofs, rows of `P` with one entry, met in ascending order:
/// numbered ascending, each new column would be appended after all the others, a walk across
/// the whole row each time, the row's cost the square of its length. Numbered descending, each
/// new interface column of the rank goes to the head of the list.
fn interface_column(first: PetscInt, count: usize, k: usize) -> PetscInt {
    first + (count - 1 - k) as PetscInt
}

/// `P` as a matrix of the tangent `a`'s row layout.
fn assemble_prolongator(a: p::Mat, e: &Entries) -> Result<Matrix> {
    let (mut local_rows, mut local_cols): (PetscInt, PetscInt) = (0, 0);
    chk!(MatGetLocalSize(a, &mut local_rows, &mut local_cols))?;
    let longest = e.lengths.iter().copied().max().unwrap_or(1).max(1);
    let mut comm = p::MPI_Comm(std::ptr::null_mut());
    chk!(PetscObjectGetComm(a as p::PetscObject, &mut comm))?;
    let mut raw: p::Mat = std::ptr::null_mut();
    chk!(MatCreateAIJ(
        comm,
        local_rows,
        e.local_cols,
        p::PETSC_DETERMINE,
        p::PETSC_DETERMINE,
        longest,
        std::ptr::null(),
        longest,
        std::ptr::null(),
        &mut raw
    ))?;
    let m = Matrix { raw };
    let mut at = 0;
    for (&row, &n) in e.rows.iter().zip(&e.lengths) {
        let end = at + n as usize;
        chk!(MatSetValues(
            m.raw,
            1,
            &row,
            n,
            e.cols[at..end].as_ptr(),
            e.vals[at..end].as_ptr(),
            p::InsertMode::INSERT_VALUES
        ))?;
        at = end;
    }
    chk!(MatAssemblyBegin(
        m.raw,
        p::MatAssemblyType::MAT_FINAL_ASSEMBLY
    ))?;
    chk!(MatAssemblyEnd(
        m.raw,
        p::MatAssemblyType::MAT_FINAL_ASSEMBLY
    ))?;
    Ok(m)
}

/// The finest interpolation of the bulk field's multigrid (borrowed from it).
///
/// # Safety
/// As [`prolongator_entries`].
unsafe fn bulk_interpolation(split: p::PC) -> Result<p::Mat> {
    let mut n: PetscInt = 0;
    let mut subksp: *mut p::KSP = std::ptr::null_mut();
    chk!(PCFieldSplitGetSubKSP(split, &mut n, &mut subksp))?;
    let mut multigrid: p::PC = std::ptr::null_mut();
    // The bulk is the second field (`Snes::split_interface` names them in that order).
    let got = match n {
        2 => chk!(KSPGetPC(*subksp.add(1), &mut multigrid)),
        _ => Err(Error::Solve(format!("a split of {n} fields, not 2"))),
    };
    chk!(petsc_ffi_free(subksp as *mut c_void))?;
    got?;
    let pc_type = super::snes::pc_type_name(multigrid)?;
    if pc_type != "gamg" {
        return Err(Error::Solve(format!(
            "the bulk field's preconditioner is {pc_type:?}, not gamg"
        )));
    }
    let mut levels: PetscInt = 0;
    chk!(PCMGGetLevels(multigrid, &mut levels))?;
    if levels < 2 {
        return Err(Error::Solve(
            "the bulk field's multigrid has no coarse level".into(),
        ));
    }
    let mut interpolation: p::Mat = std::ptr::null_mut();
    chk!(PCMGGetInterpolation(
        multigrid,
        levels - 1,
        &mut interpolation
    ))?;
    Ok(interpolation)
}

/// The owned global rows of the field `name` of the split `split`.
///
/// # Safety
/// `split` is a field split with that field.
unsafe fn field_indices(split: p::PC, name: &std::ffi::CStr) -> Result<Vec<PetscInt>> {
    let mut is: p::IS = std::ptr::null_mut();
    chk!(PCFieldSplitGetIS(split, name.as_ptr(), &mut is))?;
    let mut len: PetscInt = 0;
    chk!(ISGetLocalSize(is, &mut len))?;
    let mut ptr: *const PetscInt = std::ptr::null();
    chk!(ISGetIndices(is, &mut ptr))?;
    let indices = super::slice_or_empty(ptr, len.max(0) as usize).to_vec();
    chk!(ISRestoreIndices(is, &mut ptr))?;
    Ok(indices)
}

/// `count` of every rank of [`super::comm`] (*collective*).
fn counts_of_ranks(count: usize) -> Result<Vec<usize>> {
    let mut raw: p::Vec = std::ptr::null_mut();
    chk!(VecCreateMPI(
        super::comm(),
        super::to_petsc_int(count)?,
        p::PETSC_DETERMINE,
        &mut raw
    ))?;
    let v = Vector { raw };
    let mut starts: *const PetscInt = std::ptr::null();
    chk!(VecGetOwnershipRanges(v.raw, &mut starts))?;
    let ranks = super::comm_size()?;
    // SAFETY: PETSc's array of `ranks + 1` starts, valid while `v` lives.
    let starts = unsafe { std::slice::from_raw_parts(starts, ranks + 1) };
    Ok(starts.windows(2).map(|w| (w[1] - w[0]) as usize).collect())
}
