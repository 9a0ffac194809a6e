//! Structured mesh generators: every part is one or more [`mapped_block`]s (see [`block`] for the
//! lattice, the tetrahedral split and the named sets), mapped to a box ([`box_mesh`],
//! [`zoned_box_mesh`], [`beam`]) or to a cube-sphere ([`sphere`]:
//! [`thick_sphere_octant`], [`hemisphere_quarter`]). Graded spacings come from [`grading`].
//!
//! Merging parts and checking a mesh are [`Mesh::merge`](crate::mesh::Mesh::merge) and
//! [`Mesh::check`](crate::mesh::Mesh::check).

pub mod block;
pub mod grading;
pub mod sphere;

pub use block::{beam, box_mesh, mapped_block, zoned_box_mesh};
pub use grading::{exp_grading, ZoneGrading};
pub use sphere::{hemisphere_quarter, thick_sphere_octant, HEMISPHERE_CORE};
