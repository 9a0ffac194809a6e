//! The walk both kernels share: every sub-segment pair of a face pair, the overlap of its
//! projections, and the pallets the overlap is integrated on (docs/theory.md section 3).
//!
//! The value kernel ([`super::pair`]: the weights) and the linearized kernel
//! ([`super::linearize`]: the weights and their derivatives) integrate a face pair the same way
//! up to the quadrature points. This module is that common part, so that both see the same
//! sub-segment pairs, rejections, overlap polygons and pallets; each kernel supplies only what
//! it does at the points (`SubPairKernel`).
//!
//! # The walk (`walk_sub_pairs`)
//!
//! 1. **Sub-segments.** Both faces are split into their linear sub-segments
//!    ([`sub_segments`]); every pair `(s, m)` of a secondary and a primary sub-segment is
//!    integrated on its own. Each secondary sub-segment gets its projection plane (normal `n_c`,
//!    [`super::projection`]); one without a plane (a degenerate face) has all its pairs counted
//!    as [`RejectStats::non_convex`].
//! 2. **Project.** `m` whose normal (geometric, at its centre) does not oppose `n_c`
//!    (`n_m . n_c > -`[`OPPOSED_NORMALS_COSINE`]) is rejected
//!    ([`RejectStats::normals_not_opposed`]). The vertices of `s` and `m` are projected onto the
//!    plane. `s` comes out counter-clockwise (its normal is about `n_c`); `m` faces the other way,
//!    so its vertex order is reversed for the clipping to make it counter-clockwise too. A
//!    projected sub-segment that is not convex with positive area (a warped or folded quad, a
//!    degenerate face) is rejected ([`RejectStats::non_convex`]).
//! 3. **Clip** ([`clip_convex_traced`], which also records where each overlap vertex comes from)
//!    with the tolerances relative to the size of `s` (the largest distance between its
//!    projected vertices): no overlap ([`RejectStats::no_overlap`], also for disjoint bounding
//!    boxes) or a sliver ([`RejectStats::sliver`]) are counted and skipped. The provenance is
//!    given in `m`'s own vertex order (the overlap, `Overlap`).
//! 4. **Pallets.** The overlap is split into pallets (`pallets_of`): the triangles
//!    `(c, p_i, p_j)` of the apex `c` of the [`PalletSplit`] with the polygon edges `(i, j)` it
//!    names, those of positive area `det [u v] / 2`, `u = p_i - c`, `v = p_j - c`. On each, the
//!    kernel runs the unit-triangle rule `FaceType::Tri3.quadrature(degree)` mapped affinely:
//!    the point `P = c + q_0 u + q_1 v` of the rule's point `q`, with the weight
//!    `w_q det [u v]`. It maps each point back onto both projected sub-segments
//!    (`Overlap::locate`, [`super::projection`]) and integrates there.
//!
//! A sub-segment pair is added to the face pair's result only if every one of its points was
//! mapped back and evaluated to finite values; otherwise the kernel skips it whole
//! (`PairFailure`), and it is counted ([`RejectStats::inverse_map_failed`] or
//! [`RejectStats::non_finite`]), so the momentum identity holds also for what is kept.
//!
//! # Counting
//!
//! Every counter of [`RejectStats`] counts **sub-segment pairs** (a Quad9 against a Quad9 is 16
//! of them), except [`RejectStats::non_finite`], which counts face pairs with a non-finite node
//! coordinate plus sub-segment pairs with a non-finite intermediate value. Rejections are never
//! fatal here; a caller should stop the step on `non_finite > 0` (docs/theory.md section 10).

use std::collections::BTreeMap;

use super::clip::{clip_convex_traced, is_convex_ccw, Clipped, PalletSplit, Point, VertexOrigin};
use super::projection::{det2, LocalPoint, Plane, Projected};
use super::segments::{sub_segments, SubSegment, TractionScheme};
use crate::fe::shape::Scalar;
use crate::fe::{face_normal, FaceType};
use crate::vec3::{dot, Vec3};

