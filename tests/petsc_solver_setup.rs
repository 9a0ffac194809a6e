//! What a run sets up in PETSc around its solves: the solver's phases as PETSc log stages, a
//! singular tangent (an under-constrained body) reported, and the rigid body modes given to
//! algebraic multigrid.

mod common;

/// `-log_view` shows the solver's phases as PETSc log stages.
#[test]
fn phases_are_petsc_log_stages() {
    let case = common::write_case("log_stages", &common::column_case(""));
    let (_, stdout) = common::run_case(&case, 1, &["-q", "-log_view"]);
    for stage in ["setup", "assembly", "solve", "output"] {
        assert!(
            stdout
                .lines()
                .any(|l| l.trim_start().starts_with(&format!("{}:", stage))
                    || l.contains(&format!(": {stage}"))),
            "stage {stage} missing from -log_view"
        );
    }
}

/// Runs `case` on `ranks` ranks, which must fail with one error line: that line and the
/// output folder.
fn failed_run(case: &std::path::Path, ranks: usize) -> (String, std::path::PathBuf) {
    let out_dir = case.parent().unwrap().join(format!("out{ranks}"));
    let out = common::run_raw(case, ranks, &out_dir, &["-q"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{ranks} rank(s): {stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("mortar: error:"))
        .collect();
    assert_eq!(errors.len(), 1, "{ranks} rank(s): {stderr}");
    (errors[0].to_string(), out_dir)
}

/// A box held only along z on one face can translate in x and y and rotate about z: the
/// singular tangent is detected and reported, on 1 and 2 ranks, instead of "converging" to an
/// arbitrary rigid shift: by MUMPS's null pivots on the direct solve, and on the iterative path
/// (which has none) by the rigid motions the tangent does not resist, naming the body.
#[test]
fn an_under_constrained_body_is_reported() {
    let toml = common::column_case("").replace(
        "[[dirichlet]]\nset = \"c.zmin\"\ncomponents = [\"x\", \"y\", \"z\"]",
        "[[dirichlet]]\nset = \"c.zmin\"\ncomponents = [\"z\"]\n[[pressure]]\nset = \"c.zmax\"\nvalue = 1.0",
    );
    assert!(toml.contains("components = [\"z\"]"));
    for (path, says) in [
        ("direct", "null pivot"),
        ("iterative", "body 'c' can move rigidly"),
    ] {
        let text = format!("{toml}\n[newton]\nlinear_solver = \"{path}\"\n");
        let case = common::write_case(&format!("under_constrained_{path}"), &text);
        for ranks in [1, 2] {
            let (error, out_dir) = failed_run(&case, ranks);
            assert!(error.contains("singular"), "{error}");
            assert!(error.contains(says), "{error}");
            // The summary says the same (not `message: null`, as if still running).
            let s = common::summary(&out_dir);
            let message = s["message"].as_str().unwrap_or_default();
            assert_eq!(format!("mortar: error: {message}"), error, "{s}");
        }
    }
}

/// Two blocks pressed together by two opposite pressures, each held only by a symmetry plane
/// normal to y: neither alone can move without pressing into the other, but the two together
/// can translate in x and z and rotate about y. On the iterative path both are named (the
/// direct solve's null pivots name no body), on 1 and 2 ranks.
#[test]
fn bodies_free_together_are_reported_on_the_iterative_path() {
    let mut toml = common::slide_case(2);
    for (from, to) in [
        ("[[symmetry]]\nset = \"low.zmin\"\nnormal = \"z\"\n", ""),
        ("[[symmetry]]\nset = \"low.xmin\"\nnormal = \"x\"\n", ""),
        (
            "[[dirichlet]]\nset = \"up.zmax\"\ncomponents = [\"z\"]",
            "[[pressure]]\nset = \"low.zmin\"\nvalue = 10.0\n\
             [[pressure]]\nset = \"up.zmax\"\nvalue = 10.0\n[[dirichlet]]\nset = \"up.zmax\"\n\
             components = [\"z\"]",
        ),
    ] {
        assert!(toml.contains(from), "no `{from}`");
        toml = toml.replacen(from, to, 1);
    }
    // The two displacement tables on up.zmax go: the pressures alone load the blocks.
    let start = toml.find("[[dirichlet]]").unwrap();
    let end = toml.find("[[interface]]").unwrap();
    toml.replace_range(start..end, "");
    toml = toml.replace(
        "[steps]",
        "[newton]\nlinear_solver = \"iterative\"\n[steps]",
    );
    let case = common::write_case("free_together", &toml);
    for ranks in [1, 2] {
        let (error, _) = failed_run(&case, ranks);
        assert!(error.contains("singular"), "{error}");
        assert!(
            error.contains("bodies 'low', 'up' can move rigidly"),
            "{error}"
        );
    }
}

/// Algebraic multigrid gets the rigid body modes (`MatSetNearNullSpace`): a Hex8 cantilever
/// 20 x 2 x 2 under a follower pressure, 2 load steps, GMRES with GAMG to 1e-8. Without the
/// modes the linear solves hit their cap (10 000 iterations) and the steps are cut. Bound: at
/// most 1 000 linear iterations in all, no cut, and the displacements of the direct solve to
/// 1e-6, on 1 and 2 ranks.
#[test]
fn algebraic_multigrid_gets_the_rigid_body_modes() {
    let toml = common::cantilever_case("hex8", [20, 2, 2], 2);
    let case = common::write_case("amg_rigid_modes", &toml);
    let (direct, _) = common::run_case(&case, 1, &["-q"]);
    let reference = common::displacements(&direct);
    let amg = [
        "-q",
        "-ksp_type",
        "gmres",
        "-pc_type",
        "gamg",
        "-ksp_rtol",
        "1e-8",
    ];
    for ranks in [1, 2] {
        let (out, _) = common::run_case(&case, ranks, &amg);
        let steps = common::summary(&out)["steps"].as_array().unwrap().clone();
        assert_eq!(steps.len(), 2, "{ranks} rank(s): steps were cut");
        let linear = common::History::read(&out).sum("linear_its");
        assert!(
            linear <= 1000.0,
            "{ranks} rank(s): {linear} linear iterations"
        );
        let diff = common::max_rel_difference(&common::displacements(&out), &reference);
        assert!(
            diff < 1e-6,
            "{ranks} rank(s): {diff:e} from the direct solve"
        );
    }
}

/// Inexact Newton (`-snes_ksp_ew`, Eisenstat-Walker's linear tolerances) with the load-step
/// predictor, whose linear solve runs outside a Newton solve (it crashed PETSc there): the
/// frictional slide converges to the state of the default solve within the Newton tolerance,
/// on 1 and 2 ranks.
#[test]
fn inexact_newton_runs_with_the_predictor() {
    let case = common::write_case("inexact_newton", &common::slide_case(4));
    let (exact, _) = common::run_case(&case, 1, &["-q"]);
    let inexact = ["-q", "-snes_ksp_ew", "-ksp_type", "gmres", "-pc_type", "lu"];
    for ranks in [1, 2] {
        let (out, _) = common::run_case(&case, ranks, &inexact);
        let d = common::max_rel_difference_of_runs(&exact, &out);
        assert!(
            d < 1e-8,
            "{ranks} rank(s): {d:e} from the exact linear solves"
        );
    }
}
