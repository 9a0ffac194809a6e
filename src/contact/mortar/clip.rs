//! Convex polygon clipping in the projection plane (docs/theory.md sections 3.4 and 3.5).
//!
//! # Clipping
//!
//! [`clip_convex`] intersects two convex counter-clockwise polygons by Sutherland-Hodgman: the
//! subject polygon is cut by the half-plane to the left of each edge `(a, b)` of the clip polygon
//! in turn. With the orientation `o(a, b, p) = (b - a) x (p - a)` (twice the signed area of the
//! triangle `a b p`, positive when `p` is left of the edge):
//!
//! - a vertex `p` is kept ("inside") when `o(a, b, p) >= -tol |b - a|`, i.e. when it is at most
//!   the length tolerance `tol` outside the edge's line: an area tolerance scaled by the edge;
//! - where an edge `p q` of the subject crosses from inside to outside (or back), the crossing is
//!   `p + t (q - p)` with `t = o_p / (o_p - o_q)` clamped to `[0, 1]` (the two orientations have
//!   opposite classifications, so the denominator is positive and the point stays on `p q`);
//! - consecutive points closer than `tol` are merged, and vertices within `tol` of the chord of
//!   their neighbours (collinear, or reflex by round-off) are dropped;
//! - the smaller of the two polygons is the one cut (the intersection is symmetric), so every
//!   computed crossing lies on a short edge: a tiny polygon against a huge one keeps the tiny
//!   one's precision.
//!
//! All tolerances are relative to `scale`, the size of the segment being integrated:
//! `tol = 1e-13 scale`. The result is counter-clockwise. It is [`Clipped::Empty`] if fewer than
//! three vertices remain (disjoint polygons, or polygons touching along an edge or at a corner),
//! and [`Clipped::Sliver`] if its area is below `1e-8 scale^2` (docs/theory.md 3.4): the overlap is
//! too thin to integrate meaningfully and the caller counts it.
//!
//! Each dropped point or inside-by-tolerance decision changes the area by at most about
//! `tol` times the polygon's perimeter, i.e. `~1e-13 scale^2` relative.
//!
//! # Provenance
//!
//! [`clip_convex_traced`] clips in the same way and also says where each vertex of the result
//! comes from ([`VertexOrigin`]), which the linearization needs to differentiate the vertices
//! ([`super::linearize`]). It is recorded, not guessed afterwards: every working vertex carries
//! the lines of the polygon edges before and after it (each line named by its polygon and two
//! input vertices). An input vertex starts with its own two edges; a crossing created on the
//! cut edge `p q` by the clipping edge `a b` gets the lines of `p q` and of `a b`, in the order
//! of the boundary; a point merged into its neighbour (closer than the length tolerance) hands
//! over its outer line, so the chain of lines stays that of the polygon. At the end a vertex on
//! two consecutive edges of one polygon is that polygon's vertex, and a vertex on an edge of each
//! is their crossing. The clipped polygon is identical to [`clip_convex`]'s.
//!
//! # Pallets
//!
//! [`pallets`] splits a convex polygon of `N` vertices into the triangles the quadrature rule
//! runs on, each the triangle of one polygon edge with an apex ([`PalletSplit`]):
//!
//! - [`PalletSplit::Centroid`] (the default, docs/theory.md 3.5): `N` triangles from the area
//!   centroid, one per edge (also for a triangle). The split depends continuously on the
//!   vertices, unlike a diagonal or Delaunay split whose choice flips with round-off on
//!   cocircular polygons: when a vertex appears or disappears, its pallet appears or disappears
//!   with zero area.
//! - [`PalletSplit::Fan`]: `N - 2` triangles from one vertex, the apex, chosen by the vertices'
//!   provenance ([`VertexOrigin`], in its order: the lowest-numbered vertex of the first
//!   polygon inside the overlap, else of the second, else the first crossing), not by position
//!   nor by the order in which the clipping returns the vertices (which depends on a round-off
//!   comparison of the two polygons' sizes). Only where vertices of the two polygons nearly
//!   coincide (within the clipping's length tolerance) can round-off decide which of them
//!   survives, and so the apex. The two splits tile the same polygon, so a rule
//!   exact for the integrand gives the same integral on both (the mortar integrand is a
//!   polynomial on affine pairs, where both are exact: the patch tests); a rectangle takes 2
//!   pallets instead of 4, a hexagon 4 instead of 6. The price: the apex follows the overlap's
//!   topology, so when the overlap gains or loses a vertex the split can jump, and with it the
//!   quadrature error on curved faces (not the integral of an integrand the rule integrates
//!   exactly). While the topology stays, the split moves continuously with the vertices.

use crate::fe::shape::Scalar;

/// A point or vector of the projection plane.
pub type Point = [f64; 2];

/// Distance tolerance of the clipping, relative to `scale`.
pub const LENGTH_TOLERANCE: f64 = 1e-13;

/// Overlaps with an area below this times `scale^2` are slivers.
pub const SLIVER_AREA: f64 = 1e-8;

/// Distance tolerance of the convexity test, relative to `scale`.
pub const CONVEXITY_TOLERANCE: f64 = 1e-12;

/// Result of [`clip_convex`].
#[derive(Clone, Debug, PartialEq)]
pub enum Clipped {
    /// The intersection, convex and counter-clockwise, at least three vertices.
    Polygon(Vec<Point>),
    /// No overlap of positive area (disjoint, or touching at an edge or a corner).
    Empty,
    /// An overlap of area below `1e-8 scale^2`.
    Sliver,
}

fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: Point, b: Point) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn distance(a: Point, b: Point) -> f64 {
    let d = sub(a, b);
    d[0].hypot(d[1])
}

/// `(b - a) x (p - a)`: positive when `p` is left of the directed line `a b`.
fn orientation(a: Point, b: Point, p: Point) -> f64 {
    cross(sub(b, a), sub(p, a))
}

fn all_finite(p: &[Point]) -> bool {
    p.iter().all(|v| v[0].is_finite() && v[1].is_finite())
}

/// Signed area (shoelace formula, about the first vertex to limit round-off): positive for a
/// counter-clockwise polygon.
pub fn polygon_area(p: &[Point]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    let origin = p[0];
    let twice: f64 = p
        .windows(2)
        .skip(1)
        .map(|w| cross(sub(w[0], origin), sub(w[1], origin)))
        .sum();
    0.5 * twice
}

/// True if `p` is a convex polygon of positive area, counter-clockwise: every vertex lies left of
/// (or within `1e-12 scale` of) the line of every edge. This rejects clockwise, reflex and
/// self-intersecting (e.g. star-shaped) polygons alike.
pub fn is_convex_ccw(p: &[Point], scale: f64) -> bool {
    if p.len() < 3 || !all_finite(p) || polygon_area(p) <= 0.0 {
        return false;
    }
    let tol = CONVEXITY_TOLERANCE * scale.abs();
    (0..p.len()).all(|i| {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        let length = distance(a, b);
        p.iter().all(|&v| orientation(a, b, v) >= -tol * length)
    })
}

/// The line of an edge of one of the two input polygons of [`clip_convex_traced`]: polygon
/// `poly` (0: the first argument, 1: the second) through its input vertices `from` and `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct EdgeLine {
    poly: u8,
    from: usize,
    to: usize,
}

/// A vertex of a polygon being clipped, with the lines of the polygon edges before and after
/// it: every vertex is the intersection of these two lines.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    p: Point,
    before: EdgeLine,
    after: EdgeLine,
}

/// Where a vertex of the polygon returned by [`clip_convex_traced`] comes from: the input is the
/// pair `(first, second)` as passed, with the input vertex numbering. Ordered (the first
/// polygon's vertices, the second's, crossings, unresolved) for the apex of a fan of pallets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum VertexOrigin {
    /// Input vertex `i` of the first polygon.
    First(usize),
    /// Input vertex `j` of the second polygon.
    Second(usize),
    /// The crossing of the line through the first polygon's input vertices `first` (an edge) with
    /// the line through the second polygon's input vertices `second`.
    Crossing {
        first: [usize; 2],
        second: [usize; 2],
    },
    /// Two lines of the same polygon that are not consecutive: only after merging points closer
    /// than the length tolerance (degenerate configurations), where the vertex has no unique
    /// provenance.
    Unresolved,
}

impl Vertex {
    fn origin(&self) -> VertexOrigin {
        let (b, a) = (self.before, self.after);
        if b.poly != a.poly {
            let (first, second) = if b.poly == 0 { (b, a) } else { (a, b) };
            return VertexOrigin::Crossing {
                first: [first.from, first.to],
                second: [second.from, second.to],
            };
        }
        match (b.to == a.from, b.poly) {
            (true, 0) => VertexOrigin::First(b.to),
            (true, _) => VertexOrigin::Second(b.to),
            (false, _) => VertexOrigin::Unresolved,
        }
    }
}

/// A point of the plane, bare or carried by a traced [`Vertex`].
trait Located: Copy {
    fn at(&self) -> Point;

    /// Takes over the edge after `next`, a point merged into this one.
    fn absorb_next(&mut self, _next: &Self) {}

    /// Takes over the edge before `previous`, a point merged into this one.
    fn absorb_previous(&mut self, _previous: &Self) {}
}

impl Located for Point {
    fn at(&self) -> Point {
        *self
    }
}

impl Located for (Point, usize) {
    fn at(&self) -> Point {
        self.0
    }
}

impl Located for Vertex {
    fn at(&self) -> Point {
        self.p
    }

    fn absorb_next(&mut self, next: &Self) {
        self.after = next.after;
    }

    fn absorb_previous(&mut self, previous: &Self) {
        self.before = previous.before;
    }
}

/// Merges consecutive points (cyclically) closer than `tol`, keeping the first; a kept traced
/// vertex takes over the outer edge lines of the points merged into it, so that the chain of
/// edge lines stays that of the polygon.
fn merge_close_points<V: Located>(p: &[V], tol: f64) -> Vec<V> {
    let mut out: Vec<V> = Vec::with_capacity(p.len());
    for v in p {
        let apart = out
            .last()
            .is_none_or(|last| distance(last.at(), v.at()) > tol);
        if apart {
            out.push(*v);
        } else if let Some(last) = out.last_mut() {
            last.absorb_next(v);
        }
    }
    while out.len() > 1 && distance(out[0].at(), out[out.len() - 1].at()) <= tol {
        if let Some(last) = out.pop() {
            out[0].absorb_previous(&last);
        }
    }
    out
}

