//! The projected sub-segments of a pair in level-2 duals ([`PlaneMap`]): their local
//! coordinates and `det(dP/dlocal)` at a quadrature point with their derivatives, and the
//! overlap polygon's vertices differentiated along their provenance ([`traced_polygon`])
//! (module docs of [`super`], steps 2 to 4).

use num_dual::DualSVec64;

use super::plane_value::{plane_det2, PlaneValue};
use super::{slots, PlaneDual, PLANE_SLOTS, PRIMARY_SLOT};
use crate::contact::mortar::clip::VertexOrigin;
use crate::contact::mortar::overlap::Overlap;
use crate::contact::mortar::projection::{det2, solve2, Bilinear, LocalPoint, Projected};

/// An overlap vertex whose provenance misses the float vertex by more than this times the
/// sub-segment size is held fixed (module docs of [`super`], "Degenerate configurations").
const PROVENANCE_TOLERANCE: f64 = 1e-8;

/// A dual number with real part `re` and the derivatives of `like`.
fn with_re<const K: usize>(re: f64, like: &DualSVec64<K>) -> DualSVec64<K> {
    DualSVec64::new(re, like.eps)
}

/// A projected sub-segment in level-2 duals: its vertices seeded on their slots (the first
/// three of a triangle), for the provenance of the overlap vertices, and the float data of the
/// per-point maps (see [`PlaneValue`]).
pub(super) struct PlaneMap<'o> {
    pub(super) vertices: [[PlaneDual; 2]; 4],
    /// The float sub-segment (its vertices and, for a quadrilateral, its bilinear map).
    pub(super) projected: &'o Projected<'o>,
    /// The slot of the first vertex.
    first: usize,
    /// A quadrilateral: the derivatives of the monomial coefficients `a`, `b`, `c` of its bilinear
    /// map (constant); a triangle: `det(dP/dlocal)` (constant).
    shape: MapShape,
}

/// The constant level-2 data of a projected sub-segment (see [`PlaneMap`]); one per projected
/// sub-segment of an overlapping pair, on the stack, so the size of `Quad` does not matter.
#[allow(clippy::large_enum_variant)]
enum MapShape {
    Triangle(PlaneValue),
    Quad {
        a: [[f64; PLANE_SLOTS]; 2],
        b: [[f64; PLANE_SLOTS]; 2],
        c: [[f64; PLANE_SLOTS]; 2],
    },
}

impl<'o> PlaneMap<'o> {
    /// The projected sub-segment `projected`, seeded on the slots from `first`.
    pub(super) fn new(projected: &'o Projected<'o>, first: usize) -> Self {
        let v = &projected.vertices;
        let mut vertices = [[PlaneDual::from_re(0.0); 2]; 4];
        for (i, (to, from)) in vertices.iter_mut().zip(v).enumerate() {
            *to = [
                PlaneDual::from_re(from[0]).derivative(first + 2 * i),
                PlaneDual::from_re(from[1]).derivative(first + 2 * i + 1),
            ];
        }
        let shape = if v.len() == 4 {
            let map = Bilinear::new(&vertices);
            MapShape::Quad {
                a: map.a.map(|x| slots(&x)),
                b: map.b.map(|x| slots(&x)),
                c: map.c.map(|x| slots(&x)),
            }
        } else {
            let q = &vertices;
            MapShape::Triangle(PlaneValue::of(&det2(
                [q[1][0] - q[0][0], q[1][1] - q[0][1]],
                [q[2][0] - q[0][0], q[2][1] - q[0][1]],
            )))
        };
        PlaneMap {
            vertices,
            projected,
            first,
            shape,
        }
    }

    fn vertex(&self, i: usize) -> [PlaneDual; 2] {
        self.vertices[i]
    }

    /// Local coordinates of `p` given the float solution `found`: closed form on a triangle, one
    /// Newton step from `found` on a quadrilateral (module docs of [`super`], step 4), with their
    /// derivatives, rounded as the level-2 duals round them (see [`PlaneValue`]).
    pub(super) fn local(&self, p: &[PlaneValue; 2], found: &LocalPoint) -> [PlaneValue; 2] {
        match (&self.shape, self.projected.bilinear()) {
            (&MapShape::Triangle(det), _) => self.triangle_local(p, &det),
            (MapShape::Quad { .. }, Some(map)) => self.quad_local(map, p, found),
            (MapShape::Quad { .. }, None) => unreachable!("a quadrilateral has its bilinear map"),
        }
    }

