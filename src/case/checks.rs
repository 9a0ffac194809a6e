//! The limits of a case file's values and the checks that several parts of the scene share,
//! each with its one-line error naming the key: names that become file names, axes, two-word
//! keys, load curves, quadrature degrees, penalty factors, and the run settings (steps and
//! Newton).

use crate::io::case_file::{LoadCurveSpec, NewtonSpec, StepsSpec};
use crate::{within_bounds, MAX_MAGNITUDE};

use super::LoadCurve;

/// `[(name, given)]` of optional keys of a spec: `given!(spec; a, b)` is
/// `[("a", spec.a.is_some()), ("b", spec.b.is_some())]`.
macro_rules! given {
    ($spec:expr; $($key:ident),+ $(,)?) => {
        [$((stringify!($key), $spec.$key.is_some())),+]
    };
}
pub(super) use given;

/// The first key of `keys` that is given.
pub(super) fn first_given<'a>(keys: &[(&'a str, bool)]) -> Option<&'a str> {
    keys.iter().find(|(_, given)| *given).map(|(k, _)| *k)
}

/// Largest accepted `newton.max_it`.
const MAX_NEWTON_ITS: usize = 10_000;
/// Largest accepted `steps.count`.
const MAX_STEPS: usize = 1_000_000;

/// The smallest load step that cutting may reach (`1 / steps.count / 2^max_cuts`): a margin far
/// above the round-off of the load itself (1e-16), where steps would stop advancing it, and
/// a run could never end.
const MIN_STEP: f64 = 1e-12;

/// Most Uzawa augmentations per step (`interface.uzawa_max`).
pub(super) const MAX_UZAWA: usize = 1000;

/// Bounds of an interface's penalty factor (times E/h): beyond them the contact stiffness
/// swamps or vanishes against the bulk's in double precision.
pub(super) const PENALTY_RANGE: (f64, f64) = (1e-6, 1e12);

/// The largest normal `penalty` of a contact interface without friction: above it Newton's
/// residual stalls at the round-off of its own assembly even on the contact patch test (1e10
/// converges, 1e12 does not; docs/verification.md, "Extremes").
pub(super) const MAX_FRICTIONLESS_CONTACT_PENALTY: f64 = 1e10;

/// The largest normal `penalty` of a contact interface with friction: above it the Coulomb
/// cone, mu times a pressure that a tiny penetration changes a lot, switches nodes between
/// stick and slip from one Newton iterate to the next, and the sliding blocks no longer
/// converge (1e3 does, in 403 iterations; 1e4, 1e8, 1e10 and 1e12 fail; docs/verification.md,
/// "Extremes").
pub(super) const MAX_FRICTIONAL_CONTACT_PENALTY: f64 = 1e3;

/// Largest mesh a generator may build (hexahedra per part), so a typo in `divisions` is an
/// error rather than an exhausted memory.
pub(super) const MAX_GENERATED_ELEMENTS: usize = 20_000_000;

/// Bounds of the generators' grading ratios (`box.grading`, `hemisphere_quarter`'s
/// `pole_grading` and `radial_grading`): beyond them the cell sizes under- or overflow.
pub(super) const MIN_GRADING: f64 = 1e-6;
pub(super) const MAX_GRADING: f64 = 1e6;

/// A name that becomes part of output file names (the scene's, an interface's): not empty,
/// not hidden (a leading `.`), and no path separators or control characters, so that every
/// file stays inside the output folder.
pub(super) fn check_file_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        Err("must not be empty (it names output files)".into())
    } else if name.starts_with('.') {
        Err("must not start with '.' (it names output files)".into())
    } else if name
        .chars()
        .any(|c| c == '/' || c == '\\' || c.is_control())
    {
        Err("must not contain '/', '\\' or control characters (it names output files)".into())
    } else {
        Ok(())
    }
}

