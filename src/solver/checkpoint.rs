//! Checkpoints, and runs restarted from them.
//!
//! With `output.checkpoint_every = N`, every N-th finished step, and the last finished step of
//! the run (complete, stopped by a signal, or given up), leaves in `<out>/checkpoint/` one file
//! per rank, `step_<k>_r<rank>.ckpt` ([`crate::io::checkpoint`]), holding what the next step
//! needs:
//!
//! - what identifies the run: the program version and the layout of its checkpoints
//!   ([`FORMAT`]), the digests of the case file as read, of the mesh and of the PETSc options
//!   file, and the rank count;
//! - the load path: the load and step size after cuts, the step count, the run's counters and
//!   whether the next step starts with the fallback line search;
//!   the summary's step records;
//! - this rank's part of the solution and its rows of the matrix pattern (a contact pattern
//!   follows the contact zone: the restarted matrix has the same nonzeros, so the linear
//!   solver does the same arithmetic);
//! - every contribution's carried state ([`crate::model::Contribution::write_state`]: the
//!   contact multipliers, tractions and slip history, the tied multipliers);
//! - on rank 0, the history rows and the PVD series.
//!
//! Each rank writes its file atomically; once every rank has, rank 0 points
//! `checkpoint/latest` at the step (atomically too), and the older files go. A run killed at any
//! moment leaves `latest` naming a complete set.
//!
//! `mortar run CASE --restart DIR` reads the files `DIR/checkpoint/latest` names, checks that
//! they were written by this program version for this case file, mesh, options file and rank
//! count (one line naming what differs, exit 1, nothing in DIR touched, otherwise), removes the
//! step files of DIR that its series do not list (the steps after the checkpoint, redone), and
//! goes on with the next step, appending to the history, the series and the summary.
//!
//! **The same answer, bit for bit.** On the same rank count the partition, the dofs and every
//! evaluation are those of the run that wrote the checkpoint. What the linear solver built is
//! not in a file: the factorization the next step's predictor reuses under
//! `steps.predictor_tangent = "last_newton"`, and what a preconditioner keeps from one set-up
//! to the next (GAMG keeps its whole set-up through a load step, `Snes::rebuild_multigrid`,
//! and under the user's own options its interpolation for as long as the matrix lives).
//! So after a checkpoint the run goes on as a restart from it would: with a new matrix of the
//! same pattern (and on the iterative path a new Newton solver), the next step's predictor
//! assembling the tangent at the converged state. (A checkpoint written at a stop that is not one of
//! every N is the exception: its restart starts the next step from that tangent where the run
//! would have reused the factorization, and agrees with it to the Newton tolerance.)

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;

use crate::case::Scene;
use crate::error::{Error, Result};
use crate::io::checkpoint::{Fnv64, Reader, Writer};
use crate::io::output::{write_atomic, StepRecord};
use crate::model::{StateSink, StateSource};
use crate::petsc::LinearPath;

use super::assembly::Pattern;
use super::collective::agree_on;
use super::setup::new_snes;
use super::Run;

/// The checkpoint folder in the output folder.
pub(super) const FOLDER: &str = "checkpoint";

/// The file in [`FOLDER`] that names the last complete checkpoint.
const LATEST: &str = "latest";

/// `step_<k>_r<rank>.ckpt`.
fn file_name(step: usize, rank: usize) -> String {
    format!("step_{step:04}_r{rank}.ckpt")
}

/// The layout of the checkpoints, raised whenever what they hold or mean changes (2: the
/// history's `matrix_entries` column, and a pattern renewed at each step's predicted end), so
/// that a checkpoint of another layout is refused by name rather than misread.
const FORMAT: u32 = 2;

/// What ties a checkpoint to the run that may continue it.
pub(super) struct Identity {
    version: String,
    /// Digests of the case file as read, the mesh and the PETSc options file.
    digests: [u64; 3],
    ranks: usize,
}

impl Identity {
    fn of(scene: &Scene, ranks: usize) -> Identity {
        let options = match &scene.petsc_options {
            Some(path) => std::fs::read(path).map_or(0, |b| Fnv64::default().bytes(&b).finish()),
            None => 0,
        };
        Identity {
            version: format!("{} (checkpoint format {FORMAT})", env!("CARGO_PKG_VERSION")),
            digests: [scene.case_digest, Fnv64::of_debug(&scene.mesh), options],
            ranks,
        }
    }

