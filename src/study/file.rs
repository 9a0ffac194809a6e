//! The study file: its keys (each documented where it is declared: [`StudyFile`],
//! [`RefinementSpec`], [`VariantSpec`], [`CurvesSpec`]; unknown keys are errors), and loading
//! and validating it into a [`Study`].
//!
//! ```toml
//! case = "case.toml"                 # the base scene, relative to the study file
//! metric = "energy_error"            # the summary metric measured against h
//! title = "Thick sphere"             # plot title (optional)
//!
//! [[refinement]]                     # at least 1 (2 or more for a slope)
//! h = 0.5                            # mesh size for the x axis
//! set = { "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2 }
//!
//! [[variant]]                        # at least 1
//! name = "hex20"                     # in file names and metric names: slope_<name>
//! set = { "mesh.0.element" = "hex20" }
//! ```
//!
//! A study of load curves, such as the force-displacement curves of sliding blocks (one
//! refinement, four variants; `metric` is still recorded per run in `study.csv`):
//!
//! ```toml
//! case = "case.toml"
//! metric = "slip_force_ratio"
//! title = "Sliding blocks: tangential reaction"
//!
//! [[refinement]]
//! h = 1.0
//!
//! [[variant]]
//! name = "case1"
//! [[variant]]
//! name = "case2"
//! set = { "interface.0.passes" = 1 }
//!
//! [curves]                           # compare history.csv curves of the variants
//! x = "u_upper.zmax_x"               # history.csv columns
//! y = "reaction_upper.zmax_x"
//! x_label = "prescribed displacement"  # axis labels (default: the column names)
//! y_label = "tangential force"
//! reference = "case1"                # the variant the others are compared with
//! after = 0.0                        # compare only points with x > after
//! abs = true                         # plot and compare |y|
//! ```
//!
//! Before any run, every variant x refinement is built and validated (paths, case keys, mesh),
//! so a mistake in the last variant is reported at once, not after the first runs. Every run
//! shares one PETSc ([`crate::study::one_run`]), so no variant may change `petsc_options`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::curves::Curves;
use super::edits::{apply_sets, edits};
use crate::case::Scene;
use crate::error::{Error, Result};
use crate::io::case_file::one_line;

/// The study file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// The base scene: a case file, relative to the study file.
    pub case: String,
    /// The metric of the runs' `summary.json` measured against h (`energy_error` for the Lamé
    /// sphere), or a list of metrics whose largest absolute value is the run's error (a patch
    /// test measures both the stress and the penetration: `["max_rel_stress_error",
    /// "max_rel_penetration_blocks"]`, named `max(max_rel_stress_error, ...)` in the outputs).
    pub metric: MetricSpec,
    /// Plot title (of both plots). Default: `<scene name>: <metric>` for the convergence plot,
    /// `<scene name>: <y label>` for the curves.
    pub title: Option<String>,
    /// Mesh refinements, at least 1, each with its mesh size: 2 or more give each variant a
    /// convergence slope and the convergence plot; 1 is a sweep of the variants on one mesh
    /// (the Pareto front and the expectations work alike).
    #[serde(default)]
    pub refinement: Vec<RefinementSpec>,
    /// Variants (element types, schemes, ...), at least 1: each is run at every refinement.
    #[serde(default)]
    pub variant: Vec<VariantSpec>,
    /// Curves of the runs' load histories to plot and compare between variants (see
    /// [`crate::study::curves`]). Default: none.
    pub curves: Option<CurvesSpec>,
    /// Errors at or below this value count as equal on the Pareto front (round-off: a patch
    /// test's runs are all exact, and the fastest of them is the one to pick). Finite, >= 0.
    /// Default 0.
    #[serde(default)]
    pub error_floor: f64,
    /// Errors within this fraction of each other (of the larger) count as equal on the Pareto
    /// front: differences far below any discretization error, such as the same integrals
    /// summed in another order, or two quadratures that agree to 12 digits, where the slower
    /// run would otherwise stay on the front by an error smaller in the last digits. Finite, in
    /// [0, 1). Default 1e-9.
    #[serde(default = "default_error_noise")]
    pub error_noise: f64,
    /// How many times each run is made: its wall time is the fastest of them (noise from other
    /// work on the machine only ever adds time), its other results those of the first, whose
    /// outputs stay in `runs/` (the repeats write to `runs/<variant>/<level>.repeat/`, removed
    /// afterwards). A repeat counts only when it converges in as many Newton iterations as the
    /// first (on more than one rank round-off of the parallel solve may take another path).
    /// `study.csv` gives the slowest time too. Reference variants (`reference_only`, the
    /// `[curves]` reference), whose times are not compared, run once. From 1 to 10. Default 1.
    #[serde(default = "default_repeat")]
    pub repeat: usize,
    /// Wall times within this fraction of each other count as equal on the Pareto front: the
    /// machine's noise (two runs that do the same work differ by a few per cent, and the
    /// faster of them would otherwise push the other off the front). Finite, in [0, 1).
    /// Default 0.
    #[serde(default)]
    pub time_noise: f64,
    /// Checks on the study's summary metrics (`slope_* >= 1.9`; see `crate::expect`): printed
    /// with their measured values after the study, which fails when one does not hold.
    /// Default: none.
    #[serde(default)]
    pub expect: Vec<String>,
    /// For a metric that is a value, not an error (a peak pressure, a tip displacement, with no
    /// exact value to compare with): the variant whose run at the finest refinement (the
    /// smallest h) is the truth. Every other run's error is then `|m - m_ref| / |m_ref|`, its
    /// metric's relative difference to that run's; the reference run itself has no error (not
    /// on the plots or the front). One metric, not a list. Not with `[curves]`, whose
    /// `reference` plays this part. Default: none (the metric is an error).
    pub finest_reference: Option<String>,
}

