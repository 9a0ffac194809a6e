//! Finite-element building blocks: topology ([`element`]), shape functions ([`shape`]) and
//! quadrature ([`quadrature`]).

pub mod element;
pub mod quadrature;
pub mod shape;

pub use element::{ElementType, FaceType};
pub use quadrature::{gauss_legendre, Rule2, Rule3};
pub use shape::{face_normal, face_tangents};
