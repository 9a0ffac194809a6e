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
//! 1. **Topology from floats.** Every sub-segment pair `(s, m)` goes through the float walk
//!    that [`super::integrate_pair`] runs ([`super::overlap`]): plane, projection, rejection tests,
//!    clipping, pallets, and the float inverse maps of every quadrature point (at the real parts of
//!    the dual points, which are the float points up to round-off). So the same pairs are rejected
//!    and counted in [`RejectStats`], the same pallets and points are integrated, a failed inverse
//!    map fails the same pair, and a non-finite input gives the same count and zero weights.
//! 2. **Provenance.** The clipping records where each vertex of the overlap comes from
//!    ([`super::clip::clip_convex_traced`]): while Sutherland-Hodgman cuts, every vertex carries
//!    the two edge lines it lies on (an input vertex lies on its two edges, a crossing on the cut
//!    edge and the clipping edge), so each output vertex is a vertex of `s`, a vertex of `m`, or
//!    the crossing of an edge of `s` with an edge of `m`. Recording is exact; classifying the
//!    float output afterwards would need tolerances.
//! 3. **Geometry again, in dual numbers, along that topology**, in two levels of forward mode:
//!    - *Level 1* (`DualSVec64<N>`, seeded on the `ndof` node coordinates): the projection plane
//!      of `s` (origin `x(xi_c)` and normal at the sub-segment centre, the axis `e1` along its
//!      projected first edge, `e2 = n x e1`: the very code of [`super::projection`], generic over
//!      the scalar) and the projected vertices of `s` and `m`: at most 16 plane coordinates `P`,
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
//! just to round-off. Two properties of the problem ask for it:
//!
//! - The nonlinear solve can depend on the last bit of the weights where surfaces touch
//!   exactly: there the weighted gaps are round-off (`+-1e-16`), and their signs decide which
//!   nodes get a (round-off) pressure. A quotient rounded as `a / b` instead of the duals'
//!   `a * (1 / b)` changes the weights in the last bit.
//! - Where an overlap vertex is the crossing of two nearly parallel edges (edges of the two
//!   meshes a few `1e-5` apart), its plane derivatives reach `1e12` and cancel in the integral:
//!   the derivatives are then only as accurate as `1e-16 * 1e12` allows, and a different order
//!   of the same operations changes them by up to `1e-4` relative.
//!
//! Keeping the duals' operations keeps the kernel's results those of the dual formulation,
//! whatever the conditioning; the test `float_level2_reproduces_the_dual_reference` checks it on
//! generic pairs of every face type and scheme and on pairs of the bending scene
//! (`cases/bending`). (The friction states do not follow those round-off signs: a node inside
//! the touching band takes the stick tangent without traction,
//! `contact::law::touching_friction`.)
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
//! (nothing in duals is computed for pairs that are rejected: those cost the float work only). The
//! bulk is per quadrature point and independent of `N`: level 2 (16 slots, plain floats) and the
//! accumulation. The derivative of `w Phi_k N_b` at a point lies in the span of five directions,
//! `dw/dP`, `dxi_s/dP` and `dxi_m/dP`, plus `dw/dx_s`; the points of a pallet are tabulated (one
//! coefficient per entry and direction) and added by matrix products (`nalgebra`'s `gemm`, which
//! uses the vectorized `matrixmultiply` kernels; the `n1` rows without the `dxi_m` directions),
//! then chained with `dP/dy` once per sub-segment pair, without the block of `dP/dy` that is zero
//! (the plane coordinates of the secondary vertices do not depend on the primary nodes), into a
//! row-major buffer whose rows are added to the output's. Scheme 3 skips the traction nodes that
//! are not vertices of the secondary sub-segment. Nothing is allocated per point, and the
//! derivative buffers are not cleared per sub-segment pair (its first pallet overwrites them). The
//! cost against `integrate_pair` (`benches/mortar.rs`) is in docs/performance.md.
//!
//! # Tests
//!
//! Against the dual-number formulation of level 2 (`dual_reference`): values bit for bit,
//! derivatives to 1e-13 of the largest (they are bit for bit as well; the test asks for less).
//! Against [`super::integrate_pair`] for all 25 face-type pairs and every valid scheme on tilted,
//! curved, perturbed, partially overlapping faces: the values (1e-13 of the largest weight) and
//! the derivatives against central finite differences; the momentum identity
//! `sum_b dn1_kb = sum_c dn2_kc`; frame indifference (zero derivative along rigid translations
//! and rotations of both faces); finite output on degenerate input (coincident faces, a vertex
//! exactly on an edge, slivers, NaN coordinates).
//!
//! # Code map
//!
//! - this module: [`integrate_pair_linearized`], the kernel on the walk of [`super::overlap`],
//!   and level 1 (`Level1Walk`: the plane and the projected vertices in `DualSVec64<N>`, and
//!   `dP/dy`);
//! - `level2`: level 2 of one overlapping sub-segment pair (pallets, points, values);
//! - `plane_value`: `PlaneValue`, the level-2 dual written out in floats, and the pallet point
//!   and sub-segment map in it;
//! - `plane_map`: the projected sub-segments in level 2 (local coordinates, `det(dP/dlocal)`)
//!   and the overlap vertices from their provenance;
//! - `parent`: the shape functions and `J_face` with their `xi`-derivatives;
//! - `tangent`: the tabulation per pallet and the chain to `dn/dy` (`SubPairTangent`);
//! - `dual_reference` (tests): level 2 in `DualSVec64<16>`, which the float level 2 must
//!   reproduce.

