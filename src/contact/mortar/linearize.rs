//! The mortar weights of one face pair **with their exact derivatives** with respect to the node
//! coordinates of both faces: the consistent tangent of the contact kernel (docs/theory.md
//! section 7).
//!
//! [`integrate_pair_linearized`] returns the weights `n1_kb`, `n2_kc` of
//! [`super::integrate_pair`] (dense, [`LinearizedWeights`]) and `d n1_kb / d y_j`,
//! `d n2_kc / d y_j` for the face coordinates flattened as
//! `y = [x_s0, y_s0, z_s0, x_s1, ..., x_p0, ...]`: the secondary face's nodes (face order) first,
//! then the primary face's; `ndof = 3 (ns + np)`.
//!
//! # Method: topology in floats, geometry again in dual numbers
//!
//! The weights are piecewise smooth functions of `y`: smooth as long as the *topology* does not
//! change (which sub-segment pairs overlap, which vertices the overlap polygon has and where each
//! comes from, which pallets are integrated). The derivative computed here is the derivative of
//! the branch taken, by forward-mode automatic differentiation (`num_dual`):
//!
//! 1. **Topology from floats.** Every sub-segment pair `(s, m)` goes through the float code of
//!    [`super::integrate_pair`] (`pair.rs`): plane, projection, rejection tests, clipping, and
//!    the float inverse maps of every quadrature point (at the real parts of the dual points,
//!    which are the float points up to round-off). So the same pairs are rejected and counted in
//!    [`RejectStats`], the same pallets and points are integrated, a failed inverse map fails
//!    the same pair, and a non-finite input gives the same count and zero weights.
//! 2. **Provenance.** The clipping records where each vertex of the overlap comes from
//!    ([`super::clip::clip_convex_traced`]): while Sutherland-Hodgman cuts, every vertex carries
//!    the two edge lines it lies on (an input vertex lies on its two edges, a crossing on the cut
//!    edge and the clipping edge), so each output vertex is a vertex of `s`, a vertex of `m`, or
//!    the crossing of an edge of `s` with an edge of `m`. Recording is exact; classifying the
//!    float output afterwards would need tolerances.
//! 3. **Geometry again, in dual numbers, along that topology**, in two levels of forward mode:
//!    - *Level 1* (`DualSVec64<N>`, seeded on the `ndof` node coordinates): the projection plane
//!      of `s` (origin `x(xi_c)` and normal at the sub-segment centre, the axis `e1` along its
//!      projected first edge, `e2 = n x e1`: the very code of `pair.rs`, generic over the
//!      scalar) and the projected vertices of `s` and `m`: at most 16 plane coordinates `P`,
//!      and their Jacobian `dP/dy`.
//!    - *Level 2* (derivatives with respect to those 16 plane coordinates): the overlap
//!      vertices from their provenance (a crossing of the lines `a b` and `c d` is
//!      `a + t (b - a)`, `t = o_a / (o_a - o_b)`, `o` the orientation about `c d`), the pallet
//!      apex, the pallet areas, in `DualSVec64<16>` (once per sub-segment pair or pallet);
//!      then per quadrature point, with the chain rule written out in plain floats
//!      (`PlaneValue`, whose docs give the formulas): the point, its local coordinates on both
//!      projected sub-segments, `det(dP/dlocal)`, the face parent coordinates `xi_s`, `xi_m`
//!      (the sub-segments' affine maps), and from these `Phi(xi_s)`, `N1(xi_s)`, `N2(xi_m)`
//!      and the surface Jacobian `J_face(xi_s)`. Every value and every derivative is computed
//!      by the floating-point operations, in their order, that 16-slot duals would do (the
//!      quotient `a / b` as `a * (1 / b)`, the product rule `da b + db a`, ...): the result is
//!      bit for bit that of the same code in `DualSVec64<16>` (kept in the tests as
//!      `dual_reference`). See "Exactness" below for why.
//!    - The shape functions are evaluated in floats with their `xi`-derivatives (and, for the
//!      secondary face, their second derivatives, for the `xi`-derivatives of `J_face`:
//!      [`FaceType::tensor_shape_derivatives`] on Quad4 and Quad9, rounded as `DualSVec64<2>`
//!      rounds them; the generic kernels of [`crate::fe::shape`] in `DualSVec64<2>` on the other
//!      faces) and chained to level 2 through `dxi/dP`, which is exact and much cheaper than
//!      evaluating them in 16-slot duals.
//!    - `J_face = |x_,xi x x_,eta|` also depends on the secondary coordinates directly:
//!      `dJ = (x_,eta x n) . dx_,xi + (n x x_,xi) . dx_,eta` with `dx_,i = sum_a N_a,i dx_a`.
//!
//!    The weights are `n = F(P(y), x_s)`, so `dn/dy = dF/dP dP/dy + dF/dx_s`, assembled once per
//!    sub-segment pair. The level-2 work per quadrature point (the bulk of the cost) does not
//!    grow with the number of nodes.
//! 4. **Inverse maps**: solved in floats (the points are those of `integrate_pair`), then
//!    differentiated: on a triangle the closed-form barycentric coordinates in dual numbers; on
//!    a quadrilateral one final Newton step in dual numbers from the converged float solution,
//!    `local = local_f - J_f^-1 (P(local_f) - p)` (float `J_f`: its derivative multiplies the
//!    residual, zero at convergence). Its real part is the float solution (to the 1e-13 Newton
//!    tolerance) and its derivative is the implicit-function derivative.
//!
//! Real parts: every dual computation runs the same formulas as the float path, and the overlap
//! vertices keep the float clipping's values as real part (the provenance supplies only their
//! derivatives), so the weights equal those of [`super::integrate_pair`] up to round-off.
//!
//! # Exactness
//!
//! The float level 2 reproduces the dual formulation bit for bit, values and derivatives, not
//! just to round-off, for two reasons measured on the bending scene (`cases/bending`):
//!
//! - The nonlinear solve depends on the last bit of the weights where surfaces touch exactly:
//!   there the weighted gaps are round-off (`+-1e-16`) and their signs decide which nodes get a
//!   (round-off) pressure and so a friction state at the first tangent, the predictor's. With
//!   one quotient rounded as `a / b` instead of the duals' `a * (1 / b)` the weights changed in
//!   the last bit, the friction states of the first tangent with them, and the scene's first
//!   load step no longer converged.
//! - Where an overlap vertex is the crossing of two nearly parallel edges (edges of the two
//!   meshes a few `1e-5` apart), its plane derivatives reach `1e12` and cancel in the integral:
//!   the derivatives are then only as accurate as `1e-16 * 1e12` allows, and a different order
//!   of the same operations changed them by up to `1e-4` relative.
//!
//! Keeping the duals' operations keeps the kernel's results those of the dual formulation (so a
//! scene converges as it did with it); the test `float_level2_reproduces_the_dual_reference`
//! checks it on generic pairs of every face type and scheme and on pairs of the bending scene.
//! (The first reason has since lost its force: a node inside the touching band takes the stick
//! tangent without traction, `contact::law::touching_friction`, so the round-off signs of
//! touching gaps no longer pick friction states. Measured: with Dunavant's pallet rules in
//! place of collapsed Gauss, which change the weights at round-off, the two-pass bending
//! scene's first step took 28 iterations and 6 cuts before that change and 2 after it.)
//!
//! # Degenerate configurations
//!
//! At a change of topology (a vertex exactly on an edge, coincident edges) the weights are
//! continuous but not differentiable: the derivative returned is that of the branch the float
//! code took, finite. An overlap vertex whose provenance is ambiguous (two points merged by the
//! clipping's length tolerance: [`super::clip::VertexOrigin::Unresolved`]), or whose provenance
//! does not reproduce the float vertex (a crossing clamped to an edge end), is held fixed (zero
//! derivative) and counted in [`LinearizedWeights::unresolved_vertices`]. A sub-segment pair
//! whose derivatives are not finite while the float values are is skipped whole and counted as
//! [`RejectStats::non_finite`], like a non-finite value in `integrate_pair`.
//!
//! # Cost
//!
//! Level 1 uses `DualSVec64<N>` with `N = 24` when `ns + np <= 8` (Tri3 and Quad4 pairs) and
//! `N = 54` otherwise, but only for a few hundred operations per overlapping sub-segment pair
//! (nothing in duals is computed for pairs that are rejected: those cost the float work only). The bulk is
//! per quadrature point and independent of `N`: level 2 (16 slots, plain floats) and the
//! accumulation. The derivative of `w Phi_k N_b` at a point lies in the span of five directions,
//! `dw/dP`, `dxi_s/dP` and `dxi_m/dP`, plus `dw/dx_s`; the points of a pallet are tabulated (one
//! coefficient per entry and direction) and added by matrix products (`nalgebra`'s `gemm`, which
//! uses the vectorized `matrixmultiply` kernels; the `n1` rows without the `dxi_m` directions),
//! then chained with `dP/dy` once per sub-segment pair, without the block of `dP/dy` that is
//! zero (the plane coordinates of the secondary vertices do not depend on the primary nodes),
//! into a row-major buffer whose rows are added to the output's. Scheme 3 skips the traction
//! nodes that are not vertices of the secondary sub-segment. Nothing is allocated per point,
//! and the derivative buffers are not cleared per sub-segment pair (its first pallet
//! overwrites them). Measured (release, one core, the pairs of `benches/mortar.rs`, scheme 2,
//! 2026-11-23, with `integrate_pair` on the same host): Quad4-Quad4 27 us per pair (5.5 times
//! `integrate_pair`), Quad9-Quad9 0.62 ms (7.4 times); 36 us and 0.90 ms with the full product
//! and the buffers cleared per sub-segment pair.
//!
//! # Tests
//!
//! Against the dual-number formulation of level 2 (`dual_reference`): values bit for bit,
//! derivatives to 1e-13 of the largest (measured: bit for bit as well, over 6 489 pairs of the
//! bending scene and 2.0e6 numbers of generic pairs; the test asks for less). Against
//! [`super::integrate_pair`] for all 25 face-type pairs and every valid scheme on tilted,
//! curved, perturbed, partially overlapping faces: the values (1e-13 of the largest weight) and
//! the derivatives against central finite differences; the momentum identity
//! `sum_b dn1_kb = sum_c dn2_kc`; frame indifference (zero derivative along rigid translations
//! and rotations of both faces); finite output on degenerate input (coincident faces, a vertex
//! exactly on an edge, slivers, NaN coordinates).

