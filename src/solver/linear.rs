//! Which linear solver the Newton steps use: the case's `newton.linear_solver`, or by size.
//!
//! A direct solve (LU through MUMPS) costs about `n^2` per factorization on these meshes and
//! an iterative one (GMRES with multigrid and an exact solve on the interfaces' dofs) about
//! `n` per iteration, with a bounded number of iterations, so the iterative path wins from
//! some size on, and its memory and cost per linear iteration grow about as the dofs. Below a
//! threshold `auto` still solves directly, where the runs are short: the direct solve needs no
//! iteration to converge, whatever the tangent's condition. The threshold
//! depends on the elements' order ([`DIRECT_BELOW`], [`DIRECT_BELOW_SECOND_ORDER`]): where the
//! iterative path overtakes the direct one depends on how many linear iterations the
//! multigrid takes, which second-order elements on graded meshes raise most (the
//! measurements: docs/performance.md, "The crossover by the elements' order"). PETSc's
//! `-ksp_type` or `-pc_type` options replace the choice.

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::io::case_file::LinearSolverSpec;
use crate::model::Model;
use crate::petsc::{options, LinearPath, PetscInt};

/// The free dofs from which `newton.linear_solver = "auto"` solves iteratively, on a mesh of
/// first-order elements (Hex8, Tet4).
pub const DIRECT_BELOW: usize = 5_000;

/// [`DIRECT_BELOW`] on a mesh with at least one second-order element (Hex20, Hex27, Tet10).
pub const DIRECT_BELOW_SECOND_ORDER: usize = 15_000;

/// The threshold of a linear scene, whatever its elements: its tangent is factorized once for
/// the whole run, so the direct solve stays the faster far longer, until its memory grows too
/// large.
pub const LINEAR_DIRECT_BELOW: usize = 150_000;

/// The free dofs from which `auto` solves iteratively, and where that number comes from (for
/// the run's first lines).
#[derive(Debug, Clone, Copy)]
struct Crossover {
    direct_below: usize,
    source: &'static str,
}

/// The linear solver of a run, and why, for its first lines.
#[derive(Debug, Clone)]
pub(super) struct LinearChoice {
    pub path: LinearPath,
    pub why: String,
}

/// The choice for `scene` with `free_dofs` free dofs; `interfaces`: the model has interfaces
/// (the iterative path then splits their dofs off, and corrects across them with
/// `newton.coarse_correction`).
pub(super) fn choose(scene: &Scene, free_dofs: usize, interfaces: bool) -> Result<LinearChoice> {
    let from_options = options::has("-ksp_type")? || options::has("-pc_type")?;
    let spec = (scene.newton.linear_solver, crossover(scene));
    let interfaces = Interfaces {
        split: interfaces,
        coarse_correction: interfaces && scene.newton.coarse_correction,
    };
    let mut choice = decide(spec, free_dofs, interfaces, from_options);
    let corrected = matches!(
        choice.path,
        LinearPath::Iterative {
            coarse_correction: true,
            ..
        }
    );
    if scene.newton.coarse_correction && !corrected {
        choice.why += " (newton.coarse_correction: only on the iterative path with interfaces)";
    }
    Ok(choice)
}

/// What the iterative path does with the model's interfaces.
#[derive(Debug, Clone, Copy)]
struct Interfaces {
    split: bool,
    coarse_correction: bool,
}

/// The scene's `newton.direct_below`, or without it the threshold of its kind.
fn crossover(scene: &Scene) -> Crossover {
    let (direct_below, source) = match scene.newton.direct_below {
        Some(direct_below) => (direct_below, "newton.direct_below"),
        None if scene.is_linear() => (LINEAR_DIRECT_BELOW, "a linear scene"),
        None if scene.mesh.types.iter().any(|t| t.order() > 1) => {
            (DIRECT_BELOW_SECOND_ORDER, "second-order elements")
        }
        None => (DIRECT_BELOW, "first-order elements"),
    };
    Crossover {
        direct_below,
        source,
    }
}