/// The most runs `repeat` may ask for each variant and level.
const MAX_REPEAT: usize = 10;

/// `repeat` when the study file does not set it.
fn default_repeat() -> usize {
    1
}

/// `error_noise` when the study file does not set it: errors that agree to nine digits are the
/// same error for every metric a study measures.
fn default_error_noise() -> f64 {
    1e-9
}

/// The study's `metric`: one name, or several whose largest absolute value is the error.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged, expecting = "a metric name or a list of metric names")]
pub enum MetricSpec {
    One(String),
    Largest(Vec<String>),
}

impl MetricSpec {
    /// The metric names.
    fn names(&self) -> Vec<String> {
        match self {
            MetricSpec::One(m) => vec![m.clone()],
            MetricSpec::Largest(ms) => ms.clone(),
        }
    }
}

/// The `[curves]` table: one curve per variant, from the `history.csv` of its run at the last
/// refinement level, plotted in `curves.png`/`curves.svg` and compared with the reference
/// variant's (`curve_max_rel_diff_<variant>` in the study summary; see
/// [`crate::study::curves`]). A run that failed or diverged is plotted with the points it has
/// (its converged steps) and compared over the overlap.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurvesSpec {
    /// The `history.csv` column of the x axis, e.g. `u_upper.zmax_x` (the mean displacement of
    /// a constrained set along x). A column the runs do not write is an error listing those they
    /// do.
    pub x: String,
    /// The `history.csv` column of the y axis, e.g. `reaction_upper.zmax_z` (the reaction force
    /// on a constrained set along z).
    pub y: String,
    /// The x axis label. Default: the column name `x`.
    pub x_label: Option<String>,
    /// The y axis label. Default: the column name `y` (as `|y|` with `abs`).
    pub y_label: Option<String>,
    /// The name of the variant the others are compared with (must be one of the variants).
    pub reference: String,
    /// Compare only the points with x > `after` (e.g. 0 to leave out a first phase in which x
    /// stays 0); the plot shows every point. Default: -infinity (every point).
    pub after: Option<f64>,
    /// Plot and compare |y| instead of y (a compressive reaction is negative). Default: false.
    #[serde(default)]
    pub abs: bool,
    /// The name of the comparison metrics, `<metric>_<variant>` in the study summary (e.g.
    /// `tip_rel_diff` for a beam's tip). Letters, digits and `_`. Default: `curve_max_rel_diff`.
    pub metric: Option<String>,
}

