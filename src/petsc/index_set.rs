//! Index sets (PETSc `IS`): lists of global indices, here the owned rows of one field of a
//! field-split preconditioner.

use petsc_ffi as p;

use super::matrix::NullSpace;
use super::{chk, PetscInt};
use crate::error::Result;

/// A parallel index set of this rank's indices; destroyed on drop.
pub struct IndexSet {
    pub(crate) raw: p::IS,
}

impl IndexSet {
    /// The set of `indices` (this rank's part; copied). Collective.
    pub fn new(indices: &[PetscInt]) -> Result<IndexSet> {
        let mut raw: p::IS = std::ptr::null_mut();
        chk!(ISCreateGeneral(
            super::comm(),
            super::to_petsc_int(indices.len())?,
            indices.as_ptr(),
            p::PetscCopyMode::PETSC_COPY_VALUES,
            &mut raw
        ))?;
        Ok(IndexSet { raw })
    }

    /// Attaches `space` as the near null space of the submatrix on this set (PETSc's field
    /// split reads it from the set, named `nearnullspace`, and passes it to the submatrix).
    pub fn attach_near_null_space(&self, space: &NullSpace) -> Result<()> {
        chk!(PetscObjectCompose(
            self.raw as p::PetscObject,
            c"nearnullspace".as_ptr(),
            space.raw as p::PetscObject
        ))
    }
}

impl Drop for IndexSet {
    fn drop(&mut self) {
        // SAFETY: `raw` is a valid IS owned by this struct; PETSc keeps its own references.
        let code = unsafe { p::ISDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!("ISDestroy returned error code {code}"));
        }
    }
}
