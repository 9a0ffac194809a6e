//! One pass of a contact interface: which side carries the tractions, its traction nodes and
//! the state each node keeps between Newton solves.

use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};

use crate::case::{ContactMethod, Interface, Scene};
use crate::contact::law::{LawParams, NodeHistory};
use crate::contact::mortar::{traction_nodes, TractionScheme};
use crate::contact::normals::{NodalNormals, SurfaceFace};
use crate::dofs::DofMap;
use crate::error::Result;
use crate::fe::FaceType;
use crate::mesh::FaceRef;

use super::changes::StateLog;
use super::coverage::full_integrals;
use super::evaluate::ValuesAt;

/// The state of one traction node that persists between Newton solves.
#[derive(Clone, Debug, Default)]
pub struct NodeState {
    /// Uzawa multipliers and the converged tangential traction of the last step.
    pub history: NodeHistory,
    /// Initial penalties `alpha E / h_A` and `alpha_T E / h_A`.
    pub eps_n: f64,
    pub eps_t: f64,
    /// `h_A`: the mean size (square root of the area) of the secondary faces around A.
    pub h: f64,
    /// Integral of the node's traction function over the whole secondary surface (reference).
    pub a_full: f64,
    /// Weighted gap vector at the last converged step, if the node had an overlap then.
    pub gap_old: Option<[f64; 3]>,
    /// Node-on-segment: the primary face and closest point of the last converged step.
    pub segment_old: Option<(usize, [f64; 2])>,
}

/// One pass: which side carries the tractions, and its nodes' state.
#[derive(Clone, Debug)]
pub struct ContactPass {
    /// Faces carrying the tractions.
    pub secondary: Vec<FaceRef>,
    pub(crate) sec_faces: Vec<FaceData>,
    pub(crate) pri_faces: Vec<FaceData>,
    /// Traction nodes (global ids), ascending.
    pub nodes: Vec<usize>,
    /// Per secondary face: the index into `nodes` of its k-th traction node.
    pub(crate) carriers: Vec<Vec<usize>>,
    /// Per traction node: the secondary faces carrying it, with its index `k` in each.
    pub(crate) node_faces: Vec<Vec<(usize, usize)>>,
    /// Per traction node. Within a step the multipliers and history (`history`, `gap_old`,
    /// `segment_old`) are kept only by the rank holding the node. A pass shared by several
    /// ranks hands every rank every node's after each converged step (`share_held_state`);
    /// the state of a pass one rank does stays as it started on the other ranks. (The
    /// node-on-segment pattern reads `segment_old` on every rank: for such a pass a row owned
    /// by another rank may then miss the old face's columns, which costs PETSc a
    /// reallocation, not an error.)
    pub state: Vec<NodeState>,
    /// Per traction node: its reference position (along which the nodes are dealt).
    pub(crate) reference: Vec<[f64; 3]>,
    /// The ranks that share the pass's contact work, and this rank.
    pub(crate) workers: std::ops::Range<usize>,
    pub(crate) rank: usize,
    /// Secondary faces that carry a node this rank holds (the faces it integrates).
    pub(crate) local_faces: Vec<usize>,
    /// The traction nodes this rank holds: it does their contact work and keeps their
    /// multipliers and history (indices into `nodes`; see "Parallel layout").
    pub(crate) held: Vec<usize>,
    /// Per secondary face: this rank reports the face's pair statistics (it holds the face's
    /// first traction node), so that a face integrated on two ranks counts once.
    pub(crate) tallied: Vec<bool>,
    /// Symmetry constraints `(node, axis)` of the secondary surface (for the normals).
    pub(crate) symmetry: Vec<(usize, usize)>,
    /// Mortar or node-on-segment.
    pub(crate) method: ContactMethod,
    /// Every node of the pass's faces, ascending: their positions key `last_values`.
    pub(crate) surface_nodes: Vec<usize>,
    /// The last values-only integration and its search's candidates (`ContactPass::values_at`;
    /// the matrix pattern's check takes the candidates).
    pub(crate) last_values: RefCell<Option<ValuesAt>>,
    /// The law states at the last tangent evaluation (of the held nodes; of every node after a
    /// new deal), and their changes.
    pub(crate) state_log: RefCell<StateLog>,
    /// Per secondary face: the primary faces whose pairs the matrix pattern holds, ascending
    /// (mortar; recorded as the pattern's stencils are handed out: the `frictional` module
    /// docs, "Matrix pattern").
    pub(crate) held_pairs: RefCell<Vec<Vec<usize>>>,
    /// Traction nodes held pressed while a Newton update is solved again
    /// (`ContactInterfaces::hold_closing`): open at the iterate, carried through the other
    /// surface by the first update.
    pub(crate) closing_held: RefCell<std::collections::BTreeSet<usize>>,
}

/// A face's type and global nodes.
#[derive(Clone, Debug)]
pub(crate) struct FaceData {
    pub(crate) kind: FaceType,
    pub(crate) nodes: Vec<usize>,
}

