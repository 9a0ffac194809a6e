//! The projection plane of a secondary sub-segment, and the maps between that plane and the
//! local coordinates of the projected sub-segments (docs/theory.md section 3): the geometry the
//! value kernel ([`super::pair`]) and the linearized kernel ([`super::linearize`]) share.
//!
//! # The plane (step 1 of the walk, [`super::overlap`])
//!
//! Through the centre `x_c = x(xi_c)` of a secondary sub-segment `s` (the face map at the
//! sub-segment's centroid in parent coordinates) with normal `n_c`, the secondary face's unit
//! geometric normal at `xi_c` ([`crate::fe::face_normal`]). This is a choice: the paper uses the
//! interpolated nodal normal; nodal normals belong to the contact enforcement (docs/theory.md
//! section 2), while the geometry of the overlap only needs a plane that the sub-segment projects
//! onto without folding, and the face's own normal depends on that face alone. In-plane basis:
//! `e1` along the first edge of `s` (projected; along the coordinate axis least aligned with
//! `n_c` if that edge is degenerate), `e2 = n_c x e1`, so the 2D coordinates
//!
//! `P(x) = ((x - x_c) . e1, (x - x_c) . e2)`
//!
//! are the same for any rigid motion of the pair. The vertices of the sub-segments are face
//! nodes; their positions are projected along `n_c`.
//!
//! # The inverse maps (step 4 of the walk)
//!
//! Each quadrature point `P` of the overlap is mapped back onto both projected sub-segments:
//!
//! - on a triangle `Q_0 Q_1 Q_2`, in closed form: the barycentric coordinates
//!   `(det [d b] / det [a b], det [a d] / det [a b])` with `a = Q_1 - Q_0`, `b = Q_2 - Q_0`,
//!   `d = P - Q_0`, and `det(dP/dlocal) = det [a b]`;
//! - on a quadrilateral, by Newton on the bilinear map `P(s, t) = p0 + a s + b t + c s t` (the
//!   Quad4 interpolation of its vertices in monomial form): start at the centre, each iterate
//!   kept inside `[-2, 2]^2`, converged when the step is below `1e-13`.
//!
//! A point is accepted if its local coordinates lie in the sub-segment's local domain (up to
//! `1e-6`: the points lie in the clipped overlap, so inside both sub-segments up to round-off)
//! and `det(dP/dlocal)` has the sub-segment's orientation (positive for the counter-clockwise
//! secondary, negative for the primary in its own vertex order); otherwise the inverse map has
//! failed.
//!
//! # One code for floats and dual numbers
//!
//! The plane, the projection, the triangle map and the bilinear map are written once,
//! generically over the scalar ([`crate::fe::shape::Scalar`]): the value kernel runs them in
//! `f64`, the linearized kernel in dual numbers (level 1: the plane and the projected vertices;
//! its level-2 reference: the local coordinates), so both run the same formulas in the same
//! order.

use super::clip::Point;
use super::segments::SubSegment;
use crate::fe::shape::{face_normal_at, face_point_at, Scalar};
use crate::fe::FaceType;
use crate::vec3::{cross, dot, normalized, sub, Vec3};

/// Newton on a bilinear inverse map stops when the step (in local coordinates, range 2) is below
/// this.
const NEWTON_STEP_TOLERANCE: f64 = 1e-13;

/// Most Newton iterations on a bilinear inverse map.
const MAX_NEWTON_ITERATIONS: usize = 40;

/// A point whose local coordinates fall further than this outside the local domain (in local
/// units) is a failed inverse map (the points all lie in the clipped overlap, so inside both
/// sub-segments up to round-off).
const LOCAL_DOMAIN_SLACK: f64 = 1e-6;

/// The projection plane of a secondary sub-segment (module docs), for any [`Scalar`].
pub(super) struct Plane<T = f64> {
    origin: Vec3<T>,
    pub(super) normal: Vec3<T>,
    e1: Vec3<T>,
    e2: Vec3<T>,
}

impl<T: Scalar> Plane<T> {
    /// The plane through the centre of `seg` of a face of type `kind` with node coordinates `x`,
    /// with the face's normal there.
    pub(super) fn of_sub_segment(kind: FaceType, x: &[Vec3<T>], seg: &SubSegment) -> Option<Self> {
        let centre = seg.centre().map(T::from);
        let origin = face_point_at(kind, x, centre);
        let (normal, jac) = face_normal_at(kind, x, centre);
        let finite = origin.iter().chain(&normal).all(|v| v.re().is_finite());
        if jac.re() <= 0.0 || !finite {
            return None;
        }
        let e1 = Self::first_axis(x, seg, normal)?;
        Some(Plane {
            origin,
            normal,
            e1,
            e2: cross(normal, e1),
        })
    }

