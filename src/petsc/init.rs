//! The initialization guard: MPI first (rsmpi), then PETSc; PETSc finalized before MPI.

use std::ffi::CString;
use std::os::raw::c_char;
use std::path::Path;

use std::cell::RefCell;
use std::rc::Rc;

use mpi::collective::CommunicatorCollectives;
use mpi::raw::AsRaw;
use mpi::topology::{Color, Communicator, SimpleCommunicator};
use petsc_ffi as p;

use super::chk;
use crate::error::{Error, Result};

/// Owns MPI and PETSc for the life of the program. Create exactly one, early in `main`.
pub struct Petsc {
    // Keep the argv strings alive: PETSc keeps pointers to them (PetscGetArgs).
    _args: Vec<CString>,
    _argv: Vec<*mut c_char>,
    universe: mpi::environment::Universe,
    /// The ranks of a run on fewer ranks than the job ([`Petsc::on_first_ranks`]).
    scope: RefCell<Option<Rc<SimpleCommunicator>>>,
    /// `PetscFinalize` has run ([`Petsc::finalize`]); `Drop` then leaves it.
    finalized: bool,
}

/// Initializes MPI (once per process).
pub fn start_mpi() -> Result<mpi::environment::Universe> {
    mpi::initialize()
        .ok_or_else(|| Error::Other("MPI was already initialized in this process".into()))
}

impl Petsc {
    /// Initializes MPI, then PETSc: [`start_mpi`] followed by [`Petsc::start`].
    pub fn initialize(args: &[String], options_file: Option<&Path>) -> Result<Petsc> {
        Petsc::start(start_mpi()?, args, options_file)
    }

    /// Initializes PETSc on an MPI already started by [`start_mpi`] (so a program can learn its
    /// rank, e.g. to report input errors once, before PETSc starts). `args` is the program name
    /// followed by the PETSc options; `options_file` (the scene's options) is read by PETSc
    /// before the command line, so command line options win.
    pub fn start(
        universe: mpi::environment::Universe,
        args: &[String],
        options_file: Option<&Path>,
    ) -> Result<Petsc> {
        check_sizes()?;
        let c_args: Vec<CString> = args
            .iter()
            .map(|a| {
                CString::new(a.as_str())
                    .map_err(|_| Error::Other(format!("argument '{a}' contains a NUL byte")))
            })
            .collect::<Result<_>>()?;
        let mut argv: Vec<*mut c_char> = c_args.iter().map(|c| c.as_ptr() as *mut c_char).collect();
        argv.push(std::ptr::null_mut());
        let mut argc = c_args.len() as i32;
        let mut argv_ptr = argv.as_mut_ptr();
        let file = match options_file {
            Some(f) => {
                if !f.is_file() {
                    return Err(Error::Other(format!(
                        "PETSc options file {} does not exist",
                        f.display()
                    )));
                }
                Some(CString::new(f.to_string_lossy().as_bytes()).map_err(|_| {
                    Error::Other(format!("options file path {} has a NUL byte", f.display()))
                })?)
            }
            None => None,
        };
        let file_ptr = file.as_ref().map_or(std::ptr::null(), |c| c.as_ptr());
        // The handler goes in before PetscInitialize (so an error reading the options file is
        // captured, not printed as a traceback) and again after it, in case initialization
        // reset the handler stack.
        chk!(PetscPushErrorHandler(
            Some(super::error::capture_error),
            std::ptr::null_mut()
        ))?;
        chk!(PetscInitialize(
            &mut argc,
            &mut argv_ptr,
            file_ptr,
            std::ptr::null()
        ))?;
        chk!(PetscPushErrorHandler(
            Some(super::error::capture_error),
            std::ptr::null_mut()
        ))?;
        // PETSc's signal handler reports a closed pipe (`mortar run ... | head`) as a crash
        // ("Caught signal number 13 Broken Pipe ... Try option -start_in_debugger"), and Rust
        // ignores the signal (a write then fails): a closed pipe now ends the run as it ends
        // any program. PETSc keeps its reports of the other signals (SEGV, FPE under
        // `-fp_trap`, ...).
        super::default_signal(signal_hook::consts::SIGPIPE);
        check_library_sizes()?;
        Ok(Petsc {
            _args: c_args,
            _argv: argv,
            universe,
            scope: RefCell::new(None),
            finalized: false,
        })
    }

    /// The ranks of the current run: every rank of the job, or inside
    /// [`Petsc::on_first_ranks`] the ranks running.
    pub fn world(&self) -> Rc<SimpleCommunicator> {
        match &*self.scope.borrow() {
            Some(c) => Rc::clone(c),
            None => Rc::new(self.universe.world()),
        }
    }

