use nalgebra::{DMatrix, Matrix3, Vector3};

use super::*;
use crate::fe::{ElementType, FaceType};
use crate::material::Material;

const LINEAR: Material = Material::LinearElastic {
    young: 100.0,
    poisson: 0.3,
};
const NEO: Material = Material::NeoHookean {
    young: 100.0,
    poisson: 0.3,
};

use crate::test_rng::Rng;

/// A smooth nonlinear map of the parent domain (curves the edges of quadratic elements) with
/// positive Jacobian everywhere on it.
fn distort(xi: [f64; 3]) -> [f64; 3] {
    let a = Matrix3::new(1.0, 0.2, 0.1, 0.1, 0.9, -0.15, -0.05, 0.1, 1.1);
    let v = a * Vector3::from(xi);
    [
        v[0] + 0.3 + 0.05 * xi[1] * xi[2],
        v[1] - 0.2 + 0.04 * xi[0] * xi[2],
        v[2] + 0.1 + 0.06 * xi[0] * xi[1],
    ]
}

/// Distorted reference node coordinates of an element: the smooth map plus a small random
/// perturbation of every node.
fn distorted_nodes(et: ElementType, rng: &mut Rng) -> Vec<[f64; 3]> {
    let h = if et.is_hex() { 0.04 } else { 0.02 };
    et.node_coords()
        .into_iter()
        .map(|xi| distort(xi).map(|c| c + h * rng.sym()))
        .collect()
}

fn geometry(et: ElementType, x: &[[f64; 3]]) -> ElementGeometry {
    ElementGeometry::new(et, &et.quadrature(et.default_quadrature_degree()), x).unwrap()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, &x| a.max(x.abs()))
}

/// Displacement `u = H X + c` at the nodes.
fn affine_u(x: &[[f64; 3]], h: &Matrix3<f64>, c: [f64; 3]) -> Vec<[f64; 3]> {
    x.iter()
        .map(|xa| {
            let v = h * Vector3::from(*xa);
            [v[0] + c[0], v[1] + c[1], v[2] + c[2]]
        })
        .collect()
}

fn internal(geom: &ElementGeometry, mat: &Material, u: &[[f64; 3]]) -> Vec<f64> {
    let mut f = vec![0.0; 3 * u.len()];
    internal_force(geom, mat, u, &mut f, None).unwrap();
    f
}

#[test]
fn internal_force_tangent_matches_fd() {
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let h = Matrix3::new(0.1, -0.15, 0.05, 0.08, -0.05, 0.12, -0.1, 0.07, 0.15);
    for et in ElementType::ALL {
        let x = distorted_nodes(et, &mut rng);
        let geom = geometry(et, &x);
        let nn = et.num_nodes();
        for mat in [LINEAR, NEO] {
            let mut u = affine_u(&x, &h, [0.1, -0.2, 0.3]);
            for ua in &mut u {
                for c in ua.iter_mut() {
                    *c += 0.02 * rng.sym();
                }
            }
            let mut f = vec![0.0; 3 * nn];
            let mut k = DMatrix::from_element(3, 3, 7.0); // wrong shape: must be resized
            internal_force(&geom, &mat, &u, &mut f, Some(&mut k)).unwrap();
            assert_eq!(f, internal(&geom, &mat, &u));
            let eps = 1e-6;
            let mut k_fd = DMatrix::zeros(3 * nn, 3 * nn);
            for b in 0..nn {
                for kk in 0..3 {
                    let (mut up, mut um) = (u.clone(), u.clone());
                    up[b][kk] += eps;
                    um[b][kk] -= eps;
                    let (fp, fm) = (internal(&geom, &mat, &up), internal(&geom, &mat, &um));
                    for r in 0..3 * nn {
                        k_fd[(r, 3 * b + kk)] = (fp[r] - fm[r]) / (2.0 * eps);
                    }
                }
            }
            let scale = k.amax();
            let err = (&k - &k_fd).amax();
            assert!(
                err < 1e-6 * scale,
                "{et:?} {mat:?}: |K - K_fd| = {err}, |K| = {scale}"
            );
            assert!(
                (&k - k.transpose()).amax() < 1e-12 * scale,
                "{et:?} K not symmetric"
            );
        }
    }
}

#[test]
fn free_element_is_in_equilibrium() {
    let mut rng = Rng(12345);
    for et in ElementType::ALL {
        let x = distorted_nodes(et, &mut rng);
        let geom = geometry(et, &x);
        for mat in [LINEAR, NEO] {
            let u: Vec<[f64; 3]> = (0..et.num_nodes())
                .map(|_| [0.05 * rng.sym(), 0.05 * rng.sym(), 0.05 * rng.sym()])
                .collect();
            let f = internal(&geom, &mat, &u);
            assert!(max_abs(&f) > 1e-3, "{et:?}: trivial force");
            for i in 0..3 {
                let s: f64 = f.iter().skip(i).step_by(3).sum();
                assert!(
                    s.abs() < 1e-12 * max_abs(&f),
                    "{et:?} {mat:?}: sum f_{i} = {s}"
                );
            }
        }
    }
}

