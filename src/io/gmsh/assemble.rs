//! From the parsed file to a mesh: the node coordinates by tag, the elements sorted by role,
//! the volume elements with their nodes numbered compactly in tag order, their bodies and
//! element sets, and the face and node sets of the lower-dimensional physical groups (see the
//! module documentation of [`super`]).

use std::collections::{BTreeMap, BTreeSet, HashMap};

use mshio::ElementType as GmshType;

use super::{gmsh_to_vtk_perm, Reader};
use crate::error::Result;
use crate::fe::ElementType;
use crate::mesh::{FaceRef, Mesh};

/// What a Gmsh element type becomes.
enum Role {
    Volume(ElementType),
    /// A surface element with this many corners.
    Surface(usize),
    /// Lines and points: only their nodes matter.
    Nodes,
}

fn role(t: GmshType) -> Option<Role> {
    Some(match t {
        GmshType::Hex8 => Role::Volume(ElementType::Hex8),
        GmshType::Hex20 => Role::Volume(ElementType::Hex20),
        GmshType::Hex27 => Role::Volume(ElementType::Hex27),
        GmshType::Tet4 => Role::Volume(ElementType::Tet4),
        GmshType::Tet10 => Role::Volume(ElementType::Tet10),
        GmshType::Qua4 | GmshType::Qua8 | GmshType::Qua9 => Role::Surface(4),
        GmshType::Tri3 | GmshType::Tri6 => Role::Surface(3),
        GmshType::Lin2 | GmshType::Lin3 | GmshType::Pnt => Role::Nodes,
        _ => return None,
    })
}

/// The physical groups of the file: those of every entity `(dim, tag)`, and their names.
pub(super) struct Groups {
    of_entity: HashMap<(i32, i32), Vec<i32>>,
    names: HashMap<(i32, i32), String>,
}

impl Groups {
    /// The groups of the entities (each entity's sorted, unique, positive tags) and the names
    /// of `$PhysicalNames`.
    pub(super) fn new(
        entities: Option<&mshio::Entities<i32, f64>>,
        names: HashMap<(i32, i32), String>,
    ) -> Groups {
        let mut of_entity: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
        if let Some(ent) = entities {
            let mut add = |dim: i32, tag: i32, phys: &[i32]| {
                let mut g: Vec<i32> = phys.iter().map(|p| p.abs()).collect();
                g.sort_unstable();
                g.dedup();
                of_entity.insert((dim, tag), g);
            };
            for p in &ent.points {
                add(0, p.tag, &p.physical_tags);
            }
            for c in &ent.curves {
                add(1, c.tag, &c.physical_tags);
            }
            for s in &ent.surfaces {
                add(2, s.tag, &s.physical_tags);
            }
            for v in &ent.volumes {
                add(3, v.tag, &v.physical_tags);
            }
        }
        Groups { of_entity, names }
    }

    /// The groups of entity `(dim, tag)` (none if it has no entry).
    fn of(&self, dim: i32, tag: i32) -> Vec<i32> {
        self.of_entity.get(&(dim, tag)).cloned().unwrap_or_default()
    }

    /// The name of group `tag` of dimension `dim`: from `$PhysicalNames`, else
    /// `"physical_<tag>"`.
    fn name(&self, dim: i32, tag: i32) -> String {
        self.names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical_{tag}"))
    }
}

/// A volume element of the file.
pub(super) struct Volume {
    kind: ElementType,
    /// Its Gmsh element tag.
    pub(super) tag: u64,
    /// Its nodes' Gmsh tags, in VTK order.
    nodes: Vec<u64>,
    /// Its entity's physical groups.
    groups: Vec<i32>,
}

/// A surface, line or point element in a physical group.
pub(super) struct Lower {
    dim: i32,
    tag: u64,
    /// Corners of a surface element (0 for lines and points).
    corners: usize,
    nodes: Vec<u64>,
    groups: Vec<i32>,
}

/// Every set sorted, without duplicates.
fn sorted_sets<T: Ord>(mut sets: BTreeMap<String, Vec<T>>) -> BTreeMap<String, Vec<T>> {
    for v in sets.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    sets
}

