//! Interfaces between bodies: search, mortar integration, and what is enforced on them.
//!
//! - [`search`]: candidate segment pairs from bounding boxes (an R*-tree), only for the declared
//!   interfaces.
//! - [`mortar`]: geometry only: sub-segments of quadratic faces, traction shape functions of the
//!   three schemes, and the integration of one secondary face against one primary face into
//!   mortar weights.
//! - [`tying`]: mesh tying of dissimilar meshes (the vector weighted-gap constraint) by penalty
//!   plus Uzawa augmented Lagrangian.
//! - [`normals`]: averaged nodal normals of a contact surface and their linearization.
//! - [`law`]: the pointwise laws of frictional contact (normal pressure, Coulomb return map,
//!   traction transport, Uzawa updates) with their derivatives: physics only.
//! - [`frictional`]: frictional contact on current mortar weights: gaps, slip, the laws,
//!   Uzawa, the consistent tangent, and their assembly into the distributed system.
//! - [`block_sum`]: sums the dense node blocks of a tangent into sparse node rows before PETSc.

pub mod block_sum;
pub mod frictional;
pub mod law;
pub mod mortar;
pub mod node_on_segment;
pub mod normals;
pub mod search;
pub mod tying;

use crate::case::Interface;
use crate::mesh::FaceRef;

/// The (secondary, primary) faces of pass `pass` of an interface: its declared sides in the
/// first pass, swapped in the second (two passes: both sides carry tractions in turn).
pub(crate) fn pass_sides(iface: &Interface, pass: usize) -> (&[FaceRef], &[FaceRef]) {
    if pass == 0 {
        (&iface.secondary, &iface.primary)
    } else {
        (&iface.primary, &iface.secondary)
    }
}
