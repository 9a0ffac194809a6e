//! Distributed sparse matrices (MPIAIJ / SeqAIJ) with exact preallocation.
//!
//! The sparsity of every locally owned row is computed from the mesh (and later the contact
//! stencils) before the matrix exists; the diagonal-block (`d_nnz`) and off-diagonal-block
//! (`o_nnz`) counts follow from it, and a new nonzero outside that pattern is made an error
//! (`MAT_NEW_NONZERO_ALLOCATION_ERR`) so a wrong stencil fails loudly instead of slowly.
//!
//! The whole pattern is stored as explicit zeros when the matrix is made: PETSc's AIJ final
//! assembly drops every preallocated slot that holds no value, so a contact block that is empty
//! at the first assembly (the bodies not touching yet) would otherwise lose its slots and cost
//! one reallocation of the row storage per entry when contact begins (docs/performance.md,
//! "Assembly and the matrix pattern"). With the pattern kept, the matrix's nonzero structure is
//! also the same from one Newton iteration to the next, so the LU's symbolic factorization can
//! be reused; where a moving contact needs more, the matrix is preallocated anew in place
//! ([`Matrix::preallocate_again`]), and the zeros it stores raise its nonzero state, from which
//! the next preconditioner set-up learns of the new pattern.
//!
//! **Owned entries.** The tangent blocks of every contribution go to the rows this rank owns
//! straight into the stored values (`super::owned_rows`), not through `MatSetValues`.
//!
//! **Off-process entries.** On more than one rank, the entries a rank adds to rows another rank
//! owns (element blocks along the partition boundary, and the contact rows of the nodes a rank
//! holds: `contact::frictional`, "Parallel layout") travel through PETSc's original stash
//! (`-matstash_legacy`, a default the options override): the newer one sorts and merges every
//! stashed entry before sending it, which on two ranks cost more than the messages themselves
//! (docs/performance.md, "Assembly and the matrix pattern").

use petsc_ffi as p;

use super::{chk, to_petsc_int, PetscInt};
use crate::error::Result;

/// The nonzero pattern of the rows this rank owns.
#[derive(Clone, Debug, Default)]
pub struct Sparsity {
    /// Global index of the first owned row (rows and columns share the layout).
    pub row_start: usize,
    /// Sorted, unique global column indices of each owned row.
    pub rows: Vec<Vec<PetscInt>>,
}

impl Sparsity {
    /// Per-row counts of columns inside (`d_nnz`) and outside (`o_nnz`) the owned column range.
    pub fn nnz(&self) -> (Vec<PetscInt>, Vec<PetscInt>) {
        let lo = self.row_start as PetscInt;
        let hi = (self.row_start + self.rows.len()) as PetscInt;
        self.rows
            .iter()
            .map(|cols| {
                let d = cols.iter().filter(|&&c| c >= lo && c < hi).count() as PetscInt;
                (d, cols.len() as PetscInt - d)
            })
            .unzip()
    }

    /// Total nonzeros of the owned rows.
    pub fn num_nonzeros(&self) -> usize {
        self.rows.iter().map(|r| r.len()).sum()
    }
}

/// A PETSc matrix; destroyed on drop.
pub struct Matrix {
    pub(crate) raw: p::Mat,
}

impl Matrix {
    /// A square AIJ matrix over [`super::comm`] with `sparsity.rows.len()` owned rows and
    /// columns, preallocated exactly and holding explicit zeros on the whole pattern (module
    /// docs); new nonzeros are an error. Collective.
    pub fn new_aij(sparsity: &Sparsity) -> Result<Matrix> {
        super::ensure_initialized()?;
        if super::comm_size()? > 1 {
            // Read when the matrix gets its type (module docs, "Off-process entries"); the
            // same on every rank, since the two stashes do not talk to each other.
            super::options::set_default("-matstash_legacy", "true")?;
        }
        let n = to_petsc_int(sparsity.rows.len())?;
        let mut raw: p::Mat = std::ptr::null_mut();
        chk!(MatCreate(super::comm(), &mut raw))?;
        let m = Matrix { raw };
        chk!(MatSetSizes(
            m.raw,
            n,
            n,
            p::PETSC_DETERMINE,
            p::PETSC_DETERMINE
        ))?;
        chk!(MatSetType(m.raw, c"aij".as_ptr()))?;
        let mut m = m;
        m.preallocate(sparsity)?;
        chk!(MatSetOption(
            m.raw,
            p::MatOption::MAT_NEW_NONZERO_ALLOCATION_ERR,
            p::PetscBool::PETSC_TRUE
        ))?;
        Ok(m)
    }

