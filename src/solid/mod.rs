//! Element residuals and tangents of the bulk (total Lagrangian), and surface and body loads.
//!
//! # Kinematics
//!
//! An element maps the parent domain to the reference configuration by
//! `X(xi) = sum_a N_a(xi) X_a`, with Jacobian `J0_ij = dX_i/dxi_j = sum_a X_ai dN_a/dxi_j` and
//! reference gradients `dN_a/dX_J = sum_j dN_a/dxi_j (J0^-1)_jJ`. These, the values `N_a`, the
//! weights `w det J0` and the points `X` are precomputed once per element in [`ElementGeometry`].
//! With nodal displacements `u_a` the deformation gradient at a point is
//!
//! ```text
//! F_iJ = d_iJ + sum_a u_ai dN_a/dX_J.
//! ```
//!
//! # Internal force and tangent
//!
//! From the stored energy `Pi = int W(F) dV0`, with `P = dW/dF` and `A = dP/dF`
//! ([`crate::material`]):
//!
//! ```text
//! f_int,ai      = sum_q P_iJ dN_a/dX_J w det J0
//! K_(ai)(bk)    = sum_q dN_a/dX_J A_iJkL dN_b/dX_L w det J0
//! ```
//!
//! The tangent uses the factored isotropic form [`crate::material::IsoTangent`]
//! `A_iJkL = alpha d_ik d_JL + beta M_Li M_Jk + gamma M_Ji M_Lk`: with `g_a = M^T dN_a/dX`,
//!
//! ```text
//! K_ab = sum_q w det J0 [ alpha (dN_a/dX . dN_b/dX) I + beta g_b g_a^T + gamma g_a g_b^T ],
//! ```
//!
//! which is symmetric (`K_ba = K_ab^T`, from the major symmetry of `A`), so only the blocks
//! `a <= b` are computed and mirrored.
//!
//! # Loads
//!
//! Body force per reference volume: `f_a = int N_a b dV0`.
//!
//! Follower pressure `p` on a face with current node positions `x_a`: with the tangents
//! `t1 = x_,xi = sum_c x_c N_c,xi`, `t2 = x_,eta` and `n da = (t1 x t2) dxi deta`,
//!
//! ```text
//! f_a = -p int N_a (t1 x t2) dxi deta.
//! ```
//!
//! Since `d(t1 x t2)/dx_b = N_b,xi d(t1 x t2)/dt1 + N_b,eta d(t1 x t2)/dt2
//! = [N_b,eta t1 - N_b,xi t2]_x` (with `[v]_x w = v x w`), the exact (nonsymmetric) tangent is
//!
//! ```text
//! df_a/dx_b = -p int N_a [N_b,eta t1 - N_b,xi t2]_x dxi deta.
//! ```
//!
//! The external force enters the residual with the opposite sign of the internal force
//! (`R = f_int - f_ext`), so the solver subtracts this tangent.

mod bulk;
mod kernel;
mod loads;

#[cfg(test)]
mod tests;

pub use bulk::{gather_nodes, Bulk};
pub use kernel::{
    element_stress, for_each_point, internal_force, ElementGeometry, InvertedElement, MAX_NODES,
};
pub use loads::{body_force, follower_pressure, MAX_FACE_NODES};
