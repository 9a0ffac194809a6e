//! One evaluation of the contact interfaces at a state: the weights of the candidate pairs,
//! each held traction node's kinematics and law, and its block of forces (and tangent).

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;

use crate::case::ContactMethod;
use crate::contact::law::{
    bilateral_pressure, normal_pressure_touching, tangential_law, LawParams,
};
use crate::contact::mortar::{
    integrate_pair, integrate_pair_linearized, traction_node_count, FaceGeom, IntegrationOptions,
    LinearizedWeights, PalletSplit, RejectStats, TractionScheme,
};
use crate::contact::normals::NodalNormals;
use crate::error::Result;
use crate::model::State;
use crate::vec3::{dot, tangential};

use super::coverage::{
    coverage_fade, coverage_scale, FullIntegral, TractionIntegrals, MIN_COVERAGE,
};
use super::fields::{status_code, NodeFields};
use super::pass::{ContactPass, FaceData};
use super::tangent::{Linearization, NodeBlock, Slots};
use super::{ContactInterface, ContactInterfaces, ContactTimings, EVAL_MARGIN, TOUCH_TOLERANCE};

/// The values-only pairs of a pass at one set of positions, with the search's candidates and
/// the pairs' statistics.
#[derive(Clone, Debug)]
pub(crate) struct ValuesAt {
    /// Positions of the pass's `surface_nodes`, as bits (so that `-0.0` and NaN compare as
    /// what they are).
    pub(crate) positions: Vec<[u64; 3]>,
    /// The candidate primary faces of each face this rank integrates ([`ContactPass::candidates`]).
    pub(crate) candidates: Vec<(usize, Vec<usize>)>,
    pub(crate) pairs: Rc<Vec<PairData>>,
    pub(crate) stats: RejectStats,
}

/// The weights of one face pair of one evaluation.
#[derive(Clone, Debug)]
pub(crate) struct PairData {
    /// Index of the secondary face in the pass.
    pub(crate) s: usize,
    /// Index of the primary face.
    pub(crate) m: usize,
    /// Values, and derivatives when the tangent is wanted.
    pub(crate) w: LinearizedWeights,
}

/// Traction nodes (indices into a pass's nodes) with their pairs and their traction index in
/// each pair's secondary face ([`ContactPass::pairs_by_node`]).
pub(crate) type ByNode<'p> = BTreeMap<usize, Vec<(&'p PairData, usize)>>;

/// The secondary faces whose pairs a tangent evaluation linearizes.
#[derive(Clone, Copy)]
pub(crate) enum Linearize {
    /// The faces carrying a node the law presses ([`ContactPass::pressed_faces`]): the others'
    /// derivatives would go unused.
    PressedFaces,
    /// Every face of a held node (tests: the reference for [`Linearize::PressedFaces`]).
    #[cfg_attr(not(test), allow(dead_code))]
    EveryFace,
}

impl ContactInterface {
    /// What an evaluation of this interface needs at positions `x` (old positions `x_old`).
    pub(crate) fn context<'a>(
        &self,
        modes: LawModes,
        x: &'a [[f64; 3]],
        x_old: &'a [[f64; 3]],
    ) -> EvalContext<'a> {
        EvalContext {
            iface_mu: self.mu,
            modes,
            scheme: self.scheme,
            degree: self.quadrature_degree,
            pallets: self.pallets,
            scale: self.penalty_scale,
            x,
            x_old,
            face_integrals: RefCell::new(BTreeMap::new()),
        }
    }
}

impl ContactInterfaces {
    /// Evaluates every pass at `at` and hands each held node's block to `sink`. Returns why
    /// the state cannot be evaluated (a degenerate normal, a non-finite value), if so.
    pub(crate) fn assemble(
        &self,
        at: &State,
        tangent: bool,
        mut sink: impl FnMut(&NodeBlock) -> Result<()>,
    ) -> Result<Option<String>> {
        self.assemble_linearizing(at, tangent, Linearize::PressedFaces, &mut sink)
    }

