//! Level-2 values in plain floats: a function of the plane coordinates of a sub-segment pair
//! with its derivatives along the level-2 slots ([`PlaneValue`]), and the pallet point and
//! sub-segment map written with them (module docs of [`super`], "Exactness").

use super::parent::OfParent;
use super::{slots, PlaneDual, PLANE_SLOTS};
use crate::contact::mortar::overlap::Pallet;
use crate::contact::mortar::segments::SubSegment;

/// A function of the plane coordinates at one quadrature point: its value and its derivatives
/// along the level-2 slots, as plain floats.
///
/// The level-2 work per quadrature point is done on these, with the derivatives written out (the
/// chain rule by hand), rather than in `PlaneDual`. Every operation, values and derivatives, is the
/// one `PlaneDual` arithmetic would do, in its order (`x / y` is `x * (1 / y)` with derivative
/// `(dx y - dy x) (1 / y) (1 / y)`, `x y` has `dx y + dy x`, ...), so the results are bit for bit
/// those of the dual code (module docs of [`super`], "Exactness"). The derivatives are those of the
/// module docs of [`super`]:
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
pub(super) struct PlaneValue {
    pub(super) re: f64,
    pub(super) d: [f64; PLANE_SLOTS],
}

impl PlaneValue {
    pub(super) const ZERO: PlaneValue = PlaneValue {
        re: 0.0,
        d: [0.0; PLANE_SLOTS],
    };

    pub(super) fn of(x: &PlaneDual) -> Self {
        PlaneValue {
            re: x.re,
            d: slots(x),
        }
    }

    /// `self * f` for a float `f`.
    pub(super) fn scaled(&self, f: f64) -> Self {
        PlaneValue {
            re: self.re * f,
            d: self.d.map(|v| v * f),
        }
    }

    /// `self / den`.
    pub(super) fn over(&self, den: &PlaneValue) -> Self {
        let inverse = 1.0 / den.re;
        PlaneValue {
            re: self.re * inverse,
            d: std::array::from_fn(|k| {
                (self.d[k] * den.re - den.d[k] * self.re) * inverse * inverse
            }),
        }
    }

    /// `self * other` (the product rule, in the order of the duals' operations).
    pub(super) fn times(&self, other: &PlaneValue) -> Self {
        PlaneValue {
            re: self.re * other.re,
            d: std::array::from_fn(|k| self.d[k] * other.re + other.d[k] * self.re),
        }
    }

    /// `self - other`.
    pub(super) fn minus(&self, other: &PlaneValue) -> Self {
        PlaneValue {
            re: self.re - other.re,
            d: std::array::from_fn(|k| self.d[k] - other.d[k]),
        }
    }

    /// `self * f(xi(P))` for a function `f` of the parent coordinates given with its
    /// `xi`-derivatives and `xi` with its `P`-derivatives (the chain rule to plane coordinates).
    pub(super) fn times_lifted(&self, f: &OfParent, xi: &[PlaneValue; 2]) -> Self {
        let g = f.d;
        PlaneValue {
            re: self.re * f.re,
            d: std::array::from_fn(|k| {
                self.d[k] * f.re + self.re * (xi[0].d[k] * g[0] + xi[1].d[k] * g[1])
            }),
        }
    }
}

/// `det [u v]` of two plane vectors (as `projection::det2` in level-2 duals).
pub(super) fn plane_det2(u: &[PlaneValue; 2], v: &[PlaneValue; 2]) -> PlaneValue {
    u[0].times(&v[1]).minus(&u[1].times(&v[0]))
}

/// The level-2 pallet: its apex, the edges `u`, `v` from the apex and `det [u v]`.
pub(super) struct PlanePallet {
    apex: [PlaneValue; 2],
    u: [PlaneValue; 2],
    v: [PlaneValue; 2],
    pub(super) twice_area: PlaneValue,
}

impl PlanePallet {
    /// The pallet in level-2 duals, as plain floats.
    pub(super) fn of(pallet: &Pallet<PlaneDual>) -> Self {
        PlanePallet {
            apex: pallet.apex.map(|c| PlaneValue::of(&c)),
            u: pallet.u.map(|c| PlaneValue::of(&c)),
            v: pallet.v.map(|c| PlaneValue::of(&c)),
            twice_area: PlaneValue::of(&pallet.twice_area),
        }
    }

    /// The point `c + q_0 u + q_1 v` of the pallet.
    pub(super) fn point(&self, q: [f64; 2]) -> [PlaneValue; 2] {
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
pub(super) fn to_parent(seg: &SubSegment, local: &[PlaneValue; 2]) -> [PlaneValue; 2] {
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
