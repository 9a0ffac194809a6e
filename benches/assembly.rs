//! Bulk element assembly throughput: [`mortar::solid::internal_force`] over a batch of elements.
//!
//! # What is measured
//!
//! One benchmark iteration evaluates the internal force of every element of a batch of about
//! 1000 elements (a `box_mesh` of the unit cube, 10x10x10 hexahedra or 4x6x7 cells of six
//! tetrahedra), each with its own precomputed [`ElementGeometry`] and nodal displacements, so
//! criterion's throughput (`Throughput::Elements`) is printed in elements per second.
//!
//! - `assembly_tangent/<element>/<material>`: internal force **and** tangent
//!   (`k = Some(..)`), what a Jacobian evaluation of the Newton solver does per element.
//! - `assembly_residual/<element>/<material>`: internal force only (`k = None`), what a residual
//!   evaluation does.
//!
//! Elements: Hex8 (2x2x2 Gauss), Hex20 and Hex27 (3x3x3), Tet10 (degree 4), each with its
//! default quadrature degree. Materials: compressible Neo-Hookean and small-strain linear
//! elasticity (`E = 1000`, `nu = 0.3`).
//!
//! Only the element kernel is timed: no gather of displacements, no scatter into a global matrix,
//! no allocation (the force vector and the tangent are allocated once per benchmark with the
//! right shape, as the solver does). Geometry setup is outside the timed loop.
//!
//! - `assembly_scatter/<element>/<path>`: the other half of a Jacobian evaluation, the element
//!   tangents added into the PETSc matrix (one rank, the mesh's exact pattern, zeroed and
//!   assembled in each iteration; one dense tangent for every element, so only the scatter is
//!   timed): `set_values` is `MatSetValues` per element, `owned_rows` the direct path the
//!   solver uses (`petsc::OwnedRows`). Hex8 and Hex27.
//!
//! # Inputs
//!
//! The elements are not parallelepipeds: every node of the box mesh (mid-edge, face and centre
//! nodes included) is moved by a smooth orientation-preserving map plus a deterministic
//! pseudo-random jitter of 5% of the cell size, so the elements are curved and irregular and
//! `dN/dX` differs from point to point. The displacement field is a smooth finite deformation
//! (about 10% compression along z, shear and bending-like terms, displacement gradients up to
//! about 0.2), sampled at the reference nodes.
//!
//! Run: `cargo bench --bench assembly -- --noplot` (or `benches/report.sh`).

use std::f64::consts::PI;
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput};
use nalgebra::DMatrix;

use mortar::dofs::DofMap;
use mortar::fe::ElementType;
use mortar::material::Material;
use mortar::mesh::generate::box_mesh;
use mortar::petsc::{Matrix, Petsc, PetscInt};
use mortar::solid::{internal_force, ElementGeometry};

/// A batch of elements of one type, ready for the kernel.
struct Batch {
    kind: ElementType,
    geoms: Vec<ElementGeometry>,
    /// Nodal displacements of each element (element-local node order).
    disp: Vec<Vec<[f64; 3]>>,
}

/// Cells per axis: 1000 hexahedra, or 168 cells x 6 = 1008 tetrahedra.
fn divisions(kind: ElementType) -> [usize; 3] {
    if kind.is_hex() {
        [10, 10, 10]
    } else {
        [4, 6, 7]
    }
}

/// A deterministic pseudo-random number in `[-1, 1]` from a node index and a component.
fn jitter(node: usize, comp: usize) -> f64 {
    // SplitMix64 finalizer.
    let mut z = (node as u64)
        .wrapping_mul(3)
        .wrapping_add(comp as u64)
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    2.0 * (z >> 11) as f64 / (1u64 << 53) as f64 - 1.0
}

/// Distorted position of a reference node `x` of the unit cube (node index `node`), with `h` the
/// smallest cell size.
fn distort(x: [f64; 3], node: usize, h: f64) -> [f64; 3] {
    let s = |t: f64| (PI * t).sin();
    let smooth = [
        x[0] + 0.04 * s(x[1]) * s(x[2]),
        x[1] + 0.04 * s(x[2]) * s(x[0]),
        x[2] + 0.04 * s(x[0]) * s(x[1]),
    ];
    let a = 0.05 * h;
    [
        smooth[0] + a * jitter(node, 0),
        smooth[1] + a * jitter(node, 1),
        smooth[2] + a * jitter(node, 2),
    ]
}

/// The displacement field sampled at reference position `x`: about 10% compression along z with
/// lateral bulging, shear and bending terms.
fn displacement(x: [f64; 3]) -> [f64; 3] {
    let s = |t: f64| (PI * t).sin();
    let c = |t: f64| (PI * t).cos();
    [
        0.03 * (x[0] - 0.5) + 0.04 * x[2] * s(x[1]) + 0.02 * c(x[2]),
        0.03 * (x[1] - 0.5) - 0.03 * x[2] * s(x[0]),
        -0.10 * x[2] + 0.02 * s(x[0]) * s(x[1]),
    ]
}

