//! Integration of one secondary face against one primary face (docs/theory.md section 3).
//!
//! [`integrate_pair`] computes the mortar weights
//!
//! `n1_kb = int_gamma Phi_k N1_b dgamma`, `n2_kc = int_gamma Phi_k N2_c dgamma`
//!
//! over the overlap `gamma` of a secondary face (traction functions `Phi_k`,
//! [`super::segments`], shape functions `N1_b`) and a primary face (shape functions `N2_c`).
//!
//! # Steps, for every secondary sub-segment `s` and primary sub-segment `m`
//!
//! Both faces are split into their linear sub-segments ([`sub_segments`]); every pair `(s, m)`
//! is integrated on its own:
//!
//! 1. **Plane.** Through the centre `x_c = x(xi_c)` of `s` (the face map at the sub-segment's
//!    centroid in parent coordinates) with normal `n_c`, the secondary face's unit geometric normal
//!    at `xi_c` ([`face_normal`]). This is a choice: the paper uses the interpolated nodal normal;
//!    nodal normals belong to the contact enforcement (docs/theory.md section 2), while the geometry
//!    of the overlap only needs a plane that the sub-segment projects onto without folding, and
//!    the face's own normal depends on that face alone. In-plane basis: `e1` along the first edge
//!    of `s` (projected), `e2 = n_c x e1`, so the 2D coordinates are the same for any rigid motion
//!    of the pair.
//! 2. **Project.** The vertices of `s` and `m` are face nodes; their positions are projected onto
//!    the plane along `n_c`. `s` comes out counter-clockwise (its normal is about `n_c`); `m`
//!    faces the other way, so its vertex order is reversed to make it counter-clockwise too.
//!    Rejected and counted: `m` whose normal (geometric, at its centre) does not oppose `n_c`
//!    (`n_m . n_c > -`[`OPPOSED_NORMALS_COSINE`]: [`RejectStats::normals_not_opposed`]), and a
//!    projected sub-segment that is not convex with positive area (a warped or folded quad, a
//!    degenerate face: [`RejectStats::non_convex`]).
//! 3. **Clip** ([`clip_convex`](super::clip::clip_convex); the traced variant, which also
//!    records where each overlap vertex comes from) with the tolerances relative to the size of `s` (the largest
//!    distance between its projected vertices): no overlap ([`RejectStats::no_overlap`], also for
//!    disjoint bounding boxes) or a sliver ([`RejectStats::sliver`]) are counted and skipped.
//! 4. **Quadrature.** The overlap is split into pallets ([`pallets`](super::clip::pallets):
//!    from its centroid, or a fan from one vertex chosen by where the vertices come from,
//!    [`PalletSplit`]); on each, the unit-triangle rule `FaceType::Tri3.quadrature(degree)` mapped affinely. Each point `P` is
//!    mapped back onto both projected sub-segments: local coordinates on a triangle in closed form
//!    (barycentric), on a quadrilateral by Newton on the bilinear map `p0 + a s + b t + c s t`
//!    (start at the centre, step limited to the parent square, converged when the step is below
//!    `1e-13`); then to face
//!    parent coordinates by the sub-segment's affine map ([`SubSegment::to_parent`]). There `N1`
//!    (secondary face), `Phi` ([`traction_shape_on`]) and `N2` (primary face) are evaluated.
//! 5. **Measure.** The weight of a point is the area element of the secondary face pulled back
//!    through the chain `P -> local -> xi -> x(xi)`:
//!
//!    `dgamma = w_P * J_face(xi) * det(dxi/dlocal) / det(dP/dlocal)`,
//!
//!    with `J_face = |x_,xi x x_,eta|` ([`face_normal`]), `det(dxi/dlocal)` the constant
//!    [`SubSegment::parent_jacobian`] and `det(dP/dlocal)` the Jacobian of the projected
//!    sub-segment's linear map at the point. Integrating it over the whole projected sub-segment
//!    gives exactly `int J_face dxi` over the sub-segment's parent region: the true area of the
//!    curved (isoparametric) face. So a secondary face fully covered by primary faces gets
//!    `sum n1 =` its area, to quadrature accuracy, whatever its curvature or in-plane distortion.
//!    (This replaces the simpler `dA_plane / |n_true . n_c|`, which equals it on flat faces with
//!    affine geometry but is only an approximation on curved faces, because the point `x(xi(P))`
//!    is not the point of the face that projects onto `P`.) On flat affine faces `dgamma` is the
//!    plane's area element.
//! 6. **Accumulate** `n1[k][b] += dgamma Phi_k N1_b` and `n2[k][c] += dgamma Phi_k N2_c` at the
//!    same points with the same weights, so that `sum_b n1_kb = sum_c n2_kc = int Phi_k` (up to
//!    round-off): linear momentum is conserved exactly (docs/theory.md 3.7).
//!
//! A sub-segment pair is accumulated only if every one of its points was mapped and evaluated to
//! finite values; otherwise it is skipped whole and counted ([`RejectStats::inverse_map_failed`]
//! or [`RejectStats::non_finite`]), so the momentum identity holds also for what is kept.
//!
//! # Shared with the linearization
//!
//! [`super::linearize`] differentiates this computation along the topology it finds. The steps
//! above are split so that it runs the same float code (`overlap_of_sub_pair`: steps 2 and 3,
//! `Projected::invert`), and the pieces it re-evaluates in dual numbers are written once,
//! generically over the scalar ([`crate::fe::shape::Scalar`]): the plane (`Plane`), the
//! triangle and bilinear maps (`triangle_local`, `Bilinear`), the sub-segment maps
//! ([`SubSegment::to_parent_at`]) and the shape functions. Here they run in `f64`.
//!
//! # Counting
//!
//! Every counter of [`RejectStats`] counts **sub-segment pairs** (a Quad9 against a Quad9 is 16
//! of them), except [`RejectStats::non_finite`], which counts face pairs with a non-finite node
//! coordinate plus sub-segment pairs with a non-finite intermediate value. Rejections are never
//! fatal here; a caller should stop the step on `non_finite > 0` (docs/theory.md section 10).
//!
//! # Quadrature degree
//!
//! On flat interfaces with affine faces every integrand is a polynomial in the plane
//! coordinates: `Phi N` is bilinear x bilinear (degree 4) for linear faces and up to biquadratic x
//! biquadratic (degree 8) for Quad9. Hence the defaults of [`IntegrationOptions::for_faces`]: 8 if
//! either face is quadratic, 4 otherwise. The traction scheme is not re-checked here: validate it
//! with [`super::segments::traction_nodes`] once at set-up (scheme 1 on Quad8/Tri6 integrates the
//! face's own `N`, well defined but ill-posed as a constraint).

