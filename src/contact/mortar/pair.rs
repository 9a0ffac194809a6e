//! The value kernel: the mortar weights of one secondary face against one primary face
//! (docs/theory.md section 3).
//!
//! [`integrate_pair`] computes the mortar weights
//!
//! `n1_kb = int_gamma Phi_k N1_b dgamma`, `n2_kc = int_gamma Phi_k N2_c dgamma`
//!
//! over the overlap `gamma` of a secondary face (traction functions `Phi_k`,
//! [`super::segments`], shape functions `N1_b`) and a primary face (shape functions `N2_c`).
//!
//! # Steps
//!
//! Steps 1 to 4 are the walk both kernels share ([`super::overlap`]): every pair `(s, m)` of a
//! secondary and a primary sub-segment is projected onto the plane of `s`, clipped, and its
//! overlap split into pallets; each quadrature point `P` of a pallet is mapped back to local
//! coordinates on both projected sub-segments ([`super::projection`]). At each point this
//! kernel then does:
//!
//! 5. **Evaluate.** The local coordinates go to face parent coordinates by the sub-segments'
//!    affine maps ([`SubSegment::to_parent`]). There `N1` (secondary face), `Phi`
//!    ([`traction_shape_on`]) and `N2` (primary face) are evaluated.
//! 6. **Measure.** The weight of a point is the area element of the secondary face pulled back
//!    through the chain `P -> local -> xi -> x(xi)`:
//!
//!    `dgamma = w_P * J_face(xi) * det(dxi/dlocal) / det(dP/dlocal)`,
//!
//!    with `w_P` the pallet rule's weight times `det [u v]` of the pallet, `J_face =
//!    |x_,xi x x_,eta|` ([`crate::fe::face_normal`]), `det(dxi/dlocal)` the constant
//!    [`SubSegment::parent_jacobian`] and `det(dP/dlocal)` the Jacobian of the projected
//!    sub-segment's linear map at the point. Integrating it over the whole projected sub-segment
//!    gives exactly `int J_face dxi` over the sub-segment's parent region: the true area of the
//!    curved (isoparametric) face. So a secondary face fully covered by primary faces gets
//!    `sum n1 =` its area, to quadrature accuracy, whatever its curvature or in-plane distortion.
//!    (The simpler `dA_plane / |n_true . n_c|` equals it on flat faces with affine geometry but
//!    is only an approximation on curved faces, because the point `x(xi(P))` is not the point of
//!    the face that projects onto `P`.) On flat affine faces `dgamma` is the plane's area
//!    element.
//! 7. **Accumulate** `n1[k][b] += dgamma Phi_k N1_b` and `n2[k][c] += dgamma Phi_k N2_c` at the
//!    same points with the same weights, so that `sum_b n1_kb = sum_c n2_kc = int Phi_k` (up to
//!    round-off): linear momentum is conserved exactly (docs/theory.md 3.7).
//!
//! A sub-segment pair is accumulated only if every one of its points was mapped and evaluated to
//! finite values; otherwise it is skipped whole and counted ([`RejectStats::inverse_map_failed`]
//! or [`RejectStats::non_finite`]), so the momentum identity holds also for what is kept. The
//! counts are those of [`super::overlap`] ("Counting").
//!
//! # Shared with the linearization
//!
//! [`super::linearize`] differentiates this computation along the topology it finds: it runs the
//! same walk ([`super::overlap`]) and the same float inverse maps, and the pieces it
//! re-evaluates in dual numbers are written once, generically over the scalar
//! ([`crate::fe::shape::Scalar`]): the plane and the triangle and bilinear maps
//! ([`super::projection`]), the pallets, the sub-segment maps ([`SubSegment::to_parent_at`]) and
//! the shape functions. Here they run in `f64`.
//!
//! # Quadrature degree
//!
//! On flat interfaces with affine faces every integrand is a polynomial in the plane
//! coordinates: `Phi N` is bilinear x bilinear (degree 4) for linear faces and up to biquadratic x
//! biquadratic (degree 8) for Quad9. Hence the defaults of [`IntegrationOptions::for_faces`]: 8 if
//! either face is quadratic, 4 otherwise. The traction scheme is not re-checked here: validate it
//! with [`super::segments::traction_nodes`] once at set-up (scheme 1 on Quad8/Tri6 integrates the
//! face's own `N`, well defined but ill-posed as a constraint).

