//! The tangent block of one traction node (module docs, "Consistent tangent"): its slots
//! (the nodes it couples), its forces, and the derivative of its forces with respect to every
//! slot's position.

use crate::contact::law::FrictionResult;
use crate::contact::normals::NodalNormals;

use super::coverage::FullIntegral;
use super::evaluate::{EvalContext, PairData};
use super::pass::ContactPass;

/// The forces and (optionally) tangent block of one node, in local slot numbering.
pub(crate) struct NodeBlock {
    /// Global nodes of the slots.
    pub(crate) slots: Vec<usize>,
    /// Force on each slot dof (`3 slot + c`).
    pub(crate) force: Vec<f64>,
    /// Tangent, row-major `3m x 3m` (empty when not wanted).
    pub(crate) tangent: Vec<f64>,
}

/// Values at one node that the tangent needs.
pub(crate) struct Linearization<'a> {
    pub(crate) nu: [f64; 3],
    pub(crate) gap: [f64; 3],
    pub(crate) area: f64,
    pub(crate) gh: f64,
    pub(crate) p: f64,
    pub(crate) dp_dgh: f64,
    /// The full integral when the penalties carry the coverage scale `s = a_full / a`, whose
    /// derivative `ds / s = d a_full / a_full - da / a` enters `d (eps gh)` and `d (eps_t dsh)`.
    pub(crate) coverage: Option<&'a FullIntegral>,
    /// A fading node ([`super::coverage_fade`]): `r`, `dr/dc` and the traction before the factor,
    /// `t`; the force is `r t`, and `d (r t) = r dt + t dr`, `dc = -c ds / s`.
    pub(crate) fade: Option<(f64, f64, [f64; 3])>,
    pub(crate) dsh: [f64; 3],
    /// The return map's result and derivatives (friction only).
    pub(crate) friction: Option<&'a FrictionResult>,
    /// The slip is measured (the node had an overlap at the last converged step); otherwise
    /// it is the constant zero.
    pub(crate) slip_history: bool,
}

/// Local numbering of the nodes one traction node couples, with its force and tangent.
pub(crate) struct Slots {
    pub(crate) nodes: Vec<usize>,
    pub(crate) force: Vec<f64>,
    pub(crate) tangent: Vec<f64>,
}

impl Slots {
    /// Slots for every node of the pairs of the node and of its normal's stencil.
    pub(crate) fn new(
        pass: &ContactPass,
        normals: &NodalNormals,
        node: usize,
        terms: &[(&PairData, usize)],
    ) -> Slots {
        let mut nodes: Vec<usize> = normals.derivative(node).iter().map(|d| d.0).collect();
        for &(pair, _) in terms {
            nodes.extend(&pass.sec_faces[pair.s].nodes);
            nodes.extend(&pass.pri_faces[pair.m].nodes);
        }
        nodes.sort_unstable();
        nodes.dedup();
        let n = 3 * nodes.len();
        Slots {
            nodes,
            force: vec![0.0; n],
            tangent: Vec::new(),
        }
    }

    /// Adds slots for `nodes` (before any force or tangent is added).
    pub(crate) fn include(&mut self, nodes: impl Iterator<Item = usize>) {
        self.nodes.extend(nodes);
        self.nodes.sort_unstable();
        self.nodes.dedup();
        self.force = vec![0.0; 3 * self.nodes.len()];
    }

    pub(crate) fn slot(&self, node: usize) -> usize {
        self.nodes
            .binary_search(&node)
            .expect("contact: node outside its own stencil")
    }

    /// Column of each pair-local input dof (secondary face nodes, then primary).
    pub(crate) fn pair_columns(&self, pass: &ContactPass, pair: &PairData) -> Vec<usize> {
        pass.sec_faces[pair.s]
            .nodes
            .iter()
            .chain(&pass.pri_faces[pair.m].nodes)
            .flat_map(|&n| {
                let s = self.slot(n);
                (0..3).map(move |c| 3 * s + c)
            })
            .collect()
    }

    /// Residual terms: `F_B += n1_AB t`, `F_C -= n2_AC t` (the residual is internal minus
    /// external force, and the secondary node receives `-n1_AB t`).
    pub(crate) fn add_forces(
        &mut self,
        pass: &ContactPass,
        terms: &[(&PairData, usize)],
        t: [f64; 3],
    ) {
        for &(pair, k) in terms {
            let w = &pair.w;
            for (b, &n) in pass.sec_faces[pair.s].nodes.iter().enumerate() {
                let v = w.n1[k * w.sec_nodes + b];
                let s = self.slot(n);
                for (f, tc) in self.force[3 * s..3 * s + 3].iter_mut().zip(t) {
                    *f += v * tc;
                }
            }
            for (cn, &n) in pass.pri_faces[pair.m].nodes.iter().enumerate() {
                let v = w.n2[k * w.pri_nodes + cn];
                let s = self.slot(n);
                for (f, tc) in self.force[3 * s..3 * s + 3].iter_mut().zip(t) {
                    *f -= v * tc;
                }
            }
        }
    }

