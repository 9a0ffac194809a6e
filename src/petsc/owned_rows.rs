//! Adding dense blocks straight into the stored values of the rows this rank owns.
//!
//! `MatSetValues` finds every entry of a block by a binary search in its row, with PETSc's
//! generic per-entry checks around it: for the bulk tangent (81 x 81 blocks of Hex27 rows of
//! about 375 stored columns) that search cost more than the element kernel itself
//! (docs/performance.md, "Assembly and the matrix pattern"). [`OwnedRows`] reads
//! the matrix's own compressed rows (`MatGetRowIJ`, `MatSeqAIJGetArray` of the diagonal block
//! and, on more than one rank, of the off-diagonal block with its global column map
//! `MatMPIAIJGetSeqAIJ`) and finds an entry from a hint: the free dofs of one node have
//! consecutive global numbers and so consecutive slots in a sorted row, and the rows of one
//! node share their columns, so almost every entry is found by one comparison; a binary search
//! is the fallback.
//!
//! - Entries of rows other ranks own go through `MatSetValues` (PETSc's stash), as before.
//! - An entry outside the stored pattern (possible once a matrix allows new nonzeros) is kept
//!   aside and added with `MatSetValues` after the arrays are handed back: inserting it while
//!   they are held would reallocate them. Until the next assembly the rows then have gaps (and
//!   on more than one rank the off-diagonal block loses its column map), so a later
//!   [`Matrix::with_owned_rows`] before that assembly adds everything through `MatSetValues`.
//! - The arrays are handed back on drop, so also on an error or a panic in the closure.
//! - Checked against `MatSetValues` bit for bit on one and two ranks (`tests/petsc_layer.rs`,
//!   `tests/petsc_layer_two_ranks.rs`).
//! - The sums are those of `MatSetValues` bit for bit: each stored entry receives the same
//!   additions in the same order.
//! - Matrices of other types (none are made here, but an option could make one) take the plain
//!   `MatSetValues` path for every entry.

use std::ops::Range;

use petsc_ffi as p;

use super::{chk, Matrix, PetscInt};
use crate::error::Result;

/// One compressed block (diagonal or off-diagonal) of the owned rows.
struct Block<'a> {
    /// Row starts (`rows + 1`) and the sorted column of every stored entry (block-local).
    starts: &'a [PetscInt],
    columns: &'a [PetscInt],
    values: &'a mut [f64],
}

/// The stored values of this rank's rows, borrowed from PETSc for the life of
/// [`Matrix::with_owned_rows`]'s closure.
pub struct OwnedRows<'a> {
    raw: p::Mat,
    /// The owned rows; empty for a matrix type without direct access (every entry then goes
    /// through `MatSetValues`).
    rows: Range<PetscInt>,
    /// Global columns of the diagonal block.
    columns: Range<PetscInt>,
    diagonal: Block<'a>,
    /// The off-diagonal block and the global column of each of its local columns (ascending).
    off_diagonal: Option<(Block<'a>, &'a [PetscInt])>,
    /// Entries outside the stored pattern: `(row, column, value)`, added afterwards.
    outside: Vec<(PetscInt, PetscInt, f64)>,
    /// Per node-column hint: the slot offset found in the last row (see `add`).
    hints: Vec<Option<Slot>>,
}

/// Where an entry is stored: the block (off-diagonal or not) and the offset in its row.
#[derive(Clone, Copy, PartialEq, Debug)]
struct Slot {
    off_diagonal: bool,
    offset: usize,
}

impl OwnedRows<'_> {
    /// Adds a dense block (row-major, `rows.len() x cols.len()`) at global indices; negative
    /// indices are ignored, like [`Matrix::add_values`].
    ///
    /// # Panics
    /// If `vals` does not hold `rows.len() * cols.len()` entries.
    pub fn add(&mut self, rows: &[PetscInt], cols: &[PetscInt], vals: &[f64]) -> Result<()> {
        assert_eq!(
            rows.len() * cols.len(),
            vals.len(),
            "OwnedRows::add: wrong block size"
        );
        self.hints.clear();
        self.hints.resize(cols.len(), None);
        for (i, &row) in rows.iter().enumerate() {
            let line = &vals[i * cols.len()..(i + 1) * cols.len()];
            if row < 0 {
                continue;
            }
            if !self.rows.contains(&row) {
                super::matrix::add_values_raw(self.raw, &[row], cols, line)?;
                continue;
            }
            let local = (row - self.rows.start) as usize;
            let diagonal = self.diagonal.row(local);
            let off_diagonal = self
                .off_diagonal
                .as_mut()
                .map(|(block, map)| (block.row(local), *map));
            let mut row_view = RowView {
                columns: self.columns.clone(),
                diagonal,
                off_diagonal,
            };
            // The slot of the last column found in this row.
            let mut previous: Option<Slot> = None;
            for (j, (&col, &v)) in cols.iter().zip(line).enumerate() {
                if col < 0 {
                    continue;
                }
                // Hints: this column's slot in the last row (the rows of a node share their
                // columns), one past the previous column's (a node's free dofs are
                // consecutive).
                let next = previous.map(|s| Slot {
                    offset: s.offset + 1,
                    ..s
                });
                previous = row_view.find(col, [self.hints[j], next]);
                match previous {
                    Some(slot) => {
                        self.hints[j] = Some(slot);
                        *row_view.value(slot) += v;
                    }
                    None => self.outside.push((row, col, v)),
                }
            }
        }
        Ok(())
    }
}

