//! Unit tests of the contact interfaces: Uzawa on partly covered nodes, the pressed faces of
//! a tangent, the coverage fade, the traction integrals, and the dealing of work to ranks.

use super::closing::CLOSING_DEPTH;
use super::coverage::traction_integrals;
use super::deal::{deal_in_strips, node_work, pass_ranks};
use super::evaluate::Linearize;
use super::{coverage_fade, ContactInterfaces, FADE_COVERAGE, MIN_COVERAGE, PENETRATION_REACH};
use crate::case::Scene;
use crate::contact::mortar::RejectStats;
use crate::contact::mortar::TractionScheme;
use crate::dofs::DofMap;
use crate::fe::FaceType;
use crate::model::{NodalForces, State};
use std::collections::BTreeSet;

/// Two Hex8 blocks: the top of the lower one (4 x 4 faces, nodes every 0.25, the secondary
/// side) covered by the upper one from x = 0.45 and y = 0.245 on, 0.01 deep. With bilinear
/// traction functions a node's coverage is the product of its coverages along x and y:
/// along x, the column at 0 has no overlap, the column at 0.25 is 2 % covered, the one at
/// 0.5 68 %, the others wholly; along y, the row at 0 is 0.04 % covered (below
/// [`MIN_COVERAGE`]), the row at 0.25 52 %, the others wholly.
fn partly_covered_blocks() -> Scene {
    scene_of(PARTLY_COVERED)
}

/// The case text of [`partly_covered_blocks`].
pub(crate) const PARTLY_COVERED: &str = r#"
name = "partly_covered"
[[mesh]]
body = "low"
generator = "box"
element = "hex8"
divisions = [4, 4, 1]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 0.5]
[[mesh]]
body = "up"
generator = "box"
element = "hex8"
divisions = [2, 2, 1]
lo = [0.45, 0.245, 0.49]
hi = [1.45, 1.245, 1.0]
[[material]]
body = "low"
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[material]]
body = "up"
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[symmetry]]
set = "low.zmin"
normal = "z"
[[dirichlet]]
set = "up.zmax"
components = ["x", "y", "z"]
value = [0.0, 0.0, 0.0]
[[interface]]
name = "blocks"
kind = "contact"
secondary = "low.zmax"
primary = "up.zmin"
scheme = 2
friction = 0.3
"#;

/// The scene of a case text.
pub(crate) fn scene_of(case: &str) -> Scene {
    // One folder per call: the tests run in parallel threads.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("mortar-covered-{}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("case.toml");
    std::fs::write(&path, case).unwrap();
    let scene = Scene::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    scene
}

/// The contact interfaces of `scene` with every element on rank 0 of 1.
fn on_one_rank(scene: &Scene) -> ContactInterfaces {
    let elements = vec![0; scene.mesh.num_elements()];
    let dofs = DofMap::new(&scene.mesh, elements, 0, 1, &scene.constrained_mask());
    ContactInterfaces::new(scene, &dofs).unwrap()
}

/// The Uzawa bookkeeping of partly covered nodes ([`partly_covered_blocks`]), every node
/// starting with multipliers. One Uzawa update
/// - releases the multipliers of the nodes without traction (no overlap, or below
///   [`MIN_COVERAGE`]), without a violation: they exert no force whatever their multipliers;
/// - leaves the fading nodes out (below [`FADE_COVERAGE`]: no constraint to meet, the
///   multipliers kept);
/// - updates every other node, partly covered or not, and counts its penetration as a
///   violation.
///
/// Closing the step (`commit`, without applying the update) then releases the normal
/// multiplier of the nodes without traction and keeps those of the others.
#[test]
fn uzawa_skips_fading_nodes_and_releases_nodes_without_traction() {
    let scene = partly_covered_blocks();
    let mut contact = on_one_rank(&scene);
    const LAMBDA_N: f64 = 5.0;
    for st in &mut contact.interfaces[0].passes[0].state {
        st.history.lambda_n = LAMBDA_N;
        st.history.lambda_t = [0.5, 0.0, 0.0];
    }
    let u = vec![0.0; 3 * scene.mesh.num_nodes()];
    let at = State {
        scene: &scene,
        u: &u,
        t: 1.0,
    };

    let fields = contact.local_fields(&at, 0, 0);
    let updates = contact.uzawa_updates(&at, 0, 0.0);
    // Nodes without traction, fading, partly covered, wholly covered.
    let mut counts = [0; 4];
    for (a, f) in &fields {
        let update = updates.iter().find(|u| u.pass == 0 && u.node == *a);
        let coverage = f.area / f.full_area;
        if f.area == 0.0 {
            counts[0] += 1;
            let update = update.expect("a node without traction is released");
            let (violation, new) = (update.violation, update.history);
            assert_eq!(violation, 0.0, "node {a}: a release is no violation");
            assert_eq!((new.lambda_n, new.lambda_t), (0.0, [0.0; 3]), "node {a}");
            continue;
        }
        if coverage < FADE_COVERAGE {
            counts[1] += 1;
            assert!(
                update.is_none(),
                "fading node {a} (coverage {coverage}) updated"
            );
            continue;
        }
        counts[if coverage < 1.0 - 1e-9 { 2 } else { 3 }] += 1;
        let update = update.expect("a covered node is updated");
        let (violation, new) = (update.violation, update.history);
        assert!(f.gap > 0.0, "node {a}: gap {}", f.gap);
        assert!(violation > 1.0, "node {a}: violation {violation}");
        assert!(
            new.lambda_n > LAMBDA_N,
            "node {a}: lambda_n {}",
            new.lambda_n
        );
    }
    // Without traction: the column at x = 0 and the rest of the row at y = 0; fading: the
    // rest of the column at x = 0.25; partly covered: the rest of the column at x = 0.5 and
    // of the row at y = 0.25.
    assert_eq!(counts, [9, 4, 6, 6]);

    contact.close_step(&at);
    let pass = &contact.interfaces[0].passes[0];
    for (a, f) in &fields {
        let history = &pass.state[*a].history;
        if f.area == 0.0 {
            assert_eq!(history.lambda_n, 0.0, "node {a} without traction");
            assert_eq!(
                history.traction_t_old, [0.0; 3],
                "node {a} without traction"
            );
        } else {
            assert_eq!(history.lambda_n, LAMBDA_N, "node {a}");
        }
    }
}

