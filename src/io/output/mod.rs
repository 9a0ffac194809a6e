//! Result files: VTK XML output for ParaView, the CSV load history and `summary.json`, and the
//! lock that keeps two runs out of one folder ([`lock_folder`]).
//!
//! This layer knows nothing about MPI: every function takes plain data, and the caller decides
//! which rank writes which file (typically each rank its own `.vtu` piece, rank 0 the `.pvtu`,
//! `.pvd`, history and summary).
//!
//! # Atomic writes
//!
//! Every file is written through [`write_atomic`]: the bytes go to a temporary file in the same
//! directory, named `.<file name>.<process id>.tmp`, which is flushed to disk (`fsync`) and then
//! renamed over the destination; on Unix the directory is synced afterwards (best effort). A
//! rename within one directory is atomic, so a run killed at any moment leaves every file either
//! in its previous complete state or in its new complete state, never truncated. Files that are
//! updated during a run (the `.pvd` series, the CSV history) are rewritten whole each time.
//!
//! No results file ever holds a NaN or an infinity: a non-finite value is an error naming the
//! field, column or metric, and nothing is written.
//!
//! # Formats
//!
//! - **`.vtu`** ([`write_vtu`]): one VTK XML `UnstructuredGrid` piece (file version 1.0,
//!   `byte_order="LittleEndian"`, `header_type="UInt64"`). Each `DataArray` is inline binary
//!   (`format="binary"`): base64 of one little-endian `UInt64` byte count followed by the raw
//!   little-endian values, encoded as a single stream. Points and fields are `Float64`,
//!   connectivity and offsets `Int64` (offsets are VTK end offsets), cell types `UInt8` (VTK cell
//!   type numbers; node ordering is VTK's, see [`crate::fe::element`]).
//! - **`.pvtu`** ([`write_pvtu`]): a `PUnstructuredGrid` declaring the point and cell fields
//!   (`Float64`, with their component counts) and listing the per-rank `.vtu` pieces by name
//!   relative to the `.pvtu` itself.
//! - **`.pvd`** ([`write_pvd`]): a VTK `Collection` with one `DataSet` per output time
//!   (`timestep`, `part="0"`, `file` relative to the `.pvd`). It is rewritten whole after every
//!   step, so ParaView can open it at any time during a run.
//! - **CSV history** ([`History`]): a header line of column names, then one line per row with
//!   numbers in Rust's shortest round-trip form (`{}`), comma-separated, `\n` line ends. Column
//!   names holding a comma, quote or line break are quoted as in RFC 4180. [`read_csv`] reads
//!   it back.
//! - **`summary.json`** ([`Summary`]): pretty-printed JSON of the run: case name, rank count,
//!   convergence, per-step records, timings and metrics (objects keyed by name, sorted), and the
//!   failure message (`null` on success).

mod base64;
mod history;
mod lock;
mod summary;
mod vtk;

pub use base64::{decode as base64_decode, encode as base64_encode};
pub use history::{read_csv, History};
pub use lock::{lock_folder, FolderLock};
pub use summary::{StepRecord, Summary};
pub use vtk::{vtu_document, write_pvd, write_pvtu, write_vtu, Field, Piece};

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Writes `bytes` to `path` atomically: a temporary `.<name>.<pid>.tmp` in the same directory,
/// `fsync`, then a rename over `path`. On failure the temporary file is removed and `path` is
/// left as it was.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path.file_name().ok_or_else(|| {
        Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"),
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = dir.join(tmp_name);

    let result = (|| {
        let mut file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    // Make the rename itself durable; some file systems refuse to sync directories.
    #[cfg(unix)]
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// The von Mises equivalent stress `sqrt(3/2 s':s')` of a Cauchy stress (its symmetric part;
/// `s'` is the deviator).
pub fn von_mises(s: &nalgebra::Matrix3<f64>) -> f64 {
    let sym = (s + s.transpose()) * 0.5;
    let dev = sym - nalgebra::Matrix3::identity() * (sym.trace() / 3.0);
    (1.5 * dev.norm_squared()).sqrt()
}

/// Escapes text for an XML attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// An error about the contents of results file `path`.
fn content_error(path: &Path, msg: impl std::fmt::Display) -> Error {
    Error::Other(format!("{}: {msg}", path.display()))
}

#[cfg(test)]
pub(crate) mod test_util {
    use std::path::PathBuf;

    /// A fresh, empty scratch directory for one test; removed on drop.
    pub struct Scratch(pub PathBuf);

    impl Scratch {
        pub fn new(name: &str) -> Scratch {
            let dir =
                std::env::temp_dir().join(format!("mortar-output-{}-{name}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            Scratch(dir)
        }

        pub fn path(&self, name: &str) -> PathBuf {
            self.0.join(name)
        }

        /// The names of the files in the directory, sorted.
        pub fn listing(&self) -> Vec<String> {
            let mut names: Vec<String> = std::fs::read_dir(&self.0)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            names
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::test_util::Scratch;
    use super::*;
    use nalgebra::Matrix3;

    #[test]
    fn atomic_write_leaves_no_temporary_file() {
        let dir = Scratch::new("atomic");
        let p = dir.path("result.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second, longer").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second, longer");
        assert_eq!(dir.listing(), vec!["result.txt".to_string()]);
    }

    #[test]
    fn atomic_write_failure_names_path_and_keeps_nothing() {
        let dir = Scratch::new("atomic-fail");
        let p = dir.path("missing/result.txt");
        let err = write_atomic(&p, b"x").unwrap_err();
        assert!(matches!(err, Error::Io { .. }));
        assert!(err.to_string().contains("missing/result.txt"));
        assert!(dir.listing().is_empty());
    }

    #[test]
    fn von_mises_uniaxial_and_shear() {
        for s in [250.0, -3.5e8] {
            for axis in 0..3 {
                let mut m = Matrix3::zeros();
                m[(axis, axis)] = s;
                assert!((von_mises(&m) - f64::abs(s)).abs() <= 1e-12 * f64::abs(s));
            }
        }
        let tau = 42.0;
        let mut m = Matrix3::zeros();
        m[(0, 2)] = tau;
        m[(2, 0)] = tau;
        assert!((von_mises(&m) - 3f64.sqrt() * tau).abs() < 1e-12 * tau);
        // Hydrostatic stress has no deviator.
        assert!(von_mises(&(Matrix3::identity() * -7.0)).abs() < 1e-12);
    }

    #[test]
    fn xml_escaping() {
        assert_eq!(xml_escape(r#"a<b>&"c'"#), "a&lt;b&gt;&amp;&quot;c&apos;");
    }
}