    /// Unit vector along the first edge of `seg` projected on the plane, or (degenerate edge)
    /// along the coordinate axis least aligned with `normal`.
    fn first_axis(x: &[Vec3<T>], seg: &SubSegment, normal: Vec3<T>) -> Option<Vec3<T>> {
        let in_plane = |d: Vec3<T>| {
            let along = dot(d, normal);
            normalized(sub(d, normal.map(|v| v * along)))
        };
        let edge = sub(x[seg.local_nodes[1]], x[seg.local_nodes[0]]);
        let axis = (0..3)
            .min_by(|&i, &j| normal[i].re().abs().total_cmp(&normal[j].re().abs()))
            .map(|i| std::array::from_fn(|d| T::from(if d == i { 1.0 } else { 0.0 })))?;
        in_plane(edge).or_else(|| in_plane(axis))
    }

    /// In-plane coordinates of the projection of `x`.
    fn project(&self, x: Vec3<T>) -> [T; 2] {
        let d = sub(x, self.origin);
        [dot(d, self.e1), dot(d, self.e2)]
    }

    /// The projected vertices of `seg` of a face with node coordinates `x`, in `seg`'s order.
    pub(super) fn project_vertices(&self, x: &[Vec3<T>], seg: &SubSegment) -> Vec<[T; 2]> {
        seg.local_nodes
            .iter()
            .map(|&a| self.project(x[a]))
            .collect()
    }
}

/// `det [u v]` of two plane vectors.
pub(super) fn det2<T: Scalar>(u: [T; 2], v: [T; 2]) -> T {
    u[0] * v[1] - u[1] * v[0]
}

/// Local (barycentric) coordinates of `p` on the triangle `q` and `det(dP/dlocal)`, for any
/// [`Scalar`]; not finite for a degenerate triangle.
pub(super) fn triangle_local<T: Scalar>(q: &[[T; 2]], p: [T; 2]) -> ([T; 2], T) {
    let a = [q[1][0] - q[0][0], q[1][1] - q[0][1]];
    let b = [q[2][0] - q[0][0], q[2][1] - q[0][1]];
    let d = [p[0] - q[0][0], p[1] - q[0][1]];
    let det = det2(a, b);
    ([det2(d, b) / det, det2(a, d) / det], det)
}

/// The bilinear map `P(s, t) = sum_i N_i(s, t) q_i` of a quadrilateral `q` (Quad4 local
/// coordinates) in the monomial form `P = p0 + a s + b t + c s t`, for any [`Scalar`].
pub(super) struct Bilinear<T = f64> {
    p0: [T; 2],
    pub(super) a: [T; 2],
    pub(super) b: [T; 2],
    pub(super) c: [T; 2],
}

impl<T: Scalar> Bilinear<T> {
    /// The map of the quadrilateral with vertices `q` (the first four).
    pub(super) fn new(q: &[[T; 2]]) -> Self {
        let combine = |w: [f64; 4]| -> [T; 2] {
            std::array::from_fn(|i| {
                (q[0][i] * w[0] + q[1][i] * w[1] + q[2][i] * w[2] + q[3][i] * w[3]) * 0.25
            })
        };
        Bilinear {
            p0: combine([1.0, 1.0, 1.0, 1.0]),
            a: combine([-1.0, 1.0, 1.0, -1.0]),
            b: combine([-1.0, -1.0, 1.0, 1.0]),
            c: combine([1.0, -1.0, 1.0, -1.0]),
        }
    }

    /// `P(local)` and the Jacobian matrix `J[i][j] = dP_i/dlocal_j`.
    fn eval(&self, local: [T; 2]) -> ([T; 2], [[T; 2]; 2]) {
        let [s, t] = local;
        let (a, b, c) = (self.a, self.b, self.c);
        let p = [
            self.p0[0] + a[0] * s + b[0] * t + c[0] * s * t,
            self.p0[1] + a[1] * s + b[1] * t + c[1] * s * t,
        ];
        let j = [
            [a[0] + c[0] * t, b[0] + c[0] * s],
            [a[1] + c[1] * t, b[1] + c[1] * s],
        ];
        (p, j)
    }

    /// `P(local)` at float local coordinates.
    pub(super) fn point(&self, local: [f64; 2]) -> [T; 2] {
        let [s, t] = local;
        let (a, b, c) = (self.a, self.b, self.c);
        [
            self.p0[0] + a[0] * s + b[0] * t + c[0] * (s * t),
            self.p0[1] + a[1] * s + b[1] * t + c[1] * (s * t),
        ]
    }