    fn write(&self, rank: usize, out: &mut Writer) {
        out.text("program version", &self.version);
        out.u64s("digests", &self.digests);
        out.u64s("ranks", &[self.ranks as u64, rank as u64]);
    }

    /// Checks that `from` was written by this identity's run on `rank`.
    fn check(&self, rank: usize, from: &mut Reader) -> Result<()> {
        let refuse = |msg: String| Err(Error::Restart(msg));
        let version = from.text("program version")?;
        if version != self.version {
            return refuse(format!(
                "the checkpoint was written by mortar {version}; this is mortar {}",
                self.version
            ));
        }
        let digests = from.u64s("digests")?;
        if digests.len() != self.digests.len() {
            return Err(layout("digests"));
        }
        let what = ["case file", "mesh", "PETSc options file"];
        for ((theirs, mine), what) in digests.iter().zip(self.digests).zip(what) {
            if *theirs != mine {
                return refuse(format!(
                    "the checkpoint is of another {what}: the {what} changed since it was \
                     written (restart with the files of the run, or start afresh)"
                ));
            }
        }
        let ranks = from.u64s("ranks")?;
        if ranks != [self.ranks as u64, rank as u64] {
            return refuse(format!(
                "the checkpoint is of another rank count or rank ({ranks:?} for {} rank(s))",
                self.ranks
            ));
        }
        Ok(())
    }
}

/// The checkpoint a restart reads: this rank's file, checked, positioned after its identity.
pub(super) struct Resumed {
    reader: Reader,
    /// The finished step it holds.
    pub step: usize,
    /// Its load factor, and the size of the next step.
    pub load: (f64, f64),
}

/// Reads and checks this rank's file of the last checkpoint in `dir` (*collective*: every
/// rank returns the same [`Error::Restart`] when one rank's file is refused).
pub(super) fn open(
    scene: &Scene,
    dir: &Path,
    (rank, ranks): (usize, usize),
    world: &SimpleCommunicator,
) -> Result<Resumed> {
    let mine = open_mine(scene, dir, rank, ranks);
    let failed = mine
        .as_ref()
        .err()
        .map(|e| Error::Restart(restart_message(e)));
    agree_on_restart(world, failed.map_or(Ok(()), Err))?;
    mine
}

/// The text of a refusal, without the `restart: ` every [`Error::Restart`] prints first.
fn restart_message(e: &Error) -> String {
    let text = e.to_string();
    text.strip_prefix("restart: ").unwrap_or(&text).to_string()
}

fn open_mine(scene: &Scene, dir: &Path, rank: usize, ranks: usize) -> Result<Resumed> {
    let folder = dir.join(FOLDER);
    let latest = folder.join(LATEST);
    let text = std::fs::read_to_string(&latest).map_err(|e| {
        Error::Restart(match e.kind() {
            std::io::ErrorKind::NotFound => format!(
                "no checkpoint in {} (no {}): the run wrote none (set output.checkpoint_every)",
                dir.display(),
                latest.display()
            ),
            _ => format!("cannot read {}: {e}", latest.display()),
        })
    })?;
    let (step, written_by) = parse_latest(&text)
        .ok_or_else(|| Error::Restart(format!("{} is damaged: {text:?}", latest.display())))?;
    if written_by != ranks {
        return Err(Error::Restart(format!(
            "the checkpoint in {} was written by {written_by} rank(s); this run has {ranks}: \
             restart it on {written_by}",
            dir.display()
        )));
    }
    let mut reader = Reader::open(&folder.join(file_name(step, rank)))?;
    Identity::of(scene, ranks).check(rank, &mut reader)?;
    let (t, dt) = match reader.f64s("load")?[..] {
        [t, dt] => (t, dt),
        _ => return Err(layout("load")),
    };
    if t >= 1.0 - 1e-12 {
        return Err(Error::Restart(format!(
            "the run in {} is complete (its checkpoint is of step {step}, at the full load): \
             nothing to continue",
            dir.display()
        )));
    }
    Ok(Resumed {
        reader,
        step,
        load: (t, dt),
    })
}

