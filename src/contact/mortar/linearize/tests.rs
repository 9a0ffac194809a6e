//! The tests of the linearized kernel (module docs of [`super`], "Tests").

use super::*;
use crate::contact::mortar::pair::integrate_pair;
use crate::contact::mortar::test_support::{
    geom, max_abs, max_difference, settings, with_splits, Setting, SCHEMES,
};
use crate::test_rng::Rng;
use crate::vec3::{cross, Vec3};

/// Parent coordinates mapped to `[0, 1]^2` (quads) or kept (the unit triangle).
fn unit_coords(kind: FaceType, xi: [f64; 2]) -> [f64; 2] {
    if kind.is_quad() {
        [0.5 * (xi[0] + 1.0), 0.5 * (xi[1] + 1.0)]
    } else {
        xi
    }
}

/// The curved sheet `z = 0.2 x^2 - 0.1 x y + 0.15 y^2 + lift`, tilted (turned by 0.7 rad
/// about `(1, 2, 3)`) and moved.
fn sheet(x: f64, y: f64, lift: f64) -> Vec3 {
    tilted([x, y, 0.2 * x * x - 0.1 * x * y + 0.15 * y * y + lift])
}

/// `p` turned by 0.7 rad about `(1, 2, 3)` and moved.
fn tilted(p: Vec3) -> Vec3 {
    let norm = 14f64.sqrt();
    let k = [1.0 / norm, 2.0 / norm, 3.0 / norm];
    let (s, c) = 0.7f64.sin_cos();
    let kxp = cross(k, p);
    let kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    let shift = [0.3, -0.2, 0.5];
    std::array::from_fn(|d| p[d] * c + kxp[d] * s + k[d] * kp * (1.0 - c) + shift[d])
}

/// A secondary face on the sheet, in-plane distorted, nodes perturbed in and out of the
/// sheet (non-planar, curved edges for quadratic faces).
fn secondary_face(kind: FaceType, rng: &mut Rng) -> Vec<Vec3> {
    kind.node_coords()
        .iter()
        .map(|xi| {
            let [u, v] = unit_coords(kind, *xi);
            let x = u + 0.08 * u * v + rng.symmetric(0.02);
            let y = 0.9 * v + 0.05 * u * u + rng.symmetric(0.02);
            sheet(x, y, rng.symmetric(0.01))
        })
        .collect()
}

/// A primary face facing the other way (`u` and `v` swapped), turned by `angle`, shifted by
/// `shift` and lifted by `gap` off the sheet, perturbed like the secondary.
fn primary_face(kind: FaceType, angle: f64, shift: [f64; 2], gap: f64, rng: &mut Rng) -> Vec<Vec3> {
    let (s, c) = angle.sin_cos();
    kind.node_coords()
        .iter()
        .map(|xi| {
            let [u, v] = unit_coords(kind, *xi);
            let (a, b) = (0.95 * v + 0.04 * u * v, 0.85 * u);
            let x = shift[0] + c * a - s * b + rng.symmetric(0.02);
            let y = shift[1] + s * a + c * b + rng.symmetric(0.02);
            sheet(x, y, gap + rng.symmetric(0.01))
        })
        .collect()
}

/// A generic pair: tilted, curved, perturbed, partially overlapping, non-matching.
fn generic_pair(sec: FaceType, pri: FaceType, seed: u64) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed.wrapping_mul(0x2545_f491_4f6c_dd1d));
    let xs = secondary_face(sec, &mut rng);
    let xp = primary_face(pri, 0.3, [0.35, 0.25], 0.02, &mut rng);
    (xs, xp)
}

fn options(how: Setting, sec: FaceType, pri: FaceType) -> IntegrationOptions {
    IntegrationOptions {
        pallets: how.1,
        ..IntegrationOptions::for_faces(how.0, sec, pri)
    }
}

fn linearized(
    sec: (FaceType, &[Vec3]),
    pri: (FaceType, &[Vec3]),
    how: Setting,
    stats: &mut RejectStats,
) -> LinearizedWeights {
    let opts = options(how, sec.0, pri.0);
    integrate_pair_linearized(&geom(sec.0, sec.1), &geom(pri.0, pri.1), &opts, stats)
}