    /// The tangent block (module docs, "Consistent tangent"), of the node `node` with the
    /// pairs `terms`, the values `lin` and the applied traction `t`.
    pub(crate) fn add_tangent(
        &mut self,
        evaluated: (&ContactPass, &EvalContext, &NodalNormals),
        node: usize,
        terms: &[(&PairData, usize)],
        lin: &Linearization,
        t: [f64; 3],
    ) {
        let (pass, ctx, normals) = evaluated;
        let d = self.differentials(pass, ctx, normals, node, terms, lin.friction.is_some());
        let ds_over_s = self.scale_differential(lin, &d.da);
        let dp = pressure_differential(lin, &d, &ds_over_s);
        let mut dt = traction_differential(lin, &d, &dp, &ds_over_s);
        // A fading node: d (r t) = r dt + t (dr/dc) dc, with dc / c = -ds / s.
        if let Some((r, dr_dc, t_full)) = lin.fade {
            let c = lin.coverage.map_or(1.0, |full| lin.area / full.value);
            for (row, ti) in dt.iter_mut().zip(t_full) {
                for (v, dlog_s) in row.iter_mut().zip(&ds_over_s) {
                    *v = r * *v - ti * dr_dc * c * dlog_s;
                }
            }
        }
        self.add_force_differentials(pass, terms, &d.columns, &dt, t);
    }

    /// The differentials of the node's kinematics over its slots: `d a`, `d g`, `d gt`
    /// (friction only) and `d nu`, with each pair's columns.
    fn differentials(
        &self,
        pass: &ContactPass,
        ctx: &EvalContext,
        normals: &NodalNormals,
        node: usize,
        terms: &[(&PairData, usize)],
        friction: bool,
    ) -> Differentials {
        let n = 3 * self.nodes.len();
        let mut d = Differentials {
            da: vec![0.0; n],
            dg: vec![vec![0.0; n]; 3],
            dgt: vec![vec![0.0; n]; 3],
            dnu: vec![vec![0.0; n]; 3],
            columns: Vec::with_capacity(terms.len()),
        };
        for &(b, m) in normals.derivative(node) {
            let s = self.slot(b);
            for (row, mi) in d.dnu.iter_mut().zip(m) {
                for (j, v) in mi.iter().enumerate() {
                    row[3 * s + j] += v;
                }
            }
        }
        for &(pair, k) in terms {
            let w = &pair.w;
            let cols = self.pair_columns(pass, pair);
            let nd = w.ndof();
            for (b, &nb) in pass.sec_faces[pair.s].nodes.iter().enumerate() {
                let r = k * w.sec_nodes + b;
                let (v, dv) = (w.n1[r], &w.dn1[r * nd..(r + 1) * nd]);
                let s = self.slot(nb);
                for (j, &col) in cols.iter().enumerate() {
                    d.da[col] += dv[j];
                    for i in 0..3 {
                        d.dg[i][col] += dv[j] * ctx.x[nb][i];
                        if friction {
                            d.dgt[i][col] += dv[j] * ctx.x_old[nb][i];
                        }
                    }
                }
                for i in 0..3 {
                    d.dg[i][3 * s + i] += v;
                }
            }
            for (cn, &nc) in pass.pri_faces[pair.m].nodes.iter().enumerate() {
                let r = k * w.pri_nodes + cn;
                let (v, dv) = (w.n2[r], &w.dn2[r * nd..(r + 1) * nd]);
                let s = self.slot(nc);
                for (j, &col) in cols.iter().enumerate() {
                    for i in 0..3 {
                        d.dg[i][col] -= dv[j] * ctx.x[nc][i];
                        if friction {
                            d.dgt[i][col] -= dv[j] * ctx.x_old[nc][i];
                        }
                    }
                }
                for i in 0..3 {
                    d.dg[i][3 * s + i] -= v;
                }
            }
            d.columns.push(cols);
        }
        d
    }

