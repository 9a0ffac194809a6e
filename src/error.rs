//! The project-wide error type.
//!
//! Every failure a user can cause (a bad case file, mesh or option) ends as one of these, printed
//! as a single line naming the culprit, and a non-zero exit. Programming errors may still panic;
//! user input never does.

use std::path::PathBuf;

/// Result with the project's error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong, by concern.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A case-file or study-file problem: the key (dotted path) and what is wrong with it.
    #[error("case file {file}: {msg}")]
    Case { file: PathBuf, msg: String },
    /// A mesh problem: names the element, node or set.
    #[error("mesh: {0}")]
    Mesh(String),
    /// A Gmsh file that cannot be read.
    #[error("gmsh file {file}: {msg}")]
    Gmsh { file: PathBuf, msg: String },
    /// An I/O failure on a named file.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A PETSc error code, with PETSc's message and the Rust location of the call.
    #[error("PETSc error {code} in {call} at {location}: {msg}")]
    Petsc {
        code: i32,
        call: &'static str,
        location: &'static std::panic::Location<'static>,
        msg: String,
    },
    /// A physical failure inside a solve (inverted element, NaN, diverged Newton).
    #[error("solve: {0}")]
    Solve(String),
    /// Anything else with a clear message.
    #[error("{0}")]
    Other(String),
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Error {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
