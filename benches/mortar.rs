//! Mortar segment-pair integration throughput: face pairs integrated per second, one core.
//!
//! Two overlapping faces (the primary shifted by a third of the face in x and y, rotated by
//! 10 degrees and facing the other way, so that the overlap is a genuine clipped polygon),
//! integrated with `integrate_pair` (projection, clipping, pallets, quadrature, inverse maps,
//! weights). Quad4-Quad4 with scheme 2 and the default degree 4; Quad9-Quad9 with scheme 2 and
//! degree 8 (each Quad9 face is 4 sub-segments, so a face pair is 16 sub-segment pairs). Each
//! with the overlaps split into centroid pallets (the default) and into fans (`_fan`: two
//! pallets fewer per overlap polygon).
//!
//! Group `mortar_pair_linearized`: the same pairs with `integrate_pair_linearized` (the weights
//! and their exact derivatives with respect to all node coordinates, the consistent tangent).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mortar::contact::mortar::{
    integrate_pair, integrate_pair_linearized, FaceGeom, IntegrationOptions, PalletSplit,
    RejectStats, TractionScheme,
};
use mortar::fe::FaceType;

/// Nodes of a face on the unit square [0,1]^2 at height z, rotated by `angle` about its centre
/// and shifted by `shift`; `flip` reverses the orientation (a primary face looks the other way).
fn face(kind: FaceType, angle: f64, shift: [f64; 2], flip: bool) -> Vec<[f64; 3]> {
    let (c, s) = (angle.cos(), angle.sin());
    kind.node_coords()
        .into_iter()
        .map(|xi| {
            let (mut x, y) = (0.5 * xi[0], 0.5 * xi[1]);
            if flip {
                x = -x;
            }
            [
                0.5 + shift[0] + c * x - s * y,
                0.5 + shift[1] + s * x + c * y,
                0.0,
            ]
        })
        .collect()
}

/// The benchmarked pair of `kind`: secondary, primary and options.
fn pair(
    kind: FaceType,
    degree: usize,
    pallets: PalletSplit,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, IntegrationOptions) {
    let sec = face(kind, 0.0, [0.0, 0.0], false);
    let pri = face(kind, 10f64.to_radians(), [0.33, 0.33], true);
    let opts = IntegrationOptions {
        scheme: TractionScheme::Corners,
        degree,
        pallets,
    };
    (sec, pri, opts)
}

const CASES: [(FaceType, usize, PalletSplit); 4] = [
    (FaceType::Quad4, 4, PalletSplit::Centroid),
    (FaceType::Quad9, 8, PalletSplit::Centroid),
    (FaceType::Quad4, 4, PalletSplit::Fan),
    (FaceType::Quad9, 8, PalletSplit::Fan),
];

/// Throughput of one pair kernel (returning the overlap area) on the pairs of [`CASES`].
fn bench_kernel(
    c: &mut Criterion,
    group_name: &str,
    kernel: impl Fn(&FaceGeom, &FaceGeom, &IntegrationOptions, &mut RejectStats) -> f64,
) {
    let mut group = c.benchmark_group(group_name);
    group.throughput(Throughput::Elements(1));
    for (kind, degree, pallets) in CASES {
        let (sec, pri, opts) = pair(kind, degree, pallets);
        let (s, p) = (FaceGeom { kind, x: &sec }, FaceGeom { kind, x: &pri });
        let area = kernel(&s, &p, &opts, &mut RejectStats::default());
        assert!(area > 0.1, "{kind:?}: overlap area {area}");
        let name = match pallets {
            PalletSplit::Centroid => kind.name().to_string(),
            PalletSplit::Fan => format!("{}_fan", kind.name()),
        };
        group.bench_function(name, |b| {
            b.iter(|| kernel(&s, &p, &opts, &mut RejectStats::default()))
        });
    }
    group.finish();
}

fn bench_pairs(c: &mut Criterion) {
    bench_kernel(c, "mortar_pair", |s, p, o, st| {
        integrate_pair(s, p, o, st).area
    });
}

fn bench_linearized_pairs(c: &mut Criterion) {
    bench_kernel(c, "mortar_pair_linearized", |s, p, o, st| {
        integrate_pair_linearized(s, p, o, st).area
    });
}

criterion_group!(benches, bench_pairs, bench_linearized_pairs);
criterion_main!(benches);