/// One stored row of a block: its block-local columns and their values.
type StoredRow<'r> = (&'r [PetscInt], &'r mut [f64]);

/// One stored row: its columns and values in the diagonal and off-diagonal blocks.
struct RowView<'r> {
    /// Global columns of the diagonal block.
    columns: Range<PetscInt>,
    diagonal: StoredRow<'r>,
    /// With the global column of each local column of the off-diagonal block.
    off_diagonal: Option<(StoredRow<'r>, &'r [PetscInt])>,
}

impl RowView<'_> {
    /// The slot of global column `col`: the first hint that holds, else a binary search.
    #[inline]
    fn find(&self, col: PetscInt, hints: [Option<Slot>; 2]) -> Option<Slot> {
        if self.columns.contains(&col) {
            let key = col - self.columns.start;
            let stored = self.diagonal.0;
            for h in hints.into_iter().flatten() {
                if !h.off_diagonal && stored.get(h.offset) == Some(&key) {
                    return Some(h);
                }
            }
            let offset = stored.binary_search(&key).ok()?;
            return Some(Slot {
                off_diagonal: false,
                offset,
            });
        }
        let ((stored, _), map) = self.off_diagonal.as_ref()?;
        let global = |k: usize| map[stored[k] as usize];
        for h in hints.into_iter().flatten() {
            if h.off_diagonal && h.offset < stored.len() && global(h.offset) == col {
                return Some(h);
            }
        }
        let offset = stored.partition_point(|&c| map[c as usize] < col);
        (offset < stored.len() && global(offset) == col).then_some(Slot {
            off_diagonal: true,
            offset,
        })
    }

    #[inline]
    fn value(&mut self, slot: Slot) -> &mut f64 {
        if slot.off_diagonal {
            let ((_, values), _) = self
                .off_diagonal
                .as_mut()
                .expect("an off-diagonal slot has its block");
            &mut values[slot.offset]
        } else {
            &mut self.diagonal.1[slot.offset]
        }
    }
}

impl Block<'_> {
    /// The stored columns and values of one local row.
    fn row(&mut self, local: usize) -> (&[PetscInt], &mut [f64]) {
        let range = self.starts[local] as usize..self.starts[local + 1] as usize;
        (&self.columns[range.clone()], &mut self.values[range])
    }
}

/// A sequential AIJ block's compressed rows and values, handed back to PETSc on drop (also on
/// an error or a panic inside the closure).
struct HeldBlock {
    mat: p::Mat,
    rows: PetscInt,
    starts: *const PetscInt,
    columns: *const PetscInt,
    values: *mut f64,
}

impl HeldBlock {
    fn get(mat: p::Mat) -> Result<HeldBlock> {
        let (mut rows, mut starts, mut columns) = (0, std::ptr::null(), std::ptr::null());
        let mut done = p::PetscBool::PETSC_FALSE;
        chk!(MatGetRowIJ(
            mat,
            0,
            p::PetscBool::PETSC_FALSE,
            p::PetscBool::PETSC_FALSE,
            &mut rows,
            &mut starts,
            &mut columns,
            &mut done
        ))?;
        if done != p::PetscBool::PETSC_TRUE {
            return Err(crate::Error::Other(
                "MatGetRowIJ: no compressed rows for this matrix block".into(),
            ));
        }
        let mut held = HeldBlock {
            mat,
            rows,
            starts,
            columns,
            values: std::ptr::null_mut(),
        };
        chk!(MatSeqAIJGetArray(mat, &mut held.values))?;
        Ok(held)
    }

    /// True if the rows are stored back to back (`starts[rows]` = the entries in use): so after
    /// an assembly, not after an insertion outside the pattern, which leaves room at row ends.
    fn is_compact(&self) -> Result<bool> {
        let used = super::matrix::local_info(self.mat)?.nz_used;
        // SAFETY: `starts` has `rows + 1` entries.
        let stored = unsafe { *self.starts.add(self.rows as usize) };
        Ok(stored as f64 == used)
    }

    /// The block as slices.
    ///
    /// # Safety
    /// Valid while `self` lives; PETSc's arrays are not reallocated meanwhile (no entry is
    /// inserted into the local rows while they are held).
    unsafe fn block<'a>(&self) -> Block<'a> {
        let rows = self.rows as usize;
        let starts = std::slice::from_raw_parts(self.starts, rows + 1);
        let stored = starts[rows] as usize;
        let (columns, values): (&[PetscInt], &mut [f64]) = if stored == 0 {
            (&[], &mut [])
        } else {
            (
                std::slice::from_raw_parts(self.columns, stored),
                std::slice::from_raw_parts_mut(self.values, stored),
            )
        };
        Block {
            starts,
            columns,
            values,
        }
    }
}