impl ContactPass {
    /// One pass of `iface`: the faces `sec` carry the tractions against `pri`; the ranks
    /// `workers` share its contact work (module docs, "Parallel layout").
    pub(crate) fn new(
        scene: &Scene,
        dofs: &DofMap,
        iface: &Interface,
        (sec, pri): (&[FaceRef], &[FaceRef]),
        young: &[f64],
        workers: std::ops::Range<usize>,
    ) -> Result<ContactPass> {
        let mesh = &scene.mesh;
        let data = |faces: &[FaceRef]| -> Vec<FaceData> {
            faces
                .iter()
                .map(|&f| FaceData {
                    kind: mesh.face_type(f),
                    nodes: mesh.face_nodes(f),
                })
                .collect()
        };
        let sec_faces = data(sec);
        let pri_faces = data(pri);
        let carrier_scheme = iface.method.carrier_scheme(iface.scheme);
        let (nodes, carriers) = traction_nodes_of(&sec_faces, carrier_scheme)?;
        let (a_full, sizes) =
            full_integrals(scene, carrier_scheme, &sec_faces, &carriers, nodes.len());
        let state = nodes
            .iter()
            .zip(a_full.iter().zip(&sizes))
            .map(|(&n, (&a, &h))| NodeState {
                eps_n: iface.penalty * young[n] / h,
                eps_t: iface.tangential_penalty * young[n] / h,
                h,
                a_full: a,
                ..Default::default()
            })
            .collect();
        let reference: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
        let mut pass = ContactPass {
            secondary: sec.to_vec(),
            node_faces: faces_of_nodes(&carriers, nodes.len()),
            symmetry: symmetry_of(scene, &sec_faces),
            surface_nodes: surface_nodes(&sec_faces, &pri_faces),
            sec_faces,
            pri_faces,
            nodes,
            carriers,
            state,
            reference,
            workers,
            rank: dofs.rank,
            local_faces: Vec::new(),
            held: Vec::new(),
            tallied: Vec::new(),
            method: iface.method,
            last_values: RefCell::new(None),
            state_log: RefCell::new(StateLog::default()),
            held_pairs: RefCell::new(Vec::new()),
            closing_held: RefCell::new(Default::default()),
        };
        pass.deal(&mesh.coords);
        Ok(pass)
    }

    /// The law's parameters at a node: its penalties times the interface's growth factor
    /// `scale` and the node's [`super::coverage_scale`] `coverage` (1 for a covered node).
    pub(crate) fn law_params(
        &self,
        st: &NodeState,
        mu: f64,
        scale: f64,
        coverage: f64,
    ) -> LawParams {
        let scale = scale * coverage;
        LawParams {
            eps_n: st.eps_n * scale,
            eps_t: st.eps_t * scale,
            mu,
        }
    }

    /// Nodal normals of the secondary surface at positions `x`.
    pub(crate) fn normals(&self, x: &[[f64; 3]]) -> std::result::Result<NodalNormals, String> {
        let faces: Vec<SurfaceFace> = self
            .sec_faces
            .iter()
            .map(|f| SurfaceFace {
                kind: f.kind,
                nodes: &f.nodes,
            })
            .collect();
        NodalNormals::compute(&faces, x, &self.symmetry)
    }
}

/// The traction nodes of the secondary faces (global ids, ascending) and, per face, the
/// index into them of its k-th traction node.
fn traction_nodes_of(
    faces: &[FaceData],
    scheme: TractionScheme,
) -> Result<(Vec<usize>, Vec<Vec<usize>>)> {
    let mut nodes: Vec<usize> = Vec::new();
    let mut local_carriers: Vec<Vec<usize>> = Vec::new();
    for f in faces {
        let ks = traction_nodes(f.kind, scheme).map_err(crate::Error::Mesh)?;
        let global: Vec<usize> = ks.iter().map(|&k| f.nodes[k]).collect();
        nodes.extend(&global);
        local_carriers.push(global);
    }
    nodes.sort_unstable();
    nodes.dedup();
    let index: BTreeMap<usize, usize> = nodes.iter().enumerate().map(|(i, &n)| (n, i)).collect();
    let carriers = local_carriers
        .iter()
        .map(|g| g.iter().map(|n| index[n]).collect())
        .collect();
    Ok((nodes, carriers))
}

/// Per traction node: the faces carrying it, with its index `k` in each.
fn faces_of_nodes(carriers: &[Vec<usize>], count: usize) -> Vec<Vec<(usize, usize)>> {
    let mut node_faces = vec![Vec::new(); count];
    for (f, car) in carriers.iter().enumerate() {
        for (k, &a) in car.iter().enumerate() {
            node_faces[a].push((f, k));
        }
    }
    node_faces
}

/// The symmetry constraints `(node, axis)` of the scene on the nodes of `faces`.
fn symmetry_of(scene: &Scene, faces: &[FaceData]) -> Vec<(usize, usize)> {
    let surface: BTreeSet<usize> = faces.iter().flat_map(|f| f.nodes.iter().copied()).collect();
    scene
        .symmetry
        .iter()
        .filter(|(n, _)| surface.contains(n))
        .copied()
        .collect()
}

/// Every node of the secondary and primary faces, ascending.
fn surface_nodes(sec: &[FaceData], pri: &[FaceData]) -> Vec<usize> {
    let mut nodes: Vec<usize> = sec
        .iter()
        .chain(pri)
        .flat_map(|f| f.nodes.iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}