#[cfg(test)]
mod dual_reference;

use nalgebra::{DMatrix, DMatrixViewMut};
use num_dual::DualSVec64;

use super::clip::{PalletSplit, VertexOrigin};
use super::pair::{
    det2, diameter, is_finite_face, overlap_of_sub_pair, primary_subs, solve2, Bilinear, FaceGeom,
    IntegrationOptions, LocalPoint, Overlap, PairFailure, Plane, Projected, RejectStats,
    SubPairOutcome,
};
use super::segments::{
    sub_segments, traction_node_count, traction_shape_on_at, SubSegment, TractionScheme,
};
use crate::fe::shape::TensorShape;
use crate::fe::{FaceType, Rule2};
use crate::vec3::cross;

/// Mortar weights of one face pair, dense, with their derivatives.
///
/// Inputs are the face coordinates flattened as `y = [x_s0, y_s0, z_s0, x_s1, ..., x_p0, ...]`:
/// the secondary face's nodes (face order) first, then the primary face's; `ndof = 3 (ns + np)`.
#[derive(Clone, Debug, Default)]
pub struct LinearizedWeights {
    /// Traction nodes `nt`, secondary nodes `ns`, primary nodes `np`.
    pub traction_nodes: usize,
    pub sec_nodes: usize,
    pub pri_nodes: usize,
    /// `n1[k * ns + b]`.
    pub n1: Vec<f64>,
    /// `n2[k * np + c]`.
    pub n2: Vec<f64>,
    /// `dn1[(k * ns + b) * ndof + j] = d n1_kb / d y_j`.
    pub dn1: Vec<f64>,
    /// `dn2[(k * np + c) * ndof + j] = d n2_kc / d y_j`.
    pub dn2: Vec<f64>,
    /// Overlap area (sum of the quadrature weights).
    pub area: f64,
    /// Overlap vertices held fixed because their provenance was ambiguous (degenerate
    /// configurations only; see the module docs).
    pub unresolved_vertices: usize,
}

impl LinearizedWeights {
    /// `3 (ns + np)`.
    pub fn ndof(&self) -> usize {
        3 * (self.sec_nodes + self.pri_nodes)
    }

    /// Zero weights and derivatives for the given sizes.
    fn zeros(traction_nodes: usize, sec_nodes: usize, pri_nodes: usize) -> Self {
        let ndof = 3 * (sec_nodes + pri_nodes);
        LinearizedWeights {
            traction_nodes,
            sec_nodes,
            pri_nodes,
            n1: vec![0.0; traction_nodes * sec_nodes],
            n2: vec![0.0; traction_nodes * pri_nodes],
            dn1: vec![0.0; traction_nodes * sec_nodes * ndof],
            dn2: vec![0.0; traction_nodes * pri_nodes * ndof],
            area: 0.0,
            unresolved_vertices: 0,
        }
    }
}

/// As [`super::integrate_pair`], with derivatives (see [`LinearizedWeights`] and the module
/// docs). Rejections, integrated pairs and their quadrature points are counted in `stats` as
/// `integrate_pair` counts them, except that a sub-segment pair whose derivatives are not finite
/// while its values are counts as non-finite here (module docs, "Degenerate configurations").
///
/// # Panics
/// If a face's `x.len()` differs from its type's number of nodes.
pub fn integrate_pair_linearized(
    sec: &FaceGeom,
    pri: &FaceGeom,
    opts: &IntegrationOptions,
    stats: &mut RejectStats,
) -> LinearizedWeights {
    assert_eq!(
        sec.x.len(),
        sec.kind.num_nodes(),
        "integrate_pair_linearized: secondary"
    );
    assert_eq!(
        pri.x.len(),
        pri.kind.num_nodes(),
        "integrate_pair_linearized: primary"
    );
    linearized_with(sec, pri, opts, stats, Kernel::integrate_overlap)
}

/// [`integrate_pair_linearized`] with the given level 2 (the float one, or in the tests the
/// dual-number reference).
fn linearized_with<'a>(
    sec: &'a FaceGeom<'a>,
    pri: &'a FaceGeom<'a>,
    opts: &IntegrationOptions,
    stats: &mut RejectStats,
    level2: Level2<'a>,
) -> LinearizedWeights {
    let (ns, np) = (sec.kind.num_nodes(), pri.kind.num_nodes());
    let mut out = LinearizedWeights::zeros(traction_node_count(sec.kind, opts.scheme), ns, np);
    if !is_finite_face(sec) || !is_finite_face(pri) {
        stats.non_finite += 1;
        return out;
    }
    let kernel = Kernel::new(sec, pri, opts, level2);
    if ns + np <= 8 {
        kernel.run::<24>(&mut out, stats);
    } else {
        kernel.run::<54>(&mut out, stats);
    }
    out
}

/// Slots of the level-2 duals: the plane coordinates of the vertices of the secondary
/// sub-segment (`2 i + axis`) and of the primary one (`PRIMARY_SLOT + 2 j + axis`).
const PLANE_SLOTS: usize = 16;
const PRIMARY_SLOT: usize = 8;

/// Level-2 dual: derivatives with respect to the plane coordinates of a sub-segment pair.
type PlaneDual = DualSVec64<PLANE_SLOTS>;

/// Derivatives with respect to a face's parent coordinates `xi`.
type ParentDual = DualSVec64<2>;

/// Largest `3 ns` (Quad9).
const MAX_SEC_DOFS: usize = 27;

/// Largest number of face nodes (Quad9).
const MAX_NODES: usize = 9;

/// An overlap vertex whose provenance misses the float vertex by more than this times the
/// sub-segment size is held fixed (see the module docs).
const PROVENANCE_TOLERANCE: f64 = 1e-8;

/// The derivative slots of a dual number (zeros if it has none).
fn slots<const K: usize>(x: &DualSVec64<K>) -> [f64; K] {
    x.eps.0.as_ref().map_or([0.0; K], |m| m.data.0[0])
}

/// A dual number with real part `re` and the derivatives of `like`.
fn with_re<const K: usize>(re: f64, like: &DualSVec64<K>) -> DualSVec64<K> {
    DualSVec64::new(re, like.eps)
}

/// Node coordinates as duals seeded on slots `first + 3 a + axis`.
fn seeded<const N: usize>(x: &[[f64; 3]], first: usize) -> Vec<[DualSVec64<N>; 3]> {
    x.iter()
        .enumerate()
        .map(|(a, p)| {
            std::array::from_fn(|d| DualSVec64::from_re(p[d]).derivative(first + 3 * a + d))
        })
        .collect()
}

/// Parent coordinates as duals seeded on their own two slots.
fn parent_seed(xi: [f64; 2]) -> [ParentDual; 2] {
    [
        ParentDual::from_re(xi[0]).derivative(0),
        ParentDual::from_re(xi[1]).derivative(1),
    ]
}

/// A function of the parent coordinates: value and `xi`-derivatives, as plain floats.
#[derive(Clone, Copy, Default)]
struct OfParent {
    re: f64,
    d: [f64; 2],
}

impl OfParent {
    fn of(f: &ParentDual) -> Self {
        OfParent {
            re: f.re,
            d: slots(f),
        }
    }

    /// The first `from.len()` entries of `to` from `from`.
    fn fill(to: &mut [OfParent], from: &[ParentDual]) {
        for (t, f) in to.iter_mut().zip(from) {
            *t = OfParent::of(f);
        }
    }
}

/// Everything fixed for one face pair.
struct Kernel<'a> {
    sec: &'a FaceGeom<'a>,
    pri: &'a FaceGeom<'a>,
    scheme: TractionScheme,
    rule: Rule2,
    pallets: PalletSplit,
    level2: Level2<'a>,
}

/// The level 2 of one overlapping sub-segment pair: [`Kernel::integrate_overlap`] (in the tests
/// also `dual_reference::integrate_overlap`, which it must reproduce bit for bit).
type Level2<'a> = fn(&Kernel<'a>, &Overlap, &mut SubPairTangent) -> Result<(), PairFailure>;

