//! Quadrature rules on the parent domains of [`super::element`].
//!
//! Every rule has positive weights summing to the measure of its parent domain (8 for the hexahedron
//! `[-1, 1]^3`, 1/6 for the unit tetrahedron, 4 for the square `[-1, 1]^2`, 1/2 for the unit
//! triangle), and `quadrature(degree)` integrates every polynomial of total degree `<= degree` exactly.
//!
//! # Gauss-Legendre on `[-1, 1]`
//!
//! The `n` points are the roots of the Legendre polynomial `P_n`, found by Newton's method started
//! from `cos(pi (i + 3/4) / (n + 1/2))`. `P_n` and `P_{n-1}` come from the three-term recurrence
//! `(k + 1) P_{k+1}(x) = (2k + 1) x P_k(x) - k P_{k-1}(x)`, the derivative from
//! `P_n'(x) = n (x P_n(x) - P_{n-1}(x)) / (x^2 - 1)`, and the weights are
//! `w_i = 2 / ((1 - x_i^2) P_n'(x_i)^2)`. The rule is exact for degree `2n - 1`.
//!
//! # Hexahedra and quadrilaterals
//!
//! Tensor products of Gauss-Legendre rules with `ceil((degree + 1) / 2)` points per direction:
//! a monomial of total degree `<= degree` has degree `<= degree <= 2n - 1` in each variable.
//!
//! # Tetrahedra and triangles
//!
//! Low degrees use symmetric rules: the centroid (degree 1) and the 4-point rule (tetrahedron, points
//! `(a, a, a)` and permutations of `(b, a, a)` with `a = (5 - sqrt 5) / 20`, `b = 1 - 3a`, weights
//! 1/24) or 3-point rule (triangle, points `(1/6, 1/6)`, `(2/3, 1/6)`, `(1/6, 2/3)`, weights 1/6) of
//! degree 2.
//!
//! Higher degrees use the collapsed (Duffy / Stroud conical product) construction: the unit cube
//! `(u, v, w)` in `[0, 1]^3` is mapped onto the tetrahedron by
//!
//! ```text
//! xi = u,   eta = (1 - u) v,   zeta = (1 - u) (1 - v) w,   d(xi, eta, zeta) = (1 - u)^2 (1 - v) du dv dw.
//! ```
//!
//! A monomial `xi^a eta^b zeta^c` times the Jacobian becomes
//! `u^a (1 - u)^(b + c + 2) v^b (1 - v)^(c + 1) w^c`, of degree `<= degree + 2` in `u`,
//! `<= degree + 1` in `v` and `<= degree` in `w`, so Gauss-Legendre rules (mapped to `[0, 1]`) with
//! `ceil((degree + 3) / 2)`, `ceil((degree + 2) / 2)` and `ceil((degree + 1) / 2)` points integrate
//! it exactly. The weights are products of positive Gauss weights and the Jacobian, positive at the
//! interior Gauss points. The triangle is the 2D analogue: `xi = u`, `eta = (1 - u) v`,
//! `d(xi, eta) = (1 - u) du dv`, with `ceil((degree + 2) / 2)` and `ceil((degree + 1) / 2)` points.
//!
//! Triangles of degree 3 to 8 (the mortar pallets' range) use Dunavant's symmetric rules
//! instead, with positive weights and interior points (`tri_dunavant_rule`): 6, 6, 7, 12, 16 and
//! 16 points where the collapsed rule takes 6, 9, 12, 16, 20 and 25. Collapsed rules serve
//! tetrahedra of degree 3 and up and triangles of degree 9 and up.

use super::element::{ElementType, FaceType};

/// A quadrature rule on a 3D parent domain.
#[derive(Clone, Debug)]
pub struct Rule3 {
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
}

/// A quadrature rule on a 2D parent domain.
#[derive(Clone, Debug)]
pub struct Rule2 {
    pub points: Vec<[f64; 2]>,
    pub weights: Vec<f64>,
}

