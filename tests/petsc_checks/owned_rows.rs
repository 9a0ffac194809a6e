//! Check 8 of the PETSc layer's tests, shared by `petsc_layer.rs` (one rank) and
//! `petsc_layer_two_ranks.rs` (two): blocks added straight into the stored rows give the
//! matrix of `MatSetValues` bit for bit; the entries outside the pattern are stored once
//! (`Matrix::stored_entries`).

use mortar::petsc::{Matrix, Petsc, Sparsity};

/// Check 8 of `petsc_layer.rs` (see `petsc_layer_boundary_behaviour`), on this process's share
/// of the rows (all of them on one rank; `petsc_layer_two_ranks.rs` runs it on two).
pub fn owned_rows_match_set_values(petsc: &Petsc) {
    const ROWS: i32 = 30;
    let (rank, size) = (petsc.rank() as i32, petsc.size() as i32);
    // Contiguous ownership in whole nodes: 10 nodes of 3 rows, split between the ranks.
    let first = 3 * (10 * rank / size);
    let end = 3 * (10 * (rank + 1) / size);
    // Node-like pattern: rows in triples, each triple coupled to the triples within 2 of it.
    let pattern = Sparsity {
        row_start: first as usize,
        rows: (first..end)
            .map(|r| {
                let node = r / 3;
                (0..ROWS).filter(|c| (c / 3 - node).abs() <= 2).collect()
            })
            .collect(),
    };
    // A deterministic stream of values, the same on every rank.
    let mut seed = 12345u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    // Every rank adds every block: on two ranks half the rows of each are the other rank's
    // (they go through the stash) and the columns span both ranks (off-diagonal blocks).
    let mut blocks: Vec<(Vec<i32>, Vec<f64>)> = Vec::new();
    for first in 0..8 {
        // Three nodes, one dof constrained (-1), in a shuffled node order.
        let mut idx: Vec<i32> = [first + 2, first, first + 1]
            .iter()
            .flat_map(|&n| (0..3).map(move |c| 3 * n + c))
            .collect();
        idx[4] = -1;
        let vals = (0..idx.len() * idx.len()).map(|_| next()).collect();
        blocks.push((idx, vals));
    }
    // Outside the pattern: rows and columns {0, 1, 2, 27} (node 0 against a dof of node 9,
    // in another rank's columns on two ranks).
    let outside = (
        vec![0, 1, 27, 2],
        (0..16).map(|_| next()).collect::<Vec<f64>>(),
    );
    let build = |direct: bool| -> Vec<f64> {
        let mut m = Matrix::new_aij(&pattern).unwrap();
        m.allow_new_nonzeros().unwrap();
        let preallocated = m.stored_entries().unwrap();
        assert_eq!(preallocated, pattern.num_nonzeros() as u64, "rank {rank}");
        let mut stored = Vec::new();
        for _ in 0..2 {
            // Twice: the second sum lands on the values of the first assembly. Within one
            // assembly the blocks come twice, the second time after the entries outside the
            // pattern were inserted (rows with gaps, on two ranks no off-diagonal column map):
            // `with_owned_rows` must then fall back to `MatSetValues`.
            for with_outside in [true, false] {
                if direct {
                    m.with_owned_rows(|rows| {
                        for (idx, vals) in &blocks {
                            rows.add(idx, idx, vals)?;
                        }
                        if with_outside {
                            rows.add(&outside.0, &outside.0, &outside.1)?;
                        }
                        Ok(())
                    })
                    .unwrap();
                } else {
                    for (idx, vals) in &blocks {
                        m.add_values(idx, idx, vals).unwrap();
                    }
                    if with_outside {
                        m.add_values(&outside.0, &outside.0, &outside.1).unwrap();
                    }
                }
            }
            m.assemble().unwrap();
            stored.push(m.stored_entries().unwrap());
        }
        // The first assembly stores the entries outside the pattern in the rows this rank
        // owns (on two ranks: rows 0-2 and column 27 on one, row 27 and columns 0-2 on the
        // other), the second finds them stored.
        let outside_here = outside
            .0
            .iter()
            .filter(|&&r| (first..end).contains(&r))
            .map(|&r| {
                let row = &pattern.rows[(r - first) as usize];
                outside.0.iter().filter(|c| !row.contains(c)).count() as u64
            })
            .sum::<u64>();
        assert!(outside_here > 0);
        assert_eq!(stored, [preallocated + outside_here; 2], "rank {rank}");
        let owned: Vec<i32> = (first..end).collect();
        let all: Vec<i32> = (0..ROWS).collect();
        m.get_values(&owned, &all).unwrap()
    };
    let (by_rows, by_set_values) = (build(true), build(false));
    assert!(by_set_values.iter().filter(|v| **v != 0.0).count() > 300 / size as usize);
    for (k, (a, b)) in by_rows.iter().zip(&by_set_values).enumerate() {
        let (row, col) = (first + k as i32 / ROWS, k as i32 % ROWS);
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "entry ({row}, {col}) on rank {rank}"
        );
    }
}