/// The elements of a distorted box mesh of `kind`, with their geometry and displacements.
fn batch(kind: ElementType) -> Batch {
    let div = divisions(kind);
    let mut mesh = box_mesh(kind, div, [0.0; 3], [1.0; 3], "bench");
    let h = 1.0 / *div.iter().max().expect("three divisions") as f64;
    for (node, x) in mesh.coords.iter_mut().enumerate() {
        *x = distort(*x, node, h);
    }
    let rule = kind.quadrature(kind.default_quadrature_degree());
    let mut geoms = Vec::with_capacity(mesh.num_elements());
    let mut disp = Vec::with_capacity(mesh.num_elements());
    for e in 0..mesh.num_elements() {
        let x_ref = mesh.element_coords(e);
        let geom = ElementGeometry::new(kind, &rule, &x_ref).unwrap_or_else(|inv| {
            panic!(
                "{} element {e} is inverted: {}",
                kind.name(),
                inv.describe(rule.points.len())
            )
        });
        geoms.push(geom);
        disp.push(x_ref.iter().map(|&x| displacement(x)).collect());
    }
    Batch { kind, geoms, disp }
}

/// Evaluates every element of the batch once; returns a checksum of the results (so that
/// nothing is optimized away).
fn sweep(b: &Batch, mat: &Material, f: &mut [f64], mut k: Option<&mut DMatrix<f64>>) -> f64 {
    let mut sum = 0.0;
    for (geom, u) in b.geoms.iter().zip(&b.disp) {
        internal_force(black_box(geom), mat, black_box(u), f, k.as_deref_mut())
            .expect("no element inverts under the benchmark displacement");
        sum += f[0];
        if let Some(k) = k.as_deref() {
            sum += k[(0, 0)];
        }
    }
    sum
}

fn assembly(c: &mut Criterion) {
    let batches: Vec<Batch> = [
        ElementType::Hex8,
        ElementType::Hex20,
        ElementType::Hex27,
        ElementType::Tet10,
    ]
    .into_iter()
    .map(batch)
    .collect();
    let materials = [
        Material::NeoHookean {
            young: 1000.0,
            poisson: 0.3,
        },
        Material::LinearElastic {
            young: 1000.0,
            poisson: 0.3,
        },
    ];
    for (group_name, tangent) in [("assembly_tangent", true), ("assembly_residual", false)] {
        let mut group = c.benchmark_group(group_name);
        for b in &batches {
            group.throughput(Throughput::Elements(b.geoms.len() as u64));
            let n = 3 * b.kind.num_nodes();
            for mat in &materials {
                let id = BenchmarkId::new(b.kind.name(), mat.name());
                group.bench_with_input(id, mat, |bencher, mat| {
                    let mut f = vec![0.0; n];
                    let mut k = DMatrix::zeros(n, n);
                    bencher.iter(|| {
                        let k = if tangent { Some(&mut k) } else { None };
                        black_box(sweep(b, mat, &mut f, k))
                    });
                });
            }
        }
        group.finish();
    }
}

/// The element tangents scattered into a PETSc matrix, by `MatSetValues` and by the direct path.
fn scatter(c: &mut Criterion) {
    let mut group = c.benchmark_group("assembly_scatter");
    for kind in [ElementType::Hex8, ElementType::Hex27] {
        let mesh = box_mesh(kind, divisions(kind), [0.0; 3], [1.0; 3], "bench");
        let ne = mesh.num_elements();
        let dofs = DofMap::new(&mesh, vec![0; ne], 0, 1, &vec![false; 3 * mesh.num_nodes()]);
        let mut jac = Matrix::new_aij(&dofs.bulk_sparsity(&mesh)).expect("a matrix");
        let n = 3 * kind.num_nodes();
        let tangent: Vec<f64> = (0..n * n).map(|k| jitter(k, 0)).collect();
        let elements: Vec<Vec<PetscInt>> = (0..ne)
            .map(|e| {
                let mut idx = Vec::new();
                dofs.element_dofs(mesh.element_nodes(e), &mut idx);
                idx
            })
            .collect();
        group.throughput(Throughput::Elements(ne as u64));
        for path in ["set_values", "owned_rows"] {
            group.bench_function(BenchmarkId::new(kind.name(), path), |bencher| {
                bencher.iter(|| {
                    jac.zero_entries().expect("zeroed");
                    if path == "set_values" {
                        for idx in &elements {
                            jac.add_values(idx, idx, &tangent).expect("added");
                        }
                    } else {
                        jac.with_owned_rows(|rows| {
                            elements
                                .iter()
                                .try_for_each(|idx| rows.add(idx, idx, &tangent))
                        })
                        .expect("added");
                    }
                    jac.assemble().expect("assembled");
                });
            });
        }
    }
    group.finish();
}

fn main() {
    // PETSc (and MPI) for the scatter benchmarks, finalized after them.
    let petsc = Petsc::initialize(&["bench".into()], None)
        .unwrap_or_else(|e| panic!("PETSc initialization failed: {e}"));
    let mut criterion = Criterion::default().configure_from_args();
    assembly(&mut criterion);
    scatter(&mut criterion);
    criterion.final_summary();
    drop(petsc);
}
