//! What the results carry from step to step (rank 0's history rows and PVD series), written to
//! a checkpoint and read back at a restart, and the step files a restart removes: those of the
//! steps after its checkpoint, which it redoes.

use std::collections::BTreeSet;

use crate::error::{Error, Result};
use crate::io::checkpoint::{Reader, Writer};
use crate::io::output::write_pvd;
use crate::model::{StateSink, StateSource};

use super::folder::remove_step_files;
use super::Results;

impl Results {
    /// Rank 0's history rows and series into a checkpoint (nothing on other ranks).
    pub fn write_state(&self, out: &mut Writer) {
        let Some(history) = &self.history else {
            return;
        };
        out.f64s("history", &history.rows().concat());
        let mut series = vec![(String::new(), &self.pvd)];
        series.extend(self.interface_pvd.iter().map(|(stem, s)| (stem.clone(), s)));
        let stems: Vec<&str> = series.iter().map(|(stem, _)| stem.as_str()).collect();
        out.text("series", &stems.join("\n"));
        for (_, entries) in series {
            out.f64s(
                "series times",
                &entries.iter().map(|e| e.0).collect::<Vec<_>>(),
            );
            let files: Vec<&str> = entries.iter().map(|e| e.1.as_str()).collect();
            out.text("series files", &files.join("\n"));
        }
    }

    /// Reads back what [`Results::write_state`] wrote (rank 0), into memory:
    /// [`Results::rewrite_after_restart`] writes it.
    pub fn read_state(&mut self, from: &mut Reader) -> Result<()> {
        let Some(history) = &mut self.history else {
            return Ok(());
        };
        let values = from.f64s("history")?;
        let columns = history.columns().len();
        if values.len() % columns != 0 {
            return Err(Error::Restart(
                "the checkpoint's history does not fit this case's columns".into(),
            ));
        }
        let rows = values.chunks_exact(columns).map(<[f64]>::to_vec).collect();
        history.restore_rows(rows);
        let stems = from.text("series")?;
        for stem in stems.split('\n') {
            let times = from.f64s("series times")?;
            let files = from.text("series files")?;
            let files: Vec<String> = match files.as_str() {
                "" => Vec::new(),
                f => f.split('\n').map(String::from).collect(),
            };
            if files.len() != times.len() {
                return Err(Error::Restart("the checkpoint's series are damaged".into()));
            }
            let entries: Vec<(f64, String)> = times.into_iter().zip(files).collect();
            let own = |f: &str| !f.contains("..") && !f.starts_with('/');
            if !own(stem) || entries.iter().any(|(_, f)| !own(f)) {
                return Err(Error::Restart("the checkpoint's series are damaged".into()));
            }
            if stem.is_empty() {
                self.pvd = entries;
            } else {
                self.interface_pvd.insert(stem.to_string(), entries);
            }
        }
        Ok(())
    }

    /// After [`Results::read_state`] on every rank (rank 0): removes every step file the series
    /// do not list, and rewrites the history and the series (a failure is kept for
    /// [`Results::agree`]).
    pub fn rewrite_after_restart(&mut self) {
        let Some(history) = &self.history else {
            return;
        };
        let written = history
            .write()
            .and_then(|()| remove_step_files(&self.dir, &self.case, &self.listed_files()))
            .and_then(|()| self.rewrite_series());
        self.keep(written);
    }

    /// Every series file and step file the series list: the PVDs, the PVTU of each volume
    /// step with its pieces, and the interface files (relative to the output folder).
    fn listed_files(&self) -> BTreeSet<String> {
        let mut kept = BTreeSet::new();
        for (_, pvtu) in &self.pvd {
            let step = pvtu
                .strip_prefix(&format!("{}_", self.case))
                .and_then(|s| s.strip_suffix(".pvtu"))
                .and_then(|s| s.parse::<usize>().ok());
            if let Some(step) = step {
                kept.extend((0..self.ranks).map(|r| self.piece_name(step, r)));
            }
            kept.insert(pvtu.clone());
        }
        kept.extend(
            self.interface_pvd
                .values()
                .flatten()
                .map(|(_, f)| f.clone()),
        );
        kept.extend(self.interface_pvd.keys().map(|stem| format!("{stem}.pvd")));
        if !self.pvd.is_empty() {
            kept.insert(format!("{}.pvd", self.case));
        }
        kept
    }

    /// The PVD files as the series stand (a restart).
    fn rewrite_series(&self) -> Result<()> {
        if !self.pvd.is_empty() {
            write_pvd(&self.dir.join(format!("{}.pvd", self.case)), &self.pvd)?;
        }
        for (stem, series) in &self.interface_pvd {
            write_pvd(&self.dir.join(format!("{stem}.pvd")), series)?;
        }
        Ok(())
    }
}
