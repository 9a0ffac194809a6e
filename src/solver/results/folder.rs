//! The run's output folder: made, and emptied of an earlier run's outputs of the same case
//! (and only those).

use std::collections::BTreeSet;
use std::path::Path;

use crate::error::{Error, Result};

/// Creates `dir/vtu` and removes the outputs an earlier run of case `case` left in `dir`
/// ([`is_run_output`]) and its checkpoints ([`is_checkpoint_file`]); other files are left
/// alone.
pub(super) fn prepare_folder(dir: &Path, case: &str) -> Result<()> {
    let vtu = dir.join("vtu");
    std::fs::create_dir_all(&vtu).map_err(|e| Error::io(&vtu, e))?;
    for (folder, in_vtu) in [(dir, false), (vtu.as_path(), true)] {
        for path in run_outputs(folder, case, in_vtu)? {
            remove(&path)?;
        }
    }
    let checkpoints = dir.join(super::super::checkpoint::FOLDER);
    if let Ok(entries) = std::fs::read_dir(&checkpoints) {
        for entry in entries.flatten() {
            if entry.file_name().to_str().is_some_and(is_checkpoint_file) {
                remove(&entry.path())?;
            }
        }
    }
    Ok(())
}

/// The checkpoint files a fresh run removes (`solver::checkpoint`): `checkpoint/latest` and
/// `checkpoint/step_<k>_r<rank>.ckpt`, or their temporary files.
fn is_checkpoint_file(name: &str) -> bool {
    let name = temporary_target(name).unwrap_or(name);
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    name == "latest"
        || name
            .strip_prefix("step_")
            .and_then(|s| s.strip_suffix(".ckpt"))
            .and_then(|s| s.split_once("_r"))
            .is_some_and(|(k, r)| digits(k) && digits(r))
}

/// A restart: removes the series and step files of case `case` in `dir` that are not in
/// `kept` (paths relative to `dir`: those its checkpoint lists), and the temporary files of
/// writes a killed run left unfinished. The history, summary and displacements stay (they are
/// rewritten).
pub(super) fn remove_step_files(dir: &Path, case: &str, kept: &BTreeSet<String>) -> Result<()> {
    let vtu = dir.join("vtu");
    for (folder, in_vtu) in [(dir, false), (vtu.as_path(), true)] {
        for path in run_outputs(folder, case, in_vtu)? {
            let name = path
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or_default();
            let relative = if in_vtu {
                format!("vtu/{name}")
            } else {
                name.to_string()
            };
            let stays = matches!(name, "summary.json" | "history.csv" | "displacement.csv")
                || kept.contains(&relative);
            if !stays {
                remove(&path)?;
            }
        }
    }
    Ok(())
}

/// The files of `folder` a run of `case` writes ([`is_run_output`]); none if it does not exist.
fn run_outputs(folder: &Path, case: &str, in_vtu: bool) -> Result<Vec<std::path::PathBuf>> {
    let entries = match std::fs::read_dir(folder) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        entries => entries.map_err(|e| Error::io(folder, e))?,
    };
    let mut found = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(folder, e))?;
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        let name = entry.file_name();
        if is_file
            && name
                .to_str()
                .is_some_and(|n| is_run_output(n, case, in_vtu))
        {
            found.push(entry.path());
        }
    }
    Ok(found)
}

/// Removes `path`; one already gone is no error.
fn remove(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::io(path, e)),
        _ => Ok(()),
    }
}

/// Whether a file named `name` in a run's folder (or in its `vtu/` when `in_vtu`) is one a run
/// of case `case` writes: `summary.json`, `history.csv`, `displacement.csv`, `<case>.pvd`,
/// `<case>_<step>.pvtu`, `vtu/<case>_<step>_r<rank>.vtu`, and per interface pass
/// `<case>_<interface>_pass<p>.pvd` and `vtu/<case>_<interface>_pass<p>_<step>.vtu` (`<step>`
/// four digits or more), or the temporary file of one of these (`.<name>.<pid>.tmp`, left by a
/// killed run: `io::output::write_atomic`). Another case whose name extends this one's
/// (`<case>_big`) keeps its steps and pieces; only a file of its that reads as an interface
/// pass of this case (`<case>_big_pass1.pvd`, an interface `big`) would go.
fn is_run_output(name: &str, case: &str, in_vtu: bool) -> bool {
    let name = temporary_target(name).unwrap_or(name);
    if !in_vtu && matches!(name, "summary.json" | "history.csv" | "displacement.csv") {
        return true;
    }
    let Some(rest) = name.strip_prefix(case) else {
        return false;
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let step = |s: &str| s.len() >= 4 && digits(s);
    // `_<interface>_pass<p>` followed by `tail`.
    let pass = |s: &str, tail: &dyn Fn(&str) -> bool| {
        s.strip_prefix('_')
            .and_then(|s| s.rsplit_once("_pass"))
            .is_some_and(|(interface, p)| {
                let end = p.find(|c: char| !c.is_ascii_digit()).unwrap_or(p.len());
                !interface.is_empty() && end > 0 && tail(&p[end..])
            })
    };
    if in_vtu {
        let Some(rest) = rest.strip_suffix(".vtu") else {
            return false;
        };
        let piece = rest
            .strip_prefix('_')
            .and_then(|r| r.split_once("_r"))
            .is_some_and(|(s, r)| step(s) && digits(r));
        piece || pass(rest, &|t| t.strip_prefix('_').is_some_and(step))
    } else {
        rest == ".pvd"
            || rest
                .strip_prefix('_')
                .and_then(|r| r.strip_suffix(".pvtu"))
                .is_some_and(step)
            || rest
                .strip_suffix(".pvd")
                .is_some_and(|r| pass(r, &|t| t.is_empty()))
    }
}

/// The file a temporary file of `io::output::write_atomic` (`.<name>.<pid>.tmp`) was for.
fn temporary_target(name: &str) -> Option<&str> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (target, pid) = inner.rsplit_once('.')?;
    (!pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())).then_some(target)
}

