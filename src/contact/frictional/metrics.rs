//! The summary metrics of the contact interfaces: penetration and gaps at the final state, the
//! segment-pair counts, the slip force ratio over the run, and the figures of the contact
//! patch test and of the Hertz verification.

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use crate::case::Verification;
use crate::contact::mortar::{sub_segments, traction_nodes, traction_shape};
use crate::model::{NodalForces, State};
use crate::verify::PressurePoint;

use super::{ContactInterfaces, NodeFields};

/// Degree of the rule on each (sub-)segment for the Hertz measurement: exact for `p_h r^2 dA`
/// on flat bilinear faces (degree 1 + 2 + 1 per direction, tensor Gauss), near it on curved
/// quadratic ones.
const HERTZ_QUADRATURE_DEGREE: usize = 7;

impl ContactInterfaces {
    /// Figures of the final state `at` (*collective*): per interface the largest normalized
    /// gap (`max_gap_<name>`, positive in penetration; only when some node has an overlap) and
    /// the largest penetration relative to the node size h_A (`max_rel_penetration_<name>`; 0
    /// when nothing penetrates, also when the bodies have parted); for the contact patch test
    /// `max_rel_pressure_error` (the largest |p_A - p0| / p0 over every node with an overlap)
    /// and `net_contact_force` (|sum of every contact nodal force| / (p0 times the contact
    /// area)); for the Hertz verification, its figures ([`Self::hertz_metrics`]).
    pub(crate) fn state_metrics(
        &self,
        at: &State,
        world: &SimpleCommunicator,
    ) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        let patch_pressure = match at.scene.verification {
            Some(Verification::ContactPatch { pressure, .. }) => Some(pressure),
            _ => None,
        };
        let (mut pressure_error, mut area) = (0.0f64, 0.0);
        for (i, iface) in self.interfaces.iter().enumerate() {
            let mut worst_gap = f64::NEG_INFINITY;
            let mut worst_rel = 0.0f64;
            for (p, pass) in iface.passes.iter().enumerate() {
                let fields = self.pass_fields(at, i, p, world);
                for (f, st) in fields.iter().zip(&pass.state) {
                    if f.area <= 0.0 {
                        continue;
                    }
                    worst_gap = worst_gap.max(f.gap);
                    worst_rel = worst_rel.max(f.gap / st.h);
                    if let Some(p0) = patch_pressure {
                        pressure_error = pressure_error.max((f.pressure - p0).abs() / p0);
                        if p == 0 {
                            area += f.area;
                        }
                    }
                }
            }
            // Always there, so that an expectation on it holds when the bodies have parted (0:
            // nothing penetrates); the largest gap only exists where a node has an overlap.
            out.push((format!("max_rel_penetration_{}", iface.name), worst_rel));
            if worst_gap.is_finite() {
                out.push((format!("max_gap_{}", iface.name), worst_gap));
            }
        }
        if let Some(Verification::Hertz { interface, .. }) = &at.scene.verification {
            out.extend(self.hertz_metrics(at, world, interface));
        }
        if let Some(p0) = patch_pressure {
            let net = self.net_force(at, world);
            out.push(("max_rel_pressure_error".into(), pressure_error));
            out.push((
                "net_contact_force".into(),
                net / (p0 * area).max(f64::MIN_POSITIVE),
            ));
        }
        out
    }

    /// The magnitude of the sum of every contact nodal force (*collective*).
    fn net_force(&self, at: &State, world: &SimpleCommunicator) -> f64 {
        let mut nodal = vec![0.0; at.u.len()];
        let mut sink = NodalForces(&mut nodal);
        let _ = self.assemble(at, false, |block| {
            crate::model::ForceSink::add_forces(&mut sink, &block.slots, &block.force)
        });
        let mut local = [0.0; 3];
        for (d, v) in nodal.iter().enumerate() {
            local[d % 3] += v;
        }
        let mut total = [0.0f64; 3];
        world.all_reduce_into(&local[..], &mut total[..], SystemOperation::sum());
        (total[0].powi(2) + total[1].powi(2) + total[2].powi(2)).sqrt()
    }

    /// Figures of the whole run (*collective*): the segment-pair counts of the last evaluation
    /// (`pairs_<name>_<kind>`, summed over ranks) and, for frictional interfaces,
    /// `slip_force_ratio_<name>`: the mean of tangential / (mu normal) contact force over the
    /// committed steps in which every pressed node slips (also as `slip_force_ratio` when the
    /// scene has one frictional interface).
    pub(crate) fn run_metrics(&self, world: &SimpleCommunicator) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        let frictional = self.interfaces.iter().filter(|i| i.mu > 0.0).count();
        for (i, iface) in self.interfaces.iter().enumerate() {
            let stats = iface.stats.borrow().to_map();
            let vals: Vec<u64> = stats.values().map(|&v| v as u64).collect();
            let mut sums = vec![0u64; vals.len()];
            world.all_reduce_into(&vals[..], &mut sums[..], SystemOperation::sum());
            for (kind, v) in stats.keys().zip(sums) {
                out.push((format!("pairs_{}_{kind}", iface.name), v as f64));
            }
            if iface.mu <= 0.0 {
                continue;
            }
            let ratios: Vec<f64> = self
                .history
                .iter()
                .map(|step| step[i])
                .filter(|f| f[5] == 0.0 && f[6] > 0.0 && f[0] > 0.0)
                .map(|f| f[1] / (iface.mu * f[0]))
                .collect();
            if !ratios.is_empty() {
                let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
                out.push((format!("slip_force_ratio_{}", iface.name), mean));
                if frictional == 1 {
                    out.push(("slip_force_ratio".into(), mean));
                }
            }
        }
        out
    }

    /// The `hertz` verification's metrics (`crate::verify`, "Hertz"), from the nodal fields of
    /// the first pass of the contact interface `interface`, gathered on every rank: the force
    /// from the nodal forces, the contact radius and the peak pressure from the interpolated
    /// pressure field `p_h = sum_A p_A Phi_A` integrated over the current secondary faces.
    fn hertz_metrics(
        &self,
        at: &State,
        world: &SimpleCommunicator,
        interface: &str,
    ) -> Vec<(String, f64)> {
        let Some(Verification::Hertz {
            radius,
            model_fraction,
            e_star,
            ..
        }) = at.scene.verification.clone()
        else {
            return Vec::new();
        };
        let Some(i) = self.interfaces.iter().position(|c| c.name == interface) else {
            return Vec::new();
        };
        let fields = self.pass_fields(at, i, 0, world);
        // The force: the nodal forces' axial components.
        let axial: f64 = fields
            .iter()
            .map(|f| f.area * f.pressure * f.normal[2])
            .sum();
        let force = axial.abs() / model_fraction;
        let pressed = fields.iter().filter(|f| f.pressure > 0.0).count();
        let max_pressure = fields.iter().map(|f| f.pressure).fold(0.0, f64::max);
        let mut out = vec![
            ("contact_force".to_string(), force),
            ("hertz_contact_nodes".to_string(), pressed as f64),
            ("max_pressure".to_string(), max_pressure),
        ];
        if force > 0.0 {
            let (a_h, p0_h) = crate::verify::hertz(force, radius, e_star);
            out.push(("hertz_contact_radius".into(), a_h));
            out.push(("hertz_peak_pressure".into(), p0_h));
            let points = self.pressure_points(at, i, &fields);
            if let Some(m) = crate::verify::hertz_measure(&points) {
                let ea = (m.contact_radius - a_h).abs() / a_h;
                let ep = (m.peak_pressure - p0_h).abs() / p0_h;
                out.push(("contact_radius".into(), m.contact_radius));
                out.push(("peak_pressure".into(), m.peak_pressure));
                out.push(("rel_error_contact_radius".into(), ea));
                out.push(("rel_error_peak_pressure".into(), ep));
                out.push(("rel_error_hertz".into(), ea.max(ep)));
            }
        }
        out
    }

    /// `p_h` at the quadrature points of every secondary face of interface `i`'s first pass
    /// that carries a pressure (`fields`: the pass's nodal fields).
    fn pressure_points(&self, at: &State, i: usize, fields: &[NodeFields]) -> Vec<PressurePoint> {
        let mesh = &at.scene.mesh;
        let iface = &self.interfaces[i];
        let pass = &iface.passes[0];
        let scheme = pass.method.carrier_scheme(iface.scheme);
        let current =
            |n: usize| -> [f64; 3] { std::array::from_fn(|c| mesh.coords[n][c] + at.u[3 * n + c]) };
        let row = |n: usize| pass.nodes.binary_search(&n).ok();
        let mut points = Vec::new();
        let (mut phi, mut shape) = (Vec::new(), Vec::new());
        for &face in &pass.secondary {
            let kind = mesh.face_type(face);
            let nodes = mesh.face_nodes(face);
            let Ok(carriers) = traction_nodes(kind, scheme) else {
                continue;
            };
            let p: Vec<f64> = carriers
                .iter()
                .map(|&k| row(nodes[k]).map_or(0.0, |r| fields[r].pressure))
                .collect();
            if p.iter().all(|&v| v <= 0.0) {
                continue;
            }
            let x: Vec<[f64; 3]> = nodes.iter().map(|&n| current(n)).collect();
            shape.resize(kind.num_nodes(), 0.0);
            for (s, seg) in sub_segments(kind).iter().enumerate() {
                let rule = seg.linear_kind().quadrature(HERTZ_QUADRATURE_DEGREE);
                for (local, w) in rule.points.iter().zip(&rule.weights) {
                    let xi = seg.to_parent(*local);
                    traction_shape(kind, scheme, s, xi, &mut phi);
                    kind.shape(xi, &mut shape);
                    let (_, jac) = crate::fe::face_normal(kind, &x, xi);
                    let at: [f64; 3] = std::array::from_fn(|c| {
                        shape.iter().zip(&x).map(|(n, xa)| n * xa[c]).sum::<f64>()
                    });
                    points.push(PressurePoint {
                        r2: at[0] * at[0] + at[1] * at[1],
                        pressure: phi.iter().zip(&p).map(|(f, v)| f * v).sum(),
                        weight: w * seg.parent_jacobian() * jac,
                    });
                }
            }
        }
        points
    }
}