/// Newton iterations beyond which a Legendre root search gives up improving (it converges in a
/// handful).
const MAX_NEWTON_ITERATIONS: usize = 100;

/// `(P_n(x), P_n'(x))` by the three-term recurrence, for `|x| < 1`.
fn legendre_with_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p_prev, mut p) = (1.0, x);
    for k in 1..n {
        let kf = k as f64;
        let p_next = ((2.0 * kf + 1.0) * x * p - kf * p_prev) / (kf + 1.0);
        p_prev = p;
        p = p_next;
    }
    let dp = n as f64 * (x * p - p_prev) / (x * x - 1.0);
    (p, dp)
}

/// The root of `P_n` nearest to `guess`, by Newton's method.
fn legendre_root(n: usize, guess: f64) -> f64 {
    let mut x = guess;
    for _ in 0..MAX_NEWTON_ITERATIONS {
        let (p, dp) = legendre_with_derivative(n, x);
        let dx = p / dp;
        x -= dx;
        if dx.abs() <= 1e-16 {
            break;
        }
    }
    x
}

/// Gauss weight `2 / ((1 - x^2) P_n'(x)^2)` of the root `x`.
fn legendre_weight(n: usize, x: f64) -> f64 {
    let (_, dp) = legendre_with_derivative(n, x);
    2.0 / ((1.0 - x * x) * dp * dp)
}

/// Gauss-Legendre points and weights on [-1,1], n >= 1 (any n up to at least 12, computed by
/// Newton on the Legendre recurrence to full double precision, not tabulated).
///
/// Points are in increasing order and exactly symmetric about 0 (the middle point of an odd rule is
/// exactly 0).
///
/// # Panics
/// If `n == 0`.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "gauss_legendre: need at least one point");
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    let nf = n as f64;
    for i in 0..n / 2 {
        let guess = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
        let root = legendre_root(n, guess);
        let weight = legendre_weight(n, root);
        x[i] = -root;
        x[n - 1 - i] = root;
        w[i] = weight;
        w[n - 1 - i] = weight;
    }
    if n % 2 == 1 {
        w[n / 2] = legendre_weight(n, 0.0);
    }
    (x, w)
}

/// Gauss-Legendre rule with `n` points mapped to `[0, 1]`.
fn gauss_legendre_unit(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w) = gauss_legendre(n);
    (
        x.iter().map(|t| 0.5 * (1.0 + t)).collect(),
        w.iter().map(|v| 0.5 * v).collect(),
    )
}

/// Number of Gauss points integrating one-dimensional polynomials of degree `degree` exactly:
/// `ceil((degree + 1) / 2)`.
fn gauss_points_for_degree(degree: usize) -> usize {
    degree / 2 + 1
}

/// Tensor Gauss rule on `[-1, 1]^D` exact for degree `degree` in each variable: points and
/// weights, the first coordinate running fastest.
fn tensor_rule<const D: usize>(degree: usize) -> (Vec<[f64; D]>, Vec<f64>) {
    let (x, w) = gauss_legendre(gauss_points_for_degree(degree));
    let n = x.len();
    let index = |t: usize, d: usize| t / n.pow(d as u32) % n;
    (0..n.pow(D as u32))
        .map(|t| {
            let point = std::array::from_fn(|d| x[index(t, d)]);
            let weight = (1..D).fold(w[index(t, 0)], |acc, d| acc * w[index(t, d)]);
            (point, weight)
        })
        .unzip()
}

/// Tensor Gauss rule on `[-1, 1]^3` exact for degree `degree` in each variable.
fn hex_tensor_rule(degree: usize) -> Rule3 {
    let (points, weights) = tensor_rule(degree);
    Rule3 { points, weights }
}

/// Tensor Gauss rule on `[-1, 1]^2` exact for degree `degree` in each variable.
fn quad_tensor_rule(degree: usize) -> Rule2 {
    let (points, weights) = tensor_rule(degree);
    Rule2 { points, weights }
}

