//! The output folder of a run: a rerun into it first removes what the earlier run of the case
//! wrote there, and a second run into a folder a run is writing into is refused.

mod common;

/// A rerun into the same folder first removes what the earlier run of the case wrote there
/// (`solver::results`): a run of 3 steps with two passes, then one of 2 steps with one pass,
/// leaves exactly the second run's files (no third step, no second pass's series, no temporary
/// file of a killed write) beside a file of the user's, which stays: a PVD of the earlier run's
/// would open as if it were the new run's.
#[test]
fn a_rerun_replaces_the_earlier_outputs() {
    let two_passes = common::slide_case(3).replace("friction = 0.3", "friction = 0.3\npasses = 2");
    let case = common::write_case("rerun_outputs", &two_passes);
    let (out, _) = common::run_case(&case, 1, &["-q"]);
    let name = common::summary(&out)["case"].as_str().unwrap().to_string();
    assert!(out.join(format!("{name}_slide_pass2.pvd")).is_file());
    assert!(out.join(format!("{name}_0003.pvtu")).is_file());
    std::fs::write(out.join("notes.txt"), "the user's").unwrap();
    std::fs::write(out.join(format!(".{name}.pvd.12345.tmp")), "killed").unwrap();

    std::fs::write(&case, common::slide_case(2)).unwrap();
    let (again, _) = common::run_case(&case, 1, &["-q"]);
    assert_eq!(again, out);
    let files = |dir: &std::path::Path| -> std::collections::BTreeSet<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    };
    let named = |names: &[&str]| -> std::collections::BTreeSet<String> {
        names.iter().map(|n| n.replace("{c}", &name)).collect()
    };
    assert_eq!(
        files(&out),
        named(&[
            "summary.json",
            "history.csv",
            "displacement.csv",
            "notes.txt",
            "vtu",
            ".mortar.lock",
            "{c}.pvd",
            "{c}_0001.pvtu",
            "{c}_0002.pvtu",
            "{c}_slide_pass1.pvd",
        ])
    );
    assert_eq!(
        files(&out.join("vtu")),
        named(&[
            "{c}_0001_r0.vtu",
            "{c}_0002_r0.vtu",
            "{c}_slide_pass1_0001.vtu",
            "{c}_slide_pass1_0002.vtu",
        ])
    );
}

/// A second run into a folder a run is writing into is refused at once, with one line naming
/// the folder (the two would mix their files: `summary.json` and `history.csv` have the same
/// names for every case); the first run ends unharmed, and a run after it works (the lock goes
/// with the process that held it; its empty file stays).
#[test]
fn a_folder_another_run_is_writing_into_is_refused() {
    let case = common::write_case("folder_in_use", &common::slide_case(100));
    let out_dir = case.parent().unwrap().join("out");
    let first = common::start_until(
        common::subcommand("run", &case, 1, &out_dir, &[]),
        "  step 2 ",
    );
    // Held still while the second run starts, so that it surely meets the first one running.
    first.signal(0, "STOP");
    let second = common::run_raw(&case, 1, &out_dir, &["-q"]);
    first.signal(0, "CONT");
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    let said = format!(
        "mortar: error: output: {}: another run is writing into this folder",
        out_dir.display()
    );
    assert!(lines[0].starts_with(&said), "{stderr}");
    let first = first.finish();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let s = common::summary(&out_dir);
    assert_eq!(s["converged"], true);
    assert_eq!(s["steps"].as_array().unwrap().len(), 100);
    let third = common::run_raw(&case, 1, &out_dir, &["-q"]);
    assert!(
        third.status.success(),
        "{}",
        String::from_utf8_lossy(&third.stderr)
    );
}