/// Drops vertices within `tol` of the chord joining their neighbours (collinear points, and
/// reflex corners created by round-off, on either side of the chord), until none is left.
fn drop_flat_vertices<V: Located>(mut p: Vec<V>, tol: f64) -> Vec<V> {
    let mut changed = true;
    while changed && p.len() >= 3 {
        changed = false;
        let n = p.len();
        for i in 0..n {
            let (prev, cur, next) = (p[(i + n - 1) % n].at(), p[i].at(), p[(i + 1) % n].at());
            if orientation(prev, next, cur).abs() <= tol * distance(prev, next) {
                p.remove(i);
                changed = true;
                break;
            }
        }
    }
    p
}

/// Input polygon `poly` (0 or 1) cleaned for clipping: close points merged, counter-clockwise,
/// each vertex with the lines of its two edges (in the input vertex numbering).
fn prepared(p: &[Point], poly: u8, tol: f64) -> Vec<Vertex> {
    let numbered: Vec<(Point, usize)> = p.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    let mut kept = merge_close_points(&numbered, tol);
    let points: Vec<Point> = kept.iter().map(|v| v.0).collect();
    if polygon_area(&points) < 0.0 {
        kept.reverse();
    }
    let n = kept.len();
    let line = |k: usize, l: usize| EdgeLine {
        poly,
        from: kept[k % n].1,
        to: kept[l % n].1,
    };
    (0..n)
        .map(|k| Vertex {
            p: kept[k].0,
            before: line(k + n - 1, k),
            after: line(k, k + 1),
        })
        .collect()
}

/// Largest distance of a vertex from the first vertex (a cheap size measure).
fn extent(p: &[Vertex]) -> f64 {
    p.iter().map(|v| distance(v.p, p[0].p)).fold(0.0, f64::max)
}

/// The two polygons, the smaller one first: clipping the smaller polygon by the larger one
/// computes every crossing on a short edge, where its round-off is smallest.
fn smaller_first(a: Vec<Vertex>, b: Vec<Vertex>) -> (Vec<Vertex>, Vec<Vertex>) {
    if !a.is_empty() && !b.is_empty() && extent(&b) < extent(&a) {
        (b, a)
    } else {
        (a, b)
    }
}

/// The part of `poly` left of the directed line `a b` (within `tol`), `a` and `b` consecutive
/// vertices of the clip polygon. A crossing lies on the line of the cut edge of `poly` and on the
/// line of `a b`, which its traced lines record.
fn clip_by_edge(poly: &[Vertex], a: &Vertex, b: &Vertex, tol: f64) -> Vec<Vertex> {
    let area_tol = tol * distance(a.p, b.p);
    let n = poly.len();
    let mut out = Vec::with_capacity(n + 1);
    for i in 0..n {
        let (p, q) = (&poly[i], &poly[(i + 1) % n]);
        let (op, oq) = (orientation(a.p, b.p, p.p), orientation(a.p, b.p, q.p));
        let (p_in, q_in) = (op >= -area_tol, oq >= -area_tol);
        if p_in {
            out.push(*p);
        }
        if p_in != q_in {
            let t = (op / (op - oq)).clamp(0.0, 1.0);
            let crossing = [
                p.p[0] + t * (q.p[0] - p.p[0]),
                p.p[1] + t * (q.p[1] - p.p[1]),
            ];
            let (before, after) = if p_in {
                (p.after, a.after)
            } else {
                (a.after, q.before)
            };
            out.push(Vertex {
                p: crossing,
                before,
                after,
            });
        }
    }
    merge_close_points(&out, tol)
}

/// Intersection of two convex polygons (counter-clockwise; clockwise input is reversed first),
/// tolerances relative to `scale` (the segment size): inside tests against an area tolerance,
/// edge parameters clamped to `[0, 1]`, points closer than a length tolerance merged, result
/// counter-clockwise, [`Clipped::Empty`] if fewer than 3 vertices remain, [`Clipped::Sliver`] if
/// the area is below `1e-8 scale^2`. Non-finite input, or a `scale` that is not finite and
/// positive, gives [`Clipped::Empty`]. Never panics, never returns NaN.
pub fn clip_convex(subject: &[Point], clip: &[Point], scale: f64) -> Clipped {
    match clip_vertices(subject, clip, scale) {
        Ok(vertices) => Clipped::Polygon(vertices.iter().map(|v| v.p).collect()),
        Err(outcome) => outcome,
    }
}

/// [`clip_convex`] with the provenance of every vertex of the result (in its order; empty unless
/// the result is a polygon): a vertex of `first`, a vertex of `second`, or the crossing of an
/// edge of each (see the module docs).
pub fn clip_convex_traced(
    first: &[Point],
    second: &[Point],
    scale: f64,
) -> (Clipped, Vec<VertexOrigin>) {
    match clip_vertices(first, second, scale) {
        Ok(vertices) => (
            Clipped::Polygon(vertices.iter().map(|v| v.p).collect()),
            vertices.iter().map(Vertex::origin).collect(),
        ),
        Err(outcome) => (outcome, Vec::new()),
    }
}

