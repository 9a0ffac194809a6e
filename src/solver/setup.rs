//! Setting a run up: the partition, the dofs, the model's contributions (only those the scene
//! requires), the matrix pattern, the PETSc objects, and the output folder.

use std::cell::RefCell;
use std::time::Instant;

use mpi::collective::Root;
use mpi::topology::{Communicator, SimpleCommunicator};

use crate::case::Scene;
use crate::contact::frictional::ContactInterfaces;
use crate::contact::tying::TiedInterfaces;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::io::output::Summary;
use crate::model::{Contribution, Model};
use crate::petsc::log::Phases;
use crate::petsc::snes::Tolerances;
use crate::petsc::{options, Matrix, Petsc, Scatter, Snes, Vector};
use crate::solid::Bulk;

use super::assembly::Pattern;
use super::checkpoint;
use super::evaluation::{Evaluation, Evaluator};
use super::linear;
use super::predictor::{NewtonTangent, Tangent};
use super::results::Results;
use super::state::RunState;
use super::{
    Context, Linear, Run, RunOptions, CONTACT_MONITOR, FALLBACK_LINE_SEARCH, PHASES, TIMED_PARTS,
};

impl<'a> Run<'a> {
    /// Everything a run of `scene` needs, made (*collective*).
    pub(super) fn set_up(scene: &'a Scene, petsc: &Petsc, opts: &'a RunOptions) -> Result<Self> {
        let world = petsc.world();
        let mut phases = Phases::new(&PHASES)?;
        for name in TIMED_PARTS {
            phases.add(name, 0.0);
        }
        let started = Instant::now();
        let setup_stage = phases.push("setup")?;
        let element_rank = partition(scene, &world, petsc.size())?;
        let mut dofs = DofMap::new(
            &scene.mesh,
            element_rank,
            petsc.rank(),
            petsc.size(),
            &scene.constrained_mask(),
        );
        let model = model_of(scene, &mut dofs, &world)?;
        let x = Vector::new_mpi(dofs.owned_count)?;
        let evaluator = RefCell::new(Evaluator::new(
            Scatter::new(&x, &dofs.gathered_global)?,
            scene.mesh.num_nodes(),
        ));
        let cx = Context {
            scene,
            opts,
            rank: petsc.rank(),
            ranks: petsc.size(),
            world,
            dofs,
            evaluator,
        };
        let linear = Linear::new(&cx, &model, x)?;
        let fallback_line_search = (scene.has_friction() && linear.snes.line_search()? == "basic")
            .then_some(FALLBACK_LINE_SEARCH);
        // A refused restart leaves the folder as it was: checked before anything is written.
        let resumed = opts
            .restart
            .then(|| checkpoint::open(scene, &opts.out_dir, (cx.rank, cx.ranks), &cx.world))
            .transpose()?;
        let out = (opts.out_dir.as_path(), opts.restart);
        let results = Results::new(scene, out, model.history_columns(), &cx.world)?;
        let mut run = Run {
            summary: Summary {
                case: scene.name.clone(),
                ranks: cx.ranks,
                converged: false,
                ..Default::default()
            },
            cx,
            model,
            linear,
            results,
            phases,
            state: RunState::new(scene),
            fallback_line_search,
            contact_monitor: options::has(CONTACT_MONITOR)?,
            checkpointed: None,
            identity: Default::default(),
            started,
        };
        if let Some(resumed) = resumed {
            run.resume(resumed)?;
        }
        drop(setup_stage);
        run.phases.add("setup", run.started.elapsed().as_secs_f64());
        Ok(run)
    }
}

/// The contributions of `scene` on this rank: the bulk, and the tied and contact interfaces
/// where the scene has them; `dofs` then also gathers the interfaces' nodes (*collective*).
fn model_of(scene: &Scene, dofs: &mut DofMap, world: &SimpleCommunicator) -> Result<Model> {
    let mut interfaces: Vec<Box<dyn Contribution>> = Vec::new();
    let tying = TiedInterfaces::new(scene, dofs, world)?;
    if !tying.is_empty() {
        interfaces.push(Box::new(tying));
    }
    let contact = ContactInterfaces::new(scene, dofs)?;
    if !contact.is_empty() {
        interfaces.push(Box::new(contact));
    }
    let mut parts: Vec<Box<dyn Contribution>> = vec![Box::new(Bulk::new(scene, dofs)?)];
    parts.extend(interfaces);
    let model = Model::new(parts);
    dofs.gather_also(&model.coupled_nodes());
    Ok(model)
}

