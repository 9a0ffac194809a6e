//! Body force and follower pressure (see the module docs of [`crate::solid`] for the formulas).

use nalgebra::DMatrix;

use super::kernel::ElementGeometry;
use crate::fe::quadrature::Rule2;
use crate::fe::FaceType;

/// The largest number of nodes of a face (Quad9): the size of stack buffers.
pub const MAX_FACE_NODES: usize = 9;

/// Body force b (per reference volume) consistent nodal load: f_a = int N_a b dV0 (length 3nn,
/// overwritten).
///
/// # Panics
/// If `f.len() != 3 num_nodes`.
pub fn body_force(geom: &ElementGeometry, b: [f64; 3], f: &mut [f64]) {
    assert_eq!(
        f.len(),
        3 * geom.num_nodes(),
        "body_force: wrong force length"
    );
    f.fill(0.0);
    for q in 0..geom.num_points() {
        let w = geom.weight(q);
        for (fa, na) in f.chunks_exact_mut(3).zip(geom.shape_values(q)) {
            for (fai, bi) in fa.iter_mut().zip(b) {
                *fai += w * na * bi;
            }
        }
    }
}

/// Follower pressure p on a face (positive p pushes against the outward normal, i.e. compresses),
/// on the CURRENT configuration `x_cur = X + u` of the face nodes (face node order): external
/// force `f_a = -p int N_a (x_,xi x x_,eta) dxi deta` (length 3n, overwritten), with its
/// (nonsymmetric) tangent `d f / d x` (3n x 3n, overwritten; resized if its shape is wrong) if
/// requested.
///
/// # Panics
/// If `x_cur.len() != ft.num_nodes()` or `f.len() != 3 ft.num_nodes()`.
pub fn follower_pressure(
    ft: FaceType,
    rule: &Rule2,
    x_cur: &[[f64; 3]],
    p: f64,
    f: &mut [f64],
    mut k: Option<&mut DMatrix<f64>>,
) {
    let nn = ft.num_nodes();
    let n = 3 * nn;
    assert_eq!(x_cur.len(), nn, "follower_pressure: wrong number of nodes");
    assert_eq!(f.len(), n, "follower_pressure: wrong force length");
    f.fill(0.0);
    if let Some(k) = k.as_deref_mut() {
        if k.shape() != (n, n) {
            *k = DMatrix::zeros(n, n);
        } else {
            k.fill(0.0);
        }
    }
    let mut nv = [0.0; MAX_FACE_NODES];
    let mut dn = [[0.0; 2]; MAX_FACE_NODES];
    let (nv, dn) = (&mut nv[..nn], &mut dn[..nn]);
    for (&xi, &w) in rule.points.iter().zip(&rule.weights) {
        ft.shape(xi, nv);
        ft.shape_grad(xi, dn);
        let (mut t1, mut t2) = ([0.0; 3], [0.0; 3]);
        for (xa, da) in x_cur.iter().zip(dn.iter()) {
            for d in 0..3 {
                t1[d] += da[0] * xa[d];
                t2[d] += da[1] * xa[d];
            }
        }
        let c = [
            t1[1] * t2[2] - t1[2] * t2[1],
            t1[2] * t2[0] - t1[0] * t2[2],
            t1[0] * t2[1] - t1[1] * t2[0],
        ];
        let pw = p * w;
        for (fa, na) in f.chunks_exact_mut(3).zip(nv.iter()) {
            for (fai, ci) in fa.iter_mut().zip(c) {
                *fai -= pw * na * ci;
            }
        }
        let Some(k) = k.as_deref_mut() else {
            continue;
        };
        for (b, db) in dn.iter().enumerate() {
            // d(t1 x t2)/dx_b = [v]_x with v = N_b,eta t1 - N_b,xi t2.
            let v = [
                db[1] * t1[0] - db[0] * t2[0],
                db[1] * t1[1] - db[0] * t2[1],
                db[1] * t1[2] - db[0] * t2[2],
            ];
            let skew = [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
            for (a, na) in nv.iter().enumerate() {
                let s = -pw * na;
                for (i, row) in skew.iter().enumerate() {
                    for (kk, sik) in row.iter().enumerate() {
                        k[(3 * a + i, 3 * b + kk)] += s * sik;
                    }
                }
            }
        }
    }
}
