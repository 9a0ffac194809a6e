//! A lock on an output folder, so that two runs (or studies) never write into one folder at
//! once: they would mix their files (`summary.json` and `history.csv` have the same names for
//! every case, and a study empties its run folders before each run).
//!
//! The lock is an advisory `flock` on `dir/.mortar.lock`, taken without waiting: a second
//! writer is refused at once. The system releases it when the process ends, however it ends
//! (a killed run leaves the empty file, never a stale lock), and the file is left in place: removing
//! it while locked would let two later runs lock two different files under the same name. On
//! a file system without `flock` (some parallel or network file systems) the folder goes
//! unlocked, with one warning. On NFS a lock may hold on one client only.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{print_warning, Error, Result};

/// The lock file's name in a locked folder.
const LOCK_FILE: &str = ".mortar.lock";

/// A folder's lock, held while this value lives.
#[derive(Debug)]
pub struct FolderLock {
    _file: std::fs::File,
}

/// Creates `dir` and takes its lock: `None` on a file system without locks. Only one rank of
/// a run takes it (rank 0: the writer of the shared files).
///
/// # Errors
/// [`Error::Other`] naming the folder when another process holds its lock; an I/O error when
/// the folder or the lock file cannot be made.
pub fn lock_folder(dir: &Path) -> Result<Option<FolderLock>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let path: PathBuf = dir.join(LOCK_FILE);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| Error::io(&path, e))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(FolderLock { _file: file })),
        Err(std::fs::TryLockError::WouldBlock) => Err(Error::Other(format!(
            "{}: another run is writing into this folder (it holds {LOCK_FILE}); wait for it \
             to end, or give this one another --out",
            dir.display()
        ))),
        Err(std::fs::TryLockError::Error(e)) if locks_unsupported(&e) => {
            static WARNED: AtomicBool = AtomicBool::new(false);
            if !WARNED.swap(true, Ordering::Relaxed) {
                print_warning(format_args!(
                    "{}: the file system takes no locks ({e}): nothing stops another run from \
                     writing into the same folder",
                    path.display()
                ));
            }
            Ok(None)
        }
        Err(std::fs::TryLockError::Error(e)) => Err(Error::io(&path, e)),
    }
}

/// Whether `e` says the file system has no `flock` (ENOLCK, ENOSYS, EOPNOTSUPP).
fn locks_unsupported(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::Unsupported || matches!(e.raw_os_error(), Some(37 | 38 | 95))
}
