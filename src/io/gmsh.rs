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

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use mshio::ElementType as GmshType;

use crate::error::{Error, Result};
use crate::fe::ElementType;
use crate::mesh::{FaceRef, Mesh};

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

struct Reader {
    file: PathBuf,
}

/// How the file stores its data, from the `$MeshFormat` line (checked by
/// `Reader::check_header`): binary or not, and the size of a `size_t`.
fn storage(bytes: &[u8]) -> (bool, usize) {
    let format: Vec<String> = bytes
        .split(|&b| b == b'\n')
        .map(|l| String::from_utf8_lossy(l).trim().to_string())
        .skip_while(|l| l != "$MeshFormat")
        .nth(1)
        .map(|l| l.split_whitespace().map(str::to_string).collect())
        .unwrap_or_default();
    let binary = format.get(1).is_some_and(|t| t == "1");
    let size_t = format.get(2).and_then(|d| d.parse().ok()).unwrap_or(8);
    (binary, size_t)
}

/// Lines of the ASCII prologue of a file (up to the first section with binary content).
fn prologue_lines(bytes: &[u8]) -> impl Iterator<Item = &str> {
    bytes
        .split(|&b| b == b'\n')
        .map(|l| std::str::from_utf8(l).unwrap_or("").trim())
        .take_while(|l| {
            !matches!(
                *l,
                "$Entities" | "$Nodes" | "$Elements" | "$PartitionedEntities"
            )
        })
}

impl Reader {
    fn err(&self, msg: impl Into<String>) -> Error {
        Error::Gmsh {
            file: self.file.clone(),
            msg: msg.into(),
        }
    }

    /// Checks `$MeshFormat`: version 4.1, file type 0 or 1, a supported size_t size.
    fn check_header(&self, bytes: &[u8]) -> Result<()> {
        let mut lines = bytes
            .split(|&b| b == b'\n')
            .map(|l| String::from_utf8_lossy(l).trim().to_string())
            .skip_while(|l| l.is_empty());
        match lines.next() {
            None => return Err(self.err("file is empty (truncated?)")),
            Some(l) if l == "$MeshFormat" => {}
            Some(_) => return Err(self.err("not a Gmsh file: it does not start with $MeshFormat")),
        }
        let Some(header) = lines.next() else {
            return Err(self.err("file is truncated inside $MeshFormat"));
        };
        let fields: Vec<&str> = header.split_whitespace().collect();
        if fields.len() != 3 {
            return Err(self.err(format!(
                "bad $MeshFormat line '{header}' (expected 'version file-type data-size')"
            )));
        }
        if fields[0].parse::<f64>().ok() != Some(4.1) {
            return Err(self.err(format!(
                "MSH format version {} is not supported, only 4.1 (export with Mesh.MshFileVersion = 4.1)",
                fields[0]
            )));
        }
        if !matches!(fields[1], "0" | "1") {
            return Err(self.err(format!(
                "bad file type {} in $MeshFormat (0 = ASCII, 1 = binary)",
                fields[1]
            )));
        }
        if !matches!(fields[2], "4" | "8") {
            return Err(self.err(format!(
                "unsupported data size {} in $MeshFormat (4 or 8)",
                fields[2]
            )));
        }
        Ok(())
    }

    /// The node tags of `$Nodes` in file order, for blocks of `counts` nodes (as `mshio` read
    /// them). `mshio` keeps a block's tags only when the file's tags are not dense, and then
    /// in a map, where a repeated tag overwrites; a file whose dense tags are not in order, or
    /// that repeats a tag, would be misread. So the tags are read here, in ASCII as in binary
    /// (`stored`: binary or not and the `size_t` size, from [`storage`]; `int` of 4 bytes,
    /// coordinates of 8).
    fn node_tags(
        &self,
        bytes: &[u8],
        (binary, size_t): (bool, usize),
        counts: &[usize],
    ) -> Result<Vec<u64>> {
        let bad = || self.err("cannot read the node tags of $Nodes");
        // The section's first line, "$Nodes" (with a CR in a file of CRLF lines).
        let start = [&b"$Nodes\n"[..], &b"$Nodes\r\n"[..]]
            .iter()
            .find_map(|marker| {
                bytes
                    .windows(marker.len())
                    .enumerate()
                    .find(|(i, w)| w == marker && (*i == 0 || bytes[i - 1] == b'\n'))
                    .map(|(i, _)| i + marker.len())
            })
            .ok_or_else(bad)?;
        let body = &bytes[start..];
        let total: usize = counts.iter().sum();
        let mut tags = Vec::with_capacity(total);
        if binary {
            let unsigned = |at: usize| -> Option<u64> {
                let b = body.get(at..at + size_t)?;
                Some(match size_t {
                    4 => u64::from(u32::from_le_bytes(b.try_into().ok()?)),
                    _ => u64::from_le_bytes(b.try_into().ok()?),
                })
            };
            // The header: 4 size_t; each block: 3 int, a size_t count, the tags, 3 doubles each.
            let mut at = 4 * size_t;
            for &n in counts {
                at += 3 * 4 + size_t;
                for k in 0..n {
                    tags.push(unsigned(at + k * size_t).ok_or_else(bad)?);
                }
                at += n * size_t + 3 * 8 * n;
            }
        } else {
            let mut words = std::str::from_utf8(body)
                .map_err(|_| bad())?
                .split_ascii_whitespace();
            // The header: 4 numbers; each block: 4 numbers, the tags, 3 coordinates each.
            words.nth(3).ok_or_else(bad)?;
            for &n in counts {
                words.nth(3).ok_or_else(bad)?;
                for _ in 0..n {
                    tags.push(words.next().and_then(|w| w.parse().ok()).ok_or_else(bad)?);
                }
                if n > 0 {
                    words.nth(3 * n - 1).ok_or_else(bad)?;
                }
            }
        }
        Ok(tags)
    }

