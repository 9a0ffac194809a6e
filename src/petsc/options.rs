//! PETSc's options database.

use std::ffi::CString;

use petsc_ffi as p;

use super::chk;
use crate::error::Result;

/// True when `-name` is set (with any value).
pub fn has(name: &str) -> Result<bool> {
    let c = CString::new(name).expect("option names have no NUL");
    let mut set = p::PetscBool::PETSC_FALSE;
    chk!(PetscOptionsHasName(
        std::ptr::null_mut(),
        std::ptr::null(),
        c.as_ptr(),
        &mut set
    ))?;
    Ok(set == p::PetscBool::PETSC_TRUE)
}

/// Sets `-name value` unless the user already set `-name` (a default that options override).
pub fn set_default(name: &str, value: &str) -> Result<()> {
    if has(name)? {
        return Ok(());
    }
    let n = CString::new(name).expect("option names have no NUL");
    let v = CString::new(value).expect("option values have no NUL");
    chk!(PetscOptionsSetValue(
        std::ptr::null_mut(),
        n.as_ptr(),
        v.as_ptr()
    ))
}