/// The axis `"x"`, `"y"` or `"z"` as 0, 1 or 2.
pub(super) fn axis(s: &str) -> Option<usize> {
    match s {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

/// A key that takes one of two words: false for the first, true for the second, and otherwise
/// the one-line message naming the key and both words.
pub(super) fn two_words(key: &str, value: &str, [no, yes]: [&str; 2]) -> Result<bool, String> {
    match value {
        v if v == no => Ok(false),
        v if v == yes => Ok(true),
        other => Err(format!(
            "{key} = \"{other}\": must be \"{no}\" or \"{yes}\""
        )),
    }
}

/// The load curve of a spec (`key` names it in messages).
pub(super) fn parse_curve(c: &LoadCurveSpec, key: &str) -> Result<LoadCurve, String> {
    match (c.kind.as_deref().unwrap_or("ramp"), &c.table) {
        ("ramp", None) => Ok(LoadCurve::Ramp),
        ("constant", None) => Ok(LoadCurve::Constant),
        ("table", Some(t)) => {
            if t.len() < 2 {
                return Err(format!("{key}.table needs at least two points"));
            }
            if t.windows(2).any(|w| w[1][0] <= w[0][0])
                || t.iter().flatten().any(|v| !v.is_finite())
            {
                return Err(format!("{key}.table: t must increase and values be finite"));
            }
            Ok(LoadCurve::Table(t.clone()))
        }
        ("table", None) => Err(format!(
            "{key}: kind = \"table\" needs table = [[t, f], ...]"
        )),
        (k @ ("ramp" | "constant"), Some(_)) => {
            Err(format!("{key}: table given with kind = \"{k}\""))
        }
        (k, _) => Err(format!(
            "{key}.kind = \"{k}\": must be ramp, constant or table"
        )),
    }
}

/// A quadrature degree (`key` names it): 1 to 10, if given.
pub(super) fn check_quadrature_degree(key: &str, q: Option<usize>) -> Result<(), String> {
    match q {
        Some(q) if !(1..=10).contains(&q) => Err(format!("{key} = {q}: must be in 1..=10")),
        _ => Ok(()),
    }
}

/// A penalty factor (`key` names it) within [`PENALTY_RANGE`].
pub(super) fn check_penalty(key: &str, v: f64) -> Result<f64, String> {
    check_penalty_up_to(key, v, PENALTY_RANGE.1, "")
}

/// A penalty factor (`key` names it) from [`PENALTY_RANGE`]'s lower end up to `top`, the bound
/// for `what` (named in the message, after the range).
pub(super) fn check_penalty_up_to(key: &str, v: f64, top: f64, what: &str) -> Result<f64, String> {
    if (PENALTY_RANGE.0..=top).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "{key} = {v}: must lie in [{:e}, {top:e}] (a factor of E/h){what}",
            PENALTY_RANGE.0
        ))
    }
}

/// A value that must be finite and positive (`key` names it).
pub(super) fn check_positive(key: &str, v: f64) -> Result<f64, String> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{key} = {v}: must be finite and > 0"))
    }
}

/// The load stepping and the Newton settings: at least one step and at most [`MAX_STEPS`],
/// finite positive tolerances, `max_it` within `1..=MAX_NEWTON_ITS`, and a smallest cut step
/// of at least [`MIN_STEP`] of the load.
pub(super) fn check_run_settings(steps: &StepsSpec, n: &NewtonSpec) -> Result<(), String> {
    if steps.count == 0 {
        return Err("steps.count must be at least 1".into());
    }
    if !(n.rtol > 0.0 && n.atol > 0.0 && n.rtol.is_finite() && n.atol.is_finite()) {
        return Err(format!(
            "newton: rtol = {} and atol = {} must be finite and > 0",
            n.rtol, n.atol
        ));
    }
    if !(n.augmented_rtol > 0.0 && n.augmented_rtol < 1.0) {
        return Err(format!(
            "newton.augmented_rtol = {}: must be in (0, 1)",
            n.augmented_rtol
        ));
    }
    if !(1..=MAX_NEWTON_ITS).contains(&n.max_it) {
        return Err(format!(
            "newton.max_it = {}: must be in 1..={MAX_NEWTON_ITS}",
            n.max_it
        ));
    }
    if steps.count > MAX_STEPS {
        return Err(format!(
            "steps.count = {}: at most {MAX_STEPS}",
            steps.count
        ));
    }
    let smallest_step = 0.5f64.powi(steps.max_cuts.min(1100) as i32) / steps.count as f64;
    if smallest_step < MIN_STEP {
        return Err(format!(
            "steps.max_cuts = {}: with steps.count = {} the smallest step would be {smallest_step:.3e} \
             of the load, below {MIN_STEP:e} (steps near round-off would never finish the run)",
            steps.max_cuts, steps.count
        ));
    }
    Ok(())
}

/// Every value finite and within `+-MAX_MAGNITUDE`.
pub(super) fn all_within_bounds<'a>(values: impl IntoIterator<Item = &'a f64>) -> bool {
    values.into_iter().all(|&v| within_bounds(v))
}

/// The message of a value (`what`, with its key) that is not finite or beyond the bounds.
pub(super) fn out_of_bounds(what: &str) -> String {
    format!("{what} is not finite or beyond +-{MAX_MAGNITUDE:e}")
}

/// Every entry of a vector or matrix (`key` names it) finite and within `+-MAX_MAGNITUDE`.
pub(super) fn check_entries<'a>(
    key: &str,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<(), String> {
    if all_within_bounds(values) {
        Ok(())
    } else {
        Err(format!(
            "{key}: entries must be finite and within +-{MAX_MAGNITUDE:e}"
        ))
    }
}