/// One-point centroid rule on the unit tetrahedron (degree 1).
fn tet_centroid_rule() -> Rule3 {
    Rule3 {
        points: vec![[0.25; 3]],
        weights: vec![1.0 / 6.0],
    }
}

/// Symmetric 4-point rule on the unit tetrahedron (degree 2).
fn tet_four_point_rule() -> Rule3 {
    let a = (5.0 - 5f64.sqrt()) / 20.0;
    let b = 1.0 - 3.0 * a;
    Rule3 {
        points: vec![[a, a, a], [b, a, a], [a, b, a], [a, a, b]],
        weights: vec![1.0 / 24.0; 4],
    }
}

/// Collapsed (conical product) Gauss rule on the unit tetrahedron exact for total degree `degree`.
fn tet_collapsed_rule(degree: usize) -> Rule3 {
    let (u, wu) = gauss_legendre_unit(gauss_points_for_degree(degree + 2));
    let (v, wv) = gauss_legendre_unit(gauss_points_for_degree(degree + 1));
    let (w, ww) = gauss_legendre_unit(gauss_points_for_degree(degree));
    let mut rule = Rule3 {
        points: Vec::new(),
        weights: Vec::new(),
    };
    for (ui, wui) in u.iter().zip(&wu) {
        for (vj, wvj) in v.iter().zip(&wv) {
            for (wk, wwk) in w.iter().zip(&ww) {
                let (su, sv) = (1.0 - ui, 1.0 - vj);
                rule.points.push([*ui, su * vj, su * sv * wk]);
                rule.weights.push(wui * wvj * wwk * su * su * sv);
            }
        }
    }
    rule
}

/// One-point centroid rule on the unit triangle (degree 1).
fn tri_centroid_rule() -> Rule2 {
    Rule2 {
        points: vec![[1.0 / 3.0; 2]],
        weights: vec![0.5],
    }
}

/// Symmetric 3-point rule on the unit triangle (degree 2).
fn tri_three_point_rule() -> Rule2 {
    let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
    Rule2 {
        points: vec![[a, a], [b, a], [a, b]],
        weights: vec![1.0 / 6.0; 3],
    }
}

/// A symmetric orbit of points of a triangle rule, in barycentric coordinates, with the weight
/// of each point (the weights of a rule sum to 1).
enum Orbit {
    /// The centroid.
    Centroid(f64),
    /// `(a, a, 1 - 2a)` and its 3 permutations.
    Two(f64, f64),
    /// `(a, b, 1 - a - b)` and its 6 permutations.
    Three(f64, f64, f64),
}