/// Aitken's relaxation of the Uzawa updates lives within one step: closing the step and
/// restoring a cut one both forget the factor, the updates and a fallback, so that neither a
/// new step nor a checkpoint (written after a closed step) carries them.
#[test]
fn a_step_starts_its_relaxation_afresh() {
    let scene = partly_covered_blocks();
    let mut contact = on_one_rank(&scene);
    let u = vec![0.0; 3 * scene.mesh.num_nodes()];
    let at = State {
        scene: &scene,
        u: &u,
        t: 1.0,
    };
    let saved = contact.snapshot();
    let under_way = |contact: &mut ContactInterfaces| {
        let relaxation = &mut contact.interfaces[0].relaxation;
        relaxation.omega = 4.0;
        relaxation.previous.insert((0, 3), [1.0, 0.0, 0.0]);
        relaxation.fell_back = true;
    };
    let fresh = |contact: &ContactInterfaces| {
        let relaxation = &contact.interfaces[0].relaxation;
        relaxation.omega == 1.0 && relaxation.previous.is_empty() && !relaxation.fell_back
    };
    under_way(&mut contact);
    contact.close_step(&at);
    assert!(fresh(&contact), "closing a step");
    under_way(&mut contact);
    contact.restore_snapshot(&saved);
    assert!(fresh(&contact), "restoring a cut step");
}

