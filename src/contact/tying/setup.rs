//! Setting up a tied interface: the mortar weights of every secondary face against the primary
//! side, integrated once on the reference configuration, gathered on every rank, and summed
//! into constraint rows (module docs, "Parallel layout").

use std::collections::BTreeMap;

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::datatype::PartitionMut;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::Count;

use crate::case::{Interface, Scene};
use crate::contact::mortar::{
    integrate_pair, traction_nodes, FaceGeom, IntegrationOptions, RejectStats,
};
use crate::contact::search::{Aabb, PrimaryTree};
use crate::dofs::DofMap;
use crate::error::Result;
use crate::mesh::FaceRef;

use super::Row;

/// An interface whose secondary side meets no primary face is an error; one covered by less
/// than 90 % of its area draws a warning (rank 0): tied faces are meant to lie on each other.
pub(super) fn check_coverage(
    scene: &Scene,
    iface: &Interface,
    pass: usize,
    secondary: &[FaceRef],
    rows: &[Row],
    world: &SimpleCommunicator,
) -> Result<()> {
    let tied: f64 = rows.iter().map(|r| r.area).sum();
    let side = if pass == 0 {
        &iface.secondary_set
    } else {
        &iface.primary_set
    };
    if rows.is_empty() {
        return Err(crate::Error::Mesh(format!(
            "interface '{}' ties nothing: no face of '{side}' overlaps the other side (farther \
             apart than the search margin, 10 % of a face's size, or facing the same way)",
            iface.name
        )));
    }
    let total: f64 = secondary.iter().map(|&f| face_area(scene, f)).sum();
    if tied < 0.9 * total && world.rank() == 0 {
        crate::error::print_warning(format_args!(
            "interface '{}': only {:.1} % of '{side}' is tied",
            iface.name,
            100.0 * tied / total
        ));
    }
    Ok(())
}

/// The area of one face (reference configuration).
fn face_area(scene: &Scene, f: FaceRef) -> f64 {
    let kind = scene.mesh.face_type(f);
    let x: Vec<[f64; 3]> = scene
        .mesh
        .face_nodes(f)
        .iter()
        .map(|&n| scene.mesh.coords[n])
        .collect();
    let rule = kind.quadrature(kind.default_quadrature_degree());
    rule.points
        .iter()
        .zip(&rule.weights)
        .map(|(&xi, w)| w * crate::fe::face_normal(kind, &x, xi).1)
        .sum()
}

/// A weight of one row: (traction node A, node, weight, side: 1 secondary / 2 primary).
pub(super) type Triplet = (usize, usize, f64, u8);

/// Integrates this rank's secondary faces against every primary face.
pub(super) fn integrate_side(
    scene: &Scene,
    dofs: &DofMap,
    iface: &Interface,
    secondary: &[FaceRef],
    primary: &[FaceRef],
) -> (Vec<Triplet>, RejectStats) {
    let mesh = &scene.mesh;
    let coords = |f: FaceRef| -> Vec<[f64; 3]> {
        mesh.face_nodes(f).iter().map(|&n| mesh.coords[n]).collect()
    };
    let primary_x: Vec<Vec<[f64; 3]>> = primary.iter().map(|&f| coords(f)).collect();
    let boxes: Vec<Aabb> = primary_x.iter().map(|x| Aabb::of_points(x)).collect();
    let tree = PrimaryTree::new(&boxes);
    let mut stats = RejectStats::default();
    let mut out = Vec::new();
    let mut candidates = Vec::new();
    for &s in secondary
        .iter()
        .filter(|f| dofs.element_rank[f.element] == dofs.rank)
    {
        let sx = coords(s);
        let s_kind = mesh.face_type(s);
        let s_nodes = mesh.face_nodes(s);
        let carriers = traction_nodes(s_kind, iface.scheme).expect("validated with the scene");
        let sbox = Aabb::of_points(&sx);
        tree.query(&sbox.inflated(0.1 * sbox.diagonal()), &mut candidates);
        for &p in &candidates {
            let p_kind = mesh.face_type(primary[p]);
            let p_nodes = mesh.face_nodes(primary[p]);
            let degree = iface.quadrature_degree.unwrap_or(
                if s_kind == crate::fe::FaceType::Quad4 && p_kind == crate::fe::FaceType::Quad4 {
                    4
                } else {
                    8
                },
            );
            let opts = IntegrationOptions {
                scheme: iface.scheme,
                degree,
                pallets: iface.pallets,
            };
            let w = integrate_pair(
                &FaceGeom {
                    kind: s_kind,
                    x: &sx,
                },
                &FaceGeom {
                    kind: p_kind,
                    x: &primary_x[p],
                },
                &opts,
                &mut stats,
            );
            for &(k, b, v) in &w.n1 {
                out.push((s_nodes[carriers[k]], s_nodes[b], v, 1));
            }
            for &(k, c, v) in &w.n2 {
                out.push((s_nodes[carriers[k]], p_nodes[c], v, 2));
            }
        }
    }
    (out, stats)
}

