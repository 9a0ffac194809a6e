//! Gathering the entries a rank needs (owned and ghost) from a distributed vector.
//!
//! Each rank lists the global indices its elements touch; a `VecScatter` copies those entries of
//! the distributed solution into a sequential vector on the rank. PETSc does the communication.

use petsc_ffi as p;

use super::{chk, to_petsc_int, PetscInt, Vector};
use crate::error::Result;

/// A scatter from a distributed vector into a local sequential vector of chosen global entries.
pub struct Scatter {
    raw: p::VecScatter,
    local: Vector,
}

impl Scatter {
    /// Prepares gathering `global_indices` of vectors laid out like `template`.
    pub fn new(template: &Vector, global_indices: &[PetscInt]) -> Result<Scatter> {
        let local = Vector::new_seq(global_indices.len())?;
        let mut is: p::IS = std::ptr::null_mut();
        chk!(ISCreateGeneral(
            super::comm_self(),
            to_petsc_int(global_indices.len())?,
            global_indices.as_ptr(),
            p::PetscCopyMode::PETSC_COPY_VALUES,
            &mut is
        ))?;
        let mut raw: p::VecScatter = std::ptr::null_mut();
        let created = chk!(VecScatterCreate(
            template.raw,
            is,
            local.raw,
            std::ptr::null_mut(),
            &mut raw
        ));
        chk!(ISDestroy(&mut is))?;
        created?;
        Ok(Scatter { raw, local })
    }

    /// Gathers the chosen entries of `x` and returns them in the order of the indices.
    pub fn gather(&mut self, x: &Vector) -> Result<Vec<f64>> {
        let mode = p::InsertMode::INSERT_VALUES;
        let fwd = p::ScatterMode::SCATTER_FORWARD;
        chk!(VecScatterBegin(self.raw, x.raw, self.local.raw, mode, fwd))?;
        chk!(VecScatterEnd(self.raw, x.raw, self.local.raw, mode, fwd))?;
        self.local.to_local_vec()
    }
}

impl Drop for Scatter {
    fn drop(&mut self) {
        if super::is_finalized() {
            return;
        }
        // SAFETY: `raw` is a valid VecScatter owned by this struct.
        let code = unsafe { p::VecScatterDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!(
                "VecScatterDestroy returned error code {code}"
            ));
        }
    }
}