use std::collections::BTreeMap;

use super::clip::{clip_convex_traced, is_convex_ccw, Clipped, PalletSplit, Point, VertexOrigin};
use super::segments::{
    sub_segments, traction_node_count, traction_shape_on, SubSegment, TractionScheme,
};
use crate::fe::shape::{
    face_normal_at, face_point_at, normal_from_tangents, tangents_from_grad, Scalar,
};
use crate::fe::{face_normal, FaceType};
use crate::vec3::{cross, dot, normalized, sub, Vec3};

/// A primary sub-segment is integrated only if its normal `n_m` satisfies
/// `n_m . n_c <= -OPPOSED_NORMALS_COSINE` (the normals are more than about 84 degrees apart).
pub const OPPOSED_NORMALS_COSINE: f64 = 0.1;

/// Newton on a bilinear inverse map stops when the step (in local coordinates, range 2) is below
/// this.
const NEWTON_STEP_TOLERANCE: f64 = 1e-13;

/// Most Newton iterations on a bilinear inverse map.
const MAX_NEWTON_ITERATIONS: usize = 40;

/// A point whose local coordinates fall further than this outside the local domain (in local
/// units) is a failed inverse map (the points all lie in the clipped overlap, so inside both
/// sub-segments up to round-off).
const LOCAL_DOMAIN_SLACK: f64 = 1e-6;

/// A face: its type and node coordinates.
#[derive(Clone, Copy, Debug)]
pub struct FaceGeom<'a> {
    pub kind: FaceType,
    /// Node coordinates, in the face's node order.
    pub x: &'a [[f64; 3]],
}

/// How a pair is integrated.
#[derive(Clone, Copy, Debug)]
pub struct IntegrationOptions {
    pub scheme: TractionScheme,
    /// Degree of the triangle rule on each pallet.
    pub degree: usize,
    /// How the overlap is split into pallets.
    pub pallets: PalletSplit,
}

impl IntegrationOptions {
    /// The default pallet-rule degree for a face type: 4 for linear faces (bilinear x bilinear),
    /// 8 for quadratic faces (biquadratic x biquadratic).
    pub fn default_degree(kind: FaceType) -> usize {
        match kind {
            FaceType::Quad4 | FaceType::Tri3 => 4,
            _ => 8,
        }
    }

    /// `scheme` with the larger default degree of the two face types.
    pub fn for_faces(scheme: TractionScheme, secondary: FaceType, primary: FaceType) -> Self {
        IntegrationOptions {
            scheme,
            degree: Self::default_degree(secondary).max(Self::default_degree(primary)),
            pallets: PalletSplit::default(),
        }
    }
}

/// Mortar weights of one face pair, as sparse triples (only non-zero entries).
#[derive(Clone, Debug, Default)]
pub struct PairWeights {
    /// `(k, b, n1)`: `k` indexes `traction_nodes(secondary kind, scheme)` (which equals the
    /// face-local node number of the traction node); `b` is a face-local node of the secondary
    /// face.
    pub n1: Vec<(usize, usize, f64)>,
    /// `(k, c, n2)`: `c` is a face-local node of the primary face.
    pub n2: Vec<(usize, usize, f64)>,
    /// Area of the overlap (the sum of the quadrature weights, equal to the sum of all `n1` up
    /// to round-off).
    pub area: f64,
}

/// Counts of rejected and integrated sub-segment pairs (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RejectStats {
    pub normals_not_opposed: usize,
    pub non_convex: usize,
    pub no_overlap: usize,
    pub sliver: usize,
    pub inverse_map_failed: usize,
    /// Non-finite node coordinates (per face pair) or intermediate values (per sub-segment pair).
    pub non_finite: usize,
    pub pairs_integrated: usize,
    /// Quadrature points of the integrated pairs (their cost: with the degree and the pallet
    /// split).
    pub quadrature_points: usize,
}

impl RejectStats {
    /// Adds `other`'s counts to these.
    pub fn add(&mut self, other: &RejectStats) {
        self.normals_not_opposed += other.normals_not_opposed;
        self.non_convex += other.non_convex;
        self.no_overlap += other.no_overlap;
        self.sliver += other.sliver;
        self.inverse_map_failed += other.inverse_map_failed;
        self.non_finite += other.non_finite;
        self.pairs_integrated += other.pairs_integrated;
        self.quadrature_points += other.quadrature_points;
    }

    /// The counts by name (the field names), for summaries.
    pub fn to_map(&self) -> BTreeMap<String, usize> {
        [
            ("normals_not_opposed", self.normals_not_opposed),
            ("non_convex", self.non_convex),
            ("no_overlap", self.no_overlap),
            ("sliver", self.sliver),
            ("inverse_map_failed", self.inverse_map_failed),
            ("non_finite", self.non_finite),
            ("pairs_integrated", self.pairs_integrated),
            ("quadrature_points", self.quadrature_points),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }
}

impl RejectStats {
    /// Counts what became of one sub-segment pair.
    pub(super) fn record(&mut self, outcome: &SubPairOutcome) {
        match outcome {
            SubPairOutcome::Integrated { points } => {
                self.pairs_integrated += 1;
                self.quadrature_points += points;
            }
            SubPairOutcome::NormalsNotOpposed => self.normals_not_opposed += 1,
            SubPairOutcome::NonConvex => self.non_convex += 1,
            SubPairOutcome::NoOverlap => self.no_overlap += 1,
            SubPairOutcome::Sliver => self.sliver += 1,
            SubPairOutcome::Failed(PairFailure::InverseMap) => self.inverse_map_failed += 1,
            SubPairOutcome::Failed(PairFailure::NonFinite) => self.non_finite += 1,
        }
    }
}

/// True if the node coordinates of a face are all finite.
pub(super) fn is_finite_face(face: &FaceGeom) -> bool {
    face.x.iter().flatten().all(|v| v.is_finite())
}

/// The projection plane of a secondary sub-segment, for any [`Scalar`] (`f64` here; dual numbers
/// in [`super::linearize`], with the same code).
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
    pub(super) fn project(&self, x: Vec3<T>) -> [T; 2] {
        let d = sub(x, self.origin);
        [dot(d, self.e1), dot(d, self.e2)]
    }
}

impl Plane {
    /// The projected vertices of `seg`, in its order or reversed.
    fn project_sub_segment(&self, face: &FaceGeom, seg: &SubSegment, reverse: bool) -> Vec<Point> {
        let mut p: Vec<Point> = seg
            .local_nodes
            .iter()
            .map(|&a| self.project(face.x[a]))
            .collect();
        if reverse {
            p.reverse();
        }
        p
    }
}

