//! Shape functions of the solid elements and faces, and the geometry of a face.
//!
//! Node ordering and parent domains are those of [`super::element`] (VTK ordering); every shape
//! function satisfies `N_a(node_coords()[b]) = delta_ab`.
//!
//! # Hexahedra and quadrilaterals (parent domain `[-1, 1]^d`, `d = 3` or `2`)
//!
//! Node `a` sits at `s^a` with `s^a_i` in `{-1, 0, 1}`. All three families are built from products
//! of one-dimensional factors:
//!
//! - **Hex8, Quad4** (multilinear): `N_a = prod_i (1 + s^a_i x_i) / 2`.
//! - **Hex27, Quad9** (Lagrange, tensor product of the 1D quadratics):
//!   `N_a = prod_i l_{s^a_i}(x_i)` with `l_{-1}(t) = t (t - 1) / 2`, `l_0(t) = 1 - t^2`,
//!   `l_{+1}(t) = t (t + 1) / 2`.
//! - **Hex20, Quad8** (serendipity), with `p_i = 1 + s^a_i x_i`:
//!   - corner nodes: `N_a = 2^-d (prod_i p_i) (sum_i s^a_i x_i - (d - 1))`, whose gradient is
//!     `dN_a/dx_j = 2^-d s^a_j (prod_{i != j} p_i) (sum_i s^a_i x_i + s^a_j x_j + 2 - d)`;
//!   - mid-edge nodes, on the edge along direction `m` (`s^a_m = 0`):
//!     `N_a = 2^(1-d) (1 - x_m^2) prod_{i != m} p_i`.
//!
//!   The serendipity space is spanned by the monomials `x^a y^b z^c` with every exponent `<= 2`
//!   and at most one exponent equal to 2 (20 monomials in 3D, 8 in 2D).
//!
//! # Tetrahedra and triangles (unit simplex)
//!
//! With the barycentric coordinates `L_0 = 1 - sum_i x_i`, `L_i = x_i` (`i = 1..=d`):
//!
//! - **Tet4, Tri3**: `N_a = L_a`.
//! - **Tet10, Tri6**: corners `N_a = L_a (2 L_a - 1)`; the mid-edge node of edge `(a, b)`:
//!   `N = 4 L_a L_b`. Gradients follow from `grad L_0 = (-1, ..., -1)`, `grad L_i = e_i`.
//!
//! # Face geometry
//!
//! For a face with node coordinates `x_a`, the tangents are `x_,xi = sum_a dN_a/dxi x_a` and
//! `x_,eta = sum_a dN_a/deta x_a`; the surface element is `dA = |x_,xi x x_,eta| dxi deta`, and the
//! outward normal (faces are ordered counter-clockwise seen from outside) is
//! `normalize(x_,xi x x_,eta)`.
//!
//! # Generic face kernels
//!
//! The face shape functions and the face geometry are written once, generically over the scalar
//! ([`Scalar`]: `f64` or a forward-mode dual number of `num_dual`): [`FaceType::shape_at`],
//! [`FaceType::shape_grad_at`], [`FaceType::shape_and_grad_at`], [`face_point_at`],
//! [`face_tangents_at`], [`face_normal_at`]. With dual parent coordinates the values carry their
//! `xi`-derivatives (and the gradients the second derivatives); with dual node coordinates the
//! geometry carries its derivatives with respect to the nodes. The `f64` functions
//! ([`FaceType::shape`], [`face_normal`], ...) are these instantiated at `f64`, plain float
//! code. The mortar linearization ([`crate::contact::mortar::linearize`]) is their user in dual numbers.

use super::element::{ElementType, FaceType, HEX_NODES, QUAD_NODES};

pub use crate::vec3::Scalar;

/// Edges of the triangle, in the order of the Tri6 mid-edge nodes 3..5.
const TRI_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];

/// Largest number of nodes of a face (Quad9).
const MAX_FACE_NODES: usize = 9;

/// The three families of shape functions on `[-1, 1]^d`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TensorFamily {
    Linear,
    Serendipity,
    Lagrange,
}

/// The 1D linear factor `(1 + s t) / 2` of the node at `s = +-1` and its derivative.
#[inline]
fn linear_1d<T: Scalar>(s: f64, t: T) -> (T, T) {
    ((t * s + 1.0) * 0.5, T::from(0.5 * s))
}

/// The 1D quadratic Lagrange factor of the node at `s` in `{-1, 0, 1}` and its derivative.
#[inline]
fn quadratic_1d<T: Scalar>(s: f64, t: T) -> (T, T) {
    if s < -0.5 {
        (t * 0.5 * (t - 1.0), t - 0.5)
    } else if s > 0.5 {
        (t * 0.5 * (t + 1.0), t + 0.5)
    } else {
        (T::from(1.0) - t * t, t * -2.0)
    }
}

/// Product of the entries of `v`, leaving out entry `skip` (no entry is left out if
/// `skip >= D`).
#[inline]
fn product_except<T: Scalar, const D: usize>(v: &[T; D], skip: usize) -> T {
    v.iter()
        .enumerate()
        .filter(|&(i, _)| i != skip)
        .map(|(_, x)| *x)
        .product()
}

