//! Which linear solver the Newton steps use: the case's `newton.linear_solver`, or by size.
//!
//! A direct solve (LU through MUMPS) costs about `n^2` per factorization on these meshes and
//! an iterative one (GMRES with multigrid and an exact solve on the interfaces' dofs) about
//! `n` per iteration, with a bounded number of iterations: below a crossover the direct solve
//! is at least as fast, from there on the iterative one, whose memory and cost per linear
//! iteration grow about as the dofs. The crossover depends on the elements' order: a node of
//! a second-order mesh couples with two to three times as many dofs as one of a first-order
//! mesh, which costs the iterative path's matrix products and multigrid more than it costs
//! the direct solve of as many dofs ([`DIRECT_BELOW`], [`DIRECT_BELOW_SECOND_ORDER`]; the
//! measurements: docs/performance.md, "The crossover"). PETSc's `-ksp_type` or `-pc_type`
//! options replace the choice.

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::io::case_file::LinearSolverSpec;
use crate::model::Model;
use crate::petsc::{options, LinearPath, PetscInt};

/// The free dofs from which `newton.linear_solver = "auto"` solves iteratively, on a mesh of
/// first-order elements (Hex8, Tet4).
pub const DIRECT_BELOW: usize = 5_000;

/// [`DIRECT_BELOW`] on a mesh with second-order elements (Hex20, Hex27, Tet10).
pub const DIRECT_BELOW_SECOND_ORDER: usize = 15_000;

/// [`DIRECT_BELOW`] for a linear scene: its tangent is factorized once for the whole run, so
/// the direct solve stays the faster far longer, until its memory grows too large.
pub const LINEAR_DIRECT_BELOW: usize = 150_000;

/// The free dofs from which `auto` solves iteratively, and where that number comes from (for
/// the run's first lines).
#[derive(Debug, Clone, Copy)]
struct Crossover {
    direct_below: usize,
    basis: &'static str,
}

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
    let crossover = match scene.newton.direct_below {
        Some(direct_below) => Crossover {
            direct_below,
            basis: "newton.direct_below",
        },
        None => default_crossover(scene),
    };
    let spec = (scene.newton.linear_solver, crossover);
    Ok(decide(spec, free_dofs, interfaces, from_options))
}

/// The crossover of a scene that does not set `newton.direct_below`.
fn default_crossover(scene: &Scene) -> Crossover {
    let (direct_below, basis) = if scene.is_linear() {
        (LINEAR_DIRECT_BELOW, "a linear scene")
    } else if scene.mesh.types.iter().any(|t| t.order() > 1) {
        (DIRECT_BELOW_SECOND_ORDER, "second-order elements")
    } else {
        (DIRECT_BELOW, "first-order elements")
    };
    Crossover {
        direct_below,
        basis,
    }
}

/// [`choose`], given whether PETSc's options choose the solver.
fn decide(
    (spec, crossover): (LinearSolverSpec, Crossover),
    free_dofs: usize,
    interfaces: bool,
    from_options: bool,
) -> LinearChoice {
    let iterative = LinearPath::Iterative {
        interface_split: interfaces,
    };
    let Crossover {
        direct_below,
        basis,
    } = crossover;
    let (path, why) = match spec {
        _ if from_options => (LinearPath::Direct, "PETSc's options".to_string()),
        LinearSolverSpec::Direct => (LinearPath::Direct, "newton.linear_solver".into()),
        LinearSolverSpec::Iterative => (iterative, "newton.linear_solver".into()),
        LinearSolverSpec::Auto if free_dofs < direct_below => (
            LinearPath::Direct,
            format!("{free_dofs} free dofs, below {direct_below} ({basis})"),
        ),
        LinearSolverSpec::Auto => (
            iterative,
            format!("{free_dofs} free dofs, from {direct_below} on ({basis})"),
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

    /// A scene's own crossover: by its elements' order, or a linear scene's (shipped cases).
    #[test]
    fn the_crossover_follows_the_elements_order() {
        let crossover = |case: &str| {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(case);
            let c = default_crossover(&Scene::load(&path).unwrap());
            (c.direct_below, c.basis)
        };
        let first = (DIRECT_BELOW, "first-order elements");
        assert_eq!(crossover("cases/refinement/hex8_1.toml"), first);
        let second = (DIRECT_BELOW_SECOND_ORDER, "second-order elements");
        assert_eq!(crossover("cases/refinement/hex27_1.toml"), second);
        assert_eq!(crossover("cases/hertz/case.toml"), second);
        let linear = (LINEAR_DIRECT_BELOW, "a linear scene");
        assert_eq!(crossover("cases/thick_sphere_tied/case.toml"), linear);
    }

    /// `auto` takes the direct path below the crossover and the iterative one from it on, with
    /// the interfaces split off when there are some; a forced choice holds at any size; PETSc's
    /// options override everything.
    #[test]
    fn the_path_follows_the_size_unless_chosen() {
        let at = |direct_below| Crossover {
            direct_below,
            basis: "newton.direct_below",
        };
        let auto = (LinearSolverSpec::Auto, at(1000));
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
        let direct = (LinearSolverSpec::Direct, at(1000));
        assert_eq!(path(direct, 1_000_000, true, false), LinearPath::Direct);
        let iterative = (LinearSolverSpec::Iterative, at(1000));
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
             free dofs, from 1000 on (newton.direct_below)"
        );
    }
}
