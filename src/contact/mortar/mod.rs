//! Mortar segment-to-segment integration (geometry only; no physics).
//!
//! Puso, Laursen & Solberg (2004), section 3, and docs/theory.md sections 3 and 5. The quantities
//! produced are the mortar weights of eq. (6),
//!
//! `n1_AB = int_gamma Phi_A N1_B dgamma`, `n2_AC = int_gamma Phi_A N2_C dgamma`,
//!
//! for traction nodes A of the secondary face, displacement nodes B of the secondary face and C
//! of the primary face, over the overlap gamma of the two faces.
//!
//! The modules, in the order a face pair goes through them:
//!
//! - [`segments`]: the linear sub-segments of quadratic faces (the paper's Figure 1; Tri6 is
//!   split into four triangles) and the traction functions `Phi` of the three schemes
//!   ([`TractionScheme`]); scheme 1 is refused on Quad8 and Tri6 by [`traction_nodes`].
//! - [`projection`]: the projection plane of a secondary sub-segment (the face's geometric
//!   normal at the sub-segment centre) and the maps between the plane and the sub-segments'
//!   local coordinates (triangle in closed form, bilinear quadrilateral by Newton), generic over
//!   the scalar so that both kernels run the same code.
//! - [`clip`]: robust intersection of convex polygons in the projection plane, with the
//!   provenance of each overlap vertex, and the pallets (triangles from the overlap's centroid,
//!   or a fan from one of its vertices) the overlap is integrated on.
//! - [`overlap`]: the walk both kernels share: every sub-segment pair, its rejection tests,
//!   its overlap polygon and pallets, and the counts of what became of it ([`RejectStats`]).
//! - [`pair`]: the value kernel, [`integrate_pair`]: at each quadrature point `N1`, `Phi`, `N2`
//!   and the measure, and the weights with the same points for `n1` and `n2` (so
//!   `sum_B n1_AB = sum_C n2_AC`: linear momentum).
//! - [`linearize`]: the linearized kernel, [`integrate_pair_linearized`]: the same weights with
//!   their exact derivatives with respect to the node coordinates of both faces.
//!
//! Conventions a caller relies on: traction node `k` of a face is its face-local node `k`
//! (traction nodes are all nodes, or the corners, which come first); the measure is the true
//! area of the curved secondary face (a fully covered secondary face gets `sum n1 =` its area);
//! the traction scheme is validated once with [`traction_nodes`], not in [`integrate_pair`].

pub mod clip;
pub mod linearize;
pub mod overlap;
pub mod pair;
pub mod projection;
pub mod segments;
#[cfg(test)]
mod test_support;

pub use clip::{clip_convex, is_convex_ccw, pallets, polygon_area, Clipped, PalletSplit};
pub use linearize::{integrate_pair_linearized, LinearizedWeights};
pub use pair::{
    integrate_pair, FaceGeom, IntegrationOptions, PairWeights, RejectStats, OPPOSED_NORMALS_COSINE,
};
pub use segments::{
    sub_segments, traction_node_count, traction_nodes, traction_shape, traction_shape_on,
    SubSegment, TractionScheme,
};
