//! Linear solves (`KSP`) outside Newton, e.g. for predictors or projections.
//!
//! The solver is chosen in the options database, with the project's defaults (see
//! [`set_linear_solver_defaults`]); SNES uses the same defaults for its inner KSP.

use petsc_ffi as p;

use super::{chk, to_petsc_int, Matrix, PetscInt, Vector};
use crate::error::Result;

/// What one linear solve did.
#[derive(Clone, Copy, Debug)]
pub struct KspOutcome {
    /// True for a positive converged reason.
    pub converged: bool,
    /// PETSc's `KSPConvergedReason` code.
    pub reason: i32,
    /// Iterations (1 for a direct solve).
    pub iterations: usize,
}

/// A PETSc linear solver; destroyed on drop.
pub struct Ksp {
    raw: p::KSP,
}

impl Ksp {
    /// A linear solver configured from the options database (after the project's defaults for
    /// a direct solve).
    pub fn new() -> Result<Ksp> {
        super::ensure_initialized()?;
        let mut raw: p::KSP = std::ptr::null_mut();
        chk!(KSPCreate(super::comm(), &mut raw))?;
        let ksp = Ksp { raw };
        set_linear_solver_defaults(LinearPath::Direct)?;
        chk!(KSPSetFromOptions(ksp.raw))?;
        Ok(ksp)
    }

    /// Solves `a x = b` (`x` is also the initial guess for iterative solvers).
    pub fn solve(&mut self, a: &Matrix, b: &Vector, x: &mut Vector) -> Result<KspOutcome> {
        chk!(KSPSetOperators(self.raw, a.raw, a.raw))?;
        chk!(KSPSolve(self.raw, b.raw, x.raw))?;
        let mut reason = p::KSPConvergedReason(0);
        chk!(KSPGetConvergedReason(self.raw, &mut reason))?;
        let mut its: PetscInt = 0;
        chk!(KSPGetIterationNumber(self.raw, &mut its))?;
        Ok(KspOutcome {
            converged: reason.0 > 0,
            reason: reason.0,
            iterations: its.max(0) as usize,
        })
    }
}

impl Drop for Ksp {
    fn drop(&mut self) {
        if super::is_finalized() {
            return;
        }
        // SAFETY: `raw` is a valid KSP owned by this struct.
        let code = unsafe { p::KSPDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!("KSPDestroy returned error code {code}"));
        }
    }
}

/// The linear solver of the Newton steps, when the options choose none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearPath {
    /// LU through MUMPS.
    Direct,
    /// GMRES preconditioned by algebraic multigrid (GAMG, with the matrix's near null space).
    /// With `interface_split`, a multiplicative field split: the interface dofs solved exactly
    /// (LU through MUMPS), then multigrid on the other dofs
    /// ([`super::Snes::split_interface`] names the fields); with `coarse_correction` as well,
    /// a two-level preconditioner: the interface dofs by point Jacobi and multigrid on the
    /// others, then the interface coarse correction (`super::coarse`), which solves the
    /// interface dofs exactly with the multigrid's first coarse space.
    Iterative {
        interface_split: bool,
        coarse_correction: bool,
    },
}

/// The options of the iterative path ([`LinearPath::Iterative`]), each a default the user's
/// options replace.
const ITERATIVE: [(&str, &str); 4] = [
    ("-ksp_type", "gmres"),
    ("-ksp_gmres_restart", "100"),
    ("-ksp_rtol", "1e-8"),
    ("-ksp_max_it", "1000"),
];

/// Inexact Newton on the iterative path: each Newton step's linear tolerance follows the
/// Newton residual's progress (Eisenstat and Walker's second choice, PETSc's default version:
/// `rtol_k = gamma (|F_k| / |F_k-1|)^alpha`, safeguarded), here at most [`EW_RTOL_MAX`]
/// (also the first step's), instead of the fixed `-ksp_rtol`. Far from the solution, where the
/// line search cuts the step anyway, a rough direction costs a fraction of an exact one; near
/// it the tolerance falls with the residual, so the convergence stays fast. Each is a default
/// the user's `-snes_ksp_ew*` options replace.
const INEXACT_NEWTON: [(&str, &str); 3] = [
    ("-snes_ksp_ew", "true"),
    ("-snes_ksp_ew_rtol0", EW_RTOL_MAX),
    ("-snes_ksp_ew_rtolmax", EW_RTOL_MAX),
];

