//! What a run leaves on disk, step by step.
//!
//! Layout of the output folder:
//!
//! - `vtu/<case>_<step>_r<rank>.vtu`: one piece per rank (its own elements): reference
//!   coordinates, point field `displacement`, cell fields `cauchy_stress` (9 components,
//!   volume-averaged), `von_mises`, `rank`. In ParaView: open the PVD, then Warp By Vector.
//! - `<case>_<step>.pvtu`: joins the pieces of a step; `<case>.pvd`: the time series (time = load
//!   factor), rewritten after each step.
//! - `history.csv`: one row per converged step, and per step accepted without convergence under
//!   `steps.on_failure = "continue"` (`converged` = 0; see [`Results::push_history`]).
//! - `displacement.csv`: every node's reference position and displacement at the last converged
//!   step (`node,x,y,z,ux,uy,uz`).
//! - `summary.json`: see `io::output::Summary`.
//!
//! Every file is written atomically (temporary file, then rename). A run first removes from its
//! folder the files an earlier run of the same case left there (the files above, named after
//! the case, and the temporary files of writes a killed run left unfinished; nothing else), so
//! that every output file describes this run: a rerun with fewer steps, passes or interfaces
//! leaves no stale series behind, and a folder without `summary.json` holds a run that has not
//! finished a step.
//!
//! A file that cannot be written (a full disk, a folder without write permission) is one
//! rank's failure at first; every collective call of the step still runs on every rank, and the
//! ranks agree on the failure at the end of the step's output ([`Results::agree`]), so that the
//! run stops with one line, [`Error::Output`], on any number of ranks.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mpi::collective::{CommunicatorCollectives, SystemOperation};

mod carried;
mod folder;
mod interface;

use super::collective::agree_on;
use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::{Error, Result};
use crate::io::output::{
    lock_folder, write_pvd, write_pvtu, write_vtu, Field, FolderLock, History, Piece, Summary,
};
use crate::model::{CellField, Output, SurfaceOutput};
use folder::prepare_folder;
use interface::write_interface_piece;

/// One converged step, as a history row: `step, load, newton_its, augmentations, cuts,
/// converged, linear_its, residual`, the reaction components and mean prescribed displacements
/// of every reaction set, the mean displacement of every tracked set, the contributions'
/// history columns (the contact force sums of every contact interface, `contact_<name>_normal`,
/// `_tangential`, `_fx`, `_fy`, `_fz`, `_stick`, `_slip`, `_dissipation`, `_max_slip`), the
/// matrix's stored entries, and the seconds of assembly, solve and output. Newton iterations are summed over the step's Uzawa
/// solves.
pub struct StepRow<'a> {
    pub step: usize,
    pub load: f64,
    pub newton_its: usize,
    pub augmentations: usize,
    pub cuts: usize,
    /// False for a step accepted without convergence (`steps.on_failure = "continue"`).
    pub converged: bool,
    pub linear_its: usize,
    pub residual: f64,
    pub reactions: &'a [[f64; 3]],
    /// Displacements (dof-indexed; the constrained dofs at least).
    pub u: &'a [f64],
    /// Mean displacement of each tracked set (`Results::tracked`).
    pub tracked: &'a [[f64; 3]],
    /// The contributions' history values, in the order of their columns.
    pub contributions: &'a [f64],
    /// The entries the matrix stores, over the ranks, at the step's end: its pattern and any
    /// entry a Newton iterate added outside it.
    pub matrix_entries: u64,
    pub seconds: [f64; 3],
}

/// Per-run output state.
pub struct Results {
    dir: PathBuf,
    case: String,
    rank: usize,
    ranks: usize,
    history: Option<History>,
    pvd: Vec<(f64, String)>,
    /// Time series of each interface pass, by file stem.
    interface_pvd: BTreeMap<String, Vec<(f64, String)>>,
    reaction_sets: Vec<(String, Vec<usize>)>,
    /// The first write of this rank that failed since the last [`Results::agree`].
    failed: Option<Error>,
    /// Rank 0's lock on the folder ([`lock_folder`]), held for the run's life.
    _lock: Option<FolderLock>,
}

const POINT_FIELDS: [(&str, usize); 1] = [("displacement", 3)];

