//! Rough search: candidate segment pairs from bounding boxes.
//!
//! Step 1 of the segment-to-segment integration (docs/theory.md section 3.1): before any secondary
//! segment is integrated against a primary segment, the pairs that can possibly overlap are found
//! from axis-aligned bounding boxes.
//!
//! # What it does
//!
//! The caller gives one [`Aabb`] per secondary segment and one per primary segment (usually
//! [`Aabb::of_points`] of the current positions of the face's nodes) and a search distance
//! `margin`. [`candidate_pairs`] returns every `(i, j)` such that secondary box `i`, inflated by
//! `margin` on every side, intersects primary box `j`. Boxes are closed: boxes that only touch (a
//! shared face, edge or corner) intersect. The result is exact with respect to that predicate: it
//! is the same set of pairs as the brute-force double loop over [`Aabb::intersects`], only
//! found faster.
//!
//! # What it does not do
//!
//! It only proposes candidates. It does not look at normals, at the orientation of the faces or
//! at the actual separation, and a candidate pair need not overlap at all once projected (boxes of
//! tilted or diagonal segments overlap far more often than the segments do). The mortar
//! integrator ([`super::mortar`]) does the real geometry, rejects pairs whose projected polygons
//! do not overlap (or whose normals do not oppose), and counts those rejections; a rejected
//! candidate costs one projection and one clipping, never a wrong result. The converse matters
//! more: a pair the search misses is never integrated, so the boxes must be conservative:
//!
//! - `margin` is the search distance: it must cover the largest gap at which contact should be
//!   detected plus the motion between two searches if a search is reused.
//! - The box of the nodes of a quadratic face does not always bound the curved face (a Lagrange
//!   quadratic overshoots its nodes: nodal values 0, 1, 1 at xi = -1, 0, 1 reach 1.125 at
//!   xi = 1/2), so for Quad8, Quad9 and Tri6 faces the margin must also cover that bulge, e.g. a
//!   fraction of [`Aabb::diagonal`].
//! - Which faces take part (only the declared interfaces, only the rank's own secondary faces)
//!   is the caller's choice.
//!
//! Degenerate input never panics. A box with a NaN coordinate, or with `min > max` on some axis
//! (e.g. [`Aabb::of_points`] of no points, or a box shrunk past empty by a negative `margin`),
//! intersects nothing and yields no pair; NaN positions are reported elsewhere (they stop the
//! step), not here.
//!
//! # Why an R*-tree
//!
//! Segment boxes are extended, overlapping objects of varying size (graded meshes, coarse against
//! fine sides, quadratic and linear faces), not points. A uniform grid needs a cell size tuned to
//! the segment size and degrades when sizes vary; sorting along one axis (sweep and prune)
//! degrades when a surface is large along the sorted axis. A bounding-volume hierarchy adapts to
//! both, and the `rstar` crate provides a maintained one. The tree is built once over the primary
//! boxes by bulk loading (rstar's overlap-minimizing top-down packing, which gives better nodes
//! than inserting one box at a time with the R* heuristics), and queried once per secondary box.
//! [`PrimaryTree`] keeps the tree for repeated queries.
//!
//! Flat interfaces normal to a coordinate axis (the usual test problems: punches, patch tests,
//! tied planes) need care: bulk loading splits along all three axes, and along an axis where
//! every box lies in the same thin layer that split separates nothing, so sibling nodes overlap
//! and queries slow down with the mesh size and depend on the order of the boxes. When the primary
//! boxes form a layer no thicker than their median diagonal along some axis, the tree is built on
//! the two other axes and the third is tested exactly at the leaves. Either way the pairs are the
//! same; only the speed differs.
//!
//! # Complexity
//!
//! With `n` secondary and `m` primary boxes of comparable size (a surface mesh), building the tree
//! costs `O(m log m)` and one query `O(log m + k)` with `k` its number of hits, so
//! [`candidate_pairs`] costs `O((n + m) log m + pairs)` (plus sorting each query's few hits).
//! Memory is `O(m + pairs)`. The brute-force loop is `O(n m)`. As for every R-tree this is the
//! typical cost, not a worst-case bound: boxes that all overlap each other (e.g. every segment
//! spanning the whole surface) make every query visit the whole tree.
//!
//! # Determinism
//!
//! The output is sorted by `(i, j)` (and [`PrimaryTree::query`] returns sorted indices), so it
//! depends only on the boxes and the margin, not on the tree's internal order, the order in which
//! the tree visits its nodes or the rstar version. Every rank holding the same boxes gets the same
//! pairs, in the same order.

