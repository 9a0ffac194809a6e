//! VTK XML writers: `.vtu` pieces, the `.pvtu` that joins them, the `.pvd` time series.

use std::fmt::Write as _;
use std::path::Path;

use super::{base64, content_error, write_atomic, xml_escape};
use crate::Result;

/// A point or cell field: `components` values per point (cell), flat.
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    pub name: &'a str,
    pub components: usize,
    pub values: &'a [f64],
}

impl<'a> Field<'a> {
    /// The field `name` of `components` values per point (cell).
    pub fn new(name: &'a str, components: usize, values: &'a [f64]) -> Field<'a> {
        Field {
            name,
            components,
            values,
        }
    }
}

/// One rank's part of the mesh with its fields, in VTK's unstructured-grid layout.
#[derive(Clone, Debug)]
pub struct Piece<'a> {
    pub points: &'a [[f64; 3]],
    /// VTK cell type numbers (12 hexahedron, 25 quadratic hexahedron, 29 triquadratic
    /// hexahedron, 10 tetrahedron, 24 quadratic tetrahedron, ...).
    pub cell_types: &'a [u8],
    /// Flat cell-to-point lists, local point indices.
    pub connectivity: &'a [usize],
    /// End offset of each cell's list in `connectivity` (VTK style).
    pub offsets: &'a [usize],
    pub point_data: Vec<Field<'a>>,
    pub cell_data: Vec<Field<'a>>,
}

const HEADER: &str = "<?xml version=\"1.0\"?>\n";

/// Appends one inline binary `DataArray` (UInt64 byte count + little-endian data, one base64
/// stream).
fn data_array(xml: &mut String, indent: &str, attrs: &str, raw: &[u8]) {
    let mut block = Vec::with_capacity(8 + raw.len());
    block.extend_from_slice(&(raw.len() as u64).to_le_bytes());
    block.extend_from_slice(raw);
    let _ = writeln!(xml, "{indent}<DataArray {attrs} format=\"binary\">");
    let _ = writeln!(xml, "{indent}  {}", base64::encode(&block));
    let _ = writeln!(xml, "{indent}</DataArray>");
}

fn f64_bytes(values: impl Iterator<Item = f64>) -> Vec<u8> {
    values.flat_map(f64::to_le_bytes).collect()
}

/// Checks a field's length and finiteness; `what` is "point" or "cell".
fn check_field(path: &Path, f: &Field, count: usize, what: &str) -> Result<()> {
    if f.components == 0 {
        return Err(content_error(
            path,
            format!("{what} field '{}' has zero components", f.name),
        ));
    }
    if f.values.len() != f.components * count {
        return Err(content_error(
            path,
            format!(
                "{what} field '{}' has {} values, expected {} ({count} {what}s x {} components)",
                f.name,
                f.values.len(),
                f.components * count,
                f.components
            ),
        ));
    }
    if let Some(i) = f.values.iter().position(|v| !v.is_finite()) {
        return Err(content_error(
            path,
            format!(
                "{what} field '{}' is not finite ({}) at {what} {}, component {}",
                f.name,
                f.values[i],
                i / f.components,
                i % f.components
            ),
        ));
    }
    Ok(())
}

fn check_piece(path: &Path, piece: &Piece) -> Result<()> {
    let n_points = piece.points.len();
    let n_cells = piece.cell_types.len();
    if piece.offsets.len() != n_cells {
        return Err(content_error(
            path,
            format!("{} cell types but {} offsets", n_cells, piece.offsets.len()),
        ));
    }
    let mut prev = 0;
    for (c, &end) in piece.offsets.iter().enumerate() {
        if end < prev || end > piece.connectivity.len() {
            return Err(content_error(
                path,
                format!("cell {c}: bad end offset {end}"),
            ));
        }
        prev = end;
    }
    if prev != piece.connectivity.len() {
        return Err(content_error(
            path,
            format!(
                "offsets end at {prev} but the connectivity has {} entries",
                piece.connectivity.len()
            ),
        ));
    }
    if let Some(&p) = piece.connectivity.iter().find(|&&p| p >= n_points) {
        return Err(content_error(
            path,
            format!("connectivity refers to point {p} of {n_points}"),
        ));
    }
    if let Some(i) = piece
        .points
        .iter()
        .position(|x| x.iter().any(|v| !v.is_finite()))
    {
        return Err(content_error(
            path,
            format!("point {i} has non-finite coordinates {:?}", piece.points[i]),
        ));
    }
    for f in &piece.point_data {
        check_field(path, f, n_points, "point")?;
    }
    for f in &piece.cell_data {
        check_field(path, f, n_cells, "cell")?;
    }
    Ok(())
}