/// Value and gradient of `prod_i f_i(x_i)` given the factors `f_i` and their derivatives `df_i`.
#[inline]
fn tensor_product<T: Scalar, const D: usize>(f: [T; D], df: [T; D]) -> (T, [T; D]) {
    let value = product_except(&f, D);
    let grad = std::array::from_fn(|j| df[j] * product_except(&f, j));
    (value, grad)
}

/// Value and gradient of a serendipity shape function of the node at `s`.
#[inline]
fn serendipity_node<T: Scalar, const D: usize>(x: [T; D], s: [f64; D]) -> (T, [T; D]) {
    match s.iter().position(|&si| si == 0.0) {
        None => serendipity_corner(x, s),
        Some(m) => serendipity_mid_edge(x, s, m),
    }
}

/// Serendipity corner function `2^-d (prod p_i) (sum s_i x_i - (d - 1))`.
#[inline]
fn serendipity_corner<T: Scalar, const D: usize>(x: [T; D], s: [f64; D]) -> (T, [T; D]) {
    let d = D as f64;
    let scale = 0.5f64.powi(D as i32);
    let p: [T; D] = std::array::from_fn(|i| x[i] * s[i] + 1.0);
    let sx: T = (0..D).map(|i| x[i] * s[i]).sum();
    let value = product_except(&p, D) * scale * (sx - (d - 1.0));
    let grad = std::array::from_fn(|j| {
        product_except(&p, j) * (scale * s[j]) * (sx + x[j] * s[j] + 2.0 - d)
    });
    (value, grad)
}

/// Serendipity mid-edge function `2^(1-d) (1 - x_m^2) prod_{i != m} p_i` of the node with
/// `s_m = 0`.
#[inline]
fn serendipity_mid_edge<T: Scalar, const D: usize>(
    x: [T; D],
    s: [f64; D],
    m: usize,
) -> (T, [T; D]) {
    let f: [T; D] = std::array::from_fn(|i| {
        if i == m {
            T::from(1.0) - x[i] * x[i]
        } else {
            (x[i] * s[i] + 1.0) * 0.5
        }
    });
    let df: [T; D] = std::array::from_fn(|i| {
        if i == m {
            x[i] * -2.0
        } else {
            T::from(0.5 * s[i])
        }
    });
    tensor_product(f, df)
}

/// Value and gradient of the shape function of the node at `s` of a hexahedron or quadrilateral.
#[inline]
fn tensor_node<T: Scalar, const D: usize>(
    family: TensorFamily,
    x: [T; D],
    s: [f64; D],
) -> (T, [T; D]) {
    let factors = |one_d: fn(f64, T) -> (T, T)| {
        let fd: [(T, T); D] = std::array::from_fn(|i| one_d(s[i], x[i]));
        tensor_product(fd.map(|v| v.0), fd.map(|v| v.1))
    };
    match family {
        TensorFamily::Linear => factors(linear_1d),
        TensorFamily::Lagrange => factors(quadratic_1d),
        TensorFamily::Serendipity => serendipity_node(x, s),
    }
}

/// Barycentric coordinate `L_k` of the `D`-simplex and its (constant) gradient.
#[inline]
fn barycentric<T: Scalar, const D: usize>(x: [T; D], k: usize) -> (T, [T; D]) {
    if k == 0 {
        (
            T::from(1.0) - x.iter().copied().sum::<T>(),
            [T::from(-1.0); D],
        )
    } else {
        (
            x[k - 1],
            std::array::from_fn(|j| T::from(if j == k - 1 { 1.0 } else { 0.0 })),
        )
    }
}

/// Value and gradient of shape function `a` of a linear (`edges` empty) or quadratic simplex whose
/// mid-edge node `D + 1 + k` sits on `edges[k]`.
#[inline]
fn simplex_node<T: Scalar, const D: usize>(
    x: [T; D],
    a: usize,
    edges: &[[usize; 2]],
) -> (T, [T; D]) {
    let corners = D + 1;
    if edges.is_empty() {
        return barycentric(x, a);
    }
    if a < corners {
        let (l, dl) = barycentric(x, a);
        (l * (l * 2.0 - 1.0), dl.map(|g| (l * 4.0 - 1.0) * g))
    } else {
        let [i, j] = edges[a - corners];
        let (li, dli) = barycentric(x, i);
        let (lj, dlj) = barycentric(x, j);
        let grad = std::array::from_fn(|k| (lj * dli[k] + li * dlj[k]) * 4.0);
        (li * 4.0 * lj, grad)
    }
}