    /// The barycentric coordinates `det [d b] / det`, `det [a d] / det` (`a = Q_1 - Q_0`,
    /// `b = Q_2 - Q_0`, `d = P - Q_0`): the operations of `triangle_local` in level-2 duals.
    fn triangle_local(&self, p: &[PlaneValue; 2], det: &PlaneValue) -> [PlaneValue; 2] {
        let q = &self.projected.vertices;
        // The edges have constant unit derivatives: a_i = +1 on vertex 1, -1 on vertex 0.
        let edge = |to: usize| -> [PlaneValue; 2] {
            std::array::from_fn(|axis| {
                let mut e = PlaneValue {
                    re: q[to][axis] - q[0][axis],
                    d: [0.0; PLANE_SLOTS],
                };
                e.d[self.first + 2 * to + axis] = 1.0;
                e.d[self.first + axis] = -1.0;
                e
            })
        };
        let (a, b) = (edge(1), edge(2));
        let d: [PlaneValue; 2] = std::array::from_fn(|axis| {
            let mut e = PlaneValue {
                re: p[axis].re - q[0][axis],
                d: p[axis].d,
            };
            e.d[self.first + axis] -= 1.0;
            e
        });
        [plane_det2(&d, &b), plane_det2(&a, &d)].map(|num| num.over(det))
    }

    /// One Newton step from `found`, `local = found - J^-1 (P(found) - p)` with the float
    /// Jacobian `J`: the derivative `J^-1 (dp - dP(found))`, where `dP(found) / dQ_i` is the
    /// bilinear function `N_i(found)` of vertex `i` evaluated in the monomial form of
    /// [`Bilinear::point`], as the duals evaluate it.
    fn quad_local(
        &self,
        map: &Bilinear,
        p: &[PlaneValue; 2],
        found: &LocalPoint,
    ) -> [PlaneValue; 2] {
        let p_float = [p[0].re, p[1].re];
        let x = map.point(found.local);
        let j = map.jacobian_re(found.local);
        let det = det2(j[0], j[1]);
        let [d0, d1] = solve2(j, det, [x[0] - p_float[0], x[1] - p_float[1]]);
        let local = [found.local[0] - d0, found.local[1] - d1];
        let [s, t] = found.local;
        // The monomial coefficients' derivatives along vertex i's slots: p0 1/4, a, b, c +-1/4.
        const SIGNS: [[f64; 3]; 4] = [
            [-0.25, -0.25, 0.25],
            [0.25, -0.25, -0.25],
            [0.25, 0.25, 0.25],
            [-0.25, 0.25, -0.25],
        ];
        let st = s * t;
        // g = dp - dP(found), then J^-1 g.
        let mut g = [p[0].d, p[1].d];
        for (i, [sa, sb, sc]) in SIGNS.iter().enumerate() {
            let n = 0.25 + sa * s + sb * t + sc * st;
            for (axis, ga) in g.iter_mut().enumerate() {
                ga[self.first + 2 * i + axis] -= n;
            }
        }
        [
            PlaneValue {
                re: local[0],
                d: std::array::from_fn(|k| (g[0][k] * j[1][1] - g[1][k] * j[0][1]) / det),
            },
            PlaneValue {
                re: local[1],
                d: std::array::from_fn(|k| (g[1][k] * j[0][0] - g[0][k] * j[1][0]) / det),
            },
        ]
    }

