//! PETSc error codes as `Result`s with PETSc's message.
//!
//! A handler pushed with `PetscPushErrorHandler` records the message of the first (initial) error
//! raised on this thread; [`check`] turns a non-zero code into `Error::Petsc` with that message,
//! the name of the PETSc function and the caller's Rust location.

use std::cell::RefCell;
use std::ffi::CStr;
use std::os::raw::{c_char, c_int, c_void};

use petsc_ffi as p;

use crate::error::{Error, Result};

thread_local! {
    static LAST_MESSAGE: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Records PETSc's message of the initial error and returns the code unchanged (no printing).
pub(super) unsafe extern "C" fn capture_error(
    _comm: p::MPI_Comm,
    line: c_int,
    func: *const c_char,
    file: *const c_char,
    code: p::PetscErrorCode,
    kind: p::PetscErrorType,
    mess: *const c_char,
    _ctx: *mut c_void,
) -> p::PetscErrorCode {
    if kind == p::PetscErrorType::PETSC_ERROR_INITIAL {
        // SAFETY: PETSc passes NUL-terminated strings or null.
        let text = |s: *const c_char| {
            if s.is_null() {
                String::new()
            } else {
                unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned()
            }
        };
        let mut msg = text(mess);
        if msg.is_empty() {
            let mut generic: *const c_char = std::ptr::null();
            // SAFETY: PetscErrorMessage writes a pointer to a static string.
            unsafe { p::PetscErrorMessage(code, &mut generic, std::ptr::null_mut()) };
            msg = text(generic);
        }
        // One line: PETSc's messages may span several.
        let msg = msg.split_whitespace().collect::<Vec<_>>().join(" ");
        let msg = format!("{msg} (in {}() at {}:{line})", text(func), text(file));
        LAST_MESSAGE.with(|m| *m.borrow_mut() = Some(msg));
    }
    code
}

/// Turns a PETSc error code into a `Result`.
#[track_caller]
pub fn check(code: p::PetscErrorCode, call: &'static str) -> Result<()> {
    if code == 0 {
        return Ok(());
    }
    let msg = LAST_MESSAGE
        .with(|m| m.borrow_mut().take())
        .unwrap_or_else(|| "no message".to_string());
    Err(Error::Petsc {
        code,
        call,
        location: std::panic::Location::caller(),
        msg,
    })
}