use std::ops::ControlFlow;

use rstar::{Point, RTree, RTreeObject, AABB};

/// An axis-aligned box.
///
/// Closed: a point on the boundary is inside. A box with `min > max` on some axis, or with a NaN
/// coordinate, is empty: it intersects nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Aabb {
    /// The empty box: `min = +inf`, `max = -inf`. It intersects nothing.
    pub const EMPTY: Aabb = Aabb {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };

    /// The smallest box containing all `points`; [`Aabb::EMPTY`] for no points. A NaN coordinate
    /// of a point makes the box empty on that axis (so it intersects nothing).
    pub fn of_points(points: &[[f64; 3]]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            for (k, &v) in p.iter().enumerate() {
                if v.is_nan() {
                    b.min[k] = f64::NAN;
                    b.max[k] = f64::NAN;
                } else if !b.min[k].is_nan() {
                    b.min[k] = b.min[k].min(v);
                    b.max[k] = b.max[k].max(v);
                }
            }
        }
        b
    }

    /// The box grown by `by` on every side (shrunk if `by < 0`; a box shrunk past zero width is
    /// empty).
    pub fn inflated(&self, by: f64) -> Aabb {
        Aabb {
            min: self.min.map(|v| v - by),
            max: self.max.map(|v| v + by),
        }
    }

    /// `true` if the box contains at least one point: `min <= max` on every axis (false with a
    /// NaN coordinate).
    pub fn is_valid(&self) -> bool {
        (0..3).all(|k| self.min[k] <= self.max[k])
    }

    /// `true` if the two (closed) boxes share at least one point; touching boxes intersect. An
    /// empty box intersects nothing.
    pub fn intersects(&self, other: &Aabb) -> bool {
        (0..3).all(|k| {
            self.min[k] <= self.max[k]
                && other.min[k] <= other.max[k]
                && self.min[k] <= other.max[k]
                && other.min[k] <= self.max[k]
        })
    }

    /// Length of the box's diagonal, `|max - min|` (0 for an empty box): a size scale, e.g. for a
    /// margin relative to the segment size.
    pub fn diagonal(&self) -> f64 {
        if !self.is_valid() {
            return 0.0;
        }
        let d = [0, 1, 2].map(|k| self.max[k] - self.min[k]);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }
}

/// One primary box in the tree, with its index in the caller's slice.
struct Entry<P: Point> {
    envelope: AABB<P>,
    index: usize,
}

impl<P: Point> RTreeObject for Entry<P> {
    type Envelope = AABB<P>;

    fn envelope(&self) -> Self::Envelope {
        self.envelope.clone()
    }
}

/// The tree over the valid primary boxes: in 3D, or in the plane of two axes when the boxes
/// form a layer thinner than a typical box along the third (see the module docs).
enum Index {
    Spatial(RTree<Entry<[f64; 3]>>),
    Planar {
        tree: RTree<Entry<[f64; 2]>>,
        /// The two axes the tree is built on.
        axes: [usize; 2],
        /// All primary boxes, for the exact test along the dropped axis.
        boxes: Vec<Aabb>,
    },
}