    /// `det(dP/dlocal)` at `local`.
    pub(super) fn jacobian(&self, local: [T; 2]) -> T {
        let [s, t] = local;
        let (a, b, c) = (self.a, self.b, self.c);
        (a[0] + c[0] * t) * (b[1] + c[1] * s) - (b[0] + c[0] * s) * (a[1] + c[1] * t)
    }

    /// The real part of the Jacobian matrix at float local coordinates.
    pub(super) fn jacobian_re(&self, local: [f64; 2]) -> [[f64; 2]; 2] {
        let [s, t] = local;
        let (a, b, c) = (
            self.a.map(|v| v.re()),
            self.b.map(|v| v.re()),
            self.c.map(|v| v.re()),
        );
        [
            [a[0] + c[0] * t, b[0] + c[0] * s],
            [a[1] + c[1] * t, b[1] + c[1] * s],
        ]
    }
}

/// `J^-1 r` for a 2x2 matrix `J` with determinant `det`.
pub(super) fn solve2<T: Scalar>(j: [[f64; 2]; 2], det: f64, r: [T; 2]) -> [T; 2] {
    [
        (r[0] * j[1][1] - r[1] * j[0][1]) / det,
        (r[1] * j[0][0] - r[0] * j[1][0]) / det,
    ]
}

/// A projected linear sub-segment (triangle or quadrilateral), its vertices in the order of its
/// sub-segment's vertices: counter-clockwise in the plane (`orientation = 1`, the secondary) or
/// clockwise (`-1`, the primary).
pub(super) struct Projected<'s> {
    pub(super) vertices: Vec<Point>,
    pub(super) seg: &'s SubSegment,
    orientation: f64,
    /// The bilinear map of a quadrilateral.
    bilinear: Option<Bilinear>,
}

/// Local coordinates of a plane point on a projected sub-segment and `det(dP/dlocal)` there
/// (negative for a clockwise sub-segment).
pub(super) struct LocalPoint {
    pub(super) local: [f64; 2],
    pub(super) jacobian: f64,
}

impl<'s> Projected<'s> {
    /// The projected vertices of `seg`, counter-clockwise (`orientation = 1`) or clockwise (`-1`).
    pub(super) fn new(vertices: Vec<Point>, seg: &'s SubSegment, orientation: f64) -> Self {
        let bilinear = (vertices.len() == 4).then(|| Bilinear::new(&vertices));
        Projected {
            vertices,
            seg,
            orientation,
            bilinear,
        }
    }

    /// The bilinear map of a quadrilateral (`None` for a triangle).
    pub(super) fn bilinear(&self) -> Option<&Bilinear> {
        self.bilinear.as_ref()
    }

    /// Local coordinates of `p` (barycentric on a triangle, bilinear inverse on a quad).
    pub(super) fn invert(&self, p: Point) -> Option<LocalPoint> {
        let found = match &self.bilinear {
            None => self.invert_triangle(p),
            Some(map) => self.invert_quad(map, p),
        }?;
        let slack = LOCAL_DOMAIN_SLACK;
        let [r, s] = found.local;
        let inside = if self.vertices.len() == 3 {
            r >= -slack && s >= -slack && r + s <= 1.0 + slack
        } else {
            r.abs() <= 1.0 + slack && s.abs() <= 1.0 + slack
        };
        (inside && self.is_positive(found.jacobian)).then_some(found)
    }

    /// True if a Jacobian determinant has the sub-segment's orientation (and is finite).
    fn is_positive(&self, det: f64) -> bool {
        det * self.orientation > 0.0 && det.is_finite()
    }

    fn invert_triangle(&self, p: Point) -> Option<LocalPoint> {
        let (local, jacobian) = triangle_local(&self.vertices, p);
        self.is_positive(jacobian)
            .then_some(LocalPoint { local, jacobian })
    }

    /// Newton on the bilinear map from the centre; each iterate is kept inside `[-2, 2]^2`.
    fn invert_quad(&self, map: &Bilinear, p: Point) -> Option<LocalPoint> {
        let mut local = [0.0; 2];
        for _ in 0..MAX_NEWTON_ITERATIONS {
            let (x, j) = map.eval(local);
            let det = det2(j[0], j[1]);
            if !self.is_positive(det) {
                return None;
            }
            let step = solve2(j, det, [x[0] - p[0], x[1] - p[1]]);
            local = [
                (local[0] - step[0]).clamp(-2.0, 2.0),
                (local[1] - step[1]).clamp(-2.0, 2.0),
            ];
            if step[0].abs().max(step[1].abs()) < NEWTON_STEP_TOLERANCE {
                let (_, j) = map.eval(local);
                let jacobian = det2(j[0], j[1]);
                return Some(LocalPoint { local, jacobian });
            }
        }
        None
    }
}
