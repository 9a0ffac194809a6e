//! Distributed vectors (`Vec`), owned or borrowed from a PETSc callback.

use petsc_ffi as p;

use super::{chk, to_petsc_int, PetscInt};
use crate::error::Result;

/// A PETSc vector; destroyed (its reference released) on drop.
pub struct Vector {
    pub(crate) raw: p::Vec,
}

impl Vector {
    /// A distributed (MPI) vector with `local` entries on this rank.
    pub fn new_mpi(local: usize) -> Result<Vector> {
        super::ensure_initialized()?;
        let mut raw: p::Vec = std::ptr::null_mut();
        chk!(VecCreateMPI(
            super::comm(),
            to_petsc_int(local)?,
            p::PETSC_DETERMINE,
            &mut raw
        ))?;
        Ok(Vector { raw })
    }

    /// A sequential vector of length `n` on this rank only.
    pub fn new_seq(n: usize) -> Result<Vector> {
        super::ensure_initialized()?;
        let mut raw: p::Vec = std::ptr::null_mut();
        chk!(VecCreateSeq(super::comm_self(), to_petsc_int(n)?, &mut raw))?;
        Ok(Vector { raw })
    }

    /// Wraps a vector PETSc passes to a callback, taking a reference so that drop is balanced.
    ///
    /// # Safety
    /// `raw` must be a valid PETSc `Vec`.
    pub(crate) unsafe fn from_borrowed(raw: p::Vec) -> Result<Vector> {
        chk!(PetscObjectReference(raw as p::PetscObject))?;
        Ok(Vector { raw })
    }

    /// A new vector with the same layout (values not copied).
    pub fn duplicate(&self) -> Result<Vector> {
        let mut raw: p::Vec = std::ptr::null_mut();
        chk!(VecDuplicate(self.raw, &mut raw))?;
        Ok(Vector { raw })
    }

    /// A new vector with the same layout and values.
    pub fn copy(&self) -> Result<Vector> {
        let mut copy = self.duplicate()?;
        self.copy_to(&mut copy)?;
        Ok(copy)
    }

    /// Copies the values of `self` into `dst` (same layout).
    pub fn copy_to(&self, dst: &mut Vector) -> Result<()> {
        chk!(VecCopy(self.raw, dst.raw))
    }

    /// Sets every entry to `value`.
    pub fn set_all(&mut self, value: f64) -> Result<()> {
        chk!(VecSet(self.raw, value))
    }

    /// Global index range `[lo, hi)` owned by this rank.
    pub fn ownership_range(&self) -> Result<(usize, usize)> {
        let (mut lo, mut hi): (PetscInt, PetscInt) = (0, 0);
        chk!(VecGetOwnershipRange(self.raw, &mut lo, &mut hi))?;
        Ok((lo as usize, hi as usize))
    }

    /// Global length.
    pub fn global_size(&self) -> Result<usize> {
        let mut n: PetscInt = 0;
        chk!(VecGetSize(self.raw, &mut n))?;
        Ok(n as usize)
    }

    /// Adds (or inserts) values at global indices; negative indices (constrained dofs) are
    /// skipped. Call [`Vector::assemble`] afterwards.
    ///
    /// # Panics
    /// If `idx` and `vals` differ in length (PETSc would read past `vals`).
    pub fn set_values(&mut self, idx: &[PetscInt], vals: &[f64], add: bool) -> Result<()> {
        assert_eq!(idx.len(), vals.len(), "Vector::set_values: lengths differ");
        if idx.iter().any(|&i| i < 0) {
            // Vectors ignore negative indices only with VEC_IGNORE_NEGATIVE_INDICES, which
            // SNES's work vectors need not carry: filter here instead.
            let (i2, v2): (Vec<PetscInt>, Vec<f64>) = idx
                .iter()
                .zip(vals)
                .filter(|(&i, _)| i >= 0)
                .map(|(&i, &v)| (i, v))
                .unzip();
            return self.set_values(&i2, &v2, add);
        }
        let mode = if add {
            p::InsertMode::ADD_VALUES
        } else {
            p::InsertMode::INSERT_VALUES
        };
        chk!(VecSetValues(
            self.raw,
            to_petsc_int(idx.len())?,
            idx.as_ptr(),
            vals.as_ptr(),
            mode
        ))
    }

    /// Communicates values set for entries owned by other ranks.
    pub fn assemble(&mut self) -> Result<()> {
        chk!(VecAssemblyBegin(self.raw))?;
        chk!(VecAssemblyEnd(self.raw))
    }

    /// 2-norm.
    pub fn norm2(&self) -> Result<f64> {
        let mut n = 0.0;
        chk!(VecNorm(self.raw, p::NormType::NORM_2, &mut n))?;
        Ok(n)
    }

    /// `self *= alpha`.
    pub fn scale(&mut self, alpha: f64) -> Result<()> {
        chk!(VecScale(self.raw, alpha))
    }

    /// The inner product `self . x` (collective).
    pub fn dot(&self, x: &Vector) -> Result<f64> {
        let mut d = 0.0;
        chk!(VecDot(self.raw, x.raw, &mut d))?;
        Ok(d)
    }

    /// `self += alpha * x`.
    pub fn axpy(&mut self, alpha: f64, x: &Vector) -> Result<()> {
        chk!(VecAXPY(self.raw, alpha, x.raw))
    }

    /// Reads the locally owned entries.
    pub fn with_local<R>(&self, f: impl FnOnce(&[f64]) -> R) -> Result<R> {
        let mut n: PetscInt = 0;
        chk!(VecGetLocalSize(self.raw, &mut n))?;
        let mut ptr: *const f64 = std::ptr::null();
        chk!(VecGetArrayRead(self.raw, &mut ptr))?;
        // SAFETY: PETSc gives `n` readable entries until the matching restore below.
        let out = f(unsafe { super::slice_or_empty(ptr, n as usize) });
        chk!(VecRestoreArrayRead(self.raw, &mut ptr))?;
        Ok(out)
    }

    /// Reads and writes the locally owned entries.
    pub fn with_local_mut<R>(&mut self, f: impl FnOnce(&mut [f64]) -> R) -> Result<R> {
        let mut n: PetscInt = 0;
        chk!(VecGetLocalSize(self.raw, &mut n))?;
        let mut ptr: *mut f64 = std::ptr::null_mut();
        chk!(VecGetArray(self.raw, &mut ptr))?;
        let slice: &mut [f64] = if n == 0 {
            &mut []
        } else {
            // SAFETY: PETSc gives `n` writable entries until the matching restore below.
            unsafe { std::slice::from_raw_parts_mut(ptr, n as usize) }
        };
        let out = f(slice);
        chk!(VecRestoreArray(self.raw, &mut ptr))?;
        Ok(out)
    }

    /// Copy of the locally owned entries.
    pub fn to_local_vec(&self) -> Result<Vec<f64>> {
        self.with_local(|s| s.to_vec())
    }
}

impl Drop for Vector {
    fn drop(&mut self) {
        if super::is_finalized() {
            return;
        }
        // SAFETY: `raw` is a valid Vec we hold a reference to. An error cannot be returned from
        // Drop; report it rather than swallow it.
        let code = unsafe { p::VecDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!("VecDestroy returned error code {code}"));
        }
    }
}