/// `integrate_pair`'s weights, dense (`n1` then `n2`), with its counts.
fn reference(
    sec: (FaceType, &[Vec3]),
    pri: (FaceType, &[Vec3]),
    how: Setting,
) -> (Vec<f64>, RejectStats) {
    let scheme = how.0;
    let opts = options(how, sec.0, pri.0);
    let mut stats = RejectStats::default();
    let w = integrate_pair(&geom(sec.0, sec.1), &geom(pri.0, pri.1), &opts, &mut stats);
    let (ns, np) = (sec.0.num_nodes(), pri.0.num_nodes());
    let nt = traction_node_count(sec.0, scheme);
    let mut dense = vec![0.0; nt * (ns + np)];
    for &(k, b, v) in &w.n1 {
        dense[k * ns + b] = v;
    }
    for &(k, c, v) in &w.n2 {
        dense[nt * ns + k * np + c] = v;
    }
    (dense, stats)
}

fn values(w: &LinearizedWeights) -> Vec<f64> {
    w.n1.iter().chain(&w.n2).copied().collect()
}

/// `d values / d y_j` for every entry of `values` (column `j`).
fn derivative_column(w: &LinearizedWeights, j: usize) -> Vec<f64> {
    let ndof = w.ndof();
    w.dn1
        .chunks(ndof)
        .chain(w.dn2.chunks(ndof))
        .map(|row| row[j])
        .collect()
}

/// Every combination of face types (secondary, primary).
fn all_type_pairs() -> impl Iterator<Item = (FaceType, FaceType)> {
    FaceType::ALL
        .into_iter()
        .flat_map(|s| FaceType::ALL.into_iter().map(move |p| (s, p)))
}

/// The float level 2 against the dual reference on one pair: the same counts, the values
/// bit for bit, the derivatives to 1e-13 of the largest (in fact bit for bit too).
fn assert_reproduces_reference(
    sec: (FaceType, &[Vec3]),
    pri: (FaceType, &[Vec3]),
    opts: &IntegrationOptions,
    what: &str,
) {
    let (sg, pg) = (geom(sec.0, sec.1), geom(pri.0, pri.1));
    let (mut s_float, mut s_dual) = (RejectStats::default(), RejectStats::default());
    let float = integrate_pair_linearized(&sg, &pg, opts, &mut s_float);
    let dual = linearized_with(
        &sg,
        &pg,
        opts,
        &mut s_dual,
        dual_reference::integrate_overlap,
    );
    assert_eq!(s_float, s_dual, "{what}: counts");
    assert_eq!(float.area.to_bits(), dual.area.to_bits(), "{what}: area");
    assert_eq!(
        float.unresolved_vertices, dual.unresolved_vertices,
        "{what}"
    );
    for (name, a, b) in [("n1", &float.n1, &dual.n1), ("n2", &float.n2, &dual.n2)] {
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert_eq!(
                x.to_bits(),
                y.to_bits(),
                "{what}: {name}[{i}] {x:e} != {y:e}"
            );
        }
    }
    let (df, dd) = (
        [&float.dn1[..], &float.dn2[..]],
        [&dual.dn1[..], &dual.dn2[..]],
    );
    let scale = max_abs(dd[0]).max(max_abs(dd[1]));
    let difference = max_difference(df[0], dd[0]).max(max_difference(df[1], dd[1]));
    assert!(
        difference <= 1e-13 * scale,
        "{what}: derivatives differ by {difference:e} (largest {scale:e})"
    );
}