    /// True when the binary file's check integer (the `int` 1 after the `$MeshFormat` line)
    /// reads 1 in little-endian order, the order [`Reader::node_tags`] reads.
    fn little_endian(&self, bytes: &[u8]) -> bool {
        let Some(mut at) = bytes
            .windows(11)
            .position(|w| w == b"$MeshFormat".as_slice())
        else {
            return false;
        };
        // Past the end of the "$MeshFormat" line and of the "4.1 1 8" line.
        for _ in 0..2 {
            let Some(end) = bytes[at..].iter().position(|&b| b == b'\n') else {
                return false;
            };
            at += end + 1;
        }
        bytes
            .get(at..at + 4)
            .is_some_and(|b| b == 1i32.to_le_bytes().as_slice())
    }

    /// `$PhysicalNames`: `(dim, tag) -> name`.
    fn physical_names(&self, bytes: &[u8]) -> Result<HashMap<(i32, i32), String>> {
        let mut names = HashMap::new();
        let mut lines = prologue_lines(bytes).skip_while(|l| *l != "$PhysicalNames");
        if lines.next().is_none() {
            return Ok(names);
        }
        let count: usize = lines
            .next()
            .and_then(|l| l.parse().ok())
            .ok_or_else(|| self.err("bad count in $PhysicalNames"))?;
        for _ in 0..count {
            let line = lines
                .next()
                .ok_or_else(|| self.err("file is truncated inside $PhysicalNames"))?;
            let mut it = line.splitn(3, char::is_whitespace);
            let bad = || self.err(format!("bad $PhysicalNames line '{line}'"));
            let dim: i32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
            let tag: i32 = it
                .next()
                .and_then(|s| s.trim().parse().ok())
                .ok_or_else(bad)?;
            let quoted = it.next().ok_or_else(bad)?.trim();
            // A name in double quotes (as gmsh writes it), or bare.
            let name = match quoted.strip_prefix('"') {
                Some(rest) => rest.strip_suffix('"').ok_or_else(bad)?,
                None => quoted,
            }
            .to_string();
            names.insert((dim, tag), name);
        }
        match lines.next() {
            Some("$EndPhysicalNames") => Ok(names),
            _ => Err(self.err("$PhysicalNames: missing $EndPhysicalNames after the names")),
        }
    }

    /// Runs `mshio`, turning its errors (and, defensively, panics) into messages.
    fn parse(&self, bytes: &[u8]) -> Result<mshio::MshFile<u64, i32, f64>> {
        // mshio panics on some malformed headers: silence the default hook so the panic
        // becomes our one-line error, not a message plus a backtrace note.
        let hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let parsed = std::panic::catch_unwind(|| {
            mshio::parse_msh_bytes(bytes).map_err(|e| {
                let trace = e.filtered_backtrace();
                let Some((at, kind)) = trace.first() else {
                    return "unknown parse error".to_string();
                };
                let offset = bytes.len() - at.len();
                let line = bytes[..offset].iter().filter(|&&b| b == b'\n').count() + 1;
                let contexts: Vec<String> = trace[1..]
                    .iter()
                    .rev()
                    .map(|(_, k)| {
                        k.context()
                            .map(str::to_string)
                            .unwrap_or_else(|| k.to_string())
                    })
                    .collect();
                let truncated = !at.windows(4).any(|w| w == b"$End");
                format!(
                    "{}{}: {} (byte {offset}, line {line})",
                    if truncated {
                        "file is truncated: "
                    } else {
                        "cannot parse "
                    },
                    contexts.join(" > "),
                    kind
                )
            })
        });
        std::panic::set_hook(hook);
        match parsed {
            Ok(Ok(f)) => Ok(f),
            Ok(Err(msg)) => Err(self.err(msg)),
            Err(_) => Err(self.err("the MSH parser failed (malformed file)")),
        }
    }