impl ElementType {
    /// Value and parametric gradient of shape function `a` at `xi`.
    fn shape_node(self, xi: [f64; 3], a: usize) -> (f64, [f64; 3]) {
        match self {
            ElementType::Hex8 => tensor_node(TensorFamily::Linear, xi, HEX_NODES[a]),
            ElementType::Hex20 => tensor_node(TensorFamily::Serendipity, xi, HEX_NODES[a]),
            ElementType::Hex27 => tensor_node(TensorFamily::Lagrange, xi, HEX_NODES[a]),
            ElementType::Tet4 => simplex_node(xi, a, &[]),
            ElementType::Tet10 => simplex_node(xi, a, ElementType::Tet10.edges()),
        }
    }

    /// Shape function values at parametric point xi; n.len() == num_nodes().
    ///
    /// # Panics
    /// If `n.len() != self.num_nodes()`.
    pub fn shape(self, xi: [f64; 3], n: &mut [f64]) {
        assert_eq!(n.len(), self.num_nodes(), "shape: wrong buffer length");
        for (a, na) in n.iter_mut().enumerate() {
            *na = self.shape_node(xi, a).0;
        }
    }

    /// Parametric gradients dN_a/dxi_j; dn.len() == num_nodes().
    ///
    /// # Panics
    /// If `dn.len() != self.num_nodes()`.
    pub fn shape_grad(self, xi: [f64; 3], dn: &mut [[f64; 3]]) {
        assert_eq!(
            dn.len(),
            self.num_nodes(),
            "shape_grad: wrong buffer length"
        );
        for (a, ga) in dn.iter_mut().enumerate() {
            *ga = self.shape_node(xi, a).1;
        }
    }
}

/// Calls `f(a, N_a, grad N_a)` for every node `a` of a face of type `ft` at `xi`. On the tensor
/// faces (Quad4, Quad9) the 1D factors of each axis are evaluated once for the three node
/// positions `-1, 0, 1` rather than once per node: the same floating-point operations as
/// [`FaceType::shape_node_at`] for each node.
#[inline]
fn for_face_nodes<T: Scalar>(ft: FaceType, xi: [T; 2], mut f: impl FnMut(usize, (T, [T; 2]))) {
    match ft {
        FaceType::Quad4 => for_tensor_nodes(ft, xi, linear_1d, f),
        FaceType::Quad9 => for_tensor_nodes(ft, xi, quadratic_1d, f),
        _ => {
            for a in 0..ft.num_nodes() {
                f(a, ft.shape_node_at(xi, a));
            }
        }
    }
}

/// [`for_face_nodes`] on a tensor face whose 1D factor is `one_d`.
#[inline]
fn for_tensor_nodes<T: Scalar>(
    ft: FaceType,
    xi: [T; 2],
    one_d: impl Fn(f64, T) -> (T, T),
    mut f: impl FnMut(usize, (T, [T; 2])),
) {
    let factors: [[(T, T); 3]; 2] =
        std::array::from_fn(|i| std::array::from_fn(|k| one_d(k as f64 - 1.0, xi[i])));
    for (a, s) in QUAD_NODES[..ft.num_nodes()].iter().enumerate() {
        let fd: [(T, T); 2] = std::array::from_fn(|i| factors[i][(s[i] + 1.0) as usize]);
        f(a, tensor_product(fd.map(|v| v.0), fd.map(|v| v.1)));
    }
}

/// The derivatives of the 1D factor of the node at `s` (`linear_1d` or `quadratic_1d`) at `t`
/// as forward-mode dual numbers compute them when `t` is a dual seeded with derivative 1:
/// `(d value / dt, d (its derivative) / dt)`. The first equals the derivative `quadratic_1d`
/// returns up to round-off only: the duals differentiate `t (t -+ 1) / 2` by the product rule,
/// `(t -+ 1) / 2 + t / 2`, rounded twice.
fn one_d_dual_slopes(ft: FaceType, s: f64, t: f64) -> (f64, f64) {
    match ft {
        FaceType::Quad9 if s < -0.5 => (0.5 * (t - 1.0) + t * 0.5, 1.0),
        FaceType::Quad9 if s > 0.5 => (0.5 * (t + 1.0) + t * 0.5, 1.0),
        FaceType::Quad9 => (-(t + t), -2.0),
        _ => (0.5 * s, 0.0),
    }
}

/// The shape function of a tensor face (Quad4, Quad9) at a point with its derivatives, in
/// floats, each rounded as the generic kernels compute it in forward-mode dual numbers seeded on
/// `xi` (see [`FaceType::tensor_shape_derivatives`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct TensorShape {
    /// `N_a`.
    pub value: f64,
    /// `dN_a/dxi_j`: the derivative part of the dual value of [`FaceType::shape_at`].
    pub value_derivative: [f64; 2],
    /// `N_a,i`: the gradient of [`FaceType::shape_grad_at`].
    pub gradient: [f64; 2],
    /// `d(N_a,i)/dxi_j` at `[i][j]`: the derivative part of the dual gradient.
    pub gradient_derivative: [[f64; 2]; 2],
}