/// One mesh refinement.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefinementSpec {
    /// Mesh size (the plot's x axis and the slope's h), finite and > 0, different for every
    /// refinement.
    pub h: f64,
    /// Edits of the case: dotted path = value (see [`crate::study::edits`]). Applied after the
    /// variant's. Default: none.
    #[serde(default)]
    pub set: toml::Table,
}

/// One variant of the scene.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariantSpec {
    /// Name: letters, digits, `_` and `-`, unique; used in file names (`runs/<name>/`) and metric
    /// names (`slope_<name>`).
    pub name: String,
    /// Edits of the case: dotted path = value (see [`crate::study::edits`]). Default: none.
    #[serde(default)]
    pub set: toml::Table,
    /// Edits per refinement level, applied last (after the refinement's own `set`): one table
    /// per refinement, for a variant whose mesh follows the level differently (e.g. a
    /// conforming mesh where the others are dissimilar). Default: none.
    #[serde(default)]
    pub refinement_set: Vec<toml::Table>,
    /// A baseline expected to break (node-on-segment in the paper's Figure 7): when its run
    /// fails, the failure is recorded, plotted and reported as for any run, but does not make
    /// the study fail. Default false.
    #[serde(default)]
    pub may_fail: bool,
    /// Shown for comparison but not a choice of the scene's settings (a conforming mesh where
    /// the scene is about dissimilar ones): its runs are plotted but never on the Pareto front.
    /// Default false.
    #[serde(default)]
    pub reference_only: bool,
    /// PETSc options of this variant's runs, written as on the command line
    /// (`"-ksp_type gmres -pc_type gamg"`): put into PETSc's options database for its runs
    /// only, over the options file and the command line, and restored after each run.
    /// Default: none.
    pub petsc: Option<String>,
    /// Runs this variant on the first `ranks` ranks of the study's job only (from 1 to the
    /// number of ranks the study runs on; the other ranks wait), so that one study measures
    /// the speedup: `mpirun -n 2 mortar study` with variants `ranks = 1` and `ranks = 2`.
    /// Default: every rank of the job.
    pub ranks: Option<usize>,
}

impl VariantSpec {
    /// The scene's own settings: no edits, no PETSc options, every rank, a choice (not
    /// `reference_only`). The study's first such variant is its defaults (`default_on_front`).
    pub fn is_default(&self) -> bool {
        self.set.is_empty()
            && self.refinement_set.is_empty()
            && self.petsc.is_none()
            && self.ranks.is_none()
            && !self.reference_only
    }
}