impl Reader {
    /// The coordinates of every node by tag. Sized from the nodes actually read, never from the
    /// header's claim.
    pub(super) fn node_coordinates(
        &self,
        bytes: &[u8],
        stored: (bool, usize),
        nodes: &mshio::Nodes<u64, i32, f64>,
    ) -> Result<HashMap<u64, [f64; 3]>> {
        let read: usize = nodes.node_blocks.iter().map(|b| b.nodes.len()).sum();
        if read as u64 != nodes.num_nodes {
            return Err(self.err(format!(
                "$Nodes header claims {} nodes but its blocks hold {read}",
                nodes.num_nodes
            )));
        }
        let counts: Vec<usize> = nodes.node_blocks.iter().map(|b| b.nodes.len()).collect();
        let tags = self.node_tags(bytes, stored, &counts)?;
        let mut coords: HashMap<u64, [f64; 3]> = HashMap::with_capacity(read);
        let in_file_order = nodes.node_blocks.iter().flat_map(|b| &b.nodes);
        for (&tag, n) in tags.iter().zip(in_file_order) {
            if coords.insert(tag, [n.x, n.y, n.z]).is_some() {
                return Err(self.err(format!("node tag {tag} is defined twice in $Nodes")));
            }
        }
        Ok(coords)
    }

    /// The volume elements (nodes permuted to VTK order) and the lower-dimensional elements in
    /// a physical group, in file order; an error for an unsupported element type or a file
    /// without volume elements.
    pub(super) fn sort_elements(
        &self,
        elements: &mshio::Elements<u64, i32>,
        groups: &Groups,
    ) -> Result<(Vec<Volume>, Vec<Lower>)> {
        let mut volumes: Vec<Volume> = Vec::new();
        let mut lower: Vec<Lower> = Vec::new();
        for block in &elements.element_blocks {
            let gtype = block.element_type;
            let Some(r) = role(gtype) else {
                return Err(self.err(format!(
                    "unsupported element type {} ({gtype:?}) in entity ({}, {}); supported: \
                     hex8 (5), hex20 (17), hex27 (12), tet4 (4), tet10 (11), and for groups quad4 \
                     (3), quad8 (16), quad9 (10), tri3 (2), tri6 (9), lines (1, 8), points (15)",
                    gtype as u32, block.entity_dim, block.entity_tag
                )));
            };
            let groups = groups.of(block.entity_dim, block.entity_tag);
            for el in &block.elements {
                match r {
                    Role::Volume(kind) => volumes.push(Volume {
                        kind,
                        tag: el.element_tag,
                        nodes: gmsh_to_vtk_perm(kind)
                            .iter()
                            .map(|&k| el.nodes[k])
                            .collect(),
                        groups: groups.clone(),
                    }),
                    Role::Surface(_) | Role::Nodes if !groups.is_empty() => lower.push(Lower {
                        dim: block.entity_dim,
                        tag: el.element_tag,
                        corners: if let Role::Surface(c) = r { c } else { 0 },
                        nodes: el.nodes.clone(),
                        groups: groups.clone(),
                    }),
                    _ => {}
                }
            }
        }
        if volumes.is_empty() {
            return Err(
                self.err("no volume elements (hex8, hex20, hex27, tet4 or tet10) in the file")
            );
        }
        Ok((volumes, lower))
    }

    /// The mesh of the volume elements: their nodes numbered compactly in tag order (returned
    /// as the node of each tag), one body per 3D group (each element's smallest; elements in
    /// none form the body `"body"`), and an element set per 3D group.
    pub(super) fn volume_mesh(
        &self,
        volumes: &[Volume],
        coords: &HashMap<u64, [f64; 3]>,
        groups: &Groups,
    ) -> Result<(Mesh, HashMap<u64, usize>)> {
        let mut used: BTreeSet<u64> = BTreeSet::new();
        for v in volumes {
            for &t in &v.nodes {
                if !coords.contains_key(&t) {
                    return Err(self.err(format!(
                        "element {} refers to node {t}, which is not in $Nodes",
                        v.tag
                    )));
                }
                used.insert(t);
            }
        }
        let index: HashMap<u64, usize> = used.iter().enumerate().map(|(i, &t)| (t, i)).collect();
        let mut mesh = Mesh::new();
        mesh.coords = used.iter().map(|t| coords[t]).collect();
        let body_groups: BTreeSet<i32> = volumes
            .iter()
            .filter_map(|v| v.groups.first().copied())
            .collect();
        let mut body_of_group: HashMap<i32, usize> = HashMap::new();
        for &g in &body_groups {
            body_of_group.insert(g, mesh.bodies.len());
            mesh.bodies.push(groups.name(3, g));
        }
        let mut default_body = None;
        let mut element_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for v in volumes {
            let body = match v.groups.first() {
                Some(g) => body_of_group[g],
                None => *default_body.get_or_insert_with(|| {
                    mesh.bodies.push("body".to_string());
                    mesh.bodies.len() - 1
                }),
            };
            let conn: Vec<usize> = v.nodes.iter().map(|t| index[t]).collect();
            let e = mesh.push_element(v.kind, body, &conn);
            for &g in &v.groups {
                element_sets.entry(groups.name(3, g)).or_default().push(e);
            }
        }
        mesh.element_sets = sorted_sets(element_sets);
        Ok((mesh, index))
    }

