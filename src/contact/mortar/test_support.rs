//! What the tests of the mortar kernels share: the traction schemes and pallet splits to run,
//! faces as the kernels take them, and comparisons of results.

use super::clip::PalletSplit;
use super::overlap::FaceGeom;
use super::segments::{traction_nodes, TractionScheme};
use crate::fe::FaceType;

/// The three traction schemes.
pub const SCHEMES: [TractionScheme; 3] = [
    TractionScheme::FaceShape,
    TractionScheme::Corners,
    TractionScheme::PiecewiseLinear,
];

/// The two ways of splitting an overlap into pallets.
pub const SPLITS: [PalletSplit; 2] = [PalletSplit::Centroid, PalletSplit::Fan];

/// A traction scheme and a pallet split: how a pair is integrated, beside the degree.
pub type Setting = (TractionScheme, PalletSplit);

/// The schemes a secondary face type admits.
pub fn allowed_schemes(kind: FaceType) -> Vec<TractionScheme> {
    SCHEMES
        .into_iter()
        .filter(|&s| traction_nodes(kind, s).is_ok())
        .collect()
}

/// Every scheme of `schemes` with each pallet split.
pub fn with_splits(schemes: impl IntoIterator<Item = TractionScheme>) -> Vec<Setting> {
    schemes
        .into_iter()
        .flat_map(|scheme| SPLITS.map(|split| (scheme, split)))
        .collect()
}

/// Every scheme a secondary face type admits, with each pallet split.
pub fn settings(kind: FaceType) -> Vec<Setting> {
    with_splits(allowed_schemes(kind))
}

/// A face of type `kind` with node coordinates `x`, as the kernels take it.
pub fn geom(kind: FaceType, x: &[[f64; 3]]) -> FaceGeom<'_> {
    FaceGeom { kind, x }
}

/// The largest difference between entries of `a` and `b`.
pub fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The largest magnitude of an entry.
pub fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}