impl Drop for HeldBlock {
    fn drop(&mut self) {
        let mut done = p::PetscBool::PETSC_FALSE;
        // SAFETY: `mat` is the block these arrays were taken from, still alive (its matrix is
        // borrowed by `with_owned_rows`).
        let codes = unsafe {
            [
                p::MatSeqAIJRestoreArray(self.mat, &mut self.values),
                p::MatRestoreRowIJ(
                    self.mat,
                    0,
                    p::PetscBool::PETSC_FALSE,
                    p::PetscBool::PETSC_FALSE,
                    &mut self.rows,
                    &mut self.starts,
                    &mut self.columns,
                    &mut done,
                ),
            ]
        };
        if codes.iter().any(|&c| c != 0) {
            crate::error::print_warning(format_args!(
                "handing a matrix block back to PETSc failed: {codes:?}"
            ));
        }
    }
}

impl<'a> OwnedRows<'a> {
    /// Every entry through `MatSetValues` (a matrix type without direct access, or rows not
    /// stored back to back).
    fn plain(raw: p::Mat) -> OwnedRows<'a> {
        OwnedRows {
            raw,
            rows: 0..0,
            columns: 0..0,
            diagonal: Block {
                starts: &[0],
                columns: &[],
                values: &mut [],
            },
            off_diagonal: None,
            outside: Vec::new(),
            hints: Vec::new(),
        }
    }
}

impl Matrix {
    /// Runs `f` with direct access to the stored values of the owned rows (module docs), then
    /// adds the entries `f` put outside the stored pattern. Not collective. Direct access needs
    /// a `seqaij` or `mpiaij` matrix whose rows are stored back to back (assembled since any
    /// insertion outside its pattern); otherwise [`OwnedRows::add`] is `MatSetValues`.
    pub fn with_owned_rows<R>(
        &mut self,
        f: impl FnOnce(&mut OwnedRows<'_>) -> Result<R>,
    ) -> Result<R> {
        let mut kind: p::MatType = std::ptr::null();
        chk!(MatGetType(self.raw, &mut kind))?;
        // SAFETY: PETSc returns a NUL-terminated type name owned by the matrix.
        let kind = unsafe { std::ffi::CStr::from_ptr(kind) }.to_bytes();
        let (diagonal, off_diagonal, map) = match kind {
            b"seqaij" => (self.raw, None, std::ptr::null()),
            b"mpiaij" => {
                let (mut ad, mut ao, mut map): (p::Mat, p::Mat, *const PetscInt) =
                    (std::ptr::null_mut(), std::ptr::null_mut(), std::ptr::null());
                chk!(MatMPIAIJGetSeqAIJ(self.raw, &mut ad, &mut ao, &mut map))?;
                (ad, Some(ao), map)
            }
            _ => return f(&mut OwnedRows::plain(self.raw)),
        };
        let (mut lo, mut hi): (PetscInt, PetscInt) = (0, 0);
        chk!(MatGetOwnershipRange(self.raw, &mut lo, &mut hi))?;
        let diagonal = HeldBlock::get(diagonal)?;
        let off_diagonal = off_diagonal.map(HeldBlock::get).transpose()?;
        let mut off_columns: PetscInt = 0;
        if let Some(o) = &off_diagonal {
            chk!(MatGetSize(o.mat, std::ptr::null_mut(), &mut off_columns))?;
        }
        // An insertion outside the pattern since the last assembly leaves gaps in the rows and,
        // on more than one rank, may drop the off-diagonal column map (`MatDisAssemble`).
        let mut direct = diagonal.is_compact()?;
        if let Some(o) = &off_diagonal {
            direct = direct && o.is_compact()? && (off_columns == 0 || !map.is_null());
        }
        if !direct {
            drop((diagonal, off_diagonal));
            return f(&mut OwnedRows::plain(self.raw));
        }
        let (result, outside) = {
            // SAFETY: the blocks stay held until dropped below, and nothing inserts into the
            // local rows meanwhile (entries outside the pattern are kept aside); the map has
            // `off_columns` entries (checked non-null above).
            let mut rows = OwnedRows {
                raw: self.raw,
                rows: lo..hi,
                columns: lo..hi,
                diagonal: unsafe { diagonal.block() },
                off_diagonal: off_diagonal.as_ref().map(|o| {
                    let map: &[PetscInt] = if off_columns == 0 {
                        &[]
                    } else {
                        unsafe { std::slice::from_raw_parts(map, off_columns as usize) }
                    };
                    (unsafe { o.block() }, map)
                }),
                outside: Vec::new(),
                hints: Vec::new(),
            };
            let result = f(&mut rows);
            (result, std::mem::take(&mut rows.outside))
        };
        drop((diagonal, off_diagonal));
        let result = result?;
        for (row, col, v) in outside {
            self.add_values(&[row], &[col], &[v])?;
        }
        Ok(result)
    }
}