impl FaceType {
    /// The shape functions of a Quad4 or Quad9 face at `xi` with their first and second
    /// derivatives ([`TensorShape`], from the 1D factors of `for_face_nodes`), into the first
    /// `num_nodes()` entries of `out`; `false` (nothing written) for the other faces.
    ///
    /// Every number is the one a dual-number evaluation of the generic kernels at `xi` seeded
    /// on its two slots gives ([`FaceType::shape_and_grad_at`] with `DualSVec64<2>`), bit for
    /// bit: the values and gradients by the same float operations, their derivatives by the
    /// product rule in the duals' order (`d(f_0 f_1) = f_0' f_1 + f_1' f_0` of the 1D factors
    /// `f`, with the factors' derivatives as the duals round them). So float code built on it
    /// reproduces a dual code exactly, which matters where derivatives are ill-conditioned.
    ///
    /// # Panics
    /// If `out` is shorter than `num_nodes()`.
    pub fn tensor_shape_derivatives(self, xi: [f64; 2], out: &mut [TensorShape]) -> bool {
        let one_d = match self {
            FaceType::Quad4 => linear_1d::<f64>,
            FaceType::Quad9 => quadratic_1d::<f64>,
            _ => return false,
        };
        // factors[axis][node position -1, 0, 1]: (f, f', f' as the duals round it, f'').
        let factors: [[(f64, f64, f64, f64); 3]; 2] = std::array::from_fn(|i| {
            std::array::from_fn(|k| {
                let s = k as f64 - 1.0;
                let (f, d) = one_d(s, xi[i]);
                let (dv, h) = one_d_dual_slopes(self, s, xi[i]);
                (f, d, dv, h)
            })
        });
        for (a, s) in QUAD_NODES[..self.num_nodes()].iter().enumerate() {
            let [(f0, d0, v0, h0), (f1, d1, v1, h1)] =
                std::array::from_fn(|i| factors[i][(s[i] + 1.0) as usize]);
            out[a] = TensorShape {
                // (The generic kernels multiply from 1.0, which is exact.)
                value: f0 * f1,
                value_derivative: [v0 * f1, v1 * f0],
                gradient: [d0 * f1, d1 * f0],
                gradient_derivative: [[h0 * f1, v1 * d0], [v0 * d1, h1 * f0]],
            };
        }
        true
    }

    /// Value and parametric gradient of shape function `a` at `xi`, for any [`Scalar`].
    #[inline]
    fn shape_node_at<T: Scalar>(self, xi: [T; 2], a: usize) -> (T, [T; 2]) {
        match self {
            FaceType::Quad4 => tensor_node(TensorFamily::Linear, xi, QUAD_NODES[a]),
            FaceType::Quad8 => tensor_node(TensorFamily::Serendipity, xi, QUAD_NODES[a]),
            FaceType::Quad9 => tensor_node(TensorFamily::Lagrange, xi, QUAD_NODES[a]),
            FaceType::Tri3 => simplex_node(xi, a, &[]),
            FaceType::Tri6 => simplex_node(xi, a, &TRI_EDGES),
        }
    }

    /// Shape function values at parametric point xi; n.len() == num_nodes().
    ///
    /// # Panics
    /// If `n.len() != self.num_nodes()`.
    pub fn shape(self, xi: [f64; 2], n: &mut [f64]) {
        self.shape_at(xi, n);
    }

    /// Parametric gradients dN_a/dxi_j; dn.len() == num_nodes().
    ///
    /// # Panics
    /// If `dn.len() != self.num_nodes()`.
    pub fn shape_grad(self, xi: [f64; 2], dn: &mut [[f64; 2]]) {
        self.shape_grad_at(xi, dn);
    }

    /// [`FaceType::shape`] for any [`Scalar`]: with a dual `xi`, the values carry their
    /// derivatives along `xi`'s.
    ///
    /// # Panics
    /// If `n.len() != self.num_nodes()`.
    pub fn shape_at<T: Scalar>(self, xi: [T; 2], n: &mut [T]) {
        assert_eq!(n.len(), self.num_nodes(), "shape: wrong buffer length");
        for_face_nodes(self, xi, |a, (v, _)| n[a] = v);
    }

    /// Values and gradients at once, for any [`Scalar`] ([`FaceType::shape_at`] and
    /// [`FaceType::shape_grad_at`] in one pass).
    ///
    /// # Panics
    /// If `n.len()` or `dn.len()` differs from `self.num_nodes()`.
    pub fn shape_and_grad_at<T: Scalar>(self, xi: [T; 2], n: &mut [T], dn: &mut [[T; 2]]) {
        assert_eq!(n.len(), self.num_nodes(), "shape: wrong buffer length");
        assert_eq!(dn.len(), self.num_nodes(), "shape: wrong buffer length");
        for_face_nodes(self, xi, |a, (v, g)| (n[a], dn[a]) = (v, g));
    }

    /// [`FaceType::shape_grad`] for any [`Scalar`] (with a dual `xi`, the gradients carry the
    /// second derivatives of the shape functions along `xi`'s derivatives).
    ///
    /// # Panics
    /// If `dn.len() != self.num_nodes()`.
    pub fn shape_grad_at<T: Scalar>(self, xi: [T; 2], dn: &mut [[T; 2]]) {
        assert_eq!(
            dn.len(),
            self.num_nodes(),
            "shape_grad: wrong buffer length"
        );
        for_face_nodes(self, xi, |a, (_, g)| dn[a] = g);
    }
}