#[test]
fn rigid_motions_give_zero_force() {
    let mut rng = Rng(777);
    let axis = Vector3::new(1.0, 2.0, 3.0).normalize();
    let r =
        *nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), 1.1).matrix();
    for et in ElementType::ALL {
        let x = distorted_nodes(et, &mut rng);
        let geom = geometry(et, &x);
        // Translation: both laws.
        let u = vec![[0.3, -1.2, 2.5]; et.num_nodes()];
        for mat in [LINEAR, NEO] {
            let f = internal(&geom, &mat, &u);
            assert!(
                max_abs(&f) < 1e-11,
                "{et:?} {mat:?}: translation gives {}",
                max_abs(&f)
            );
        }
        // Large rotation: Neo-Hookean only (the small-strain law is not objective).
        let u = affine_u(&x, &(r - Matrix3::identity()), [0.5, 0.0, -0.3]);
        let f = internal(&geom, &NEO, &u);
        assert!(
            max_abs(&f) < 1e-11,
            "{et:?}: rotation gives {}",
            max_abs(&f)
        );
        let f_lin = internal(&geom, &LINEAR, &u);
        assert!(
            max_abs(&f_lin) > 1.0,
            "{et:?}: linear law should not be objective"
        );
    }
}

#[test]
fn uniform_strain_gives_uniform_stress() {
    let mut rng = Rng(4242);
    let h = Matrix3::new(0.05, 0.02, -0.03, 0.01, -0.04, 0.02, 0.03, 0.0, 0.06);
    let f_exact = Matrix3::identity() + h;
    for et in ElementType::ALL {
        let x = distorted_nodes(et, &mut rng);
        let geom = geometry(et, &x);
        let u = affine_u(&x, &h, [0.2, 0.1, -0.4]);
        for mat in [LINEAR, NEO] {
            let s_exact = mat.cauchy(&f_exact);
            let tol = 1e-10 * s_exact.amax();
            let mut count = 0;
            for_each_point(&geom, &u, |xq, fm, w| {
                assert!(w > 0.0);
                assert!((fm - f_exact).amax() < 1e-10, "{et:?}: F = {fm} at {xq:?}");
                let s = mat.cauchy(fm);
                assert!(
                    (s - s_exact).amax() < tol,
                    "{et:?} {mat:?}: {s} vs {s_exact}"
                );
                count += 1;
            });
            assert_eq!(count, geom.num_points());
            let (s, vm) = element_stress(&geom, &mat, &u);
            assert!((s - s_exact).amax() < tol, "{et:?} {mat:?}");
            assert!((vm - crate::material::von_mises(&s_exact)).abs() < tol);
        }
    }
}

/// Points are where the rule puts them: the quadrature-point positions interpolate the nodes.
#[test]
fn geometry_volume_and_points() {
    let a = Matrix3::new(2.0, 0.3, 0.1, -0.2, 1.5, 0.4, 0.1, 0.2, 0.8);
    let c = [1.0, -2.0, 0.5];
    for et in ElementType::ALL {
        let x = affine_u(&et.node_coords(), &a, c);
        let geom = geometry(et, &x);
        let ref_vol = if et.is_hex() { 8.0 } else { 1.0 / 6.0 };
        assert!(
            (geom.volume() - a.determinant() * ref_vol).abs() < 1e-12,
            "{et:?}"
        );
        let rule = et.quadrature(et.default_quadrature_degree());
        assert_eq!(geom.num_points(), rule.points.len());
        for (q, xi) in rule.points.iter().enumerate() {
            let xq = affine_u(&[*xi], &a, c)[0];
            for (pd, xd) in geom.point(q).iter().zip(xq) {
                assert!((pd - xd).abs() < 1e-13);
            }
            let s: f64 = geom.shape_values(q).iter().sum();
            assert!((s - 1.0).abs() < 1e-13);
        }
    }
}

#[test]
fn body_force_sums_to_b_times_volume() {
    let mut rng = Rng(99);
    let b = [1.5, -2.0, 9.81];
    for et in ElementType::ALL {
        let x = distorted_nodes(et, &mut rng);
        let geom = geometry(et, &x);
        let mut f = vec![1.0; 3 * et.num_nodes()];
        body_force(&geom, b, &mut f);
        for (i, bi) in b.iter().enumerate() {
            let s: f64 = f.iter().skip(i).step_by(3).sum();
            assert!((s - bi * geom.volume()).abs() < 1e-12, "{et:?}: {s}");
        }
    }
}