    /// [`Self::assemble`], with a tangent that linearizes the pairs of the faces `linearize`
    /// says.
    pub(crate) fn assemble_linearizing(
        &self,
        at: &State,
        tangent: bool,
        linearize: Linearize,
        sink: &mut dyn FnMut(&NodeBlock) -> Result<()>,
    ) -> Result<Option<String>> {
        let x = at.positions();
        let evaluation = Evaluation {
            tangent,
            linearize,
            timed: &self.timings,
        };
        for iface in &self.interfaces {
            let mut stats = RejectStats::default();
            // A pass this rank holds no node of costs it nothing (not even its normals).
            for pass in iface.passes.iter().filter(|p| !p.held.is_empty()) {
                let ctx = iface.context(self.modes.get(), &x, &self.x_old);
                let failure = match pass.method {
                    ContactMethod::NodeOnSegment => {
                        pass.node_on_segment_blocks(&ctx, &evaluation, sink)?
                    }
                    ContactMethod::Mortar => {
                        pass.mortar_blocks(&ctx, &evaluation, &mut stats, sink)?
                    }
                };
                if let Some(why) = failure {
                    return Ok(Some(format!("interface '{}': {why}", iface.name)));
                }
            }
            *iface.stats.borrow_mut() = stats;
        }
        Ok(None)
    }
}

/// What an evaluation computes, beside the state.
pub(crate) struct Evaluation<'a> {
    /// The tangent blocks too (else the forces only).
    pub(crate) tangent: bool,
    pub(crate) linearize: Linearize,
    pub(crate) timed: &'a ContactTimings,
}

/// Why a mortar evaluation stopped on values that are not finite.
const NON_FINITE: &str = "non-finite values in the mortar integration";

impl ContactPass {
    /// The blocks of the held nodes of a mortar pass (module docs, "Consistent tangent");
    /// why the state cannot be evaluated, if so. The pair statistics of the residual's weights
    /// go to `stats`.
    fn mortar_blocks(
        &self,
        ctx: &EvalContext,
        evaluation: &Evaluation,
        stats: &mut RejectStats,
        sink: &mut dyn FnMut(&NodeBlock) -> Result<()>,
    ) -> Result<Option<String>> {
        let timed = evaluation.timed;
        let normals = match timed.integration.time(|| self.normals(ctx.x)) {
            Ok(n) => n,
            Err(e) => return Ok(Some(e)),
        };
        let values = self.values_at(ctx, Some(timed), stats);
        if stats.non_finite > 0 {
            return Ok(Some(NON_FINITE.into()));
        }
        let (measured, kinematics) = timed.assembly.time(|| self.measured(ctx, &values));
        // The tangent's weights with their derivatives, of the faces of pressed nodes only;
        // the law's inputs (area, gap, slip) still come from the residual's weights, so that
        // every branch of the law (open or pressed, stick or slip, which the cone's tie band
        // decides to 1e-10) is the one the residual took (module docs, "Consistent tangent").
        let linearized = if evaluation.tangent {
            match self.linearized_pairs(ctx, evaluation, &normals, &kinematics) {
                Some(pairs) => Some(pairs),
                None => return Ok(Some(NON_FINITE.into())),
            }
        } else {
            None
        };
        timed.assembly.time(|| -> Result<()> {
            let differentiated = linearized
                .as_ref()
                .map(|pairs| self.pairs_by_node(pairs, &self.held));
            let by_node = differentiated.as_ref().unwrap_or(&measured);
            let mut states = Vec::new();
            for (&a, terms) in by_node {
                // A node without residual weights has no force to linearize.
                let Some(kin) = kinematics.get(&a) else {
                    continue;
                };
                let (block, fields) =
                    self.node_block(ctx, &normals, a, kin, terms, evaluation.tangent);
                if evaluation.tangent {
                    states.push((a, fields.status));
                }
                if let Some(block) = block {
                    sink(&block)?;
                }
            }
            if evaluation.tangent {
                self.record_states(states);
            }
            Ok(())
        })?;
        Ok(None)
    }