/// A tangent linearizes only the pairs of the faces that carry a pressed node
/// ([`Linearize::PressedFaces`]), and its blocks are bit for bit those of a tangent that
/// linearizes every face, on each rank of 1 and of 2 (strips of held nodes, faces whose
/// nodes two ranks hold): [`partly_covered_blocks`]
/// - tilted: the upper block lifted by `0.06 (x - 0.45)` about y, so that it presses the
///   lower surface's nodes at x = 0.5 and the fading ones at x = 0.25 (1-2 % covered), and
///   stands over those at x = 0.75 and 1 (mean weighted gaps -0.008 and -0.018): the faces
///   between x = 0.75 and 1 overlap the upper block and carry no pressed node, and on one
///   rank those four are exactly the faces skipped;
/// - flush: the upper block lifted by 0.01, onto the lower surface, so that the covered
///   nodes sit in the touching band (no pressure, a tangent: `dp/dgh > 0`).
///
/// Checked to fail with every overlapping face linearized, with one face per pressed node,
/// with "pressed" read as `p > 0` (the touching band left out), and with the fading nodes
/// left out.
#[test]
fn tangent_linearizes_only_the_faces_of_pressed_nodes() {
    let scene = partly_covered_blocks();
    let mesh = &scene.mesh;
    let up = mesh.bodies.iter().position(|b| b == "up").unwrap();
    let lifted = |lift: &dyn Fn(f64) -> f64| {
        let mut u = vec![0.0; 3 * mesh.num_nodes()];
        for e in (0..mesh.num_elements()).filter(|&e| mesh.body[e] == up) {
            for &n in mesh.element_nodes(e) {
                u[3 * n + 2] = lift(mesh.coords[n][0]);
            }
        }
        u
    };
    let tilted = lifted(&|x| 0.06 * (x - 0.45));
    let flush = lifted(&|_| 0.01);
    for (name, u) in [("tilted", &tilted), ("flush", &flush)] {
        for (rank, ranks) in [(0, 1), (0, 2), (1, 2)] {
            let elements = vec![0; mesh.num_elements()];
            let dofs = DofMap::new(mesh, elements, rank, ranks, &scene.constrained_mask());
            let contact = ContactInterfaces::new(&scene, &dofs).unwrap();
            let blocks = |linearize| {
                let mut out: Vec<(Vec<usize>, Vec<u64>, Vec<u64>)> = Vec::new();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect();
                let at = State {
                    scene: &scene,
                    u,
                    t: 1.0,
                };
                let mut keep = |b: &super::NodeBlock| {
                    out.push((b.slots.clone(), bits(&b.force), bits(&b.tangent)));
                    Ok(())
                };
                let failure = contact
                    .assemble_linearizing(&at, true, linearize, &mut keep)
                    .unwrap();
                assert_eq!(failure, None, "{name}, rank {rank} of {ranks}");
                out
            };
            let pressed = blocks(Linearize::PressedFaces);
            let every = blocks(Linearize::EveryFace);
            let at = format!("{name}, rank {rank} of {ranks}");
            assert!(pressed.iter().all(|b| !b.2.is_empty()), "{at}");
            assert_eq!(pressed.len(), every.len(), "{at}: blocks");
            if let Some(k) = (0..pressed.len()).find(|&k| pressed[k] != every[k]) {
                panic!("{at}: the block of slots {:?} differs", pressed[k].0);
            }
            if ranks == 1 {
                assert!(!pressed.is_empty(), "{at}: nothing pressed");
            }
        }
    }

    // Tilted, one rank: the faces with an overlap but no pressed node are the four of the
    // column between x = 0.75 and 1.
    let elements = vec![0; mesh.num_elements()];
    let dofs = DofMap::new(mesh, elements, 0, 1, &scene.constrained_mask());
    let contact = ContactInterfaces::new(&scene, &dofs).unwrap();
    let x = State {
        scene: &scene,
        u: &tilted,
        t: 1.0,
    }
    .positions();
    let iface = &contact.interfaces[0];
    let pass = &iface.passes[0];
    let ctx = iface.context(Default::default(), &x, &contact.x_old);
    let normals = pass.normals(&x).unwrap();
    let values = pass.values_at(&ctx, None, &mut RejectStats::default());
    let (_, kinematics) = pass.measured(&ctx, &values);
    let linearized: BTreeSet<usize> = pass
        .pressed_faces(&ctx, &normals, &kinematics)
        .into_iter()
        .collect();
    let skipped: BTreeSet<usize> = values
        .iter()
        .map(|p| p.s)
        .filter(|s| !linearized.contains(s))
        .collect();
    let column = |s: &usize| {
        let xs = pass.sec_faces[*s].nodes.iter().map(|&n| mesh.coords[n][0]);
        xs.fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)))
    };
    assert_eq!(skipped.len(), 4, "skipped faces {skipped:?}");
    assert!(skipped.iter().all(|s| column(s) == (0.75, 1.0)));
}

/// The displacements of [`partly_covered_blocks`] with the upper block lifted by 0.02.
fn upper_lifted(scene: &Scene) -> Vec<f64> {
    let mesh = &scene.mesh;
    let up = mesh.bodies.iter().position(|b| b == "up").unwrap();
    let mut u = vec![0.0; 3 * mesh.num_nodes()];
    for e in (0..mesh.num_elements()).filter(|&e| mesh.body[e] == up) {
        for &n in mesh.element_nodes(e) {
            u[3 * n + 2] = 0.02;
        }
    }
    u
}