/// A primary sub-segment is integrated only if its normal `n_m` satisfies
/// `n_m . n_c <= -OPPOSED_NORMALS_COSINE` (the normals are more than about 84 degrees apart).
pub const OPPOSED_NORMALS_COSINE: f64 = 0.1;

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

    /// The names of the counts, in the order of [`RejectStats::counts`].
    pub const NAMES: [&'static str; 8] = [
        "normals_not_opposed",
        "non_convex",
        "no_overlap",
        "sliver",
        "inverse_map_failed",
        "non_finite",
        "pairs_integrated",
        "quadrature_points",
    ];

    /// The counts, in the order of [`RejectStats::NAMES`].
    pub fn counts(&self) -> [usize; 8] {
        [
            self.normals_not_opposed,
            self.non_convex,
            self.no_overlap,
            self.sliver,
            self.inverse_map_failed,
            self.non_finite,
            self.pairs_integrated,
            self.quadrature_points,
        ]
    }

    /// The statistics of `counts` (in the order of [`RejectStats::NAMES`]).
    pub fn from_counts(c: [usize; 8]) -> RejectStats {
        RejectStats {
            normals_not_opposed: c[0],
            non_convex: c[1],
            no_overlap: c[2],
            sliver: c[3],
            inverse_map_failed: c[4],
            non_finite: c[5],
            pairs_integrated: c[6],
            quadrature_points: c[7],
        }
    }

    /// The counts by name (the field names), for summaries.
    pub fn to_map(&self) -> BTreeMap<String, usize> {
        Self::NAMES
            .iter()
            .zip(self.counts())
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
fn is_finite_face(face: &FaceGeom) -> bool {
    face.x.iter().flatten().all(|v| v.is_finite())
}

/// Panics unless each face has its type's number of nodes (`kernel` names the caller).
pub(super) fn assert_node_counts(sec: &FaceGeom, pri: &FaceGeom, kernel: &str) {
    assert_eq!(sec.x.len(), sec.kind.num_nodes(), "{kernel}: secondary");
    assert_eq!(pri.x.len(), pri.kind.num_nodes(), "{kernel}: primary");
}

/// What a kernel does with the sub-segment pairs the walk finds (module docs): the value kernel
/// of [`super::pair`] and the linearized kernel of [`super::linearize`].
pub(super) trait SubPairKernel {
    /// A secondary sub-segment that has a projection plane; its pairs follow.
    fn start_secondary(&mut self, _seg: &SubSegment) {}

    /// Integrates the overlap of one sub-segment pair: [`SubPairOutcome::Integrated`] if it was
    /// added to the face pair's result, [`SubPairOutcome::Failed`] (and nothing added) otherwise.
    fn integrate(&mut self, overlap: &Overlap) -> SubPairOutcome;
}

/// Runs `kernel` on every overlapping sub-segment pair of `sec` against `pri` and counts what
/// became of every sub-segment pair in `stats` (module docs). A face pair with a non-finite node
/// coordinate is counted once as [`RejectStats::non_finite`], and nothing is integrated.
pub(super) fn walk_sub_pairs(
    sec: &FaceGeom,
    pri: &FaceGeom,
    stats: &mut RejectStats,
    kernel: &mut impl SubPairKernel,
) {
    if !is_finite_face(sec) || !is_finite_face(pri) {
        stats.non_finite += 1;
        return;
    }
    let pri_segments = sub_segments(pri.kind);
    let primaries = primary_subs(pri, &pri_segments);
    for s_seg in &sub_segments(sec.kind) {
        let Some(plane) = Plane::of_sub_segment(sec.kind, sec.x, s_seg) else {
            stats.non_convex += pri_segments.len();
            continue;
        };
        kernel.start_secondary(s_seg);
        for primary in &primaries {
            let outcome = match overlap_of_sub_pair(sec, pri, &plane, s_seg, primary) {
                Ok(overlap) => kernel.integrate(&overlap),
                Err(outcome) => outcome,
            };
            stats.record(&outcome);
        }
    }
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

/// Why a sub-segment pair was not accumulated.
pub(super) enum PairFailure {
    InverseMap,
    NonFinite,
}

/// A primary sub-segment and its unit normal at its centre (`None` if degenerate).
struct PrimarySub<'s> {
    seg: &'s SubSegment,
    normal: Option<Vec3>,
}

/// The unit normal of a face at the centre of a sub-segment, if defined.
fn sub_segment_normal(face: &FaceGeom, seg: &SubSegment) -> Option<Vec3> {
    let (n, jac) = face_normal(face.kind, face.x, seg.centre());
    (jac > 0.0 && n.iter().all(|v| v.is_finite())).then_some(n)
}

/// The primary sub-segments of a face with their normals (see [`PrimarySub`]).
fn primary_subs<'s>(pri: &FaceGeom, segments: &'s [SubSegment]) -> Vec<PrimarySub<'s>> {
    segments
        .iter()
        .map(|seg| PrimarySub {
            seg,
            normal: sub_segment_normal(pri, seg),
        })
        .collect()
}