    /// The pairs of the faces a tangent linearizes, with the derivatives of their weights;
    /// `None` when a derivative is not finite where the values are. The pairs are counted by
    /// the residual's weights; the derivatives of the faces not linearized are neither computed
    /// nor checked.
    fn linearized_pairs(
        &self,
        ctx: &EvalContext,
        evaluation: &Evaluation,
        normals: &NodalNormals,
        kinematics: &BTreeMap<usize, Kinematics>,
    ) -> Option<Vec<PairData>> {
        let timed = evaluation.timed;
        let faces = match evaluation.linearize {
            Linearize::PressedFaces => timed
                .assembly
                .time(|| self.pressed_faces(ctx, normals, kinematics)),
            Linearize::EveryFace => self.local_faces.clone(),
        };
        // (No pressed node: no search either.)
        let candidates = if faces.is_empty() {
            Vec::new()
        } else {
            timed
                .search
                .time(|| self.candidates(ctx.x, &faces, EVAL_MARGIN))
        };
        let mut own = RejectStats::default();
        let integrate = || self.integrate(ctx, &candidates, true, &mut own);
        let pairs = timed.integration.time(integrate);
        (own.non_finite == 0).then_some(pairs)
    }
}

/// How an evaluation's law departs from the nodal law of the module docs (both off: the law
/// itself).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LawModes {
    /// The stick predictor: pressed nodes stick whatever their cone.
    pub(crate) stick_all: bool,
    /// The bilateral iteration: a node with a normal multiplier is held bilaterally
    /// ([`crate::contact::law::bilateral_pressure`]).
    pub(crate) bilateral: bool,
}

/// What one evaluation of a pass needs besides the pass.
pub(crate) struct EvalContext<'a> {
    pub(crate) iface_mu: f64,
    pub(crate) modes: LawModes,
    pub(crate) scheme: TractionScheme,
    pub(crate) degree: Option<usize>,
    pub(crate) pallets: PalletSplit,
    pub(crate) scale: f64,
    /// Current and last converged positions of every node.
    pub(crate) x: &'a [[f64; 3]],
    pub(crate) x_old: &'a [[f64; 3]],
    /// The traction integrals of the secondary faces at `x`, computed once per face for the
    /// nodes they carry (with the gradient if it was asked for).
    pub(crate) face_integrals: RefCell<BTreeMap<usize, Rc<TractionIntegrals>>>,
}

/// Sums of one node's weights.
pub(crate) struct Kinematics {
    pub(crate) area: f64,
    pub(crate) gap: [f64; 3],
    /// The current weights applied to the old positions (friction only).
    pub(crate) gap_at_old: [f64; 3],
}

impl ContactPass {
    /// The candidate pairs of this rank's faces integrated at positions `ctx.x`, values only,
    /// with their statistics added to `stats`; the search and the integration are timed in
    /// `timed` when given.
    ///
    /// The weights are a function of the positions alone, and a state is evaluated several
    /// times: by a residual and the tangent that follows it at the same point (the law's
    /// inputs; module docs, "Consistent tangent"), and at a converged state by the Uzawa
    /// update, the reactions, the output and the commit of the step. So the last result is
    /// kept and returned again while the pass's nodes sit at the same positions, bit for bit;
    /// the search's candidates are kept with it for the matrix pattern's check before a tangent
    /// (`holds_pairs_at`).
    pub(crate) fn values_at(
        &self,
        ctx: &EvalContext,
        timed: Option<&ContactTimings>,
        stats: &mut RejectStats,
    ) -> Rc<Vec<PairData>> {
        let positions = self.surface_positions(ctx.x);
        if let Some(last) = self.last_values.borrow().as_ref() {
            if last.positions == positions {
                stats.add(&last.stats);
                return Rc::clone(&last.pairs);
            }
        }
        let search = || self.candidates(ctx.x, &self.local_faces, EVAL_MARGIN);
        let candidates = match timed {
            Some(t) => t.search.time(search),
            None => search(),
        };
        let mut own = RejectStats::default();
        let mut integrate = || self.integrate(ctx, &candidates, false, &mut own);
        let pairs = Rc::new(match timed {
            Some(t) => t.integration.time(integrate),
            None => integrate(),
        });
        stats.add(&own);
        *self.last_values.borrow_mut() = Some(ValuesAt {
            positions,
            candidates,
            pairs: Rc::clone(&pairs),
            stats: own,
        });
        pairs
    }

    /// The positions `x` of the pass's `surface_nodes`, as bits: the key of `last_values`.
    pub(crate) fn surface_positions(&self, x: &[[f64; 3]]) -> Vec<[u64; 3]> {
        self.surface_nodes
            .iter()
            .map(|&n| x[n].map(f64::to_bits))
            .collect()
    }

