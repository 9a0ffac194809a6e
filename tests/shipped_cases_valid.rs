//! Every file shipped in `cases/` is valid: each scene passes `mortar check`, and each study
//! reads and validates, so that one no test runs cannot rot unnoticed.

mod common;

/// Every scene shipped in cases/ passes `mortar check`: each folder's `case.toml`, and the other
/// case files beside it (the levels of `cases/refinement`), every `.toml` but the studies.
#[test]
fn every_shipped_case_is_valid() {
    let cases = common::cases_dir();
    let mut n = 0;
    for scene in std::fs::read_dir(&cases).unwrap() {
        let scene = scene.unwrap().path();
        if !scene.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&scene).unwrap() {
            let case = file.unwrap().path();
            let name = case.file_name().unwrap().to_string_lossy().into_owned();
            if !name.ends_with(".toml") || name.starts_with("study") {
                continue;
            }
            n += 1;
            let out = common::mortar_command()
                .arg("check")
                .arg(&case)
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}: {}",
                case.display(),
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    assert!(n >= 16, "{n} case files");
}

/// Every study shipped in cases/ reads and validates (every variant x refinement of its case:
/// paths, keys, meshes), so that one no test runs cannot rot unnoticed.
#[test]
fn every_shipped_study_is_valid() {
    let cases = common::cases_dir();
    let mut studies = Vec::new();
    for scene in std::fs::read_dir(&cases).unwrap() {
        let scene = scene.unwrap().path();
        if !scene.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(scene).unwrap() {
            let path = file.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if name.starts_with("study") && name.ends_with(".toml") {
                studies.push(path);
            }
        }
    }
    assert!(studies.len() >= 9, "{studies:?}");
    for path in studies {
        if let Err(e) = mortar::study::Study::load(&path) {
            panic!("{}: {e}", path.display());
        }
    }
}
