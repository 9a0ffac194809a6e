//! METIS partitioning of the elements.
//!
//! The elements are the vertices of the **dual graph**; two elements are adjacent when they
//! share a face, i.e. when one face of each has the same set of corner nodes (3 for triangles,
//! 4 for quadrilaterals; a triangle never matches a quadrilateral). The graph is cut by METIS
//! k-way partitioning (`METIS_PartGraphKway`, default imbalance tolerance 3 %, fixed random
//! seed, so the result is deterministic for a given mesh and part count).
//!
//! Nodes are owned by the smallest part among the elements touching them ([`node_owners`]).

use std::collections::HashMap;

use metis::{Graph, Idx};

use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// Fixed METIS seed: the same mesh always gives the same partition.
const METIS_SEED: Idx = 12345;

/// The element dual graph in CSR form `(xadj, adjncy)`: face-sharing neighbours of each element,
/// sorted.
pub fn dual_graph(mesh: &Mesh) -> (Vec<usize>, Vec<usize>) {
    let ne = mesh.num_elements();
    let mut first: HashMap<[usize; 4], usize> = HashMap::new();
    let mut nbrs: Vec<Vec<usize>> = vec![Vec::new(); ne];
    for e in 0..ne {
        let kind = mesh.types[e];
        let en = mesh.element_nodes(e);
        let nc = kind.face_type().num_corners();
        for f in 0..kind.num_faces() {
            let mut key = [usize::MAX; 4];
            for (k, &l) in kind.face_nodes(f)[..nc].iter().enumerate() {
                key[k] = en[l];
            }
            key.sort_unstable();
            match first.get(&key) {
                Some(&other) if other != e => {
                    nbrs[e].push(other);
                    nbrs[other].push(e);
                }
                Some(_) => {}
                None => {
                    first.insert(key, e);
                }
            }
        }
    }
    let mut xadj = Vec::with_capacity(ne + 1);
    let mut adjncy = Vec::new();
    xadj.push(0);
    for mut v in nbrs {
        v.sort_unstable();
        v.dedup();
        adjncy.extend(v);
        xadj.push(adjncy.len());
    }
    (xadj, adjncy)
}

/// Part (`0..nparts`) of every element, by METIS k-way partitioning of the dual graph.
///
/// `nparts == 1` gives all zeros. With no more elements than parts, element `e` goes to part `e`
/// (some parts stay empty).
pub fn partition_elements(mesh: &Mesh, nparts: usize) -> Result<Vec<usize>> {
    let ne = mesh.num_elements();
    if nparts == 0 {
        return Err(Error::Mesh("cannot partition into 0 parts".into()));
    }
    if nparts == 1 {
        return Ok(vec![0; ne]);
    }
    if ne <= nparts {
        return Ok((0..ne).collect());
    }
    let too_big = |what: &str| Error::Mesh(format!("{what} too large for METIS indices"));
    let (xadj, adjncy) = dual_graph(mesh);
    let xadj: Vec<Idx> = xadj
        .into_iter()
        .map(Idx::try_from)
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| too_big("dual graph"))?;
    let adjncy: Vec<Idx> = adjncy
        .into_iter()
        .map(Idx::try_from)
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| too_big("dual graph"))?;
    let np = Idx::try_from(nparts).map_err(|_| too_big("part count"))?;
    let mut part: Vec<Idx> = vec![0; ne];
    // METIS keeps global state (its random generator): one call at a time in a process.
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = METIS
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    Graph::new(1, np, &xadj, &adjncy)
        .map_err(|e| Error::Mesh(format!("METIS rejected the dual graph: {e:?}")))?
        .set_option(metis::option::Seed(METIS_SEED))
        .part_kway(&mut part)
        .map_err(|e| {
            Error::Mesh(format!(
                "METIS k-way partitioning of {ne} elements into {nparts} parts failed: {e:?}"
            ))
        })?;
    let part: Vec<usize> = part
        .into_iter()
        .map(|p| {
            usize::try_from(p)
                .ok()
                .filter(|&p| p < nparts)
                .ok_or_else(|| Error::Mesh(format!("METIS returned part {p} of {nparts}")))
        })
        .collect::<Result<_>>()?;
    Ok(canonical_labels(part, nparts))
}