    /// Runs `f` on the first `ranks` ranks of the job only (collective over the job): inside,
    /// [`Petsc::world`], [`Petsc::rank`], [`Petsc::size`] and the communicator of every new
    /// PETSc object ([`super::comm`]) are those ranks'; the other ranks skip `f` (they get
    /// `None`) and wait for its end. `ranks` must be between 1 and the job's size; with the
    /// job's size this is `Some(f())` on every rank.
    pub fn on_first_ranks<R>(&self, ranks: usize, f: impl FnOnce() -> R) -> Option<R> {
        let world = self.universe.world();
        let size = world.size() as usize;
        assert!(
            (1..=size).contains(&ranks) && self.scope.borrow().is_none(),
            "on_first_ranks({ranks}) on a job of {size} ranks (not nested)"
        );
        if ranks == size {
            return Some(f());
        }
        let inside = (world.rank() as usize) < ranks;
        let color = if inside {
            Color::with_value(0)
        } else {
            Color::undefined()
        };
        let out = world.split_by_color(color).map(|sub| {
            // The same MPI communicator handle, in the bindings' type (both OpenMPI's
            // `ompi_communicator_t *`).
            super::set_run_comm(Some(sub.as_raw() as petsc_ffi::MPI_Comm));
            *self.scope.borrow_mut() = Some(Rc::new(sub));
            let out = f();
            super::set_run_comm(None);
            // Every PETSc object of the run is gone: the communicator is freed.
            self.scope.borrow_mut().take();
            out
        });
        world.barrier();
        out
    }

    /// Options set on the command line or in the options file that no PETSc object ever read,
    /// usually typos (`-snes_monitr`); `-options_left` lists them.
    pub fn unused_options(&self) -> Result<usize> {
        let mut n: p::PetscInt = 0;
        chk!(PetscOptionsAllUsed(std::ptr::null_mut(), &mut n))?;
        Ok(n.max(0) as usize)
    }

    /// This process's rank in [`Petsc::world`].
    pub fn rank(&self) -> usize {
        self.world().rank() as usize
    }

    /// Number of ranks of [`Petsc::world`].
    pub fn size(&self) -> usize {
        self.world().size() as usize
    }

    /// Hands the memory this process freed back to the OS (glibc's `malloc_trim`: PETSc's
    /// objects, MUMPS's factors and Rust's data share one allocator, which otherwise keeps
    /// what a large run freed, so that the resident memory of a later, smaller run starts at
    /// the larger one's peak). Between the runs of a study.
    pub fn release_free_memory(&self) {
        // SAFETY: malloc_trim only walks the allocator's own free lists.
        unsafe {
            p::petsc_ffi_malloc_trim();
        }
    }
}

impl Petsc {
    /// Ends PETSc (collective), reporting its failure: what PETSc writes at the end of a run
    /// (a `-log_view` file) may fail to be written, on one rank only, while the others wait
    /// inside `PetscFinalize`, so the caller should abort the job on an error. MPI ends when
    /// `self` drops, after this.
    pub fn finalize(&mut self) -> Result<()> {
        self.finalized = true;
        // SAFETY: as in `Drop`: every PETSc object of the program is gone by now (the caller
        // owns none; this guard was created first).
        chk!(PetscFinalize()).map_err(|e| {
            Error::Other(format!(
                "PETSc could not finish the run (what it writes at the end, such as a \
                 -log_view file, may be missing): {e}"
            ))
        })
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        if self.finalized {
            return;
        }
        // SAFETY: every PETSc object owned by the program is dropped before this guard (it is
        // created first in main and dropped last). A finalize error cannot be returned from
        // Drop; print it rather than lose it.
        let code = unsafe { p::PetscFinalize() };
        if code != 0 {
            crate::error::print_warning(format_args!(
                "PetscFinalize returned error code {code}: what PETSc writes at \
                 the end of a run (a -log_view file, say) may be missing"
            ));
        }
        // `universe` drops after this, calling MPI_Finalize.
    }
}

/// Asserts that the PETSc *library* in use (not only its headers) has the index and scalar sizes
/// the bindings assume, asking it at run time.
fn check_library_sizes() -> Result<()> {
    let (mut int, mut scalar) = (0usize, 0usize);
    chk!(PetscDataTypeGetSize(p::PetscDataType::PETSC_INT, &mut int))?;
    chk!(PetscDataTypeGetSize(
        p::PetscDataType::PETSC_DOUBLE,
        &mut scalar
    ))?;
    if int != std::mem::size_of::<p::PetscInt>() || scalar != std::mem::size_of::<f64>() {
        return Err(Error::Other(format!(
            "PETSc library mismatch: PetscInt {int} bytes and PetscReal {scalar} bytes at run time; \
             the bindings assume {} and 8",
            std::mem::size_of::<p::PetscInt>()
        )));
    }
    Ok(())
}

/// Asserts that the headers the bindings (and the shim) were compiled against have the index
/// and scalar sizes the bindings assume.
fn check_sizes() -> Result<()> {
    // SAFETY: plain functions returning sizeof values.
    let (int, scalar, real) = unsafe {
        (
            p::petsc_ffi_sizeof_petscint(),
            p::petsc_ffi_sizeof_petscscalar(),
            p::petsc_ffi_sizeof_petscreal(),
        )
    };
    let want = (
        std::mem::size_of::<p::PetscInt>(),
        std::mem::size_of::<f64>(),
        std::mem::size_of::<f64>(),
    );
    if (int, scalar, real) != want || std::mem::size_of::<p::PetscScalar>() != 8 {
        return Err(Error::Other(format!(
            "PETSc build mismatch: PetscInt {int} bytes, PetscScalar {scalar}, PetscReal {real}; \
             the bindings assume {} / 8 / 8 (real double, 32-bit indices)",
            want.0
        )));
    }
    Ok(())
}