    /// Integrates every candidate pair (secondary face, its candidate primary faces; see
    /// [`ContactPass::candidates`]), in canonical order; the pair statistics of the faces this
    /// rank tallies go to `stats` (non-finite values from every face).
    pub(crate) fn integrate(
        &self,
        ctx: &EvalContext,
        candidates: &[(usize, Vec<usize>)],
        tangent: bool,
        stats: &mut RejectStats,
    ) -> Vec<PairData> {
        let mut out = Vec::new();
        for &(s, ref ms) in candidates {
            let sf = &self.sec_faces[s];
            let sx: Vec<[f64; 3]> = sf.nodes.iter().map(|&n| ctx.x[n]).collect();
            for &m in ms {
                let pf = &self.pri_faces[m];
                let px: Vec<[f64; 3]> = pf.nodes.iter().map(|&n| ctx.x[n]).collect();
                let mut opts = IntegrationOptions::for_faces(ctx.scheme, sf.kind, pf.kind);
                if let Some(d) = ctx.degree {
                    opts.degree = d;
                }
                opts.pallets = ctx.pallets;
                let (sg, pg) = (
                    FaceGeom {
                        kind: sf.kind,
                        x: &sx,
                    },
                    FaceGeom {
                        kind: pf.kind,
                        x: &px,
                    },
                );
                let mut face_stats = RejectStats::default();
                let w = if tangent {
                    integrate_pair_linearized(&sg, &pg, &opts, &mut face_stats)
                } else {
                    let values = integrate_pair(&sg, &pg, &opts, &mut face_stats);
                    dense_values(&values, sf, pf, ctx.scheme)
                };
                if self.tallied[s] {
                    stats.add(&face_stats);
                } else {
                    // Counted by the rank that tallies the face; a failure still counts here.
                    stats.non_finite += face_stats.non_finite;
                }
                if w.area > 0.0 {
                    out.push(PairData { s, m, w });
                }
            }
        }
        out
    }