/// [`choose`], given whether PETSc's options choose the solver.
fn decide(
    (spec, crossover): (LinearSolverSpec, Crossover),
    free_dofs: usize,
    interfaces: Interfaces,
    from_options: bool,
) -> LinearChoice {
    let iterative = LinearPath::Iterative {
        interface_split: interfaces.split,
        coarse_correction: interfaces.coarse_correction,
    };
    let Crossover {
        direct_below,
        source,
    } = crossover;
    let (path, why) = match spec {
        _ if from_options => (LinearPath::Direct, "PETSc's options".to_string()),
        LinearSolverSpec::Direct => (LinearPath::Direct, "newton.linear_solver".into()),
        LinearSolverSpec::Iterative => (iterative, "newton.linear_solver".into()),
        LinearSolverSpec::Auto if free_dofs < direct_below => (
            LinearPath::Direct,
            format!("{free_dofs} free dofs, below {direct_below} ({source})"),
        ),
        LinearSolverSpec::Auto => (
            iterative,
            format!("{free_dofs} free dofs, from {direct_below} on ({source})"),
        ),
    };
    let what = match (from_options, path) {
        (true, _) => "as PETSc's options say",
        (false, LinearPath::Direct) => "direct (LU through MUMPS)",
        (
            false,
            LinearPath::Iterative {
                interface_split: true,
                coarse_correction: false,
            },
        ) => "iterative (GMRES; an exact solve on the interfaces' dofs, then multigrid)",
        (
            false,
            LinearPath::Iterative {
                interface_split: true,
                coarse_correction: true,
            },
        ) => {
            "iterative (GMRES; multigrid, then a coarse correction across the interfaces that \
             solves their dofs exactly)"
        }
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

    /// A scene's threshold: by its elements' order, or a linear scene's, unless the case sets
    /// its own (shipped cases).
    #[test]
    fn the_crossover_follows_the_elements_order() {
        let load = |case: &str, direct_below: Option<i64>| {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(case);
            let scene = Scene::load_edited(&path, |table| {
                if let Some(n) = direct_below {
                    let mut newton = toml::Table::new();
                    newton.insert("direct_below".into(), n.into());
                    table.insert("newton".into(), newton.into());
                }
                Ok(())
            });
            let c = crossover(&scene.unwrap());
            (c.direct_below, c.source)
        };
        let first = (DIRECT_BELOW, "first-order elements");
        assert_eq!(load("cases/refinement/hex8_1.toml", None), first);
        let second = (DIRECT_BELOW_SECOND_ORDER, "second-order elements");
        assert_eq!(load("cases/refinement/hex27_1.toml", None), second);
        assert_eq!(load("cases/hertz/case.toml", None), second);
        let linear = (LINEAR_DIRECT_BELOW, "a linear scene");
        assert_eq!(load("cases/thick_sphere_tied/case.toml", None), linear);
        let own = (1234, "newton.direct_below");
        assert_eq!(load("cases/refinement/hex27_1.toml", Some(1234)), own);
        assert_eq!(load("cases/thick_sphere_tied/case.toml", Some(1234)), own);
    }

    /// `auto` takes the direct path below the crossover and the iterative one from it on, with
    /// the interfaces split off when there are some; a forced choice holds at any size; PETSc's
    /// options override everything.
    #[test]
    fn the_path_follows_the_size_unless_chosen() {
        let at = |direct_below| Crossover {
            direct_below,
            source: "newton.direct_below",
        };
        let auto = (LinearSolverSpec::Auto, at(1000));
        let path = |spec, dofs, split, options| {
            let interfaces = Interfaces {
                split,
                coarse_correction: false,
            };
            decide(spec, dofs, interfaces, options).path
        };
        let split_only = |split| Interfaces {
            split,
            coarse_correction: false,
        };
        assert_eq!(path(auto, 999, true, false), LinearPath::Direct);
        let split = LinearPath::Iterative {
            interface_split: true,
            coarse_correction: false,
        };
        assert_eq!(path(auto, 1000, true, false), split);
        assert_eq!(
            path(auto, 1000, false, false),
            LinearPath::Iterative {
                interface_split: false,
                coarse_correction: false,
            }
        );
        let direct = (LinearSolverSpec::Direct, at(1000));
        assert_eq!(path(direct, 1_000_000, true, false), LinearPath::Direct);
        let iterative = (LinearSolverSpec::Iterative, at(1000));
        assert_eq!(path(iterative, 10, true, false), split);
        let coarse = Interfaces {
            split: true,
            coarse_correction: true,
        };
        assert_eq!(
            decide(iterative, 10, coarse, false).path,
            LinearPath::Iterative {
                interface_split: true,
                coarse_correction: true,
            }
        );
        let chosen = decide(iterative, 10, split_only(true), true);
        assert!(
            chosen.why.starts_with("as PETSc's options say"),
            "{}",
            chosen.why
        );
        let why = decide(auto, 5000, split_only(true), false).why;
        assert_eq!(
            why,
            "iterative (GMRES; an exact solve on the interfaces' dofs, then multigrid): 5000 \
             free dofs, from 1000 on (newton.direct_below)"
        );
    }
}