/// Three pairs of the bending scene (`cases/bending`: Hex27 layers, Quad9 faces, scheme 2,
/// degree 8), secondary then primary nodes, face order: the undeformed pair at `x = 0`
/// (exactly touching, coincident edges at `y = 0, 1`: weighted gaps of round-off size, whose
/// signs the last bit of the weights decides); a pair of the first Newton iterate; a pair late
/// in the bending whose overlap has a vertex where nearly parallel edges cross (`x = 7.51124`
/// and `7.51122`): plane derivatives of 1e12 cancel, so the derivatives depend on the order of
/// the operations (module docs of [`super`], "Exactness").
const BENDING_PAIRS: [[f64; 54]; 3] = [
    [
        0.0,
        0.0,
        1.0,
        1.25,
        0.0,
        1.0,
        1.25,
        1.0,
        1.0,
        0.0,
        1.0,
        1.0,
        0.625,
        0.0,
        1.0,
        1.25,
        0.5,
        1.0,
        0.625,
        1.0,
        1.0,
        0.0,
        0.5,
        1.0,
        0.625,
        0.5,
        1.0,
        0.0,
        0.0,
        1.0,
        0.0,
        1.0,
        1.0,
        1.6666666666666665,
        1.0,
        1.0,
        1.6666666666666665,
        0.0,
        1.0,
        0.0,
        0.5,
        1.0,
        0.8333333333333333,
        1.0,
        1.0,
        1.6666666666666665,
        0.5,
        1.0,
        0.8333333333333333,
        0.0,
        1.0,
        0.8333333333333333,
        0.5,
        1.0,
    ],
    [
        2.4995821184900553,
        0.0,
        0.9997766457851738,
        3.7476983666222528,
        0.0,
        1.001145592226524,
        3.747908671178117,
        1.0,
        1.0011778169595529,
        2.4996333570308233,
        1.0,
        0.9997888810667629,
        3.1238948846935743,
        0.0,
        1.0000585347834672,
        3.747803518900185,
        0.5000328594332102,
        1.0011617045930383,
        3.1239603722275655,
        1.0,
        1.000068980261321,
        2.4996077377604395,
        0.4999970347958154,
        0.9997827634259684,
        3.12392762846057,
        0.4999989529323504,
        1.000063757522394,
        1.665436256498429,
        0.0,
        0.9998509532274821,
        1.6657073138978975,
        1.0,
        0.9998613837645863,
        3.3335054144694696,
        1.0,
        1.000246602350682,
        3.3335468265207084,
        0.0,
        1.0002372151579992,
        1.6655717851981633,
        0.4999924372943439,
        0.9998561684960342,
        2.499154349094873,
        1.0,
        0.9997112889681756,
        3.333526120495089,
        0.4999934724811446,
        1.0002419087543406,
        2.499162949859735,
        0.0,
        0.9996986042691017,
        2.499158649477304,
        0.5000010084686364,
        0.9997049466186387,
    ],
    [
        7.511243814701613,
        0.0,
        2.0510031664462645,
        8.755208367328038,
        0.0,
        2.288075599570319,
        8.75520837555786,
        1.0,
        2.28807559303152,
        7.51124376999247,
        1.0,
        2.0510031768339263,
        8.133296617246586,
        0.0,
        2.169511107591984,
        8.755208371430433,
        0.49999999459881106,
        2.288075596279586,
        8.133296599407045,
        1.0,
        2.169511112480069,
        7.511243792348219,
        0.5000000210713396,
        2.0510031716355575,
        8.133296608322649,
        0.5000000133501024,
        2.169511110040916,
        6.681742245101922,
        0.0,
        1.8944101769563169,
        6.681742074807264,
        1.0,
        1.8944102272340086,
        8.340605670182246,
        1.0,
        2.2089661931503257,
        8.34060566539637,
        0.0,
        2.2089661976757924,
        6.681742159957448,
        0.5000000852667351,
        1.8944102020971931,
        7.511224655514203,
        1.0,
        2.05101453787608,
        8.340605667817163,
        0.4999999937443363,
        2.2089661954391135,
        7.51122463393879,
        0.0,
        2.051014551296121,
        7.5112246447251465,
        0.49999998901017156,
        2.0510145445852785,
    ],
];

/// Test 0. The float level 2 reproduces the dual-number reference ([`dual_reference`]):
/// values bit for bit, derivatives to 1e-13 of the largest, for every face-type pair and
/// valid scheme on generic configurations (also moved into one plane: touching faces) and
/// on the bending scene's pairs (with every scheme).
#[test]
fn float_level2_reproduces_the_dual_reference() {
    for (st, pt) in all_type_pairs() {
        for how in settings(st) {
            let opts = options(how, st, pt);
            for seed in 0..2 {
                let (xs, xp) = generic_pair(st, pt, seed);
                let what = format!("{st:?}-{pt:?} {how:?} seed {seed}");
                assert_reproduces_reference((st, &xs), (pt, &xp), &opts, &what);
                let flat = |x: &[Vec3]| x.iter().map(|p| [p[0], p[1], 0.0]).collect::<Vec<_>>();
                let (fs, fp) = (flat(&xs), flat(&xp));
                let what = format!("{what}, flat");
                assert_reproduces_reference((st, &fs), (pt, &fp), &opts, &what);
            }
        }
    }
    for (i, pair) in BENDING_PAIRS.iter().enumerate() {
        let x: Vec<Vec3> = pair.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        let (xs, xp) = x.split_at(9);
        for how in with_splits(SCHEMES) {
            let opts = options(how, FaceType::Quad9, FaceType::Quad9);
            let what = format!("bending pair {i}, {how:?}");
            assert_reproduces_reference((FaceType::Quad9, xs), (FaceType::Quad9, xp), &opts, &what);
        }
    }
}

