//! `mortar`: mortar segment-to-segment frictional contact between deforming solids
//! (Puso, Laursen & Solberg 2004), on PETSc and MPI.
//!
//! Modules by concern:
//! - [`petsc`]: the only unsafe code outside `ffi/`: PETSc objects with RAII, errors as `Result`.
//! - [`mesh`]: meshes, generators, partitioning.
//! - [`fe`]: element topology, shape functions, quadrature.
//! - [`material`]: constitutive laws (physics only).
//! - [`solid`]: element residuals and tangents of the bulk, surface loads.
//! - [`model`]: the contributions of the discrete model (bulk, tying, contact) and what they hand
//!   the solver.
//! - [`dofs`]: ownership, PETSc numbering, ghosts and sparsity.
//! - [`solver`]: load stepping, Newton through SNES, step cutting.
//! - [`io`]: case files, Gmsh import, VTU/PVD output, CSV history, summary.
//! - [`case`]: the validated scene a run is made of.
//! - [`interrupt`]: a graceful stop on SIGINT and SIGTERM.

pub mod case;
pub mod contact;
pub mod dofs;
pub mod error;
pub mod expect;
pub mod family;
pub mod fe;
pub mod interrupt;
pub mod io;
pub mod material;
pub mod memory;
pub mod mesh;
pub mod model;
pub mod petsc;
pub mod scaling;
pub mod solid;
pub mod solver;
pub mod study;
#[cfg(test)]
mod test_rng;
pub mod vec3;
pub mod verify;

pub use error::{Error, Result};

/// Largest magnitude accepted for an input quantity (a coordinate, length, modulus, prescribed
/// displacement or load): beyond it the quantities formed from them (squares, stiffness times
/// displacement) overflow. Checked where the input is read.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// A finite value within [`MAX_MAGNITUDE`].
pub fn within_bounds(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_MAGNITUDE
}