/// Largest distance between two vertices.
pub(super) fn diameter(p: &[Point]) -> f64 {
    let mut d: f64 = 0.0;
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            d = d.max((a[0] - b[0]).hypot(a[1] - b[1]));
        }
    }
    d
}

fn bounding_boxes_disjoint(a: &[Point], b: &[Point]) -> bool {
    let bounds = |p: &[Point], i: usize| {
        p.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v[i]), hi.max(v[i]))
            })
    };
    (0..2).any(|i| {
        let ((alo, ahi), (blo, bhi)) = (bounds(a, i), bounds(b, i));
        ahi < blo || bhi < alo
    })
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
    pub(super) fn eval(&self, local: [T; 2]) -> ([T; 2], [[T; 2]; 2]) {
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
    fn new(vertices: Vec<Point>, seg: &'s SubSegment, orientation: f64) -> Self {
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
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
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
                let jacobian = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                return Some(LocalPoint { local, jacobian });
            }
        }
        None
    }
}

/// Why a sub-segment pair was not accumulated.
pub(super) enum PairFailure {
    InverseMap,
    NonFinite,
}

/// Dense accumulators of one face pair.
struct Accumulator {
    n1: Vec<f64>,
    n2: Vec<f64>,
    area: f64,
    /// Quadrature points added.
    points: usize,
    sec_nodes: usize,
    pri_nodes: usize,
}

impl Accumulator {
    fn new(traction_nodes: usize, sec_nodes: usize, pri_nodes: usize) -> Self {
        Accumulator {
            n1: vec![0.0; traction_nodes * sec_nodes],
            n2: vec![0.0; traction_nodes * pri_nodes],
            area: 0.0,
            points: 0,
            sec_nodes,
            pri_nodes,
        }
    }

    /// Adds one quadrature point's contributions.
    fn add_point(&mut self, weight: f64, phi: &[f64], n1: &[f64], n2: &[f64]) {
        self.area += weight;
        self.points += 1;
        for (k, &pk) in phi.iter().enumerate() {
            let wp = weight * pk;
            let row1 = &mut self.n1[k * self.sec_nodes..(k + 1) * self.sec_nodes];
            for (v, nb) in row1.iter_mut().zip(n1) {
                *v += wp * nb;
            }
            let row2 = &mut self.n2[k * self.pri_nodes..(k + 1) * self.pri_nodes];
            for (v, nc) in row2.iter_mut().zip(n2) {
                *v += wp * nc;
            }
        }
    }

    fn merge(&mut self, other: &Accumulator) {
        self.area += other.area;
        self.points += other.points;
        for (a, b) in self.n1.iter_mut().zip(&other.n1) {
            *a += b;
        }
        for (a, b) in self.n2.iter_mut().zip(&other.n2) {
            *a += b;
        }
    }

    fn clear(&mut self) {
        self.area = 0.0;
        self.points = 0;
        self.n1.iter_mut().for_each(|v| *v = 0.0);
        self.n2.iter_mut().for_each(|v| *v = 0.0);
    }

    fn into_weights(self) -> PairWeights {
        let triples = |dense: &[f64], cols: usize| {
            dense
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(i, v)| (i / cols, i % cols, *v))
                .collect()
        };
        PairWeights {
            n1: triples(&self.n1, self.sec_nodes),
            n2: triples(&self.n2, self.pri_nodes),
            area: self.area,
        }
    }
}

/// Everything fixed for one face pair.
struct PairContext<'a> {
    sec: &'a FaceGeom<'a>,
    pri: &'a FaceGeom<'a>,
    scheme: TractionScheme,
    rule: crate::fe::Rule2,
    pallets: PalletSplit,
}

/// Scratch buffers for shape function values.
#[derive(Default)]
struct Scratch {
    phi: Vec<f64>,
    n1: Vec<f64>,
    dn1: Vec<[f64; 2]>,
    n2: Vec<f64>,
}

impl PairContext<'_> {
    /// Integrates the clipped polygon of `overlap` (of its projected sub-segments `s` and `m`)
    /// into `acc` (which the caller merges only on success).
    fn integrate_overlap(
        &self,
        overlap: &Overlap,
        acc: &mut Accumulator,
        scratch: &mut Scratch,
    ) -> Result<(), PairFailure> {
        let (s, m) = (&overlap.s, &overlap.m);
        let sec_jacobian = s.seg.parent_jacobian();
        let (polygon, origins) = (&overlap.polygon, &overlap.origins);
        let c = self.pallets.apex(polygon, origins);
        for (i, j) in self.pallets.edges(polygon.len(), origins) {
            let (a, b) = (polygon[i], polygon[j]);
            let (u, v) = ([a[0] - c[0], a[1] - c[1]], [b[0] - c[0], b[1] - c[1]]);
            let twice_area = u[0] * v[1] - u[1] * v[0];
            if twice_area <= 0.0 {
                continue;
            }
            for (q, w) in self.rule.points.iter().zip(&self.rule.weights) {
                let p = [
                    c[0] + q[0] * u[0] + q[1] * v[0],
                    c[1] + q[0] * u[1] + q[1] * v[1],
                ];
                let on_s = s.invert(p).ok_or(PairFailure::InverseMap)?;
                let on_m = m.invert(p).ok_or(PairFailure::InverseMap)?;
                let xi_s = s.seg.to_parent(on_s.local);
                let xi_m = m.seg.to_parent(on_m.local);
                let face_jacobian = self.evaluate(s.seg, xi_s, xi_m, scratch);
                let weight = w * twice_area * face_jacobian * sec_jacobian / on_s.jacobian;
                let values = scratch.phi.iter().chain(&scratch.n1).chain(&scratch.n2);
                if !weight.is_finite() || !values.into_iter().all(|v| v.is_finite()) {
                    return Err(PairFailure::NonFinite);
                }
                acc.add_point(weight, &scratch.phi, &scratch.n1, &scratch.n2);
            }
        }
        Ok(())
    }

    /// Phi and N1 at `xi_s` on the secondary face, N2 at `xi_m` on the primary face; returns
    /// the surface Jacobian `J_face(xi_s)` (from the gradients of N1, as [`face_normal`]).
    fn evaluate(
        &self,
        seg: &SubSegment,
        xi_s: [f64; 2],
        xi_m: [f64; 2],
        scratch: &mut Scratch,
    ) -> f64 {
        let ns = self.sec.kind.num_nodes();
        traction_shape_on(self.sec.kind, self.scheme, seg, xi_s, &mut scratch.phi);
        scratch.n1.resize(ns, 0.0);
        scratch.dn1.resize(ns, [0.0; 2]);
        scratch.n2.resize(self.pri.kind.num_nodes(), 0.0);
        self.sec
            .kind
            .shape_and_grad_at(xi_s, &mut scratch.n1, &mut scratch.dn1);
        self.pri.kind.shape(xi_m, &mut scratch.n2);
        let (t1, t2) = tangents_from_grad(self.sec.x, &scratch.dn1);
        normal_from_tangents(t1, t2).1
    }
}