use super::clip::PalletSplit;
use super::overlap::{
    assert_node_counts, pallets_of, walk_sub_pairs, Overlap, PairFailure, SubPairKernel,
    SubPairOutcome,
};
pub use super::overlap::{FaceGeom, IntegrationOptions, RejectStats, OPPOSED_NORMALS_COSINE};
use super::segments::{traction_node_count, traction_shape_on, SubSegment, TractionScheme};
use crate::fe::shape::{normal_from_tangents, tangents_from_grad};
use crate::fe::{FaceType, Rule2};

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
    assert_node_counts(sec, pri, "integrate_pair");
    let (ns, np) = (sec.kind.num_nodes(), pri.kind.num_nodes());
    let traction_count = traction_node_count(sec.kind, opts.scheme);
    let mut kernel = ValueKernel {
        context: PairContext {
            sec,
            pri,
            scheme: opts.scheme,
            rule: FaceType::Tri3.quadrature(opts.degree),
            pallets: opts.pallets,
        },
        scratch: Scratch::default(),
        pair: Accumulator::new(traction_count, ns, np),
        total: Accumulator::new(traction_count, ns, np),
    };
    walk_sub_pairs(sec, pri, stats, &mut kernel);
    kernel.total.into_weights()
}

/// The value kernel on the sub-segment pairs of one face pair (the walk's [`SubPairKernel`]).
struct ValueKernel<'a> {
    context: PairContext<'a>,
    scratch: Scratch,
    /// The sub-segment pair being integrated, merged into `total` on success.
    pair: Accumulator,
    total: Accumulator,
}

impl SubPairKernel for ValueKernel<'_> {
    fn integrate(&mut self, overlap: &Overlap) -> SubPairOutcome {
        self.pair.clear();
        let integrated = self
            .context
            .integrate_overlap(overlap, &mut self.pair, &mut self.scratch);
        match integrated {
            Ok(()) => {
                self.total.merge(&self.pair);
                SubPairOutcome::Integrated {
                    points: self.pair.points,
                }
            }
            Err(failure) => SubPairOutcome::Failed(failure),
        }
    }
}

/// Everything fixed for one face pair.
struct PairContext<'a> {
    sec: &'a FaceGeom<'a>,
    pri: &'a FaceGeom<'a>,
    scheme: TractionScheme,
    rule: Rule2,
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
        for pallet in pallets_of(self.pallets, &overlap.polygon, &overlap.origins) {
            for (q, w) in self.rule.points.iter().zip(&self.rule.weights) {
                let p = pallet.point(*q);
                let (on_s, on_m) = overlap.locate(p)?;
                let xi_s = s.seg.to_parent(on_s.local);
                let xi_m = m.seg.to_parent(on_m.local);
                let face_jacobian = self.evaluate(s.seg, xi_s, xi_m, scratch);
                let weight = w * pallet.twice_area * face_jacobian * sec_jacobian / on_s.jacobian;
                let values = scratch.phi.iter().chain(&scratch.n1).chain(&scratch.n2);
                if !weight.is_finite() || !values.into_iter().all(|v| v.is_finite()) {
                    return Err(PairFailure::NonFinite);
                }
                acc.add_point(weight, &scratch.phi, &scratch.n1, &scratch.n2);
            }
        }
        Ok(())
    }

    /// Phi and N1 at `xi_s` on the secondary face, N2 at `xi_m` on the primary face; returns the
    /// surface Jacobian `J_face(xi_s)` (from the gradients of N1, as [`crate::fe::face_normal`]).
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::mortar::segments::traction_nodes;
    use crate::contact::mortar::test_support::{geom, max_difference, settings, SCHEMES};
    use crate::fe::face_normal;
    use crate::vec3::{cross, dot, normalized, Vec3};

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
                    &geom(sec.kind, &xs),
                    &geom(pri.kind, &xp),
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
        let (w, stats) = integrate_quad4_with(TractionScheme::FaceShape, &sec_x, &pri_x);
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

    /// Scheme 1 on a Quad9 face against a coincident primary: `a_A = sum_B n1_AB` are the integrals
    /// of the Quad9 functions, `A/36, A/9, 4A/9` (corner, mid-edge, centre), all positive.
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
        integrate_quad4_with(TractionScheme::Corners, sec_x, pri_x)
    }

    /// A Quad4 pair integrated with `scheme`: finite weights, and the counts.
    fn integrate_quad4_with(
        scheme: TractionScheme,
        sec_x: &[Vec3],
        pri_x: &[Vec3],
    ) -> (PairWeights, RejectStats) {
        let opts = IntegrationOptions::for_faces(scheme, FaceType::Quad4, FaceType::Quad4);
        let mut stats = RejectStats::default();
        let w = integrate_pair(
            &geom(FaceType::Quad4, sec_x),
            &geom(FaceType::Quad4, pri_x),
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
                    &geom(FaceType::Quad9, &sec),
                    &geom(FaceType::Tri6, &pri),
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
                &geom(FaceType::Quad9, &sec),
                &geom(FaceType::Tri6, &pri),
                &opts,
                &mut stats,
            );
            let w1 = integrate_pair(
                &geom(FaceType::Quad9, &sec_m),
                &geom(FaceType::Tri6, &pri_m),
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