/// The bilateral iteration's law ([`partly_covered_blocks`] with the upper block lifted 0.02,
/// so that the surfaces stand 0.01 apart, and a normal multiplier of 1 000 where one is given;
/// `eps_N = 4e5`, so `lambda_n + eps_N gh = -3 000`): the law leaves every node open; in the
/// bilateral iteration the nodes with a multiplier are pressed (the faces carrying them
/// linearized: the column of faces at the right edge) and those without stay open; off again,
/// nothing is pressed.
#[test]
fn the_bilateral_iteration_presses_only_nodes_with_a_multiplier() {
    use crate::model::Contribution;
    let scene = partly_covered_blocks();
    let mesh = &scene.mesh;
    let u = upper_lifted(&scene);
    let x = State {
        scene: &scene,
        u: &u,
        t: 1.0,
    }
    .positions();
    let mut contact = on_one_rank(&scene);
    let pressed = |contact: &ContactInterfaces| {
        let iface = &contact.interfaces[0];
        let pass = &iface.passes[0];
        let ctx = iface.context(contact.modes.get(), &x, &contact.x_old);
        let normals = pass.normals(&x).unwrap();
        let values = pass.values_at(&ctx, None, &mut RejectStats::default());
        let (_, kinematics) = pass.measured(&ctx, &values);
        pass.pressed_faces(&ctx, &normals, &kinematics)
    };
    assert!(!contact.has_bilateral_nodes());
    contact.set_bilateral(true);
    assert!(
        pressed(&contact).is_empty(),
        "bilateral without multipliers"
    );
    // A multiplier on the nodes of the column at x = 1 (wholly covered).
    let pass = &mut contact.interfaces[0].passes[0];
    let column: Vec<usize> = (0..pass.nodes.len())
        .filter(|&a| mesh.coords[pass.nodes[a]][0] == 1.0)
        .collect();
    column
        .iter()
        .for_each(|&a| pass.state[a].history.lambda_n = 1000.0);
    assert!(contact.has_bilateral_nodes());
    let bilateral: BTreeSet<usize> = pressed(&contact).into_iter().collect();
    let pass = &contact.interfaces[0].passes[0];
    let column_faces: BTreeSet<usize> = column
        .iter()
        .flat_map(|&a| pass.node_faces[a].iter().map(|&(s, _)| s))
        .collect();
    assert_eq!(bilateral, column_faces);
    contact.set_bilateral(false);
    assert!(pressed(&contact).is_empty(), "pressed by the law");
}

