//! Expectations: checks a case or a study declares on its own metrics, for users' CI (and the
//! project's own).
//!
//! A case file or a study file may list
//!
//! ```toml
//! expect = ["max_newton_its <= 8", "slope_* >= 1.9", "energy_error < 1e-3"]
//! ```
//!
//! Each entry is `<metric> <op> <number>` with `op` one of `<=`, `>=`, `<`, `>`, `==`; the
//! metric may hold `*` wildcards (any run of characters), and then every metric of the summary
//! it matches must satisfy the comparison, and at least one must match. After `mortar run`
//! (against the run's `summary.json` metrics) or `mortar study` (against the study's), every
//! expectation is printed with its measured values, and the command exits with an error when
//! one fails. A NaN never satisfies a comparison.

use std::collections::BTreeMap;
use std::fmt;

/// A comparison of an expectation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    Le,
    Ge,
    Lt,
    Gt,
    Eq,
}

impl Op {
    const ALL: [(&'static str, Op); 5] = [
        ("<=", Op::Le),
        (">=", Op::Ge),
        ("==", Op::Eq),
        ("<", Op::Lt),
        (">", Op::Gt),
    ];

    fn holds(self, v: f64, bound: f64) -> bool {
        match self {
            Op::Le => v <= bound,
            Op::Ge => v >= bound,
            Op::Lt => v < bound,
            Op::Gt => v > bound,
            Op::Eq => v == bound,
        }
    }

    fn symbol(self) -> &'static str {
        Op::ALL
            .iter()
            .find(|(_, o)| *o == self)
            .map_or("?", |(s, _)| s)
    }
}

/// One declared expectation.
#[derive(Clone, Debug, PartialEq)]
pub struct Expectation {
    /// Metric name, possibly with `*` wildcards.
    pub pattern: String,
    pub op: Op,
    pub bound: f64,
    /// The bound as written (for messages).
    pub bound_text: String,
}

impl fmt::Display for Expectation {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "{} {} {}",
            self.pattern,
            self.op.symbol(),
            self.bound_text
        )
    }
}

/// What one expectation found.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub expectation: Expectation,
    /// The matching metrics and their values.
    pub measured: Vec<(String, f64)>,
    /// Every matching metric satisfies it, and one at least matches.
    pub met: bool,
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let values: Vec<String> = self
            .measured
            .iter()
            .map(|(k, v)| format!("{k} = {v:.6e}"))
            .collect();
        write!(
            f,
            "expect {}: {} -> {}",
            self.expectation,
            if values.is_empty() {
                "no such metric".to_string()
            } else {
                values.join(", ")
            },
            if self.met { "ok" } else { "FAILED" }
        )
    }
}

impl Expectation {
    /// Parses `<metric> <op> <number>`; the error says what is wrong with `text`.
    pub fn parse(text: &str) -> Result<Expectation, String> {
        let (at, sym, op) = Op::ALL
            .iter()
            .filter_map(|&(sym, op)| text.find(sym).map(|at| (at, sym, op)))
            .min_by_key(|&(at, sym, _)| (at, std::cmp::Reverse(sym.len())))
            .ok_or_else(|| format!("\"{text}\": no comparison (one of <=, >=, <, >, ==)"))?;
        let pattern = text[..at].trim();
        let number = text[at + sym.len()..].trim();
        let valid = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-' | '*');
        if pattern.is_empty() || !pattern.chars().all(valid) {
            return Err(format!(
                "\"{text}\": the metric name must be letters, digits, _ . - and * wildcards"
            ));
        }
        let bound: f64 = number
            .parse()
            .ok()
            .filter(|b: &f64| b.is_finite())
            .ok_or_else(|| format!("\"{text}\": \"{number}\" is not a finite number"))?;
        Ok(Expectation {
            pattern: pattern.to_string(),
            op,
            bound,
            bound_text: number.to_string(),
        })
    }

    /// Checks the expectation against `metrics`.
    pub fn check(&self, metrics: &BTreeMap<String, f64>) -> Outcome {
        let measured: Vec<(String, f64)> = metrics
            .iter()
            .filter(|(k, _)| matches(&self.pattern, k))
            .map(|(k, v)| (k.clone(), *v))
            .collect();
        let met =
            !measured.is_empty() && measured.iter().all(|(_, v)| self.op.holds(*v, self.bound));
        Outcome {
            expectation: self.clone(),
            measured,
            met,
        }
    }
}