    /// Gives the matrix the pattern `sparsity` in place, entries outside it allowed
    /// ([`Matrix::allow_new_nonzeros`]): the same PETSc object, so that a solver holding it
    /// keeps it, with its values dropped and a new nonzero pattern, which the next
    /// preconditioner set-up sees. Collective.
    pub fn preallocate_again(&mut self, sparsity: &Sparsity) -> Result<()> {
        self.preallocate(sparsity)?;
        self.allow_new_nonzeros()
    }

    /// Preallocates `sparsity` exactly and stores zeros on it ([`Matrix::store_pattern`]); on
    /// a matrix preallocated before, PETSc drops its old pattern first. Collective.
    fn preallocate(&mut self, sparsity: &Sparsity) -> Result<()> {
        let (d_nnz, o_nnz) = sparsity.nnz();
        // Both calls are made; PETSc ignores the one that does not match the actual type.
        chk!(MatSeqAIJSetPreallocation(self.raw, 0, d_nnz.as_ptr()))?;
        chk!(MatMPIAIJSetPreallocation(
            self.raw,
            0,
            d_nnz.as_ptr(),
            0,
            o_nnz.as_ptr()
        ))?;
        self.store_pattern(sparsity)
    }

    /// Inserts a zero at every entry of `sparsity` and assembles, so that the final assembly
    /// keeps the whole preallocated pattern (module docs). Collective.
    fn store_pattern(&mut self, sparsity: &Sparsity) -> Result<()> {
        let widest = sparsity.rows.iter().map(Vec::len).max().unwrap_or(0);
        let zeros = vec![0.0; widest];
        for (i, cols) in sparsity.rows.iter().enumerate() {
            let row = to_petsc_int(sparsity.row_start + i)?;
            chk!(MatSetValues(
                self.raw,
                1,
                &row,
                to_petsc_int(cols.len())?,
                cols.as_ptr(),
                zeros.as_ptr(),
                p::InsertMode::INSERT_VALUES
            ))?;
        }
        self.assemble()
    }

    /// Lets entries outside the preallocated pattern be added (PETSc reallocates, slowly) instead
    /// of failing: for contact, whose stencils move with the sliding bodies.
    pub fn allow_new_nonzeros(&mut self) -> Result<()> {
        chk!(MatSetOption(
            self.raw,
            p::MatOption::MAT_NEW_NONZERO_ALLOCATION_ERR,
            p::PetscBool::PETSC_FALSE
        ))
    }

    /// The entries this rank's rows store (`MatGetInfo`'s `nz_used`): the preallocated pattern
    /// and every entry added outside it since, once assembled. It never shrinks (PETSc's own
    /// count of reallocations, `mallocs`, restarts when an assembly rebuilds the off-diagonal
    /// block for a new column).
    pub fn stored_entries(&self) -> Result<u64> {
        Ok(local_info(self.raw)?.nz_used as u64)
    }

    /// Wraps a matrix PETSc passes to a callback, taking a reference so that drop is balanced.
    ///
    /// # Safety
    /// `raw` must be a valid PETSc `Mat`.
    pub(crate) unsafe fn from_borrowed(raw: p::Mat) -> Result<Matrix> {
        chk!(PetscObjectReference(raw as p::PetscObject))?;
        Ok(Matrix { raw })
    }

    /// Sets all stored entries to zero (keeps the pattern).
    pub fn zero_entries(&mut self) -> Result<()> {
        chk!(MatZeroEntries(self.raw))
    }

    /// Adds a dense block (row-major, `rows.len() x cols.len()`) at global indices; negative
    /// indices are ignored (constrained dofs). Rows owned by other ranks are communicated at
    /// [`Matrix::assemble`].
    ///
    /// # Panics
    /// If `vals` does not hold `rows.len() * cols.len()` entries.
    pub fn add_values(&mut self, rows: &[PetscInt], cols: &[PetscInt], vals: &[f64]) -> Result<()> {
        assert_eq!(
            rows.len() * cols.len(),
            vals.len(),
            "Matrix::add_values: wrong block size"
        );
        add_values_raw(self.raw, rows, cols, vals)
    }

    /// Final assembly (communicates off-rank entries).
    pub fn assemble(&mut self) -> Result<()> {
        chk!(MatAssemblyBegin(
            self.raw,
            p::MatAssemblyType::MAT_FINAL_ASSEMBLY
        ))?;
        chk!(MatAssemblyEnd(
            self.raw,
            p::MatAssemblyType::MAT_FINAL_ASSEMBLY
        ))
    }

    /// Values of owned entries `(row, col)` (for tests and diagnostics).
    pub fn get_values(&self, rows: &[PetscInt], cols: &[PetscInt]) -> Result<Vec<f64>> {
        let mut vals = vec![0.0; rows.len() * cols.len()];
        assert!(vals.len() == rows.len() * cols.len());
        chk!(MatGetValues(
            self.raw,
            to_petsc_int(rows.len())?,
            rows.as_ptr(),
            to_petsc_int(cols.len())?,
            cols.as_ptr(),
            vals.as_mut_ptr()
        ))?;
        Ok(vals)
    }