/// The nodes a Newton update carries through the other surface (`newton.hold_closing`).
/// [`partly_covered_blocks`] lifted 0.02 (every node open: no tangent there), and an update
/// that lowers the upper block so that the surfaces overlap: by less than [`CLOSING_DEPTH`]
/// `h_A` at every node, no node is held; by more (four times, at the largest
/// `h_A`), every node covered at least [`MIN_COVERAGE`] (columns x = 0.25 to 1, rows y = 0.25
/// to 1: sixteen), the deepest at the smallest `h_A`. Held, they are pressed at the lifted
/// state too (in tension: they have a tangent there); released, the law is the law again.
#[test]
fn an_update_that_carries_open_nodes_through_holds_them() {
    use crate::model::Contribution;
    let scene = partly_covered_blocks();
    let mesh = &scene.mesh;
    let lifted = upper_lifted(&scene);
    let at = State {
        scene: &scene,
        u: &lifted,
        t: 1.0,
    };
    let contact = on_one_rank(&scene);
    let mut tangent = DenseTangent::default();
    assert!(contact.jacobian(&at, &mut tangent).unwrap().is_none());
    assert!(tangent.0.is_empty(), "every node open where lifted");
    let pass = &contact.interfaces[0].passes[0];
    let sizes = pass.state.iter().map(|st| st.h);
    let (h_min, h_max) = sizes.fold((f64::MAX, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    // The surfaces stand 0.01 apart where lifted by 0.02: overlapping by `depth` at 0.01 -
    // depth, each node by `depth / h_A` of its face size.
    let hold = |depth: f64| {
        let u: Vec<f64> = lifted
            .iter()
            .map(|&v| if v > 0.0 { 0.01 - depth } else { 0.0 })
            .collect();
        let to = State {
            scene: &scene,
            u: &u,
            t: 1.0,
        };
        contact.hold_closing(&at, &to)
    };
    assert_eq!(hold(0.5 * CLOSING_DEPTH * h_min).held, 0);
    contact.release_closing();
    let closing = hold(4.0 * CLOSING_DEPTH * h_max);
    let held: BTreeSet<usize> = pass.closing_held.borrow().iter().copied().collect();
    let expected: BTreeSet<usize> = (0..pass.nodes.len())
        .filter(|&a| {
            let [x, y, _] = mesh.coords[pass.nodes[a]];
            x >= 0.25 && y >= 0.25
        })
        .collect();
    assert_eq!(held, expected);
    assert_eq!(closing.held, 16);
    let deepest = 4.0 * CLOSING_DEPTH * h_max / h_min;
    assert!(
        (closing.deepest - deepest).abs() < 1e-9 * deepest,
        "deepest {} against {deepest}",
        closing.deepest
    );
    let mut held_tangent = DenseTangent::default();
    assert!(contact.jacobian(&at, &mut held_tangent).unwrap().is_none());
    assert!(!held_tangent.0.is_empty(), "held nodes are pressed");
    contact.release_closing();
    let mut released = DenseTangent::default();
    assert!(contact.jacobian(&at, &mut released).unwrap().is_none());
    assert!(released.0.is_empty(), "released: open again");
}

/// A dof-indexed dense copy of the blocks a tangent adds.
#[derive(Default)]
struct DenseTangent(std::collections::BTreeMap<(usize, usize), f64>);

impl crate::model::TangentSink for DenseTangent {
    fn add_block(&mut self, rows: &[usize], cols: &[usize], values: &[f64]) -> crate::Result<()> {
        let n = 3 * cols.len();
        for (r, &a) in rows.iter().enumerate() {
            for (c, &b) in cols.iter().enumerate() {
                for (i, j) in (0..3).flat_map(|i| (0..3).map(move |j| (i, j))) {
                    let v = values[(3 * r + i) * n + 3 * c + j];
                    *self.0.entry((3 * a + i, 3 * b + j)).or_default() += v;
                }
            }
        }
        Ok(())
    }
}

/// A node the bilateral iteration holds in tension linearizes only the penalty's pull: its
/// tension's geometric terms (the turning normal, the changing weights) are left out, so its
/// tangent is the same whatever the multiplier, as long as the node stays in tension.
/// ([`partly_covered_blocks`] lifted 0.02 as above, the column at x = 1 with the multiplier
/// 1 000 or 2 000: tensions of 3 000 and 2 000 at its covered nodes, more at its partly
/// covered one. With the geometric terms the two tangents would differ by 1 000 times those
/// terms.)
#[test]
fn a_node_held_in_tension_linearizes_only_the_penalty() {
    use crate::model::Contribution;
    let scene = partly_covered_blocks();
    let mesh = &scene.mesh;
    let u = upper_lifted(&scene);
    let at = State {
        scene: &scene,
        u: &u,
        t: 1.0,
    };
    let tangent_with = |lambda_n: f64| {
        let mut contact = on_one_rank(&scene);
        let pass = &mut contact.interfaces[0].passes[0];
        for a in 0..pass.nodes.len() {
            if mesh.coords[pass.nodes[a]][0] == 1.0 {
                pass.state[a].history.lambda_n = lambda_n;
            }
        }
        contact.set_bilateral(true);
        let mut tangent = DenseTangent::default();
        assert!(contact.jacobian(&at, &mut tangent).unwrap().is_none());
        tangent.0
    };
    let (low, high) = (tangent_with(1000.0), tangent_with(2000.0));
    assert!(!low.is_empty(), "the held nodes have a tangent");
    let largest = low.values().fold(0.0f64, |m, v| m.max(v.abs()));
    let keys: BTreeSet<_> = low.keys().chain(high.keys()).collect();
    for k in keys {
        let (a, b) = (low.get(k).unwrap_or(&0.0), high.get(k).unwrap_or(&0.0));
        assert!(
            (a - b).abs() <= 1e-12 * largest,
            "dofs {k:?}: {a} against {b} (largest entry {largest})"
        );
    }
}

/// The fade is 0 up to MIN_COVERAGE, 1 from FADE_COVERAGE on, increasing between, with a
/// continuous derivative that matches central differences (and is 0 at both ends).
#[test]
fn coverage_fade_is_a_smooth_step() {
    assert_eq!(coverage_fade(0.0), (0.0, 0.0));
    assert_eq!(coverage_fade(MIN_COVERAGE), (0.0, 0.0));
    assert_eq!(coverage_fade(FADE_COVERAGE), (1.0, 0.0));
    assert_eq!(coverage_fade(0.7), (1.0, 0.0));
    let mut last = 0.0;
    for i in 1..100 {
        let c = MIN_COVERAGE + (FADE_COVERAGE - MIN_COVERAGE) * i as f64 / 100.0;
        let (r, dr) = coverage_fade(c);
        assert!(r > last && r < 1.0, "not increasing at {c}");
        last = r;
        let h = 1e-7;
        let fd = (coverage_fade(c + h).0 - coverage_fade(c - h).0) / (2.0 * h);
        assert!(
            (dr - fd).abs() <= 1e-6 * dr.abs().max(1.0),
            "{c}: {dr} vs {fd}"
        );
    }
}

/// The traction integrals of a face: on a flat square the corner functions integrate to a
/// quarter of the area each; on a curved, distorted Quad9 face the corner functions sum to
/// the area, and the gradient matches central differences of the integrals.
#[test]
fn traction_integrals_and_their_gradient() {
    let square = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
    ];
    let flat = traction_integrals(
        FaceType::Quad4,
        TractionScheme::Corners,
        &square,
        false,
        |_, _| {},
    );
    assert!((flat.area - 4.0).abs() < 1e-14);
    for v in &flat.value {
        assert!((v - 1.0).abs() < 1e-14, "{v}");
    }
    let parent = FaceType::Quad9.node_coords();
    let x: Vec<[f64; 3]> = parent
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let w = 0.05 * (i as f64 * 1.7).sin();
            [p[0] + w, p[1] - 0.5 * w, 0.2 * p[0] * p[0] + 0.1 * p[1] + w]
        })
        .collect();
    for scheme in [TractionScheme::Corners, TractionScheme::PiecewiseLinear] {
        let f = traction_integrals(FaceType::Quad9, scheme, &x, true, |_, _| {});
        if scheme == TractionScheme::Corners {
            let sum: f64 = f.value.iter().sum();
            assert!((sum - f.area).abs() < 1e-13 * f.area, "{sum} vs {}", f.area);
        }
        let h = 1e-6;
        for b in 0..x.len() {
            for c in 0..3 {
                let mut xp = x.clone();
                let mut xm = x.clone();
                xp[b][c] += h;
                xm[b][c] -= h;
                let fp = traction_integrals(FaceType::Quad9, scheme, &xp, false, |_, _| {});
                let fm = traction_integrals(FaceType::Quad9, scheme, &xm, false, |_, _| {});
                for k in 0..f.value.len() {
                    let fd = (fp.value[k] - fm.value[k]) / (2.0 * h);
                    let g = f.gradient[k * x.len() + b][c];
                    assert!(
                        (g - fd).abs() < 1e-7,
                        "{scheme:?} k {k} node {b}.{c}: {g} vs {fd}"
                    );
                }
            }
        }
    }
}