/// Test 1. The values equal `integrate_pair`'s (dense, 1e-13 of the largest weight), with the
/// same counts, for every face-type pair and valid scheme on three generic configurations.
#[test]
fn values_equal_integrate_pair() {
    let mut worst: f64 = 0.0;
    for (sk, pk) in all_type_pairs() {
        for seed in 0..3 {
            let (xs, xp) = generic_pair(sk, pk, seed);
            for how in settings(sk) {
                let what = format!("{sk:?} on {pk:?} {how:?} seed {seed}");
                let mut stats = RejectStats::default();
                let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
                let (expected, expected_stats) = reference((sk, &xs), (pk, &xp), how);
                assert_eq!(stats, expected_stats, "{what}");
                assert!(
                    stats.pairs_integrated > 0 && w.area > 1e-3,
                    "{what}: {stats:?}"
                );
                assert_eq!(w.unresolved_vertices, 0, "{what}");
                let error = max_difference(&values(&w), &expected) / max_abs(&expected);
                assert!(error < 1e-13, "{what}: relative error {error:e}");
                worst = worst.max(error);
            }
        }
    }
    eprintln!("values: worst relative difference {worst:e}");
}

/// Test 2. The derivatives against central differences of `integrate_pair` (step 1e-6, faces
/// of size 1): below 1e-6 of the largest derivative, every face-type pair and scheme. The
/// counts are the same at every perturbed position (the topology does not change).
#[test]
fn derivatives_match_central_differences() {
    const STEP: f64 = 1e-6;
    let mut worst: f64 = 0.0;
    for (sk, pk) in all_type_pairs() {
        let (xs, xp) = generic_pair(sk, pk, 7);
        let ns = xs.len();
        let schemes = settings(sk);
        let exact: Vec<(LinearizedWeights, RejectStats)> = schemes
            .iter()
            .map(|&how| {
                let mut stats = RejectStats::default();
                let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
                (w, stats)
            })
            .collect();
        let mut errors = vec![0.0f64; schemes.len()];
        for j in 0..3 * (ns + xp.len()) {
            let moved = |sign: f64| {
                let (mut s, mut p) = (xs.clone(), xp.clone());
                if j < 3 * ns {
                    s[j / 3][j % 3] += sign * STEP;
                } else {
                    p[j / 3 - ns][j % 3] += sign * STEP;
                }
                (s, p)
            };
            let ((s_plus, p_plus), (s_minus, p_minus)) = (moved(1.0), moved(-1.0));
            for (i, &how) in schemes.iter().enumerate() {
                let (plus, plus_stats) = reference((sk, &s_plus), (pk, &p_plus), how);
                let (minus, minus_stats) = reference((sk, &s_minus), (pk, &p_minus), how);
                assert_eq!(plus_stats, exact[i].1, "{sk:?} on {pk:?} dof {j}");
                assert_eq!(minus_stats, exact[i].1, "{sk:?} on {pk:?} dof {j}");
                let fd: Vec<f64> = plus
                    .iter()
                    .zip(&minus)
                    .map(|(a, b)| (a - b) / (2.0 * STEP))
                    .collect();
                let column = derivative_column(&exact[i].0, j);
                errors[i] = errors[i].max(max_difference(&column, &fd));
            }
        }
        for (i, scheme) in schemes.iter().enumerate() {
            let w = &exact[i].0;
            let largest = max_abs(&w.dn1).max(max_abs(&w.dn2));
            let error = errors[i] / largest;
            assert!(
                error < 1e-6,
                "{sk:?} on {pk:?} {scheme:?}: relative error {error:e}"
            );
            worst = worst.max(error);
        }
    }
    eprintln!("derivatives vs central differences: worst relative error {worst:e}");
}

