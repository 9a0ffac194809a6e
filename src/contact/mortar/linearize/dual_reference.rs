//! Level 2 of [`super`] in `PlaneDual` numbers (16-slot forward mode): the dual formulation that
//! the float level 2 must reproduce **bit for bit** (test
//! `float_level2_reproduces_the_dual_reference`; why, in the module docs of [`super`],
//! "Exactness"). It runs the same walk, pallets and float inverse maps, and evaluates the point
//! geometry with the generic code of `projection` and the shape functions in dual numbers.

use num_dual::DualNum;

use super::parent::{face_jacobian_by_nodes, parent_seed, OfParent};
use super::plane_map::{PlaneMap, TracedOverlap};
use super::plane_value::PlaneValue;
use super::tangent::{PointGeometry, PointValues, SubPairTangent};
use super::{Kernel, ParentDual, PlaneDual, MAX_NODES, MAX_SEC_DOFS};
use crate::contact::mortar::overlap::{pallets_of, Overlap, PairFailure};
use crate::contact::mortar::projection::{det2, solve2, triangle_local, Bilinear, LocalPoint};
use crate::contact::mortar::segments::{traction_shape_on_at, SubSegment, TractionScheme};
use crate::vec3::cross;

/// [`Kernel::integrate_overlap`] in level-2 duals.
pub(super) fn integrate_overlap(
    kernel: &Kernel,
    overlap: &Overlap,
    tangent: &mut SubPairTangent,
) -> Result<(), PairFailure> {
    let traced = TracedOverlap::new(overlap, &mut tangent.unresolved);
    let (s_dual, m_dual) = (DualMap::new(&traced.s), DualMap::new(&traced.m));
    let sec_jacobian = overlap.s.seg.parent_jacobian();
    for pallet in pallets_of(kernel.pallets, &traced.polygon, &overlap.origins) {
        for (point, (q, w)) in kernel
            .rule
            .points
            .iter()
            .zip(&kernel.rule.weights)
            .enumerate()
        {
            let p = pallet.point(*q);
            let (on_s, on_m) = overlap.locate([p[0].re, p[1].re])?;
            let local_s = s_dual.local(p, &on_s);
            let local_m = m_dual.local(p, &on_m);
            let xi_s = overlap.s.seg.to_parent_at(local_s);
            let xi_m = overlap.m.seg.to_parent_at(local_m);
            let measure = pallet.twice_area * (w * sec_jacobian) / s_dual.jacobian(local_s);
            add_point(kernel, overlap.s.seg, xi_s, xi_m, measure, point, tangent)?;
        }
        tangent.add_pallet();
    }
    tangent.finished()
}

/// [`Kernel::add_point`] in level-2 duals.
fn add_point(
    kernel: &Kernel,
    seg: &SubSegment,
    xi_s: [PlaneDual; 2],
    xi_m: [PlaneDual; 2],
    measure: PlaneDual,
    point: usize,
    tangent: &mut SubPairTangent,
) -> Result<(), PairFailure> {
    let (sec, pri) = (kernel.sec, kernel.pri);
    let (ns, np) = (sec.x.len(), pri.x.len());
    let zero = ParentDual::from_re(0.0);
    let (mut n, mut dn) = ([zero; MAX_NODES], [[zero; 2]; MAX_NODES]);
    let mut values = PointValues::default();
    let s_parent = parent_seed(xi_s.map(|v| v.re));
    sec.kind
        .shape_and_grad_at(s_parent, &mut n[..ns], &mut dn[..ns]);
    let mut dweight_dx = [0.0; MAX_SEC_DOFS];
    let face_jacobian = face_jacobian(sec.x, &dn[..ns], &mut dweight_dx);
    OfParent::fill(&mut values.n1, &n[..ns]);
    if kernel.scheme == TractionScheme::FaceShape {
        values.phi = values.n1;
    } else {
        traction_shape_on_at(
            sec.kind,
            kernel.scheme,
            seg,
            s_parent,
            &mut tangent.phi_scratch,
        );
        OfParent::fill(&mut values.phi, &tangent.phi_scratch);
    }
    pri.kind
        .shape_at(parent_seed(xi_m.map(|v| v.re)), &mut n[..np]);
    OfParent::fill(&mut values.n2, &n[..np]);
    let weight = measure * lift(&face_jacobian, &xi_s);
    values.set_weight(weight.re, face_jacobian.re, &mut dweight_dx)?;
    let at = PointGeometry {
        seg,
        xi_s: xi_s.map(|x| PlaneValue::of(&x)),
        xi_m: xi_m.map(|x| PlaneValue::of(&x)),
        measure: PlaneValue::of(&measure),
    };
    let weight = PlaneValue::of(&weight);
    tangent.tabulate(point, &values, &at, &weight, &dweight_dx[..3 * ns]);
    Ok(())
}

