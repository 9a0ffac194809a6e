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

use super::bulk::gather_nodes;
use super::model::Model;
use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::{Error, Result};
use crate::io::output::{
    lock_folder, write_pvd, write_pvtu, write_vtu, Field, FolderLock, History, Piece, Summary,
};
use crate::solid::element_stress;

/// One converged step, as a history row: `step, load, newton_its, augmentations, cuts,
/// linear_its, residual`, the reaction components of every reaction set, the contact force
/// sums of every contact interface (`contact_<name>_normal`, `_tangential`, `_fx`, `_fy`,
/// `_fz`, `_stick`, `_slip`, `_dissipation`, `_max_slip`: see `ContactInterfaces::force_sums`), and the seconds of assembly, solve and output.
/// Newton iterations are summed over the step's Uzawa solves.
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
    pub contact_forces: &'a [[f64; crate::contact::frictional::FORCE_SUMS]],
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
const CELL_FIELDS: [(&str, usize); 3] = [("cauchy_stress", 9), ("von_mises", 1), ("rank", 1)];

impl Results {
    /// Creates the output folders and removes an earlier run's outputs (rank 0; collective:
    /// every rank returns the same [`Error::Output`] on failure), and sets the history columns.
    pub fn new(
        scene: &Scene,
        dir: &Path,
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<Results> {
        use mpi::traits::Communicator;
        let (rank, ranks) = (world.rank() as usize, world.size() as usize);
        let (prepared, lock) = if rank == 0 {
            match lock_folder(dir) {
                Ok(lock) => (prepare_folder(dir, &scene.name), lock),
                Err(e) => (Err(e), None),
            }
        } else {
            (Ok(()), None)
        };
        super::agree_on(world, prepared)?;
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
            for iface in scene
                .interfaces
                .iter()
                .filter(|i| i.kind == crate::case::InterfaceKind::Contact)
            {
                for c in [
                    "normal",
                    "tangential",
                    "fx",
                    "fy",
                    "fz",
                    "stick",
                    "slip",
                    "dissipation",
                    "max_slip",
                ] {
                    cols.push(format!("contact_{}_{c}", iface.name));
                }
            }
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
    pub fn reactions(
        &self,
        scene: &Scene,
        model: &Model,
        u: &[f64],
        t: f64,
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<Vec<[f64; 3]>> {
        let mut nodal = vec![0.0; u.len()];
        model.nodal_forces(scene, u, t, &mut nodal);
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
        Ok(global.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
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
        super::agree_on(world, failed)
    }

    /// Writes this rank's VTU piece; once every rank has written its own (agreed on:
    /// [`Results::agree`]), rank 0 writes the PVTU and the PVD.
    #[allow(clippy::too_many_arguments)]
    pub fn write_step(
        &mut self,
        scene: &Scene,
        dofs: &DofMap,
        model: &Model,
        u: &[f64],
        step: usize,
        t: f64,
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<()> {
        let mesh = &scene.mesh;
        let mut local_index = BTreeMap::new();
        for (i, &n) in dofs.local_nodes.iter().enumerate() {
            local_index.insert(n, i);
        }
        let points: Vec<[f64; 3]> = dofs.local_nodes.iter().map(|&n| mesh.coords[n]).collect();
        let disp: Vec<f64> = dofs
            .local_nodes
            .iter()
            .flat_map(|&n| [u[3 * n], u[3 * n + 1], u[3 * n + 2]])
            .collect();
        let (mut types, mut conn, mut offsets) = (Vec::new(), Vec::new(), Vec::new());
        let (mut stress, mut mises, mut rank_field) = (Vec::new(), Vec::new(), Vec::new());
        let mut ue = Vec::new();
        for (e, geom) in model.bulk.elements() {
            types.push(mesh.types[*e].vtk_cell_type());
            conn.extend(mesh.element_nodes(*e).iter().map(|n| local_index[n]));
            offsets.push(conn.len());
            gather_nodes(u, mesh.element_nodes(*e), &mut ue);
            let (s, vm) = element_stress(geom, &scene.materials[mesh.body[*e]], &ue);
            stress.extend(s.transpose().iter().copied());
            mises.push(vm);
            rank_field.push(self.rank as f64);
        }
        let piece = Piece {
            points: &points,
            cell_types: &types,
            connectivity: &conn,
            offsets: &offsets,
            point_data: vec![Field {
                name: "displacement",
                components: 3,
                values: &disp,
            }],
            cell_data: vec![
                Field {
                    name: "cauchy_stress",
                    components: 9,
                    values: &stress,
                },
                Field {
                    name: "von_mises",
                    components: 1,
                    values: &mises,
                },
                Field {
                    name: "rank",
                    components: 1,
                    values: &rank_field,
                },
            ],
        };
        let case = self.case.clone();
        let piece_name = |r: usize| format!("vtu/{case}_{step:04}_r{r}.vtu");
        let written = write_vtu(&self.dir.join(piece_name(self.rank)), &piece);
        self.keep(written);
        self.agree(world)?;
        if self.rank == 0 {
            let pvtu = format!("{}_{step:04}.pvtu", self.case);
            let pieces: Vec<String> = (0..self.ranks).map(piece_name).collect();
            let written = write_pvtu(&self.dir.join(&pvtu), &pieces, &POINT_FIELDS, &CELL_FIELDS)
                .and_then(|()| {
                    self.pvd.push((t, pvtu));
                    write_pvd(&self.dir.join(format!("{}.pvd", self.case)), &self.pvd)
                });
            self.keep(written);
        }
        Ok(())
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
        row.extend(r.contact_forces.iter().flatten());
        row.extend(r.seconds);
        let written = h.push_row(row);
        self.keep(written);
    }

    /// Writes every interface pass as its own VTU, with a PVD per interface and pass (rank 0):
    /// the faces that carried the tractions (reference coordinates), with point fields
    /// `displacement` and `normal` (the averaged unit face normal of the reference faces), and
    /// - tied interfaces: `traction` (t_A), `weighted_gap` (g_A), `gap` (g_A / a_A) and `a`
    ///   (a_A);
    /// - contact interfaces: `pressure` (p_A), `gap` (gh_A, positive in penetration),
    ///   `slip` (the step's normalized slip increment dsh_A), `traction_t` (tangential traction),
    ///   `traction` (p_A nu_A + t_T), `status` (0 open, 1 stick, 2 slip) and `a` (a_A).
    ///
    /// At nodes that carry no traction (mid-nodes under scheme 2) the tractions and pressure are
    /// interpolated by the scheme's functions, `status` is -1 (no traction unknown: not
    /// "open"), and the other fields are zero there.
    pub fn write_interfaces(
        &mut self,
        scene: &Scene,
        model: &Model,
        u: &[f64],
        step: usize,
        t: f64,
        world: &mpi::topology::SimpleCommunicator,
    ) {
        for (i, tied) in model.tying.interfaces.iter().enumerate() {
            for (p, pass) in tied.passes.iter().enumerate() {
                let (traction, gap) = model.tying.pass_fields(i, p, u, world);
                if self.rank != 0 {
                    continue;
                }
                let rows: Vec<usize> = pass.rows.iter().map(|r| r.node).collect();
                let flat = |v: &[[f64; 3]]| -> Vec<f64> { v.iter().flatten().copied().collect() };
                let weighted: Vec<f64> = gap
                    .iter()
                    .zip(&pass.rows)
                    .flat_map(|(g, r)| g.map(|v| v * r.area))
                    .collect();
                let area: Vec<f64> = pass.rows.iter().map(|r| r.area).collect();
                let (traction, gap) = (flat(&traction), flat(&gap));
                let fields = [
                    row_field("traction", 3, &traction, true),
                    row_field("weighted_gap", 3, &weighted, false),
                    row_field("gap", 3, &gap, false),
                    row_field("a", 1, &area, false),
                ];
                let stem = format!("{}_{}_pass{}", self.case, tied.name, p + 1);
                let written = self.write_interface_step(
                    scene,
                    &stem,
                    tied.scheme,
                    &pass.secondary,
                    &rows,
                    &fields,
                    u,
                    step,
                    t,
                );
                self.keep(written);
            }
        }
        for (i, iface) in model.contact.interfaces.iter().enumerate() {
            for (p, pass) in iface.passes.iter().enumerate() {
                let nf = model.contact.pass_fields(scene, i, p, u, world);
                if self.rank != 0 {
                    continue;
                }
                let vec3 =
                    |f: &dyn Fn(&crate::contact::frictional::NodeFields) -> [f64; 3]| -> Vec<f64> {
                        nf.iter().flat_map(f).collect()
                    };
                let scalar =
                    |f: &dyn Fn(&crate::contact::frictional::NodeFields) -> f64| -> Vec<f64> {
                        nf.iter().map(f).collect()
                    };
                let pressure = scalar(&|f| f.pressure);
                let gap = scalar(&|f| f.gap);
                let slip = vec3(&|f| f.slip);
                let traction_t = vec3(&|f| f.traction_t);
                let traction =
                    vec3(&|f| std::array::from_fn(|c| f.pressure * f.normal[c] + f.traction_t[c]));
                let status = scalar(&|f| f.status as f64);
                let area = scalar(&|f| f.area);
                let fields = [
                    row_field("pressure", 1, &pressure, true),
                    row_field("gap", 1, &gap, false),
                    row_field("slip", 3, &slip, false),
                    row_field("traction_t", 3, &traction_t, true),
                    row_field("traction", 3, &traction, true),
                    row_field("status", 1, &status, false).absent_as(-1.0),
                    row_field("a", 1, &area, false),
                ];
                let stem = format!("{}_{}_pass{}", self.case, iface.name, p + 1);
                let written = self.write_interface_step(
                    scene,
                    &stem,
                    iface.scheme,
                    &pass.secondary,
                    &pass.nodes,
                    &fields,
                    u,
                    step,
                    t,
                );
                self.keep(written);
            }
        }
    }

    /// One interface pass at one step: its VTU and its PVD (rank 0).
    #[allow(clippy::too_many_arguments)]
    fn write_interface_step(
        &mut self,
        scene: &Scene,
        stem: &str,
        scheme: crate::contact::mortar::TractionScheme,
        faces: &[crate::mesh::FaceRef],
        rows: &[usize],
        fields: &[RowField],
        u: &[f64],
        step: usize,
        t: f64,
    ) -> Result<()> {
        let file = format!("vtu/{stem}_{step:04}.vtu");
        write_interface_piece(&self.dir.join(&file), scene, scheme, faces, rows, fields, u)?;
        let series = self.interface_pvd.entry(stem.to_string()).or_default();
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

    /// The scene's verification metrics, reduced over ranks.
    pub fn metrics(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        model: &Model,
        u: &[f64],
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<Vec<(String, f64)>> {
        let local =
            crate::verify::local_figures(scene, model.bulk.elements(), &dofs.local_nodes, u);
        let reduce = |pairs: &[(&'static str, f64)], op: SystemOperation| {
            let vals: Vec<f64> = pairs.iter().map(|p| p.1).collect();
            let mut out = vec![0.0; vals.len()];
            world.all_reduce_into(&vals[..], &mut out[..], op);
            pairs
                .iter()
                .map(|p| p.0)
                .zip(out)
                .collect::<BTreeMap<_, _>>()
        };
        let sums = reduce(&local.sums, SystemOperation::sum());
        let maxima = reduce(&local.maxima, SystemOperation::max());
        let mut out = crate::verify::metrics(&sums, &maxima);
        out.extend(self.contact_metrics(scene, model, u, world));
        Ok(out)
    }

    /// Contact figures: per interface the largest normalized gap (`max_gap_<name>`, positive in
    /// penetration; only when some node has an overlap at the end) and the largest penetration
    /// relative to the node size h_A (`max_rel_penetration_<name>`; 0 when nothing
    /// penetrates, also when the bodies have parted), and for the
    /// contact patch test `max_rel_pressure_error` (the largest |p_A - p0| / p0 over every node
    /// with an overlap) and `net_contact_force` (|sum of every contact nodal force| / (p0 times
    /// the contact area)).
    fn contact_metrics(
        &self,
        scene: &Scene,
        model: &Model,
        u: &[f64],
        world: &mpi::topology::SimpleCommunicator,
    ) -> Vec<(String, f64)> {
        let contact = &model.contact;
        let mut out = Vec::new();
        let patch_pressure = match scene.verification {
            Some(crate::case::Verification::ContactPatch { pressure, .. }) => Some(pressure),
            _ => None,
        };
        let (mut pressure_error, mut area) = (0.0f64, 0.0);
        for (i, iface) in contact.interfaces.iter().enumerate() {
            let mut worst_gap = f64::NEG_INFINITY;
            let mut worst_rel = 0.0f64;
            for (p, pass) in iface.passes.iter().enumerate() {
                let fields = contact.pass_fields(scene, i, p, u, world);
                for (f, st) in fields.iter().zip(&pass.state) {
                    if f.area <= 0.0 {
                        continue;
                    }
                    worst_gap = worst_gap.max(f.gap);
                    worst_rel = worst_rel.max(f.gap / st.h);
                    if let Some(p0) = patch_pressure {
                        pressure_error = pressure_error.max((f.pressure - p0).abs() / p0);
                        if p == 0 {
                            area += f.area;
                        }
                    }
                }
            }
            // Always there, so that an expectation on it holds when the bodies have parted (0:
            // nothing penetrates); the largest gap only exists where a node has an overlap.
            out.push((format!("max_rel_penetration_{}", iface.name), worst_rel));
            if worst_gap.is_finite() {
                out.push((format!("max_gap_{}", iface.name), worst_gap));
            }
        }
        if let Some(crate::case::Verification::Hertz {
            radius,
            interface,
            model_fraction,
            e_star,
        }) = &scene.verification
        {
            out.extend(hertz_metrics(
                scene,
                model,
                u,
                world,
                interface,
                *radius,
                *model_fraction,
                *e_star,
            ));
        }
        if let Some(p0) = patch_pressure {
            let mut nodal = vec![0.0; u.len()];
            contact.add_nodal_forces(scene, u, &mut nodal);
            let mut local = [0.0; 3];
            for (d, v) in nodal.iter().enumerate() {
                local[d % 3] += v;
            }
            let mut total = [0.0f64; 3];
            world.all_reduce_into(&local[..], &mut total[..], SystemOperation::sum());
            let net = (total[0].powi(2) + total[1].powi(2) + total[2].powi(2)).sqrt();
            out.push(("max_rel_pressure_error".into(), pressure_error));
            out.push((
                "net_contact_force".into(),
                net / (p0 * area).max(f64::MIN_POSITIVE),
            ));
        }
        out
    }
}

/// The `hertz` verification's metrics (`crate::verify`, "Hertz"), from the nodal fields of
/// the first pass of the contact interface `interface`, gathered on every rank: the force from
/// the nodal forces, the contact radius and the peak pressure from the interpolated pressure
/// field `p_h = sum_A p_A Phi_A` integrated over the current secondary faces.
#[allow(clippy::too_many_arguments)]
fn hertz_metrics(
    scene: &Scene,
    model: &Model,
    u: &[f64],
    world: &mpi::topology::SimpleCommunicator,
    interface: &str,
    radius: f64,
    model_fraction: f64,
    e_star: f64,
) -> Vec<(String, f64)> {
    use crate::contact::mortar::{sub_segments, traction_nodes, traction_shape};
    use crate::verify::PressurePoint;
    let contact = &model.contact;
    let Some(i) = contact.interfaces.iter().position(|c| c.name == interface) else {
        return Vec::new();
    };
    let Some(spec) = scene.interfaces.iter().find(|c| c.name == interface) else {
        return Vec::new();
    };
    let scheme = spec.method.carrier_scheme(spec.scheme);
    let fields = contact.pass_fields(scene, i, 0, u, world);
    let pass = &contact.interfaces[i].passes[0];
    let mesh = &scene.mesh;
    let current =
        |n: usize| -> [f64; 3] { std::array::from_fn(|c| mesh.coords[n][c] + u[3 * n + c]) };
    // The force: the nodal forces' axial components.
    let axial: f64 = fields
        .iter()
        .map(|f| f.area * f.pressure * f.normal[2])
        .sum();
    let force = axial.abs() / model_fraction;
    let pressed = fields.iter().filter(|f| f.pressure > 0.0).count();
    let max_pressure = fields.iter().map(|f| f.pressure).fold(0.0, f64::max);
    // p_h at the quadrature points of every secondary face that carries a pressure.
    let row = |n: usize| pass.nodes.binary_search(&n).ok();
    let mut points = Vec::new();
    let (mut phi, mut shape) = (Vec::new(), Vec::new());
    for &face in &pass.secondary {
        let kind = mesh.face_type(face);
        let nodes = mesh.face_nodes(face);
        let Ok(carriers) = traction_nodes(kind, scheme) else {
            continue;
        };
        let p: Vec<f64> = carriers
            .iter()
            .map(|&k| row(nodes[k]).map_or(0.0, |r| fields[r].pressure))
            .collect();
        if p.iter().all(|&v| v <= 0.0) {
            continue;
        }
        let x: Vec<[f64; 3]> = nodes.iter().map(|&n| current(n)).collect();
        shape.resize(kind.num_nodes(), 0.0);
        for (s, seg) in sub_segments(kind).iter().enumerate() {
            let rule = seg.linear_kind().quadrature(HERTZ_QUADRATURE_DEGREE);
            for (local, w) in rule.points.iter().zip(&rule.weights) {
                let xi = seg.to_parent(*local);
                traction_shape(kind, scheme, s, xi, &mut phi);
                kind.shape(xi, &mut shape);
                let (_, jac) = crate::fe::face_normal(kind, &x, xi);
                let at: [f64; 3] = std::array::from_fn(|c| {
                    shape.iter().zip(&x).map(|(n, xa)| n * xa[c]).sum::<f64>()
                });
                points.push(PressurePoint {
                    r2: at[0] * at[0] + at[1] * at[1],
                    pressure: phi.iter().zip(&p).map(|(f, v)| f * v).sum(),
                    weight: w * seg.parent_jacobian() * jac,
                });
            }
        }
    }
    let mut out = vec![
        ("contact_force".to_string(), force),
        ("hertz_contact_nodes".to_string(), pressed as f64),
        ("max_pressure".to_string(), max_pressure),
    ];
    if force > 0.0 {
        let (a_h, p0_h) = crate::verify::hertz(force, radius, e_star);
        out.push(("hertz_contact_radius".into(), a_h));
        out.push(("hertz_peak_pressure".into(), p0_h));
        if let Some(m) = crate::verify::hertz_measure(&points) {
            let ea = (m.contact_radius - a_h).abs() / a_h;
            let ep = (m.peak_pressure - p0_h).abs() / p0_h;
            out.push(("contact_radius".into(), m.contact_radius));
            out.push(("peak_pressure".into(), m.peak_pressure));
            out.push(("rel_error_contact_radius".into(), ea));
            out.push(("rel_error_peak_pressure".into(), ep));
            out.push(("rel_error_hertz".into(), ea.max(ep)));
        }
    }
    out
}

/// Degree of the rule on each (sub-)segment for the Hertz measurement: exact for `p_h r^2 dA`
/// on flat bilinear faces (degree 1 + 2 + 1 per direction, tensor Gauss), near it on curved
/// quadratic ones.
const HERTZ_QUADRATURE_DEGREE: usize = 7;

fn row_field<'a>(
    name: &'static str,
    components: usize,
    values: &'a [f64],
    interpolate: bool,
) -> RowField<'a> {
    RowField {
        name,
        components,
        values,
        interpolate,
        absent: 0.0,
    }
}

/// A point field of an interface piece, given at the traction nodes (one value per row).
struct RowField<'a> {
    name: &'static str,
    components: usize,
    /// `components` values per row.
    values: &'a [f64],
    /// At nodes without a traction unknown (mid-nodes under scheme 2), the field interpolated
    /// by the scheme's traction functions; otherwise `absent` there.
    interpolate: bool,
    absent: f64,
}

impl RowField<'_> {
    /// The value written at nodes without a traction unknown, when not interpolated.
    fn absent_as(self, absent: f64) -> Self {
        RowField { absent, ..self }
    }
}

/// One interface side as a VTU piece: the faces that carried the tractions (reference
/// coordinates) with point fields `displacement`, `normal` (the averaged unit face normal, from
/// the reference geometry) and the given row fields; `rows` are the traction nodes in field
/// order.
fn write_interface_piece(
    path: &Path,
    scene: &Scene,
    scheme: crate::contact::mortar::TractionScheme,
    faces: &[crate::mesh::FaceRef],
    rows: &[usize],
    fields: &[RowField],
    u: &[f64],
) -> Result<()> {
    use crate::contact::mortar::{traction_nodes, traction_shape, TractionScheme};
    let mesh = &scene.mesh;
    let row_of: BTreeMap<usize, usize> = rows.iter().enumerate().map(|(r, &n)| (n, r)).collect();
    let mut index: BTreeMap<usize, usize> = BTreeMap::new();
    let (mut types, mut conn, mut offsets) = (Vec::new(), Vec::new(), Vec::new());
    let mut normal_sum: Vec<[f64; 3]> = Vec::new();
    // Interpolation at nodes without a traction unknown: (point, rows and weights) per face.
    let mut interp: Vec<Vec<(usize, f64)>> = Vec::new();
    let mut counts: Vec<f64> = Vec::new();
    let mut phi = Vec::new();
    for &f in faces {
        let nodes = mesh.face_nodes(f);
        let kind = mesh.face_type(f);
        let x: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
        let carriers = traction_nodes(kind, scheme).unwrap_or_default();
        for (&n, xi) in nodes.iter().zip(kind.node_coords()) {
            let next = index.len();
            let k = *index.entry(n).or_insert(next);
            if k == normal_sum.len() {
                normal_sum.push([0.0; 3]);
                interp.push(Vec::new());
                counts.push(0.0);
            }
            let (nrm, _) = crate::fe::face_normal(kind, &x, xi);
            for c in 0..3 {
                normal_sum[k][c] += nrm[c];
            }
            if !row_of.contains_key(&n) && scheme != TractionScheme::PiecewiseLinear {
                traction_shape(kind, scheme, 0, xi, &mut phi);
                for (p, &local) in phi.iter().zip(&carriers) {
                    if let Some(&r) = row_of.get(&nodes[local]) {
                        interp[k].push((r, *p));
                    }
                }
                counts[k] += 1.0;
            }
            conn.push(k);
        }
        offsets.push(conn.len());
        types.push(kind.vtk_cell_type());
    }
    let n = index.len();
    let mut points = vec![[0.0; 3]; n];
    let mut disp = vec![0.0; 3 * n];
    for (&node, &k) in &index {
        points[k] = mesh.coords[node];
        disp[3 * k..3 * k + 3].copy_from_slice(&u[3 * node..3 * node + 3]);
    }
    let normals: Vec<f64> = normal_sum
        .iter()
        .flat_map(|v| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                .sqrt()
                .max(f64::MIN_POSITIVE);
            [v[0] / l, v[1] / l, v[2] / l]
        })
        .collect();
    let point_values: Vec<Vec<f64>> = fields
        .iter()
        .map(|fld| {
            let nc = fld.components;
            let mut out = vec![if fld.interpolate { 0.0 } else { fld.absent }; nc * n];
            for (&node, &k) in &index {
                if let Some(&r) = row_of.get(&node) {
                    out[nc * k..nc * (k + 1)].copy_from_slice(&fld.values[nc * r..nc * (r + 1)]);
                } else if fld.interpolate && counts[k] > 0.0 {
                    for &(r, p) in &interp[k] {
                        for c in 0..nc {
                            out[nc * k + c] += p * fld.values[nc * r + c] / counts[k];
                        }
                    }
                }
            }
            out
        })
        .collect();
    let mut point_data = vec![
        Field {
            name: "displacement",
            components: 3,
            values: &disp,
        },
        Field {
            name: "normal",
            components: 3,
            values: &normals,
        },
    ];
    for (fld, values) in fields.iter().zip(&point_values) {
        point_data.push(Field {
            name: fld.name,
            components: fld.components,
            values,
        });
    }
    let piece = Piece {
        points: &points,
        cell_types: &types,
        connectivity: &conn,
        offsets: &offsets,
        point_data,
        cell_data: vec![],
    };
    write_vtu(path, &piece)
}

/// Creates `dir/vtu` and removes the outputs an earlier run of case `case` left in `dir`
/// ([`is_run_output`]); other files are left alone.
fn prepare_folder(dir: &Path, case: &str) -> Result<()> {
    let vtu = dir.join("vtu");
    std::fs::create_dir_all(&vtu).map_err(|e| Error::io(&vtu, e))?;
    for (folder, in_vtu) in [(dir, false), (vtu.as_path(), true)] {
        let entries = std::fs::read_dir(folder).map_err(|e| Error::io(folder, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(folder, e))?;
            let is_file = entry.file_type().is_ok_and(|t| t.is_file());
            let name = entry.file_name();
            if is_file
                && name
                    .to_str()
                    .is_some_and(|n| is_run_output(n, case, in_vtu))
            {
                let path = entry.path();
                match std::fs::remove_file(&path) {
                    Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                        return Err(Error::io(&path, e))
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}

/// Whether a file named `name` in a run's folder (or in its `vtu/` when `in_vtu`) is one a run
/// of case `case` writes: `summary.json`, `history.csv`, `displacement.csv`, `<case>.pvd`,
/// `<case>_<step>.pvtu`, `vtu/<case>_<step>_r<rank>.vtu`, and per interface pass
/// `<case>_<interface>_pass<p>.pvd` and `vtu/<case>_<interface>_pass<p>_<step>.vtu` (`<step>`
/// four digits or more), or the temporary file of one of these (`.<name>.<pid>.tmp`, left by a
/// killed run: `io::output::write_atomic`). Another case whose name extends this one's
/// (`<case>_big`) keeps its steps and pieces; only a file of its that reads as an interface
/// pass of this case (`<case>_big_pass1.pvd`, an interface `big`) would go.
fn is_run_output(name: &str, case: &str, in_vtu: bool) -> bool {
    let name = temporary_target(name).unwrap_or(name);
    if !in_vtu && matches!(name, "summary.json" | "history.csv" | "displacement.csv") {
        return true;
    }
    let Some(rest) = name.strip_prefix(case) else {
        return false;
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let step = |s: &str| s.len() >= 4 && digits(s);
    // `_<interface>_pass<p>` followed by `tail`.
    let pass = |s: &str, tail: &dyn Fn(&str) -> bool| {
        s.strip_prefix('_')
            .and_then(|s| s.rsplit_once("_pass"))
            .is_some_and(|(interface, p)| {
                let end = p.find(|c: char| !c.is_ascii_digit()).unwrap_or(p.len());
                !interface.is_empty() && end > 0 && tail(&p[end..])
            })
    };
    if in_vtu {
        let Some(rest) = rest.strip_suffix(".vtu") else {
            return false;
        };
        let piece = rest
            .strip_prefix('_')
            .and_then(|r| r.split_once("_r"))
            .is_some_and(|(s, r)| step(s) && digits(r));
        piece || pass(rest, &|t| t.strip_prefix('_').is_some_and(step))
    } else {
        rest == ".pvd"
            || rest
                .strip_prefix('_')
                .and_then(|r| r.strip_suffix(".pvtu"))
                .is_some_and(step)
            || rest
                .strip_suffix(".pvd")
                .is_some_and(|r| pass(r, &|t| t.is_empty()))
    }
}

/// The file a temporary file of `io::output::write_atomic` (`.<name>.<pid>.tmp`) was for.
fn temporary_target(name: &str) -> Option<&str> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (target, pid) = inner.rsplit_once('.')?;
    (!pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())).then_some(target)
}

#[cfg(test)]
mod tests {
    use super::{is_run_output, temporary_target};

    #[test]
    fn a_run_removes_only_its_case_outputs() {
        let ours = [
            "summary.json",
            "history.csv",
            "displacement.csv",
            "blocks.pvd",
            "blocks_0003.pvtu",
            "blocks_contact_pass2.pvd",
            ".blocks.pvd.4242.tmp",
            ".summary.json.7.tmp",
        ];
        for name in ours {
            assert!(is_run_output(name, "blocks", false), "{name}");
        }
        let theirs = [
            "notes.txt",
            "blocksworld.pvd",
            "other.pvd",
            "blocks.vtu",
            "blocks.pvtu",
            "blocks_big.pvd",
            "blocks_big_0001.pvtu",
            "blocks_0001.pvd",
            "blocks_01.pvtu",
            "blocks_contact_pass.pvd",
            "blocks__pass1.pvd",
            "figure",
            ".blocks.pvd.tmp",
            ".blocks.pvd.12a.tmp",
            "summary.json.bak",
            "case.toml",
        ];
        for name in theirs {
            assert!(!is_run_output(name, "blocks", false), "{name}");
        }
        assert!(is_run_output("blocks_0001_r1.vtu", "blocks", true));
        assert!(is_run_output("blocks_12345_r10.vtu", "blocks", true));
        assert!(is_run_output(
            "blocks_contact_pass2_0003.vtu",
            "blocks",
            true
        ));
        assert!(is_run_output(
            "blocks_a_pass_b_pass1_0003.vtu",
            "blocks",
            true
        ));
        assert!(is_run_output(".blocks_0001_r0.vtu.99.tmp", "blocks", true));
        for theirs in [
            "other_0001_r0.vtu",
            "blocks.vtu",
            "blocks_big_0001_r0.vtu",
            "blocks_0001_r.vtu",
            "blocks_contact_pass2.vtu",
            "blocks_contact_pass_0003.vtu",
        ] {
            assert!(!is_run_output(theirs, "blocks", true), "{theirs}");
        }
        assert!(!is_run_output("summary.json", "blocks", true));
        assert_eq!(temporary_target(".a.b.12.tmp"), Some("a.b"));
        assert_eq!(temporary_target("a.12.tmp"), None);
    }
}