    /// Attaches a near null space (PETSc's `MatSetNearNullSpace`): for elasticity the rigid
    /// body modes, which algebraic multigrid (`-pc_type gamg`) needs to build its coarse spaces;
    /// direct solvers ignore it. `modes` hold the owned rows of each vector; they are
    /// orthonormalized here (modified Gram-Schmidt), as PETSc requires. A mode that is
    /// (numerically) in the span of the earlier ones is dropped. Collective.
    pub fn set_near_null_space(&mut self, modes: &[Vec<f64>]) -> Result<()> {
        let space = NullSpace::of(modes)?;
        // The matrix takes its own reference to the space.
        chk!(MatSetNearNullSpace(self.raw, space.raw))
    }

    /// `y = A x`.
    pub fn mult(&self, x: &super::Vector, y: &mut super::Vector) -> Result<()> {
        chk!(MatMult(self.raw, x.raw, y.raw))
    }

    /// Whether the matrix is assembled (`MatAssembled`): an evaluation that failed midway may
    /// leave it open.
    pub fn is_assembled(&self) -> Result<bool> {
        let mut assembled = p::PetscBool::PETSC_FALSE;
        chk!(MatAssembled(self.raw, &mut assembled))?;
        Ok(assembled == p::PetscBool::PETSC_TRUE)
    }

    /// The diagonal of the owned rows (`MatGetDiagonal`), into `d`.
    pub fn diagonal(&self, d: &mut super::Vector) -> Result<()> {
        chk!(MatGetDiagonal(self.raw, d.raw))
    }
}

/// `MatSetValues` with `ADD_VALUES` of a dense row-major block (sizes checked by the callers).
pub(super) fn add_values_raw(
    raw: p::Mat,
    rows: &[PetscInt],
    cols: &[PetscInt],
    vals: &[f64],
) -> Result<()> {
    chk!(MatSetValues(
        raw,
        to_petsc_int(rows.len())?,
        rows.as_ptr(),
        to_petsc_int(cols.len())?,
        cols.as_ptr(),
        vals.as_ptr(),
        p::InsertMode::ADD_VALUES
    ))
}

impl Drop for Matrix {
    fn drop(&mut self) {
        if super::is_finalized() {
            return;
        }
        // SAFETY: `raw` is a valid Mat we hold a reference to.
        let code = unsafe { p::MatDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!("MatDestroy returned error code {code}"));
        }
    }
}

/// A (near) null space of vectors; destroyed on drop (the objects it is given to keep their own
/// references).
pub struct NullSpace {
    pub(crate) raw: p::MatNullSpace,
}

impl NullSpace {
    /// The space spanned by `modes` (each the owned rows of one vector), orthonormalized here
    /// (modified Gram-Schmidt), as PETSc requires; a mode that is (numerically) in the span of
    /// the earlier ones is dropped. Collective.
    pub fn of(modes: &[Vec<f64>]) -> Result<NullSpace> {
        let mut basis: Vec<super::Vector> = Vec::with_capacity(modes.len());
        for mode in modes {
            let mut v = super::Vector::new_mpi(mode.len())?;
            v.with_local_mut(|local| local.copy_from_slice(mode))?;
            let size = v.norm2()?;
            for b in &basis {
                let along = v.dot(b)?;
                v.axpy(-along, b)?;
            }
            let rest = v.norm2()?;
            // The same decision on every rank: the norms are global.
            if rest <= 1e-10 * size || rest == 0.0 {
                continue;
            }
            v.scale(1.0 / rest)?;
            basis.push(v);
        }
        let raw: Vec<p::Vec> = basis.iter().map(|v| v.raw).collect();
        let mut space: p::MatNullSpace = std::ptr::null_mut();
        chk!(MatNullSpaceCreate(
            super::comm(),
            p::PetscBool::PETSC_FALSE,
            to_petsc_int(raw.len())?,
            raw.as_ptr(),
            &mut space
        ))?;
        Ok(NullSpace { raw: space })
    }
}

impl Drop for NullSpace {
    fn drop(&mut self) {
        // SAFETY: `raw` is a valid MatNullSpace owned by this struct.
        let code = unsafe { p::MatNullSpaceDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!(
                "MatNullSpaceDestroy returned error code {code}"
            ));
        }
    }
}

/// `MatGetInfo` of this rank's part of `mat` (`MAT_LOCAL`).
pub(super) fn local_info(mat: p::Mat) -> Result<p::MatInfo> {
    let mut info = std::mem::MaybeUninit::<p::MatInfo>::uninit();
    chk!(MatGetInfo(
        mat,
        p::MatInfoType::MAT_LOCAL,
        info.as_mut_ptr()
    ))?;
    // SAFETY: MatGetInfo filled `info`.
    Ok(unsafe { info.assume_init() })
}
