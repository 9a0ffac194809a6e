/* Values and calls that PETSc, OpenMPI and the C library expose only as macros, and glibc's
 * malloc_trim. No logic lives here. */
#include <malloc.h>
#include <signal.h>
#include <petscsys.h>
#include <mpi.h>

MPI_Comm petsc_ffi_comm_world(void) { return MPI_COMM_WORLD; }
MPI_Comm petsc_ffi_comm_self(void) { return MPI_COMM_SELF; }
size_t petsc_ffi_sizeof_petscint(void) { return sizeof(PetscInt); }
size_t petsc_ffi_sizeof_petscscalar(void) { return sizeof(PetscScalar); }
size_t petsc_ffi_sizeof_petscreal(void) { return sizeof(PetscReal); }
/* PetscFree, a macro: frees memory PETSc allocated for the caller (PetscOptionsGetAll's string). */
PetscErrorCode petsc_ffi_free(void *p) { return PetscFree(p); }
/* glibc's malloc_trim(0), for the allocator PETSc, MUMPS and Rust share: hands the free memory
 * of every arena back to the OS. */
int petsc_ffi_malloc_trim(void) { return malloc_trim(0); }
/* signal(sig, SIG_DFL) (SIG_DFL is a macro): the signal's default action again, whatever
 * handler was there. */
void petsc_ffi_default_signal(int sig) { signal(sig, SIG_DFL); }
/* Whether `sig`'s disposition is SIG_IGN (a macro): a background job of a script starts with
 * SIGINT ignored, and should keep it so. */
int petsc_ffi_signal_ignored(int sig) {
    struct sigaction action;
    return sigaction(sig, NULL, &action) == 0 && action.sa_handler == SIG_IGN;
}
