//! The mortar weights of one face pair **with their derivatives** with respect to the node
//! coordinates of both faces: the consistent tangent of the contact kernel (ALGORITHM.md
//! section 7). Work in progress: see `integrate_pair_linearized`.

use super::pair::{FaceGeom, IntegrationOptions, RejectStats};

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
}

impl LinearizedWeights {
    /// `3 (ns + np)`.
    pub fn ndof(&self) -> usize {
        3 * (self.sec_nodes + self.pri_nodes)
    }
}

/// As [`super::integrate_pair`], with derivatives (see [`LinearizedWeights`]).
pub fn integrate_pair_linearized(
    _sec: &FaceGeom,
    _pri: &FaceGeom,
    _opts: &IntegrationOptions,
    _stats: &mut RejectStats,
) -> LinearizedWeights {
    unimplemented!("integrate_pair_linearized: being written")
}