/// The loosest linear tolerance of [`INEXACT_NEWTON`] (docs/performance.md, "Inexact
/// Newton": the Newton and linear iterations of the refinement family at 1e-2 and 1e-3).
const EW_RTOL_MAX: &str = "1e-3";

/// The options that say whether GAMG keeps its interpolation from one set-up to the next, on
/// the whole matrix or on the interface split's bulk field. PETSc's default keeps it for as
/// long as the matrix lives (here the whole run); the iterative path instead sets the multigrid
/// up anew once per load step and keeps it whole through the step
/// ([`super::Snes::rebuild_multigrid`]), unless the user gives one of these.
pub(crate) const MULTIGRID_REUSE: [&str; 3] = [
    "-pc_gamg_reuse_interpolation",
    "-fieldsplit_bulk_pc_gamg_reuse_interpolation",
    "-sub_0_fieldsplit_bulk_pc_gamg_reuse_interpolation",
];

/// The field split of [`LinearPath::Iterative`] with interfaces. The bulk's multigrid smooths
/// once per level and direction (PETSc's default: twice): the block iteration between the two
/// fields, not the multigrid, sets the GMRES iterations, so the cheaper cycle takes as many
/// (docs/performance.md, "One smoothing sweep").
const INTERFACE_SPLIT: [(&str, &str); 8] = [
    ("-pc_type", "fieldsplit"),
    ("-pc_fieldsplit_type", "multiplicative"),
    ("-fieldsplit_interface_ksp_type", "preonly"),
    ("-fieldsplit_interface_pc_type", "lu"),
    ("-fieldsplit_interface_pc_factor_mat_solver_type", "mumps"),
    ("-fieldsplit_bulk_ksp_type", "preonly"),
    ("-fieldsplit_bulk_pc_type", "gamg"),
    ("-fieldsplit_bulk_mg_levels_ksp_max_it", "1"),
];

/// A two-level preconditioner with the interfaces in its coarse problem: the field split with
/// the interface field by point Jacobi and the bulk by one V-cycle of unsmoothed aggregation,
/// then the interface coarse correction (`super::coarse`), which solves the interfaces' dofs
/// exactly together with the bulk multigrid's first coarse space; a multiplicative composite
/// (the split's options take the prefix `sub_0_`). The correction's exact interface makes the
/// split's own LU of it unnecessary, and unsmoothed aggregation makes its coarse space sparse,
/// so that projecting the tangent onto it is cheap (docs/performance.md, "The interface coarse
/// correction"). Its LU orders by PORD, a nested dissection: on a small projection MUMPS's
/// automatic choice is AMF, whose elimination tree costs more and leaves less for the second
/// rank (docs/performance.md, "The coarse LU on two ranks").
const INTERFACE_COARSE: [(&str, &str); 12] = [
    ("-pc_type", "composite"),
    ("-pc_composite_type", "multiplicative"),
    ("-pc_composite_pcs", "fieldsplit,shell"),
    ("-sub_0_pc_fieldsplit_type", "multiplicative"),
    ("-sub_0_fieldsplit_interface_ksp_type", "preonly"),
    ("-sub_0_fieldsplit_interface_pc_type", "jacobi"),
    ("-sub_0_fieldsplit_bulk_ksp_type", "preonly"),
    ("-sub_0_fieldsplit_bulk_pc_type", "gamg"),
    ("-sub_0_fieldsplit_bulk_pc_gamg_agg_nsmooths", "0"),
    ("-sub_0_fieldsplit_bulk_mg_levels_ksp_max_it", "1"),
    ("-sub_1_coarse_mat_mumps_icntl_24", "1"),
    ("-sub_1_coarse_mat_mumps_icntl_7", "4"),
];

/// Every option [`set_linear_solver_defaults`] may set (restored after each run of a study:
/// `options::Override`).
pub(crate) fn defaulted_options() -> impl Iterator<Item = &'static str> {
    ["-pc_factor_mat_solver_type", "-mat_mumps_icntl_24"]
        .into_iter()
        .chain(
            ITERATIVE
                .iter()
                .chain(&INEXACT_NEWTON)
                .chain(&INTERFACE_SPLIT)
                .chain(&INTERFACE_COARSE)
                .map(|o| o.0),
        )
}