/// Dunavant's symmetric rules on the unit triangle (D. A. Dunavant, "High degree efficient
/// symmetrical Gaussian quadrature rules for the triangle", IJNME 21, 1985, rules 4, 5, 6 and
/// 8): every weight positive and every point inside, and fewer points than collapsed Gauss
/// from degree 4 on.
/// Degree 3 takes the degree-4 rule (Dunavant's degree-3 rule has a negative weight) and
/// degree 7 the degree-8 rule (likewise). The digits are the published ones refined by Newton's
/// method on the moment equations in 40-digit arithmetic (every monomial of the rule's degree
/// then integrated to 1e-40; the published 15 digits moved by at most 5e-16), rounded to the
/// nearest f64.
///
/// # Panics
/// If `degree` is not in 3..=8.
fn tri_dunavant_rule(degree: usize) -> Rule2 {
    use Orbit::{Centroid, Three, Two};
    let orbits: &[Orbit] = match degree {
        3 | 4 => &[
            Two(0.4459484909159649, 0.22338158967801147),
            Two(0.09157621350977074, 0.10995174365532187),
        ],
        5 => &[
            Centroid(0.225),
            Two(0.10128650732345634, 0.12593918054482714),
            Two(0.4701420641051151, 0.1323941527885062),
        ],
        6 => &[
            Two(0.24928674517091043, 0.11678627572637937),
            Two(0.06308901449150223, 0.05084490637020682),
            Three(
                0.053145049844816945,
                0.3103524510337844,
                0.08285107561837357,
            ),
        ],
        7 | 8 => &[
            Centroid(0.14431560767778717),
            Two(0.4592925882927232, 0.09509163426728462),
            Two(0.1705693077517602, 0.10321737053471824),
            Two(0.05054722831703098, 0.03245849762319808),
            Three(
                0.008394777409957605,
                0.2631128296346381,
                0.027230314174434993,
            ),
        ],
        _ => panic!("no Dunavant rule of degree {degree} here"),
    };
    let mut rule = Rule2 {
        points: Vec::new(),
        weights: Vec::new(),
    };
    // The unit triangle's coordinates are the first two barycentric ones; its area is 1/2.
    let mut add = |l1: f64, l2: f64, w: f64| {
        rule.points.push([l1, l2]);
        rule.weights.push(0.5 * w);
    };
    for orbit in orbits {
        match *orbit {
            Centroid(w) => add(1.0 / 3.0, 1.0 / 3.0, w),
            Two(a, w) => {
                let c = 1.0 - 2.0 * a;
                add(a, a, w);
                add(a, c, w);
                add(c, a, w);
            }
            Three(a, b, w) => {
                let c = 1.0 - a - b;
                for (l1, l2) in [(a, b), (b, a), (a, c), (c, a), (b, c), (c, b)] {
                    add(l1, l2, w);
                }
            }
        }
    }
    rule
}

/// Collapsed Gauss rule on the unit triangle exact for total degree `degree`.
fn tri_collapsed_rule(degree: usize) -> Rule2 {
    let (u, wu) = gauss_legendre_unit(gauss_points_for_degree(degree + 1));
    let (v, wv) = gauss_legendre_unit(gauss_points_for_degree(degree));
    let mut rule = Rule2 {
        points: Vec::new(),
        weights: Vec::new(),
    };
    for (ui, wui) in u.iter().zip(&wu) {
        for (vj, wvj) in v.iter().zip(&wv) {
            let su = 1.0 - ui;
            rule.points.push([*ui, su * vj]);
            rule.weights.push(wui * wvj * su);
        }
    }
    rule
}

impl ElementType {
    /// A rule exact for polynomials of total degree <= `degree` on the parent domain
    /// (hex: tensor Gauss with ceil((degree+1)/2) points per direction; tet: 1-point for degree
    /// <= 1, symmetric 4-point for degree 2, collapsed Gauss rule with positive weights above).
    pub fn quadrature(self, degree: usize) -> Rule3 {
        if self.is_hex() {
            return hex_tensor_rule(degree);
        }
        match degree {
            0 | 1 => tet_centroid_rule(),
            2 => tet_four_point_rule(),
            _ => tet_collapsed_rule(degree),
        }
    }

    /// The default degree for the stiffness of this element: Hex8 3 (2x2x2), Hex20 and Hex27 5
    /// (3x3x3), Tet4 2, Tet10 4.
    ///
    /// Why:
    /// - Hex8: `dN/dxi` is linear in the other two variables, so on a parallelepiped the stiffness
    ///   integrand has degree <= 2 per variable and the mass integrand `N_a N_b` too: 2x2x2 Gauss
    ///   (degree 3) is full integration without hourglass modes.
    /// - Hex20/Hex27: gradients have degree <= 2 per variable, the stiffness integrand <= 4 and the
    ///   mass integrand <= 4: 3x3x3 Gauss (degree 5) integrates both exactly on affine elements
    ///   (2x2x2 would be reduced integration, with spurious zero-energy modes).
    /// - Tet4: the gradients are constant (one point would do for the stiffness of a straight
    ///   element); degree 2 (4 points) also integrates the consistent mass `N_a N_b` and samples
    ///   nonlinear material response at more than one point.
    /// - Tet10: gradients are linear, so the stiffness of a straight-sided element is degree 2; the
    ///   mass `N_a N_b` is degree 4, and degree 4 also leaves margin for curved (isoparametric)
    ///   elements and nonlinear materials.
    pub fn default_quadrature_degree(self) -> usize {
        match self {
            ElementType::Hex8 => 3,
            ElementType::Hex20 | ElementType::Hex27 => 5,
            ElementType::Tet4 => 2,
            ElementType::Tet10 => 4,
        }
    }
}