/// Test 3. Momentum: `sum_b dn1_kb / dy_j = sum_c dn2_kc / dy_j` for every traction node and
/// coordinate, to round-off (1e-13 of the largest derivative).
#[test]
fn derivatives_conserve_momentum() {
    let mut worst: f64 = 0.0;
    for (sk, pk) in all_type_pairs() {
        let (xs, xp) = generic_pair(sk, pk, 11);
        for how in settings(sk) {
            let mut stats = RejectStats::default();
            let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
            let (ns, np, ndof) = (w.sec_nodes, w.pri_nodes, w.ndof());
            let largest = max_abs(&w.dn1).max(max_abs(&w.dn2));
            for k in 0..w.traction_nodes {
                for j in 0..ndof {
                    let sum1: f64 = (0..ns).map(|b| w.dn1[(k * ns + b) * ndof + j]).sum();
                    let sum2: f64 = (0..np).map(|c| w.dn2[(k * np + c) * ndof + j]).sum();
                    let error = (sum1 - sum2).abs() / largest;
                    assert!(error < 1e-13, "{sk:?} on {pk:?} {how:?}: {error:e}");
                    worst = worst.max(error);
                }
            }
        }
    }
    eprintln!("momentum of the derivatives: worst relative defect {worst:e}");
}

/// Test 4. Frame indifference: the derivative along a rigid translation of both faces
/// (`sum_a dn/dx_a`, per axis) and along an infinitesimal rigid rotation
/// (`sum_a (omega x x_a) . dn/dx_a`, omega along each axis) vanishes, to 1e-12 of the largest
/// derivative (times the largest coordinate for rotations).
#[test]
fn derivatives_are_frame_indifferent() {
    let mut worst: [f64; 2] = [0.0; 2];
    for (sk, pk) in all_type_pairs() {
        let (xs, xp) = generic_pair(sk, pk, 13);
        let nodes: Vec<Vec3> = xs.iter().chain(&xp).copied().collect();
        let size = nodes.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for how in settings(sk) {
            let mut stats = RejectStats::default();
            let w = linearized((sk, &xs), (pk, &xp), how, &mut stats);
            let ndof = w.ndof();
            let largest = max_abs(&w.dn1).max(max_abs(&w.dn2));
            for row in w.dn1.chunks(ndof).chain(w.dn2.chunks(ndof)) {
                for axis in 0..3 {
                    let translation: f64 = (0..nodes.len()).map(|a| row[3 * a + axis]).sum();
                    let omega: Vec3 = std::array::from_fn(|d| (d == axis) as u8 as f64);
                    let rotation: f64 = nodes
                        .iter()
                        .enumerate()
                        .map(|(a, x)| {
                            let v = cross(omega, *x);
                            (0..3).map(|d| v[d] * row[3 * a + d]).sum::<f64>()
                        })
                        .sum();
                    let errors = [
                        translation.abs() / largest,
                        rotation.abs() / (largest * size),
                    ];
                    assert!(
                        errors[0] < 1e-12 && errors[1] < 1e-12,
                        "{sk:?} on {pk:?} {how:?} axis {axis}: {errors:?}"
                    );
                    worst = [worst[0].max(errors[0]), worst[1].max(errors[1])];
                }
            }
        }
    }
    eprintln!(
        "frame indifference: worst relative translation {:e}, rotation {:e}",
        worst[0], worst[1]
    );
}

/// A face of `kind` whose node at unit coordinates `(u, v)` (see [`unit_coords`]) sits at
/// `map(u, v)` in the plane `z = 0` (exact projections: a vertex on an edge is exactly on
/// it) or in the tilted plane.
fn planar(kind: FaceType, tilt: bool, map: impl Fn(f64, f64) -> [f64; 2]) -> Vec<Vec3> {
    kind.node_coords()
        .iter()
        .map(|xi| {
            let [u, v] = unit_coords(kind, *xi);
            let [x, y] = map(u, v);
            if tilt {
                tilted([x, y, 0.0])
            } else {
                [x, y, 0.0]
            }
        })
        .collect()
}