/// A validated study.
#[derive(Clone, Debug)]
pub struct Study {
    /// Study name, `<folder>_<stem>` of the study file (`hertz_study` for
    /// `cases/hertz/study.toml`): `case` in its summary, the default output folder.
    pub name: String,
    /// The study file.
    pub file: PathBuf,
    /// The base case file.
    pub case: PathBuf,
    /// The error's name in the outputs: the metric, or `max(a, b, ...)`.
    pub metric: String,
    /// The summary metrics whose largest absolute value is a run's error.
    pub metric_parts: Vec<String>,
    pub title: String,
    pub refinements: Vec<RefinementSpec>,
    pub variants: Vec<VariantSpec>,
    /// Each variant's own PETSc options (`VariantSpec::petsc`), parsed: names and values.
    pub variant_options: Vec<PetscOptions>,
    /// The PETSc options file of the base case (shared by every run).
    pub petsc_options: Option<PathBuf>,
    /// The `[curves]` table, validated.
    pub curves: Option<Curves>,
    /// Errors at or below this count as equal on the Pareto front (`error_floor`).
    pub error_floor: f64,
    /// Relative error differences at or below this count as equal (`error_noise`).
    pub error_noise: f64,
    /// Runs per variant and level, the fastest timed (`repeat`).
    pub repeat: usize,
    /// Relative wall-time differences at or below this count as equal (`time_noise`).
    pub time_noise: f64,
    /// Checks on the study's metrics (`expect`).
    pub expectations: Vec<crate::expect::Expectation>,
    /// The variant whose finest run is the truth (`finest_reference`), validated.
    pub finest_reference: Option<String>,
}
impl Study {
    /// Reads a study file and validates it, with every variant x refinement of its case
    /// (paths, keys, mesh). Errors name the study file and the key.
    pub fn load(path: &Path) -> Result<Study> {
        let err = |msg: String| Error::Case {
            file: path.to_path_buf(),
            msg,
        };
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let file: StudyFile = toml::from_str(&text).map_err(|e| err(one_line(&e.to_string())))?;
        let metric_parts = file.metric.names();
        check_keys(&file, &metric_parts).map_err(err)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let case = dir.join(&file.case);
        if !case.is_file() {
            return Err(err(format!(
                "case = \"{}\": no such file {}",
                file.case,
                case.display()
            )));
        }

        // The paths, against the case as written: errors name the study key.
        let case_text = std::fs::read_to_string(&case).map_err(|e| Error::io(&case, e))?;
        let base: toml::Table = toml::from_str(&case_text).map_err(|e| Error::Case {
            file: case.clone(),
            msg: one_line(&e.to_string()),
        })?;
        check_edits(&file, &base).map_err(err)?;
        let variant_options = variant_options(&file).map_err(err)?;
        let mut study = Study {
            name: study_name(path),
            variant_options,
            file: path.to_path_buf(),
            case,
            metric: match metric_parts.as_slice() {
                [one] => one.clone(),
                many => format!("max({})", many.join(", ")),
            },
            metric_parts,
            title: String::new(),
            refinements: file.refinement,
            variants: file.variant,
            petsc_options: None,
            curves: None,
            error_floor: file.error_floor,
            error_noise: file.error_noise,
            repeat: file.repeat,
            time_noise: file.time_noise,
            expectations: crate::expect::parse_all("expect", &file.expect).map_err(err)?,
            finest_reference: file.finest_reference,
        };
        // Every run's scene, built and dropped one at a time.
        let base_scene = Scene::load(&study.case)?;
        study.petsc_options = base_scene.petsc_options.clone();
        study.curves = file
            .curves
            .map(|c| Curves::new(c, file.title.as_deref(), &base_scene.name));
        study.title = file
            .title
            .unwrap_or_else(|| format!("{}: {}", base_scene.name, study.metric));
        drop(base_scene);
        study.check_scenes()?;
        Ok(study)
    }