impl FaceType {
    /// A rule exact for polynomials of total degree <= `degree` on the parent face (quads: tensor
    /// Gauss; triangles: 1-point for degree <= 1, symmetric 3-point for degree 2, Dunavant's
    /// symmetric rules for degrees 3-8 (`tri_dunavant_rule`: 6, 6, 7, 12, 16 and 16 points
    /// where collapsed Gauss takes 6, 9, 12, 16, 20 and 25), collapsed Gauss above).
    pub fn quadrature(self, degree: usize) -> Rule2 {
        if self.is_quad() {
            return quad_tensor_rule(degree);
        }
        match degree {
            0 | 1 => tri_centroid_rule(),
            2 => tri_three_point_rule(),
            3..=8 => tri_dunavant_rule(degree),
            _ => tri_collapsed_rule(degree),
        }
    }

    /// The default degree for face integrals (mortar and load terms `N_a N_b`, degree 2 for linear
    /// and 4 for quadratic faces, integrated exactly on flat faces): Quad4 3 (2x2), Quad8/Quad9 5
    /// (3x3), Tri3 2, Tri6 4.
    pub fn default_quadrature_degree(self) -> usize {
        match self {
            FaceType::Quad4 => 3,
            FaceType::Quad8 | FaceType::Quad9 => 5,
            FaceType::Tri3 => 2,
            FaceType::Tri6 => 4,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MAX_DEGREE: usize = 10;
    /// Relative tolerance of exact integration (relative to the integral of `|monomial|`).
    const EXACT_TOL: f64 = 1e-13;
    /// Relative error above which a rule is considered not exact for a monomial.
    const INEXACT_TOL: f64 = 1e-10;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    /// `(exact integral, integral of |x^a|)` over `[-1, 1]`.
    fn interval_integral(a: u32) -> (f64, f64) {
        let abs = 2.0 / f64::from(a + 1);
        (if a.is_multiple_of(2) { abs } else { 0.0 }, abs)
    }

    fn pow(x: f64, a: u32) -> f64 {
        x.powi(a as i32)
    }

    /// An element type (`D = 3`) or a face type (`D = 2`), as these tests see it: its parent
    /// domain and its rules.
    trait Domain<const D: usize>: Copy + std::fmt::Debug {
        /// True for the tensor domain `[-1, 1]^D`, false for the unit simplex.
        fn is_cube(self) -> bool;
        /// The rule of `degree`: points and weights.
        fn rule(self, degree: usize) -> (Vec<[f64; D]>, Vec<f64>);
        /// `(exact integral, integral of |monomial|)` over the parent domain.
        fn exact(self, e: [u32; D]) -> (f64, f64) {
            if self.is_cube() {
                e.iter()
                    .map(|&a| interval_integral(a))
                    .fold((1.0, 1.0), |(v, m), (iv, im)| (v * iv, m * im))
            } else {
                let total: u32 = e.iter().sum();
                let v =
                    e.iter().map(|&a| factorial(a)).product::<f64>() / factorial(total + D as u32);
                (v, v)
            }
        }
    }

    /// `Domain<$d>` for `$t`, whose tensor types answer `$cube`.
    macro_rules! domain {
        ($t:ty, $d:literal, $cube:ident) => {
            impl Domain<$d> for $t {
                fn is_cube(self) -> bool {
                    self.$cube()
                }
                fn rule(self, degree: usize) -> (Vec<[f64; $d]>, Vec<f64>) {
                    let r = self.quadrature(degree);
                    (r.points, r.weights)
                }
            }
        };
    }
    domain!(ElementType, 3, is_hex);
    domain!(FaceType, 2, is_quad);

    /// Relative error of the rule of `degree` on the monomial `x^e0 y^e1 (z^e2)`.
    fn error<const D: usize>(p: impl Domain<D>, degree: usize, e: [u32; D]) -> f64 {
        let (points, weights) = p.rule(degree);
        let q: f64 = points
            .iter()
            .zip(&weights)
            .map(|(x, w)| (0..D).fold(*w, |acc, i| acc * pow(x[i], e[i])))
            .sum();
        let (exact, scale) = p.exact(e);
        (q - exact).abs() / scale
    }

    /// Largest relative error over all monomials of total degree exactly `k`.
    fn max_error<const D: usize>(p: impl Domain<D>, degree: usize, k: u32) -> f64 {
        let n = k + 1;
        (0..n.pow(D as u32))
            .map(|i| std::array::from_fn(|d| i / n.pow(d as u32) % n))
            .filter(|e: &[u32; D]| e.iter().sum::<u32>() == k)
            .map(|e| error(p, degree, e))
            .fold(0.0, f64::max)
    }

    /// The highest total degree `e` with every monomial of degree `<= e` exact (searched up to
    /// `limit`).
    fn exactness(max_error: impl Fn(u32) -> f64, limit: u32) -> u32 {
        (0..=limit)
            .take_while(|&k| max_error(k) < EXACT_TOL)
            .last()
            .map_or(0, |k| k)
    }

    /// Every rule of degree 1..=10 integrates all monomials up to its degree exactly and is
    /// exact to degree at most `degree + 1` (Gauss-type rules have odd degree), i.e. some
    /// monomial of degree `degree + 1` or `degree + 2` is integrated wrongly.
    fn assert_rules_have_their_degree<const D: usize>(p: impl Domain<D>) {
        for degree in 1..=MAX_DEGREE {
            let d = degree as u32;
            for k in 0..=d {
                let err = max_error(p, degree, k);
                assert!(
                    err < EXACT_TOL,
                    "{p:?} rule {degree}: degree {k} error {err}"
                );
            }
            let e = exactness(|k| max_error(p, degree, k), d + 2);
            assert!(e <= d + 1, "{p:?} rule {degree} exact to {e}");
            assert!(max_error(p, degree, e + 1) > INEXACT_TOL);
        }
    }

    #[test]
    fn element_rules_have_the_requested_degree() {
        ElementType::ALL
            .into_iter()
            .for_each(assert_rules_have_their_degree);
    }

    #[test]
    fn face_rules_have_the_requested_degree() {
        FaceType::ALL
            .into_iter()
            .for_each(assert_rules_have_their_degree);
    }

    /// Tensor rules of odd degree fail on `x^(degree + 1)`: a rule exact one degree beyond its
    /// design would make the exactness test meaningless.
    #[test]
    fn tensor_rules_are_not_exact_one_degree_higher() {
        for degree in (1..=MAX_DEGREE).step_by(2) {
            let d = degree as u32 + 1;
            assert!(error(ElementType::Hex8, degree, [d, 0, 0]) > INEXACT_TOL);
            assert!(error(ElementType::Hex8, degree, [0, 0, d]) > INEXACT_TOL);
            assert!(error(FaceType::Quad4, degree, [0, d]) > INEXACT_TOL);
        }
    }

    /// The rule of `degree` has positive weights summing to the measure of the parent domain
    /// and its points inside it.
    fn assert_weights_positive_points_inside<const D: usize>(p: impl Domain<D>, degree: usize) {
        let (points, weights) = p.rule(degree);
        assert_eq!(points.len(), weights.len());
        let measure = if p.is_cube() {
            2f64.powi(D as i32)
        } else {
            1.0 / factorial(D as u32)
        };
        let sum: f64 = weights.iter().sum();
        assert!(
            (sum - measure).abs() < 1e-14 * measure,
            "{p:?} {degree}: {sum}"
        );
        assert!(weights.iter().all(|&w| w > 0.0));
        for x in &points {
            let inside = if p.is_cube() {
                x.iter().all(|t| t.abs() < 1.0)
            } else {
                x.iter().all(|&t| t > 0.0) && x.iter().sum::<f64>() < 1.0
            };
            assert!(inside, "{p:?} {degree}: {x:?}");
        }
    }

    #[test]
    fn weights_are_positive_points_inside_and_sum_to_the_volume() {
        for degree in 0..=MAX_DEGREE {
            for et in ElementType::ALL {
                assert_weights_positive_points_inside(et, degree);
            }
            for ft in FaceType::ALL {
                assert_weights_positive_points_inside(ft, degree);
            }
        }
    }

    #[test]
    fn hex_rules_use_the_documented_number_of_points() {
        for (degree, per_dir) in [(1, 1), (2, 2), (3, 2), (4, 3), (5, 3), (10, 6)] {
            assert_eq!(
                ElementType::Hex27.quadrature(degree).points.len(),
                per_dir * per_dir * per_dir
            );
            assert_eq!(
                FaceType::Quad9.quadrature(degree).points.len(),
                per_dir * per_dir
            );
        }
        assert_eq!(ElementType::Tet4.quadrature(1).points.len(), 1);
        assert_eq!(ElementType::Tet4.quadrature(2).points.len(), 4);
        assert_eq!(FaceType::Tri3.quadrature(2).points.len(), 3);
        for (degree, points) in [(3, 6), (4, 6), (5, 7), (6, 12), (7, 16), (8, 16), (9, 30)] {
            assert_eq!(FaceType::Tri6.quadrature(degree).points.len(), points);
        }
    }

    /// Gauss-Legendre with n points: sorted, symmetric, exact for x^k, k <= 2n - 1, to 1e-15
    /// (absolute, the integrals are at most 2), and wrong for x^(2n) (the error of x^(2n) is
    /// `2^(2n+1) (n!)^4 / ((2n+1) ((2n)!)^2)`, still ~3e-12 at n = 20, far above rounding).
    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in 1..=20 {
            let (x, w) = gauss_legendre(n);
            assert_eq!((x.len(), w.len()), (n, n));
            assert!(x.windows(2).all(|p| p[0] < p[1]), "n = {n}: not sorted");
            for i in 0..n {
                assert_eq!(x[i], -x[n - 1 - i]);
                assert_eq!(w[i], w[n - 1 - i]);
            }
            let integrate = |k: u32| -> f64 { x.iter().zip(&w).map(|(t, v)| v * pow(*t, k)).sum() };
            for k in 0..2 * n as u32 {
                let err = (integrate(k) - interval_integral(k).0).abs();
                assert!(err < 1e-15 * 4.0, "n = {n}, x^{k}: error {err}");
            }
            let k = 2 * n as u32;
            assert!(
                (integrate(k) - interval_integral(k).0).abs() > 1e-13,
                "n = {n} exact for x^{k}"
            );
        }
    }

    /// Against known values: the 2-point rule is +-1/sqrt 3 with weights 1, the 3-point rule 0,
    /// +-sqrt(3/5) with weights 8/9, 5/9; to a few units in the last place.
    #[test]
    fn gauss_legendre_known_values() {
        let tol = 4.0 * f64::EPSILON;
        let (x, w) = gauss_legendre(2);
        assert!((x[1] - 1.0 / 3f64.sqrt()).abs() < tol);
        assert!((w[0] - 1.0).abs() < tol);
        let (x, w) = gauss_legendre(3);
        assert_eq!(x[1], 0.0);
        assert!((x[2] - 0.6f64.sqrt()).abs() < tol);
        assert!((w[1] - 8.0 / 9.0).abs() < tol);
        assert!((w[2] - 5.0 / 9.0).abs() < tol);
    }
}