/// The default linear solver, as option defaults so that any user choice replaces it whole:
/// with neither `-ksp_type` nor `-pc_type` given, `path`: a direct solve (`preonly`, `lu`,
/// MUMPS, with null-pivot detection), or the iterative path; with only `-pc_type`, GMRES
/// around it; with only `-ksp_type`, LU through MUMPS inside it.
pub(crate) fn set_linear_solver_defaults(path: LinearPath) -> Result<()> {
    use super::options::{has, set_default};
    let (ksp, pc) = (has("-ksp_type")?, has("-pc_type")?);
    if let (
        false,
        false,
        LinearPath::Iterative {
            interface_split,
            coarse_correction,
        },
    ) = (ksp, pc, path)
    {
        for (name, value) in ITERATIVE.into_iter().chain(INEXACT_NEWTON) {
            set_default(name, value)?;
        }
        if interface_split && coarse_correction {
            for (name, value) in INTERFACE_COARSE {
                set_default(name, value)?;
            }
        } else if interface_split {
            for (name, value) in INTERFACE_SPLIT {
                set_default(name, value)?;
            }
        } else {
            set_default("-pc_type", "gamg")?;
        }
        return Ok(());
    }
    if !pc {
        set_default("-pc_type", "lu")?;
        set_default("-pc_factor_mat_solver_type", "mumps")?;
        // Null-pivot detection: a singular tangent (a body free to move rigidly) is reported
        // (`Snes::null_pivots`) instead of silently solved.
        set_default("-mat_mumps_icntl_24", "1")?;
    }
    if !ksp {
        set_default("-ksp_type", if pc { "gmres" } else { "preonly" })?;
    }
    Ok(())
}

/// The preconditioners whose set-up [`probe_factorization`] checks: factorizations, whose set-up
/// works on any nonsingular matrix.
const FACTORIZATIONS: [&str; 4] = ["lu", "cholesky", "ilu", "icc"];

/// True when `pc_type` (a `PCGetType` name) is one [`probe_factorization`] checks.
pub(crate) fn is_probed_factorization(pc_type: &str) -> bool {
    FACTORIZATIONS.contains(&pc_type)
}

/// Sets up a linear solver of the options database on a small SPD matrix (tridiagonal 2, -1,
/// 3 rows per rank, coupled across the ranks), so that what PETSc reads only when it first
/// factorizes fails here, on every rank alike and before the first step, instead of in the
/// middle of a solve (where an error may be one rank's, and ends the job): a solver package
/// that does not exist or does not take this matrix type (`-pc_factor_mat_solver_type`,
/// `-pc_type ilu` on 2 ranks), a malformed package option (`-mat_mumps_icntl_8 xyz`). For the
/// factorizations only ([`is_probed_factorization`]; the caller checks): another
/// preconditioner may need more than a matrix (fields, coordinates) to be set up. Viewers the
/// options ask for (`-mat_view`, MUMPS's own output) see this matrix too. Collective; the
/// errors it finds are those of the options, the same on every rank.
pub(crate) fn probe_factorization() -> Result<()> {
    let ksp = Ksp::new()?;
    let mut raw: p::Mat = std::ptr::null_mut();
    chk!(MatCreate(super::comm(), &mut raw))?;
    let mut probe = Matrix { raw };
    let rows = to_petsc_int(3)?;
    chk!(MatSetSizes(
        probe.raw,
        rows,
        rows,
        p::PETSC_DETERMINE,
        p::PETSC_DETERMINE
    ))?;
    chk!(MatSetType(probe.raw, c"aij".as_ptr()))?;
    // Both calls are made; PETSc ignores the one that does not match the actual type.
    chk!(MatSeqAIJSetPreallocation(probe.raw, 3, std::ptr::null()))?;
    chk!(MatMPIAIJSetPreallocation(
        probe.raw,
        3,
        std::ptr::null(),
        2,
        std::ptr::null()
    ))?;
    let (mut lo, mut hi, mut n): (PetscInt, PetscInt, PetscInt) = (0, 0, 0);
    chk!(MatGetOwnershipRange(probe.raw, &mut lo, &mut hi))?;
    chk!(MatGetSize(probe.raw, &mut n, std::ptr::null_mut()))?;
    for row in lo..hi {
        for (col, value) in [(row - 1, -1.0), (row, 2.0), (row + 1, -1.0)] {
            if (0..n).contains(&col) {
                chk!(MatSetValues(
                    probe.raw,
                    1,
                    &row,
                    1,
                    &col,
                    &value,
                    p::InsertMode::INSERT_VALUES
                ))?;
            }
        }
    }
    probe.assemble()?;
    chk!(KSPSetOperators(ksp.raw, probe.raw, probe.raw))?;
    chk!(KSPSetUp(ksp.raw))
}