/// The clipping of [`clip_convex`] on traced vertices: the polygon, or why there is none.
fn clip_vertices(first: &[Point], second: &[Point], scale: f64) -> Result<Vec<Vertex>, Clipped> {
    let usable = scale.is_finite() && scale > 0.0 && all_finite(first) && all_finite(second);
    if !usable {
        return Err(Clipped::Empty);
    }
    let tol = LENGTH_TOLERANCE * scale;
    let (subject, clip) = smaller_first(prepared(first, 0, tol), prepared(second, 1, tol));
    let mut poly = subject;
    if clip.len() < 3 {
        return Err(Clipped::Empty);
    }
    for i in 0..clip.len() {
        if poly.len() < 3 {
            return Err(Clipped::Empty);
        }
        poly = clip_by_edge(&poly, &clip[i], &clip[(i + 1) % clip.len()], tol);
    }
    let poly = drop_flat_vertices(poly, tol);
    if poly.len() < 3 {
        return Err(Clipped::Empty);
    }
    let points: Vec<Point> = poly.iter().map(|v| v.p).collect();
    let area = polygon_area(&points);
    if !area.is_finite() || area <= 0.0 {
        Err(Clipped::Empty)
    } else if area < SLIVER_AREA * scale * scale {
        Err(Clipped::Sliver)
    } else {
        Ok(poly)
    }
}

/// Area centroid of a polygon, the vertex mean if its area is not positive, for any [`Scalar`]
/// (the choice between centroid and mean by the real part).
pub fn area_centroid_at<T: Scalar>(p: &[[T; 2]]) -> [T; 2] {
    let n = p.len() as f64;
    let zero = T::from(0.0);
    let mean = p
        .iter()
        .fold([zero; 2], |acc, v| [acc[0] + v[0] / n, acc[1] + v[1] / n]);
    let origin = p.first().copied().unwrap_or([zero; 2]);
    let (mut twice_area, mut moment) = (zero, [zero; 2]);
    for w in p.windows(2).skip(1) {
        let a = [w[0][0] - origin[0], w[0][1] - origin[1]];
        let b = [w[1][0] - origin[0], w[1][1] - origin[1]];
        let c = a[0] * b[1] - a[1] * b[0];
        twice_area += c;
        moment = [moment[0] + c * (a[0] + b[0]), moment[1] + c * (a[1] + b[1])];
    }
    if twice_area.re() > 0.0 && twice_area.re().is_finite() {
        [
            origin[0] + moment[0] / (twice_area * 3.0),
            origin[1] + moment[1] / (twice_area * 3.0),
        ]
    } else {
        mean
    }
}

/// How an overlap polygon is split into pallets (module docs, "Pallets"). Case key
/// `pallets` of an interface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PalletSplit {
    /// `N` triangles `(centroid, p_i, p_i+1)` from the area centroid.
    #[default]
    Centroid,
    /// `N - 2` triangles `(p_a, p_i, p_i+1)` from one vertex `p_a`, chosen by the vertices'
    /// origins ([`PalletSplit::apex`]).
    Fan,
}

impl PalletSplit {
    /// The split of a case file's name (`"centroid"` or `"fan"`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "centroid" => Some(PalletSplit::Centroid),
            "fan" => Some(PalletSplit::Fan),
            _ => None,
        }
    }

    /// The apex shared by the pallets of polygon `p` (at least three vertices), whose vertices
    /// come from `origins` (one per vertex; empty: the fan's apex is the first vertex).
    pub fn apex<T: Scalar>(self, p: &[[T; 2]], origins: &[VertexOrigin]) -> [T; 2] {
        match self {
            PalletSplit::Centroid => area_centroid_at(p),
            PalletSplit::Fan => p[fan_apex(origins)],
        }
    }

    /// The edges `(i, j)` of a polygon of `n >= 3` vertices (origins as for [`Self::apex`])
    /// whose triangle with the apex is a pallet, counter-clockwise.
    pub fn edges(self, n: usize, origins: &[VertexOrigin]) -> impl Iterator<Item = (usize, usize)> {
        let (first, count) = match self {
            PalletSplit::Centroid => (0, n),
            PalletSplit::Fan => (fan_apex(origins) + 1, n.saturating_sub(2)),
        };
        (first..first + count).map(move |i| (i % n, (i + 1) % n))
    }
}

/// The index of a fan's apex: the vertex of the smallest origin (the first vertex without
/// origins).
fn fan_apex(origins: &[VertexOrigin]) -> usize {
    (0..origins.len()).min_by_key(|&i| origins[i]).unwrap_or(0)
}