/// `f(xi(P))` with `f` given with its `xi`-derivatives and `xi` with its `P`-derivatives.
fn lift(f: &ParentDual, xi: &[PlaneDual; 2]) -> PlaneDual {
    match &f.eps.0 {
        None => PlaneDual::from_re(f.re),
        Some(g) => PlaneDual::new(f.re, xi[0].eps * g[0] + xi[1].eps * g[1]),
    }
}

/// `super::parent::face_jacobian` from the shape-function gradients in `ParentDual` numbers.
fn face_jacobian(
    x: &[[f64; 3]],
    dn: &[[ParentDual; 2]],
    dj_dx: &mut [f64; MAX_SEC_DOFS],
) -> ParentDual {
    let mut t = [[ParentDual::from_re(0.0); 3]; 2];
    for (xa, ga) in x.iter().zip(dn) {
        for (ti, gi) in t.iter_mut().zip(ga) {
            for d in 0..3 {
                ti[d] += *gi * xa[d];
            }
        }
    }
    let c = cross(t[0], t[1]);
    let jacobian = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    face_jacobian_by_nodes(
        t.map(|ti| ti.map(|v| v.re)),
        c.map(|v| v.re),
        jacobian.re,
        dn.iter().map(|g| [g[0].re, g[1].re]),
        dj_dx,
    );
    jacobian
}

/// A projected sub-segment in level-2 duals, with the bilinear map of a quadrilateral.
struct DualMap {
    vertices: Vec<[PlaneDual; 2]>,
    bilinear: Option<Bilinear<PlaneDual>>,
}

impl DualMap {
    fn new(map: &PlaneMap) -> Self {
        let vertices = map.vertices[..map.projected.vertices.len()].to_vec();
        let bilinear = (vertices.len() == 4).then(|| Bilinear::new(&vertices));
        DualMap { vertices, bilinear }
    }

    /// Closed form on a triangle, one Newton step from `found` on a quadrilateral.
    fn local(&self, p: [PlaneDual; 2], found: &LocalPoint) -> [PlaneDual; 2] {
        match &self.bilinear {
            None => triangle_local(&self.vertices[..3], p).0,
            Some(map) => {
                let x = map.point(found.local);
                let j = map.jacobian_re(found.local);
                let det = det2(j[0], j[1]);
                let [d0, d1] = solve2(j, det, [x[0] - p[0], x[1] - p[1]]);
                [-d0 + found.local[0], -d1 + found.local[1]]
            }
        }
    }

    /// `det(dP/dlocal)` at `local`.
    fn jacobian(&self, local: [PlaneDual; 2]) -> PlaneDual {
        match &self.bilinear {
            None => {
                let q = &self.vertices;
                det2(
                    [q[1][0] - q[0][0], q[1][1] - q[0][1]],
                    [q[2][0] - q[0][0], q[2][1] - q[0][1]],
                )
            }
            Some(map) => map.jacobian(local),
        }
    }
}