/// The unit normal of a face at the centre of a sub-segment, if defined.
fn sub_segment_normal(face: &FaceGeom, seg: &SubSegment) -> Option<Vec3> {
    let (n, jac) = face_normal(face.kind, face.x, seg.centre());
    (jac > 0.0 && n.iter().all(|v| v.is_finite())).then_some(n)
}

/// The primary sub-segments of a face with their normals (see [`PrimarySub`]).
pub(super) fn primary_subs<'s>(pri: &FaceGeom, segments: &'s [SubSegment]) -> Vec<PrimarySub<'s>> {
    segments
        .iter()
        .map(|seg| PrimarySub {
            seg,
            normal: sub_segment_normal(pri, seg),
        })
        .collect()
}

/// Integrates one secondary face against one primary face (see the module docs), adding the
/// rejections and integrated sub-segment pairs to `stats`.
///
/// # Panics
/// If a face's `x.len()` differs from its type's number of nodes.
pub fn integrate_pair(
    sec: &FaceGeom,
    pri: &FaceGeom,
    opts: &IntegrationOptions,
    stats: &mut RejectStats,
) -> PairWeights {
    assert_eq!(
        sec.x.len(),
        sec.kind.num_nodes(),
        "integrate_pair: secondary"
    );
    assert_eq!(pri.x.len(), pri.kind.num_nodes(), "integrate_pair: primary");
    let traction_count = traction_node_count(sec.kind, opts.scheme);
    let mut total = Accumulator::new(traction_count, sec.kind.num_nodes(), pri.kind.num_nodes());
    if !is_finite_face(sec) || !is_finite_face(pri) {
        stats.non_finite += 1;
        return total.into_weights();
    }
    let context = PairContext {
        sec,
        pri,
        scheme: opts.scheme,
        rule: FaceType::Tri3.quadrature(opts.degree),
        pallets: opts.pallets,
    };
    let mut scratch = Scratch::default();
    let mut pair_acc = Accumulator::new(traction_count, sec.kind.num_nodes(), pri.kind.num_nodes());
    let pri_segments = sub_segments(pri.kind);
    let primaries = primary_subs(pri, &pri_segments);
    for s_seg in &sub_segments(sec.kind) {
        let Some(plane) = Plane::of_sub_segment(sec.kind, sec.x, s_seg) else {
            stats.non_convex += pri_segments.len();
            continue;
        };
        for primary in &primaries {
            pair_acc.clear();
            let outcome = match overlap_of_sub_pair(sec, pri, &plane, s_seg, primary) {
                Ok(overlap) => {
                    match context.integrate_overlap(&overlap, &mut pair_acc, &mut scratch) {
                        Ok(()) => SubPairOutcome::Integrated {
                            points: pair_acc.points,
                        },
                        Err(failure) => SubPairOutcome::Failed(failure),
                    }
                }
                Err(outcome) => outcome,
            };
            if let SubPairOutcome::Integrated { .. } = outcome {
                total.merge(&pair_acc);
            }
            stats.record(&outcome);
        }
    }
    total.into_weights()
}

/// What became of one sub-segment pair.
pub(super) enum SubPairOutcome {
    /// Integrated with this many quadrature points.
    Integrated {
        points: usize,
    },
    NormalsNotOpposed,
    NonConvex,
    NoOverlap,
    Sliver,
    Failed(PairFailure),
}

/// A primary sub-segment and its unit normal at its centre (`None` if degenerate).
pub(super) struct PrimarySub<'s> {
    pub(super) seg: &'s SubSegment,
    normal: Option<Vec3>,
}

/// The float geometry of a sub-segment pair whose projections overlap (steps 2 and 3 of the
/// module docs).
pub(super) struct Overlap<'s> {
    /// The projected secondary sub-segment (counter-clockwise).
    pub(super) s: Projected<'s>,
    /// The projected primary sub-segment, in its own vertex order (clockwise).
    pub(super) m: Projected<'s>,
    /// The clipped overlap, counter-clockwise.
    pub(super) polygon: Vec<Point>,
    /// The provenance of each vertex of `polygon`: [`VertexOrigin::First`] indexes the vertices
    /// of `s`, [`VertexOrigin::Second`] those of `m` (both in their sub-segment's vertex order).
    pub(super) origins: Vec<VertexOrigin>,
}