/// `step <k>` and `ranks <n>` of [`LATEST`].
fn parse_latest(text: &str) -> Option<(usize, usize)> {
    let mut lines = text.lines();
    let step = lines.next()?.strip_prefix("step ")?.parse().ok()?;
    let ranks = lines.next()?.strip_prefix("ranks ")?.parse().ok()?;
    Some((step, ranks))
}

/// `PathBuf` of this rank's file of the checkpoint of `step` in `dir`.
fn path_of(dir: &Path, step: usize, rank: usize) -> PathBuf {
    dir.join(FOLDER).join(file_name(step, rank))
}

impl Run<'_> {
    /// Whether the step just finished is one of every `output.checkpoint_every`.
    pub(super) fn checkpoint_due(&self) -> bool {
        let every = self.cx.scene.checkpoint_every;
        every > 0 && self.state.step.is_multiple_of(every)
    }

    /// Writes the checkpoint of the last finished step, once (*collective*).
    pub(super) fn write_checkpoint(&mut self) -> Result<()> {
        let step = self.state.step;
        if self.cx.scene.checkpoint_every == 0 || step == 0 || self.checkpointed == Some(step) {
            return Ok(());
        }
        let (dir, rank) = (&self.cx.opts.out_dir, self.cx.rank);
        let bytes = self.checkpoint_bytes()?;
        let path = path_of(dir, step, rank);
        let written = std::fs::create_dir_all(dir.join(FOLDER))
            .map_err(|e| Error::io(dir.join(FOLDER), e))
            .and_then(|()| write_atomic(&path, &bytes));
        agree_on(&self.cx.world, written)?;
        let latest = if rank == 0 {
            let text = format!("step {step}\nranks {}\n", self.cx.ranks);
            write_atomic(&dir.join(FOLDER).join(LATEST), text.as_bytes())
        } else {
            Ok(())
        };
        agree_on(&self.cx.world, latest)?;
        if let Some(old) = self.checkpointed {
            let _ = std::fs::remove_file(path_of(dir, old, rank));
        }
        self.checkpointed = Some(step);
        self.as_a_restart_would_go_on()
    }

    /// The linear solver from here as a restart from this step sets it up: a new matrix of the
    /// same pattern, and on the iterative path a new Newton solver, so that nothing built
    /// before (a factorization the predictor would reuse, a multigrid hierarchy PETSc would
    /// keep) carries over (module docs) (*collective*).
    fn as_a_restart_would_go_on(&mut self) -> Result<()> {
        let l = &mut self.linear;
        if l.choice.path != LinearPath::Direct {
            // A preconditioner may keep what it built (the interface split its fields'
            // matrices) through a new matrix. (Not on the direct path, where a new matrix
            // suffices: Debian's PETSc 3.18 crashes in SuperLU_DIST's first factorization after
            // a solver that used it was destroyed.)
            let solver = (l.force_scale, l.choice.path);
            l.snes = new_snes(&self.cx, &self.model, solver, &l.rigid_modes)?;
        }
        self.remake_matrix()?;
        // A linear scene's tangent is assembled and factorized once, and then kept: again for
        // the new matrix.
        self.linear.tangent.ready = false;
        if self.cx.scene.is_linear() {
            self.linear.snes.freeze_jacobian()?;
        }
        Ok(())
    }

    /// This rank's checkpoint file (module docs), in the order [`Run::resume`] reads it.
    fn checkpoint_bytes(&self) -> Result<Vec<u8>> {
        let mut out = Writer::default();
        let (scene, ranks) = (self.cx.scene, self.cx.ranks);
        let identity = self.identity.get_or_init(|| Identity::of(scene, ranks));
        identity.write(self.cx.rank, &mut out);
        let s = &self.state;
        out.f64s("load", &[s.t, s.dt]);
        let c = &s.counts;
        let counts = [
            s.step,
            c.uzawa_capped,
            c.fallbacks,
            c.unconverged,
            c.newton,
            c.cuts,
            s.cuts_in_row,
            s.lead_with_fallback as usize,
        ];
        out.u64s("counts", &counts.map(|n| n as u64));
        let steps = &self.summary.steps;
        let records: Vec<u64> = steps
            .iter()
            .flat_map(|r| {
                [
                    r.step,
                    r.newton_its,
                    r.cut,
                    r.converged as usize,
                    r.augmentations,
                ]
            })
            .map(|n| n as u64)
            .collect();
        out.u64s("step records", &records);
        out.f64s(
            "step loads",
            &steps.iter().map(|r| r.load).collect::<Vec<_>>(),
        );
        out.f64s("solution", &self.linear.x.to_local_vec()?);
        out.u64s("pattern", &self.linear.pattern.to_codes());
        self.model.write_state(&mut out);
        self.results.write_state(&mut out);
        Ok(out.finish())
    }

    /// Continues from `resumed`: the load path, the solution, the pattern and matrix, the
    /// model's state, the summary's steps and the results' series. Every rank reads its file
    /// first, and only once all have does anything change on disk (*collective*).
    pub(super) fn resume(&mut self, resumed: Resumed) -> Result<()> {
        let read = self.read_checkpoint(resumed);
        agree_on_restart(&self.cx.world, read)?;
        self.as_a_restart_would_go_on()?;
        self.results.rewrite_after_restart();
        self.results.write_summary(&self.summary);
        self.results.agree(&self.cx.world)
    }

    /// Reads the rest of this rank's file into the run (no collective call, nothing written).
    fn read_checkpoint(&mut self, mut resumed: Resumed) -> Result<()> {
        let from = &mut resumed.reader;
        let (t, dt) = resumed.load;
        let counts = from.u64s("counts")?;
        let &[step, capped, fallbacks, unconverged, newton, cuts, cuts_in_row, lead] = &counts[..]
        else {
            return Err(layout("counts"));
        };
        let s = &mut self.state;
        (s.t, s.dt, s.step) = (t, dt, step as usize);
        s.cuts_in_row = cuts_in_row as usize;
        s.lead_with_fallback = lead != 0;
        let c = &mut s.counts;
        (c.uzawa_capped, c.fallbacks, c.fallbacks_before) =
            (capped as usize, fallbacks as usize, fallbacks as usize);
        (c.unconverged, c.newton, c.cuts) = (unconverged as usize, newton as usize, cuts as usize);
        self.summary.steps = step_records(from)?;
        let solution = from.f64s("solution")?;
        let fits = self.linear.x.with_local_mut(|x| {
            let fits = x.len() == solution.len();
            if fits {
                x.copy_from_slice(&solution);
            }
            fits
        })?;
        if !fits {
            return Err(layout("solution"));
        }
        let codes = from.u64s("pattern")?;
        self.linear.pattern =
            Pattern::from_codes(&self.cx.dofs, &codes).ok_or_else(|| layout("pattern"))?;
        self.model.read_state(from)?;
        self.results.read_state(from)?;
        if !from.at_end() {
            return Err(layout("end"));
        }
        self.checkpointed = Some(resumed.step);
        Ok(())
    }
}

