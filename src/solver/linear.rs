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
//! measurements: docs/performance.md, "The crossover by the elements' order").
//!
//! On the iterative path with interfaces (`auto`'s or `"iterative"`), a second size decides
//! the preconditioner: the field split (an exact solve on the interfaces' dofs, multigrid on
//! the rest), or the interface coarse correction (`newton.coarse_correction`): the split with
//! the interfaces' dofs smoothed by point Jacobi, then a correction that solves them exactly
//! with the bulk multigrid's first coarse space. The correction keeps the GMRES iterations
//! per Newton iteration nearly flat under refinement but costs more per Newton iteration (a
//! projection and its LU), so it pays only from some size on: on a nonlinear scene, from
//! [`COARSE_CORRECTION_FROM`] free dofs with first-order elements and from
//! [`COARSE_CORRECTION_FROM_SECOND_ORDER`] with second-order ones (measured on the refinement
//! family's frictional slide, docs/performance.md, "The two-level form from 30 000 free dofs"
//! and "The two-level form on Hex27"). A linear scene (not measured at such sizes) keeps the
//! split unless the case asks for the correction. PETSc's `-ksp_type` or `-pc_type` options
//! replace the choice.

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

/// The free dofs from which the iterative path (`auto`'s or `"iterative"`) corrects across
/// the interfaces (`newton.coarse_correction` unset), on a nonlinear scene of first-order
/// elements.
pub const COARSE_CORRECTION_FROM: usize = 30_000;

/// [`COARSE_CORRECTION_FROM`] on a mesh with at least one second-order element.
pub const COARSE_CORRECTION_FROM_SECOND_ORDER: usize = 70_000;

/// The free dofs from which `auto` solves iteratively, and where that number comes from (for
/// the run's first lines); and from which the iterative path adds the interface coarse
/// correction, if at any size.
#[derive(Debug, Clone, Copy)]
struct Crossover {
    direct_below: usize,
    source: &'static str,
    coarse_from: Option<usize>,
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
        coarse_correction: scene.newton.coarse_correction,
    };
    let mut choice = decide(spec, free_dofs, interfaces, from_options);
    let corrected = matches!(
        choice.path,
        LinearPath::Iterative {
            coarse_correction: true,
            ..
        }
    );
    if scene.newton.coarse_correction == Some(true) && !corrected {
        choice.why += " (newton.coarse_correction: only on the iterative path with interfaces)";
    }
    Ok(choice)
}

/// What the iterative path does with the model's interfaces: whether it splits them off, and
/// whether it corrects across them (`None`: by size).
#[derive(Debug, Clone, Copy)]
struct Interfaces {
    split: bool,
    coarse_correction: Option<bool>,
}

/// The scene's `newton.direct_below`, or without it the threshold of its kind; the coarse
/// correction's threshold on a nonlinear scene, by the elements' order.
fn crossover(scene: &Scene) -> Crossover {
    let second_order = scene.mesh.types.iter().any(|t| t.order() > 1);
    let (direct_below, source) = match scene.newton.direct_below {
        Some(direct_below) => (direct_below, "newton.direct_below"),
        None if scene.is_linear() => (LINEAR_DIRECT_BELOW, "a linear scene"),
        None if second_order => (DIRECT_BELOW_SECOND_ORDER, "second-order elements"),
        None => (DIRECT_BELOW, "first-order elements"),
    };
    let coarse_from = if second_order {
        COARSE_CORRECTION_FROM_SECOND_ORDER
    } else {
        COARSE_CORRECTION_FROM
    };
    Crossover {
        direct_below,
        source,
        coarse_from: (!scene.is_linear()).then_some(coarse_from),
    }
}

/// Whether the iterative path corrects across the interfaces (as the case says, or from
/// `coarse_from` free dofs on), and what the run's second line adds about it.
fn coarse_choice(
    interfaces: Interfaces,
    coarse_from: Option<usize>,
    free_dofs: usize,
) -> (bool, Option<String>) {
    if !interfaces.split {
        return (false, None);
    }
    match (interfaces.coarse_correction, coarse_from) {
        (Some(true), _) => (
            true,
            Some("the coarse correction by newton.coarse_correction".into()),
        ),
        (None, Some(from)) if free_dofs >= from => {
            (true, Some(format!("the coarse correction from {from} on")))
        }
        _ => (false, None),
    }
}

