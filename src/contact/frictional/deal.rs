//! Which rank does the contact work of which traction node (module docs, "Parallel layout").

/// The ranks that share the contact work of pass `pass` of `passes`: the passes of an
/// interface are dealt out first, so that on two ranks the two passes of a two-pass interface
/// go one to each rank whole (no face is integrated twice); with more ranks than passes, each
/// pass gets its own block of ranks, which [`deal_in_strips`] then shares out.
pub(crate) fn pass_ranks(pass: usize, passes: usize, ranks: usize) -> std::ops::Range<usize> {
    if ranks >= passes {
        pass * ranks / passes..(pass + 1) * ranks / passes
    } else {
        let rank = pass * ranks / passes;
        rank..rank + 1
    }
}

/// The strip (of `strips`) that does the contact work of each traction node: the nodes, sorted
/// along the longest side of their bounding box (reference positions; ties by index), cut into
/// `strips` strips of equal counts. The faces next to each cut (one row of faces, or two when
/// the cut falls inside a row of nodes) are integrated by both neighbours. Equal counts are
/// equal work when the whole surface is in contact; a contact zone smaller than the surface
/// may fall in one strip.
pub(crate) fn deal_in_strips(points: &[[f64; 3]], strips: usize) -> Vec<usize> {
    let extent: [f64; 3] = std::array::from_fn(|c| {
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |b, p| {
                (b.0.min(p[c]), b.1.max(p[c]))
            });
        hi - lo
    });
    // The longest side; the first axis of equally long ones.
    let axis = (0..3)
        .max_by(|&i, &j| extent[i].total_cmp(&extent[j]).then(j.cmp(&i)))
        .unwrap_or(0);
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
    let mut strip = vec![0; points.len()];
    for (position, &a) in order.iter().enumerate() {
        strip[a] = position * strips / points.len();
    }
    strip
}

/// The contact work of one pass that falls to one rank.
pub(crate) struct Work {
    /// The traction nodes it holds (indices into the pass's nodes).
    pub held: Vec<usize>,
    /// The secondary faces carrying a node it holds (the faces it integrates).
    pub faces: Vec<usize>,
    /// Per secondary face: whether it holds the face's first traction node (and so counts
    /// the face's pair statistics).
    pub tallied: Vec<bool>,
}

impl Work {
    /// Deals the traction nodes at reference positions `points` in strips to the ranks
    /// `workers` ([`deal_in_strips`]); the share of `rank`. `carriers`: per secondary face,
    /// its traction nodes.
    pub fn dealt(
        points: &[[f64; 3]],
        carriers: &[Vec<usize>],
        workers: std::ops::Range<usize>,
        rank: usize,
    ) -> Work {
        let holder: Vec<usize> = deal_in_strips(points, workers.len())
            .into_iter()
            .map(|strip| workers.start + strip)
            .collect();
        Work {
            held: (0..points.len()).filter(|&a| holder[a] == rank).collect(),
            faces: (0..carriers.len())
                .filter(|&s| carriers[s].iter().any(|&a| holder[a] == rank))
                .collect(),
            tallied: carriers
                .iter()
                .map(|c| c.first().is_some_and(|&a| holder[a] == rank))
                .collect(),
        }
    }
}
