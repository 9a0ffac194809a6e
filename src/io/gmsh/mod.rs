//! Gmsh `.msh` 4.1 import (ASCII and binary), parsed with the `mshio` crate.
//!
//! # Elements
//!
//! Gmsh element types 5 (hex8), 17 (hex20), 12 (hex27), 4 (tet4) and 11 (tet10) become mesh
//! elements, their nodes permuted from Gmsh's reference ordering to the VTK ordering of
//! [`crate::fe::element`]: `vtk[k] = gmsh[PERM[k]]`. Corners agree in both conventions; the
//! mid-edge and face nodes differ:
//!
//! - hex20: Gmsh edges are `8:(0,1) 9:(0,3) 10:(0,4) 11:(1,2) 12:(1,5) 13:(2,3) 14:(2,6) 15:(3,7)
//!   16:(4,5) 17:(4,7) 18:(5,6) 19:(6,7)`; VTK wants the bottom ring, the top ring, then the
//!   verticals.
//! - hex27: Gmsh face nodes are `20: zeta=-1, 21: eta=-1, 22: xi=-1, 23: xi=+1, 24: eta=+1,
//!   25: zeta=+1`, centre 26; VTK orders the faces `xi-, xi+, eta-, eta+, zeta-, zeta+`.
//! - tet10: Gmsh's node 8 is on edge (2,3) and node 9 on edge (1,3); VTK swaps them.
//!
//! Surface elements 3 (quad4), 16 (quad8), 10 (quad9), 2 (tri3), 9 (tri6), lines 1 and 8 and
//! points 15 only carry physical groups.
//!
//! # Physical groups
//!
//! A group is named by `$PhysicalNames` when present, else `"physical_<tag>"`.
//!
//! - dimension 3: an element set, and a body (each element's body is its 3D group of smallest
//!   tag; elements in no 3D group form the body `"body"`);
//! - dimension 2: a face set (each surface element is matched, by its corner node set, to the
//!   face of a volume element; for an interface face shared by two volume elements, the one
//!   whose face has the surface element's orientation, else the lower index) and a node set
//!   (all nodes of the surface elements);
//! - dimensions 0 and 1: node sets.
//!
//! Only nodes referenced by volume elements are kept, numbered in increasing Gmsh tag order;
//! a group that refers to any other node is an error. Surface, line and point elements in no
//! physical group are ignored.
//!
//! The node tags are read from the file in file order (`mshio` drops them when they are dense,
//! `max - min + 1 == count`, and keeps them in a map otherwise), so nodes listed out of tag
//! order are placed by their tags, and a tag defined twice is an error.
//!
//! The mesh is checked ([`Mesh::check`]) before it is returned; element messages then carry the
//! Gmsh element tag.

mod assemble;
mod format;

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::fe::ElementType;
use crate::mesh::Mesh;

/// Gmsh -> VTK node permutations: VTK node `k` is Gmsh node `PERM[k]`.
const HEX8_PERM: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
const HEX20_PERM: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
];
const HEX27_PERM: [usize; 27] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15, 22, 23, 21, 24, 20, 25,
    26,
];
const TET4_PERM: [usize; 4] = [0, 1, 2, 3];
const TET10_PERM: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

/// The Gmsh -> VTK permutation of a solid element type.
pub fn gmsh_to_vtk_perm(kind: ElementType) -> &'static [usize] {
    match kind {
        ElementType::Hex8 => &HEX8_PERM,
        ElementType::Hex20 => &HEX20_PERM,
        ElementType::Hex27 => &HEX27_PERM,
        ElementType::Tet4 => &TET4_PERM,
        ElementType::Tet10 => &TET10_PERM,
    }
}

/// Reads a Gmsh 4.1 file (ASCII or binary).
pub fn read_msh(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    read_msh_bytes(&bytes, path)
}