#[test]
fn passes_are_dealt_before_strips() {
    // Two passes on two ranks: one each, whole.
    assert_eq!(pass_ranks(0, 2, 2), 0..1);
    assert_eq!(pass_ranks(1, 2, 2), 1..2);
    // One pass: every rank shares it.
    assert_eq!(pass_ranks(0, 1, 2), 0..2);
    // Two passes on one rank, or on four ranks.
    assert_eq!(pass_ranks(1, 2, 1), 0..1);
    assert_eq!(pass_ranks(1, 2, 4), 2..4);
    // Two passes on three ranks: blocks of 1 and 2.
    assert_eq!(pass_ranks(0, 2, 3), 0..1);
    assert_eq!(pass_ranks(1, 2, 3), 1..3);
}

#[test]
fn every_node_is_held_by_exactly_one_rank() {
    let points: Vec<[f64; 3]> = (0..23)
        .map(|i| [(i % 5) as f64 * 0.3, (i / 5) as f64, 0.5 * (i % 2) as f64])
        .collect();
    for ranks in 1..=5 {
        for passes in 1..=2 {
            let mut held_by_pass = vec![0usize; passes];
            for (pass, held) in held_by_pass.iter_mut().enumerate() {
                let workers = pass_ranks(pass, passes, ranks);
                assert!(!workers.is_empty() && workers.end <= ranks);
                let strips = deal_in_strips(&points, &vec![1.0; points.len()], workers.len());
                let mut counts = vec![0usize; workers.len()];
                for &s in &strips {
                    counts[s] += 1;
                }
                let (lo, hi) = (counts.iter().min(), counts.iter().max());
                assert!(hi.unwrap() - lo.unwrap() <= 1, "{ranks} ranks: {counts:?}");
                *held += counts.iter().sum::<usize>();
            }
            assert!(held_by_pass.iter().all(|&n| n == points.len()));
            // Every rank gets a share of some pass.
            let used: std::collections::BTreeSet<usize> = (0..passes)
                .flat_map(|p| pass_ranks(p, passes, ranks))
                .collect();
            assert_eq!(used.len(), ranks);
        }
    }
    assert!(deal_in_strips(&[], &[], 3).is_empty());
}

#[test]
fn strips_split_along_the_longest_side_in_equal_counts() {
    // A 5 x 3 grid of points, longer along y: two ranks take the lower and upper rows.
    let points: Vec<[f64; 3]> = (0..15)
        .map(|i| [(i % 3) as f64, (i / 3) as f64, 1.0])
        .collect();
    let owner = deal_in_strips(&points, &[1.0; 15], 2);
    let counts = [0, 1].map(|r| owner.iter().filter(|&&o| o == r).count());
    assert_eq!(counts, [8, 7]);
    for (p, &o) in points.iter().zip(&owner) {
        match p[1] {
            y if y < 2.0 => assert_eq!(o, 0),
            y if y > 2.0 => assert_eq!(o, 1),
            _ => {}
        }
    }
    // One rank holds everything; more ranks than points leave some empty.
    assert!(deal_in_strips(&points, &[1.0; 15], 1)
        .iter()
        .all(|&o| o == 0));
    let many = deal_in_strips(&points[..2], &[1.0; 2], 4);
    assert_eq!(many, vec![0, 2]);
}

