//! The weights of one sub-segment pair and their derivatives, tabulated per pallet and chained
//! to the node coordinates ([`SubPairTangent`]; module docs of [`super`], "Cost").

use nalgebra::{DMatrix, DMatrixViewMut};

use super::parent::OfParent;
use super::plane_value::PlaneValue;
use super::{LinearizedWeights, ParentDual, MAX_NODES, MAX_SEC_DOFS, PLANE_SLOTS, PRIMARY_SLOT};
use crate::contact::mortar::overlap::{PairFailure, SubPairOutcome};
use crate::contact::mortar::segments::SubSegment;

/// The level-2 geometry of one quadrature point.
pub(super) struct PointGeometry<'s> {
    /// The secondary sub-segment (for scheme 3).
    pub(super) seg: &'s SubSegment,
    pub(super) xi_s: [PlaneValue; 2],
    pub(super) xi_m: [PlaneValue; 2],
    /// `w_P det(dP/dlocal_pallet) det(dxi/dlocal) / det(dP/dlocal_s)`: the weight without
    /// `J_face`.
    pub(super) measure: PlaneValue,
}

/// `Phi_k(xi_s)`, `N1_b(xi_s)`, `N2_c(xi_m)` with their `xi`-derivatives, and the weight, at
/// one quadrature point.
#[derive(Default)]
pub(super) struct PointValues {
    pub(super) phi: [OfParent; MAX_NODES],
    pub(super) n1: [OfParent; MAX_NODES],
    pub(super) n2: [OfParent; MAX_NODES],
    weight: f64,
}

impl PointValues {
    /// Sets the weight `weight` of the point (`face_jacobian` the `J_face` in it) and turns
    /// `dJ_face/dx_s` in `dweight_dx` into `dweight/dx_s = weight / J_face dJ_face/dx_s`; fails
    /// on a non-finite value, as `integrate_pair` does (values only).
    pub(super) fn set_weight(
        &mut self,
        weight: f64,
        face_jacobian: f64,
        dweight_dx: &mut [f64; MAX_SEC_DOFS],
    ) -> Result<(), PairFailure> {
        let ratio = if face_jacobian > 0.0 {
            weight / face_jacobian
        } else {
            0.0
        };
        dweight_dx.iter_mut().for_each(|g| *g *= ratio);
        self.weight = weight;
        self.is_finite().then_some(()).ok_or(PairFailure::NonFinite)
    }

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
pub(super) struct SubPairTangent {
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
    pub(super) unresolved: usize,
    /// Scratch for the traction functions of one point.
    pub(super) phi_scratch: Vec<ParentDual>,
}

impl SubPairTangent {
    /// Buffers for the face sizes of `out` and pallets of `points` quadrature points.
    pub(super) fn new(out: &LinearizedWeights, points: usize) -> Self {
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
    pub(super) fn start(&mut self, active: Vec<usize>) {
        self.active = active;
    }

    /// The rows of `n1` (the first) and of all weights.
    fn rows(&self) -> (usize, usize) {
        let n = self.active.len();
        (n * self.ns, n * (self.ns + self.np))
    }

    pub(super) fn clear(&mut self) {
        self.values.fill(0.0);
        self.area = 0.0;
        self.points_added = 0;
        self.pallets_added = 0;
        self.unresolved = 0;
    }

    /// Adds the values of one point and tabulates its derivatives (column `point` of each
    /// block).
    pub(super) fn tabulate(
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
    pub(super) fn add_pallet(&mut self) {
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

    /// The end of a sub-segment pair's level 2: fails if a derivative is not finite.
    pub(super) fn finished(&self) -> Result<(), PairFailure> {
        self.is_finite().then_some(()).ok_or(PairFailure::NonFinite)
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
    pub(super) fn merge_into(
        &mut self,
        out: &mut LinearizedWeights,
        chain: &DMatrix<f64>,
    ) -> SubPairOutcome {
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
