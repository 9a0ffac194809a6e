//! What a run leaves on disk, step by step.
//!
//! Layout of the output folder:
//!
//! - `vtu/<case>_<step>_r<rank>.vtu`: one piece per rank (its own elements): reference
//!   coordinates, point field `displacement`, cell fields `cauchy_stress` (9 components,
//!   volume-averaged), `von_mises`, `rank`. In ParaView: open the PVD, then Warp By Vector.
//! - `<case>_<step>.pvtu`: joins the pieces of a step; `<case>.pvd`: the time series (time = load
//!   factor), rewritten after each step.
//! - `history.csv`: one row per converged step (see [`Results::push_history`]).
//! - `displacement.csv`: every node's reference position and displacement at the last converged
//!   step (`node,x,y,z,ux,uy,uz`).
//! - `summary.json`: see `io::output::Summary`.
//!
//! Every file is written atomically (temporary file, then rename).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mpi::collective::{CommunicatorCollectives, SystemOperation};

use super::bulk::gather_nodes;
use super::model::Model;
use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::{Error, Result};
use crate::io::output::{write_pvd, write_pvtu, write_vtu, Field, History, Piece, Summary};
use crate::solid::element_stress;

/// One converged step, as a history row: `step, load, newton_its, augmentations, cuts,
/// linear_its, residual`, the reaction components of every reaction set, and the seconds of
/// assembly, solve and output. Newton iterations are summed over the step's Uzawa solves.
pub struct StepRow<'a> {
    pub step: usize,
    pub load: f64,
    pub newton_its: usize,
    pub augmentations: usize,
    pub cuts: usize,
    pub linear_its: usize,
    pub residual: f64,
    pub reactions: &'a [[f64; 3]],
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
}

const POINT_FIELDS: [(&str, usize); 1] = [("displacement", 3)];
const CELL_FIELDS: [(&str, usize); 3] = [("cauchy_stress", 9), ("von_mises", 1), ("rank", 1)];

impl Results {
    /// Creates the output folders (rank 0) and the history columns.
    pub fn new(scene: &Scene, dir: &Path, rank: usize, ranks: usize) -> Result<Results> {
        std::fs::create_dir_all(dir.join("vtu")).map_err(|e| Error::io(dir, e))?;
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

    /// Writes this rank's VTU piece; after a barrier, rank 0 writes the PVTU and the PVD.
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
        let piece_name = |r: usize| format!("vtu/{}_{step:04}_r{r}.vtu", self.case);
        write_vtu(&self.dir.join(piece_name(self.rank)), &piece)?;
        world.barrier();
        if self.rank == 0 {
            let pvtu = format!("{}_{step:04}.pvtu", self.case);
            let pieces: Vec<String> = (0..self.ranks).map(piece_name).collect();
            write_pvtu(&self.dir.join(&pvtu), &pieces, &POINT_FIELDS, &CELL_FIELDS)?;
            self.pvd.push((t, pvtu));
            write_pvd(&self.dir.join(format!("{}.pvd", self.case)), &self.pvd)?;
        }
        Ok(())
    }

    /// Appends a history row (rank 0).
    pub fn push_history(&mut self, r: &StepRow) -> Result<()> {
        let Some(h) = self.history.as_mut() else {
            return Ok(());
        };
        let mut row = vec![
            r.step as f64,
            r.load,
            r.newton_its as f64,
            r.augmentations as f64,
            r.cuts as f64,
            r.linear_its as f64,
            r.residual,
        ];
        row.extend(r.reactions.iter().flatten());
        row.extend(r.seconds);
        h.push_row(row)
    }

    /// Writes each tied interface (every pass) as its own VTU, with a PVD per interface and
    /// pass (rank 0): the faces that carried the tractions (reference coordinates), with point
    /// fields `displacement`, `traction` (t_A; at nodes that carry none, such as the mid-nodes
    /// under scheme 2, the traction interpolated by the scheme's functions), `weighted_gap`
    /// (g_A), `gap` (g_A / a_A), `a` (a_A; zero where no traction unknown) and `normal` (the
    /// averaged unit face normal at each node).
    pub fn write_interfaces(
        &mut self,
        scene: &Scene,
        model: &Model,
        u: &[f64],
        step: usize,
        t: f64,
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<()> {
        for (i, tied) in model.tying.interfaces.iter().enumerate() {
            for (p, pass) in tied.passes.iter().enumerate() {
                let (traction, gap) = model.tying.pass_fields(i, p, u, world);
                if self.rank != 0 {
                    continue;
                }
                let stem = format!("{}_{}_pass{}", self.case, tied.name, p + 1);
                let file = format!("vtu/{stem}_{step:04}.vtu");
                write_interface_piece(
                    &self.dir.join(&file),
                    scene,
                    tied.scheme,
                    &pass.secondary,
                    &pass.rows,
                    &traction,
                    &gap,
                    u,
                )?;
                let series = self.interface_pvd.entry(stem.clone()).or_default();
                series.push((t, file));
                write_pvd(&self.dir.join(format!("{stem}.pvd")), series)?;
            }
        }
        Ok(())
    }

    /// Writes summary.json (rank 0 only).
    pub fn write_summary(&self, summary: &Summary) -> Result<()> {
        if self.rank == 0 {
            summary.write(&self.dir.join("summary.json"))?;
        }
        Ok(())
    }

    /// Writes `displacement.csv` (rank 0): `node,x,y,z,ux,uy,uz` for every node, reference
    /// coordinates and displacements of the last converged step, gathered from the owners.
    pub fn write_displacements(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        world: &mpi::topology::SimpleCommunicator,
    ) -> Result<()> {
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
            return Ok(());
        }
        let mut csv = String::from("node,x,y,z,ux,uy,uz\n");
        for (n, x) in scene.mesh.coords.iter().enumerate() {
            let d = &all[3 * n..3 * n + 3];
            csv.push_str(&format!(
                "{n},{},{},{},{},{},{}\n",
                x[0], x[1], x[2], d[0], d[1], d[2]
            ));
        }
        crate::io::output::write_atomic(&self.dir.join("displacement.csv"), csv.as_bytes())
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
        Ok(crate::verify::metrics(&sums, &maxima))
    }
}

