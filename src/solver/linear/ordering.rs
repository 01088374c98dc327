//! A fill-reducing order for projective dynamics' factor from where the particles are:
//! nested dissection by coordinate bisection.
//!
//! The springs of a cloth join near neighbours, so a line across the cloth that cuts it in two
//! is a small set of particles (a separator). Numbering each half first, recursively, and the
//! separator last keeps the halves' columns of the factor apart and gathers the separators
//! into wide supernodes. On the 256² grid the factor has about as many values as in faer's
//! minimum degree order (3.49 M against 3.47 M) in 10,282 supernodes instead of 17,367, and the
//! narrow ones are what a substitution pays for beyond its values
//! (`cargo test --release --lib substitutions_against -- --ignored --nocapture` times both).
//! Which order a factorisation uses is decided in [`crate::solver::methods::projective`], by a model of the
//! substitutions' cost.
//!
//! Each cut is at the median of the set's longer extent; the separator is the particles of
//! the upper half that have a spring to the lower half, so the two halves left share no spring.
//! The order is then put in [`postorder`] of its elimination tree, which the substitutions'
//! two halves need.

use glam::DVec2;

/// Sets of at most this many particles are numbered as they come (measured on the 256² cloth,
/// 2 to 16: 4 gave the fastest substitutions).
pub const LEAF: usize = 4;

/// The graph of `rows` rows joined by `pairs` (each pair once, in either order), as what
/// [`nested_dissection`] reads: `neighbours[start[r]..start[r + 1]]` are the rows joined to r.
pub fn adjacency(
    rows: usize,
    pairs: impl Iterator<Item = (usize, usize)>,
) -> (Vec<usize>, Vec<u32>) {
    let mut adjacent = vec![vec![]; rows];
    for (a, b) in pairs.filter(|(a, b)| a != b) {
        adjacent[a].push(b as u32);
        adjacent[b].push(a as u32);
    }
    let mut start = Vec::with_capacity(rows + 1);
    start.push(0);
    for a in &adjacent {
        start.push(start[start.len() - 1] + a.len());
    }
    (start, adjacent.concat())
}

/// The rows `0..position.len()` in nested dissection order: `order[p]` is the row numbered p.
/// `neighbours[start[r]..start[r + 1]]` are the rows joined to row r by a spring.
pub fn nested_dissection(position: &[DVec2], start: &[usize], neighbours: &[u32]) -> Vec<u32> {
    let n = position.len();
    let mut rows: Vec<u32> = (0..n as u32).collect();
    let mut order = Vec::with_capacity(n);
    // side[r] is the set a row was last put in: the lower half of a cut is marked with the
    // cut's number, so the test for a spring across the cut needs no clearing.
    let mut side = vec![u32::MAX; n];
    let mut cuts = 0u32;
    // Sets still to number, and separators waiting for the sets before them: a stack of work
    // (depth-first, lower half first), so that a deep recursion cannot overflow the stack.
    enum Work {
        Dissect(std::ops::Range<usize>),
        Emit(std::ops::Range<usize>),
    }
    let mut stack = vec![Work::Dissect(0..n)];
    while let Some(work) = stack.pop() {
        let range = match work {
            Work::Emit(range) => {
                order.extend_from_slice(&rows[range]);
                continue;
            }
            Work::Dissect(range) => range,
        };
        let set = &mut rows[range.clone()];
        if set.len() <= LEAF {
            order.extend_from_slice(set);
            continue;
        }
        let (lo, hi) = set.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &r| {
                let p = position[r as usize];
                (lo.min(p), hi.max(p))
            },
        );
        let extent = hi - lo;
        // NaN extents compare false: such a set is cut along x, by index order if need be.
        let along_y = extent.y > extent.x;
        let key = |r: &u32| {
            let p = position[*r as usize];
            if along_y { p.y } else { p.x }
        };
        let mut half = set.len() / 2;
        set.select_nth_unstable_by(half, |a, b| key(a).total_cmp(&key(b)));
        // Particles level with the median go to the upper half, so that a cut between rows of
        // a grid runs between them, not through one (a ragged cut makes a wider separator).
        let median = key(&set[half]);
        let mut lower = 0;
        for i in 0..half {
            if key(&set[i]).total_cmp(&median).is_lt() {
                set.swap(lower, i);
                lower += 1;
            }
        }
        if lower > 0 {
            half = lower;
        }
        cuts += 1;
        for &r in &set[..half] {
            side[r as usize] = cuts;
        }
        // The upper half: the separator (a spring to the lower half) to the end.
        let upper = &mut set[half..];
        let mut kept = 0;
        for i in 0..upper.len() {
            let r = upper[i] as usize;
            let across = neighbours[start[r]..start[r + 1]]
                .iter()
                .any(|&q| side[q as usize] == cuts);
            if !across {
                upper.swap(kept, i);
                kept += 1;
            }
        }
        let (a, b) = (range.start, range.start + half);
        let separator = b + kept..range.end;
        stack.push(Work::Emit(separator));
        stack.push(Work::Dissect(b..b + kept));
        stack.push(Work::Dissect(a..b));
    }
    postorder(&order, start, neighbours)
}