/// Checks finite output equal to `integrate_pair`'s (1e-12 of the largest weight) with the
/// same counts; returns the counts.
fn assert_finite_and_consistent(
    sec: (FaceType, &[Vec3]),
    pri: (FaceType, &[Vec3]),
    what: &str,
) -> Vec<RejectStats> {
    settings(sec.0)
        .into_iter()
        .map(|how| {
            let mut stats = RejectStats::default();
            let w = linearized(sec, pri, how, &mut stats);
            let all = w.n1.iter().chain(&w.n2).chain(&w.dn1).chain(&w.dn2);
            assert!(
                all.into_iter().chain([&w.area]).all(|v| v.is_finite()),
                "{what} {how:?}"
            );
            let (expected, expected_stats) = reference(sec, pri, how);
            assert_eq!(stats, expected_stats, "{what} {how:?}");
            let error = max_difference(&values(&w), &expected);
            assert!(
                error <= 1e-12 * max_abs(&expected),
                "{what} {how:?}: {error:e}"
            );
            stats
        })
        .collect()
}

/// Test 5. Degenerate input never gives NaN: coincident faces exactly on top of each other
/// (equal and different types), edges along edges with vertices exactly on edges, a vertex
/// exactly on an edge, faces turned by 1e-12, slivers (counted) and overlaps just above the
/// sliver area, touching corners, a collapsed face and a NaN coordinate (counted, zero
/// weights).
#[test]
fn degenerate_input_gives_finite_output() {
    use FaceType::*;
    let square = |shift: [f64; 2], angle: f64, swap: bool| {
        move |u: f64, v: f64| {
            let (u, v) = if swap { (v, u) } else { (u, v) };
            let (s, c) = angle.sin_cos();
            let (x, y) = (u - 0.5, v - 0.5);
            [
                0.5 + shift[0] + c * x - s * y,
                0.5 + shift[1] + s * x + c * y,
            ]
        }
    };
    let kinds = [
        (Quad4, Quad4),
        (Quad9, Quad9),
        (Tri6, Tri6),
        (Quad8, Quad4),
        (Tri3, Quad9),
    ];
    for ((sk, pk), tilt) in kinds.into_iter().flat_map(|k| [(k, false), (k, true)]) {
        let xs = planar(sk, tilt, square([0.0; 2], 0.0, false));
        let cases = [
            ("coincident", [0.0, 0.0], 0.0, 1),
            ("turned by 1e-12", [0.0, 0.0], 1e-12, 1),
            ("half shifted", [0.5, 0.0], 0.0, 1),
            ("sliver 1e-9", [1.0 - 1e-9, 0.0], 0.0, 0),
            ("overlap 1e-7", [1.0 - 1e-7, 0.3], 0.0, 1),
            ("touching corner", [1.0, 1.0], 0.0, 0),
        ];
        for (what, shift, angle, integrated) in cases {
            let xp = planar(pk, tilt, square(shift, angle, true));
            let what = format!("{sk:?} on {pk:?} {what} (tilted: {tilt})");
            for stats in assert_finite_and_consistent((sk, &xs), (pk, &xp), &what) {
                // (Shifted triangles overlap elsewhere, or not at all.)
                if sk.is_quad() && pk.is_quad() {
                    assert_eq!(stats.pairs_integrated > 0, integrated > 0, "{what}");
                }
            }
        }
        // A primary triangle with a vertex exactly at the middle of an edge of the secondary.
        let (a, b, c) = ([0.5, 0.0], [-0.2, 0.7], [1.2, 0.7]);
        let xp = planar(Tri3, tilt, |u, v| {
            std::array::from_fn(|d| a[d] + u * (b[d] - a[d]) + v * (c[d] - a[d]))
        });
        let what = format!("{sk:?}: vertex on an edge (tilted: {tilt})");
        assert_finite_and_consistent((sk, &xs), (Tri3, &xp), &what);
        // A collapsed primary, and a NaN coordinate.
        let point = vec![[0.5, 0.5, 0.0]; pk.num_nodes()];
        assert_finite_and_consistent((sk, &xs), (pk, &point), "collapsed");
        let mut nan = planar(pk, tilt, square([0.2, 0.1], 0.0, true));
        nan[1][2] = f64::NAN;
        for stats in assert_finite_and_consistent((sk, &xs), (pk, &nan), "NaN") {
            assert_eq!((stats.non_finite, stats.pairs_integrated), (1, 0));
        }
    }
}