#[test]
fn inverted_elements_are_rejected() {
    for et in ElementType::ALL {
        let rule = et.quadrature(et.default_quadrature_degree());
        // Mirror image: negative everywhere.
        let x: Vec<[f64; 3]> = et
            .node_coords()
            .into_iter()
            .map(|p| [-p[0], p[1], p[2]])
            .collect();
        let err = ElementGeometry::new(et, &rule, &x).unwrap_err();
        assert_eq!(err.point, 0);
        assert!(err.det < 0.0);
        assert!(err
            .describe(rule.points.len())
            .contains("quadrature point 0"));
    }
    // A Hex8 with one corner pulled inside: the quadrature points are still fine, the corner is not.
    let et = ElementType::Hex8;
    let rule = et.quadrature(et.default_quadrature_degree());
    let mut x = et.node_coords();
    x[6] = [0.2, 0.2, 0.2];
    let err = ElementGeometry::new(et, &rule, &x).unwrap_err();
    assert_eq!(err.node(rule.points.len()), Some(6), "{err:?}");
    assert!(err.det <= 0.0);
}

#[test]
fn inverted_deformation_is_an_error() {
    for et in ElementType::ALL {
        let x = et.node_coords();
        let geom = geometry(et, &x);
        let u = affine_u(
            &x,
            &Matrix3::from_diagonal(&Vector3::new(-2.0, 0.0, 0.0)),
            [0.0; 3],
        );
        let mut f = vec![0.0; 3 * et.num_nodes()];
        let det = internal_force(&geom, &NEO, &u, &mut f, None).unwrap_err();
        assert!((det + 1.0).abs() < 1e-12, "{et:?}: det = {det}");
        assert!(internal_force(&geom, &LINEAR, &u, &mut f, None).is_ok());
    }
}

fn pressure(ft: FaceType, x: &[[f64; 3]], p: f64) -> Vec<f64> {
    let mut f = vec![0.0; 3 * x.len()];
    follower_pressure(
        ft,
        &ft.quadrature(ft.default_quadrature_degree()),
        x,
        p,
        &mut f,
        None,
    );
    f
}

#[test]
fn follower_pressure_tangent_matches_fd() {
    let mut rng = Rng(31337);
    let p = 2.5;
    for et in ElementType::ALL {
        let ft = et.face_type();
        let xe = distorted_nodes(et, &mut rng);
        for face in 0..et.num_faces() {
            let x: Vec<[f64; 3]> = et.face_nodes(face).iter().map(|&a| xe[a]).collect();
            let n = 3 * x.len();
            let rule = ft.quadrature(ft.default_quadrature_degree());
            let mut f = vec![0.0; n];
            let mut k = DMatrix::zeros(n, n);
            follower_pressure(ft, &rule, &x, p, &mut f, Some(&mut k));
            assert_eq!(f, pressure(ft, &x, p));
            let eps = 1e-6;
            let mut k_fd = DMatrix::zeros(n, n);
            for b in 0..x.len() {
                for kk in 0..3 {
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[b][kk] += eps;
                    xm[b][kk] -= eps;
                    let (fp, fm) = (pressure(ft, &xp, p), pressure(ft, &xm, p));
                    for r in 0..n {
                        k_fd[(r, 3 * b + kk)] = (fp[r] - fm[r]) / (2.0 * eps);
                    }
                }
            }
            let scale = k.amax();
            assert!(scale > 0.1);
            let err = (&k - &k_fd).amax();
            assert!(err < 1e-6 * scale, "{ft:?} face {face}: |K - K_fd| = {err}");
        }
    }
}

#[test]
fn pressure_on_closed_surface_sums_to_zero() {
    let mut rng = Rng(2024);
    let p = 3.0;
    for et in ElementType::ALL {
        let ft: FaceType = et.face_type();
        // Unit cube [0, 1]^3 for hexahedra, the unit tetrahedron for tetrahedra.
        let x0: Vec<[f64; 3]> = if et.is_hex() {
            et.node_coords()
                .into_iter()
                .map(|p| p.map(|c| 0.5 * (c + 1.0)))
                .collect()
        } else {
            et.node_coords()
        };
        let xd = distorted_nodes(et, &mut rng);
        for (x, undeformed) in [(&x0, true), (&xd, false)] {
            let mut total = [0.0; 3];
            for face in 0..et.num_faces() {
                let xf: Vec<[f64; 3]> = et.face_nodes(face).iter().map(|&a| x[a]).collect();
                let f = pressure(ft, &xf, p);
                let mut s = [0.0; 3];
                for i in 0..3 {
                    s[i] = f.iter().skip(i).step_by(3).sum::<f64>();
                    total[i] += s[i];
                }
                if undeformed {
                    // Resultant -p * area * outward normal.
                    let expected = if et.is_hex() {
                        let mut e = [0.0; 3];
                        e[face / 2] = if face % 2 == 0 { p } else { -p };
                        e
                    } else {
                        match face {
                            0 => [0.0, 0.0, 0.5 * p],
                            1 => [0.0, 0.5 * p, 0.0],
                            2 => [0.5 * p, 0.0, 0.0],
                            _ => [-0.5 * p; 3],
                        }
                    };
                    for i in 0..3 {
                        assert!(
                            (s[i] - expected[i]).abs() < 1e-13,
                            "{et:?} face {face}: {s:?}"
                        );
                    }
                }
            }
            for t in total {
                assert!(t.abs() < 1e-12, "{et:?}: closed surface gives {total:?}");
            }
        }
    }
}
