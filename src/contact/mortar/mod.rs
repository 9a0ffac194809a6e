//! Mortar segment-to-segment integration (geometry only; no physics).
//!
//! Puso, Laursen & Solberg (2004), section 3, and ALGORITHM.md sections 3 and 5. The quantities
//! produced are the mortar weights of eq. (6),
//!
//! `n1_AB = int_gamma Phi_A N1_B dgamma`, `n2_AC = int_gamma Phi_A N2_C dgamma`,
//!
//! for traction nodes A of the secondary face, displacement nodes B of the secondary face and C
//! of the primary face, over the overlap gamma of the two faces.

pub mod clip;
pub mod pair;
pub mod segments;