    /// The pairs carrying each of `nodes` (indices into `self.nodes`), with the traction index
    /// `k` of the node in the pair's secondary face.
    pub(crate) fn pairs_by_node<'p>(&self, pairs: &'p [PairData], nodes: &[usize]) -> ByNode<'p> {
        let wanted: std::collections::BTreeSet<usize> = nodes.iter().copied().collect();
        let mut out: BTreeMap<usize, Vec<(&PairData, usize)>> = BTreeMap::new();
        for pair in pairs {
            for (k, &a) in self.carriers[pair.s].iter().enumerate() {
                if wanted.contains(&a) {
                    out.entry(a).or_default().push((pair, k));
                }
            }
        }
        out
    }

    /// The held nodes' pairs in the residual's weights `values` ([`Self::pairs_by_node`]) and
    /// their [`Self::kinematics`]: the law's inputs of a residual and of a tangent.
    pub(crate) fn measured<'p>(
        &self,
        ctx: &EvalContext,
        values: &'p [PairData],
    ) -> (ByNode<'p>, BTreeMap<usize, Kinematics>) {
        let measured = self.pairs_by_node(values, &self.held);
        let kinematics = measured
            .iter()
            .map(|(&a, terms)| (a, self.kinematics(ctx, terms)))
            .collect();
        (measured, kinematics)
    }

    /// `a_A`, `g_A` and (friction) the current weights on the old positions.
    pub(crate) fn kinematics(&self, ctx: &EvalContext, terms: &[(&PairData, usize)]) -> Kinematics {
        let (area, gap) = self.weighted_gap(terms, ctx.x);
        let gap_at_old = if ctx.iface_mu > 0.0 {
            self.weighted_gap(terms, ctx.x_old).1
        } else {
            [0.0; 3]
        };
        Kinematics {
            area,
            gap,
            gap_at_old,
        }
    }

    /// `a_A = sum_B n1_AB` and the weighted gap `sum_B n1_AB y_B - sum_C n2_AC y_C` of the
    /// node's `terms` (its pairs and its index in each) at the node values `y`.
    pub(crate) fn weighted_gap(
        &self,
        terms: &[(&PairData, usize)],
        y: &[[f64; 3]],
    ) -> (f64, [f64; 3]) {
        let (mut area, mut gap) = (0.0, [0.0; 3]);
        for &(pair, t) in terms {
            let w = &pair.w;
            let (sf, pf) = (&self.sec_faces[pair.s], &self.pri_faces[pair.m]);
            for (b, &n) in sf.nodes.iter().enumerate() {
                let v = w.n1[t * w.sec_nodes + b];
                area += v;
                for c in 0..3 {
                    gap[c] += v * y[n][c];
                }
            }
            for (cn, &n) in pf.nodes.iter().enumerate() {
                let v = w.n2[t * w.pri_nodes + cn];
                for c in 0..3 {
                    gap[c] -= v * y[n][c];
                }
            }
        }
        (area, gap)
    }

    /// The normal part of the law at traction node `a` (normal `nu`) from its kinematics
    /// `kin`: `None` when the node is covered less than [`MIN_COVERAGE`] and carries no
    /// traction. Shared by [`Self::node_block`] and [`Self::pressed_faces`], so that both
    /// decide alike which nodes are pressed.
    pub(crate) fn normal_law(
        &self,
        ctx: &EvalContext,
        a: usize,
        nu: [f64; 3],
        kin: &Kinematics,
    ) -> Option<NormalLaw> {
        let st = &self.state[a];
        let full = self.full_integral(ctx, a, false);
        if kin.area < MIN_COVERAGE * full.value {
            return None;
        }
        let gh = dot(nu, kin.gap) / kin.area;
        let coverage = coverage_scale(kin.area, full.value);
        let prm = self.law_params(st, ctx.iface_mu, ctx.scale, coverage.unwrap_or(1.0));
        let (p, dp_dgh) = if self.held_pressed(ctx.modes, a) {
            bilateral_pressure(st.history.lambda_n, prm.eps_n, gh)
        } else {
            normal_pressure_touching(st.history.lambda_n, prm.eps_n, gh, TOUCH_TOLERANCE * st.h)
        };
        Some(NormalLaw {
            full,
            gh,
            coverage,
            prm,
            p,
            dp_dgh,
        })
    }

    /// Whether the law holds node `a` on its pressed branch whatever its gap
    /// ([`bilateral_pressure`]): the bilateral iteration's nodes with a multiplier, and those a
    /// Newton update is solved again with (`ContactInterfaces::hold_closing`).
    pub(crate) fn held_pressed(&self, modes: LawModes, a: usize) -> bool {
        (modes.bilateral && self.state[a].history.lambda_n > 0.0)
            || self.closing_held.borrow().contains(&a)
    }

    /// The secondary faces (ascending) carrying a node of `kinematics` (held nodes and their
    /// [`Self::kinematics`]) that the law presses (`dp/dgh != 0`: in contact or within the
    /// touching band). Only these faces' pairs are linearized: an open node has no tangent
    /// ([`Self::node_block`] returns none), so the derivatives of a pair whose secondary face
    /// carries no pressed node would go unused. Where the contact zone is smaller than the
    /// surfaces the search pairs (a Hertz contact), this skips most of the linearized kernel.
    pub(crate) fn pressed_faces(
        &self,
        ctx: &EvalContext,
        normals: &NodalNormals,
        kinematics: &BTreeMap<usize, Kinematics>,
    ) -> Vec<usize> {
        let mut faces = std::collections::BTreeSet::new();
        for (&a, kin) in kinematics {
            let nu = normals.normal(self.nodes[a]).unwrap_or_default();
            let pressed = self
                .normal_law(ctx, a, nu, kin)
                .is_some_and(|law| law.dp_dgh != 0.0);
            if pressed {
                faces.extend(self.node_faces[a].iter().map(|&(f, _)| f));
            }
        }
        faces.into_iter().collect()
    }

    /// Forces (and tangent) of traction node `a` from its pairs `terms`, and its fields.
    /// `None` when the node carries no traction. `kin` is the node's [`Self::kinematics`]:
    /// of `terms` for a residual, of the residual's weights for a tangent (see
    /// [`ContactInterfaces::assemble_linearizing`]).
    pub(crate) fn node_block(
        &self,
        ctx: &EvalContext,
        normals: &NodalNormals,
        a: usize,
        kin: &Kinematics,
        terms: &[(&PairData, usize)],
        tangent: bool,
    ) -> (Option<NodeBlock>, NodeFields) {
        let st = &self.state[a];
        let node = self.nodes[a];
        let nu = normals.normal(node).unwrap_or_default();
        let mut fields = NodeFields {
            normal: nu,
            ..Default::default()
        };
        let Some(NormalLaw {
            mut full,
            gh,
            coverage,
            prm,
            p,
            dp_dgh,
        }) = self.normal_law(ctx, a, nu, kin)
        else {
            return (None, fields);
        };
        let area = kin.area;
        let (fade, dfade) = coverage_fade(area / full.value);
        if coverage.is_some() && tangent {
            full = self.full_integral(ctx, a, true);
        }
        let slip_history = ctx.iface_mu > 0.0 && st.gap_old.is_some();
        let dsh = match st.gap_old {
            Some(g_old) if slip_history => {
                std::array::from_fn(|c| (g_old[c] - kin.gap_at_old[c]) / area)
            }
            _ => [0.0; 3],
        };
        let band = (TOUCH_TOLERANCE * st.h, ctx.modes.stick_all);
        let fr = tangential_law(&st.history, &prm, nu, (p, dp_dgh), dsh, band);
        let t: [f64; 3] = std::array::from_fn(|c| p * nu[c] + fr.traction[c]);
        fields = NodeFields {
            area,
            full_area: full.value,
            gap: gh,
            pressure: fade * p,
            slip: tangential(dsh, nu),
            traction_t: fr.traction.map(|v| fade * v),
            law_traction_t: fr.traction,
            normal: nu,
            status: status_code(fr.status),
            weighted_gap: kin.gap,
            segment: None,
        };
        if dp_dgh == 0.0 {
            return (None, fields);
        }
        let mut block = Slots::new(self, normals, node, terms);
        if coverage.is_some() && tangent {
            block.include(full.gradient.iter().map(|g| g.0));
        }
        let applied = t.map(|v| fade * v);
        block.add_forces(self, terms, applied);
        if tangent {
            // A node the bilateral iteration holds in tension (the only way to `p < 0`)
            // linearizes its tension's geometric terms as zero (module docs, "Bilateral
            // iteration"); the traction the tangent carries is then its friction's alone.
            let (p, t) = if p < 0.0 { (0.0, fr.traction) } else { (p, t) };
            let carried = t.map(|v| fade * v);
            let lin = Linearization {
                nu,
                gap: kin.gap,
                area,
                gh,
                p,
                dp_dgh,
                coverage: coverage.is_some().then_some(&full),
                fade: (fade < 1.0).then_some((fade, dfade, t)),
                dsh,
                friction: (ctx.iface_mu > 0.0).then_some(&fr),
                slip_history,
            };
            block.add_tangent((self, ctx, normals), node, terms, &lin, carried);
        }
        (Some(block.into_block()), fields)
    }
}