/// Every rank's triplets, on every rank, in rank order.
pub(super) fn all_gather(local: &[Triplet], world: &SimpleCommunicator) -> Vec<Triplet> {
    let flat: Vec<f64> = local
        .iter()
        .flat_map(|&(a, n, w, side)| [a as f64, n as f64, w, side as f64])
        .collect();
    let size = world.size() as usize;
    let mut counts = vec![0 as Count; size];
    world.all_gather_into(&(flat.len() as Count), &mut counts[..]);
    let displs: Vec<Count> = counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    let total = counts.iter().sum::<Count>() as usize;
    let mut all = vec![0.0; total];
    {
        let mut partition = PartitionMut::new(&mut all[..], counts, displs);
        world.all_gather_varcount_into(&flat[..], &mut partition);
    }
    all.chunks(4)
        .map(|c| (c[0] as usize, c[1] as usize, c[2], c[3] as u8))
        .collect()
}

/// Rejection counters summed over ranks.
pub(super) fn reduce_stats(
    local: &RejectStats,
    world: &SimpleCommunicator,
) -> BTreeMap<String, usize> {
    let map = local.to_map();
    let keys: Vec<&String> = map.keys().collect();
    let vals: Vec<u64> = map.values().map(|&v| v as u64).collect();
    let mut sums = vec![0u64; vals.len()];
    world.all_reduce_into(&vals[..], &mut sums[..], SystemOperation::sum());
    keys.into_iter()
        .cloned()
        .zip(sums.into_iter().map(|v| v as usize))
        .collect()
}

/// Rows from all triplets: weights of one (A, node) pair summed, a_A and the penalty set.
pub(super) fn build_rows(scene: &Scene, iface: &Interface, triplets: &[Triplet]) -> Vec<Row> {
    // Summed in a canonical order (not the ranks' order), so that the rows, and the results,
    // are bitwise the same on any number of ranks.
    let mut sorted = triplets.to_vec();
    sorted.sort_by_key(|x| (x.0, x.1, x.3, x.2.to_bits()));
    let mut by_a: BTreeMap<usize, BTreeMap<usize, f64>> = BTreeMap::new();
    let mut area: BTreeMap<usize, f64> = BTreeMap::new();
    for &(a, n, w, side) in &sorted {
        let signed = if side == 1 { w } else { -w };
        *by_a.entry(a).or_default().entry(n).or_insert(0.0) += signed;
        if side == 1 {
            *area.entry(a).or_insert(0.0) += w;
        }
    }
    let young = young_by_node(scene);
    let max_area = area.values().copied().fold(0.0, f64::max);
    by_a.into_iter()
        .filter_map(|(a, terms)| {
            let area = area.get(&a).copied().unwrap_or(0.0);
            // A node whose traction function barely meets the other side (a_A -> 0) would get
            // an unbounded eps_A / a_A: such rows are dropped (docs/theory.md section 10).
            if area <= 1e-12 * max_area {
                return None;
            }
            let h = area.sqrt();
            // Weights at round-off level (cancellations in the sums above) are dropped: they
            // change nothing but would widen the matrix.
            let largest = terms.values().fold(0.0f64, |m, w| m.max(w.abs()));
            Some(Row {
                node: a,
                area,
                eps: iface.penalty * young[a] / h,
                h,
                terms: terms
                    .into_iter()
                    .filter(|&(_, w)| w.abs() > 1e-12 * largest)
                    .collect(),
                lambda: [0.0; 3],
            })
        })
        .collect()
}

/// Young's modulus of the body of each node (the first element around it).
pub(crate) fn young_by_node(scene: &Scene) -> Vec<f64> {
    let mesh = &scene.mesh;
    let mut e = vec![0.0; mesh.num_nodes()];
    for el in (0..mesh.num_elements()).rev() {
        let young = scene.materials[mesh.body[el]].young();
        for &n in mesh.element_nodes(el) {
            e[n] = young;
        }
    }
    e
}