/// The pallets of polygon `p`, with vertex origins as for [`PalletSplit::apex`]: triangles
/// `(apex, p_i, p_j)` (module docs, "Pallets"); none for fewer than three vertices.
pub fn pallets(p: &[Point], origins: &[VertexOrigin], split: PalletSplit) -> Vec<[Point; 3]> {
    if p.len() < 3 {
        return Vec::new();
    }
    let apex = split.apex(p, origins);
    split
        .edges(p.len(), origins)
        .map(|(i, j)| [apex, p[i], p[j]])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Convex hull by Andrew's monotone chain with sign-only predicates (collinear points
    /// dropped), counter-clockwise.
    fn convex_hull(points: &[Point]) -> Vec<Point> {
        let mut pts = points.to_vec();
        pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        pts.dedup();
        if pts.len() < 3 {
            return pts;
        }
        let mut hull: Vec<Point> = Vec::new();
        for pass in 0..2 {
            let start = hull.len();
            let ordered: Vec<Point> = if pass == 0 {
                pts.clone()
            } else {
                pts.iter().rev().copied().collect()
            };
            for p in ordered {
                while hull.len() >= start + 2
                    && orientation(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
                {
                    hull.pop();
                }
                hull.push(p);
            }
            hull.pop();
        }
        hull
    }

    fn inside_convex(p: Point, poly: &[Point]) -> bool {
        (0..poly.len()).all(|i| orientation(poly[i], poly[(i + 1) % poly.len()], p) >= 0.0)
    }

    /// Crossing of segments `a b` and `c d`, if they cross at one point.
    fn segment_crossing(a: Point, b: Point, c: Point, d: Point) -> Option<Point> {
        let (r, s) = (sub(b, a), sub(d, c));
        let denom = cross(r, s);
        if denom == 0.0 {
            return None;
        }
        let t = cross(sub(c, a), s) / denom;
        let u = cross(sub(c, a), r) / denom;
        ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u))
            .then(|| [a[0] + t * r[0], a[1] + t * r[1]])
    }

    /// Reference intersection area by another method: the hull of the vertices of each polygon
    /// inside the other and of all edge-edge crossings.
    fn reference_area(a: &[Point], b: &[Point]) -> f64 {
        let mut pts: Vec<Point> = a.iter().copied().filter(|&p| inside_convex(p, b)).collect();
        pts.extend(b.iter().copied().filter(|&p| inside_convex(p, a)));
        for i in 0..a.len() {
            for j in 0..b.len() {
                let (a0, a1) = (a[i], a[(i + 1) % a.len()]);
                let (b0, b1) = (b[j], b[(j + 1) % b.len()]);
                pts.extend(segment_crossing(a0, a1, b0, b1));
            }
        }
        polygon_area(&convex_hull(&pts))
    }

    fn area_of(c: &Clipped) -> f64 {
        match c {
            Clipped::Polygon(p) => polygon_area(p),
            _ => 0.0,
        }
    }

    fn assert_valid(c: &Clipped, scale: f64) {
        if let Clipped::Polygon(p) = c {
            assert!(p.len() >= 3);
            assert!(all_finite(p), "{p:?}");
            assert!(is_convex_ccw(p, scale), "{p:?}");
        }
    }

    fn square(x0: f64, y0: f64, side: f64) -> Vec<Point> {
        vec![
            [x0, y0],
            [x0 + side, y0],
            [x0 + side, y0 + side],
            [x0, y0 + side],
        ]
    }

    fn rotate_about(p: &[Point], centre: Point, angle: f64) -> Vec<Point> {
        let (s, c) = angle.sin_cos();
        p.iter()
            .map(|v| {
                let d = sub(*v, centre);
                [
                    centre[0] + c * d[0] - s * d[1],
                    centre[1] + s * d[0] + c * d[1],
                ]
            })
            .collect()
    }

    fn rigid(p: &[Point], angle: f64, shift: Point) -> Vec<Point> {
        rotate_about(p, [0.0, 0.0], angle)
            .into_iter()
            .map(|v| [v[0] + shift[0], v[1] + shift[1]])
            .collect()
    }

    fn rotated_order<T: Clone>(p: &[T], k: usize) -> Vec<T> {
        let mut q = p.to_vec();
        q.rotate_left(k % p.len());
        q
    }

    fn points_strategy() -> impl Strategy<Value = Vec<Point>> {
        prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y)| [x, y]), 3..9)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2048))]

        /// Random convex pairs: the clipped area matches the reference to 1e-12 (scale 1), is
        /// invariant under rotating the vertex order of either input and under a rigid motion of
        /// both, and never NaN.
        #[test]
        fn clipped_area_matches_reference(
            pa in points_strategy(),
            pb in points_strategy(),
            offset in (-1.0..1.0f64, -1.0..1.0f64),
            ka in 0usize..8,
            kb in 0usize..8,
            angle in -3.2..3.2f64,
            shift in (-10.0..10.0f64, -10.0..10.0f64),
        ) {
            let a = convex_hull(&pa);
            let b: Vec<Point> = convex_hull(&pb)
                .into_iter()
                .map(|v| [v[0] + offset.0, v[1] + offset.1])
                .collect();
            prop_assume!(a.len() >= 3 && b.len() >= 3);
            prop_assume!(polygon_area(&a) > 1e-3 && polygon_area(&b) > 1e-3);
            let scale = 1.0;
            let clipped = clip_convex(&a, &b, scale);
            assert_valid(&clipped, scale);
            let reference = reference_area(&a, &b);
            let area = area_of(&clipped);
            if let Clipped::Sliver = clipped {
                prop_assert!(reference < SLIVER_AREA + 1e-12);
            } else {
                prop_assert!((area - reference).abs() < 1e-12, "{} vs {}", area, reference);
            }
            // Vertex-order rotations.
            let rotated = clip_convex(&rotated_order(&a, ka), &rotated_order(&b, kb), scale);
            prop_assert!((area_of(&rotated) - area).abs() < 1e-12);
            // Rigid motion of both.
            let (ma, mb) = (rigid(&a, angle, [shift.0, shift.1]), rigid(&b, angle, [shift.0, shift.1]));
            let moved = clip_convex(&ma, &mb, scale);
            assert_valid(&moved, scale);
            prop_assert!((area_of(&moved) - area).abs() < 1e-12);
            // Symmetric in the two inputs.
            let swapped = clip_convex(&b, &a, scale);
            prop_assert!((area_of(&swapped) - area).abs() < 1e-12);
            // Pallets tile the polygon.
            if let Clipped::Polygon(p) = &clipped {
                let counts = [(PalletSplit::Centroid, p.len()), (PalletSplit::Fan, p.len() - 2)];
                for (split, count) in counts {
                    let tris = pallets(p, &[], split);
                    prop_assert_eq!(tris.len(), count);
                    let sum: f64 = tris.iter().map(|t| polygon_area(t)).sum();
                    prop_assert!((sum - area).abs() < 1e-13);
                    prop_assert!(tris.iter().all(|t| polygon_area(t) >= -1e-15));
                }
            }
        }
    }

    /// Reflection of `p` across the line through `a` and `b`, reversed to stay counter-clockwise.
    fn reflect(p: &[Point], a: Point, b: Point) -> Vec<Point> {
        let d = sub(b, a);
        let len2 = d[0] * d[0] + d[1] * d[1];
        p.iter()
            .rev()
            .map(|v| {
                let r = sub(*v, a);
                let t = (r[0] * d[0] + r[1] * d[1]) / len2;
                let foot = [a[0] + t * d[0], a[1] + t * d[1]];
                [2.0 * foot[0] - v[0], 2.0 * foot[1] - v[1]]
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1024))]

        /// Near-degenerate pairs: a polygon against itself turned by a tiny angle about one of its
        /// vertices (nearly coincident, near-parallel edges), and against its mirror image across
        /// one of its edges (touching along the edge). Never NaN, always a valid polygon, the area
        /// within the perturbation's bound.
        #[test]
        fn near_degenerate_pairs(
            pa in points_strategy(),
            k in 0usize..8,
            exponent in 4i32..16,
            angle in -3.2..3.2f64,
            shift in (-10.0..10.0f64, -10.0..10.0f64),
        ) {
            let a = rigid(&convex_hull(&pa), angle, [shift.0, shift.1]);
            prop_assume!(a.len() >= 3 && polygon_area(&a) > 1e-3);
            let area_a = polygon_area(&a);
            let eps = 10f64.powi(-exponent);
            let pivot = a[k % a.len()];
            let turned = rotate_about(&a, pivot, eps);
            let c = clip_convex(&a, &turned, 1.0);
            assert_valid(&c, 1.0);
            // Turning by eps about a vertex moves no point by more than 2 eps (diameter <= 2
            // sqrt 2), so the lost area is at most the perimeter (<= 8 sqrt 2) times that.
            prop_assert!((area_of(&c) - area_a).abs() <= 40.0 * eps + 1e-12, "{:?}", c);
            let (e0, e1) = (a[k % a.len()], a[(k + 1) % a.len()]);
            let mirrored = reflect(&a, e0, e1);
            let c = clip_convex(&a, &mirrored, 1.0);
            prop_assert!(matches!(c, Clipped::Empty | Clipped::Sliver), "{:?}", c);
        }
    }

    #[test]
    fn identical_squares() {
        let a = square(0.0, 0.0, 1.0);
        match clip_convex(&a, &a, 1.0) {
            Clipped::Polygon(p) => {
                assert_eq!(p.len(), 4);
                assert!((polygon_area(&p) - 1.0).abs() < 1e-15);
                for v in &a {
                    assert!(p.iter().any(|w| distance(*v, *w) < 1e-15));
                }
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn shared_edge_is_empty() {
        let c = clip_convex(&square(0.0, 0.0, 1.0), &square(1.0, 0.0, 1.0), 1.0);
        assert_eq!(c, Clipped::Empty);
        // The same with a rotated pair (the shared edge then carries round-off).
        let a = rigid(&square(0.0, 0.0, 1.0), 0.7, [3.0, -2.0]);
        let b = rigid(&square(1.0, 0.0, 1.0), 0.7, [3.0, -2.0]);
        let c = clip_convex(&a, &b, 1.0);
        assert!(matches!(c, Clipped::Empty | Clipped::Sliver), "{c:?}");
    }

    #[test]
    fn touching_corner_is_empty() {
        let c = clip_convex(&square(0.0, 0.0, 1.0), &square(1.0, 1.0, 1.0), 1.0);
        assert_eq!(c, Clipped::Empty);
        let tri = [[1.0, 1.0], [2.0, 0.5], [2.0, 2.0]];
        assert_eq!(
            clip_convex(&square(0.0, 0.0, 1.0), &tri, 1.0),
            Clipped::Empty
        );
    }

    #[test]
    fn one_inside_the_other() {
        let big = square(-1.0, -1.0, 3.0);
        let small = [[0.0, 0.0], [0.5, 0.1], [0.2, 0.6]];
        for (s, c) in [(&big[..], &small[..]), (&small[..], &big[..])] {
            match clip_convex(s, c, 1.0) {
                Clipped::Polygon(p) => {
                    assert_eq!(p.len(), 3);
                    assert!((polygon_area(&p) - polygon_area(&small)).abs() < 1e-15);
                }
                other => panic!("{other:?}"),
            }
        }
    }

    /// Edges at an angle of 1e-12: the intersection of a square with itself turned by 1e-12
    /// (area 1 up to 1e-12), and of a half-shifted pair whose long edges are near-parallel.
    #[test]
    fn near_parallel_edges() {
        let a = square(0.0, 0.0, 1.0);
        let b = rotate_about(&a, [0.5, 0.5], 1e-12);
        let c = clip_convex(&a, &b, 1.0);
        assert_valid(&c, 1.0);
        assert!((area_of(&c) - 1.0).abs() < 1e-12, "{c:?}");
        let shifted = rotate_about(&square(0.5, 0.0, 1.0), [1.0, 0.5], 1e-12);
        let c = clip_convex(&a, &shifted, 1.0);
        assert_valid(&c, 1.0);
        assert!((area_of(&c) - 0.5).abs() < 1e-12, "{c:?}");
        // A thin triangle nearly parallel to an edge of the square, crossing it.
        let thin = [[-0.5, 1.0 - 1e-12], [0.5, 0.5], [1.5, 1.0 + 1e-12]];
        let c = clip_convex(&a, &thin, 1.0);
        assert_valid(&c, 1.0);
        let reference = reference_area(&a, &thin);
        assert!(
            (area_of(&c) - reference).abs() < 1e-12,
            "{c:?}: {} vs {reference}",
            area_of(&c)
        );
    }

    /// An overlap 1e-10 wide and 1 long (area 1e-10 < 1e-8): a sliver, reported as such.
    #[test]
    fn sliver_overlap() {
        let a = square(0.0, 0.0, 1.0);
        let b = square(1.0 - 1e-10, 0.0, 1.0);
        assert_eq!(clip_convex(&a, &b, 1.0), Clipped::Sliver);
        // The same overlap relative to a segment of size 1e-2 is no sliver.
        let (a, b) = (square(0.0, 0.0, 1e-2), square(1e-2 - 1e-7, 0.0, 1e-2));
        match clip_convex(&a, &b, 1e-2) {
            Clipped::Polygon(p) => {
                let reference = reference_area(&a, &b);
                assert!((reference - 1e-9).abs() < 1e-18);
                assert!((polygon_area(&p) - reference).abs() < 1e-12 * 1e-4);
            }
            other => panic!("{other:?}"),
        }
    }

    /// A tiny polygon inside a huge one: exact when the scale is the tiny one's size, a sliver
    /// relative to the huge one's size.
    #[test]
    fn tiny_versus_huge() {
        let huge = square(-1e3, -1e3, 2e3);
        let tiny = square(0.25, 0.5, 1e-3);
        for (subject, clip) in [(&tiny, &huge), (&huge, &tiny)] {
            match clip_convex(subject, clip, 1e-3) {
                Clipped::Polygon(p) => {
                    let (got, expected) = (polygon_area(&p), polygon_area(&tiny));
                    assert!(
                        (got - expected).abs() < 1e-12 * 1e-6,
                        "{p:?}: {got} vs {expected}"
                    );
                }
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(clip_convex(&tiny, &huge, 2e3), Clipped::Sliver);
    }

    #[test]
    fn degenerate_input_never_gives_nan() {
        let a = square(0.0, 0.0, 1.0);
        let nan = [[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert_eq!(clip_convex(&a, &nan, 1.0), Clipped::Empty);
        assert_eq!(clip_convex(&nan, &a, 1.0), Clipped::Empty);
        assert_eq!(clip_convex(&a, &a, 0.0), Clipped::Empty);
        assert_eq!(clip_convex(&a, &a, f64::NAN), Clipped::Empty);
        let segment = [[0.0, 0.0], [1.0, 1.0], [0.5, 0.5]];
        assert_eq!(clip_convex(&a, &segment, 1.0), Clipped::Empty);
        let point = [[0.5, 0.5]; 4];
        assert_eq!(clip_convex(&a, &point, 1.0), Clipped::Empty);
        // Clockwise input is accepted (reversed).
        let cw: Vec<Point> = a.iter().rev().copied().collect();
        assert!((area_of(&clip_convex(&cw, &a, 1.0)) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn convexity_test() {
        let a = square(0.0, 0.0, 1.0);
        assert!(is_convex_ccw(&a, 1.0));
        let cw: Vec<Point> = a.iter().rev().copied().collect();
        assert!(!is_convex_ccw(&cw, 1.0));
        let dart = [[0.0, 0.0], [1.0, 0.0], [0.3, 0.3], [0.0, 1.0]];
        assert!(!is_convex_ccw(&dart, 1.0));
        let star: Vec<Point> = (0..5)
            .map(|k| {
                let t = 4.0 * std::f64::consts::PI * k as f64 / 5.0;
                [t.cos(), t.sin()]
            })
            .collect();
        assert!(polygon_area(&star) > 0.0);
        assert!(!is_convex_ccw(&star, 1.0));
        // A collinear vertex on an edge is still convex.
        let with_mid = [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(is_convex_ccw(&with_mid, 1.0));
        assert!(!is_convex_ccw(&a[..2], 1.0));
    }

    #[test]
    fn pallets_of_a_triangle_and_a_pentagon() {
        let tri = [[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
        let t = pallets(&tri, &[], PalletSplit::Centroid);
        assert_eq!(t.len(), 3);
        for p in &t {
            assert!((polygon_area(p) - 1.0 / 3.0).abs() < 1e-15);
            assert!((p[0][0] - 2.0 / 3.0).abs() < 1e-15 && (p[0][1] - 1.0 / 3.0).abs() < 1e-15);
        }
        assert_eq!(pallets(&tri, &[], PalletSplit::Fan), vec![tri]);
        let pent = [[0.0, 0.0], [2.0, 0.0], [2.5, 1.0], [1.0, 2.0], [-0.5, 1.0]];
        for (split, count) in [(PalletSplit::Centroid, 5), (PalletSplit::Fan, 3)] {
            let tris = pallets(&pent, &[], split);
            assert_eq!(tris.len(), count);
            let sum: f64 = tris.iter().map(|p| polygon_area(p)).sum();
            assert!((sum - polygon_area(&pent)).abs() < 1e-14);
            assert!(tris.iter().all(|t| polygon_area(t) > 0.0));
            assert!(pallets(&pent[..2], &[], split).is_empty());
        }
        // The fan's apex is the first vertex; its pallets share it.
        let fan = pallets(&pent, &[], PalletSplit::Fan);
        assert!(fan.iter().all(|t| t[0] == pent[0]));
        assert_eq!(fan[2], [pent[0], pent[3], pent[4]]);
        // With origins, the apex is the vertex of the smallest origin, whatever its place in
        // the list: here vertex 3 (the first polygon's vertex 0); the fan goes round from it.
        let origins = [
            VertexOrigin::Second(2),
            VertexOrigin::Crossing {
                first: [0, 1],
                second: [1, 2],
            },
            VertexOrigin::First(1),
            VertexOrigin::First(0),
            VertexOrigin::Second(0),
        ];
        let fan = pallets(&pent, &origins, PalletSplit::Fan);
        let expected = [[3, 4, 0], [3, 0, 1], [3, 1, 2]].map(|t| t.map(|i| pent[i]));
        assert_eq!(fan, expected);
        // The same pallets whichever vertex the clipping happens to return first.
        for k in 1..pent.len() {
            let (p, o) = (rotated_order(&pent, k), rotated_order(&origins, k));
            assert_eq!(
                pallets(&p, &o, PalletSplit::Fan),
                expected,
                "rotated by {k}"
            );
        }
    }

    /// The point a provenance stands for: the input vertex, or the crossing of the two lines.
    fn origin_point(origin: VertexOrigin, a: &[Point], b: &[Point]) -> Option<Point> {
        match origin {
            VertexOrigin::First(i) => Some(a[i]),
            VertexOrigin::Second(j) => Some(b[j]),
            VertexOrigin::Crossing { first, second } => {
                let (p, q) = (a[first[0]], a[first[1]]);
                let (c, d) = (b[second[0]], b[second[1]]);
                let (op, oq) = (orientation(c, d, p), orientation(c, d, q));
                let t = op / (op - oq);
                Some([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])])
            }
            VertexOrigin::Unresolved => None,
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1024))]

        /// Random convex pairs, in either vertex order: every vertex of the traced clipping is
        /// reproduced by its provenance (1e-9), and the polygon is that of `clip_convex`.
        #[test]
        fn provenance_reproduces_the_vertices(
            pa in points_strategy(),
            pb in points_strategy(),
            offset in (-1.0..1.0f64, -1.0..1.0f64),
            reverse in any::<bool>(),
        ) {
            let a = convex_hull(&pa);
            let mut b: Vec<Point> = convex_hull(&pb)
                .into_iter()
                .map(|v| [v[0] + offset.0, v[1] + offset.1])
                .collect();
            prop_assume!(a.len() >= 3 && b.len() >= 3);
            prop_assume!(polygon_area(&a) > 1e-3 && polygon_area(&b) > 1e-3);
            if reverse {
                b.reverse();
            }
            let (clipped, origins) = clip_convex_traced(&a, &b, 1.0);
            prop_assert_eq!(&clipped, &clip_convex(&a, &b, 1.0));
            if let Clipped::Polygon(p) = &clipped {
                prop_assert_eq!(p.len(), origins.len());
                for (v, &origin) in p.iter().zip(&origins) {
                    let traced = origin_point(origin, &a, &b);
                    prop_assert!(traced.is_some_and(|t| distance(t, *v) < 1e-9),
                        "{:?}: {:?} vs {:?}", origin, traced, v);
                }
            } else {
                prop_assert!(origins.is_empty());
            }
        }
    }

    /// Two unit squares offset by half a side: the overlap's corners are a vertex of each and two
    /// edge crossings, named with the input numbering (also for a clockwise second polygon).
    #[test]
    fn provenance_of_offset_squares() {
        let a = square(0.0, 0.0, 1.0);
        let b = square(0.5, 0.5, 1.0);
        let expected = [
            ([0.5, 0.5], VertexOrigin::Second(0)),
            (
                [1.0, 0.5],
                VertexOrigin::Crossing {
                    first: [1, 2],
                    second: [0, 1],
                },
            ),
            ([1.0, 1.0], VertexOrigin::First(2)),
            (
                [0.5, 1.0],
                VertexOrigin::Crossing {
                    first: [2, 3],
                    second: [3, 0],
                },
            ),
        ];
        let (clipped, origins) = clip_convex_traced(&a, &b, 1.0);
        let Clipped::Polygon(p) = clipped else {
            panic!("{clipped:?}");
        };
        assert_eq!(p.len(), 4);
        for (point, origin) in expected {
            let k = p.iter().position(|v| distance(*v, point) < 1e-15).unwrap();
            assert_eq!(origins[k], origin, "{point:?}");
        }
        // The second polygon clockwise: the same vertices, edges named by the input numbering.
        let cw: Vec<Point> = b.iter().rev().copied().collect();
        let (clipped, origins) = clip_convex_traced(&a, &cw, 1.0);
        let Clipped::Polygon(p) = clipped else {
            panic!("{clipped:?}");
        };
        let k = p
            .iter()
            .position(|v| distance(*v, [0.5, 0.5]) < 1e-15)
            .unwrap();
        assert_eq!(origins[k], VertexOrigin::Second(3));
        for (v, &origin) in p.iter().zip(&origins) {
            assert!(distance(origin_point(origin, &a, &cw).unwrap(), *v) < 1e-15);
        }
    }
}