impl<'a> Kernel<'a> {
    fn new(
        sec: &'a FaceGeom<'a>,
        pri: &'a FaceGeom<'a>,
        opts: &IntegrationOptions,
        level2: Level2<'a>,
    ) -> Self {
        Kernel {
            sec,
            pri,
            scheme: opts.scheme,
            rule: FaceType::Tri3.quadrature(opts.degree),
            pallets: opts.pallets,
            level2,
        }
    }

    /// All sub-segment pairs, with level-1 duals of `N >= ndof` slots.
    fn run<const N: usize>(&self, out: &mut LinearizedWeights, stats: &mut RejectStats) {
        let (sec, pri) = (self.sec, self.pri);
        let sec_dual = seeded::<N>(sec.x, 0);
        let pri_dual = seeded::<N>(pri.x, 3 * sec.x.len());
        let pri_segments = sub_segments(pri.kind);
        let primaries = primary_subs(pri, &pri_segments);
        let mut tangent = SubPairTangent::new(out, self.rule.points.len());
        for s_seg in &sub_segments(sec.kind) {
            let Some(plane) = Plane::of_sub_segment(sec.kind, sec.x, s_seg) else {
                stats.non_convex += pri_segments.len();
                continue;
            };
            tangent.start(self.active_traction_nodes(s_seg, out.traction_nodes));
            // Level 1 of the secondary sub-segment, at its first overlap.
            let mut level1 = None;
            for primary in &primaries {
                let outcome = match overlap_of_sub_pair(sec, pri, &plane, s_seg, primary) {
                    Ok(overlap) => {
                        let secondary = level1.get_or_insert_with(|| {
                            let dual_plane = Plane::of_sub_segment(sec.kind, &sec_dual, s_seg)?;
                            let vertices = project(&dual_plane, &sec_dual, s_seg);
                            Some((dual_plane, vertices))
                        });
                        match secondary {
                            Some((dual_plane, s_vertices)) => {
                                let m_vertices = project(dual_plane, &pri_dual, primary.seg);
                                let vertices = [&s_vertices[..], &m_vertices[..]];
                                self.integrate_sub_pair(&overlap, vertices, &mut tangent, out)
                            }
                            // (The float plane exists, so only by round-off at its limits.)
                            None => SubPairOutcome::Failed(PairFailure::NonFinite),
                        }
                    }
                    Err(outcome) => outcome,
                };
                stats.record(&outcome);
            }
        }
    }

    /// One overlapping sub-segment pair, added to `out` if it is integrated in full;
    /// `vertices` are the level-1 projected vertices of `s` and `m`.
    fn integrate_sub_pair<const N: usize>(
        &self,
        overlap: &Overlap,
        vertices: [&[[DualSVec64<N>; 2]]; 2],
        tangent: &mut SubPairTangent,
        out: &mut LinearizedWeights,
    ) -> SubPairOutcome {
        tangent.clear();
        match (self.level2)(self, overlap, tangent) {
            Ok(()) => {
                let chain = plane_chain(vertices[0], vertices[1], out.ndof());
                tangent.merge_into(out, &chain)
            }
            Err(failure) => SubPairOutcome::Failed(failure),
        }
    }

    /// The traction nodes whose `Phi` is not identically zero on the secondary sub-segment: its
    /// vertices for scheme 3, all otherwise.
    fn active_traction_nodes(&self, s_seg: &SubSegment, count: usize) -> Vec<usize> {
        match self.scheme {
            TractionScheme::PiecewiseLinear => s_seg.local_nodes.clone(),
            _ => (0..count).collect(),
        }
    }

    /// Level 2 for one overlapping sub-segment pair, into `tangent` (merged by the caller on
    /// success only, like `integrate_pair` does).
    fn integrate_overlap(
        &self,
        overlap: &Overlap,
        tangent: &mut SubPairTangent,
    ) -> Result<(), PairFailure> {
        let s_map = PlaneMap::new(&overlap.s, 0);
        let m_map = PlaneMap::new(&overlap.m, PRIMARY_SLOT);
        let (polygon, unresolved) = traced_polygon(overlap, &s_map, &m_map);
        tangent.unresolved += unresolved;
        let sec_jacobian = overlap.s.seg.parent_jacobian();
        let apex = self.pallets.apex(&polygon, &overlap.origins);
        for (i, j) in self.pallets.edges(polygon.len(), &overlap.origins) {
            let (a, b) = (polygon[i], polygon[j]);
            let u = [a[0] - apex[0], a[1] - apex[1]];
            let v = [b[0] - apex[0], b[1] - apex[1]];
            let twice_area = det2(u, v);
            if twice_area.re <= 0.0 {
                continue;
            }
            let pallet = Pallet {
                apex: apex.map(|c| PlaneValue::of(&c)),
                u: u.map(|c| PlaneValue::of(&c)),
                v: v.map(|c| PlaneValue::of(&c)),
                twice_area: PlaneValue::of(&twice_area),
            };
            for (point, (q, w)) in self.rule.points.iter().zip(&self.rule.weights).enumerate() {
                let p = pallet.point(*q);
                let p_float = [p[0].re, p[1].re];
                let on_s = overlap.s.invert(p_float).ok_or(PairFailure::InverseMap)?;
                let on_m = overlap.m.invert(p_float).ok_or(PairFailure::InverseMap)?;
                let local_s = s_map.local(&p, &on_s);
                let local_m = m_map.local(&p, &on_m);
                let at = PointGeometry {
                    seg: overlap.s.seg,
                    xi_s: to_parent(overlap.s.seg, &local_s),
                    xi_m: to_parent(overlap.m.seg, &local_m),
                    measure: pallet
                        .twice_area
                        .scaled(w * sec_jacobian)
                        .over(&s_map.jacobian(&local_s)),
                };
                self.add_point(&at, point, tangent)?;
            }
            tangent.add_pallet();
        }
        if tangent.is_finite() {
            Ok(())
        } else {
            Err(PairFailure::NonFinite)
        }
    }

    /// Evaluates `Phi`, `N1`, `N2` and the weight at quadrature point `point` of the current
    /// pallet and tabulates them in `tangent` (values added at once, derivatives by pallet).
    fn add_point(
        &self,
        at: &PointGeometry,
        point: usize,
        tangent: &mut SubPairTangent,
    ) -> Result<(), PairFailure> {
        let (mut values, face_jacobian, mut dweight_dx) =
            self.shape_values(at, &mut tangent.phi_scratch);
        let weight = at.measure.times_lifted(&face_jacobian, &at.xi_s);
        // dweight/dx_s = weight / J_face dJ_face/dx_s.
        let ratio = if face_jacobian.re > 0.0 {
            weight.re / face_jacobian.re
        } else {
            0.0
        };
        dweight_dx.iter_mut().for_each(|g| *g *= ratio);
        values.weight = weight.re;
        if !values.is_finite() {
            return Err(PairFailure::NonFinite);
        }
        let sec_dofs = 3 * self.sec.x.len();
        tangent.tabulate(point, &values, at, &weight, &dweight_dx[..sec_dofs]);
        Ok(())
    }

    /// `Phi(xi_s)`, `N1(xi_s)`, `N2(xi_m)` with their `xi`-derivatives (the weight is left to
    /// the caller), `J_face(xi_s)` with its `xi`-derivatives, and `dJ_face/dx_s`.
    fn shape_values(
        &self,
        at: &PointGeometry,
        phi_scratch: &mut Vec<ParentDual>,
    ) -> (PointValues, OfParent, [f64; MAX_SEC_DOFS]) {
        let (sec, pri) = (self.sec, self.pri);
        let ns = sec.x.len();
        let mut values = PointValues::default();
        let xi_s = at.xi_s.map(|v| v.re);
        let mut shapes = [TensorShape::default(); MAX_NODES];
        shape_derivatives(sec.kind, xi_s, &mut shapes[..ns]);
        let mut dj_dx = [0.0; MAX_SEC_DOFS];
        let face_jacobian = face_jacobian(sec.x, &shapes[..ns], &mut dj_dx);
        for (t, shape) in values.n1.iter_mut().zip(&shapes[..ns]) {
            *t = OfParent {
                re: shape.value,
                d: shape.value_derivative,
            };
        }
        match self.scheme {
            TractionScheme::FaceShape => values.phi = values.n1,
            // The corner functions are the linear face's.
            TractionScheme::Corners => {
                let linear = if sec.kind.is_quad() {
                    FaceType::Quad4
                } else {
                    FaceType::Tri3
                };
                shape_values_at(linear, xi_s, &mut values.phi);
            }
            TractionScheme::PiecewiseLinear => {
                traction_shape_on_at(
                    sec.kind,
                    self.scheme,
                    at.seg,
                    parent_seed(xi_s),
                    phi_scratch,
                );
                OfParent::fill(&mut values.phi, phi_scratch);
            }
        }
        shape_values_at(pri.kind, at.xi_m.map(|v| v.re), &mut values.n2);
        (values, face_jacobian, dj_dx)
    }
}