#[cfg(test)]
mod tests {
    use super::{is_checkpoint_file, is_run_output, remove_step_files, temporary_target};
    use crate::io::output::test_util::Scratch;

    /// A restart keeps the files its checkpoint lists, the history, summary and displacements,
    /// and others' files; it removes the later steps' files and unfinished writes.
    #[test]
    fn a_restart_removes_the_step_files_its_checkpoint_does_not_list() {
        let dir = Scratch::new("restart-prune");
        std::fs::create_dir_all(dir.path("vtu")).unwrap();
        let kept = ["b.pvd", "b_0001.pvtu", "vtu/b_0001_r0.vtu", "b_s_pass1.pvd"];
        let stays = [
            "history.csv",
            "summary.json",
            "notes.txt",
            "vtu/other_0002_r0.vtu",
        ];
        let goes = [
            "b_0002.pvtu",
            "vtu/b_0002_r0.vtu",
            "vtu/b_s_pass1_0002.vtu",
            "b_t_pass1.pvd",
            ".b.pvd.77.tmp",
        ];
        for f in kept.iter().chain(&stays).chain(&goes) {
            std::fs::write(dir.path(f), "x").unwrap();
        }
        let listed = kept.iter().map(|s| s.to_string()).collect();
        remove_step_files(&dir.0, "b", &listed).unwrap();
        for f in kept.iter().chain(&stays) {
            assert!(dir.path(f).exists(), "{f}");
        }
        for f in goes {
            assert!(!dir.path(f).exists(), "{f}");
        }
        assert!(is_checkpoint_file("latest") && is_checkpoint_file("step_0012_r1.ckpt"));
        assert!(is_checkpoint_file(".step_0012_r1.ckpt.42.tmp"));
        for theirs in ["step_12.ckpt", "step_x_r1.ckpt", "latest.txt", "notes"] {
            assert!(!is_checkpoint_file(theirs), "{theirs}");
        }
    }

    #[test]
    fn a_run_removes_only_its_case_outputs() {
        let ours = [
            "summary.json",
            "history.csv",
            "displacement.csv",
            "blocks.pvd",
            "blocks_0003.pvtu",
            "blocks_contact_pass2.pvd",
            ".blocks.pvd.4242.tmp",
            ".summary.json.7.tmp",
        ];
        for name in ours {
            assert!(is_run_output(name, "blocks", false), "{name}");
        }
        let theirs = [
            "notes.txt",
            "blocksworld.pvd",
            "other.pvd",
            "blocks.vtu",
            "blocks.pvtu",
            "blocks_big.pvd",
            "blocks_big_0001.pvtu",
            "blocks_0001.pvd",
            "blocks_01.pvtu",
            "blocks_contact_pass.pvd",
            "blocks__pass1.pvd",
            "figure",
            ".blocks.pvd.tmp",
            ".blocks.pvd.12a.tmp",
            "summary.json.bak",
            "case.toml",
        ];
        for name in theirs {
            assert!(!is_run_output(name, "blocks", false), "{name}");
        }
        assert!(is_run_output("blocks_0001_r1.vtu", "blocks", true));
        assert!(is_run_output("blocks_12345_r10.vtu", "blocks", true));
        assert!(is_run_output(
            "blocks_contact_pass2_0003.vtu",
            "blocks",
            true
        ));
        assert!(is_run_output(
            "blocks_a_pass_b_pass1_0003.vtu",
            "blocks",
            true
        ));
        assert!(is_run_output(".blocks_0001_r0.vtu.99.tmp", "blocks", true));
        for theirs in [
            "other_0001_r0.vtu",
            "blocks.vtu",
            "blocks_big_0001_r0.vtu",
            "blocks_0001_r.vtu",
            "blocks_contact_pass2.vtu",
            "blocks_contact_pass_0003.vtu",
        ] {
            assert!(!is_run_output(theirs, "blocks", true), "{theirs}");
        }
        assert!(!is_run_output("summary.json", "blocks", true));
        assert_eq!(temporary_target(".a.b.12.tmp"), Some("a.b"));
        assert_eq!(temporary_target("a.12.tmp"), None);
    }
}