    /// The face sets (surface elements matched to volume faces) and node sets of the
    /// lower-dimensional groups.
    pub(super) fn add_group_sets(
        &self,
        mesh: &mut Mesh,
        lower: &[Lower],
        index: &HashMap<u64, usize>,
        groups: &Groups,
    ) -> Result<()> {
        let faces = faces_by_corners(mesh);
        let mut face_sets: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
        let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for l in lower {
            let group = || groups.name(l.dim, l.groups[0]);
            let mut local = Vec::with_capacity(l.nodes.len());
            for &t in &l.nodes {
                match index.get(&t) {
                    Some(&i) => local.push(i),
                    None => {
                        return Err(self.err(format!(
                            "element {} (dimension {}, physical group '{}') uses node {t}, which \
                             belongs to no volume element",
                            l.tag,
                            l.dim,
                            group()
                        )))
                    }
                }
            }
            let face = if l.corners > 0 {
                let corners = &local[..l.corners];
                let face = matching_face(mesh, &faces, corners).ok_or_else(|| {
                    self.err(format!(
                        "surface element {} (physical group '{}', nodes {:?}) is not a face \
                         of any volume element",
                        l.tag,
                        group(),
                        &l.nodes[..l.corners]
                    ))
                })?;
                Some(face)
            } else {
                None
            };
            for &g in &l.groups {
                let name = groups.name(l.dim, g);
                if let Some(f) = face {
                    face_sets.entry(name.clone()).or_default().push(f);
                }
                node_sets.entry(name).or_default().extend_from_slice(&local);
            }
        }
        mesh.face_sets = sorted_sets(face_sets);
        mesh.node_sets = sorted_sets(node_sets);
        Ok(())
    }
}

/// The faces of the volume elements by their sorted corner nodes ([`corner_key`]).
fn faces_by_corners(mesh: &Mesh) -> HashMap<[usize; 4], Vec<FaceRef>> {
    let mut faces: HashMap<[usize; 4], Vec<FaceRef>> = HashMap::new();
    for e in 0..mesh.num_elements() {
        let kind = mesh.types[e];
        for face in 0..kind.num_faces() {
            let f = FaceRef { element: e, face };
            let corners = &mesh.face_nodes(f)[..kind.face_type().num_corners()];
            faces.entry(corner_key(corners)).or_default().push(f);
        }
    }
    faces
}

/// The volume face with these corner nodes: for an interface face shared by two volume
/// elements, the one whose face has the corners' orientation, else the lower index.
fn matching_face(
    mesh: &Mesh,
    faces: &HashMap<[usize; 4], Vec<FaceRef>>,
    corners: &[usize],
) -> Option<FaceRef> {
    let cands = faces
        .get(&corner_key(corners))
        .map(|v| v.as_slice())
        .unwrap_or(&[]);
    cands
        .iter()
        .find(|f| same_orientation(&mesh.face_nodes(**f)[..corners.len()], corners))
        .or(cands.first())
        .copied()
}

/// Sorted corner nodes, padded with `usize::MAX`.
fn corner_key(corners: &[usize]) -> [usize; 4] {
    let mut k = [usize::MAX; 4];
    k[..corners.len()].copy_from_slice(corners);
    k.sort_unstable();
    k
}

/// True when the cyclic sequence `b` is a rotation of the cyclic sequence `a`.
fn same_orientation(a: &[usize], b: &[usize]) -> bool {
    let n = a.len();
    n == b.len() && (0..n).any(|s| (0..n).all(|i| a[(i + s) % n] == b[i]))
}