/// The float geometry of a sub-segment pair whose projections overlap (steps 2 and 3 of the
/// module docs): what a kernel integrates.
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
    /// The size of `s`, the largest distance between its projected vertices: the clipping's
    /// tolerances are relative to it.
    pub(super) scale: f64,
}

impl Overlap<'_> {
    /// The local coordinates of the plane point `p` on `s` and on `m`
    /// ([`super::projection`]), or the failure of either inverse map.
    pub(super) fn locate(&self, p: Point) -> Result<(LocalPoint, LocalPoint), PairFailure> {
        let on_s = self.s.invert(p).ok_or(PairFailure::InverseMap)?;
        let on_m = self.m.invert(p).ok_or(PairFailure::InverseMap)?;
        Ok((on_s, on_m))
    }
}

/// Steps 2 and 3 of the module docs for one sub-segment pair: the projected sub-segments and
/// their overlap, or why the pair is not integrated.
fn overlap_of_sub_pair<'s>(
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
    let s_poly = plane.project_vertices(sec.x, s_seg);
    let mut m_reversed = plane.project_vertices(pri.x, m_seg);
    m_reversed.reverse();
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
    let origins = unreversed(origins, m_reversed.len());
    let mut m_poly = m_reversed;
    m_poly.reverse();
    Ok(Overlap {
        s: Projected::new(s_poly, s_seg, 1.0),
        m: Projected::new(m_poly, m_seg, -1.0),
        polygon,
        origins,
        scale,
    })
}

/// The provenance `origins` of a clipping against the primary sub-segment's `count` vertices in
/// reversed order, with the primary vertices numbered in their own order again.
fn unreversed(origins: Vec<VertexOrigin>, count: usize) -> Vec<VertexOrigin> {
    let own = |r: usize| count - 1 - r;
    origins
        .into_iter()
        .map(|o| match o {
            VertexOrigin::Second(r) => VertexOrigin::Second(own(r)),
            VertexOrigin::Crossing { first, second } => VertexOrigin::Crossing {
                first,
                second: second.map(own),
            },
            other => other,
        })
        .collect()
}

/// Largest distance between two vertices.
fn diameter(p: &[Point]) -> f64 {
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

/// One pallet of an overlap polygon (module docs, step 4): the apex `c` and the edges
/// `u = p_i - c`, `v = p_j - c` to the ends of a polygon edge, for any [`Scalar`].
pub(super) struct Pallet<T = f64> {
    pub(super) apex: [T; 2],
    pub(super) u: [T; 2],
    pub(super) v: [T; 2],
    /// `det [u v]`, twice the pallet's area (not `<= 0`).
    pub(super) twice_area: T,
}

impl<T: Scalar> Pallet<T> {
    /// The point `c + q_0 u + q_1 v` of the unit-triangle point `q`.
    pub(super) fn point(&self, q: [f64; 2]) -> [T; 2] {
        let (c, u, v) = (self.apex, self.u, self.v);
        [
            c[0] + u[0] * q[0] + v[0] * q[1],
            c[1] + u[1] * q[0] + v[1] * q[1],
        ]
    }
}

/// The pallets of a counter-clockwise overlap polygon whose vertices come from `origins`, split
/// by `split`, without those whose area is not positive (module docs, step 4; a pallet of NaN
/// area is kept, for the kernel to fail on).
pub(super) fn pallets_of<'p, T: Scalar>(
    split: PalletSplit,
    polygon: &'p [[T; 2]],
    origins: &[VertexOrigin],
) -> impl Iterator<Item = Pallet<T>> + 'p {
    let apex = split.apex(polygon, origins);
    split
        .edges(polygon.len(), origins)
        .filter_map(move |(i, j)| {
            let (a, b) = (polygon[i], polygon[j]);
            let u = [a[0] - apex[0], a[1] - apex[1]];
            let v = [b[0] - apex[0], b[1] - apex[1]];
            let twice_area = det2(u, v);
            if twice_area.re() <= 0.0 {
                None
            } else {
                Some(Pallet {
                    apex,
                    u,
                    v,
                    twice_area,
                })
            }
        })
}