/// The shape functions of `kind` at `xi` with their `xi`-derivatives, as a `ParentDual`
/// evaluation gives them (in floats on Quad4 and Quad9), into the first `kind.num_nodes()`
/// entries of `to`.
fn shape_values_at(kind: FaceType, xi: [f64; 2], to: &mut [OfParent]) {
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
fn shape_derivatives(kind: FaceType, xi: [f64; 2], out: &mut [TensorShape]) {
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
fn face_jacobian(
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
    dj_dx.fill(0.0);
    if jacobian > 0.0 {
        // dJ = (t2 x n) . dt1 + (n x t1) . dt2, dt_i = sum_a N_a,i dx_a.
        let n = c.map(|v| v / jacobian);
        let (h1, h2) = (cross(t[1], n), cross(n, t[0]));
        for (a, shape) in shapes.iter().enumerate() {
            let g = shape.gradient;
            for d in 0..3 {
                dj_dx[3 * a + d] = h1[d] * g[0] + h2[d] * g[1];
            }
        }
    }
    OfParent { re: jacobian, d }
}

/// The projected vertices of a sub-segment of a face with dual coordinates `x`.
fn project<const N: usize>(
    plane: &Plane<DualSVec64<N>>,
    x: &[[DualSVec64<N>; 3]],
    seg: &SubSegment,
) -> Vec<[DualSVec64<N>; 2]> {
    seg.local_nodes
        .iter()
        .map(|&a| plane.project(x[a]))
        .collect()
}

/// `dP/dy`: the level-1 derivatives of the plane coordinates, `PLANE_SLOTS x ndof` (row =
/// level-2 slot).
fn plane_chain<const N: usize>(
    s: &[[DualSVec64<N>; 2]],
    m: &[[DualSVec64<N>; 2]],
    ndof: usize,
) -> DMatrix<f64> {
    let mut chain = DMatrix::zeros(PLANE_SLOTS, ndof);
    for (first, vertices) in [(0, s), (PRIMARY_SLOT, m)] {
        for (i, v) in vertices.iter().enumerate() {
            for (d, c) in v.iter().enumerate() {
                let row = slots(c);
                for (j, r) in row[..ndof].iter().enumerate() {
                    chain[(first + 2 * i + d, j)] = *r;
                }
            }
        }
    }
    chain
}

/// A function of the plane coordinates at one quadrature point: its value and its derivatives
/// along the level-2 slots, as plain floats.
///
/// The level-2 work per quadrature point is done on these, with the derivatives written out
/// (the chain rule by hand), rather than in `PlaneDual`. Every operation, values and
/// derivatives, is the one `PlaneDual` arithmetic would do, in its order (`x / y` is
/// `x * (1 / y)` with derivative `(dx y - dy x) (1 / y) (1 / y)`, `x y` has `dx y + dy x`, ...),
/// so the results are bit for bit those of the dual code (module docs, "Exactness"). The
/// derivatives are those of the module docs:
///
/// - the point `P = c + q_0 u + q_1 v` of a pallet (apex `c`, edges `u`, `v` from it):
///   `dP = dc + q_0 du + q_1 dv`;
/// - its local coordinates on a projected sub-segment with vertices `Q_i`: on a triangle the
///   barycentric coordinates `det [d b] / det [a b]`, `det [a d] / det [a b]` (`a`, `b` the
///   edges from `Q_0`, `d = P - Q_0`) differentiated as quotients; on a bilinear quadrilateral
///   (`P(local) = sum_i N_i(local) Q_i`) the derivative of the one Newton step of the module
///   docs, `dlocal = J^-1 (dP - sum_i N_i dQ_i)` with `J = dP/dlocal` at the float solution and
///   `N_i` in the monomial form of the bilinear map;
/// - `xi = xi_0 + A local` (the sub-segment's affine map): `dxi = A dlocal`;
/// - `det(dP/dlocal)`: constant on a triangle (a dual of the vertices), on a quadrilateral
///   `(a_0 + c_0 t)(b_1 + c_1 s) - (b_0 + c_0 s)(a_1 + c_1 t)`, differentiated through the
///   monomial coefficients (duals of the vertices) and `(s, t)`.
#[derive(Clone, Copy)]
struct PlaneValue {
    re: f64,
    d: [f64; PLANE_SLOTS],
}

impl PlaneValue {
    const ZERO: PlaneValue = PlaneValue {
        re: 0.0,
        d: [0.0; PLANE_SLOTS],
    };

    fn of(x: &PlaneDual) -> Self {
        PlaneValue {
            re: x.re,
            d: slots(x),
        }
    }

    /// `self * f` for a float `f`.
    fn scaled(&self, f: f64) -> Self {
        PlaneValue {
            re: self.re * f,
            d: self.d.map(|v| v * f),
        }
    }

    /// `self / den`.
    fn over(&self, den: &PlaneValue) -> Self {
        let inverse = 1.0 / den.re;
        PlaneValue {
            re: self.re * inverse,
            d: std::array::from_fn(|k| {
                (self.d[k] * den.re - den.d[k] * self.re) * inverse * inverse
            }),
        }
    }

    /// `self * other` (the product rule, in the order of the duals' operations).
    fn times(&self, other: &PlaneValue) -> Self {
        PlaneValue {
            re: self.re * other.re,
            d: std::array::from_fn(|k| self.d[k] * other.re + other.d[k] * self.re),
        }
    }

    /// `self - other`.
    fn minus(&self, other: &PlaneValue) -> Self {
        PlaneValue {
            re: self.re - other.re,
            d: std::array::from_fn(|k| self.d[k] - other.d[k]),
        }
    }

    /// `self * f(xi(P))` for a function `f` of the parent coordinates given with its
    /// `xi`-derivatives and `xi` with its `P`-derivatives (the chain rule to plane coordinates).
    fn times_lifted(&self, f: &OfParent, xi: &[PlaneValue; 2]) -> Self {
        let g = f.d;
        PlaneValue {
            re: self.re * f.re,
            d: std::array::from_fn(|k| {
                self.d[k] * f.re + self.re * (xi[0].d[k] * g[0] + xi[1].d[k] * g[1])
            }),
        }
    }
}

/// `det [u v]` of two plane vectors (as [`det2`] in level-2 duals).
fn plane_det2(u: &[PlaneValue; 2], v: &[PlaneValue; 2]) -> PlaneValue {
    u[0].times(&v[1]).minus(&u[1].times(&v[0]))
}

/// The level-2 pallet: its apex, the edges `u`, `v` from the apex and `det [u v]`.
struct Pallet {
    apex: [PlaneValue; 2],
    u: [PlaneValue; 2],
    v: [PlaneValue; 2],
    twice_area: PlaneValue,
}

impl Pallet {
    /// The point `c + q_0 u + q_1 v` of the pallet.
    fn point(&self, q: [f64; 2]) -> [PlaneValue; 2] {
        let mut p = [PlaneValue::ZERO; 2];
        for (i, pi) in p.iter_mut().enumerate() {
            let (c, u, v) = (&self.apex[i], &self.u[i], &self.v[i]);
            pi.re = c.re + u.re * q[0] + v.re * q[1];
            for k in 0..PLANE_SLOTS {
                pi.d[k] = c.d[k] + u.d[k] * q[0] + v.d[k] * q[1];
            }
        }
        p
    }
}

/// The parent coordinates `xi = xi_0 + A local` of a point with local coordinates `local` on
/// `seg`.
fn to_parent(seg: &SubSegment, local: &[PlaneValue; 2]) -> [PlaneValue; 2] {
    let xi = seg.to_parent([local[0].re, local[1].re]);
    let (_, a) = seg.affine_map();
    let mut out = [PlaneValue::ZERO; 2];
    for (i, o) in out.iter_mut().enumerate() {
        o.re = xi[i];
        for k in 0..PLANE_SLOTS {
            o.d[k] = a[i][0] * local[0].d[k] + a[i][1] * local[1].d[k];
        }
    }
    out
}

/// A projected sub-segment in level-2 duals: its vertices seeded on their slots (the first
/// three of a triangle), for the provenance of the overlap vertices, and the float data of the
/// per-point maps (see [`PlaneValue`]).
struct PlaneMap<'o> {
    vertices: [[PlaneDual; 2]; 4],
    /// The float sub-segment (its vertices and, for a quadrilateral, its bilinear map).
    projected: &'o Projected<'o>,
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
    fn new(projected: &'o Projected<'o>, first: usize) -> Self {
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

    /// Local coordinates of `p` given the float solution `found`: closed form on a triangle,
    /// one Newton step from `found` on a quadrilateral (see the module docs), with their
    /// derivatives, rounded as the level-2 duals round them (see [`PlaneValue`]).
    fn local(&self, p: &[PlaneValue; 2], found: &LocalPoint) -> [PlaneValue; 2] {
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
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
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
    fn jacobian(&self, local: &[PlaneValue; 2]) -> PlaneValue {
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

/// The overlap polygon in level-2 duals: each float vertex with the derivatives of its
/// provenance, or held fixed (counted) if the provenance is ambiguous or misses it.
fn traced_polygon(
    overlap: &Overlap,
    s_map: &PlaneMap,
    m_map: &PlaneMap,
) -> (Vec<[PlaneDual; 2]>, usize) {
    let tolerance = PROVENANCE_TOLERANCE * diameter(&overlap.s.vertices);
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

/// The level-2 geometry of one quadrature point.
struct PointGeometry<'s> {
    /// The secondary sub-segment (for scheme 3).
    seg: &'s SubSegment,
    xi_s: [PlaneValue; 2],
    xi_m: [PlaneValue; 2],
    /// `w_P det(dP/dlocal_pallet) det(dxi/dlocal) / det(dP/dlocal_s)`: the weight without
    /// `J_face`.
    measure: PlaneValue,
}

/// `Phi_k(xi_s)`, `N1_b(xi_s)`, `N2_c(xi_m)` with their `xi`-derivatives, and the weight, at
/// one quadrature point.
#[derive(Default)]
struct PointValues {
    phi: [OfParent; MAX_NODES],
    n1: [OfParent; MAX_NODES],
    n2: [OfParent; MAX_NODES],
    weight: f64,
}

impl PointValues {
    /// The test of `integrate_pair` (values only).
    fn is_finite(&self) -> bool {
        let all = self.phi.iter().chain(&self.n1).chain(&self.n2);
        self.weight.is_finite() && all.into_iter().all(|f| f.re.is_finite())
    }
}

/// The weights of one sub-segment pair and their derivatives with respect to its plane
/// coordinates (level 2) and the secondary coordinates (through `J_face`).
///
/// Rows: `r = i ns + b` for `n1_kb`, then `r = rows1 + i np + c` for `n2_kc`, with
/// `k = active[i]` (so scheme 3 skips the traction nodes off the secondary sub-segment). The
/// derivatives of the points of one pallet are tabulated, then added by matrix products:
///
/// - `d(w Phi_k N_b)/dP = Phi_k N_b dw/dP + w (N_b dPhi_k/dxi + Phi_k dN_b/dxi) dxi_s/dP` for
///   `n1`, and for `n2` with `w Phi_k dN_c/dxi dxi_m/dP` in the last term: `coefficients`
///   (`rows x 5 points`: blocks `dw`, `dxi_s0`, `dxi_s1`, `dxi_m0`, `dxi_m1`) times
///   `directions` (`5 points x 16`: these derivatives of each point); the `dxi_m` blocks of
///   the `n1` rows are zero and left out of their product;
/// - `d(w Phi_k N_b)/dx_s = Phi_k N_b dw/dx_s`: the first block of the coefficients times
///   `dweight_dx` (`points x 3 ns`).
///
/// The first pallet of a sub-segment pair overwrites rows `0..rows` of `plane` and `face`, the
/// others add to them, so only the values and counts are reset between sub-segment pairs.
struct SubPairTangent {
    ns: usize,
    np: usize,
    points: usize,
    active: Vec<usize>,
    values: Vec<f64>,
    area: f64,
    /// Quadrature points tabulated.
    points_added: usize,
    /// Pallets added since `clear`. With none, `plane` and `face` hold an earlier pair's data
    /// and stand for zero.
    pallets_added: usize,
    plane: DMatrix<f64>,
    face: DMatrix<f64>,
    /// The tabulation of one pallet (see above).
    coefficients: DMatrix<f64>,
    directions: DMatrix<f64>,
    dweight_dx: DMatrix<f64>,
    /// `dn/dy` of the sub-segment pair, row-major (`rows x ndof`): scratch of `merge_into`.
    derivatives: Vec<f64>,
    unresolved: usize,
    /// Scratch for the traction functions of one point.
    phi_scratch: Vec<ParentDual>,
}

impl SubPairTangent {
    /// Buffers for the face sizes of `out` and pallets of `points` quadrature points.
    fn new(out: &LinearizedWeights, points: usize) -> Self {
        let (nt, ns, np) = (out.traction_nodes, out.sec_nodes, out.pri_nodes);
        let rows = nt * (ns + np);
        SubPairTangent {
            ns,
            np,
            points,
            active: Vec::new(),
            values: vec![0.0; rows],
            area: 0.0,
            points_added: 0,
            pallets_added: 0,
            plane: DMatrix::zeros(rows, PLANE_SLOTS),
            face: DMatrix::zeros(rows, 3 * ns),
            coefficients: DMatrix::zeros(rows, 5 * points),
            directions: DMatrix::zeros(5 * points, PLANE_SLOTS),
            dweight_dx: DMatrix::zeros(points, 3 * ns),
            derivatives: vec![0.0; rows * out.ndof()],
            unresolved: 0,
            phi_scratch: Vec::with_capacity(MAX_NODES),
        }
    }

    /// Sets the traction nodes of the rows (per secondary sub-segment).
    fn start(&mut self, active: Vec<usize>) {
        self.active = active;
    }

    /// The rows of `n1` (the first) and of all weights.
    fn rows(&self) -> (usize, usize) {
        let n = self.active.len();
        (n * self.ns, n * (self.ns + self.np))
    }

    fn clear(&mut self) {
        self.values.fill(0.0);
        self.area = 0.0;
        self.points_added = 0;
        self.pallets_added = 0;
        self.unresolved = 0;
    }

    /// Adds the values of one point and tabulates its derivatives (column `point` of each
    /// block).
    fn tabulate(
        &mut self,
        point: usize,
        values: &PointValues,
        at: &PointGeometry,
        weight: &PlaneValue,
        dweight_dx: &[f64],
    ) {
        let q = self.points;
        let w = values.weight;
        self.area += w;
        self.points_added += 1;
        let directions = [
            &weight.d,
            &at.xi_s[0].d,
            &at.xi_s[1].d,
            &at.xi_m[0].d,
            &at.xi_m[1].d,
        ];
        for (block, direction) in directions.iter().enumerate() {
            for (i, v) in direction.iter().enumerate() {
                self.directions[(block * q + point, i)] = *v;
            }
        }
        for (j, g) in dweight_dx.iter().enumerate() {
            self.dweight_dx[(point, j)] = *g;
        }
        let (ns, np) = (self.ns, self.np);
        let (rows1, _) = self.rows();
        let c = &mut self.coefficients;
        for (i, &k) in self.active.iter().enumerate() {
            let phi = values.phi[k];
            let wp = w * phi.re;
            for (b, n) in values.n1[..ns].iter().enumerate() {
                let r = i * ns + b;
                c[(r, point)] = phi.re * n.re;
                c[(r, q + point)] = w * (n.re * phi.d[0] + phi.re * n.d[0]);
                c[(r, 2 * q + point)] = w * (n.re * phi.d[1] + phi.re * n.d[1]);
                self.values[r] += wp * n.re;
            }
            for (c_node, n) in values.n2[..np].iter().enumerate() {
                let r = rows1 + i * np + c_node;
                c[(r, point)] = phi.re * n.re;
                c[(r, q + point)] = w * n.re * phi.d[0];
                c[(r, 2 * q + point)] = w * n.re * phi.d[1];
                c[(r, 3 * q + point)] = wp * n.d[0];
                c[(r, 4 * q + point)] = wp * n.d[1];
                self.values[r] += wp * n.re;
            }
        }
    }

    /// Adds the tabulated derivatives of a complete pallet (the rows of `n1` without the
    /// `dxi_m` blocks, whose coefficients are zero).
    fn add_pallet(&mut self) {
        let (rows1, rows) = self.rows();
        let q = self.points;
        // The first pallet overwrites (`beta = 0`: the old contents are never read).
        let beta = if self.pallets_added == 0 { 0.0 } else { 1.0 };
        self.pallets_added += 1;
        self.plane.rows_mut(0, rows1).gemm(
            1.0,
            &self.coefficients.view((0, 0), (rows1, 3 * q)),
            &self.directions.rows(0, 3 * q),
            beta,
        );
        self.plane.rows_mut(rows1, rows - rows1).gemm(
            1.0,
            &self.coefficients.rows(rows1, rows - rows1),
            &self.directions,
            beta,
        );
        let c = self.coefficients.rows(0, rows);
        self.face
            .rows_mut(0, rows)
            .gemm(1.0, &c.columns(0, self.points), &self.dweight_dx, beta);
    }

    fn is_finite(&self) -> bool {
        let (_, rows) = self.rows();
        self.pallets_added == 0
            || [&self.plane, &self.face].iter().all(|m| {
                // The rows in use of each column (column-major storage).
                m.as_slice()
                    .chunks_exact(m.nrows())
                    .all(|column| column[..rows].iter().all(|v| v.is_finite()))
            })
    }

    /// Adds these weights to `out`, with `dn/dy = dn/dP dP/dy + dn/dx_s` (`chain = dP/dy`).
    ///
    /// The product skips the zeros of `dP/dy`: the plane coordinates of the secondary vertices
    /// (the first `PRIMARY_SLOT` slots) do not depend on the primary coordinates. The terms
    /// left out are exact zeros, so the sums are those of the full product.
    fn merge_into(&mut self, out: &mut LinearizedWeights, chain: &DMatrix<f64>) -> SubPairOutcome {
        let ndof = out.ndof();
        let (rows1, rows) = self.rows();
        if self.pallets_added == 0 {
            // No pallet: zero weights and derivatives (`0 dP/dy`, not finite where `dP/dy` is
            // not, as the full product would be).
            if !chain.as_slice().iter().all(|v| v.is_finite()) {
                return SubPairOutcome::Failed(PairFailure::NonFinite);
            }
            out.unresolved_vertices += self.unresolved;
            return SubPairOutcome::Integrated { points: 0 };
        }
        let sec_dofs = self.face.ncols();
        let derivatives = &mut self.derivatives[..rows * ndof];
        // Row-major views of the secondary and the primary columns.
        DMatrixViewMut::from_slice_with_strides_mut(derivatives, rows, sec_dofs, ndof, 1).gemm(
            1.0,
            &self.plane.rows(0, rows),
            &chain.columns(0, sec_dofs),
            0.0,
        );
        let primary_slots = PLANE_SLOTS - PRIMARY_SLOT;
        DMatrixViewMut::from_slice_with_strides_mut(
            &mut derivatives[sec_dofs..],
            rows,
            ndof - sec_dofs,
            ndof,
            1,
        )
        .gemm(
            1.0,
            &self.plane.view((0, PRIMARY_SLOT), (rows, primary_slots)),
            &chain.view((PRIMARY_SLOT, sec_dofs), (primary_slots, ndof - sec_dofs)),
            0.0,
        );
        if !derivatives.iter().all(|v| v.is_finite()) {
            return SubPairOutcome::Failed(PairFailure::NonFinite);
        }
        out.area += self.area;
        out.unresolved_vertices += self.unresolved;
        let parts = [
            (0, self.ns, &mut out.n1, &mut out.dn1),
            (rows1, self.np, &mut out.n2, &mut out.dn2),
        ];
        for (first, count, out_values, out_derivatives) in parts {
            for (i, &k) in self.active.iter().enumerate() {
                for b in 0..count {
                    let (r, e) = (first + i * count + b, k * count + b);
                    out_values[e] += self.values[r];
                    let row = &mut out_derivatives[e * ndof..(e + 1) * ndof];
                    let from = &derivatives[r * ndof..(r + 1) * ndof];
                    for (to, d) in row.iter_mut().zip(from) {
                        *to += d;
                    }
                    for (j, to) in row[..sec_dofs].iter_mut().enumerate() {
                        *to += self.face[(r, j)];
                    }
                }
            }
        }
        SubPairOutcome::Integrated {
            points: self.points_added,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::mortar::pair::integrate_pair;
    use crate::contact::mortar::test_support::{settings, with_splits, Setting, SCHEMES};

    type Vec3 = [f64; 3];

    use crate::test_rng::Rng;

    /// Parent coordinates mapped to `[0, 1]^2` (quads) or kept (the unit triangle).
    fn unit_coords(kind: FaceType, xi: [f64; 2]) -> [f64; 2] {
        if kind.is_quad() {
            [0.5 * (xi[0] + 1.0), 0.5 * (xi[1] + 1.0)]
        } else {
            xi
        }
    }

    /// The curved sheet `z = 0.2 x^2 - 0.1 x y + 0.15 y^2 + lift`, tilted (turned by 0.7 rad
    /// about `(1, 2, 3)`) and moved.
    fn sheet(x: f64, y: f64, lift: f64) -> Vec3 {
        tilted([x, y, 0.2 * x * x - 0.1 * x * y + 0.15 * y * y + lift])
    }

    /// `p` turned by 0.7 rad about `(1, 2, 3)` and moved.
    fn tilted(p: Vec3) -> Vec3 {
        let norm = 14f64.sqrt();
        let k = [1.0 / norm, 2.0 / norm, 3.0 / norm];
        let (s, c) = 0.7f64.sin_cos();
        let kxp = cross(k, p);
        let kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
        let shift = [0.3, -0.2, 0.5];
        std::array::from_fn(|d| p[d] * c + kxp[d] * s + k[d] * kp * (1.0 - c) + shift[d])
    }

    /// A secondary face on the sheet, in-plane distorted, nodes perturbed in and out of the
    /// sheet (non-planar, curved edges for quadratic faces).
    fn secondary_face(kind: FaceType, rng: &mut Rng) -> Vec<Vec3> {
        kind.node_coords()
            .iter()
            .map(|xi| {
                let [u, v] = unit_coords(kind, *xi);
                let x = u + 0.08 * u * v + rng.symmetric(0.02);
                let y = 0.9 * v + 0.05 * u * u + rng.symmetric(0.02);
                sheet(x, y, rng.symmetric(0.01))
            })
            .collect()
    }

    /// A primary face facing the other way (`u` and `v` swapped), turned by `angle`, shifted by
    /// `shift` and lifted by `gap` off the sheet, perturbed like the secondary.
    fn primary_face(
        kind: FaceType,
        angle: f64,
        shift: [f64; 2],
        gap: f64,
        rng: &mut Rng,
    ) -> Vec<Vec3> {
        let (s, c) = angle.sin_cos();
        kind.node_coords()
            .iter()
            .map(|xi| {
                let [u, v] = unit_coords(kind, *xi);
                let (a, b) = (0.95 * v + 0.04 * u * v, 0.85 * u);
                let x = shift[0] + c * a - s * b + rng.symmetric(0.02);
                let y = shift[1] + s * a + c * b + rng.symmetric(0.02);
                sheet(x, y, gap + rng.symmetric(0.01))
            })
            .collect()
    }

    /// A generic pair: tilted, curved, perturbed, partially overlapping, non-matching.
    fn generic_pair(sec: FaceType, pri: FaceType, seed: u64) -> (Vec<Vec3>, Vec<Vec3>) {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed.wrapping_mul(0x2545_f491_4f6c_dd1d));
        let xs = secondary_face(sec, &mut rng);
        let xp = primary_face(pri, 0.3, [0.35, 0.25], 0.02, &mut rng);
        (xs, xp)
    }

    fn options(how: Setting, sec: FaceType, pri: FaceType) -> IntegrationOptions {
        IntegrationOptions {
            pallets: how.1,
            ..IntegrationOptions::for_faces(how.0, sec, pri)
        }
    }

    fn linearized(
        sec: (FaceType, &[Vec3]),
        pri: (FaceType, &[Vec3]),
        how: Setting,
        stats: &mut RejectStats,
    ) -> LinearizedWeights {
        let opts = options(how, sec.0, pri.0);
        integrate_pair_linearized(
            &FaceGeom {
                kind: sec.0,
                x: sec.1,
            },
            &FaceGeom {
                kind: pri.0,
                x: pri.1,
            },
            &opts,
            stats,
        )
    }

    /// `integrate_pair`'s weights, dense (`n1` then `n2`), with its counts.
    fn reference(
        sec: (FaceType, &[Vec3]),
        pri: (FaceType, &[Vec3]),
        how: Setting,
    ) -> (Vec<f64>, RejectStats) {
        let scheme = how.0;
        let opts = options(how, sec.0, pri.0);
        let mut stats = RejectStats::default();
        let w = integrate_pair(
            &FaceGeom {
                kind: sec.0,
                x: sec.1,
            },
            &FaceGeom {
                kind: pri.0,
                x: pri.1,
            },
            &opts,
            &mut stats,
        );
        let (ns, np) = (sec.0.num_nodes(), pri.0.num_nodes());
        let nt = traction_node_count(sec.0, scheme);
        let mut dense = vec![0.0; nt * (ns + np)];
        for &(k, b, v) in &w.n1 {
            dense[k * ns + b] = v;
        }
        for &(k, c, v) in &w.n2 {
            dense[nt * ns + k * np + c] = v;
        }
        (dense, stats)
    }

    fn values(w: &LinearizedWeights) -> Vec<f64> {
        w.n1.iter().chain(&w.n2).copied().collect()
    }

    /// `d values / d y_j` for every entry of `values` (column `j`).
    fn derivative_column(w: &LinearizedWeights, j: usize) -> Vec<f64> {
        let ndof = w.ndof();
        w.dn1
            .chunks(ndof)
            .chain(w.dn2.chunks(ndof))
            .map(|row| row[j])
            .collect()
    }

    fn max_abs(v: &[f64]) -> f64 {
        v.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    fn max_difference(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    /// Every combination of face types (secondary, primary).
    fn all_type_pairs() -> impl Iterator<Item = (FaceType, FaceType)> {
        FaceType::ALL
            .into_iter()
            .flat_map(|s| FaceType::ALL.into_iter().map(move |p| (s, p)))
    }

    /// The float level 2 against the dual reference on one pair: the same counts, the values
    /// bit for bit, the derivatives to 1e-13 of the largest (in fact bit for bit too).
    fn assert_reproduces_reference(
        sec: (FaceType, &[Vec3]),
        pri: (FaceType, &[Vec3]),
        opts: &IntegrationOptions,
        what: &str,
    ) {
        let (sg, pg) = (
            FaceGeom {
                kind: sec.0,
                x: sec.1,
            },
            FaceGeom {
                kind: pri.0,
                x: pri.1,
            },
        );
        let (mut s_float, mut s_dual) = (RejectStats::default(), RejectStats::default());
        let float = integrate_pair_linearized(&sg, &pg, opts, &mut s_float);
        let dual = linearized_with(
            &sg,
            &pg,
            opts,
            &mut s_dual,
            dual_reference::integrate_overlap,
        );
        assert_eq!(s_float, s_dual, "{what}: counts");
        assert_eq!(float.area.to_bits(), dual.area.to_bits(), "{what}: area");
        assert_eq!(
            float.unresolved_vertices, dual.unresolved_vertices,
            "{what}"
        );
        for (name, a, b) in [("n1", &float.n1, &dual.n1), ("n2", &float.n2, &dual.n2)] {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                assert_eq!(
                    x.to_bits(),
                    y.to_bits(),
                    "{what}: {name}[{i}] {x:e} != {y:e}"
                );
            }
        }
        let (df, dd) = (
            [&float.dn1[..], &float.dn2[..]],
            [&dual.dn1[..], &dual.dn2[..]],
        );
        let scale = max_abs(dd[0]).max(max_abs(dd[1]));
        let difference = max_difference(df[0], dd[0]).max(max_difference(df[1], dd[1]));
        assert!(
            difference <= 1e-13 * scale,
            "{what}: derivatives differ by {difference:e} (largest {scale:e})"
        );
    }

    /// Three pairs of the bending scene (`cases/bending`: Hex27 layers, Quad9 faces, scheme 2,
    /// degree 8), secondary then primary nodes, face order: the undeformed pair at `x = 0`
    /// (exactly touching, coincident edges at `y = 0, 1`: with the float level 2 rounding one
    /// division differently, its weights differed in the last bit, which flipped the signs of
    /// round-off gaps and the first step no longer converged); a pair of the first Newton
    /// iterate; a pair late in the bending whose overlap has a vertex where nearly parallel
    /// edges cross (`x = 7.51124` and `7.51122`): plane derivatives of 1e12 cancel, and a
    /// different order of the same operations changed the derivatives by 5e-5 relative.
    const BENDING_PAIRS: [[f64; 54]; 3] = [
        [
            0.0,
            0.0,
            1.0,
            1.25,
            0.0,
            1.0,
            1.25,
            1.0,
            1.0,
            0.0,
            1.0,
            1.0,
            0.625,
            0.0,
            1.0,
            1.25,
            0.5,
            1.0,
            0.625,
            1.0,
            1.0,
            0.0,
            0.5,
            1.0,
            0.625,
            0.5,
            1.0,
            0.0,
            0.0,
            1.0,
            0.0,
            1.0,
            1.0,
            1.6666666666666665,
            1.0,
            1.0,
            1.6666666666666665,
            0.0,
            1.0,
            0.0,
            0.5,
            1.0,
            0.8333333333333333,
            1.0,
            1.0,
            1.6666666666666665,
            0.5,
            1.0,
            0.8333333333333333,
            0.0,
            1.0,
            0.8333333333333333,
            0.5,
            1.0,
        ],
        [
            2.4995821184900553,
            0.0,
            0.9997766457851738,
            3.7476983666222528,
            0.0,
            1.001145592226524,
            3.747908671178117,
            1.0,
            1.0011778169595529,
            2.4996333570308233,
            1.0,
            0.9997888810667629,
            3.1238948846935743,
            0.0,
            1.0000585347834672,
            3.747803518900185,
            0.5000328594332102,
            1.0011617045930383,
            3.1239603722275655,
            1.0,
            1.000068980261321,
            2.4996077377604395,
            0.4999970347958154,
            0.9997827634259684,
            3.12392762846057,
            0.4999989529323504,
            1.000063757522394,
            1.665436256498429,
            0.0,
            0.9998509532274821,
            1.6657073138978975,
            1.0,
            0.9998613837645863,
            3.3335054144694696,
            1.0,
            1.000246602350682,
            3.3335468265207084,
            0.0,
            1.0002372151579992,
            1.6655717851981633,
            0.4999924372943439,
            0.9998561684960342,
            2.499154349094873,
            1.0,
            0.9997112889681756,
            3.333526120495089,
            0.4999934724811446,
            1.0002419087543406,
            2.499162949859735,
            0.0,
            0.9996986042691017,
            2.499158649477304,
            0.5000010084686364,
            0.9997049466186387,
        ],
        [
            7.511243814701613,
            0.0,
            2.0510031664462645,
            8.755208367328038,
            0.0,
            2.288075599570319,
            8.75520837555786,
            1.0,
            2.28807559303152,
            7.51124376999247,
            1.0,
            2.0510031768339263,
            8.133296617246586,
            0.0,
            2.169511107591984,
            8.755208371430433,
            0.49999999459881106,
            2.288075596279586,
            8.133296599407045,
            1.0,
            2.169511112480069,
            7.511243792348219,
            0.5000000210713396,
            2.0510031716355575,
            8.133296608322649,
            0.5000000133501024,
            2.169511110040916,
            6.681742245101922,
            0.0,
            1.8944101769563169,
            6.681742074807264,
            1.0,
            1.8944102272340086,
            8.340605670182246,
            1.0,
            2.2089661931503257,
            8.34060566539637,
            0.0,
            2.2089661976757924,
            6.681742159957448,
            0.5000000852667351,
            1.8944102020971931,
            7.511224655514203,
            1.0,
            2.05101453787608,
            8.340605667817163,
            0.4999999937443363,
            2.2089661954391135,
            7.51122463393879,
            0.0,
            2.051014551296121,
            7.5112246447251465,
            0.49999998901017156,
            2.0510145445852785,
        ],
    ];

    /// Test 0. The float level 2 reproduces the dual-number reference ([`dual_reference`]):
    /// values bit for bit, derivatives to 1e-13 of the largest, for every face-type pair and
    /// valid scheme on generic configurations (also moved into one plane: touching faces) and
    /// on the bending scene's pairs (with every scheme).
    #[test]
    fn float_level2_reproduces_the_dual_reference() {
        for (st, pt) in all_type_pairs() {
            for how in settings(st) {
                let opts = options(how, st, pt);
                for seed in 0..2 {
                    let (xs, xp) = generic_pair(st, pt, seed);
                    let what = format!("{st:?}-{pt:?} {how:?} seed {seed}");
                    assert_reproduces_reference((st, &xs), (pt, &xp), &opts, &what);
                    let flat = |x: &[Vec3]| x.iter().map(|p| [p[0], p[1], 0.0]).collect::<Vec<_>>();
                    let (fs, fp) = (flat(&xs), flat(&xp));
                    let what = format!("{what}, flat");
                    assert_reproduces_reference((st, &fs), (pt, &fp), &opts, &what);
                }
            }
        }
        for (i, pair) in BENDING_PAIRS.iter().enumerate() {
            let x: Vec<Vec3> = pair.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
            let (xs, xp) = x.split_at(9);
            for how in with_splits(SCHEMES) {
                let opts = options(how, FaceType::Quad9, FaceType::Quad9);
                let what = format!("bending pair {i}, {how:?}");
                assert_reproduces_reference(
                    (FaceType::Quad9, xs),
                    (FaceType::Quad9, xp),
                    &opts,
                    &what,
                );
            }
        }
    }

    /// Test 1. The values equal `integrate_pair`'s (dense, 1e-13 of the largest weight), with the
    /// same counts, for every face-type pair and valid scheme on three generic configurations.
    #[test]
    fn values_equal_integrate_pair() {
        let mut worst: f64 = 0.0;
        for (sk, pk) in all_type_pairs() {
            for seed in 0..3 {
                let (xs, xp) = generic_pair(sk, pk, seed);
                for how in settings(sk) {
                    let what = format!("{sk:?} on {pk:?} {how:?} seed {seed}");
                    let mut stats = RejectStats::default();
                    let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
                    let (expected, expected_stats) = reference((sk, &xs), (pk, &xp), how);
                    assert_eq!(stats, expected_stats, "{what}");
                    assert!(
                        stats.pairs_integrated > 0 && w.area > 1e-3,
                        "{what}: {stats:?}"
                    );
                    assert_eq!(w.unresolved_vertices, 0, "{what}");
                    let error = max_difference(&values(&w), &expected) / max_abs(&expected);
                    assert!(error < 1e-13, "{what}: relative error {error:e}");
                    worst = worst.max(error);
                }
            }
        }
        eprintln!("values: worst relative difference {worst:e}");
    }

    /// Test 2. The derivatives against central differences of `integrate_pair` (step 1e-6, faces
    /// of size 1): below 1e-6 of the largest derivative, every face-type pair and scheme. The
    /// counts are the same at every perturbed position (the topology does not change).
    #[test]
    fn derivatives_match_central_differences() {
        const STEP: f64 = 1e-6;
        let mut worst: f64 = 0.0;
        for (sk, pk) in all_type_pairs() {
            let (xs, xp) = generic_pair(sk, pk, 7);
            let ns = xs.len();
            let schemes = settings(sk);
            let exact: Vec<(LinearizedWeights, RejectStats)> = schemes
                .iter()
                .map(|&how| {
                    let mut stats = RejectStats::default();
                    let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
                    (w, stats)
                })
                .collect();
            let mut errors = vec![0.0f64; schemes.len()];
            for j in 0..3 * (ns + xp.len()) {
                let moved = |sign: f64| {
                    let (mut s, mut p) = (xs.clone(), xp.clone());
                    if j < 3 * ns {
                        s[j / 3][j % 3] += sign * STEP;
                    } else {
                        p[j / 3 - ns][j % 3] += sign * STEP;
                    }
                    (s, p)
                };
                let ((s_plus, p_plus), (s_minus, p_minus)) = (moved(1.0), moved(-1.0));
                for (i, &how) in schemes.iter().enumerate() {
                    let (plus, plus_stats) = reference((sk, &s_plus), (pk, &p_plus), how);
                    let (minus, minus_stats) = reference((sk, &s_minus), (pk, &p_minus), how);
                    assert_eq!(plus_stats, exact[i].1, "{sk:?} on {pk:?} dof {j}");
                    assert_eq!(minus_stats, exact[i].1, "{sk:?} on {pk:?} dof {j}");
                    let fd: Vec<f64> = plus
                        .iter()
                        .zip(&minus)
                        .map(|(a, b)| (a - b) / (2.0 * STEP))
                        .collect();
                    let column = derivative_column(&exact[i].0, j);
                    errors[i] = errors[i].max(max_difference(&column, &fd));
                }
            }
            for (i, scheme) in schemes.iter().enumerate() {
                let w = &exact[i].0;
                let largest = max_abs(&w.dn1).max(max_abs(&w.dn2));
                let error = errors[i] / largest;
                assert!(
                    error < 1e-6,
                    "{sk:?} on {pk:?} {scheme:?}: relative error {error:e}"
                );
                worst = worst.max(error);
            }
        }
        eprintln!("derivatives vs central differences: worst relative error {worst:e}");
    }

    /// Test 3. Momentum: `sum_b dn1_kb / dy_j = sum_c dn2_kc / dy_j` for every traction node and
    /// coordinate, to round-off (1e-13 of the largest derivative).
    #[test]
    fn derivatives_conserve_momentum() {
        let mut worst: f64 = 0.0;
        for (sk, pk) in all_type_pairs() {
            let (xs, xp) = generic_pair(sk, pk, 11);
            for how in settings(sk) {
                let mut stats = RejectStats::default();
                let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
                let (ns, np, ndof) = (w.sec_nodes, w.pri_nodes, w.ndof());
                let largest = max_abs(&w.dn1).max(max_abs(&w.dn2));
                for k in 0..w.traction_nodes {
                    for j in 0..ndof {
                        let sum1: f64 = (0..ns).map(|b| w.dn1[(k * ns + b) * ndof + j]).sum();
                        let sum2: f64 = (0..np).map(|c| w.dn2[(k * np + c) * ndof + j]).sum();
                        let error = (sum1 - sum2).abs() / largest;
                        assert!(error < 1e-13, "{sk:?} on {pk:?} {how:?}: {error:e}");
                        worst = worst.max(error);
                    }
                }
            }
        }
        eprintln!("momentum of the derivatives: worst relative defect {worst:e}");
    }

    /// Test 4. Frame indifference: the derivative along a rigid translation of both faces
    /// (`sum_a dn/dx_a`, per axis) and along an infinitesimal rigid rotation
    /// (`sum_a (omega x x_a) . dn/dx_a`, omega along each axis) vanishes, to 1e-12 of the largest
    /// derivative (times the largest coordinate for rotations).
    #[test]
    fn derivatives_are_frame_indifferent() {
        let mut worst: [f64; 2] = [0.0; 2];
        for (sk, pk) in all_type_pairs() {
            let (xs, xp) = generic_pair(sk, pk, 13);
            let nodes: Vec<Vec3> = xs.iter().chain(&xp).copied().collect();
            let size = nodes.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for how in settings(sk) {
                let mut stats = RejectStats::default();
                let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
                let ndof = w.ndof();
                let largest = max_abs(&w.dn1).max(max_abs(&w.dn2));
                for row in w.dn1.chunks(ndof).chain(w.dn2.chunks(ndof)) {
                    for axis in 0..3 {
                        let translation: f64 = (0..nodes.len()).map(|a| row[3 * a + axis]).sum();
                        let omega: Vec3 = std::array::from_fn(|d| (d == axis) as u8 as f64);
                        let rotation: f64 = nodes
                            .iter()
                            .enumerate()
                            .map(|(a, x)| {
                                let v = cross(omega, *x);
                                (0..3).map(|d| v[d] * row[3 * a + d]).sum::<f64>()
                            })
                            .sum();
                        let errors = [
                            translation.abs() / largest,
                            rotation.abs() / (largest * size),
                        ];
                        assert!(
                            errors[0] < 1e-12 && errors[1] < 1e-12,
                            "{sk:?} on {pk:?} {how:?} axis {axis}: {errors:?}"
                        );
                        worst = [worst[0].max(errors[0]), worst[1].max(errors[1])];
                    }
                }
            }
        }
        eprintln!(
            "frame indifference: worst relative translation {:e}, rotation {:e}",
            worst[0], worst[1]
        );
    }

    /// A face of `kind` whose node at unit coordinates `(u, v)` (see [`unit_coords`]) sits at
    /// `map(u, v)` in the plane `z = 0` (exact projections: a vertex on an edge is exactly on
    /// it) or in the tilted plane.
    fn planar(kind: FaceType, tilt: bool, map: impl Fn(f64, f64) -> [f64; 2]) -> Vec<Vec3> {
        kind.node_coords()
            .iter()
            .map(|xi| {
                let [u, v] = unit_coords(kind, *xi);
                let [x, y] = map(u, v);
                if tilt {
                    tilted([x, y, 0.0])
                } else {
                    [x, y, 0.0]
                }
            })
            .collect()
    }

    /// Checks finite output equal to `integrate_pair`'s (1e-12 of the largest weight) with the
    /// same counts; returns the counts.
    fn assert_finite_and_consistent(
        sec: (FaceType, &[Vec3]),
        pri: (FaceType, &[Vec3]),
        what: &str,
    ) -> Vec<RejectStats> {
        settings(sec.0)
            .into_iter()
            .map(|how| {
                let mut stats = RejectStats::default();
                let w = linearized(sec, pri, how, &mut stats);
                let all = w.n1.iter().chain(&w.n2).chain(&w.dn1).chain(&w.dn2);
                assert!(
                    all.into_iter().chain([&w.area]).all(|v| v.is_finite()),
                    "{what} {how:?}"
                );
                let (expected, expected_stats) = reference(sec, pri, how);
                assert_eq!(stats, expected_stats, "{what} {how:?}");
                let error = max_difference(&values(&w), &expected);
                assert!(
                    error <= 1e-12 * max_abs(&expected),
                    "{what} {how:?}: {error:e}"
                );
                stats
            })
            .collect()
    }

    /// Test 5. Degenerate input never gives NaN: coincident faces exactly on top of each other
    /// (equal and different types), edges along edges with vertices exactly on edges, a vertex
    /// exactly on an edge, faces turned by 1e-12, slivers (counted) and overlaps just above the
    /// sliver area, touching corners, a collapsed face and a NaN coordinate (counted, zero
    /// weights).
    #[test]
    fn degenerate_input_gives_finite_output() {
        use FaceType::*;
        let square = |shift: [f64; 2], angle: f64, swap: bool| {
            move |u: f64, v: f64| {
                let (u, v) = if swap { (v, u) } else { (u, v) };
                let (s, c) = angle.sin_cos();
                let (x, y) = (u - 0.5, v - 0.5);
                [
                    0.5 + shift[0] + c * x - s * y,
                    0.5 + shift[1] + s * x + c * y,
                ]
            }
        };
        let kinds = [
            (Quad4, Quad4),
            (Quad9, Quad9),
            (Tri6, Tri6),
            (Quad8, Quad4),
            (Tri3, Quad9),
        ];
        for ((sk, pk), tilt) in kinds.into_iter().flat_map(|k| [(k, false), (k, true)]) {
            let xs = planar(sk, tilt, square([0.0; 2], 0.0, false));
            let cases = [
                ("coincident", [0.0, 0.0], 0.0, 1),
                ("turned by 1e-12", [0.0, 0.0], 1e-12, 1),
                ("half shifted", [0.5, 0.0], 0.0, 1),
                ("sliver 1e-9", [1.0 - 1e-9, 0.0], 0.0, 0),
                ("overlap 1e-7", [1.0 - 1e-7, 0.3], 0.0, 1),
                ("touching corner", [1.0, 1.0], 0.0, 0),
            ];
            for (what, shift, angle, integrated) in cases {
                let xp = planar(pk, tilt, square(shift, angle, true));
                let what = format!("{sk:?} on {pk:?} {what} (tilted: {tilt})");
                for stats in assert_finite_and_consistent((sk, &xs), (pk, &xp), &what) {
                    // (Shifted triangles overlap elsewhere, or not at all.)
                    if sk.is_quad() && pk.is_quad() {
                        assert_eq!(stats.pairs_integrated > 0, integrated > 0, "{what}");
                    }
                }
            }
            // A primary triangle with a vertex exactly at the middle of an edge of the secondary.
            let (a, b, c) = ([0.5, 0.0], [-0.2, 0.7], [1.2, 0.7]);
            let xp = planar(Tri3, tilt, |u, v| {
                std::array::from_fn(|d| a[d] + u * (b[d] - a[d]) + v * (c[d] - a[d]))
            });
            let what = format!("{sk:?}: vertex on an edge (tilted: {tilt})");
            assert_finite_and_consistent((sk, &xs), (Tri3, &xp), &what);
            // A collapsed primary, and a NaN coordinate.
            let point = vec![[0.5, 0.5, 0.0]; pk.num_nodes()];
            assert_finite_and_consistent((sk, &xs), (pk, &point), "collapsed");
            let mut nan = planar(pk, tilt, square([0.2, 0.1], 0.0, true));
            nan[1][2] = f64::NAN;
            for stats in assert_finite_and_consistent((sk, &xs), (pk, &nan), "NaN") {
                assert_eq!((stats.non_finite, stats.pairs_integrated), (1, 0));
            }
        }
    }
}