/// Parses a list of expectations, naming `key` and the entry in an error.
pub fn parse_all(key: &str, texts: &[String]) -> Result<Vec<Expectation>, String> {
    texts
        .iter()
        .enumerate()
        .map(|(i, t)| Expectation::parse(t).map_err(|e| format!("{key}[{i}] = {e}")))
        .collect()
}

/// Checks every expectation; the outcomes, and a one-line error listing the failed ones (if
/// any).
pub fn check_all(
    expectations: &[Expectation],
    metrics: &BTreeMap<String, f64>,
) -> (Vec<Outcome>, Option<String>) {
    let outcomes: Vec<Outcome> = expectations.iter().map(|e| e.check(metrics)).collect();
    let failed: Vec<String> = outcomes
        .iter()
        .filter(|o| !o.met)
        .map(|o| o.expectation.to_string())
        .collect();
    let error = (!failed.is_empty()).then(|| {
        format!(
            "{} of {} expectation(s) failed: {}",
            failed.len(),
            outcomes.len(),
            failed.join("; ")
        )
    });
    (outcomes, error)
}

/// `*`-wildcard match of the whole `name`.
fn matches(pattern: &str, name: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !name.starts_with(first) || name.len() < first.len() + last.len() || !name.ends_with(last) {
        return false;
    }
    let mut rest = &name[first.len()..name.len() - last.len()];
    for mid in &parts[1..parts.len() - 1] {
        match rest.find(mid) {
            Some(at) => rest = &rest[at + mid.len()..],
            None => return false,
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn parses_every_comparison() {
        for (text, op) in [
            ("a <= 1", Op::Le),
            ("a>=1", Op::Ge),
            ("a < 1", Op::Lt),
            ("a > 1e-3", Op::Gt),
            ("a == 2", Op::Eq),
        ] {
            let e = Expectation::parse(text).unwrap();
            assert_eq!((e.pattern.as_str(), e.op), ("a", op), "{text}");
        }
        assert_eq!(Expectation::parse("slope_* >= 1.9").unwrap().bound, 1.9);
    }

    #[test]
    fn bad_expectations_say_why() {
        for (text, what) in [
            ("a 1", "no comparison"),
            ("<= 1", "metric name"),
            ("a b <= 1", "metric name"),
            ("a <= x", "not a finite number"),
            ("a <= nan", "not a finite number"),
        ] {
            let e = Expectation::parse(text).unwrap_err();
            assert!(e.contains(what), "{text}: {e}");
        }
        let e = parse_all("expect", &["a <= 1".into(), "b".into()]).unwrap_err();
        assert!(e.starts_with("expect[1] = "), "{e}");
    }

    #[test]
    fn wildcards_match_whole_names() {
        assert!(matches("slope_*", "slope_a"));
        assert!(matches("*_a", "slope_a"));
        assert!(matches("s*e_*a", "slope_a"));
        assert!(!matches("slope_*", "error_a"));
        assert!(!matches("slope", "slope_a"));
        assert!(!matches("a*a", "a"));
    }

    #[test]
    fn checks_every_match_and_needs_one() {
        let m = metrics(&[("slope_a", 2.0), ("slope_b", 1.8), ("its", f64::NAN)]);
        let e = Expectation::parse("slope_* >= 1.9").unwrap();
        let o = e.check(&m);
        assert!(!o.met);
        assert_eq!(o.measured.len(), 2);
        assert!(Expectation::parse("slope_* >= 1.7").unwrap().check(&m).met);
        assert!(!Expectation::parse("missing <= 1").unwrap().check(&m).met);
        assert!(!Expectation::parse("its <= 8").unwrap().check(&m).met);
        let (outcomes, error) = check_all(
            &[
                Expectation::parse("slope_a == 2").unwrap(),
                Expectation::parse("slope_b > 1.9").unwrap(),
            ],
            &m,
        );
        assert!(outcomes[0].met && !outcomes[1].met);
        assert_eq!(
            error.as_deref(),
            Some("1 of 2 expectation(s) failed: slope_b > 1.9")
        );
        assert_eq!(
            outcomes[1].to_string(),
            "expect slope_b > 1.9: slope_b = 1.800000e0 -> FAILED"
        );
    }
}