/// The `.vtu` document of `piece`, after the checks of [`write_vtu`] (`path` names the file in
/// errors only).
pub fn vtu_document(path: &Path, piece: &Piece) -> Result<String> {
    check_piece(path, piece)?;
    let mut xml = String::from(HEADER);
    xml.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n  <UnstructuredGrid>\n",
    );
    let _ = writeln!(
        xml,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        piece.points.len(),
        piece.cell_types.len()
    );
    for (tag, fields) in [
        ("PointData", &piece.point_data),
        ("CellData", &piece.cell_data),
    ] {
        let _ = writeln!(xml, "      <{tag}>");
        for f in fields {
            let attrs = format!(
                "type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\"",
                xml_escape(f.name),
                f.components
            );
            data_array(
                &mut xml,
                "        ",
                &attrs,
                &f64_bytes(f.values.iter().copied()),
            );
        }
        let _ = writeln!(xml, "      </{tag}>");
    }
    xml.push_str("      <Points>\n");
    data_array(
        &mut xml,
        "        ",
        "type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"",
        &f64_bytes(piece.points.iter().flatten().copied()),
    );
    xml.push_str("      </Points>\n      <Cells>\n");
    let int64 =
        |v: &[usize]| -> Vec<u8> { v.iter().flat_map(|&i| (i as i64).to_le_bytes()).collect() };
    data_array(
        &mut xml,
        "        ",
        "type=\"Int64\" Name=\"connectivity\"",
        &int64(piece.connectivity),
    );
    data_array(
        &mut xml,
        "        ",
        "type=\"Int64\" Name=\"offsets\"",
        &int64(piece.offsets),
    );
    data_array(
        &mut xml,
        "        ",
        "type=\"UInt8\" Name=\"types\"",
        piece.cell_types,
    );
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    Ok(xml)
}

/// Writes one rank's piece as a `.vtu` file (inline base64 binary, see the module docs).
///
/// Errors: a field of the wrong length or holding a NaN or infinity (named), non-finite point
/// coordinates, inconsistent cell arrays, or an I/O failure. Nothing is written on error.
pub fn write_vtu(path: &Path, piece: &Piece) -> Result<()> {
    let xml = vtu_document(path, piece)?;
    write_atomic(path, xml.as_bytes())
}

/// Writes the `.pvtu` joining `piece_files` (names relative to the `.pvtu`), declaring the point
/// and cell fields `(name, components)` every piece carries, in the pieces' order.
pub fn write_pvtu(
    path: &Path,
    piece_files: &[String],
    point_fields: &[(&str, usize)],
    cell_fields: &[(&str, usize)],
) -> Result<()> {
    let mut xml = String::from(HEADER);
    xml.push_str(
        "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n",
    );
    for (tag, fields) in [("PPointData", point_fields), ("PCellData", cell_fields)] {
        let _ = writeln!(xml, "    <{tag}>");
        for &(name, components) in fields {
            let _ = writeln!(
                xml,
                "      <PDataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{components}\"/>",
                xml_escape(name)
            );
        }
        let _ = writeln!(xml, "    </{tag}>");
    }
    xml.push_str(
        "    <PPoints>\n      <PDataArray type=\"Float64\" Name=\"Points\" \
         NumberOfComponents=\"3\"/>\n    </PPoints>\n",
    );
    for file in piece_files {
        let _ = writeln!(xml, "    <Piece Source=\"{}\"/>", xml_escape(file));
    }
    xml.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, xml.as_bytes())
}