#[cfg(test)]
mod dual_reference;
mod level2;
mod parent;
mod plane_map;
mod plane_value;
mod tangent;
#[cfg(test)]
mod tests;

use nalgebra::DMatrix;
use num_dual::DualSVec64;

use super::clip::PalletSplit;
use super::overlap::{
    assert_node_counts, walk_sub_pairs, FaceGeom, IntegrationOptions, Overlap, PairFailure,
    RejectStats, SubPairKernel, SubPairOutcome,
};
use super::projection::Plane;
use super::segments::{traction_node_count, SubSegment, TractionScheme};
use crate::fe::{FaceType, Rule2};
use tangent::SubPairTangent;

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
    assert_node_counts(sec, pri, "integrate_pair_linearized");
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

/// The derivative slots of a dual number (zeros if it has none).
fn slots<const K: usize>(x: &DualSVec64<K>) -> [f64; K] {
    x.eps.0.as_ref().map_or([0.0; K], |m| m.data.0[0])
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
        let tangent = SubPairTangent::new(out, self.rule.points.len());
        let mut walk = Level1Walk::<N> {
            kernel: self,
            out,
            tangent,
            sec_dual: seeded(sec.x, 0),
            pri_dual: seeded(pri.x, 3 * sec.x.len()),
            secondary: None,
        };
        walk_sub_pairs(sec, pri, stats, &mut walk);
    }

    /// The traction nodes whose `Phi` is not identically zero on the secondary sub-segment: its
    /// vertices for scheme 3, all otherwise.
    fn active_traction_nodes(&self, s_seg: &SubSegment, count: usize) -> Vec<usize> {
        match self.scheme {
            TractionScheme::PiecewiseLinear => s_seg.local_nodes.clone(),
            _ => (0..count).collect(),
        }
    }
}

/// The level-1 plane and projected vertices of a secondary sub-segment.
type Level1Secondary<const N: usize> = (Plane<DualSVec64<N>>, Vec<[DualSVec64<N>; 2]>);

/// [`Kernel`] on the walk of [`super::overlap`], with level 1 in duals of `N >= ndof` slots.
struct Level1Walk<'k, 'a, const N: usize> {
    kernel: &'k Kernel<'a>,
    out: &'k mut LinearizedWeights,
    tangent: SubPairTangent,
    /// The node coordinates of both faces, seeded on their slots of `y`.
    sec_dual: Vec<[DualSVec64<N>; 3]>,
    pri_dual: Vec<[DualSVec64<N>; 3]>,
    /// Level 1 of the current secondary sub-segment, computed at its first overlap (`None`
    /// inside if its plane does not exist in duals).
    secondary: Option<Option<Level1Secondary<N>>>,
}

impl<const N: usize> SubPairKernel for Level1Walk<'_, '_, N> {
    fn start_secondary(&mut self, seg: &SubSegment) {
        let active = self
            .kernel
            .active_traction_nodes(seg, self.out.traction_nodes);
        self.tangent.start(active);
        self.secondary = None;
    }

    /// Level 2 of one overlapping sub-segment pair, added to `out` if it is integrated in full.
    fn integrate(&mut self, overlap: &Overlap) -> SubPairOutcome {
        let (kind, sec_dual) = (self.kernel.sec.kind, &self.sec_dual);
        let secondary = self.secondary.get_or_insert_with(|| {
            let plane = Plane::of_sub_segment(kind, sec_dual, overlap.s.seg)?;
            let vertices = plane.project_vertices(sec_dual, overlap.s.seg);
            Some((plane, vertices))
        });
        // (The float plane exists, so only by round-off at its limits.)
        let Some((plane, s_vertices)) = secondary else {
            return SubPairOutcome::Failed(PairFailure::NonFinite);
        };
        let m_vertices = plane.project_vertices(&self.pri_dual, overlap.m.seg);
        self.tangent.clear();
        match (self.kernel.level2)(self.kernel, overlap, &mut self.tangent) {
            Ok(()) => {
                let chain = plane_chain(s_vertices, &m_vertices, self.out.ndof());
                self.tangent.merge_into(self.out, &chain)
            }
            Err(failure) => SubPairOutcome::Failed(failure),
        }
    }
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