/// A reusable tree over primary boxes, for searches repeated every Newton iteration.
///
/// Built once ([`PrimaryTree::new`], bulk loading in `O(m log m)`), queried any number of times.
/// The tree holds a copy of the boxes it was built from: if the primary surface moves, rebuild it,
/// or build it over boxes already inflated by the largest expected motion and keep it.
pub struct PrimaryTree {
    index: Index,
    len: usize,
}

impl PrimaryTree {
    /// Bulk-loads the tree over `primary`; box `j` is reported as index `j`. Empty boxes (see
    /// [`Aabb`]) are left out: they can intersect nothing.
    pub fn new(primary: &[Aabb]) -> Self {
        let valid = || primary.iter().enumerate().filter(|(_, b)| b.is_valid());
        let index = match thin_axis(primary) {
            Some(thin) => {
                let axes = match thin {
                    0 => [1, 2],
                    1 => [0, 2],
                    _ => [0, 1],
                };
                let entries = valid()
                    .map(|(index, b)| Entry {
                        envelope: planar(b, axes),
                        index,
                    })
                    .collect();
                Index::Planar {
                    tree: RTree::bulk_load(entries),
                    axes,
                    boxes: primary.to_vec(),
                }
            }
            None => {
                let entries = valid()
                    .map(|(index, b)| Entry {
                        envelope: AABB::from_corners(b.min, b.max),
                        index,
                    })
                    .collect();
                Index::Spatial(RTree::bulk_load(entries))
            }
        };
        PrimaryTree {
            index,
            len: primary.len(),
        }
    }