/// One interface side as a VTU piece (see [`Results::write_interfaces`]).
#[allow(clippy::too_many_arguments)]
fn write_interface_piece(
    path: &Path,
    scene: &Scene,
    scheme: crate::contact::mortar::TractionScheme,
    faces: &[crate::mesh::FaceRef],
    rows: &[crate::contact::tying::Row],
    traction: &[[f64; 3]],
    gap: &[[f64; 3]],
    u: &[f64],
) -> Result<()> {
    let mesh = &scene.mesh;
    let row_of: BTreeMap<usize, usize> = rows
        .iter()
        .enumerate()
        .map(|(r, row)| (row.node, r))
        .collect();
    let mut index: BTreeMap<usize, usize> = BTreeMap::new();
    let (mut types, mut conn, mut offsets) = (Vec::new(), Vec::new(), Vec::new());
    let mut normal_sum: Vec<[f64; 3]> = Vec::new();
    // Tractions interpolated at nodes without a traction unknown: sum and count per point.
    let mut interpolated: Vec<([f64; 3], f64)> = Vec::new();
    let mut phi = Vec::new();
    for &f in faces {
        let nodes = mesh.face_nodes(f);
        let kind = mesh.face_type(f);
        let x: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
        let carriers = crate::contact::mortar::traction_nodes(kind, scheme).unwrap_or_default();
        for (&n, xi) in nodes.iter().zip(kind.node_coords()) {
            let next = index.len();
            let k = *index.entry(n).or_insert(next);
            if k == normal_sum.len() {
                normal_sum.push([0.0; 3]);
                interpolated.push(([0.0; 3], 0.0));
            }
            let (nrm, _) = crate::fe::face_normal(kind, &x, xi);
            for c in 0..3 {
                normal_sum[k][c] += nrm[c];
            }
            if !row_of.contains_key(&n)
                && scheme != crate::contact::mortar::TractionScheme::PiecewiseLinear
            {
                crate::contact::mortar::traction_shape(kind, scheme, 0, xi, &mut phi);
                let acc = &mut interpolated[k];
                for (p, &local) in phi.iter().zip(&carriers) {
                    if let Some(&r) = row_of.get(&nodes[local]) {
                        for (a, t) in acc.0.iter_mut().zip(traction[r]) {
                            *a += p * t;
                        }
                    }
                }
                acc.1 += 1.0;
            }
            conn.push(k);
        }
        offsets.push(conn.len());
        types.push(kind.vtk_cell_type());
    }
    let mut points = vec![[0.0; 3]; index.len()];
    let mut disp = vec![0.0; 3 * index.len()];
    for (&n, &k) in &index {
        points[k] = mesh.coords[n];
        disp[3 * k..3 * k + 3].copy_from_slice(&u[3 * n..3 * n + 3]);
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
    let n = points.len();
    let (mut t_field, mut wg_field, mut g_field, mut a_field) = (
        vec![0.0; 3 * n],
        vec![0.0; 3 * n],
        vec![0.0; 3 * n],
        vec![0.0; n],
    );
    for (k, (sum, count)) in interpolated.iter().enumerate() {
        if *count > 0.0 {
            for c in 0..3 {
                t_field[3 * k + c] = sum[c] / count;
            }
        }
    }
    for (r, row) in rows.iter().enumerate() {
        if let Some(&k) = index.get(&row.node) {
            t_field[3 * k..3 * k + 3].copy_from_slice(&traction[r]);
            g_field[3 * k..3 * k + 3].copy_from_slice(&gap[r]);
            for c in 0..3 {
                wg_field[3 * k + c] = gap[r][c] * row.area;
            }
            a_field[k] = row.area;
        }
    }
    let piece = Piece {
        points: &points,
        cell_types: &types,
        connectivity: &conn,
        offsets: &offsets,
        point_data: vec![
            Field {
                name: "displacement",
                components: 3,
                values: &disp,
            },
            Field {
                name: "traction",
                components: 3,
                values: &t_field,
            },
            Field {
                name: "weighted_gap",
                components: 3,
                values: &wg_field,
            },
            Field {
                name: "gap",
                components: 3,
                values: &g_field,
            },
            Field {
                name: "a",
                components: 1,
                values: &a_field,
            },
            Field {
                name: "normal",
                components: 3,
                values: &normals,
            },
        ],
        cell_data: vec![],
    };
    write_vtu(path, &piece)
}
