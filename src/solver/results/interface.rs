//! One interface pass as a VTU piece: the faces that carried the tractions (reference
//! coordinates) with point fields `displacement`, `normal` (the averaged unit face normal, from
//! the reference geometry) and the pass's fields, given at its traction nodes and interpolated
//! by the scheme's traction functions at the other nodes where asked.

use std::collections::BTreeMap;
use std::path::Path;

use crate::case::Scene;
use crate::contact::mortar::{traction_nodes, traction_shape, TractionScheme};
use crate::error::Result;
use crate::io::output::{write_vtu, Field, Piece};
use crate::model::{RowField, SurfaceOutput};

/// The faces of an interface pass as cells over their nodes, each node once (numbered in the
/// order the faces meet them), with what the point fields need at each.
struct SurfaceCells {
    /// Mesh node -> point.
    index: BTreeMap<usize, usize>,
    types: Vec<u8>,
    connectivity: Vec<usize>,
    offsets: Vec<usize>,
    /// Per point: the sum of the unit normals of the faces around it.
    normal_sum: Vec<[f64; 3]>,
    /// Per point without a traction unknown: the rows and weights interpolating it, summed
    /// over the faces around it, and how many faces those are.
    interpolation: Vec<Vec<(usize, f64)>>,
    faces_at: Vec<f64>,
}

impl SurfaceCells {
    fn new(scene: &Scene, surface: &SurfaceOutput, row_of: &BTreeMap<usize, usize>) -> Self {
        let mesh = &scene.mesh;
        let mut cells = SurfaceCells {
            index: BTreeMap::new(),
            types: Vec::new(),
            connectivity: Vec::new(),
            offsets: Vec::new(),
            normal_sum: Vec::new(),
            interpolation: Vec::new(),
            faces_at: Vec::new(),
        };
        let scheme = surface.scheme;
        let mut phi = Vec::new();
        for &f in &surface.faces {
            let nodes = mesh.face_nodes(f);
            let kind = mesh.face_type(f);
            let x: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
            let carriers = traction_nodes(kind, scheme).unwrap_or_default();
            for (&n, xi) in nodes.iter().zip(kind.node_coords()) {
                let k = cells.point(n);
                let (nrm, _) = crate::fe::face_normal(kind, &x, xi);
                for (sum, v) in cells.normal_sum[k].iter_mut().zip(nrm) {
                    *sum += v;
                }
                if !row_of.contains_key(&n) && scheme != TractionScheme::PiecewiseLinear {
                    traction_shape(kind, scheme, 0, xi, &mut phi);
                    for (p, &local) in phi.iter().zip(&carriers) {
                        if let Some(&r) = row_of.get(&nodes[local]) {
                            cells.interpolation[k].push((r, *p));
                        }
                    }
                    cells.faces_at[k] += 1.0;
                }
                cells.connectivity.push(k);
            }
            cells.offsets.push(cells.connectivity.len());
            cells.types.push(kind.vtk_cell_type());
        }
        cells
    }

    /// The point of mesh node `n`, made on first sight.
    fn point(&mut self, n: usize) -> usize {
        let next = self.index.len();
        let k = *self.index.entry(n).or_insert(next);
        if k == self.normal_sum.len() {
            self.normal_sum.push([0.0; 3]);
            self.interpolation.push(Vec::new());
            self.faces_at.push(0.0);
        }
        k
    }

    /// The averaged unit normal at every point.
    fn normals(&self) -> Vec<f64> {
        self.normal_sum
            .iter()
            .flat_map(|v| {
                let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                    .sqrt()
                    .max(f64::MIN_POSITIVE);
                [v[0] / l, v[1] / l, v[2] / l]
            })
            .collect()
    }

    /// A row field at every point: its row's value at a traction node, else interpolated (or
    /// its absent value).
    fn values(&self, field: &RowField, row_of: &BTreeMap<usize, usize>) -> Vec<f64> {
        let nc = field.components;
        let absent = if field.interpolate { 0.0 } else { field.absent };
        let mut out = vec![absent; nc * self.index.len()];
        for (&node, &k) in &self.index {
            if let Some(&r) = row_of.get(&node) {
                out[nc * k..nc * (k + 1)].copy_from_slice(&field.values[nc * r..nc * (r + 1)]);
            } else if field.interpolate && self.faces_at[k] > 0.0 {
                for &(r, p) in &self.interpolation[k] {
                    for c in 0..nc {
                        out[nc * k + c] += p * field.values[nc * r + c] / self.faces_at[k];
                    }
                }
            }
        }
        out
    }
}

/// Writes `surface` at displacements `u` to `path` (module docs).
pub(super) fn write_interface_piece(
    path: &Path,
    scene: &Scene,
    surface: &SurfaceOutput,
    u: &[f64],
) -> Result<()> {
    let mesh = &scene.mesh;
    let row_of: BTreeMap<usize, usize> = surface
        .rows
        .iter()
        .enumerate()
        .map(|(r, &n)| (n, r))
        .collect();
    let cells = SurfaceCells::new(scene, surface, &row_of);
    let n = cells.index.len();
    let mut points = vec![[0.0; 3]; n];
    let mut disp = vec![0.0; 3 * n];
    for (&node, &k) in &cells.index {
        points[k] = mesh.coords[node];
        disp[3 * k..3 * k + 3].copy_from_slice(&u[3 * node..3 * node + 3]);
    }
    let normals = cells.normals();
    let values: Vec<Vec<f64>> = surface
        .fields
        .iter()
        .map(|f| cells.values(f, &row_of))
        .collect();
    let mut point_data = vec![
        Field::new("displacement", 3, &disp),
        Field::new("normal", 3, &normals),
    ];
    for (field, values) in surface.fields.iter().zip(&values) {
        point_data.push(Field {
            name: field.name,
            components: field.components,
            values,
        });
    }
    let piece = Piece {
        points: &points,
        cell_types: &cells.types,
        connectivity: &cells.connectivity,
        offsets: &cells.offsets,
        point_data,
        cell_data: vec![],
    };
    write_vtu(path, &piece)
}