    /// Number of primary boxes the tree was built from (empty ones included).
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` if the tree was built from no boxes.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Replaces the contents of `out` with the indices of the primary boxes that intersect `b`
    /// (touching included), in increasing order. `b` is used as is: inflate it first for a
    /// search distance.
    pub fn query(&self, b: &Aabb, out: &mut Vec<usize>) {
        out.clear();
        self.visit(b, |j| out.push(j));
        out.sort_unstable();
    }

    /// Calls `f` with the index of every primary box intersecting `b`, in the tree's order.
    fn visit(&self, b: &Aabb, mut f: impl FnMut(usize)) {
        if !b.is_valid() {
            return;
        }
        let _ = match &self.index {
            Index::Spatial(tree) => {
                let envelope = AABB::from_corners(b.min, b.max);
                tree.locate_in_envelope_intersecting_int(&envelope, |e| {
                    f(e.index);
                    ControlFlow::<()>::Continue(())
                })
            }
            Index::Planar { tree, axes, boxes } => {
                tree.locate_in_envelope_intersecting_int(&planar(b, *axes), |e| {
                    if b.intersects(&boxes[e.index]) {
                        f(e.index);
                    }
                    ControlFlow::<()>::Continue(())
                })
            }
        };
    }
}

/// The projection of a (valid) box on two axes.
fn planar(b: &Aabb, axes: [usize; 2]) -> AABB<[f64; 2]> {
    AABB::from_corners(axes.map(|k| b.min[k]), axes.map(|k| b.max[k]))
}

/// The axis along which the valid boxes form a layer no thicker than their median diagonal, if
/// any (the thinnest such axis).
///
/// rstar's bulk loading splits every node into slabs along each of the three axes in turn, by
/// the boxes' lower corners. Along an axis where all boxes lie within about one box size (a flat
/// surface normal to a coordinate axis, the usual test interface), those slabs do not separate
/// anything: the split follows ties or round-off, sibling nodes cover the same region, and a query
/// has to descend into all of them: a 3D tree visits several times as many nodes per query as a
/// tree built on the two in-plane axes, more as the surface grows (figures in
/// docs/performance.md). Such an axis carries no useful information for the tree, so it is
/// dropped and tested exactly at the leaves instead.
fn thin_axis(primary: &[Aabb]) -> Option<usize> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut diagonals = Vec::with_capacity(primary.len());
    for b in primary.iter().filter(|b| b.is_valid()) {
        for k in 0..3 {
            lo[k] = lo[k].min(b.min[k]);
            hi[k] = hi[k].max(b.max[k]);
        }
        diagonals.push(b.diagonal());
    }
    if diagonals.is_empty() {
        return None;
    }
    let mid = diagonals.len() / 2;
    let (_, &mut median, _) = diagonals.select_nth_unstable_by(mid, f64::total_cmp);
    let extent = [0, 1, 2].map(|k| hi[k] - lo[k]);
    let thin = (0..3)
        .min_by(|&a, &b| extent[a].total_cmp(&extent[b]))
        .expect("three axes");
    // `<=`: a layer of zero thickness made of zero-size boxes is planar too.
    (extent[thin] <= median).then_some(thin)
}

/// Candidate pairs `(i, j)`: secondary box `i` (inflated by `margin`) intersects primary box `j`.
///
/// The tree is built over the primary boxes (bulk-loaded), queried once per secondary box; the
/// output is sorted by `(i, j)` so the result does not depend on the tree's internal order.
/// `O((n + m) log m + pairs)` for `n` secondary and `m` primary boxes of a surface mesh. Exactly
/// the pairs of the brute-force loop `secondary[i].inflated(margin).intersects(&primary[j])`.
pub fn candidate_pairs(secondary: &[Aabb], primary: &[Aabb], margin: f64) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    if secondary.is_empty() || primary.is_empty() {
        return pairs;
    }
    let tree = PrimaryTree::new(primary);
    for (i, s) in secondary.iter().enumerate() {
        let start = pairs.len();
        tree.visit(&s.inflated(margin), |j| pairs.push((i, j)));
        pairs[start..].sort_unstable();
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The O(n m) reference.
    fn brute_force(secondary: &[Aabb], primary: &[Aabb], margin: f64) -> Vec<(usize, usize)> {
        let mut pairs = Vec::new();
        for (i, s) in secondary.iter().enumerate() {
            let s = s.inflated(margin);
            for (j, p) in primary.iter().enumerate() {
                if s.intersects(p) {
                    pairs.push((i, j));
                }
            }
        }
        pairs
    }

    fn unit_at(x: f64, y: f64, z: f64) -> Aabb {
        Aabb {
            min: [x, y, z],
            max: [x + 1.0, y + 1.0, z + 1.0],
        }
    }

    /// A box from a corner and non-negative extents.
    fn boxed(corner: [f64; 3], size: [f64; 3]) -> Aabb {
        Aabb {
            min: corner,
            max: [0, 1, 2].map(|k| corner[k] + size[k]),
        }
    }

    /// Random boxes: coordinates on a coarse grid half of the time, so that touching (equal
    /// coordinates) and zero-width boxes are frequent, and arbitrary reals otherwise.
    fn arb_box() -> impl Strategy<Value = Aabb> {
        let coarse = (
            prop::array::uniform3(-5i32..5),
            prop::array::uniform3(0i32..3),
        )
            .prop_map(|(c, s)| boxed(c.map(f64::from), s.map(f64::from)));
        let fine = (
            prop::array::uniform3(-5.0f64..5.0),
            prop::array::uniform3(0.0f64..2.5),
        )
            .prop_map(|(c, s)| boxed(c, s));
        prop_oneof![coarse, fine]
    }

    fn arb_margin() -> impl Strategy<Value = f64> {
        prop_oneof![Just(0.0), Just(0.5), Just(1.0), 0.0f64..1.5]
    }

    /// Random boxes squeezed into a layer `[0, 0.05]` along `axis` (of zero thickness a third of
    /// the time), as the segments of a flat interface normal to that axis.
    fn arb_layer_box(axis: usize) -> impl Strategy<Value = Aabb> {
        let thickness = prop_oneof![Just(0.0), 0.0f64..0.05];
        (arb_box(), 0.0f64..0.05, thickness).prop_map(move |(mut b, lo, t)| {
            b.min[axis] = lo;
            b.max[axis] = (lo + t).min(0.05);
            b
        })
    }

    fn is_planar(tree: &PrimaryTree) -> bool {
        matches!(tree.index, Index::Planar { .. })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn matches_brute_force(
            secondary in prop::collection::vec(arb_box(), 0..80),
            primary in prop::collection::vec(arb_box(), 0..120),
            margin in arb_margin(),
        ) {
            let fast = candidate_pairs(&secondary, &primary, margin);
            prop_assert_eq!(&fast, &brute_force(&secondary, &primary, margin));
            // Sorted by (i, j), no duplicates.
            prop_assert!(fast.windows(2).all(|w| w[0] < w[1]));
        }

        #[test]
        fn reused_tree_matches_brute_force(
            primary in prop::collection::vec(arb_box(), 0..120),
            queries in prop::collection::vec(arb_box(), 1..20),
        ) {
            let tree = PrimaryTree::new(&primary);
            prop_assert_eq!(tree.len(), primary.len());
            let mut out = vec![usize::MAX; 3];
            for q in &queries {
                tree.query(q, &mut out);
                let expected: Vec<usize> =
                    (0..primary.len()).filter(|&j| q.intersects(&primary[j])).collect();
                prop_assert_eq!(&out, &expected);
            }
        }

        #[test]
        fn flat_layer_matches_brute_force(
            (primary, secondary) in (0usize..3).prop_flat_map(|axis| (
                prop::collection::vec(arb_layer_box(axis), 0..120),
                prop::collection::vec(prop_oneof![arb_layer_box(axis), arb_box()], 0..60),
            )),
            margin in prop_oneof![Just(0.0), Just(0.01), 0.0f64..0.5],
        ) {
            let fast = candidate_pairs(&secondary, &primary, margin);
            prop_assert_eq!(&fast, &brute_force(&secondary, &primary, margin));
        }

        #[test]
        fn independent_of_primary_order(
            secondary in prop::collection::vec(arb_box(), 0..40),
            primary in prop::collection::vec(arb_box(), 1..60),
            margin in arb_margin(),
            shift in 0usize..60,
        ) {
            // Rotating the primary boxes changes the tree; the pairs map back exactly.
            let m = primary.len();
            let shift = shift % m;
            let mut rotated = primary.clone();
            rotated.rotate_left(shift);
            let mut back: Vec<(usize, usize)> = candidate_pairs(&secondary, &rotated, margin)
                .into_iter()
                .map(|(i, j)| (i, (j + shift) % m))
                .collect();
            back.sort_unstable();
            prop_assert_eq!(back, candidate_pairs(&secondary, &primary, margin));
        }
    }

    #[test]
    fn flat_layers_get_a_planar_tree() {
        // A flat grid of unit squares normal to each axis in turn, with secondary squares just
        // above, beside (out of the layer) and straddling it.
        for axis in 0..3 {
            let lift = |p: [f64; 3]| {
                let mut q = [0.0; 3];
                let mut other = (0..3).filter(|&k| k != axis);
                q[other.next().unwrap()] = p[0];
                q[other.next().unwrap()] = p[1];
                q[axis] = p[2];
                q
            };
            let square = |x: f64, y: f64, z: f64| {
                Aabb::of_points(&[lift([x, y, z]), lift([x + 1.0, y + 1.0, z])])
            };
            let primary: Vec<Aabb> = (0..64)
                .map(|c| square((c % 8) as f64, (c / 8) as f64, 0.0))
                .collect();
            let tree = PrimaryTree::new(&primary);
            assert!(is_planar(&tree), "axis {axis}");
            let secondary = [
                square(2.5, 2.5, 0.1),
                square(2.5, 2.5, 0.0),
                Aabb::of_points(&[lift([3.0, 3.0, -1.0]), lift([3.5, 3.5, 1.0])]),
                square(-2.0, 3.0, 0.0),
            ];
            for margin in [0.0, 0.1, 1.0] {
                assert_eq!(
                    candidate_pairs(&secondary, &primary, margin),
                    brute_force(&secondary, &primary, margin),
                    "axis {axis}, margin {margin}"
                );
            }
            assert!(candidate_pairs(&secondary[..1], &primary, 0.05).is_empty());
            assert_eq!(candidate_pairs(&secondary[..1], &primary, 0.1).len(), 4);
        }
        // A thick cloud keeps the 3D tree.
        let cloud: Vec<Aabb> = (0..64)
            .map(|c| unit_at((c % 4) as f64, (c / 4 % 4) as f64, (c / 16) as f64))
            .collect();
        assert!(!is_planar(&PrimaryTree::new(&cloud)));
    }

    #[test]
    fn touching_boxes_intersect() {
        let a = unit_at(0.0, 0.0, 0.0);
        // Shared face, shared edge, shared corner: all intersect, both ways.
        for b in [
            unit_at(1.0, 0.0, 0.0),
            unit_at(1.0, 1.0, 0.0),
            unit_at(1.0, 1.0, 1.0),
            unit_at(-1.0, -1.0, -1.0),
        ] {
            assert!(a.intersects(&b) && b.intersects(&a), "{a:?} {b:?}");
        }
        // A flat (zero-thickness) box lying on a face of `a`.
        let flat = Aabb {
            min: [0.2, 0.2, 1.0],
            max: [0.8, 0.8, 1.0],
        };
        assert!(a.intersects(&flat));
        // A degenerate point box on a corner.
        let point = Aabb::of_points(&[[1.0, 1.0, 1.0]]);
        assert!(a.intersects(&point));
        // Just apart.
        let apart = unit_at(1.0 + 1e-12, 0.0, 0.0);
        assert!(!a.intersects(&apart) && !apart.intersects(&a));

        let pairs = candidate_pairs(&[a], &[unit_at(1.0, 1.0, 1.0), apart, flat], 0.0);
        assert_eq!(pairs, vec![(0, 0), (0, 2)]);
    }

    #[test]
    fn margin_reaches_exactly_the_gap() {
        let gap = 0.25;
        let s = unit_at(0.0, 0.0, 0.0);
        // Primary boxes at gap, 2 gap, 4 gap above the secondary one.
        let primary = [
            unit_at(0.0, 0.0, 1.0 + gap),
            unit_at(0.0, 0.0, 1.0 + 2.0 * gap),
            unit_at(0.0, 0.0, 1.0 + 4.0 * gap),
        ];
        assert!(candidate_pairs(&[s], &primary, 0.0).is_empty());
        assert!(candidate_pairs(&[s], &primary, 0.9 * gap).is_empty());
        // Inflated by exactly the gap, the boxes touch.
        assert_eq!(candidate_pairs(&[s], &primary, gap), vec![(0, 0)]);
        assert_eq!(
            candidate_pairs(&[s], &primary, 2.0 * gap),
            vec![(0, 0), (0, 1)]
        );
        assert_eq!(candidate_pairs(&[s], &primary, 10.0).len(), 3);
        // The margin applies on every side, not only towards +z.
        let below = [unit_at(0.0, -1.0 - gap, 0.0), unit_at(-1.0 - gap, 0.0, 0.0)];
        assert_eq!(candidate_pairs(&[s], &below, gap), vec![(0, 0), (0, 1)]);
        // A negative margin shrinks: overlapping by less than |margin| is no longer a candidate.
        let overlapping = [unit_at(0.9, 0.0, 0.0)];
        assert_eq!(candidate_pairs(&[s], &overlapping, 0.0), vec![(0, 0)]);
        assert!(candidate_pairs(&[s], &overlapping, -0.2).is_empty());
    }

    #[test]
    fn empty_inputs() {
        let boxes = [unit_at(0.0, 0.0, 0.0), unit_at(0.5, 0.5, 0.5)];
        assert!(candidate_pairs(&[], &[], 1.0).is_empty());
        assert!(candidate_pairs(&boxes, &[], 1.0).is_empty());
        assert!(candidate_pairs(&[], &boxes, 1.0).is_empty());

        let tree = PrimaryTree::new(&[]);
        assert!(tree.is_empty());
        let mut out = vec![7];
        tree.query(&boxes[0], &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn empty_and_nan_boxes_intersect_nothing() {
        let everything = Aabb {
            min: [f64::NEG_INFINITY; 3],
            max: [f64::INFINITY; 3],
        };
        let nan = Aabb::of_points(&[[0.0, f64::NAN, 0.0], [1.0, 1.0, 1.0]]);
        assert!(!nan.is_valid());
        let empty = Aabb::of_points(&[]);
        assert_eq!(empty, Aabb::EMPTY);
        let inverted = Aabb {
            min: [2.0, 0.0, 0.0],
            max: [1.0, 3.0, 3.0],
        };
        let normal = unit_at(0.0, 0.0, 0.0);
        for b in [nan, empty, inverted] {
            assert!(!b.intersects(&everything) && !everything.intersects(&b));
            assert!(!b.intersects(&b));
            assert_eq!(b.diagonal(), 0.0);
        }
        // In the tree (not built over them, no panic) and as queries.
        let primary = [nan, normal, empty, inverted, everything];
        let secondary = [inverted, normal, nan, empty];
        let pairs = candidate_pairs(&secondary, &primary, 0.1);
        assert_eq!(pairs, vec![(1, 1), (1, 4)]);
        assert_eq!(pairs, brute_force(&secondary, &primary, 0.1));
        assert!(candidate_pairs(&[normal], &primary, f64::NAN).is_empty());
    }

    #[test]
    fn box_helpers() {
        let b = Aabb::of_points(&[[1.0, 2.0, 3.0], [-1.0, 4.0, 3.0], [0.0, 3.0, 5.0]]);
        assert_eq!(
            b,
            Aabb {
                min: [-1.0, 2.0, 3.0],
                max: [1.0, 4.0, 5.0],
            }
        );
        assert!((b.diagonal() - 12.0f64.sqrt()).abs() < 1e-15);
        assert_eq!(
            b.inflated(0.5),
            Aabb {
                min: [-1.5, 1.5, 2.5],
                max: [1.5, 4.5, 5.5],
            }
        );
        assert_eq!(Aabb::of_points(&[[1.0, 2.0, 3.0]]).diagonal(), 0.0);
        assert!(!b.inflated(-1.5).is_valid());
    }

    #[test]
    fn grid_against_shifted_grid() {
        // 10 x 10 unit squares at z = 0 against 10 x 10 squares shifted by half a cell at
        // z = 0.01: every interior secondary square overlaps four primary ones.
        let square = |x: f64, y: f64, z: f64| Aabb {
            min: [x, y, z],
            max: [x + 1.0, y + 1.0, z],
        };
        let secondary: Vec<Aabb> = (0..100)
            .map(|c| square((c % 10) as f64, (c / 10) as f64, 0.0))
            .collect();
        let primary: Vec<Aabb> = (0..100)
            .map(|c| square((c % 10) as f64 + 0.5, (c / 10) as f64 + 0.5, 0.01))
            .collect();
        assert!(candidate_pairs(&secondary, &primary, 0.0).is_empty());
        let pairs = candidate_pairs(&secondary, &primary, 0.02);
        assert_eq!(pairs, brute_force(&secondary, &primary, 0.02));
        let first_interior = 11;
        let hits: Vec<usize> = pairs
            .iter()
            .filter(|p| p.0 == first_interior)
            .map(|p| p.1)
            .collect();
        assert_eq!(hits, vec![0, 1, 10, 11]);
    }
}
