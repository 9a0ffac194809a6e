//! One-dimensional grading maps of `[0, 1]` onto itself, for graded meshes.
//!
//! [`exp_grading`] makes equal parameter steps grow in a constant ratio
//! (`expm1(beta u) / expm1(beta)`); [`ZoneGrading`] keeps them uniform over a fine zone first.

/// `expm1(beta u) / expm1(beta)`: a map of `[0, 1]` onto itself whose slope grows by the factor
/// `e^beta` from `u = 0` to `u = 1` (shrinks for `beta < 0`); the identity for `beta = 0`, and
/// exactly 0 and 1 at the ends.
pub fn exp_grading(u: f64, beta: f64) -> f64 {
    if beta == 0.0 {
        u
    } else if u <= 0.0 {
        0.0
    } else if u >= 1.0 {
        1.0
    } else {
        (beta * u).exp_m1() / beta.exp_m1()
    }
}

/// A smooth, increasing map of `[0, 1]` onto itself for graded meshes: the spacing of equal
/// parameter steps is uniform over a fine **zone** at the start (the first `zone` of the
/// image), then grows exponentially to `ratio` times the zone's at `u = 1`. With
/// `h(u) = 1` for `u <= u_z` and `exp(beta (u - u_z))` beyond, `beta = ln(ratio) / (1 - u_z)`,
/// the map is `H(u) / H(1)` with `H` the integral of `h` (continuous slope); `u_z` is solved
/// (bisection) so that `H(u_z) / H(1) = zone`. Without a zone it is [`exp_grading`] with
/// `beta = ln(ratio)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZoneGrading {
    u_zone: f64,
    beta: f64,
    total: f64,
}

impl ZoneGrading {
    /// `ratio >= 1` (1: the identity), `zone` in `[0, 1)`.
    ///
    /// # Panics
    /// If `ratio < 1` or `zone` is outside `[0, 1)` (validate user input first).
    pub fn new(ratio: f64, zone: f64) -> ZoneGrading {
        assert!(
            ratio >= 1.0 && ratio.is_finite() && (0.0..1.0).contains(&zone),
            "ZoneGrading: ratio {ratio} must be >= 1 and zone {zone} in [0, 1)"
        );
        let make = |u_zone: f64| {
            let beta = ratio.ln() / (1.0 - u_zone);
            let total = if beta == 0.0 {
                1.0
            } else {
                u_zone + (ratio - 1.0) / beta
            };
            ZoneGrading {
                u_zone,
                beta,
                total,
            }
        };
        if ratio == 1.0 || zone == 0.0 {
            return make(0.0);
        }
        // The zone's share of the image, u_z / H(1), grows from 0 to 1 with u_z.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            let g = make(mid);
            if mid / g.total < zone {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        make(0.5 * (lo + hi))
    }

    /// The map at `u` (exactly 0 and 1 at the ends).
    pub fn map(&self, u: f64) -> f64 {
        if u <= 0.0 {
            return 0.0;
        }
        if u >= 1.0 {
            return 1.0;
        }
        if self.beta == 0.0 {
            return u;
        }
        let h = if u <= self.u_zone {
            u
        } else {
            self.u_zone + (self.beta * (u - self.u_zone)).exp_m1() / self.beta
        };
        h / self.total
    }

    /// The exact cell ratio of [`exp_grading`] for `n` cells: the last cell `ratio` times as
    /// long as the first, consecutive cells in a constant ratio (no zone).
    pub(super) fn exact_cell_ratio(ratio: f64, n: usize) -> ZoneGrading {
        let beta = cell_ratio_exponent(ratio, n);
        ZoneGrading {
            u_zone: 0.0,
            beta,
            total: if beta == 0.0 {
                1.0
            } else {
                beta.exp_m1() / beta
            },
        }
    }

    /// True for the identity map (a ratio of 1).
    pub(super) fn is_identity(&self) -> bool {
        self.beta == 0.0
    }
}

/// The exponent `beta` of [`exp_grading`] that makes `n` equal lattice cells map to cells
/// growing geometrically, the last `ratio` times as long as the first (0 for `n = 1` or
/// `ratio = 1`).
pub(super) fn cell_ratio_exponent(ratio: f64, n: usize) -> f64 {
    if n < 2 || ratio == 1.0 {
        0.0
    } else {
        ratio.ln() * n as f64 / (n - 1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zone_grading_is_uniform_in_its_zone_then_grows_to_its_ratio() {
        for (ratio, zone) in [(1.0, 0.0), (1.0, 0.5), (20.0, 0.0), (20.0, 0.3), (5.0, 0.8)] {
            let g = ZoneGrading::new(ratio, zone);
            assert_eq!(g.map(0.0), 0.0);
            assert_eq!(g.map(1.0), 1.0);
            let n = 2000;
            let x: Vec<f64> = (0..=n).map(|i| g.map(i as f64 / n as f64)).collect();
            let dx: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
            assert!(
                dx.iter().all(|&d| d > 0.0),
                "{ratio} {zone}: not increasing"
            );
            // Slopes: the end over the start is the ratio.
            let end = dx[n - 1] / dx[0];
            assert!((end - ratio).abs() < 0.01 * ratio, "{ratio} {zone}: {end}");
            // Uniform over the first `zone` of the image, growing after it.
            let in_zone: Vec<f64> = dx
                .iter()
                .zip(&x)
                .filter(|(_, &xi)| xi < zone - 1e-3)
                .map(|(d, _)| *d)
                .collect();
            if let (Some(lo), Some(hi)) = (
                in_zone.iter().cloned().reduce(f64::min),
                in_zone.iter().cloned().reduce(f64::max),
            ) {
                assert!((hi - lo).abs() < 1e-9 * hi, "{ratio} {zone}");
                if ratio > 1.0 {
                    let after = dx[in_zone.len() + 10];
                    assert!(after > hi * (1.0 + 1e-6), "{ratio} {zone}");
                }
            }
        }
        // Without a zone, the exponential map.
        let g = ZoneGrading::new(8.0, 0.0);
        for u in [0.1, 0.5, 0.9] {
            assert!((g.map(u) - exp_grading(u, 8f64.ln())).abs() < 1e-14);
        }
    }
}