/// Position `x(xi) = sum_a N_a(xi) x_a` on a face, for any [`Scalar`] (dual node coordinates
/// and/or a dual `xi`).
///
/// # Panics
/// If `x.len() != ft.num_nodes()`.
pub fn face_point_at<T: Scalar>(ft: FaceType, x: &[[T; 3]], xi: [T; 2]) -> [T; 3] {
    let nn = ft.num_nodes();
    assert_eq!(x.len(), nn, "face_point: wrong number of node coordinates");
    let mut n = [T::from(0.0); MAX_FACE_NODES];
    ft.shape_at(xi, &mut n[..nn]);
    let mut p = [T::from(0.0); 3];
    for (xa, na) in x.iter().zip(&n[..nn]) {
        for d in 0..3 {
            p[d] += *na * xa[d];
        }
    }
    p
}

/// Tangent vectors (x_,xi, x_,eta) of a face at xi.
///
/// `x` holds the face node coordinates in the face's node order.
///
/// # Panics
/// If `x.len() != ft.num_nodes()`.
pub fn face_tangents(ft: FaceType, x: &[[f64; 3]], xi: [f64; 2]) -> ([f64; 3], [f64; 3]) {
    face_tangents_at(ft, x, xi)
}

/// [`face_tangents`] for any [`Scalar`] (dual node coordinates and/or a dual `xi`).
///
/// # Panics
/// If `x.len() != ft.num_nodes()`.
pub fn face_tangents_at<T: Scalar>(ft: FaceType, x: &[[T; 3]], xi: [T; 2]) -> ([T; 3], [T; 3]) {
    let nn = ft.num_nodes();
    assert_eq!(
        x.len(),
        nn,
        "face_tangents: wrong number of node coordinates"
    );
    let mut dn = [[T::from(0.0); 2]; MAX_FACE_NODES];
    ft.shape_grad_at(xi, &mut dn[..nn]);
    tangents_from_grad(x, &dn[..nn])
}

/// The tangent vectors `x_,xi = sum_a N_a,xi x_a`, `x_,eta` from the shape-function gradients
/// `dn` at a point (what [`face_tangents_at`] computes after evaluating them).
pub fn tangents_from_grad<T: Scalar>(x: &[[T; 3]], dn: &[[T; 2]]) -> ([T; 3], [T; 3]) {
    let mut t = [[T::from(0.0); 3]; 2];
    for (xa, ga) in x.iter().zip(dn) {
        for (tk, gk) in t.iter_mut().zip(ga) {
            for d in 0..3 {
                tk[d] += *gk * xa[d];
            }
        }
    }
    (t[0], t[1])
}

/// Surface geometry of a face at parametric point xi given the face node coordinates (in the face's
/// node order): returns (unit outward normal, surface Jacobian |x_,xi x x_,eta|) where the normal is
/// normalize(x_,xi x x_,eta). For triangles the Jacobian is relative to the unit triangle (area 1/2).
///
/// A degenerate face (zero Jacobian) gives the zero vector as normal and a zero Jacobian.
///
/// # Panics
/// If `x.len() != ft.num_nodes()`.
pub fn face_normal(ft: FaceType, x: &[[f64; 3]], xi: [f64; 2]) -> ([f64; 3], f64) {
    face_normal_at(ft, x, xi)
}

/// [`face_normal`] for any [`Scalar`]; a degenerate face (zero Jacobian in the real part) gives
/// zeros with no derivative.
///
/// # Panics
/// If `x.len() != ft.num_nodes()`.
pub fn face_normal_at<T: Scalar>(ft: FaceType, x: &[[T; 3]], xi: [T; 2]) -> ([T; 3], T) {
    let (t1, t2) = face_tangents_at(ft, x, xi);
    normal_from_tangents(t1, t2)
}

