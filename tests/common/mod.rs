//! Helpers shared by the integration tests:
//!
//! - [`run`]: write a scene into a fresh folder, run the `mortar` binary (alone, or under
//!   `mpirun -n N --timeout`), stop it with a signal;
//! - [`results`]: read what a run wrote (summary, displacements, metrics) and printed;
//! - [`scenes`]: the case texts that several test files build, each built once.

#![allow(dead_code, unused_imports)]

pub mod results;
pub mod run;
pub mod scenes;

pub use results::*;
pub use run::*;
pub use scenes::*;