    /// Builds every run's scene (one at a time), each of which must keep the base case's
    /// `petsc_options`.
    fn check_scenes(&self) -> Result<()> {
        for i in 0..self.variants.len() {
            for j in 0..self.refinements.len() {
                let scene = self.scene(i, j)?;
                if scene.petsc_options != self.petsc_options {
                    return Err(Error::Case {
                        file: self.file.clone(),
                        msg: format!(
                            "variant '{}' at refinement[{j}] changes petsc_options: every run of \
                             a study shares one PETSc (give options on the command line or in \
                             the variant's petsc key instead)",
                            self.variants[i].name
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    /// The scene of variant `v` at refinement `level`; errors name the study, the variant and
    /// the refinement.
    pub fn scene(&self, v: usize, level: usize) -> Result<Scene> {
        let (variant, refinement) = (&self.variants[v], &self.refinements[level]);
        let sets = edits(v, variant, level, refinement);
        Scene::load_edited(&self.case, |t| apply_sets(t, &sets)).map_err(|e| Error::Case {
            file: self.file.clone(),
            msg: format!("variant '{}' at refinement[{level}]: {e}", variant.name),
        })
    }

    /// How many runs the study makes: every variant at every refinement.
    pub(super) fn total_runs(&self) -> usize {
        self.variants.len() * self.refinements.len()
    }
}

/// The checks of the study file's own keys (not against its case), in the order of the keys;
/// the message of the first that fails.
fn check_keys(file: &StudyFile, metric_parts: &[String]) -> std::result::Result<(), String> {
    if metric_parts.is_empty() || metric_parts.iter().any(|m| m.trim().is_empty()) {
        return Err("metric: empty".into());
    }
    if !(file.error_floor.is_finite() && file.error_floor >= 0.0) {
        return Err(format!(
            "error_floor = {}: must be finite and >= 0",
            file.error_floor
        ));
    }
    if !(1..=MAX_REPEAT).contains(&file.repeat) {
        return Err(format!(
            "repeat = {}: must be from 1 to {MAX_REPEAT}",
            file.repeat
        ));
    }
    check_fraction("error_noise", file.error_noise)?;
    check_fraction("time_noise", file.time_noise)?;
    check_refinements(&file.refinement)?;
    let names = check_variants(&file.variant)?;
    if let Some(r) = &file.finest_reference {
        check_finest_reference(file, r, &names, metric_parts)?;
    }
    if let Some(c) = &file.curves {
        check_curves(file, c, &names)?;
    }
    Ok(())
}

/// A fraction key (`error_noise`, `time_noise`): finite, in [0, 1).
fn check_fraction(key: &str, value: f64) -> std::result::Result<(), String> {
    if value.is_finite() && (0.0..1.0).contains(&value) {
        Ok(())
    } else {
        Err(format!("{key} = {value}: must be finite, >= 0 and < 1"))
    }
}

/// At least one refinement, each h finite, positive and its own.
fn check_refinements(refinements: &[RefinementSpec]) -> std::result::Result<(), String> {
    if refinements.is_empty() {
        return Err("refinement: at least 1 is needed, found none".into());
    }
    for (i, r) in refinements.iter().enumerate() {
        if !(r.h.is_finite() && r.h > 0.0) {
            return Err(format!(
                "refinement[{i}].h = {}: must be finite and > 0",
                r.h
            ));
        }
        if let Some(j) = refinements[..i].iter().position(|o| o.h == r.h) {
            return Err(format!(
                "refinement[{i}].h = {} repeats refinement[{j}].h",
                r.h
            ));
        }
    }
    Ok(())
}

/// At least one variant, each with a name of its own that can name folders and metrics, and
/// no `ranks = 0`; returns the names.
fn check_variants(variants: &[VariantSpec]) -> std::result::Result<BTreeSet<&str>, String> {
    if variants.is_empty() {
        return Err("variant: at least 1 is needed, found none".into());
    }
    let mut names = BTreeSet::new();
    for (i, v) in variants.iter().enumerate() {
        let ok = !v.name.is_empty()
            && v.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !ok {
            return Err(format!(
                "variant[{i}].name = \"{}\": use letters, digits, '_' and '-' (it names \
                 folders and metrics)",
                v.name
            ));
        }
        if v.ranks == Some(0) {
            return Err(format!("variant[{i}].ranks = 0: at least 1"));
        }
        if !names.insert(v.name.as_str()) {
            return Err(format!("variant[{i}].name = \"{}\" is used twice", v.name));
        }
    }
    Ok(names)
}

/// `finest_reference = reference`: one metric, not with `[curves]`, one of the variants.
fn check_finest_reference(
    file: &StudyFile,
    reference: &str,
    names: &BTreeSet<&str>,
    metric_parts: &[String],
) -> std::result::Result<(), String> {
    if metric_parts.len() > 1 {
        return Err(format!(
            "finest_reference = \"{reference}\": needs one metric, not a list (the largest of \
             several values is no value to compare)"
        ));
    }
    if file.curves.is_some() {
        return Err(format!(
            "finest_reference = \"{reference}\": not with [curves] (curves.reference is the \
             truth there)"
        ));
    }
    if !names.contains(reference) {
        return Err(no_such_variant("finest_reference", reference, file));
    }
    Ok(())
}

/// The `[curves]` table: columns named, a reference among the variants, a metric name of
/// letters, digits and `_`, an `after` that is a number.
fn check_curves(
    file: &StudyFile,
    c: &CurvesSpec,
    names: &BTreeSet<&str>,
) -> std::result::Result<(), String> {
    for (key, column) in [("x", &c.x), ("y", &c.y)] {
        if column.trim().is_empty() {
            return Err(format!("curves.{key}: empty (a history.csv column)"));
        }
    }
    if !names.contains(c.reference.as_str()) {
        return Err(no_such_variant("curves.reference", &c.reference, file));
    }
    if let Some(m) = &c.metric {
        let ok = !m.is_empty() && m.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_');
        if !ok {
            return Err(format!(
                "curves.metric = \"{m}\": letters, digits and _ only"
            ));
        }
    }
    if c.after.is_some_and(f64::is_nan) {
        return Err("curves.after: not a number".into());
    }
    Ok(())
}

/// The message for a key that names a variant the study does not have.
fn no_such_variant(key: &str, name: &str, file: &StudyFile) -> String {
    let variants: Vec<&str> = file.variant.iter().map(|v| v.name.as_str()).collect();
    format!(
        "{key} = \"{name}\": no such variant (variants: {})",
        variants.join(", ")
    )
}

/// Every variant's `refinement_set` has a table per refinement, and every run's edits reach
/// their paths in the case as written (`base`).
fn check_edits(file: &StudyFile, base: &toml::Table) -> std::result::Result<(), String> {
    for (i, v) in file.variant.iter().enumerate() {
        if !v.refinement_set.is_empty() && v.refinement_set.len() != file.refinement.len() {
            return Err(format!(
                "variant[{i}].refinement_set has {} tables for {} refinements",
                v.refinement_set.len(),
                file.refinement.len()
            ));
        }
        for (j, r) in file.refinement.iter().enumerate() {
            let mut t = base.clone();
            apply_sets(&mut t, &edits(i, v, j, r))?;
        }
    }
    Ok(())
}

/// PETSc options, parsed: names and values.
pub type PetscOptions = Vec<(String, Option<String>)>;

/// Each variant's `petsc` options, parsed.
fn variant_options(file: &StudyFile) -> std::result::Result<Vec<PetscOptions>, String> {
    file.variant
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let given = v.petsc.as_deref().unwrap_or("");
            crate::petsc::options::parse(given)
                .map_err(|m| format!("variant[{i}].petsc = \"{given}\": {m}"))
        })
        .collect()
}

/// A study's name: the study file's folder and stem, `<folder>_<stem>`
/// (`cases/sliding_blocks/study_quadrature.toml` is `sliding_blocks_study_quadrature`), or the
/// stem alone for a file without a named folder. The folder keeps the default output folders
/// (`out/<name>`) of different scenes' `study.toml` apart.
fn study_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
    // The real folder (`..` resolved) of the file, which exists once the study is read.
    let folder = std::fs::canonicalize(path)
        .or_else(|_| std::path::absolute(path))
        .ok()
        .and_then(|p| Some(p.parent()?.file_name()?.to_string_lossy().into_owned()));
    match folder {
        Some(folder) => format!("{folder}_{stem}"),
        None => stem,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default study names: the study file's folder and stem; the folder of a relative
    /// path with `..` is the real one.
    #[test]
    fn study_names_carry_their_folder() {
        let name = |p: &str| study_name(Path::new(p));
        assert_eq!(name("cases/hertz/study.toml"), "hertz_study");
        assert_eq!(
            name("/x/sliding_blocks/study_uzawa.toml"),
            "sliding_blocks_study_uzawa"
        );
        assert_eq!(name("/study.toml"), "study");
        // This file exists: `src/../src/lib.rs` is in the folder `src`.
        let up = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/../src/lib.rs");
        assert_eq!(study_name(&up), "src_lib");
    }

    /// A study file that says nothing of them: errors within 1e-9 relative are equal, exact
    /// times only, one run each.
    #[test]
    fn study_file_defaults() {
        let file: StudyFile = toml::from_str("case = \"case.toml\"\nmetric = \"e\"\n").unwrap();
        assert_eq!(file.error_noise, 1e-9);
        assert_eq!(
            (file.error_floor, file.time_noise, file.repeat),
            (0.0, 0.0, 1)
        );
    }
}