impl Results {
    /// Creates the output folders and removes an earlier run's outputs, unless `restart`
    /// (which keeps them: [`Results::read_state`] sorts them out) (rank 0; collective: every
    /// rank returns the same [`Error::Output`] on failure), and sets the history columns
    /// (`contributions`: the model's own, after the tracked sets').
    pub fn new(
        scene: &Scene,
        (dir, restart): (&Path, bool),
        contributions: Vec<String>,
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<Results> {
        use mpi::traits::Communicator;
        let (rank, ranks) = (world.rank() as usize, world.size() as usize);
        let (prepared, lock) = if rank == 0 {
            match lock_folder(dir) {
                Ok(lock) if restart => (Ok(()), lock),
                Ok(lock) => (prepare_folder(dir, &scene.name), lock),
                Err(e) => (Err(e), None),
            }
        } else {
            (Ok(()), None)
        };
        agree_on(world, prepared)?;
        // Every rank writes its pieces there (its own view of the folder, where ranks do not
        // share a file system's cache).
        if rank != 0 {
            let vtu = dir.join("vtu");
            std::fs::create_dir_all(&vtu).map_err(|e| Error::io(&vtu, e))?;
        }
        let reaction_sets: Vec<(String, Vec<usize>)> = scene
            .reaction_sets
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        let history = (rank == 0).then(|| {
            let mut cols: Vec<String> = [
                "step",
                "load",
                "newton_its",
                "augmentations",
                "cuts",
                "converged",
                "linear_its",
                "residual",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect();
            for (name, _) in &reaction_sets {
                for c in ["x", "y", "z"] {
                    cols.push(format!("reaction_{name}_{c}"));
                }
            }
            for (name, _) in &reaction_sets {
                for c in ["x", "y", "z"] {
                    cols.push(format!("u_{name}_{c}"));
                }
            }
            for (name, _) in &scene.tracked {
                for c in ["x", "y", "z"] {
                    cols.push(format!("track_{name}_{c}"));
                }
            }
            cols.extend(contributions);
            cols.push("matrix_entries".to_string());
            cols.extend(["seconds_assembly", "seconds_solve", "seconds_output"].map(String::from));
            History::new(dir.join("history.csv"), cols)
        });
        Ok(Results {
            dir: dir.to_path_buf(),
            case: scene.name.clone(),
            rank,
            ranks,
            history,
            pvd: Vec::new(),
            interface_pvd: BTreeMap::new(),
            reaction_sets,
            failed: None,
            _lock: lock,
        })
    }

    /// Reaction force on each reaction set: the sum of `f_int - f_ext` over its constrained
    /// dofs, over all ranks. Returned in `reaction_sets` order, as `[x, y, z]`.
    /// `nodal`: this rank's nodal forces (`solver::assembly::nodal_forces`).
    pub fn reactions(
        &self,
        nodal: &[f64],
        world: &mpi::topology::SimpleCommunicator,
    ) -> Vec<[f64; 3]> {
        let mut local = Vec::with_capacity(3 * self.reaction_sets.len());
        for (_, dofs) in &self.reaction_sets {
            let mut r = [0.0; 3];
            for &d in dofs {
                r[d % 3] += nodal[d];
            }
            local.extend_from_slice(&r);
        }
        let mut global = vec![0.0; local.len()];
        world.all_reduce_into(&local[..], &mut global[..], SystemOperation::sum());
        global.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// The mean displacement of each tracked set (collective: owners sum, all reduce).
    pub fn tracked(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        world: &mpi::topology::SimpleCommunicator,
    ) -> Vec<[f64; 3]> {
        let mut local = Vec::with_capacity(4 * scene.tracked.len());
        for (_, nodes) in &scene.tracked {
            let mut sum = [0.0f64; 4];
            for &n in nodes.iter().filter(|&&n| dofs.node_owner[n] == self.rank) {
                for c in 0..3 {
                    sum[c] += u[3 * n + c];
                }
                sum[3] += 1.0;
            }
            local.extend(sum);
        }
        let mut all = vec![0.0f64; local.len()];
        world.all_reduce_into(&local[..], &mut all[..], SystemOperation::sum());
        all.chunks(4)
            .map(|v| std::array::from_fn(|c| v[c] / v[3].max(1.0)))
            .collect()
    }

    /// The mean constrained displacement of each reaction set, per axis (0 where the set
    /// constrains no dof along that axis).
    fn set_displacements(&self, u: &[f64]) -> Vec<[f64; 3]> {
        self.reaction_sets
            .iter()
            .map(|(_, dofs)| {
                let (mut sum, mut count) = ([0.0; 3], [0usize; 3]);
                for &d in dofs {
                    sum[d % 3] += u[d];
                    count[d % 3] += 1;
                }
                std::array::from_fn(|c| {
                    if count[c] > 0 {
                        sum[c] / count[c] as f64
                    } else {
                        0.0
                    }
                })
            })
            .collect()
    }

    /// Keeps the first failed write (see [`Results::agree`]).
    fn keep(&mut self, written: Result<()>) {
        if let (None, Err(e)) = (&self.failed, written) {
            self.failed = Some(e);
        }
    }

    /// Collective: the ranks agree on the writes since the last call; when one failed, every
    /// rank returns the first failing rank's error as [`Error::Output`].
    pub fn agree(&mut self, world: &mpi::topology::SimpleCommunicator) -> Result<()> {
        let failed = self.failed.take().map_or(Ok(()), Err);
        agree_on(world, failed)
    }

    /// Writes a step's outputs: this rank's VTU piece of the volume (`outputs`' volume
    /// fields, with `displacement` and `rank`), the PVTU and the PVD once every rank has
    /// written its own (agreed on: [`Results::agree`]; rank 0), and every interface piece
    /// (rank 0).
    pub fn write_step(
        &mut self,
        (scene, dofs): (&Scene, &DofMap),
        outputs: &[Output],
        u: &[f64],
        (step, t): (usize, f64),
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<()> {
        let mut cell_fields: Vec<(&str, usize)> = Vec::new();
        for out in outputs {
            if let Output::Volume { elements, fields } = out {
                let written = self.write_volume_piece(scene, dofs, elements, fields, u, step);
                self.keep(written);
                cell_fields.extend(fields.iter().map(|f| (f.name, f.components)));
            }
        }
        cell_fields.push(("rank", 1));
        self.agree(world)?;
        if self.rank == 0 {
            let written = self.write_series(step, t, &cell_fields);
            self.keep(written);
            for out in outputs {
                if let Output::Surface(surface) = out {
                    let written = self.write_interface_step(scene, surface, u, step, t);
                    self.keep(written);
                }
            }
        }
        Ok(())
    }

    /// This rank's piece of the volume: its elements with their cell fields and `rank`.
    fn write_volume_piece(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        elements: &[usize],
        fields: &[CellField],
        u: &[f64],
        step: usize,
    ) -> Result<()> {
        let mesh = &scene.mesh;
        let local_index: BTreeMap<usize, usize> = dofs
            .local_nodes
            .iter()
            .enumerate()
            .map(|(i, &n)| (n, i))
            .collect();
        let points: Vec<[f64; 3]> = dofs.local_nodes.iter().map(|&n| mesh.coords[n]).collect();
        let disp: Vec<f64> = dofs
            .local_nodes
            .iter()
            .flat_map(|&n| [u[3 * n], u[3 * n + 1], u[3 * n + 2]])
            .collect();
        let (mut types, mut conn, mut offsets) = (Vec::new(), Vec::new(), Vec::new());
        for &e in elements {
            types.push(mesh.types[e].vtk_cell_type());
            conn.extend(mesh.element_nodes(e).iter().map(|n| local_index[n]));
            offsets.push(conn.len());
        }
        let rank_field = vec![self.rank as f64; elements.len()];
        let mut cell_data: Vec<Field> = fields
            .iter()
            .map(|f| Field::new(f.name, f.components, &f.values))
            .collect();
        cell_data.push(Field::new("rank", 1, &rank_field));
        let piece = Piece {
            points: &points,
            cell_types: &types,
            connectivity: &conn,
            offsets: &offsets,
            point_data: vec![Field::new("displacement", 3, &disp)],
            cell_data,
        };
        write_vtu(&self.dir.join(self.piece_name(step, self.rank)), &piece)
    }

    /// `vtu/<case>_<step>_r<rank>.vtu`.
    fn piece_name(&self, step: usize, rank: usize) -> String {
        format!("vtu/{}_{step:04}_r{rank}.vtu", self.case)
    }

    /// The step's PVTU over every rank's piece, and the PVD with it (rank 0).
    fn write_series(&mut self, step: usize, t: f64, cell_fields: &[(&str, usize)]) -> Result<()> {
        let pvtu = format!("{}_{step:04}.pvtu", self.case);
        let pieces: Vec<String> = (0..self.ranks).map(|r| self.piece_name(step, r)).collect();
        write_pvtu(&self.dir.join(&pvtu), &pieces, &POINT_FIELDS, cell_fields)?;
        self.pvd.push((t, pvtu));
        write_pvd(&self.dir.join(format!("{}.pvd", self.case)), &self.pvd)
    }

    /// Appends a history row (rank 0; a failure is kept for [`Results::agree`]).
    pub fn push_history(&mut self, r: &StepRow) {
        let set_u = self.set_displacements(r.u);
        let Some(h) = self.history.as_mut() else {
            return;
        };
        let mut row = vec![
            r.step as f64,
            r.load,
            r.newton_its as f64,
            r.augmentations as f64,
            r.cuts as f64,
            if r.converged { 1.0 } else { 0.0 },
            r.linear_its as f64,
            r.residual,
        ];
        row.extend(r.reactions.iter().flatten());
        row.extend(set_u.iter().flatten());
        row.extend(r.tracked.iter().flatten());
        row.extend(r.contributions);
        row.push(r.matrix_entries as f64);
        row.extend(r.seconds);
        let written = h.push_row(row);
        self.keep(written);
    }

    /// One interface pass at one step (rank 0): its VTU, and its PVD (`<case>_<name>.pvd`):
    /// the faces that carried the tractions (reference coordinates), with point fields
    /// `displacement` and `normal` (the averaged unit face normal of the reference faces), and
    /// the pass's own fields:
    /// - tied interfaces: `traction` (t_A), `weighted_gap` (g_A), `gap` (g_A / a_A) and `a`
    ///   (a_A);
    /// - contact interfaces: `pressure` (p_A), `gap` (gh_A, positive in penetration),
    ///   `slip` (the step's normalized slip increment dsh_A), `traction_t` (tangential traction),
    ///   `traction` (p_A nu_A + t_T), `status` (0 open, 1 stick, 2 slip) and `a` (a_A).
    ///
    /// At nodes that carry no traction (mid-nodes under scheme 2) the tractions and pressure are
    /// interpolated by the scheme's functions, `status` is -1 (no traction unknown: not
    /// "open"), and the other fields are zero there.
    fn write_interface_step(
        &mut self,
        scene: &Scene,
        surface: &SurfaceOutput,
        u: &[f64],
        step: usize,
        t: f64,
    ) -> Result<()> {
        let stem = format!("{}_{}", self.case, surface.name);
        let file = format!("vtu/{stem}_{step:04}.vtu");
        write_interface_piece(&self.dir.join(&file), scene, surface, u)?;
        let series = self.interface_pvd.entry(stem.clone()).or_default();
        series.push((t, file));
        write_pvd(&self.dir.join(format!("{stem}.pvd")), series)
    }

    /// Writes summary.json (rank 0 only; a failure is kept for [`Results::agree`]).
    pub fn write_summary(&mut self, summary: &Summary) {
        if self.rank == 0 {
            let written = summary.write(&self.dir.join("summary.json"));
            self.keep(written);
        }
    }

    /// Writes `displacement.csv` (rank 0): `node,x,y,z,ux,uy,uz` for every node, reference
    /// coordinates and displacements of the last converged step, gathered from the owners
    /// (collective; a failed write is kept for [`Results::agree`]).
    pub fn write_displacements(
        &mut self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        world: &mpi::topology::SimpleCommunicator,
    ) {
        let mut mine = vec![0.0; u.len()];
        for &n in dofs
            .local_nodes
            .iter()
            .filter(|&&n| dofs.node_owner[n] == self.rank)
        {
            mine[3 * n..3 * n + 3].copy_from_slice(&u[3 * n..3 * n + 3]);
        }
        let mut all = vec![0.0; u.len()];
        world.all_reduce_into(&mine[..], &mut all[..], SystemOperation::sum());
        if self.rank != 0 {
            return;
        }
        let mut csv = String::from("node,x,y,z,ux,uy,uz\n");
        for (n, x) in scene.mesh.coords.iter().enumerate() {
            let d = &all[3 * n..3 * n + 3];
            csv.push_str(&format!(
                "{n},{},{},{},{},{},{}\n",
                x[0], x[1], x[2], d[0], d[1], d[2]
            ));
        }
        let written =
            crate::io::output::write_atomic(&self.dir.join("displacement.csv"), csv.as_bytes());
        self.keep(written);
    }
}