/// Writes the `.pvd` time series: one `DataSet` per `(time, file)` entry, file names relative to
/// the `.pvd`. Call after every output step with all entries so far; the file is replaced whole.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> Result<()> {
    let mut xml = String::from(HEADER);
    xml.push_str(
        "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n  \
         <Collection>\n",
    );
    for (time, file) in entries {
        if !time.is_finite() {
            return Err(content_error(
                path,
                format!("time of '{file}' is not finite ({time})"),
            ));
        }
        let _ = writeln!(
            xml,
            "    <DataSet timestep=\"{time}\" group=\"\" part=\"0\" file=\"{}\"/>",
            xml_escape(file)
        );
    }
    xml.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path, xml.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::super::test_util::Scratch;
    use super::*;

    /// A minimal XML reader for the tests: elements with attributes and text, checking that
    /// tags nest and close properly.
    #[derive(Debug)]
    struct Element {
        name: String,
        attrs: Vec<(String, String)>,
        text: String,
        children: Vec<Element>,
    }

    impl Element {
        fn attr(&self, key: &str) -> Option<&str> {
            self.attrs
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
        }
        fn child(&self, name: &str) -> &Element {
            self.children
                .iter()
                .find(|c| c.name == name)
                .unwrap_or_else(|| panic!("no <{name}> in <{}>", self.name))
        }
        fn all(&self, name: &str) -> Vec<&Element> {
            self.children.iter().filter(|c| c.name == name).collect()
        }
        fn array(&self, name: &str) -> &Element {
            self.all("DataArray")
                .into_iter()
                .find(|c| c.attr("Name") == Some(name))
                .unwrap_or_else(|| panic!("no DataArray {name}"))
        }
    }

    fn unescape(s: &str) -> String {
        s.replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&amp;", "&")
    }

    fn parse_xml(doc: &str) -> Element {
        let doc = doc.strip_prefix(HEADER).expect("XML declaration");
        let mut stack = vec![Element {
            name: String::new(),
            attrs: vec![],
            text: String::new(),
            children: vec![],
        }];
        let mut rest = doc;
        while let Some(open) = rest.find('<') {
            stack.last_mut().unwrap().text.push_str(&rest[..open]);
            let close = rest[open..].find('>').expect("unclosed tag") + open;
            let tag = &rest[open + 1..close];
            rest = &rest[close + 1..];
            if let Some(name) = tag.strip_prefix('/') {
                let done = stack.pop().unwrap();
                assert_eq!(done.name, name, "mismatched closing tag");
                stack.last_mut().unwrap().children.push(done);
                continue;
            }
            let (body, empty) = match tag.strip_suffix('/') {
                Some(b) => (b, true),
                None => (tag, false),
            };
            let mut parts = body.splitn(2, char::is_whitespace);
            let name = parts.next().unwrap().to_string();
            let mut attrs = vec![];
            let mut a = parts.next().unwrap_or("").trim();
            while !a.is_empty() {
                let eq = a.find("=\"").expect("attribute");
                let key = a[..eq].trim().to_string();
                let end = a[eq + 2..].find('"').expect("attribute end") + eq + 2;
                attrs.push((key, unescape(&a[eq + 2..end])));
                a = a[end + 1..].trim();
            }
            let el = Element {
                name,
                attrs,
                text: String::new(),
                children: vec![],
            };
            if empty {
                stack.last_mut().unwrap().children.push(el);
            } else {
                stack.push(el);
            }
        }
        assert!(rest.trim().is_empty());
        assert_eq!(stack.len(), 1, "unclosed elements");
        let mut root = stack.pop().unwrap();
        assert_eq!(root.children.len(), 1);
        root.children.pop().unwrap()
    }

    /// Decodes an inline binary array: checks the UInt64 byte count, returns the data bytes.
    fn decode_array(el: &Element) -> Vec<u8> {
        assert_eq!(el.attr("format"), Some("binary"));
        let bytes = base64::decode(&el.text).unwrap();
        let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
        assert_eq!(n, bytes.len() - 8);
        bytes[8..].to_vec()
    }

    fn as_f64(b: &[u8]) -> Vec<f64> {
        b.chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    fn as_i64(b: &[u8]) -> Vec<usize> {
        b.chunks(8)
            .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as usize)
            .collect()
    }

    /// Two cells: a hexahedron and a tetrahedron sharing points.
    struct Sample {
        points: Vec<[f64; 3]>,
        types: Vec<u8>,
        conn: Vec<usize>,
        offsets: Vec<usize>,
        disp: Vec<f64>,
        stress: Vec<f64>,
    }

    fn sample() -> Sample {
        let points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0 / 3.0],
            [0.5, 0.5, 2.0],
        ];
        let types = vec![12, 10];
        let conn = vec![0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 8];
        let offsets = vec![8, 12];
        let disp: Vec<f64> = (0..27).map(|i| (i as f64) * 0.1 - 1e-300).collect();
        let stress: Vec<f64> = vec![-1.5e8, std::f64::consts::PI];
        Sample {
            points,
            types,
            conn,
            offsets,
            disp,
            stress,
        }
    }

    #[test]
    fn vtu_round_trip() {
        let dir = Scratch::new("vtu");
        let Sample {
            points,
            types,
            conn,
            offsets,
            disp,
            stress,
        } = sample();
        let piece = Piece {
            points: &points,
            cell_types: &types,
            connectivity: &conn,
            offsets: &offsets,
            point_data: vec![Field::new("displacement", 3, &disp)],
            cell_data: vec![Field::new("von Mises <σ>", 1, &stress)],
        };
        let p = dir.path("out_0.vtu");
        write_vtu(&p, &piece).unwrap();
        assert_eq!(dir.listing(), vec!["out_0.vtu".to_string()]);

        let root = parse_xml(&std::fs::read_to_string(&p).unwrap());
        assert_eq!(root.name, "VTKFile");
        assert_eq!(root.attr("type"), Some("UnstructuredGrid"));
        assert_eq!(root.attr("header_type"), Some("UInt64"));
        assert_eq!(root.attr("byte_order"), Some("LittleEndian"));
        let grid = root.child("UnstructuredGrid");
        let pc = grid.child("Piece");
        assert_eq!(pc.attr("NumberOfPoints"), Some("9"));
        assert_eq!(pc.attr("NumberOfCells"), Some("2"));

        let pts = pc.child("Points").array("Points");
        assert_eq!(pts.attr("NumberOfComponents"), Some("3"));
        let flat: Vec<f64> = points.iter().flatten().copied().collect();
        assert_eq!(as_f64(&decode_array(pts)), flat);

        let cells = pc.child("Cells");
        assert_eq!(as_i64(&decode_array(cells.array("connectivity"))), conn);
        assert_eq!(as_i64(&decode_array(cells.array("offsets"))), offsets);
        assert_eq!(decode_array(cells.array("types")), types);
        assert_eq!(cells.array("types").attr("type"), Some("UInt8"));

        let d = pc.child("PointData").array("displacement");
        assert_eq!(d.attr("NumberOfComponents"), Some("3"));
        assert_eq!(d.attr("type"), Some("Float64"));
        assert_eq!(as_f64(&decode_array(d)), disp);
        let s = pc.child("CellData").array("von Mises <σ>");
        assert_eq!(as_f64(&decode_array(s)), stress);
    }

    #[test]
    fn empty_piece_is_valid() {
        let piece = Piece {
            points: &[],
            cell_types: &[],
            connectivity: &[],
            offsets: &[],
            point_data: vec![Field::new("u", 3, &[])],
            cell_data: vec![],
        };
        let root = parse_xml(&vtu_document(Path::new("e.vtu"), &piece).unwrap());
        let pc = root.child("UnstructuredGrid").child("Piece");
        assert_eq!(pc.attr("NumberOfPoints"), Some("0"));
        assert!(decode_array(pc.child("PointData").array("u")).is_empty());
    }

    #[test]
    fn non_finite_and_inconsistent_input_rejected() {
        let dir = Scratch::new("vtu-nan");
        let Sample {
            points,
            types,
            conn,
            offsets,
            mut disp,
            stress,
        } = sample();
        disp[7] = f64::NAN;
        let mut piece = Piece {
            points: &points,
            cell_types: &types,
            connectivity: &conn,
            offsets: &offsets,
            point_data: vec![Field::new("displacement", 3, &disp)],
            cell_data: vec![],
        };
        let p = dir.path("bad.vtu");
        let msg = write_vtu(&p, &piece).unwrap_err().to_string();
        assert!(
            msg.contains("'displacement'") && msg.contains("NaN"),
            "{msg}"
        );
        assert!(msg.contains("point 2, component 1"), "{msg}");

        let inf = [f64::INFINITY, 0.0];
        piece.point_data.clear();
        piece.cell_data = vec![Field::new("pressure", 1, &inf)];
        let msg = write_vtu(&p, &piece).unwrap_err().to_string();
        assert!(msg.contains("'pressure'") && msg.contains("inf"), "{msg}");

        piece.cell_data = vec![Field::new("short", 1, &stress[..1])];
        assert!(write_vtu(&p, &piece)
            .unwrap_err()
            .to_string()
            .contains("'short'"));

        piece.cell_data.clear();
        let bad_offsets = [8, 11];
        piece.offsets = &bad_offsets;
        assert!(write_vtu(&p, &piece).is_err());
        piece.offsets = &offsets;
        let bad_conn = [0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 9];
        piece.connectivity = &bad_conn;
        assert!(write_vtu(&p, &piece).is_err());
        assert!(dir.listing().is_empty());
    }

    #[test]
    fn pvtu_lists_pieces_and_fields() {
        let dir = Scratch::new("pvtu");
        let p = dir.path("step_0003.pvtu");
        let pieces: Vec<String> = (0..3).map(|r| format!("step_0003/rank_{r}.vtu")).collect();
        write_pvtu(
            &p,
            &pieces,
            &[("displacement", 3), ("stress", 9)],
            &[("rank", 1)],
        )
        .unwrap();
        let root = parse_xml(&std::fs::read_to_string(&p).unwrap());
        assert_eq!(root.attr("type"), Some("PUnstructuredGrid"));
        let grid = root.child("PUnstructuredGrid");
        let sources: Vec<&str> = grid
            .all("Piece")
            .iter()
            .map(|e| e.attr("Source").unwrap())
            .collect();
        assert_eq!(sources, pieces);
        let pd = grid.child("PPointData").all("PDataArray");
        assert_eq!(pd.len(), 2);
        assert_eq!(pd[1].attr("Name"), Some("stress"));
        assert_eq!(pd[1].attr("NumberOfComponents"), Some("9"));
        assert_eq!(pd[1].attr("type"), Some("Float64"));
        let cd = grid.child("PCellData").all("PDataArray");
        assert_eq!(cd[0].attr("Name"), Some("rank"));
        let pts = grid.child("PPoints").child("PDataArray");
        assert_eq!(pts.attr("NumberOfComponents"), Some("3"));
    }

    #[test]
    fn pvd_entries_rewritten_whole() {
        let dir = Scratch::new("pvd");
        let p = dir.path("run.pvd");
        let mut entries = vec![];
        for (i, t) in [0.1, 0.2, 1.0 / 3.0].into_iter().enumerate() {
            entries.push((t, format!("step_{i}.pvtu")));
            write_pvd(&p, &entries).unwrap();
            let root = parse_xml(&std::fs::read_to_string(&p).unwrap());
            assert_eq!(root.attr("type"), Some("Collection"));
            let sets = root.child("Collection").all("DataSet");
            assert_eq!(sets.len(), i + 1);
            for (s, (t, f)) in sets.iter().zip(&entries) {
                assert_eq!(s.attr("timestep").unwrap().parse::<f64>().unwrap(), *t);
                assert_eq!(s.attr("file"), Some(f.as_str()));
                assert_eq!(s.attr("part"), Some("0"));
            }
        }
        assert_eq!(dir.listing(), vec!["run.pvd".to_string()]);
        entries.push((f64::NAN, "bad.pvtu".into()));
        let msg = write_pvd(&p, &entries).unwrap_err().to_string();
        assert!(msg.contains("bad.pvtu"), "{msg}");
        // The previous complete file is untouched.
        let root = parse_xml(&std::fs::read_to_string(&p).unwrap());
        assert_eq!(root.child("Collection").all("DataSet").len(), 3);
    }
}