/// *Collective*: [`agree_on`] for a restart: the lowest failing rank's refusal on every rank.
fn agree_on_restart(world: &SimpleCommunicator, mine: Result<()>) -> Result<()> {
    agree_on(world, mine).map_err(|e| match e {
        Error::Output(m) => Error::Restart(m.strip_prefix("restart: ").unwrap_or(&m).to_string()),
        e => e,
    })
}

fn step_records(from: &mut Reader) -> Result<Vec<StepRecord>> {
    let records = from.u64s("step records")?;
    let loads = from.f64s("step loads")?;
    if records.len() != 5 * loads.len() {
        return Err(layout("step records"));
    }
    Ok(records
        .chunks_exact(5)
        .zip(loads)
        .map(|(r, load)| StepRecord {
            step: r[0] as usize,
            load,
            newton_its: r[1] as usize,
            cut: r[2] as usize,
            converged: r[3] != 0,
            augmentations: r[4] as usize,
        })
        .collect())
}

fn layout(record: &str) -> Error {
    Error::Restart(format!(
        "the checkpoint's record '{record}' does not fit this run (a damaged file?)"
    ))
}

#[cfg(test)]
mod tests {
    use super::parse_latest;

    #[test]
    fn latest_names_a_step_and_a_rank_count() {
        assert_eq!(parse_latest("step 12\nranks 2\n"), Some((12, 2)));
        assert_eq!(parse_latest("step 12\n"), None);
        assert_eq!(parse_latest("step x\nranks 2\n"), None);
    }
}