/// The unit normal and surface Jacobian of [`face_normal_at`] from the tangent vectors.
pub fn normal_from_tangents<T: Scalar>(t1: [T; 3], t2: [T; 3]) -> ([T; 3], T) {
    let c = crate::vec3::cross(t1, t2);
    let jac = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    if jac.re() > 0.0 {
        (c.map(|v| v / jac), jac)
    } else {
        ([T::from(0.0); 3], T::from(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_rng::Rng;

    const NUM_POINTS: usize = 50;

    /// An element type (`D = 3`) or a face type (`D = 2`), as these tests see it: its nodes and
    /// its shape functions on the parent domain.
    trait Parent<const D: usize>: Copy + std::fmt::Debug {
        /// True for the tensor domain `[-1, 1]^D`, false for the unit simplex.
        fn is_cube(self) -> bool;
        fn nodes(self) -> Vec<[f64; D]>;
        /// `(N_a, dN_a/dxi)` of every node at `xi`.
        fn eval(self, xi: [f64; D]) -> (Vec<f64>, Vec<[f64; D]>);
    }

    /// `Parent<$d>` for `$t`, whose tensor types answer `$cube`.
    macro_rules! parent {
        ($t:ty, $d:literal, $cube:ident) => {
            impl Parent<$d> for $t {
                fn is_cube(self) -> bool {
                    self.$cube()
                }
                fn nodes(self) -> Vec<[f64; $d]> {
                    self.node_coords()
                }
                fn eval(self, xi: [f64; $d]) -> (Vec<f64>, Vec<[f64; $d]>) {
                    let mut n = vec![0.0; self.num_nodes()];
                    let mut dn = vec![[0.0; $d]; self.num_nodes()];
                    self.shape(xi, &mut n);
                    self.shape_grad(xi, &mut dn);
                    (n, dn)
                }
            }
        };
    }
    parent!(ElementType, 3, is_hex);
    parent!(FaceType, 2, is_quad);

    /// `NUM_POINTS` random points of the parent domain.
    fn points<const D: usize>(p: impl Parent<D>, rng: &mut Rng) -> Vec<[f64; D]> {
        (0..NUM_POINTS).map(|_| rng.point(p.is_cube())).collect()
    }

    /// The values sum to 1 and the gradients to 0 at random points.
    fn assert_partition_of_unity<const D: usize>(p: impl Parent<D>, rng: &mut Rng) {
        for xi in points(p, rng) {
            let (n, dn) = p.eval(xi);
            assert!(
                (n.iter().sum::<f64>() - 1.0).abs() < 1e-14,
                "{p:?} at {xi:?}"
            );
            for j in 0..D {
                let s: f64 = dn.iter().map(|g| g[j]).sum();
                assert!(s.abs() < 1e-14, "{p:?} grad {j} at {xi:?}: {s}");
            }
        }
    }

    #[test]
    fn partition_of_unity_and_zero_gradient_sum() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for et in ElementType::ALL {
            assert_partition_of_unity(et, &mut rng);
        }
        for ft in FaceType::ALL {
            assert_partition_of_unity(ft, &mut rng);
        }
    }

    /// `N_a(x_b) = delta_ab`.
    fn assert_kronecker<const D: usize>(p: impl Parent<D>) {
        for (b, xb) in p.nodes().into_iter().enumerate() {
            let (n, _) = p.eval(xb);
            for (a, na) in n.iter().enumerate() {
                let expected = if a == b { 1.0 } else { 0.0 };
                assert!((na - expected).abs() < 1e-15, "{p:?} N_{a}(x_{b}) = {na}");
            }
        }
    }

    #[test]
    fn kronecker_property_at_nodes() {
        ElementType::ALL.into_iter().for_each(assert_kronecker);
        FaceType::ALL.into_iter().for_each(assert_kronecker);
    }

    const FD_STEP: f64 = 1e-6;
    const FD_TOL: f64 = 1e-8;

    /// The gradients agree with central differences of the values at random points.
    fn assert_gradients_match_central_differences<const D: usize>(
        p: impl Parent<D>,
        rng: &mut Rng,
    ) {
        for xi in points(p, rng) {
            let (n, dn) = p.eval(xi);
            for j in 0..D {
                let (mut xp, mut xm) = (xi, xi);
                xp[j] += FD_STEP;
                xm[j] -= FD_STEP;
                let (np, nm) = (p.eval(xp).0, p.eval(xm).0);
                for a in 0..n.len() {
                    let fd = (np[a] - nm[a]) / (2.0 * FD_STEP);
                    assert!((fd - dn[a][j]).abs() < FD_TOL, "{p:?} dN_{a}/dxi_{j}");
                }
            }
        }
    }

    #[test]
    fn element_gradients_match_central_differences() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for et in ElementType::ALL {
            assert_gradients_match_central_differences(et, &mut rng);
        }
    }

    #[test]
    fn face_gradients_match_central_differences() {
        let mut rng = Rng(0xdead_beef_cafe_f00d);
        for ft in FaceType::ALL {
            assert_gradients_match_central_differences(ft, &mut rng);
        }
    }

    /// Exponents of a monomial `x^e0 y^e1 z^e2`.
    type Monomial = [i32; 3];

    fn monomial(e: Monomial, x: &[f64]) -> f64 {
        (0..x.len()).map(|i| x[i].powi(e[i])).product()
    }

    fn monomial_grad(e: Monomial, x: &[f64], j: usize) -> f64 {
        if e[j] == 0 {
            return 0.0;
        }
        let mut ed = e;
        ed[j] -= 1;
        f64::from(e[j]) * monomial(ed, x)
    }

    /// Monomials with exponents `<= max` in `dim` variables accepted by `keep`.
    fn monomials(dim: usize, max: i32, keep: impl Fn(Monomial) -> bool) -> Vec<Monomial> {
        let top = |i: usize| if i < dim { max } else { 0 };
        let mut out = Vec::new();
        for a in 0..=top(0) {
            for b in 0..=top(1) {
                for c in 0..=top(2) {
                    if keep([a, b, c]) {
                        out.push([a, b, c]);
                    }
                }
            }
        }
        out
    }

    /// Number of exponents equal to 2 (serendipity spaces allow at most one).
    fn squares(e: Monomial) -> usize {
        e.iter().filter(|&&k| k == 2).count()
    }

    /// The polynomial space of an element (`dim = 3`) or face (`dim = 2`) by family.
    fn space(
        dim: usize,
        linear_tensor: bool,
        order: usize,
        serendipity: bool,
        simplex: bool,
    ) -> Vec<Monomial> {
        if simplex {
            monomials(dim, order as i32, |e| e.iter().sum::<i32>() <= order as i32)
        } else if linear_tensor {
            monomials(dim, 1, |_| true)
        } else if serendipity {
            monomials(dim, 2, |e| squares(e) <= 1)
        } else {
            monomials(dim, 2, |_| true)
        }
    }

    fn element_space(et: ElementType) -> Vec<Monomial> {
        let space = space(
            3,
            et == ElementType::Hex8,
            et.order(),
            et == ElementType::Hex20,
            !et.is_hex(),
        );
        let expected = [8, 20, 27, 4, 10][ElementType::ALL.iter().position(|&t| t == et).unwrap()];
        assert_eq!(space.len(), expected, "{et:?}");
        space
    }

    fn face_space(ft: FaceType) -> Vec<Monomial> {
        let order = if matches!(ft, FaceType::Quad4 | FaceType::Tri3) {
            1
        } else {
            2
        };
        let space = space(
            2,
            ft == FaceType::Quad4,
            order,
            ft == FaceType::Quad8,
            !ft.is_quad(),
        );
        assert_eq!(space.len(), ft.num_nodes(), "{ft:?}");
        space
    }

    /// A monomial just outside each element's space.
    fn element_outsider(et: ElementType) -> Monomial {
        match et {
            ElementType::Hex8 | ElementType::Tet4 => [2, 0, 0],
            ElementType::Hex20 => [2, 2, 0],
            ElementType::Hex27 | ElementType::Tet10 => [3, 0, 0],
        }
    }

    fn face_outsider(ft: FaceType) -> Monomial {
        match ft {
            FaceType::Quad4 | FaceType::Tri3 => [2, 0, 0],
            FaceType::Quad8 => [2, 2, 0],
            FaceType::Quad9 | FaceType::Tri6 => [0, 3, 0],
        }
    }

    /// Largest error of interpolating monomial `e` (value and gradient) over the points.
    fn interpolation_error<const D: usize>(
        p: impl Parent<D>,
        e: Monomial,
        pts: &[[f64; D]],
    ) -> f64 {
        let nodal: Vec<f64> = p.nodes().iter().map(|x| monomial(e, x)).collect();
        let mut err: f64 = 0.0;
        for xi in pts {
            let (n, dn) = p.eval(*xi);
            let u: f64 = n.iter().zip(&nodal).map(|(na, ua)| na * ua).sum();
            err = err.max((u - monomial(e, xi)).abs());
            for j in 0..D {
                let du: f64 = dn.iter().zip(&nodal).map(|(g, ua)| g[j] * ua).sum();
                err = err.max((du - monomial_grad(e, xi, j)).abs());
            }
        }
        err
    }

    /// Every monomial of `space` is interpolated exactly (values and gradients) at random
    /// points, and the monomial `outsider` is not.
    fn assert_reproduces<const D: usize>(
        p: impl Parent<D>,
        space: Vec<Monomial>,
        outsider: Monomial,
        rng: &mut Rng,
    ) {
        let pts = points(p, rng);
        for e in space {
            let err = interpolation_error(p, e, &pts);
            assert!(err < 1e-13, "{p:?} monomial {e:?}: error {err}");
        }
        let err = interpolation_error(p, outsider, &pts);
        assert!(err > 1e-3, "{p:?} reproduces {outsider:?}?");
    }

    /// Every monomial of the element's space is interpolated exactly (values and gradients), and
    /// a monomial outside it is not.
    #[test]
    fn elements_reproduce_their_polynomial_space() {
        let mut rng = Rng(0x0bad_cafe_1234_5679);
        for et in ElementType::ALL {
            assert_reproduces(et, element_space(et), element_outsider(et), &mut rng);
        }
    }

    #[test]
    fn faces_reproduce_their_polynomial_space() {
        let mut rng = Rng(0x5555_aaaa_3333_cccd);
        for ft in FaceType::ALL {
            assert_reproduces(ft, face_space(ft), face_outsider(ft), &mut rng);
        }
    }

    fn assert_vec_close(a: [f64; 3], b: [f64; 3], tol: f64, what: &str) {
        for d in 0..3 {
            assert!((a[d] - b[d]).abs() < tol, "{what}: {a:?} != {b:?}");
        }
    }

    /// Area of a face by the face's default quadrature rule.
    fn face_area(ft: FaceType, x: &[[f64; 3]]) -> f64 {
        let rule = ft.quadrature(ft.default_quadrature_degree());
        rule.points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * face_normal(ft, x, *p).1)
            .sum()
    }

    /// Maps parametric face nodes onto a plane through `origin` spanned by the orthonormal `e1`,
    /// `e2`, with in-plane coordinates given by `planar` (an affine or bilinear map of the
    /// parametric coordinates that keeps mid-edge nodes on straight edges).
    fn planar_face(
        ft: FaceType,
        origin: [f64; 3],
        e1: [f64; 3],
        e2: [f64; 3],
        corners: &[[f64; 2]],
    ) -> Vec<[f64; 3]> {
        let nc = ft.num_corners();
        ft.node_coords()
            .iter()
            .map(|xi| {
                // In-plane position: interpolate the corners with the linear (Tri3/Quad4) functions.
                let lin = if ft.is_quad() {
                    FaceType::Quad4
                } else {
                    FaceType::Tri3
                };
                let mut n = vec![0.0; nc];
                lin.shape(*xi, &mut n);
                let (u, v) = (0..nc).fold((0.0, 0.0), |(u, v), a| {
                    (u + n[a] * corners[a][0], v + n[a] * corners[a][1])
                });
                std::array::from_fn(|d| origin[d] + u * e1[d] + v * e2[d])
            })
            .collect()
    }

    /// Planar faces in a tilted plane: the normal is the plane normal everywhere and the area is
    /// the polygon area (shoelace).
    #[test]
    fn planar_face_normal_and_area() {
        let s = 1.0 / 3f64.sqrt();
        let e1 = [1.0 / 2f64.sqrt(), -1.0 / 2f64.sqrt(), 0.0];
        let e2 = [1.0 / 6f64.sqrt(), 1.0 / 6f64.sqrt(), -2.0 / 6f64.sqrt()];
        let normal = crate::vec3::cross(e1, e2);
        assert_vec_close(normal, [s, s, s], 1e-15, "plane basis");
        let origin = [0.3, -1.2, 2.5];
        let quad = [[0.0, 0.0], [2.0, 0.1], [2.5, 1.7], [-0.4, 1.2]];
        let tri = [[0.1, 0.2], [2.0, -0.3], [0.7, 1.9]];
        let shoelace = |c: &[[f64; 2]]| {
            0.5 * (0..c.len())
                .map(|k| {
                    let (a, b) = (c[k], c[(k + 1) % c.len()]);
                    a[0] * b[1] - b[0] * a[1]
                })
                .sum::<f64>()
        };
        let mut rng = Rng(0x7777_1111_2222_3333);
        for ft in FaceType::ALL {
            let corners: &[[f64; 2]] = if ft.is_quad() { &quad } else { &tri };
            let x = planar_face(ft, origin, e1, e2, corners);
            for xi in points(ft, &mut rng) {
                let (n, jac) = face_normal(ft, &x, xi);
                assert_vec_close(n, normal, 1e-14, ft.name());
                assert!(jac > 0.0);
            }
            let area = face_area(ft, &x);
            let exact = shoelace(corners);
            assert!(
                (area - exact).abs() < 1e-13 * exact,
                "{ft:?}: area {area} != {exact}"
            );
        }
    }

    /// On the faces of the parent hexahedron (face order `xi = -1, +1, eta = -1, +1, zeta = -1,
    /// +1`) and parent tetrahedron the normals point outward along the right axis and the areas are
    /// exact.
    #[test]
    fn parent_element_faces_have_outward_normals() {
        let s = 1.0 / 3f64.sqrt();
        // The parent cube's face centres (Hex27 nodes 20..25) are its outward unit normals.
        let hex_normals = &HEX_NODES[20..26];
        let tet_normals = [
            [0.0, 0.0, -1.0],
            [0.0, -1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [s, s, s],
        ];
        let tet_areas = [0.5, 0.5, 0.5, 0.5 * 3f64.sqrt()];
        let mut rng = Rng(0x4242_4242_4242_4243);
        for et in ElementType::ALL {
            let xe = et.node_coords();
            let ft = et.face_type();
            for f in 0..et.num_faces() {
                let x: Vec<[f64; 3]> = et.face_nodes(f).iter().map(|&a| xe[a]).collect();
                let (expected, exact_area) = if et.is_hex() {
                    (hex_normals[f], 4.0)
                } else {
                    (tet_normals[f], tet_areas[f])
                };
                for xi in points(ft, &mut rng) {
                    let (n, _) = face_normal(ft, &x, xi);
                    assert_vec_close(n, expected, 1e-14, &format!("{et:?} face {f}"));
                }
                let area = face_area(ft, &x);
                assert!(
                    (area - exact_area).abs() < 1e-13,
                    "{et:?} face {f}: area {area}"
                );
            }
        }
    }

    #[test]
    fn degenerate_face_gives_zero_normal() {
        let x = [[1.0, 2.0, 3.0]; 3];
        assert_eq!(face_normal(FaceType::Tri3, &x, [0.2, 0.3]), ([0.0; 3], 0.0));
    }
}
