//! Level 2 of one overlapping sub-segment pair in plain floats (module docs of [`super`], step
//! 3): the overlap's pallets and quadrature points, their local and parent coordinates with
//! their derivatives along the plane coordinates, and the values tabulated at each point.

use super::parent::{face_jacobian, parent_seed, shape_derivatives, shape_values_at, OfParent};
use super::plane_map::TracedOverlap;
use super::plane_value::{to_parent, PlanePallet};
use super::tangent::{PointGeometry, PointValues, SubPairTangent};
use super::{Kernel, ParentDual, MAX_NODES, MAX_SEC_DOFS};
use crate::contact::mortar::overlap::{pallets_of, Overlap, PairFailure};
use crate::contact::mortar::segments::{traction_shape_on_at, TractionScheme};
use crate::fe::shape::TensorShape;
use crate::fe::FaceType;

impl Kernel<'_> {
    /// Level 2 for one overlapping sub-segment pair, into `tangent` (merged by the caller on
    /// success only, like `integrate_pair` does).
    pub(super) fn integrate_overlap(
        &self,
        overlap: &Overlap,
        tangent: &mut SubPairTangent,
    ) -> Result<(), PairFailure> {
        let traced = TracedOverlap::new(overlap, &mut tangent.unresolved);
        let (s_map, m_map) = (&traced.s, &traced.m);
        let sec_jacobian = overlap.s.seg.parent_jacobian();
        for pallet in pallets_of(self.pallets, &traced.polygon, &overlap.origins) {
            let pallet = PlanePallet::of(&pallet);
            for (point, (q, w)) in self.rule.points.iter().zip(&self.rule.weights).enumerate() {
                let p = pallet.point(*q);
                let (on_s, on_m) = overlap.locate([p[0].re, p[1].re])?;
                let local_s = s_map.local(&p, &on_s);
                let local_m = m_map.local(&p, &on_m);
                let at = PointGeometry {
                    seg: overlap.s.seg,
                    xi_s: to_parent(overlap.s.seg, &local_s),
                    xi_m: to_parent(overlap.m.seg, &local_m),
                    measure: pallet
                        .twice_area
                        .scaled(w * sec_jacobian)
                        .over(&s_map.jacobian(&local_s)),
                };
                self.add_point(&at, point, tangent)?;
            }
            tangent.add_pallet();
        }
        tangent.finished()
    }

    /// Evaluates `Phi`, `N1`, `N2` and the weight at quadrature point `point` of the current
    /// pallet and tabulates them in `tangent` (values added at once, derivatives by pallet).
    fn add_point(
        &self,
        at: &PointGeometry,
        point: usize,
        tangent: &mut SubPairTangent,
    ) -> Result<(), PairFailure> {
        let (mut values, face_jacobian, mut dweight_dx) =
            self.shape_values(at, &mut tangent.phi_scratch);
        let weight = at.measure.times_lifted(&face_jacobian, &at.xi_s);
        values.set_weight(weight.re, face_jacobian.re, &mut dweight_dx)?;
        let sec_dofs = 3 * self.sec.x.len();
        tangent.tabulate(point, &values, at, &weight, &dweight_dx[..sec_dofs]);
        Ok(())
    }

    /// `Phi(xi_s)`, `N1(xi_s)`, `N2(xi_m)` with their `xi`-derivatives (the weight is left to
    /// the caller), `J_face(xi_s)` with its `xi`-derivatives, and `dJ_face/dx_s`.
    fn shape_values(
        &self,
        at: &PointGeometry,
        phi_scratch: &mut Vec<ParentDual>,
    ) -> (PointValues, OfParent, [f64; MAX_SEC_DOFS]) {
        let (sec, pri) = (self.sec, self.pri);
        let ns = sec.x.len();
        let mut values = PointValues::default();
        let xi_s = at.xi_s.map(|v| v.re);
        let mut shapes = [TensorShape::default(); MAX_NODES];
        shape_derivatives(sec.kind, xi_s, &mut shapes[..ns]);
        let mut dj_dx = [0.0; MAX_SEC_DOFS];
        let face_jacobian = face_jacobian(sec.x, &shapes[..ns], &mut dj_dx);
        for (t, shape) in values.n1.iter_mut().zip(&shapes[..ns]) {
            *t = OfParent {
                re: shape.value,
                d: shape.value_derivative,
            };
        }
        match self.scheme {
            TractionScheme::FaceShape => values.phi = values.n1,
            // The corner functions are the linear face's.
            TractionScheme::Corners => {
                let linear = if sec.kind.is_quad() {
                    FaceType::Quad4
                } else {
                    FaceType::Tri3
                };
                shape_values_at(linear, xi_s, &mut values.phi);
            }
            TractionScheme::PiecewiseLinear => {
                traction_shape_on_at(
                    sec.kind,
                    self.scheme,
                    at.seg,
                    parent_seed(xi_s),
                    phi_scratch,
                );
                OfParent::fill(&mut values.phi, phi_scratch);
            }
        }
        shape_values_at(pri.kind, at.xi_m.map(|v| v.re), &mut values.n2);
        (values, face_jacobian, dj_dx)
    }
}
