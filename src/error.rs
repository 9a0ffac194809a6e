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
    #[error("{}: {msg}", file.display())]
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
    /// An invalid PETSc option (the same on every rank).
    #[error("PETSc options ({source_name}): {msg}")]
    Options { source_name: String, msg: String },
    /// Output files that could not be written, agreed on by every rank (the first failing
    /// rank's error: path and reason).
    #[error("output: {0}")]
    Output(String),
    /// A physical failure inside a solve (inverted element, NaN, diverged Newton).
    #[error("solve: {0}")]
    Solve(String),
    /// A run or study stopped by SIGINT or SIGTERM, agreed on by every rank
    /// ([`crate::interrupt`]): the signal and what was finished.
    #[error("{0}")]
    Interrupted(String),
    /// A restart refused (no checkpoint, a damaged one, one of another case, mesh, rank count
    /// or program version), agreed on by every rank; nothing in the output folder changed.
    #[error("restart: {0}")]
    Restart(String),
    /// Declared expectations (`expect`) that the measured metrics do not meet.
    #[error("expect: {0}")]
    Expectation(String),
    /// An error already reported by another rank (or by this one): exit 1, print nothing.
    #[error("(reported)")]
    Reported,
    /// Anything else with a clear message.
    #[error("{0}")]
    Other(String),
}

impl Error {
    /// True for errors every rank meets at the same point (the same input, the same collective
    /// solver outcome): reported once by rank 0, and every rank ends normally. Any other error
    /// may be one rank's alone, while the others wait in a collective call.
    pub fn is_collective(&self) -> bool {
        matches!(
            self,
            Error::Case { .. }
                | Error::Mesh(_)
                | Error::Gmsh { .. }
                | Error::Options { .. }
                | Error::Output(_)
                | Error::Solve(_)
                | Error::Interrupted(_)
                | Error::Restart(_)
                | Error::Expectation(_)
        )
    }

    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Error {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

thread_local! {
    static CONTEXT: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with `label` (a study's "study F: variant 'v' at level 0") as the context of the
/// errors that end the job from inside `f` without returning to the caller that would name
/// it: one rank's own error on more than one rank ([`abort_line`]).
pub fn with_context<R>(label: String, f: impl FnOnce() -> R) -> R {
    let before = CONTEXT.with(|c| c.replace(Some(label)));
    let result = f();
    CONTEXT.with(|c| *c.borrow_mut() = before);
    result
}

/// The line printed for one rank's own error before the job is aborted: the rank, the context
/// ([`with_context`]) if any, and the error.
pub fn abort_line(rank: i32, e: &Error) -> String {
    match CONTEXT.with(|c| c.borrow().clone()) {
        Some(label) => format!("[rank {rank}] {label}: {e}"),
        None => format!("[rank {rank}] {e}"),
    }
}

/// Prints `mortar: error: {message}` and a newline on stderr in a single write. `eprintln!`
/// writes a line in pieces (stderr is unbuffered), and mpirun forwards each rank's stderr in
/// the pieces it reads, so a line of one rank could be split by another's output or mpirun's
/// own.
pub fn print_error(message: impl std::fmt::Display) {
    print_line("error", message);
}

/// Prints `mortar: warning: {message}` and a newline on stderr in a single write, as
/// [`print_error`].
pub fn print_warning(message: impl std::fmt::Display) {
    print_line("warning", message);
}

fn print_line(kind: &str, message: impl std::fmt::Display) {
    use std::io::Write as _;
    let line = format!("mortar: {kind}: {message}\n");
    let _ = std::io::stderr().write_all(line.as_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn abort_lines_carry_the_context_they_were_made_in() {
        let e = Error::Other("boom".into());
        assert_eq!(abort_line(1, &e), "[rank 1] boom");
        let inside = with_context("study s.toml: variant 'v' at level 2".into(), || {
            let nested = with_context("inner".into(), || abort_line(0, &e));
            assert_eq!(nested, "[rank 0] inner: boom");
            abort_line(0, &e)
        });
        assert_eq!(
            inside,
            "[rank 0] study s.toml: variant 'v' at level 2: boom"
        );
        assert_eq!(abort_line(0, &e), "[rank 0] boom");
    }
}