    /// The coverage scale's `ds / s` (zero without it): the law's inputs are in effect `s gh`
    /// and `s dsh`, and `dp_dgh`, `dt_T/d dsh` already hold `s`.
    fn scale_differential(&self, lin: &Linearization, da: &[f64]) -> Vec<f64> {
        let mut ds_over_s = vec![0.0; da.len()];
        if let Some(full) = lin.coverage {
            for &(b, g) in &full.gradient {
                let s = self.slot(b);
                for c in 0..3 {
                    ds_over_s[3 * s + c] += g[c] / full.value;
                }
            }
            for (d, a) in ds_over_s.iter_mut().zip(da) {
                *d -= a / lin.area;
            }
        }
        ds_over_s
    }

    /// `d F_B = d n1_AB t + n1_AB d t`, `d F_C = -(d n2_AC t + n2_AC d t)` into the block.
    fn add_force_differentials(
        &mut self,
        pass: &ContactPass,
        terms: &[(&PairData, usize)],
        columns: &[Vec<usize>],
        dt: &[Vec<f64>],
        t: [f64; 3],
    ) {
        let n = 3 * self.nodes.len();
        self.tangent = vec![0.0; n * n];
        for (&(pair, k), cols) in terms.iter().zip(columns) {
            let w = &pair.w;
            let nd = w.ndof();
            let sides = [
                (
                    &pass.sec_faces[pair.s].nodes,
                    &w.n1,
                    &w.dn1,
                    w.sec_nodes,
                    1.0,
                ),
                (
                    &pass.pri_faces[pair.m].nodes,
                    &w.n2,
                    &w.dn2,
                    w.pri_nodes,
                    -1.0,
                ),
            ];
            for (nodes, vals, ders, count, sign) in sides {
                for (b, &nb) in nodes.iter().enumerate() {
                    let r = k * count + b;
                    let (v, dv) = (vals[r], &ders[r * nd..(r + 1) * nd]);
                    let s = self.slot(nb);
                    for i in 0..3 {
                        let row = &mut self.tangent[(3 * s + i) * n..(3 * s + i + 1) * n];
                        for (j, &col) in cols.iter().enumerate() {
                            row[col] += sign * dv[j] * t[i];
                        }
                        for (x, d) in row.iter_mut().zip(&dt[i]) {
                            *x += sign * v * d;
                        }
                    }
                }
            }
        }
    }

    pub(crate) fn into_block(self) -> NodeBlock {
        NodeBlock {
            slots: self.nodes,
            force: self.force,
            tangent: self.tangent,
        }
    }
}

/// The differentials of a node's kinematics: rows over its slot dofs.
struct Differentials {
    da: Vec<f64>,
    dg: Vec<Vec<f64>>,
    /// `d gt`, the current weights' differential applied to the old positions (friction).
    dgt: Vec<Vec<f64>>,
    dnu: Vec<Vec<f64>>,
    /// The slot dof of each pair-local input dof, per pair.
    columns: Vec<Vec<usize>>,
}

/// `d p = (dp/dgh) (d gh + gh d s / s)`, `d gh = (nu . d g + g . d nu) / a - gh d a / a`.
fn pressure_differential(lin: &Linearization, d: &Differentials, ds_over_s: &[f64]) -> Vec<f64> {
    (0..d.da.len())
        .map(|col| {
            let dgh = ((0..3)
                .map(|i| lin.nu[i] * d.dg[i][col] + lin.gap[i] * d.dnu[i][col])
                .sum::<f64>()
                - lin.gh * d.da[col])
                / lin.area;
            lin.dp_dgh * (dgh + lin.gh * ds_over_s[col])
        })
        .collect()
}

/// `d t = nu d p + p d nu + d t_T`, with `d t_T` of the return map (friction only).
fn traction_differential(
    lin: &Linearization,
    d: &Differentials,
    dp: &[f64],
    ds_over_s: &[f64],
) -> Vec<Vec<f64>> {
    let n = dp.len();
    let mut dt: Vec<Vec<f64>> = (0..3)
        .map(|i| {
            (0..n)
                .map(|col| lin.nu[i] * dp[col] + lin.p * d.dnu[i][col])
                .collect()
        })
        .collect();
    let Some(fr) = lin.friction else {
        return dt;
    };
    for col in 0..n {
        let ddsh: [f64; 3] = if lin.slip_history {
            std::array::from_fn(|i| {
                -(d.dgt[i][col] + lin.dsh[i] * d.da[col]) / lin.area + lin.dsh[i] * ds_over_s[col]
            })
        } else {
            [0.0; 3]
        };
        for (i, row) in dt.iter_mut().enumerate() {
            let mut v = fr.d_p[i] * dp[col];
            for (j, dd) in ddsh.iter().enumerate() {
                v += fr.d_dsh[i][j] * dd + fr.d_nu[i][j] * d.dnu[j][col];
            }
            row[col] += v;
        }
    }
    dt
}