/// [`choose`], given whether PETSc's options choose the solver.
fn decide(
    (spec, crossover): (LinearSolverSpec, Crossover),
    free_dofs: usize,
    interfaces: Interfaces,
    from_options: bool,
) -> LinearChoice {
    let Crossover {
        direct_below,
        source,
        coarse_from,
    } = crossover;
    let (coarse_correction, coarse_note) = coarse_choice(interfaces, coarse_from, free_dofs);
    let iterative = LinearPath::Iterative {
        interface_split: interfaces.split,
        coarse_correction,
    };
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
    let why = match (path, coarse_note) {
        (LinearPath::Iterative { .. }, Some(note)) if !from_options => format!("{why}; {note}"),
        _ => why,
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
            (c.direct_below, c.source, c.coarse_from)
        };
        let coarse = Some(COARSE_CORRECTION_FROM);
        let first = (DIRECT_BELOW, "first-order elements", coarse);
        assert_eq!(load("cases/refinement/hex8_1.toml", None), first);
        let coarse_second = Some(COARSE_CORRECTION_FROM_SECOND_ORDER);
        let second = (
            DIRECT_BELOW_SECOND_ORDER,
            "second-order elements",
            coarse_second,
        );
        assert_eq!(load("cases/refinement/hex27_1.toml", None), second);
        assert_eq!(load("cases/hertz/case.toml", None), second);
        let linear = (LINEAR_DIRECT_BELOW, "a linear scene", None);
        assert_eq!(load("cases/thick_sphere_tied/case.toml", None), linear);
        let own = (1234, "newton.direct_below");
        assert_eq!(
            load("cases/refinement/hex8_1.toml", Some(1234)),
            (own.0, own.1, coarse)
        );
        assert_eq!(
            load("cases/refinement/hex27_1.toml", Some(1234)),
            (own.0, own.1, coarse_second)
        );
        assert_eq!(
            load("cases/thick_sphere_tied/case.toml", Some(1234)),
            (own.0, own.1, None)
        );
    }

    /// `auto` takes the direct path below the crossover and the iterative one from it on, with
    /// the interfaces split off when there are some; a forced choice holds at any size; PETSc's
    /// options override everything.
    #[test]
    fn the_path_follows_the_size_unless_chosen() {
        let at = |direct_below| Crossover {
            direct_below,
            source: "newton.direct_below",
            coarse_from: None,
        };
        let auto = (LinearSolverSpec::Auto, at(1000));
        let path = |spec, dofs, split, options| {
            let interfaces = Interfaces {
                split,
                coarse_correction: Some(false),
            };
            decide(spec, dofs, interfaces, options).path
        };
        let split_only = |split| Interfaces {
            split,
            coarse_correction: Some(false),
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
            coarse_correction: Some(true),
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

    /// Unset, the coarse correction follows the size on the iterative path with interfaces
    /// (from the threshold on, and the first lines say so); set, it holds at any size; it
    /// never applies without interfaces, on the direct path, or where the scene has no
    /// threshold for it.
    #[test]
    fn the_coarse_correction_follows_the_size_unless_chosen() {
        let auto = |coarse_from| {
            let crossover = Crossover {
                direct_below: 1000,
                source: "first-order elements",
                coarse_from,
            };
            (LinearSolverSpec::Auto, crossover)
        };
        let interfaces = |split, coarse_correction| Interfaces {
            split,
            coarse_correction,
        };
        let iterative = |interface_split, coarse_correction| LinearPath::Iterative {
            interface_split,
            coarse_correction,
        };
        let path = |coarse_from, dofs, split, coarse| {
            decide(auto(coarse_from), dofs, interfaces(split, coarse), false).path
        };
        let from = Some(5000);
        assert_eq!(path(from, 4999, true, None), iterative(true, false));
        assert_eq!(path(from, 5000, true, None), iterative(true, true));
        assert_eq!(path(from, 5000, true, Some(false)), iterative(true, false));
        assert_eq!(path(from, 1000, true, Some(true)), iterative(true, true));
        assert_eq!(path(from, 5000, false, None), iterative(false, false));
        assert_eq!(path(from, 5000, false, Some(true)), iterative(false, false));
        assert_eq!(path(from, 999, true, None), LinearPath::Direct);
        assert_eq!(path(None, 1_000_000, true, None), iterative(true, false));
        assert_eq!(
            decide(auto(from), 5000, interfaces(true, None), false).why,
            "iterative (GMRES; multigrid, then a coarse correction across the interfaces that \
             solves their dofs exactly): 5000 free dofs, from 1000 on (first-order elements); \
             the coarse correction from 5000 on"
        );
        assert_eq!(
            decide(auto(from), 5000, interfaces(true, Some(true)), false).why,
            "iterative (GMRES; multigrid, then a coarse correction across the interfaces that \
             solves their dofs exactly): 5000 free dofs, from 1000 on (first-order elements); \
             the coarse correction by newton.coarse_correction"
        );
    }
}
