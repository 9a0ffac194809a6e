//! Functions of the face parent coordinates `xi` at a quadrature point, in floats with their
//! `xi`-derivatives: the shape functions of both faces and the surface Jacobian `J_face` of the
//! secondary face (module docs of [`super`], level 2). Each is rounded as a `ParentDual`
//! evaluation rounds it, so that the float level 2 reproduces the dual formulation bit for bit.

use super::{slots, ParentDual, MAX_NODES, MAX_SEC_DOFS};
use crate::fe::shape::TensorShape;
use crate::fe::FaceType;
use crate::vec3::{cross, Vec3};

/// Parent coordinates as duals seeded on their own two slots.
pub(super) fn parent_seed(xi: [f64; 2]) -> [ParentDual; 2] {
    [
        ParentDual::from_re(xi[0]).derivative(0),
        ParentDual::from_re(xi[1]).derivative(1),
    ]
}

/// A function of the parent coordinates: value and `xi`-derivatives, as plain floats.
#[derive(Clone, Copy, Default)]
pub(super) struct OfParent {
    pub(super) re: f64,
    pub(super) d: [f64; 2],
}

impl OfParent {
    pub(super) fn of(f: &ParentDual) -> Self {
        OfParent {
            re: f.re,
            d: slots(f),
        }
    }

    /// The first `from.len()` entries of `to` from `from`.
    pub(super) fn fill(to: &mut [OfParent], from: &[ParentDual]) {
        for (t, f) in to.iter_mut().zip(from) {
            *t = OfParent::of(f);
        }
    }
}

/// The shape functions of `kind` at `xi` with their `xi`-derivatives, as a `ParentDual`
/// evaluation gives them (in floats on Quad4 and Quad9), into the first `kind.num_nodes()`
/// entries of `to`.
pub(super) fn shape_values_at(kind: FaceType, xi: [f64; 2], to: &mut [OfParent]) {
    let nn = kind.num_nodes();
    let mut shapes = [TensorShape::default(); MAX_NODES];
    if kind.tensor_shape_derivatives(xi, &mut shapes[..nn]) {
        for (t, shape) in to.iter_mut().zip(&shapes[..nn]) {
            *t = OfParent {
                re: shape.value,
                d: shape.value_derivative,
            };
        }
    } else {
        let mut n = [ParentDual::from_re(0.0); MAX_NODES];
        kind.shape_at(parent_seed(xi), &mut n[..nn]);
        OfParent::fill(to, &n[..nn]);
    }
}

/// The shape functions of the secondary face at `xi` with their first and second derivatives
/// (for `J_face` and its `xi`-derivatives): [`FaceType::tensor_shape_derivatives`] on Quad4 and
/// Quad9, the generic kernels in `ParentDual` numbers on the other faces (the same numbers).
pub(super) fn shape_derivatives(kind: FaceType, xi: [f64; 2], out: &mut [TensorShape]) {
    if kind.tensor_shape_derivatives(xi, out) {
        return;
    }
    let nn = kind.num_nodes();
    let zero = ParentDual::from_re(0.0);
    let (mut nd, mut dnd) = ([zero; MAX_NODES], [[zero; 2]; MAX_NODES]);
    kind.shape_and_grad_at(parent_seed(xi), &mut nd[..nn], &mut dnd[..nn]);
    for (o, (n, g)) in out.iter_mut().zip(nd.iter().zip(&dnd)) {
        *o = TensorShape {
            value: n.re,
            value_derivative: slots(n),
            gradient: [g[0].re, g[1].re],
            gradient_derivative: [slots(&g[0]), slots(&g[1])],
        };
    }
}

/// The surface Jacobian `J_face = |x_,xi x x_,eta|` of a face with node coordinates `x` from
/// its shape functions at a point, with its `xi`-derivatives, and `dJ_face/dx_a` (node `a`,
/// axis `d` at `3 a + d`) into `dj_dx`.
///
/// The `xi`-derivatives are those of `ParentDual` arithmetic on the tangents
/// `t_i = sum_a N_a,i x_a` (with `dt_i/dxi_j = sum_a N_a,ij x_a`), written out in its order of
/// operations: the product rule in `c = t_1 x t_2` and `c . c`, and `d sqrt(s) = ds sqrt(s)
/// (1 / s) / 2`.
pub(super) fn face_jacobian(
    x: &[[f64; 3]],
    shapes: &[TensorShape],
    dj_dx: &mut [f64; MAX_SEC_DOFS],
) -> OfParent {
    // t[i] = x_,i with its derivatives dt[i][d][j] = x_,ij.
    let mut t = [[0.0; 3]; 2];
    let mut dt = [[[0.0; 2]; 3]; 2];
    for (xa, shape) in x.iter().zip(shapes) {
        for i in 0..2 {
            let (g, h) = (shape.gradient[i], shape.gradient_derivative[i]);
            for d in 0..3 {
                t[i][d] += g * xa[d];
                for j in 0..2 {
                    dt[i][d][j] += h[j] * xa[d];
                }
            }
        }
    }
    let c = cross(t[0], t[1]);
    // d(a b - e f) = (da b + db a) - (de f + df e), as in vec3::cross.
    let product_difference = |(a, b): (usize, usize), (e, f): (usize, usize), j: usize| {
        (dt[0][a][j] * t[1][b] + dt[1][b][j] * t[0][a])
            - (dt[0][e][j] * t[1][f] + dt[1][f][j] * t[0][e])
    };
    let dc: [[f64; 2]; 3] = [
        std::array::from_fn(|j| product_difference((1, 2), (2, 1), j)),
        std::array::from_fn(|j| product_difference((2, 0), (0, 2), j)),
        std::array::from_fn(|j| product_difference((0, 1), (1, 0), j)),
    ];
    let squares = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let jacobian = squares.sqrt();
    let slope = jacobian * (1.0 / squares) * 0.5;
    let d = std::array::from_fn(|j| {
        let square = |k: usize| dc[k][j] * c[k] + dc[k][j] * c[k];
        (square(0) + square(1) + square(2)) * slope
    });
    let gradients = shapes.iter().map(|shape| shape.gradient);
    face_jacobian_by_nodes(t, c, jacobian, gradients, dj_dx);
    OfParent { re: jacobian, d }
}

/// `dJ_face/dx_a` (node `a`, axis `d` at `3 a + d`) into `dj_dx`, from the tangents
/// `t_i = x_,i`, `c = t_1 x t_2`, `J_face = |c|` and the gradients `N_a,i` of the shape functions
/// at the point: `dJ = (t_2 x n) . dt_1 + (n x t_1) . dt_2` with `n = c / J_face` and
/// `dt_i = sum_a N_a,i dx_a`. Zero where `J_face` is not positive.
pub(super) fn face_jacobian_by_nodes(
    t: [Vec3; 2],
    c: Vec3,
    jacobian: f64,
    gradients: impl Iterator<Item = [f64; 2]>,
    dj_dx: &mut [f64; MAX_SEC_DOFS],
) {
    dj_dx.fill(0.0);
    if jacobian > 0.0 {
        let n = c.map(|v| v / jacobian);
        let (h1, h2) = (cross(t[1], n), cross(n, t[0]));
        for (a, g) in gradients.enumerate() {
            for d in 0..3 {
                dj_dx[3 * a + d] = h1[d] * g[0] + h2[d] * g[1];
            }
        }
    }
}
