//! Sums the dense node blocks of an interface tangent before they go to PETSc.
//!
//! Each traction node contributes a dense `3m x 3m` block over the `m` nodes of its stencil
//! (the faces carrying it and the primary faces they meet), and neighbouring nodes share most
//! of their stencils: summed one block at a time, PETSc would look up every entry of every
//! block (several times the number of nonzeros), and on more than one rank ship every
//! off-rank entry through its stash. [`BlockSum`] adds the blocks into one sparse row of
//! `3 x 3` blocks per node (columns sorted by node, merged with the block's sorted slots), and
//! [`BlockSum::hand_out`] then hands the solver each node row once, with every column it holds.
//!
//! The sums are taken in the order the blocks arrive, entry by entry. Which blocks a rank sums
//! before PETSc adds them up depends on the number of ranks, so results differ between rank
//! counts by round-off only.

use std::collections::HashMap;

use crate::error::Result;
use crate::model::TangentSink;

/// One node row: `(column node, 3 x 3 block row-major)`, sorted by column node.
type NodeRow = Vec<(usize, [f64; 9])>;

/// A sparse sum of dense node blocks: one row of `3 x 3` blocks per node.
#[derive(Default)]
pub struct BlockSum {
    /// Row of each node that has one.
    row_of: HashMap<usize, usize>,
    /// Per row: its node and its blocks.
    rows: Vec<(usize, NodeRow)>,
}

impl BlockSum {
    /// Adds the dense block `tangent` (row-major `3m x 3m`) over the nodes `slots` (`3 slot + c`
    /// order). A node listed twice (a node-on-segment block over the current and the old face)
    /// gets both its rows and both its columns summed.
    ///
    /// # Panics
    /// If `tangent` does not hold `(3 slots.len())^2` entries.
    pub fn add(&mut self, slots: &[usize], tangent: &[f64]) {
        let m = slots.len();
        assert_eq!(tangent.len(), 9 * m * m, "BlockSum::add: wrong block size");
        let mut by_node: Vec<usize> = (0..m).collect();
        by_node.sort_unstable_by_key(|&s| slots[s]);
        for (a, &node) in slots.iter().enumerate() {
            let next = self.rows.len();
            let r = *self.row_of.entry(node).or_insert(next);
            if r == next {
                self.rows.push((node, Vec::new()));
            }
            let row = &mut self.rows[r].1;
            let mut k = 0;
            for &b in &by_node {
                let col = slots[b];
                while k < row.len() && row[k].0 < col {
                    k += 1;
                }
                if k == row.len() || row[k].0 != col {
                    row.insert(k, (col, [0.0; 9]));
                }
                let block = &mut row[k].1;
                for i in 0..3 {
                    let from = &tangent[(3 * a + i) * 3 * m + 3 * b..][..3];
                    for j in 0..3 {
                        block[3 * i + j] += from[j];
                    }
                }
            }
        }
    }

    /// Hands the sum to `out` one node row at a time: the node's three rows over every column
    /// node it holds (`3 x 3 columns`, row-major).
    pub fn hand_out(&self, out: &mut dyn TangentSink) -> Result<()> {
        let mut cols: Vec<usize> = Vec::new();
        let mut vals: Vec<f64> = Vec::new();
        for (node, row) in &self.rows {
            cols.clear();
            cols.extend(row.iter().map(|(c, _)| *c));
            vals.clear();
            for i in 0..3 {
                vals.extend(
                    row.iter()
                        .flat_map(|(_, b)| b[3 * i..3 * i + 3].iter().copied()),
                );
            }
            out.add_block(&[*node], &cols, &vals)?;
        }
        Ok(())
    }

    /// The summed `3 x 3` block of rows of `row` and columns of `col` (zero if none).
    #[cfg(test)]
    fn block(&self, row: usize, col: usize) -> [f64; 9] {
        self.row_of
            .get(&row)
            .and_then(|&r| self.rows[r].1.iter().find(|(c, _)| *c == col))
            .map_or([0.0; 9], |(_, b)| *b)
    }
}

#[cfg(test)]
mod tests {
    use super::BlockSum;

    /// A dense block over `slots` whose entry (row dof `3 a + i`, column dof `3 b + j`) is
    /// `f(slots[a], i, slots[b], j)`.
    fn block(slots: &[usize], f: impl Fn(usize, usize, usize, usize) -> f64) -> Vec<f64> {
        let n = 3 * slots.len();
        (0..n * n)
            .map(|k| {
                let (r, c) = (k / n, k % n);
                f(slots[r / 3], r % 3, slots[c / 3], c % 3)
            })
            .collect()
    }

    #[test]
    fn overlapping_blocks_sum_entry_by_entry() {
        let entry = |seed: f64| {
            move |a: usize, i: usize, b: usize, j: usize| {
                seed * (1.0 + a as f64) + 0.1 * i as f64 - 0.01 * (b * 3 + j) as f64
            }
        };
        // Unsorted slots, overlapping in nodes 7 and 2.
        let first = [7, 2, 9];
        let second = [4, 2, 7, 11];
        let mut sum = BlockSum::default();
        sum.add(&first, &block(&first, entry(1.0)));
        sum.add(&second, &block(&second, entry(2.0)));
        let nodes = [2, 4, 7, 9, 11];
        for &a in &nodes {
            for &b in &nodes {
                let got = sum.block(a, b);
                for i in 0..3 {
                    for j in 0..3 {
                        let mut want = 0.0;
                        if first.contains(&a) && first.contains(&b) {
                            want += entry(1.0)(a, i, b, j);
                        }
                        if second.contains(&a) && second.contains(&b) {
                            want += entry(2.0)(a, i, b, j);
                        }
                        assert_eq!(got[3 * i + j], want, "rows of {a}, columns of {b}");
                    }
                }
            }
        }
        // Every row keeps its columns sorted, each once.
        for (_, row) in &sum.rows {
            assert!(row.windows(2).all(|w| w[0].0 < w[1].0));
        }
    }

    #[test]
    fn a_node_listed_twice_gets_both_rows_and_columns() {
        let slots = [4, 2, 4];
        let entry = |r: usize, c: usize| (10 * r + c) as f64;
        let n = 9;
        let dense: Vec<f64> = (0..n * n).map(|k| entry(k / n, k % n)).collect();
        let mut sum = BlockSum::default();
        sum.add(&slots, &dense);
        // Rows of node 4 are block rows 0 and 2, its columns block columns 0 and 2.
        let got = sum.block(4, 4);
        for i in 0..3 {
            for j in 0..3 {
                let want: f64 = [0, 2]
                    .iter()
                    .flat_map(|&a| [0, 2].map(move |b| entry(3 * a + i, 3 * b + j)))
                    .sum();
                assert_eq!(got[3 * i + j], want);
            }
        }
        let got = sum.block(2, 4);
        assert_eq!(got[0], entry(3, 0) + entry(3, 6));
    }
}