/// The same parts, numbered in the order in which the elements first meet them (the part of
/// element 0 is part 0), so that a partition METIS returns with its labels permuted (seen with
/// the same seed) gives the same ranks.
fn canonical_labels(part: Vec<usize>, nparts: usize) -> Vec<usize> {
    let mut label = vec![usize::MAX; nparts];
    let mut next = 0;
    for &p in &part {
        if label[p] == usize::MAX {
            label[p] = next;
            next += 1;
        }
    }
    part.into_iter().map(|p| label[p]).collect()
}

/// Owner part of every node: the smallest part among the elements touching it (part 0 for nodes
/// touched by no element).
pub fn node_owners(mesh: &Mesh, elem_part: &[usize], nparts: usize) -> Vec<usize> {
    debug_assert_eq!(elem_part.len(), mesh.num_elements());
    let mut owner = vec![usize::MAX; mesh.num_nodes()];
    for (e, &p) in elem_part.iter().enumerate() {
        debug_assert!(p < nparts.max(1));
        for &n in mesh.element_nodes(e) {
            owner[n] = owner[n].min(p);
        }
    }
    for o in &mut owner {
        if *o == usize::MAX {
            *o = 0;
        }
    }
    owner
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fe::ElementType;
    use crate::mesh::generate::box_mesh;

    #[test]
    fn dual_graph_of_a_box() {
        let m = box_mesh(ElementType::Hex8, [2, 2, 2], [0.0; 3], [1.0; 3], "b");
        let (xadj, adjncy) = dual_graph(&m);
        // Every hex of a 2x2x2 box has three face neighbours.
        for e in 0..8 {
            assert_eq!(xadj[e + 1] - xadj[e], 3);
        }
        assert_eq!(adjncy.len(), 24);
        let t = box_mesh(ElementType::Tet10, [2, 2, 2], [0.0; 3], [1.0; 3], "b");
        let (xadj, _) = dual_graph(&t);
        // 48 tets * 4 faces = interior pairs * 2 + boundary (6 sides * 4 cells * 2 triangles).
        assert_eq!(xadj[48], 48 * 4 - 48);
    }

    #[test]
    fn two_parts_of_a_box_are_balanced_and_owners_follow_the_rule() {
        for kind in [ElementType::Hex8, ElementType::Tet4, ElementType::Hex20] {
            let m = box_mesh(kind, [4, 4, 4], [0.0; 3], [1.0; 3], "b");
            let part = partition_elements(&m, 2).unwrap();
            assert_eq!(part, partition_elements(&m, 2).unwrap(), "deterministic");
            let ne = m.num_elements();
            let n1 = part.iter().filter(|&&p| p == 1).count();
            let n0 = ne - n1;
            assert!(n0 > 0 && n1 > 0);
            let half = ne as f64 / 2.0;
            assert!(
                (n0 as f64 - half).abs() <= 0.1 * half,
                "{kind:?}: {n0} vs {n1}"
            );
            let own = node_owners(&m, &part, 2);
            for (n, &o) in own.iter().enumerate() {
                let min = (0..ne)
                    .filter(|&e| m.element_nodes(e).contains(&n))
                    .map(|e| part[e])
                    .min()
                    .unwrap_or(0);
                assert_eq!(o, min);
            }
        }
    }

    #[test]
    fn trivial_partitions() {
        let m = box_mesh(ElementType::Hex8, [2, 1, 1], [0.0; 3], [1.0; 3], "b");
        assert_eq!(partition_elements(&m, 1).unwrap(), vec![0, 0]);
        assert_eq!(partition_elements(&m, 3).unwrap(), vec![0, 1]);
        assert!(partition_elements(&m, 0).is_err());
        let m4 = box_mesh(ElementType::Hex8, [4, 4, 4], [0.0; 3], [1.0; 3], "b");
        let p = partition_elements(&m4, 4).unwrap();
        for k in 0..4 {
            assert!(p.contains(&k));
        }
        let mut with_free = m.clone();
        with_free.coords.push([9.0; 3]);
        assert_eq!(node_owners(&with_free, &[1, 1], 2).last(), Some(&0));
    }
}