    fn read(&self, bytes: &[u8]) -> Result<Mesh> {
        self.check_header(bytes)?;
        let stored = storage(bytes);
        if stored.0 && !self.little_endian(bytes) {
            return Err(self.err(
                "a big-endian binary file is not supported (write it on a little-endian \
                 machine, or as ASCII)",
            ));
        }
        let names = self.physical_names(bytes)?;
        let msh = self.parse(bytes)?;
        let data = msh.data;
        let nodes = data.nodes.ok_or_else(|| self.err("no $Nodes section"))?;
        let elements = data
            .elements
            .ok_or_else(|| self.err("no $Elements section"))?;

        // Node coordinates by tag.
        // Sized from the nodes actually read, never from the header's claim.
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

        // Physical groups of every entity.
        let mut entity_groups: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
        if let Some(ent) = &data.entities {
            let mut add = |dim: i32, tag: i32, phys: &[i32]| {
                let mut g: Vec<i32> = phys.iter().map(|p| p.abs()).collect();
                g.sort_unstable();
                g.dedup();
                entity_groups.insert((dim, tag), g);
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
        let group_name = |dim: i32, tag: i32| {
            names
                .get(&(dim, tag))
                .cloned()
                .unwrap_or_else(|| format!("physical_{tag}"))
        };

        // Sort the elements by role.
        struct Volume {
            kind: ElementType,
            tag: u64,
            nodes: Vec<u64>,
            groups: Vec<i32>,
        }
        struct Lower {
            dim: i32,
            tag: u64,
            corners: usize,
            nodes: Vec<u64>,
            groups: Vec<i32>,
        }
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
            let groups = entity_groups
                .get(&(block.entity_dim, block.entity_tag))
                .cloned()
                .unwrap_or_default();
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

        // Compact node numbering, in tag order.
        let mut used: BTreeSet<u64> = BTreeSet::new();
        for v in &volumes {
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

        // Bodies: the smallest 3D group of each element.
        let body_groups: BTreeSet<i32> = volumes
            .iter()
            .filter_map(|v| v.groups.first().copied())
            .collect();
        let mut body_of_group: HashMap<i32, usize> = HashMap::new();
        for &g in &body_groups {
            body_of_group.insert(g, mesh.bodies.len());
            mesh.bodies.push(group_name(3, g));
        }
        let mut default_body = None;
        let mut element_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        let mut gmsh_tags = Vec::with_capacity(volumes.len());
        for v in &volumes {
            let body = match v.groups.first() {
                Some(g) => body_of_group[g],
                None => *default_body.get_or_insert_with(|| {
                    mesh.bodies.push("body".to_string());
                    mesh.bodies.len() - 1
                }),
            };
            let conn: Vec<usize> = v.nodes.iter().map(|t| index[t]).collect();
            let e = mesh.push_element(v.kind, body, &conn);
            gmsh_tags.push(v.tag);
            for &g in &v.groups {
                element_sets.entry(group_name(3, g)).or_default().push(e);
            }
        }

        // Faces of the volume elements by sorted corner nodes.
        let mut faces: HashMap<[usize; 4], Vec<FaceRef>> = HashMap::new();
        for e in 0..mesh.num_elements() {
            let kind = mesh.types[e];
            for face in 0..kind.num_faces() {
                faces
                    .entry(corner_key(
                        &mesh.face_nodes(FaceRef { element: e, face })
                            [..kind.face_type().num_corners()],
                    ))
                    .or_default()
                    .push(FaceRef { element: e, face });
            }
        }

        let mut face_sets: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
        let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for l in &lower {
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
                            group_name(l.dim, l.groups[0])
                        )))
                    }
                }
            }
            let face = if l.corners > 0 {
                let corners = &local[..l.corners];
                let cands = faces
                    .get(&corner_key(corners))
                    .map(|v| v.as_slice())
                    .unwrap_or(&[]);
                let chosen = cands
                    .iter()
                    .find(|f| same_orientation(&mesh.face_nodes(**f)[..l.corners], corners))
                    .or(cands.first());
                match chosen {
                    Some(&f) => Some(f),
                    None => {
                        return Err(self.err(format!(
                            "surface element {} (physical group '{}', nodes {:?}) is not a face \
                             of any volume element",
                            l.tag,
                            group_name(l.dim, l.groups[0]),
                            &l.nodes[..l.corners]
                        )))
                    }
                }
            } else {
                None
            };
            for &g in &l.groups {
                let name = group_name(l.dim, g);
                if let Some(f) = face {
                    face_sets.entry(name.clone()).or_default().push(f);
                }
                node_sets.entry(name).or_default().extend_from_slice(&local);
            }
        }
        for v in element_sets.values_mut() {
            v.sort_unstable();
            v.dedup();
        }
        for v in face_sets.values_mut() {
            v.sort_unstable();
            v.dedup();
        }
        for v in node_sets.values_mut() {
            v.sort_unstable();
            v.dedup();
        }
        mesh.element_sets = element_sets;
        mesh.face_sets = face_sets;
        mesh.node_sets = node_sets;

        mesh.check_labelled(&|e| format!("element {e} (Gmsh element {})", gmsh_tags[e]))
            .map_err(|e| match e {
                Error::Mesh(m) => self.err(m),
                other => other,
            })?;
        Ok(mesh)
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

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