/// `order` renumbered so that its elimination tree is in postorder, every subtree a run of
/// consecutive numbers ending at its root: the same tree, so the same fill and supernodes.
///
/// Why: the substitutions run two subtrees at once ([`super::etree::TreeSplit`]), which needs
/// each subtree's columns to be a run. Nested dissection numbers each half before its
/// separator, so its cuts give runs, but a leaf set numbered as it comes can hold two pieces
/// with no spring between them, whose columns then interleave: on a torn cloth (nearly every
/// torn grid tried), or on the whole 256² grid with leaves of 16, and the substitutions then
/// ran on one thread only. Children are visited in ascending order, so an order already in
/// postorder (the whole grid's, with leaves of 4) comes back unchanged.
pub fn postorder(order: &[u32], start: &[usize], neighbours: &[u32]) -> Vec<u32> {
    const NONE: usize = usize::MAX;
    let n = order.len();
    let mut at = vec![0usize; n];
    for (k, &r) in order.iter().enumerate() {
        at[r as usize] = k;
    }
    // The elimination tree of the matrix in this order (Liu's algorithm: each row's neighbours
    // numbered before it hang, through their trees' current roots, under it; `ancestor`
    // shortcuts the climbs).
    let (mut parent, mut ancestor) = (vec![NONE; n], vec![NONE; n]);
    for (k, &r) in order.iter().enumerate() {
        for &q in &neighbours[start[r as usize]..start[r as usize + 1]] {
            let mut i = at[q as usize];
            if i >= k {
                continue;
            }
            while ancestor[i] != NONE && ancestor[i] != k {
                let next = ancestor[i];
                ancestor[i] = k;
                i = next;
            }
            if ancestor[i] == NONE {
                ancestor[i] = k;
                parent[i] = k;
            }
        }
    }
    // Children lists in ascending order (a counting sort by parent), then a depth-first walk
    // from each root in ascending order, numbering each node after its children.
    let mut first = vec![0usize; n + 1];
    for &p in &parent {
        if p != NONE {
            first[p + 1] += 1;
        }
    }
    for k in 0..n {
        first[k + 1] += first[k];
    }
    let mut fill = first.clone();
    let mut children = vec![0usize; first[n]];
    for (k, &p) in parent.iter().enumerate() {
        if p != NONE {
            children[fill[p]] = k;
            fill[p] += 1;
        }
    }
    let mut post = Vec::with_capacity(n);
    let mut stack: Vec<(usize, usize)> = vec![];
    for root in (0..n).filter(|&k| parent[k] == NONE) {
        stack.push((root, first[root]));
        while let Some((k, next)) = stack.last_mut() {
            if *next < first[*k + 1] {
                let child = children[*next];
                *next += 1;
                stack.push((child, first[child]));
            } else {
                post.push(order[*k]);
                stack.pop();
            }
        }
    }
    post
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A w × w grid with the cloth's springs (right, down and both diagonals), as adjacency.
    fn grid(w: usize) -> (Vec<DVec2>, Vec<usize>, Vec<u32>) {
        let position: Vec<DVec2> = (0..w * w)
            .map(|r| DVec2::new((r % w) as f64, (r / w) as f64))
            .collect();
        let mut pairs = vec![];
        for i in 0..w as i64 {
            for j in 0..w as i64 {
                for (di, dj) in [(0, 1), (1, 0), (1, 1), (1, -1)] {
                    let (ni, nj) = (i + di, j + dj);
                    if ni < w as i64 && (0..w as i64).contains(&nj) {
                        pairs.push(((i * w as i64 + j) as usize, (ni * w as i64 + nj) as usize));
                    }
                }
            }
        }
        let (start, neighbours) = adjacency(w * w, pairs.into_iter());
        (position, start, neighbours)
    }

    /// Every row once; and the last rows numbered are the first cut's separator, a line across
    /// the grid that leaves its two sides with no spring between them.
    #[test]
    fn a_grid_is_cut_by_lines_and_every_row_is_numbered_once() {
        let w = 20;
        let (position, start, neighbours) = grid(w);
        let order = nested_dissection(&position, &start, &neighbours);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..(w * w) as u32).collect::<Vec<_>>());
        let separator = &order[order.len() - w..];
        let column = position[separator[0] as usize].x;
        assert!(separator.iter().all(|&r| position[r as usize].x == column));
        // Removing it leaves no spring from one side to the other.
        for r in 0..w * w {
            let x = position[r].x;
            for &q in &neighbours[start[r]..start[r + 1]] {
                let y = position[q as usize].x;
                assert!(x == column || y == column || (x < column) == (y < column));
            }
        }
    }

    /// Two chains with no spring between them, numbered alternately (0-2-4 and 1-3-5): each
    /// chain's elimination tree is a path to its last row, so in postorder each chain comes
    /// whole; an order already in postorder (the dissection's, on a whole grid) is kept.
    #[test]
    fn postorder_makes_each_subtree_a_run_and_keeps_a_postorder() {
        let (start, neighbours) = adjacency(6, [(0, 2), (2, 4), (1, 3), (3, 5)].into_iter());
        let order: Vec<u32> = (0..6).collect();
        assert_eq!(postorder(&order, &start, &neighbours), [0, 2, 4, 1, 3, 5]);
        let (position, start, neighbours) = grid(20);
        let dissected = nested_dissection(&position, &start, &neighbours);
        assert_eq!(postorder(&dissected, &start, &neighbours), dissected);
    }

    /// Points all at one place (or not a number) still split by index: every row numbered.
    #[test]
    fn degenerate_positions_still_give_an_order() {
        for p in [DVec2::ZERO, DVec2::NAN] {
            let (_, start, neighbours) = grid(9);
            let position = vec![p; 81];
            let mut order = nested_dissection(&position, &start, &neighbours);
            order.sort_unstable();
            assert_eq!(order, (0..81).collect::<Vec<_>>());
        }
    }
}
