//! Which linear solver the Newton steps use: the case's `newton.linear_solver`, or by size.
//!
//! A direct solve (LU through MUMPS) costs about `n^2` per factorization on these meshes and
//! an iterative one (GMRES with multigrid and an exact solve on the interfaces' dofs) about
//! `n` per iteration, with a bounded number of iterations: below [`DIRECT_BELOW`] free dofs the
//! direct solve is at least as fast (docs/performance.md, "Refinement"), from there on the
//! iterative one, whose memory and cost per linear iteration grow about as the dofs. PETSc's
//! `-ksp_type` or `-pc_type` options replace the choice.

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::io::case_file::LinearSolverSpec;
use crate::model::Model;
use crate::petsc::{options, LinearPath, PetscInt};

/// The free dofs from which `newton.linear_solver = "auto"` solves iteratively.
pub const DIRECT_BELOW: usize = 20_000;

/// [`DIRECT_BELOW`] for a linear scene: its tangent is factorized once for the whole run, so
/// the direct solve stays the faster far longer, until its memory grows too large.
pub const LINEAR_DIRECT_BELOW: usize = 150_000;

/// The linear solver of a run, and why, for its first lines.
#[derive(Debug, Clone)]
pub(super) struct LinearChoice {
    pub path: LinearPath,
    pub why: String,
}

/// The choice for `scene` with `free_dofs` free dofs; `interfaces`: the model has interfaces
/// (the iterative path then splits their dofs off).
pub(super) fn choose(scene: &Scene, free_dofs: usize, interfaces: bool) -> Result<LinearChoice> {
    let from_options = options::has("-ksp_type")? || options::has("-pc_type")?;
    let default_below = if scene.is_linear() {
        LINEAR_DIRECT_BELOW
    } else {
        DIRECT_BELOW
    };
    let below = scene.newton.direct_below.unwrap_or(default_below);
    let spec = (scene.newton.linear_solver, below);
    Ok(decide(spec, free_dofs, interfaces, from_options))
}

/// [`choose`], given whether PETSc's options choose the solver.
fn decide(
    (spec, direct_below): (LinearSolverSpec, usize),
    free_dofs: usize,
    interfaces: bool,
    from_options: bool,
) -> LinearChoice {
    let iterative = LinearPath::Iterative {
        interface_split: interfaces,
    };
    let (path, why) = match spec {
        _ if from_options => (LinearPath::Direct, "PETSc's options".to_string()),
        LinearSolverSpec::Direct => (LinearPath::Direct, "newton.linear_solver".into()),
        LinearSolverSpec::Iterative => (iterative, "newton.linear_solver".into()),
        LinearSolverSpec::Auto if free_dofs < direct_below => (
            LinearPath::Direct,
            format!("{free_dofs} free dofs, below {direct_below}"),
        ),
        LinearSolverSpec::Auto => (
            iterative,
            format!("{free_dofs} free dofs, from {direct_below} on"),
        ),
    };
    let what = match (from_options, path) {
        (true, _) => "as PETSc's options say",
        (false, LinearPath::Direct) => "direct (LU through MUMPS)",
        (
            false,
            LinearPath::Iterative {
                interface_split: true,
            },
        ) => "iterative (GMRES; an exact solve on the interfaces' dofs, then multigrid)",
        (false, LinearPath::Iterative { .. }) => "iterative (GMRES with multigrid)",
    };
    LinearChoice {
        path,
        why: format!("{what}: {why}"),
    }
}

/// The owned free dofs of the nodes the model's interfaces couple, ascending: the interface
/// field of the iterative path.
pub(super) fn interface_dofs(model: &Model, dofs: &DofMap) -> Vec<PetscInt> {
    let owned = dofs.owned_start..dofs.owned_start + dofs.owned_count;
    let mut out: Vec<PetscInt> = model
        .coupled_nodes()
        .into_iter()
        .flat_map(|n| dofs.global[3 * n..3 * n + 3].iter().copied())
        .filter(|&g| g >= 0 && owned.contains(&(g as usize)))
        .collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `auto` takes the direct path below the crossover and the iterative one from it on, with
    /// the interfaces split off when there are some; a forced choice holds at any size; PETSc's
    /// options override everything.
    #[test]
    fn the_path_follows_the_size_unless_chosen() {
        let auto = (LinearSolverSpec::Auto, 1000);
        let path = |spec, dofs, interfaces, options| decide(spec, dofs, interfaces, options).path;
        assert_eq!(path(auto, 999, true, false), LinearPath::Direct);
        let split = LinearPath::Iterative {
            interface_split: true,
        };
        assert_eq!(path(auto, 1000, true, false), split);
        assert_eq!(
            path(auto, 1000, false, false),
            LinearPath::Iterative {
                interface_split: false
            }
        );
        let direct = (LinearSolverSpec::Direct, 1000);
        assert_eq!(path(direct, 1_000_000, true, false), LinearPath::Direct);
        let iterative = (LinearSolverSpec::Iterative, 1000);
        assert_eq!(path(iterative, 10, true, false), split);
        let chosen = decide(iterative, 10, true, true);
        assert!(
            chosen.why.starts_with("as PETSc's options say"),
            "{}",
            chosen.why
        );
        let why = decide(auto, 5000, true, false).why;
        assert_eq!(
            why,
            "iterative (GMRES; an exact solve on the interfaces' dofs, then multigrid): 5000 \
             free dofs, from 1000 on"
        );
    }
}