/// Reads Gmsh 4.1 content; `path` only names the source in messages.
pub fn read_msh_bytes(bytes: &[u8], path: &Path) -> Result<Mesh> {
    Reader {
        file: path.to_path_buf(),
    }
    .read(bytes)
}

/// Reads one file; its path names it in messages.
struct Reader {
    file: PathBuf,
}

impl Reader {
    fn err(&self, msg: impl Into<String>) -> Error {
        Error::Gmsh {
            file: self.file.clone(),
            msg: msg.into(),
        }
    }

    /// The file's steps: the header and the storage, `$PhysicalNames`, the parse, the nodes,
    /// the elements by role, the volume mesh (nodes, bodies, element sets), the face and node
    /// sets of the lower-dimensional groups, and the check of the whole.
    fn read(&self, bytes: &[u8]) -> Result<Mesh> {
        self.check_header(bytes)?;
        let stored = format::storage(bytes);
        if stored.0 && !self.little_endian(bytes) {
            return Err(self.err(
                "a big-endian binary file is not supported (write it on a little-endian \
                 machine, or as ASCII)",
            ));
        }
        let names = self.physical_names(bytes)?;
        let data = self.parse(bytes)?.data;
        let nodes = data.nodes.ok_or_else(|| self.err("no $Nodes section"))?;
        let elements = data
            .elements
            .ok_or_else(|| self.err("no $Elements section"))?;
        let coords = self.node_coordinates(bytes, stored, &nodes)?;
        let groups = assemble::Groups::new(data.entities.as_ref(), names);
        let (volumes, lower) = self.sort_elements(&elements, &groups)?;
        let (mut mesh, index) = self.volume_mesh(&volumes, &coords, &groups)?;
        self.add_group_sets(&mut mesh, &lower, &index, &groups)?;
        mesh.check_labelled(&|e| format!("element {e} (Gmsh element {})", volumes[e].tag))
            .map_err(|e| match e {
                Error::Mesh(m) => self.err(m),
                other => other,
            })?;
        Ok(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;
    use crate::mesh::FaceRef;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(name)
    }

    /// Gmsh reference coordinates, not derived from the permutations above: the corners (the
    /// same in both conventions), then the mid-edge nodes of Gmsh's edge lists and the hex27
    /// face and centre nodes in Gmsh's order (the Gmsh manual's node ordering figures, as in
    /// the module documentation).
    fn gmsh_reference(kind: ElementType) -> Vec<[f64; 3]> {
        let (corners, edges): (_, Vec<[usize; 2]>) = if kind.is_hex() {
            let edges = [
                [0, 1],
                [0, 3],
                [0, 4],
                [1, 2],
                [1, 5],
                [2, 3],
                [2, 6],
                [3, 7],
                [4, 5],
            ];
            let last = [[4, 7], [5, 6], [6, 7]];
            (
                ElementType::Hex8.node_coords(),
                [&edges[..], &last].concat(),
            )
        } else {
            let edges = [[0, 1], [1, 2], [2, 0], [0, 3], [2, 3], [1, 3]];
            (ElementType::Tet4.node_coords(), edges.to_vec())
        };
        let mut x = corners.clone();
        for [a, b] in edges {
            x.push(std::array::from_fn(|d| {
                0.5 * (corners[a][d] + corners[b][d])
            }));
        }
        // Faces zeta = -1, eta = -1, xi = -1, xi = +1, eta = +1, zeta = +1, then the centre.
        for (axis, side) in [
            (2, -1.0),
            (1, -1.0),
            (0, -1.0),
            (0, 1.0),
            (1, 1.0),
            (2, 1.0),
        ] {
            let mut centre = [0.0; 3];
            centre[axis] = side;
            x.push(centre);
        }
        x.push([0.0; 3]);
        x.truncate(kind.num_nodes());
        x
    }

    #[test]
    fn permutations_map_gmsh_reference_nodes_to_vtk_nodes() {
        for kind in ElementType::ALL {
            let g = gmsh_reference(kind);
            let perm = gmsh_to_vtk_perm(kind);
            assert_eq!(perm.len(), kind.num_nodes());
            let permuted: Vec<[f64; 3]> = perm.iter().map(|&k| g[k]).collect();
            assert_eq!(permuted, kind.node_coords(), "{kind:?}");
        }
    }

    #[test]
    fn ascii_two_hexes_with_groups() {
        let m = read_msh(&data("two_hex.msh")).unwrap();
        assert_eq!(m.num_nodes(), 12, "unreferenced node 13 dropped");
        assert_eq!(m.num_elements(), 2);
        assert_eq!(m.bodies, vec!["left".to_string(), "physical_6".to_string()]);
        assert_eq!(m.body, vec![0, 1]);
        assert_eq!(m.element_sets["left"], vec![0]);
        assert_eq!(m.element_sets["physical_6"], vec![1]);
        assert_eq!(m.element_nodes(1), &[1, 8, 9, 2, 5, 10, 11, 6]);
        assert_eq!(
            m.face_sets["fixed"],
            vec![FaceRef {
                element: 0,
                face: 0
            }]
        );
        assert_eq!(
            m.face_sets["load"],
            vec![FaceRef {
                element: 1,
                face: 1
            }]
        );
        assert_eq!(m.node_sets["fixed"], vec![0, 3, 4, 7]);
        assert_eq!(m.node_sets["load"], vec![8, 9, 10, 11]);
        for &n in &m.node_sets["load"] {
            assert_eq!(m.coords[n][0], 2.0);
        }
        assert_eq!(m.node_sets["corner"], vec![0]);
        assert_eq!(m.node_sets["edge"], vec![0, 1]);
        assert!(!m.face_sets.contains_key("edge"));
    }

    #[test]
    fn tet10_file_is_permuted_to_vtk_order() {
        let m = read_msh(&data("tet10.msh")).unwrap();
        assert_eq!(m.num_elements(), 1);
        assert_eq!(m.types[0], ElementType::Tet10);
        // The file holds the reference tetrahedron in Gmsh order.
        assert_eq!(m.element_coords(0), ElementType::Tet10.node_coords());
        assert_eq!(m.bodies, vec!["physical_1".to_string()]);
        assert_eq!(
            m.face_sets["physical_2"],
            vec![FaceRef {
                element: 0,
                face: 0
            }]
        );
        assert_eq!(m.node_sets["physical_2"].len(), 6);
        for &n in &m.node_sets["physical_2"] {
            assert_eq!(m.coords[n][2], 0.0);
        }
    }

    #[test]
    fn bad_files_are_errors_naming_the_file() {
        for (name, what) in [
            ("truncated.msh", "truncated"),
            ("version22.msh", "version 2.2"),
            ("unsupported.msh", "unsupported element type 6"),
            ("not_a_face.msh", "not a face"),
            ("does_not_exist.msh", "No such file"),
        ] {
            let e = read_msh(&data(name)).unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
            assert!(e.contains(what), "{name}: {e}");
        }
        let two = std::fs::read_to_string(data("two_hex.msh")).unwrap();
        let unterminated = two.replace("2 3 \"fixed\"", "2 3 \"fixed");
        let e = read_msh_bytes(unterminated.as_bytes(), Path::new("quote.msh"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("quote.msh") && e.contains("fixed"), "{e}");
        let e = read_msh_bytes(b"", Path::new("empty.msh"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("empty"), "{e}");
        let two = std::fs::read(data("two_hex.msh")).unwrap();
        for cut in (0..two.len()).step_by(37) {
            assert!(
                read_msh_bytes(&two[..cut], Path::new("cut.msh")).is_err(),
                "cut at {cut}"
            );
        }
    }

    /// `two_hex.msh` with its `$Nodes` lines edited by `edit(tags, coords)` (13 each, in file
    /// order).
    fn two_hex_with_nodes(edit: impl FnOnce(&mut Vec<String>, &mut Vec<String>)) -> String {
        let text = std::fs::read_to_string(data("two_hex.msh")).unwrap();
        let lines: Vec<String> = text.lines().map(str::to_string).collect();
        // "$Nodes", the section header, the block header, 13 tags, 13 coordinate lines.
        let at = lines.iter().position(|l| l == "$Nodes").unwrap() + 3;
        let mut tags = lines[at..at + 13].to_vec();
        let mut coords = lines[at + 13..at + 26].to_vec();
        edit(&mut tags, &mut coords);
        let mut out = lines[..at].to_vec();
        out.extend(tags);
        out.extend(coords);
        out.extend_from_slice(&lines[at + 26..]);
        out.join("\n") + "\n"
    }

    #[test]
    fn nodes_are_placed_by_their_tags_in_any_order() {
        let original = read_msh(&data("two_hex.msh")).unwrap();
        // Dense tags (1..13), the nodes of tags 1 and 6 listed in each other's place.
        let swapped = two_hex_with_nodes(|tags, coords| {
            tags.swap(0, 5);
            coords.swap(0, 5);
        });
        assert!(swapped.contains("$Nodes\n1 13 1 13\n3 1 0 13\n6\n"));
        let m = read_msh_bytes(swapped.as_bytes(), Path::new("swapped.msh")).unwrap();
        assert_eq!(m.coords, original.coords);
        assert_eq!(m.conn, original.conn);
        // The same file with CRLF line ends.
        let crlf = swapped.replace('\n', "\r\n");
        let m = read_msh_bytes(crlf.as_bytes(), Path::new("crlf.msh")).unwrap();
        assert_eq!(m.coords, original.coords);
        // A tag defined twice (and 6 not at all): an error naming it.
        let repeated = two_hex_with_nodes(|tags, _| tags[5] = "1".into());
        let e = read_msh_bytes(repeated.as_bytes(), Path::new("repeated.msh"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("repeated.msh") && e.contains("node tag 1 is defined twice"),
            "{e}"
        );
    }

    /// Writes `mesh` as a binary MSH 4.1 file: one volume entity per body (physical group =
    /// body index + 1, named after the body), nodes tagged from 1, elements in Gmsh order.
    fn write_binary(mesh: &Mesh, path: &Path) {
        fn sz(out: &mut Vec<u8>, v: usize) {
            out.extend_from_slice(&(v as u64).to_le_bytes());
        }
        fn int(out: &mut Vec<u8>, v: i32) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        fn dbl(out: &mut Vec<u8>, v: f64) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let gtype = |k: ElementType| match k {
            ElementType::Hex8 => 5,
            ElementType::Hex20 => 17,
            ElementType::Hex27 => 12,
            ElementType::Tet4 => 4,
            ElementType::Tet10 => 11,
        };
        let nb = mesh.bodies.len();
        let mut o = Vec::new();
        o.extend_from_slice(b"$MeshFormat\n4.1 1 8\n");
        int(&mut o, 1);
        o.extend_from_slice(b"\n$EndMeshFormat\n$PhysicalNames\n");
        o.extend_from_slice(format!("{nb}\n").as_bytes());
        for (b, name) in mesh.bodies.iter().enumerate() {
            o.extend_from_slice(format!("3 {} \"{name}\"\n", b + 1).as_bytes());
        }
        o.extend_from_slice(b"$EndPhysicalNames\n$Entities\n");
        for n in [0, 0, 0, nb] {
            sz(&mut o, n);
        }
        for b in 0..nb {
            int(&mut o, b as i32 + 1);
            for _ in 0..6 {
                dbl(&mut o, 0.0);
            }
            sz(&mut o, 1);
            int(&mut o, b as i32 + 1);
            sz(&mut o, 0);
        }
        o.extend_from_slice(b"\n$EndEntities\n$Nodes\n");
        let nn = mesh.num_nodes();
        for v in [1, nn, 1, nn] {
            sz(&mut o, v);
        }
        int(&mut o, 3);
        int(&mut o, 1);
        int(&mut o, 0);
        sz(&mut o, nn);
        for t in 1..=nn {
            sz(&mut o, t);
        }
        for x in &mesh.coords {
            for &c in x {
                dbl(&mut o, c);
            }
        }
        o.extend_from_slice(b"\n$EndNodes\n$Elements\n");
        let ne = mesh.num_elements();
        for v in [ne, ne, 1, ne] {
            sz(&mut o, v);
        }
        for e in 0..ne {
            int(&mut o, 3);
            int(&mut o, mesh.body[e] as i32 + 1);
            int(&mut o, gtype(mesh.types[e]));
            sz(&mut o, 1);
            sz(&mut o, e + 1);
            let perm = gmsh_to_vtk_perm(mesh.types[e]);
            let en = mesh.element_nodes(e);
            let mut g = vec![0; en.len()];
            for (k, &p) in perm.iter().enumerate() {
                g[p] = en[k] + 1;
            }
            for t in g {
                sz(&mut o, t);
            }
        }
        o.extend_from_slice(b"\n$EndElements\n");
        std::fs::write(path, o).unwrap();
    }

    #[test]
    fn binary_round_trip_of_every_type() {
        for kind in ElementType::ALL {
            let mut m = box_mesh(kind, [2, 1, 1], [0.0; 3], [2.0, 1.0, 1.5], "left");
            m.merge(box_mesh(
                kind,
                [1, 1, 1],
                [2.0, 0.0, 0.0],
                [3.0, 1.0, 1.5],
                "right",
            ));
            let path = std::env::temp_dir().join(format!(
                "mortar_gmsh_{}_{}.msh",
                kind.name(),
                std::process::id()
            ));
            write_binary(&m, &path);
            let r = read_msh(&path).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            // The check integer in big-endian order: refused, not misread.
            let check = b"4.1 1 8\n\x01\x00\x00\x00";
            let at = bytes.windows(check.len()).position(|w| w == check).unwrap();
            let mut big = bytes.clone();
            big[at + 8..at + 12].copy_from_slice(&1i32.to_be_bytes());
            let e = read_msh_bytes(&big, Path::new("big.msh"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("big.msh") && e.contains("big-endian"), "{e}");
            // The first two nodes of the first block listed in each other's place (dense tags
            // out of order): the same mesh.
            let nodes = bytes.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
            let block = nodes + 4 * 8;
            let count = u64::from_le_bytes(bytes[block + 12..block + 20].try_into().unwrap());
            let (tags, coords) = (block + 20, block + 20 + 8 * count as usize);
            let mut swapped = bytes.clone();
            for (start, len) in [(tags, 8), (coords, 24)] {
                let (first, second) = (start..start + len, start + len..start + 2 * len);
                swapped[first.clone()].copy_from_slice(&bytes[second.clone()]);
                swapped[second].copy_from_slice(&bytes[first]);
            }
            assert_ne!(swapped, bytes);
            let s = read_msh_bytes(&swapped, Path::new("swapped.msh")).unwrap();
            assert_eq!(s.coords, r.coords, "{kind:?}");
            assert_eq!(s.conn, r.conn, "{kind:?}");
            std::fs::remove_file(&path).ok();
            for cut in (0..bytes.len()).step_by(53) {
                let e = read_msh_bytes(&bytes[..cut], Path::new("cut.msh"));
                assert!(e.is_err(), "{kind:?}: cut at {cut}");
            }
            assert_eq!(r.bodies, m.bodies);
            assert_eq!(r.body, m.body);
            assert_eq!(r.types, m.types);
            assert_eq!(r.coords, m.coords, "{kind:?}");
            assert_eq!(r.conn, m.conn, "{kind:?}");
            assert_eq!(
                r.element_sets["right"].len(),
                m.num_elements() - r.element_sets["left"].len()
            );
        }
    }
}
