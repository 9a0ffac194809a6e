//! `mortar scaling`: the PETSc logs of the contact patch scene on 1 and 2 ranks give a table of
//! every phase, `scaling.csv` whose phases add up to the logged stages, the plot, and the last
//! line `speedup: X` (the ratio of the logged wall times), without a panic when the reader of
//! its output goes away early; the same log twice, or a file that is not a PETSc log, is one
//! error line.

mod common;

use std::path::Path;

fn run_scaling(logs: &[&Path], out: &Path) -> std::process::Output {
    common::mortar_command()
        .arg("scaling")
        .args(logs)
        .arg("--out")
        .arg(out)
        .output()
        .expect("cannot start mortar")
}

#[test]
fn speedup_from_the_logs_of_one_and_two_ranks() {
    let text = common::scene_text("contact_patch");
    let case = common::write_scene_copy("scaling_patch", "contact_patch", &text);
    let here = case.parent().unwrap();
    let mut logs = Vec::new();
    let mut newton_its = Vec::new();
    for ranks in [1, 2] {
        let log = here.join(format!("log_{ranks}.txt"));
        let view = format!("-log_view :{}", log.display());
        let args: Vec<&str> = view.split(' ').chain(["-q"]).collect();
        let (run_out, _) = common::run_case(&case, ranks, &args);
        newton_its.push(common::metric(&run_out, "total_newton_its"));
        logs.push(log);
    }
    let out = here.join("scaling");
    let o = run_scaling(&[&logs[0], &logs[1]], &out);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );

    // The wall times of the logs ("Time (sec):", the maximum over the ranks).
    let wall = |log: &Path| -> f64 {
        let text = std::fs::read_to_string(log).unwrap();
        let line = text.lines().find(|l| l.starts_with("Time (sec):")).unwrap();
        line.split_whitespace().nth(2).unwrap().parse().unwrap()
    };
    let speedup = wall(&logs[0]) / wall(&logs[1]);
    let last = stdout.lines().last().unwrap();
    assert_eq!(last, format!("speedup: {speedup:.2}"), "{stdout}");
    // The Newton iterations the logs count are the runs' own, and the speedup per iteration
    // divides by them.
    let per_iteration = speedup * newton_its[1] / newton_its[0];
    assert!(
        stdout.contains(&format!(
            "speedup per Newton iteration: {per_iteration:.2}\n"
        )),
        "{per_iteration:.2} ({newton_its:?} iterations): {stdout}"
    );
    for phase in [
        "mortar integration",
        "contact search",
        "bulk assembly",
        "linear solve",
    ] {
        assert!(stdout.contains(phase), "{phase}: {stdout}");
    }

    // Every phase of every run; the phases add up to the logged stages (each stage in one phase).
    let csv = std::fs::read_to_string(out.join("scaling.csv")).unwrap();
    for (k, log) in logs.iter().enumerate() {
        let ranks = (k + 1).to_string();
        let phases: f64 = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|f| f[1] == ranks && f[0] != "total" && f[0] != "per_newton_iteration")
            .map(|f| f[2].parse::<f64>().unwrap())
            .sum();
        let text = std::fs::read_to_string(log).unwrap();
        let stages: f64 = text
            .lines()
            .skip_while(|l| !l.starts_with("Summary of Stages"))
            .skip(2)
            .take_while(|l| l.contains(':'))
            .map(|l| {
                let (_, figures) = l.rsplit_once(": ").unwrap();
                figures
                    .split_whitespace()
                    .next()
                    .unwrap()
                    .parse::<f64>()
                    .unwrap()
            })
            .sum();
        assert!(
            phases > 0.0 && (phases - stages).abs() <= 1e-9 * stages,
            "{phases} vs {stages}"
        );
    }
    assert!(out.join("scaling.png").is_file() && out.join("scaling.svg").is_file());

    // A reader that goes away before the table (`mortar scaling ... | head -1`): no panic, a
    // clean exit, the files written.
    std::fs::remove_file(out.join("scaling.csv")).unwrap();
    let mut child = common::mortar_command()
        .arg("scaling")
        .args([&logs[0], &logs[1]])
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot start mortar");
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success() && stderr.is_empty(), "{stderr}");
    assert!(out.join("scaling.csv").is_file());

    // The same log twice (no second rank count): one line naming the file at fault.
    let o = run_scaling(&[&logs[0], &logs[0]], &out);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("strictly increasing"), "{stderr}");

    // Not a PETSc log: one line naming the file.
    let o = run_scaling(&[&logs[0], &case], &out);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("case.toml") && stderr.contains("-log_view"),
        "{stderr}"
    );
}