#[test]
fn strips_cut_where_the_work_is_halved() {
    // Ten nodes along x; the last four carry the contact (work 10 each), the others idle.
    let points: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
    let idle = 1e-3;
    let work: Vec<f64> = (0..10).map(|i| if i < 6 { idle } else { 10.0 }).collect();
    let owner = deal_in_strips(&points, &work, 2);
    assert_eq!(owner, [0, 0, 0, 0, 0, 0, 0, 0, 1, 1]);
    // The work of a face is shared among its traction nodes, on top of the idle work.
    let carriers = vec![vec![0, 1], vec![1, 2, 3, 4]];
    let shares = node_work(&carriers, &[3, 8], 5);
    let expected = [1.5, 3.5, 2.0, 2.0, 2.0].map(|w| w + super::deal::IDLE_NODE_WORK);
    assert_eq!(shares, expected);
}

/// A Newton update that pushes the upper block of [`partly_covered_blocks`] (0.01 deep) down
/// by `d` is shortened so that no node goes deeper than [`PENETRATION_REACH`] `h_A`
/// (`h_A` = 0.25): to `(reach - 0.01) / d`. Updates that lift it, slide it or push it less
/// deep are taken whole.
#[test]
fn an_update_stays_within_the_search_reach() {
    let scene = partly_covered_blocks();
    let contact = on_one_rank(&scene);
    let u = vec![0.0; 3 * scene.mesh.num_nodes()];
    let at = State {
        scene: &scene,
        u: &u,
        t: 1.0,
    };
    let upper: Vec<usize> = (0..scene.mesh.num_nodes())
        .filter(|&n| {
            let z = scene.mesh.coords[n][2];
            (z - 0.49).abs() < 1e-12 || z > 0.5 + 1e-12
        })
        .collect();
    let moved = |c: usize, d: f64| {
        let mut du = vec![0.0; u.len()];
        upper.iter().for_each(|&n| du[3 * n + c] = d);
        du
    };
    let reach = PENETRATION_REACH * 0.25;
    let d = 2.0 * (reach - 0.01);
    let fraction = contact.reach_fraction(&at, &moved(2, -d));
    assert!((fraction - 0.5).abs() < 1e-12, "pushed down: {fraction}");
    assert_eq!(contact.reach_fraction(&at, &moved(2, 0.5 * d)), 1.0);
    assert_eq!(contact.reach_fraction(&at, &moved(2, -0.4 * d)), 1.0);
    assert_eq!(contact.reach_fraction(&at, &moved(0, 0.3)), 1.0);
}

/// The pairs the matrix pattern holds ([`partly_covered_blocks`], the upper block's faces 0.5
/// wide from x = 0.45, over the lower's 0.25 from 0): none before the pattern's stencils are
/// handed out; the pairs of the state they were handed out at afterwards, and of a state moved
/// by much less than the search margin; not those of the upper block slid by -0.4 along x (its
/// first column of faces then reaches over the lower's first, 0.2 away before, beyond the
/// margin of 0.18), until the stencils of that state are handed out too; none once forgotten.
/// The same whether the check searches or takes the pairs the residual at the state found.
#[test]
fn the_held_pairs_are_those_the_pattern_was_given() {
    use crate::model::Contribution;
    let scene = partly_covered_blocks();
    let contact = on_one_rank(&scene);
    let mesh = &scene.mesh;
    let up = mesh.bodies.iter().position(|b| b == "up").unwrap();
    let slid = |dx: f64| {
        let mut u = vec![0.0; 3 * mesh.num_nodes()];
        for e in (0..mesh.num_elements()).filter(|&e| mesh.body[e] == up) {
            for &n in mesh.element_nodes(e) {
                u[3 * n] = dx;
            }
        }
        u
    };
    let (rest, near, far) = (slid(0.0), slid(0.001), slid(-0.4));
    let searching = |u: &[f64]| contact.holds_couplings_of(&state_at(&scene, u));
    // As before a Newton tangent: the residual at the state searched, and its pairs are kept.
    let after_residual = |u: &[f64]| {
        let at = state_at(&scene, u);
        let mut f = vec![0.0; u.len()];
        contact.residual(&at, &mut NodalForces(&mut f)).unwrap();
        let pass = &contact.interfaces[0].passes[0];
        let kept = pass.last_values.borrow();
        let kept_at = kept.as_ref().map(|v| &v.positions);
        assert_eq!(kept_at, Some(&pass.surface_positions(&at.positions())));
        contact.holds_couplings_of(&at)
    };
    let hand_out = |u: &[f64]| contact.couplings(&state_at(&scene, u), &mut |_| {});
    for holds in [&searching as &dyn Fn(&[f64]) -> bool, &after_residual] {
        assert!(!holds(&rest));
        hand_out(&rest);
        assert!(holds(&rest));
        assert!(holds(&near));
        assert!(!holds(&far));
        hand_out(&far);
        assert!(holds(&far));
        assert!(holds(&rest));
        contact.forget_couplings();
        assert!(!holds(&rest));
    }
}