impl Linear {
    /// The pattern of the contributions that do not move, the matrix, the solution `x` and its
    /// work copies, and Newton (*collective*).
    fn new(cx: &Context, model: &Model, mut x: Vector) -> Result<Linear> {
        let (scene, dofs) = (cx.scene, &cx.dofs);
        let mut pattern = Pattern::new(dofs);
        let fixed = model.parts().iter().filter(|c| !c.pattern_moves());
        let zero = vec![0.0; 3 * scene.mesh.num_nodes()];
        let reference = crate::model::State {
            scene,
            u: &zero,
            t: 0.0,
        };
        pattern.add(dofs, &reference, fixed.map(|c| c.as_ref()));
        // Near null space for algebraic multigrid (ignored by the default direct solve).
        let rigid_modes = dofs.rigid_body_modes(&scene.mesh);
        let jac = new_matrix(&pattern, dofs, &rigid_modes, model.pattern_moves())?;
        x.set_all(0.0)?;
        let ev = Evaluation { cx, model };
        let force_scale = residual_scale(&ev, &x)?;
        let interfaces = model.parts().len() > 1;
        let choice = linear::choose(scene, dofs.total_free, interfaces)?;
        let snes = new_snes(cx, model, (force_scale, choice.path), &rigid_modes)?;
        Ok(Linear {
            force_scale,
            choice,
            fixed_pattern: pattern.clone(),
            pattern,
            rigid_modes,
            jac,
            x_prev: x.duplicate()?,
            x_guess: x.duplicate()?,
            x_attempt: x.duplicate()?,
            x,
            snes,
            tangent: Tangent {
                ready: false,
                newton: NewtonTangent::Other,
            },
        })
    }
}

/// Newton and its linear solver for the model: the tolerances (the absolute one scaled by
/// `force_scale`), the linear solver `path`, the interface split (its bulk field with one set
/// of the `rigid_modes`), a frozen Jacobian for a linear scene, and the round-off floor's
/// length (*collective*).
pub(super) fn new_snes(
    cx: &Context,
    model: &Model,
    (force_scale, path): (f64, crate::petsc::LinearPath),
    rigid_modes: &[Vec<f64>],
) -> Result<Snes> {
    let (scene, dofs) = (cx.scene, &cx.dofs);
    let mut snes = Snes::new(
        Tolerances {
            atol: scene.newton.atol * force_scale,
            rtol: scene.newton.rtol,
            stol: 1e-14,
            max_it: scene.newton.max_it,
        },
        &options_source(scene),
        "basic",
        path,
    )?;
    let owned = (dofs.owned_start, dofs.owned_count);
    // The bulk field couples no two bodies: one set of six modes serves it.
    let bulk_modes = crate::dofs::one_set_of_six(rigid_modes);
    snes.split_interface(&linear::interface_dofs(model, dofs), owned, &bulk_modes)?;
    if scene.is_linear() {
        snes.freeze_jacobian()?;
    }
    let length = scene
        .mesh
        .coords
        .iter()
        .flatten()
        .fold(0.0, |m: f64, c| m.max(c.abs()));
    snes.set_round_off_length(length);
    Ok(snes)
}

/// A matrix of the pattern's sparsity, with the rigid body modes of every body as its near null
/// space; where the model's couplings move (`couplings_move`: contact), one that makes room for
/// entries outside the pattern.
pub(super) fn new_matrix(
    pattern: &Pattern,
    dofs: &DofMap,
    rigid_modes: &[Vec<f64>],
    couplings_move: bool,
) -> Result<Matrix> {
    let mut jac = Matrix::new_aij(&pattern.sparsity(dofs))?;
    jac.set_near_null_space(rigid_modes)?;
    if couplings_move {
        // A moving stencil the pattern does not hold (node-on-segment's, which is not checked
        // at the iterates) gets room from PETSc (counted, `Matrix::stored_entries`) instead of
        // failing.
        jac.allow_new_nonzeros()?;
    }
    Ok(jac)
}

/// Rank 0 partitions the elements with METIS; every rank receives the same partition.
fn partition(scene: &Scene, world: &SimpleCommunicator, ranks: usize) -> Result<Vec<usize>> {
    let n = scene.mesh.num_elements();
    let mut parts = vec![0u64; n];
    if ranks > 1 {
        if world.rank() == 0 {
            let p = crate::mesh::partition::partition_elements(&scene.mesh, ranks)?;
            parts.iter_mut().zip(p).for_each(|(a, b)| *a = b as u64);
        }
        world.process_at_rank(0).broadcast_into(&mut parts[..]);
    }
    Ok(parts.into_iter().map(|p| p as usize).collect())
}

/// The norm of the residual at u = 0 under the full load: the force scale of the absolute
/// Newton tolerance (1 if the scene is unloaded, or if a rank cannot evaluate it).
fn residual_scale(ev: &Evaluation, x: &Vector) -> Result<f64> {
    let norm = match ev.residual_at(x, 1.0)? {
        Some(f) => f.norm2()?,
        None => 0.0,
    };
    ev.cx
        .evaluator
        .borrow_mut()
        .u
        .iter_mut()
        .for_each(|v| *v = 0.0);
    Ok(if norm.is_finite() && norm > 0.0 {
        norm
    } else {
        1.0
    })
}

/// Where PETSc's options came from, for messages: the command line, the scene's options file,
/// and a study variant's `petsc` while one is set.
fn options_source(scene: &Scene) -> String {
    let mut sources = vec!["command line".to_string()];
    if let Some(f) = &scene.petsc_options {
        sources.push(f.display().to_string());
    }
    if crate::petsc::options::overridden() {
        sources.push("the study variant's `petsc`".into());
    }
    let n = sources.len();
    if n == 1 {
        sources.remove(0)
    } else {
        format!("{} or {}", sources[..n - 1].join(", "), sources[n - 1])
    }
}