    /// `det(dP/dlocal)` at `local`.
    pub(super) fn jacobian(&self, local: &[PlaneValue; 2]) -> PlaneValue {
        match (&self.shape, self.projected.bilinear()) {
            (MapShape::Quad { a, b, c }, Some(map)) => {
                let [s, t] = local;
                let (ma, mb, mc) = (map.a, map.b, map.c);
                // d J_ij through the coefficients (constant slots) and through (s, t).
                let j00 = ma[0] + mc[0] * t.re;
                let j11 = mb[1] + mc[1] * s.re;
                let j01 = mb[0] + mc[0] * s.re;
                let j10 = ma[1] + mc[1] * t.re;
                PlaneValue {
                    re: map.jacobian([s.re, t.re]),
                    d: std::array::from_fn(|k| {
                        let dj00 = a[0][k] + (c[0][k] * t.re + t.d[k] * mc[0]);
                        let dj11 = b[1][k] + (c[1][k] * s.re + s.d[k] * mc[1]);
                        let dj01 = b[0][k] + (c[0][k] * s.re + s.d[k] * mc[0]);
                        let dj10 = a[1][k] + (c[1][k] * t.re + t.d[k] * mc[1]);
                        (dj00 * j11 + dj11 * j00) - (dj01 * j10 + dj10 * j01)
                    }),
                }
            }
            (&MapShape::Triangle(det), _) => det,
            (MapShape::Quad { .. }, None) => unreachable!("a quadrilateral has its bilinear map"),
        }
    }
}

/// The crossing of the lines `a b` and `c d`: `a + t (b - a)` with `t = o_a / (o_a - o_b)`, `o`
/// the orientation about `c d` (the formula of the clipping).
fn crossing(
    a: [PlaneDual; 2],
    b: [PlaneDual; 2],
    c: [PlaneDual; 2],
    d: [PlaneDual; 2],
) -> [PlaneDual; 2] {
    let cd = [d[0] - c[0], d[1] - c[1]];
    let orientation = |p: [PlaneDual; 2]| det2(cd, [p[0] - c[0], p[1] - c[1]]);
    let (oa, ob) = (orientation(a), orientation(b));
    let t = oa / (oa - ob);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

/// The level-2 geometry of an overlap: its projected sub-segments and its polygon.
pub(super) struct TracedOverlap<'o> {
    pub(super) s: PlaneMap<'o>,
    pub(super) m: PlaneMap<'o>,
    /// The overlap polygon in level-2 duals (see [`traced_polygon`]).
    pub(super) polygon: Vec<[PlaneDual; 2]>,
}

impl<'o> TracedOverlap<'o> {
    /// The level-2 geometry of `overlap`, adding its vertices held fixed to `unresolved`.
    pub(super) fn new(overlap: &'o Overlap, unresolved: &mut usize) -> Self {
        let s = PlaneMap::new(&overlap.s, 0);
        let m = PlaneMap::new(&overlap.m, PRIMARY_SLOT);
        let (polygon, held) = traced_polygon(overlap, &s, &m);
        *unresolved += held;
        TracedOverlap { s, m, polygon }
    }
}

/// The overlap polygon in level-2 duals: each float vertex with the derivatives of its
/// provenance, or held fixed (counted) if the provenance is ambiguous or misses it.
fn traced_polygon(
    overlap: &Overlap,
    s_map: &PlaneMap,
    m_map: &PlaneMap,
) -> (Vec<[PlaneDual; 2]>, usize) {
    let tolerance = PROVENANCE_TOLERANCE * overlap.scale;
    let mut unresolved = 0;
    let polygon = overlap
        .polygon
        .iter()
        .zip(&overlap.origins)
        .map(|(v, origin)| {
            let traced = match *origin {
                VertexOrigin::First(i) => Some(s_map.vertex(i)),
                VertexOrigin::Second(j) => Some(m_map.vertex(j)),
                VertexOrigin::Crossing {
                    first: [a, b],
                    second: [c, d],
                } => Some(crossing(
                    s_map.vertex(a),
                    s_map.vertex(b),
                    m_map.vertex(c),
                    m_map.vertex(d),
                )),
                VertexOrigin::Unresolved => None,
            };
            let reproduces = |t: &[PlaneDual; 2]| {
                let miss = (t[0].re - v[0]).hypot(t[1].re - v[1]);
                let finite = t.iter().all(|c| slots(c).iter().all(|s| s.is_finite()));
                miss <= tolerance && finite
            };
            match traced {
                Some(t) if reproduces(&t) => [with_re(v[0], &t[0]), with_re(v[1], &t[1])],
                _ => {
                    unresolved += 1;
                    v.map(PlaneDual::from_re)
                }
            }
        })
        .collect();
    (polygon, unresolved)
}