/// The state of displacements `u` at full load.
fn state_at<'a>(scene: &'a Scene, u: &'a [f64]) -> State<'a> {
    State { scene, u, t: 1.0 }
}

/// The records of a checkpoint, kept in memory.
#[derive(Default)]
struct Records(std::collections::VecDeque<(String, Vec<f64>, Vec<u64>)>);

impl crate::model::StateSink for Records {
    fn f64s(&mut self, name: &str, values: &[f64]) {
        self.0
            .push_back((name.to_string(), values.to_vec(), Vec::new()));
    }
    fn u64s(&mut self, name: &str, values: &[u64]) {
        self.0
            .push_back((name.to_string(), Vec::new(), values.to_vec()));
    }
}

impl crate::model::StateSource for Records {
    fn f64s(&mut self, name: &str) -> crate::error::Result<Vec<f64>> {
        let (written, values, _) = self.0.pop_front().unwrap();
        assert_eq!(written, name);
        Ok(values)
    }
    fn u64s(&mut self, name: &str) -> crate::error::Result<Vec<u64>> {
        let (written, _, values) = self.0.pop_front().unwrap();
        assert_eq!(written, name);
        Ok(values)
    }
}

/// On two ranks the secondary surface of [`partly_covered_blocks`] (5 x 5 traction nodes, the
/// column at x = 0 out of reach of the upper block) is dealt by the work of its candidate
/// pairs, not by counts: each rank's work is within one node's of the other's. After the
/// upper block slid by -0.4 along x and the step closed, the new deal follows the contact;
/// interfaces made afresh that read the committed state back (a restart) deal alike.
#[test]
fn the_deal_follows_the_contact_and_a_restart_deals_alike() {
    use crate::model::Contribution;
    let scene = partly_covered_blocks();
    let mesh = &scene.mesh;
    let up = mesh.bodies.iter().position(|b| b == "up").unwrap();
    let on_rank = |rank| {
        let elements = vec![0; mesh.num_elements()];
        let dofs = DofMap::new(mesh, elements, rank, 2, &scene.constrained_mask());
        ContactInterfaces::new(&scene, &dofs).unwrap()
    };
    // Per rank: the nodes it holds and their work at positions `x`.
    let shares = |ranks: &[ContactInterfaces], x: &[[f64; 3]]| -> Vec<(Vec<usize>, f64)> {
        ranks
            .iter()
            .map(|c| {
                let pass = &c.interfaces[0].passes[0];
                let work = pass.node_work_at(x);
                let mine = pass.held.iter().map(|&a| work[a]).sum();
                (pass.held.clone(), mine)
            })
            .collect()
    };
    let balanced = |dealt: &[(Vec<usize>, f64)], what: &str| {
        let mut all: Vec<usize> = dealt.iter().flat_map(|(h, _)| h.clone()).collect();
        all.sort_unstable();
        assert_eq!(all, (0..25).collect::<Vec<_>>(), "{what}: held once each");
        // The most work one node carries here: a quarter of four faces' pairs.
        let node = 4.0;
        assert!((dealt[0].1 - dealt[1].1).abs() <= node, "{what}: {dealt:?}");
    };
    let mut ranks = [on_rank(0), on_rank(1)];
    let start = shares(&ranks, &mesh.coords);
    balanced(&start, "reference");
    assert!(start[0].0.len() > 13, "not dealt by counts: {start:?}");

    let mut u = vec![0.0; 3 * mesh.num_nodes()];
    for e in (0..mesh.num_elements()).filter(|&e| mesh.body[e] == up) {
        for &n in mesh.element_nodes(e) {
            u[3 * n] = -0.4;
        }
    }
    let at = State {
        scene: &scene,
        u: &u,
        t: 1.0,
    };
    for c in &mut ranks {
        c.close_step(&at);
        c.deal_as_committed();
    }
    let slid = shares(&ranks, &at.positions());
    balanced(&slid, "slid");
    assert_ne!(slid[0].0, start[0].0, "the deal moved with the contact");

    for (rank, c) in ranks.iter().enumerate() {
        let mut records = Records::default();
        c.write_state(&mut records);
        let mut restarted = on_rank(rank);
        restarted.read_state(&mut records).unwrap();
        let pass = &restarted.interfaces[0].passes[0];
        assert_eq!(pass.held, slid[rank].0, "restarted rank {rank}");
        assert_eq!(pass.local_faces, c.interfaces[0].passes[0].local_faces);
    }
}