/// The normal part of the law at one node ([`ContactPass::normal_law`]).
pub(crate) struct NormalLaw {
    /// The node's full integral (its value; no gradient).
    pub(crate) full: FullIntegral,
    /// The mean normal gap `nu . g / a`.
    pub(crate) gh: f64,
    /// The node's [`coverage_scale`], when it is partly covered.
    pub(crate) coverage: Option<f64>,
    /// The law's parameters, coverage scale included.
    pub(crate) prm: LawParams,
    /// The normal pressure and its derivative with respect to `gh`.
    pub(crate) p: f64,
    pub(crate) dp_dgh: f64,
}

/// Dense values of a pair's weights in the layout of [`LinearizedWeights`] (no derivatives).
pub(crate) fn dense_values(
    w: &crate::contact::mortar::PairWeights,
    sf: &FaceData,
    pf: &FaceData,
    scheme: TractionScheme,
) -> LinearizedWeights {
    let nt = traction_node_count(sf.kind, scheme);
    let (ns, np) = (sf.kind.num_nodes(), pf.kind.num_nodes());
    let mut out = LinearizedWeights {
        traction_nodes: nt,
        sec_nodes: ns,
        pri_nodes: np,
        n1: vec![0.0; nt * ns],
        n2: vec![0.0; nt * np],
        area: w.area,
        ..Default::default()
    };
    for &(k, b, v) in &w.n1 {
        out.n1[k * ns + b] += v;
    }
    for &(k, c, v) in &w.n2 {
        out.n2[k * np + c] += v;
    }
    out
}
