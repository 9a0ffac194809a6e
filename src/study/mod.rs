//! Convergence studies: one scene run over a list of mesh refinements and variants, in one
//! process (`mortar study STUDY.toml`), measured against the mesh size; optionally, curves of the
//! runs' load histories compared between variants (force against displacement, say).
//!
//! The rooms, in the order a study goes through them:
//! - [`file`](mod@file): the study file, its keys (every key is documented where it is declared:
//!   [`StudyFile`], [`RefinementSpec`], [`VariantSpec`], [`CurvesSpec`]), loading and
//!   validating it into a [`Study`] ([`Study::load`]).
//! - [`edits`]: how a variant's and a refinement's `set` edit the case ([`set_path`]).
//! - [`run`]: running the study ([`Study::run`]): the order of the runs, the progress, the
//!   outputs rewritten after every run, failures and interrupts; [`one_run`]: one variant at one
//!   level, on its ranks with its PETSc options, its repeats and its peak memory.
//! - [`finest`]: errors against the finest run (`finest_reference`).
//! - [`curves`]: comparing the load curves of the variants (`[curves]`).
//! - [`pareto`]: the Pareto front of error against wall time ([`pareto_front`]).
//! - [`output`]: what a study writes (`study.csv`, `summary.json`, the plots).

pub mod curves;
pub mod edits;
pub mod file;
pub mod finest;
pub mod one_run;
pub mod output;
pub mod pareto;
pub mod run;

pub use curves::Curves;
pub use edits::set_path;
pub use file::{CurvesSpec, MetricSpec, RefinementSpec, Study, StudyFile, VariantSpec};
pub use output::RunRecord;
pub use pareto::{pareto_front, Ties};
pub use run::StudyReport;