/// Steps 2 and 3 of the module docs for one sub-segment pair: the projected sub-segments and
/// their overlap, or why the pair is not integrated.
pub(super) fn overlap_of_sub_pair<'s>(
    sec: &FaceGeom,
    pri: &FaceGeom,
    plane: &Plane,
    s_seg: &'s SubSegment,
    primary: &PrimarySub<'s>,
) -> Result<Overlap<'s>, SubPairOutcome> {
    let m_seg = primary.seg;
    let Some(m_normal) = primary.normal else {
        return Err(SubPairOutcome::NonConvex);
    };
    if dot(m_normal, plane.normal) > -OPPOSED_NORMALS_COSINE {
        return Err(SubPairOutcome::NormalsNotOpposed);
    }
    let s_poly = plane.project_sub_segment(sec, s_seg, false);
    let m_reversed = plane.project_sub_segment(pri, m_seg, true);
    let scale = diameter(&s_poly);
    if !is_convex_ccw(&s_poly, scale) || !is_convex_ccw(&m_reversed, scale) {
        return Err(SubPairOutcome::NonConvex);
    }
    if bounding_boxes_disjoint(&s_poly, &m_reversed) {
        return Err(SubPairOutcome::NoOverlap);
    }
    let (polygon, origins) = match clip_convex_traced(&s_poly, &m_reversed, scale) {
        (Clipped::Polygon(p), origins) => (p, origins),
        (Clipped::Empty, _) => return Err(SubPairOutcome::NoOverlap),
        (Clipped::Sliver, _) => return Err(SubPairOutcome::Sliver),
    };
    let last = m_reversed.len() - 1;
    let unreversed = |r: usize| last - r;
    let origins = origins
        .into_iter()
        .map(|o| match o {
            VertexOrigin::Second(r) => VertexOrigin::Second(unreversed(r)),
            VertexOrigin::Crossing { first, second } => VertexOrigin::Crossing {
                first,
                second: second.map(unreversed),
            },
            other => other,
        })
        .collect();
    let mut m_poly = m_reversed;
    m_poly.reverse();
    Ok(Overlap {
        s: Projected::new(s_poly, s_seg, 1.0),
        m: Projected::new(m_poly, m_seg, -1.0),
        polygon,
        origins,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::mortar::segments::traction_nodes;
    use crate::contact::mortar::test_support::{settings, SCHEMES};

    /// A surface mesh: node positions and faces as lists of global node ids in face order.
    struct Mesh {
        kind: FaceType,
        nodes: Vec<Vec3>,
        faces: Vec<Vec<usize>>,
    }

    impl Mesh {
        fn face(&self, f: usize) -> Vec<Vec3> {
            self.faces[f].iter().map(|&a| self.nodes[a]).collect()
        }
    }

    /// A structured `nu x nv` mesh of `kind` faces over the parameter square `[0, 1]^2` mapped by
    /// `map`. Nodes sit on the half-step grid `(i / 2nu, j / 2nv)` (so mid-edge and centre nodes
    /// lie on the mapped surface); each cell is one quad or two triangles. Faces are
    /// counter-clockwise in `(u, v)`, or clockwise if `flip` (normal `-x_,u x x_,v`).
    fn grid(
        kind: FaceType,
        nu: usize,
        nv: usize,
        flip: bool,
        map: &dyn Fn(f64, f64) -> Vec3,
    ) -> Mesh {
        let row = 2 * nu + 1;
        let mut nodes = Vec::new();
        for j in 0..=2 * nv {
            for i in 0..row {
                nodes.push(map(i as f64 / (2 * nu) as f64, j as f64 / (2 * nv) as f64));
            }
        }
        let id = |p: [usize; 2]| p[0] + row * p[1];
        let mut faces = Vec::new();
        for cj in 0..nv {
            for ci in 0..nu {
                let c = [
                    [2 * ci, 2 * cj],
                    [2 * ci + 2, 2 * cj],
                    [2 * ci + 2, 2 * cj + 2],
                    [2 * ci, 2 * cj + 2],
                ];
                let mut corner_lists = if kind.is_quad() {
                    vec![vec![c[0], c[1], c[2], c[3]]]
                } else {
                    vec![vec![c[0], c[1], c[2]], vec![c[0], c[2], c[3]]]
                };
                for corners in &mut corner_lists {
                    if flip {
                        corners[1..].reverse();
                    }
                    let nc = corners.len();
                    let mut face: Vec<[usize; 2]> = corners.clone();
                    if kind.num_nodes() > nc {
                        for k in 0..nc {
                            let (a, b) = (corners[k], corners[(k + 1) % nc]);
                            face.push([(a[0] + b[0]) / 2, (a[1] + b[1]) / 2]);
                        }
                    }
                    if kind == FaceType::Quad9 {
                        face.push([2 * ci + 1, 2 * cj + 1]);
                    }
                    faces.push(face.into_iter().map(id).collect());
                }
            }
        }
        Mesh { kind, nodes, faces }
    }

    /// Sums over all face pairs, by global secondary node `A` (a traction node).
    struct Totals {
        /// `sum_B n1_AB` and `sum_C n2_AC`.
        a1: Vec<f64>,
        a2: Vec<f64>,
        /// `sum_B n1_AB f(x_B)` and `sum_C n2_AC f(x_C)` for a linear `f`.
        f1: Vec<f64>,
        f2: Vec<f64>,
        /// Sum of all `n1`, and of the pairs' `area`.
        n1_total: f64,
        area: f64,
        stats: RejectStats,
    }

    fn linear_field(x: Vec3) -> f64 {
        0.7 + 1.3 * x[0] - 2.1 * x[1] + 0.4 * x[2]
    }

    /// Axis-aligned box overlap of two faces' nodes inflated by `margin` (a stand-in for the
    /// rough search, to keep the double loop fast).
    fn boxes_overlap(a: &[Vec3], b: &[Vec3], margin: f64) -> bool {
        (0..3).all(|d| {
            let lo = |p: &[Vec3]| p.iter().map(|x| x[d]).fold(f64::INFINITY, f64::min);
            let hi = |p: &[Vec3]| p.iter().map(|x| x[d]).fold(f64::NEG_INFINITY, f64::max);
            lo(a) <= hi(b) + margin && lo(b) <= hi(a) + margin
        })
    }

    fn integrate_meshes(sec: &Mesh, pri: &Mesh, scheme: TractionScheme) -> Totals {
        integrate_meshes_split(sec, pri, scheme, PalletSplit::default())
    }

    fn integrate_meshes_split(
        sec: &Mesh,
        pri: &Mesh,
        scheme: TractionScheme,
        pallets: PalletSplit,
    ) -> Totals {
        let opts = IntegrationOptions {
            pallets,
            ..IntegrationOptions::for_faces(scheme, sec.kind, pri.kind)
        };
        let n = sec.nodes.len();
        let mut t = Totals {
            a1: vec![0.0; n],
            a2: vec![0.0; n],
            f1: vec![0.0; n],
            f2: vec![0.0; n],
            n1_total: 0.0,
            area: 0.0,
            stats: RejectStats::default(),
        };
        let traction = traction_nodes(sec.kind, scheme).unwrap();
        for (fs, sec_nodes) in sec.faces.iter().enumerate() {
            let xs = sec.face(fs);
            for (fp, pri_nodes) in pri.faces.iter().enumerate() {
                let xp = pri.face(fp);
                if !boxes_overlap(&xs, &xp, 0.1) {
                    continue;
                }
                let w = integrate_pair(
                    &FaceGeom {
                        kind: sec.kind,
                        x: &xs,
                    },
                    &FaceGeom {
                        kind: pri.kind,
                        x: &xp,
                    },
                    &opts,
                    &mut t.stats,
                );
                for &(k, b, v) in &w.n1 {
                    let a = sec_nodes[traction[k]];
                    t.a1[a] += v;
                    t.f1[a] += v * linear_field(sec.nodes[sec_nodes[b]]);
                    t.n1_total += v;
                }
                for &(k, c, v) in &w.n2 {
                    let a = sec_nodes[traction[k]];
                    t.a2[a] += v;
                    t.f2[a] += v * linear_field(pri.nodes[pri_nodes[c]]);
                }
                t.area += w.area;
            }
        }
        t
    }

    fn max_difference(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    /// A tilted, sheared flat interface: `x = o + u a + v b`, area `|a x b|`.
    const ORIGIN: Vec3 = [0.3, -0.2, 0.5];
    const EDGE_A: Vec3 = [1.0, 0.2, 0.3];
    const EDGE_B: Vec3 = [0.25, 0.9, -0.4];

    fn flat_map(gap: f64) -> impl Fn(f64, f64) -> Vec3 {
        let n = normalized(cross(EDGE_A, EDGE_B)).unwrap();
        move |u, v| std::array::from_fn(|d| ORIGIN[d] + u * EDGE_A[d] + v * EDGE_B[d] + gap * n[d])
    }

    /// Flat interface, every pair of face types, every allowed scheme, coincident (3x3 on 3x3)
    /// and non-matching (3x3 against 4x5, with a gap) meshes: the total of n1 is the interface
    /// area (1e-12), momentum `sum_B n1_AB = sum_C n2_AC` for every traction node (1e-12), and the
    /// patch-test identity `sum_B n1_AB f(x_B) = sum_C n2_AC f(x_C)` for a linear `f` (1e-12);
    /// with either pallet split.
    #[test]
    fn flat_interfaces_of_all_face_types() {
        let area = dot(cross(EDGE_A, EDGE_B), cross(EDGE_A, EDGE_B)).sqrt();
        let normal = normalized(cross(EDGE_A, EDGE_B)).unwrap();
        let normal_slope = linear_field(normal) - linear_field([0.0; 3]);
        for sec_kind in FaceType::ALL {
            for pri_kind in FaceType::ALL {
                for (nu, nv, gap) in [(3, 3, 0.0), (4, 5, 0.01)] {
                    let sec = grid(sec_kind, 3, 3, false, &flat_map(0.0));
                    let pri = grid(pri_kind, nu, nv, true, &flat_map(gap));
                    for (scheme, split) in settings(sec_kind) {
                        let what = format!(
                            "{sec_kind:?} on {pri_kind:?} {nu}x{nv} {scheme:?} {split:?} pallets"
                        );
                        let t = integrate_meshes_split(&sec, &pri, scheme, split);
                        assert!((t.n1_total - area).abs() < 1e-12, "{what}: {}", t.n1_total);
                        assert!((t.area - area).abs() < 1e-12, "{what}: {}", t.area);
                        let momentum = max_difference(&t.a1, &t.a2);
                        assert!(momentum < 1e-12, "{what}: momentum {momentum}");
                        // The primary lies `gap` further along the normal n: f(x2) = f(x1) + gap
                        // grad f . n, so the identity is sum n1 f(x_B) = sum n2 f(x_C) - gap
                        // (grad f . n) a_A.
                        let shifted: Vec<f64> = (0..t.f2.len())
                            .map(|a| t.f2[a] - gap * normal_slope * t.a1[a])
                            .collect();
                        let patch = max_difference(&t.f1, &shifted);
                        assert!(patch < 1e-12, "{what}: patch {patch}");
                        let s = &t.stats;
                        assert_eq!(
                            (s.non_convex, s.inverse_map_failed, s.non_finite, s.sliver),
                            (0, 0, 0, 0),
                            "{what}: {s:?}"
                        );
                        assert!(s.pairs_integrated > 0);
                    }
                }
            }
        }
    }

    /// Cylinder `r = R`, `theta` in `[-1/2, 1/2]`, `y` in `[0, 1]`: outward normal `e_r` for
    /// `(u, v) -> (theta, y)` counter-clockwise.
    const RADIUS: f64 = 1.5;

    fn cylinder(u: f64, v: f64) -> Vec3 {
        let theta = u - 0.5;
        [RADIUS * theta.sin(), v, RADIUS * theta.cos()]
    }

    /// Area of a mesh by a high-degree rule on every face (the isoparametric area).
    fn mesh_area(mesh: &Mesh) -> f64 {
        let rule = mesh.kind.quadrature(10);
        (0..mesh.faces.len())
            .map(|f| {
                let x = mesh.face(f);
                rule.points
                    .iter()
                    .zip(&rule.weights)
                    .map(|(p, w)| w * face_normal(mesh.kind, &x, *p).1)
                    .sum::<f64>()
            })
            .sum()
    }

    /// Curved interface (a cylinder patch, quadratic faces with mid-nodes on the cylinder,
    /// secondary 3x3 and primary 4x5 of other types): momentum per traction node to 1e-12. The
    /// total area equals the isoparametric area of the secondary mesh to 1e-10 plus 1e-8 per
    /// dropped sliver (the primary covers it exactly: its boundary projects onto the same lines;
    /// on a curved interface small genuine overlaps below 1e-8 scale^2 occur and are dropped by
    /// design), and that area is the exact cylinder area R * 1 * 1 to the interpolation error of
    /// the faces (1e-4 for quadratic, 1e-2 for linear faces).
    #[test]
    fn curved_interface_conserves_momentum() {
        use FaceType::*;
        let cases = [
            (Quad9, Quad8),
            (Quad8, Tri6),
            (Tri6, Quad9),
            (Quad9, Tri6),
            (Quad4, Tri3),
            (Tri3, Quad9),
        ];
        for (sec_kind, pri_kind) in cases {
            let sec = grid(sec_kind, 3, 3, false, &cylinder);
            let pri = grid(pri_kind, 4, 5, true, &cylinder);
            let iso_area = mesh_area(&sec);
            let geometry_tol = if matches!(sec_kind, Quad4 | Tri3) {
                1e-2
            } else {
                1e-4
            };
            assert!(
                (iso_area - RADIUS).abs() < geometry_tol,
                "{sec_kind:?}: {iso_area}"
            );
            for (scheme, split) in settings(sec_kind) {
                let what = format!("{sec_kind:?} on {pri_kind:?} {scheme:?} {split:?} pallets");
                let t = integrate_meshes_split(&sec, &pri, scheme, split);
                let momentum = max_difference(&t.a1, &t.a2);
                assert!(momentum < 1e-12, "{what}: momentum {momentum}");
                // Each dropped sliver loses less than 1e-8 scale^2 (scale < 1 here).
                let area_tol = 1e-10 + 1e-8 * t.stats.sliver as f64;
                assert!(
                    (t.n1_total - iso_area).abs() < area_tol,
                    "{what}: {} vs {iso_area}, {:?}",
                    t.n1_total,
                    t.stats
                );
                let s = &t.stats;
                assert_eq!(
                    (s.non_convex, s.inverse_map_failed, s.non_finite),
                    (0, 0, 0),
                    "{what}: {s:?}"
                );
            }
        }
    }

    /// A parallelogram in a tilted plane and the same face reversed as primary, scheme 1 on
    /// Quad4: n1 and n2 are the consistent mass matrix `A/9, A/18, A/36` (diagonal, adjacent,
    /// opposite) to 1e-13.
    #[test]
    fn coincident_quad4_gives_the_consistent_mass() {
        let map = flat_map(0.0);
        let sec_x: Vec<Vec3> = [[0.0, 0.0], [2.0, 0.0], [2.5, 0.5], [0.5, 0.5]]
            .iter()
            .map(|p| map(p[0], p[1]))
            .collect();
        let perm = [0, 3, 2, 1];
        let pri_x: Vec<Vec3> = perm.iter().map(|&a| sec_x[a]).collect();
        let area = 2.0 * 0.5 * dot(cross(EDGE_A, EDGE_B), cross(EDGE_A, EDGE_B)).sqrt();
        let mass = |a: usize, b: usize| match (a + 4 - b) % 4 {
            0 => area / 9.0,
            2 => area / 36.0,
            _ => area / 18.0,
        };
        let opts = IntegrationOptions::for_faces(
            TractionScheme::FaceShape,
            FaceType::Quad4,
            FaceType::Quad4,
        );
        let mut stats = RejectStats::default();
        let w = integrate_pair(
            &FaceGeom {
                kind: FaceType::Quad4,
                x: &sec_x,
            },
            &FaceGeom {
                kind: FaceType::Quad4,
                x: &pri_x,
            },
            &opts,
            &mut stats,
        );
        assert_eq!(w.n1.len(), 16);
        assert_eq!(w.n2.len(), 16);
        for &(k, b, v) in &w.n1 {
            assert!((v - mass(k, b)).abs() < 1e-13, "n1[{k}][{b}] = {v}");
        }
        for &(k, c, v) in &w.n2 {
            assert!((v - mass(k, perm[c])).abs() < 1e-13, "n2[{k}][{c}] = {v}");
        }
        assert!((w.area - area).abs() < 1e-13);
        assert_eq!(stats.pairs_integrated, 1);
    }

    /// Scheme 1 on a Quad9 face against a coincident primary: `a_A = sum_B n1_AB` are the
    /// integrals of the Quad9 functions, `A/36, A/9, 4A/9` (corner, mid-edge, centre), all positive.
    #[test]
    fn quad9_face_shape_weights() {
        let sec = grid(FaceType::Quad9, 1, 1, false, &flat_map(0.0));
        let pri = grid(FaceType::Quad4, 1, 1, true, &flat_map(0.0));
        let t = integrate_meshes(&sec, &pri, TractionScheme::FaceShape);
        let area = dot(cross(EDGE_A, EDGE_B), cross(EDGE_A, EDGE_B)).sqrt();
        for (local, &a) in sec.faces[0].iter().enumerate() {
            let expected = area
                * [1.0 / 36.0, 1.0 / 9.0, 4.0 / 9.0][(local >= 4) as usize + (local == 8) as usize];
            assert!(
                (t.a1[a] - expected).abs() < 1e-13,
                "node {local}: {}",
                t.a1[a]
            );
        }
    }

    /// The chain-rule measure: a doubly curved Quad9 face (on a sphere, with in-plane distorted
    /// mid-nodes) fully covered by one large flat primary face gets `sum n1 =` its isoparametric
    /// area (1e-10), though no sub-segment is planar.
    #[test]
    fn curved_face_area_is_its_isoparametric_area() {
        let sphere = |u: f64, v: f64| {
            let (theta, phi) = (0.6 * (u - 0.5) + 0.05 * (v - 0.5), 0.5 * (v - 0.5));
            [
                2.0 * theta.sin() * phi.cos(),
                2.0 * phi.sin(),
                2.0 * theta.cos() * phi.cos(),
            ]
        };
        let distorted = |u: f64, v: f64| sphere(u + 0.08 * u * (1.0 - u), v);
        let sec = grid(FaceType::Quad9, 1, 1, false, &distorted);
        let plane = |u: f64, v: f64| [4.0 * (u - 0.5), 4.0 * (v - 0.5), 2.05];
        let pri = grid(FaceType::Quad4, 1, 1, true, &plane);
        for scheme in SCHEMES {
            let t = integrate_meshes(&sec, &pri, scheme);
            let iso = mesh_area(&sec);
            assert!(
                (t.n1_total - iso).abs() < 1e-10,
                "{scheme:?}: {} vs {iso}",
                t.n1_total
            );
            assert!(max_difference(&t.a1, &t.a2) < 1e-13);
            assert_eq!(t.stats.pairs_integrated, 4);
        }
    }

    fn unit_square(kind: FaceType, z: f64, shift: [f64; 2], flip: bool) -> Vec<Vec3> {
        let map = move |u: f64, v: f64| [u + shift[0], v + shift[1], z];
        let mesh = grid(kind, 1, 1, flip, &map);
        mesh.face(0)
    }

    fn integrate_quad4(sec_x: &[Vec3], pri_x: &[Vec3]) -> (PairWeights, RejectStats) {
        let opts = IntegrationOptions::for_faces(
            TractionScheme::Corners,
            FaceType::Quad4,
            FaceType::Quad4,
        );
        let mut stats = RejectStats::default();
        let w = integrate_pair(
            &FaceGeom {
                kind: FaceType::Quad4,
                x: sec_x,
            },
            &FaceGeom {
                kind: FaceType::Quad4,
                x: pri_x,
            },
            &opts,
            &mut stats,
        );
        let all = w.n1.iter().chain(&w.n2).map(|e| e.2).chain([w.area]);
        assert!(all.into_iter().all(f64::is_finite), "{w:?}");
        (w, stats)
    }

    #[test]
    fn rejections_are_counted() {
        let sec = unit_square(FaceType::Quad4, 0.0, [0.0, 0.0], false);
        // The primary facing the same way.
        let (w, s) = integrate_quad4(&sec, &unit_square(FaceType::Quad4, 0.0, [0.2, 0.1], false));
        assert_eq!((s.normals_not_opposed, s.pairs_integrated), (1, 0));
        assert!(w.n1.is_empty() && w.n2.is_empty() && w.area == 0.0);
        // Disjoint.
        let (w, s) = integrate_quad4(&sec, &unit_square(FaceType::Quad4, 0.0, [5.0, 0.0], true));
        assert_eq!((s.no_overlap, s.pairs_integrated), (1, 0));
        assert!(w.n1.is_empty());
        // Separated by 1e-9 along the normal: integrated in full.
        let (w, s) = integrate_quad4(&sec, &unit_square(FaceType::Quad4, 1e-9, [0.0, 0.0], true));
        assert_eq!(s.pairs_integrated, 1);
        assert!((w.area - 1.0).abs() < 1e-13);
        // Overlapping by a strip 1e-9 wide: a sliver.
        let (w, s) = integrate_quad4(
            &sec,
            &unit_square(FaceType::Quad4, 0.0, [1.0 - 1e-9, 0.0], true),
        );
        assert_eq!((s.sliver, s.pairs_integrated), (1, 0));
        assert_eq!(w.area, 0.0);
        // Apart by 1e-9 in the plane, and touching along an edge or at a corner.
        for shift in [[1.0 + 1e-9, 0.0], [1.0, 0.0], [1.0, 1.0], [-1.0, 0.3]] {
            let (w, s) = integrate_quad4(&sec, &unit_square(FaceType::Quad4, 0.0, shift, true));
            assert_eq!(s.pairs_integrated, 0, "{shift:?}");
            assert_eq!(s.no_overlap + s.sliver, 1, "{shift:?}");
            assert_eq!(w.area, 0.0);
        }
        // A primary whose projection is a dart (non-convex).
        let dart = [
            [0.0, 0.0, 0.1],
            [1.0, 0.2, 0.1],
            [0.3, 0.3, 0.1],
            [0.2, 1.0, 0.1],
        ];
        let reversed: Vec<Vec3> = dart.iter().rev().copied().collect();
        let (w, s) = integrate_quad4(&sec, &reversed);
        assert_eq!((s.non_convex, s.pairs_integrated), (1, 0));
        assert_eq!(w.area, 0.0);
        // A collapsed secondary face, and a NaN coordinate.
        let point = [[0.5, 0.5, 0.0]; 4];
        let pri = unit_square(FaceType::Quad4, 0.0, [0.0, 0.0], true);
        let (_, s) = integrate_quad4(&point, &pri);
        assert_eq!((s.non_convex, s.pairs_integrated), (1, 0));
        let mut nan = pri.clone();
        nan[2][1] = f64::NAN;
        let (w, s) = integrate_quad4(&sec, &nan);
        assert_eq!((s.non_finite, s.pairs_integrated), (1, 0));
        assert!(w.n1.is_empty());
        // Counts add up and are named.
        let mut total = RejectStats::default();
        total.add(&s);
        total.add(&s);
        assert_eq!(total.to_map()["non_finite"], 2);
        assert_eq!(total.to_map().len(), 8);
    }

    /// Quadratic faces touching along an edge, or offset by 1e-9 along the normal or in the
    /// plane: finite weights, nothing integrated or the full overlap. The in-plane offset leaves
    /// strips 1e-9 wide between parallel sub-segment edges (area 5e-10 < 1e-8 scale^2): they are
    /// counted as slivers and dropped, losing 1e-9 of area.
    #[test]
    fn quadratic_faces_near_degenerate() {
        let opts = IntegrationOptions::for_faces(
            TractionScheme::PiecewiseLinear,
            FaceType::Quad9,
            FaceType::Tri6,
        );
        for (shift, z, expected_area, slivers) in [
            ([1.0, 0.0], 0.0, 0.0, false),
            ([0.0, 0.0], 1e-9, 1.0, false),
            ([1e-9, 0.0], 0.0, 1.0 - 2e-9, true),
        ] {
            let sec = unit_square(FaceType::Quad9, 0.0, [0.0, 0.0], false);
            let pri_mesh = grid(FaceType::Tri6, 1, 1, true, &move |u, v| {
                [u + shift[0], v + shift[1], z]
            });
            let mut stats = RejectStats::default();
            let mut area = 0.0;
            for f in 0..pri_mesh.faces.len() {
                let pri = pri_mesh.face(f);
                let w = integrate_pair(
                    &FaceGeom {
                        kind: FaceType::Quad9,
                        x: &sec,
                    },
                    &FaceGeom {
                        kind: FaceType::Tri6,
                        x: &pri,
                    },
                    &opts,
                    &mut stats,
                );
                assert!(w.n1.iter().chain(&w.n2).all(|e| e.2.is_finite()));
                area += w.area;
            }
            assert!(
                (area - expected_area).abs() < 1e-12,
                "{shift:?} {z}: {area}"
            );
            assert_eq!(stats.sliver > 0, slivers, "{stats:?}");
            assert_eq!(
                (stats.non_convex, stats.inverse_map_failed, stats.non_finite),
                (0, 0, 0)
            );
        }
    }

    /// A rigid motion of both faces leaves the weights unchanged (1e-13).
    #[test]
    fn weights_are_frame_indifferent() {
        let sec = grid(FaceType::Quad9, 1, 1, false, &cylinder).face(0);
        let pri_mesh = grid(FaceType::Tri6, 2, 2, true, &|u, v| {
            cylinder(0.8 * u + 0.1, 0.7 * v + 0.2)
        });
        let (s, c) = (0.7f64.sin(), 0.7f64.cos());
        let motion = |x: &Vec3| {
            let r = [c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]];
            let (s2, c2) = (0.3f64.sin(), 0.3f64.cos());
            [
                r[0] + 3.0,
                c2 * r[1] - s2 * r[2] - 1.0,
                s2 * r[1] + c2 * r[2] + 2.0,
            ]
        };
        let opts =
            IntegrationOptions::for_faces(TractionScheme::Corners, FaceType::Quad9, FaceType::Tri6);
        for f in 0..pri_mesh.faces.len() {
            let pri = pri_mesh.face(f);
            let (sec_m, pri_m): (Vec<Vec3>, Vec<Vec3>) = (
                sec.iter().map(motion).collect(),
                pri.iter().map(motion).collect(),
            );
            let mut stats = RejectStats::default();
            let w0 = integrate_pair(
                &FaceGeom {
                    kind: FaceType::Quad9,
                    x: &sec,
                },
                &FaceGeom {
                    kind: FaceType::Tri6,
                    x: &pri,
                },
                &opts,
                &mut stats,
            );
            let w1 = integrate_pair(
                &FaceGeom {
                    kind: FaceType::Quad9,
                    x: &sec_m,
                },
                &FaceGeom {
                    kind: FaceType::Tri6,
                    x: &pri_m,
                },
                &opts,
                &mut stats,
            );
            assert!(w0.area > 0.0);
            assert_eq!(w0.n1.len(), w1.n1.len());
            for (a, b) in w0.n1.iter().chain(&w0.n2).zip(w1.n1.iter().chain(&w1.n2)) {
                assert_eq!((a.0, a.1), (b.0, b.1));
                assert!((a.2 - b.2).abs() < 1e-13, "{a:?} vs {b:?}");
            }
        }
    }
}
