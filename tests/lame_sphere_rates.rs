//! Convergence rates on Lamé's thick sphere (release mode: `cargo test --release --test
//! lame_sphere_rates`; in debug builds the tests are ignored, they would take minutes).
//!
//! Reference: Lamé's solution for a thick sphere under inner pressure (docs/theory.md section 9),
//! inner radius 1, outer radius 2, p = 1, E = 1000, nu = 0.3, dead pressure load, symmetry on the
//! three planes of the octant. Mesh: the cube-sphere octant with n x n elements per patch and n
//! through the thickness, n = 4, 6, 8 (the element size h ~ 1/n).
//!
//! Goal: the relative energy-norm error falls as h^k with k = 1 for linear and k = 2 for
//! quadratic elements. Passing: the least-squares slope of log(error) against log(h) over the
//! three meshes is at least 0.9 for Hex8 and at least 1.9 for Hex20 and Hex27.

mod common;

/// Least-squares slope of log(error) against log(1/n).
fn fitted_slope(ns: &[usize], errors: &[f64]) -> f64 {
    let xs: Vec<f64> = ns.iter().map(|&n| (1.0 / n as f64).ln()).collect();
    let ys: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
    let k = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / k, ys.iter().sum::<f64>() / k);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

fn slope_for(element: &str) -> (f64, Vec<f64>) {
    let ns = [4, 6, 8];
    let errors: Vec<f64> = ns
        .iter()
        .map(|&n| {
            let case = common::write_case(
                &format!("lame_{element}_{n}"),
                &common::thick_sphere_case(element, n),
            );
            let (out, _) = common::run_case(&case, 1, &["-q"]);
            common::metric(&out, "energy_error")
        })
        .collect();
    (fitted_slope(&ns, &errors), errors)
}

#[test]
fn fitted_slope_recovers_a_known_rate() {
    let ns = [4, 6, 8];
    let e: Vec<f64> = ns.iter().map(|&n| 3.0 * (n as f64).powf(-1.5)).collect();
    assert!((fitted_slope(&ns, &e) - 1.5).abs() < 1e-12);
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test lame_sphere_rates"
)]
fn lame_sphere_hex8_converges_at_rate_one() {
    let (slope, errors) = slope_for("hex8");
    eprintln!("hex8: errors {errors:?}, slope {slope:.3}");
    assert!(slope >= 0.9, "hex8 slope {slope} (errors {errors:?})");
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test lame_sphere_rates"
)]
fn lame_sphere_hex20_converges_at_rate_two() {
    let (slope, errors) = slope_for("hex20");
    eprintln!("hex20: errors {errors:?}, slope {slope:.3}");
    assert!(slope >= 1.9, "hex20 slope {slope} (errors {errors:?})");
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test lame_sphere_rates"
)]
fn lame_sphere_hex27_converges_at_rate_two() {
    let (slope, errors) = slope_for("hex27");
    eprintln!("hex27: errors {errors:?}, slope {slope:.3}");
    assert!(slope >= 1.9, "hex27 slope {slope} (errors {errors:?})");
}
