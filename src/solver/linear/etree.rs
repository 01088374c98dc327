//! The elimination tree of a supernodal Cholesky factor cut into two halves that the
//! substitutions ([`super::cholesky`]) can run at once.

/// The slot of a row that no half shares.
pub const NOT_SHARED: u32 = u32::MAX;

/// The elimination tree cut into two halves that the substitutions can run at once, and the
/// shared supernodes above them.
///
/// faer numbers the supernodes in postorder, so a subtree is a run of consecutive supernodes
/// and columns. A supernode's forward updates go only to its ancestors, and its back
/// substitution reads only theirs. Two sets of disjoint subtrees therefore touch disjoint
/// columns, except for their common ancestors (the shared supernodes, at the top of the
/// tree): each half sends its updates of those rows to its own buffer in the forward pass,
/// and reads them from a copy in the backward pass.
#[derive(Debug, Clone)]
pub struct TreeSplit {
    /// The two halves, the first in lower columns.
    pub groups: [Half; 2],
    /// The shared supernodes, ascending.
    pub top: Vec<u32>,
    /// Each column's index among the shared rows, or [`NOT_SHARED`].
    pub slot: Vec<u32>,
    /// The shared rows, by slot.
    pub top_rows: Vec<u32>,
    /// Where each supernode's shared rows begin in its rows below: they are a supernode's
    /// highest ancestors, so they come last.
    pub shared_from: Vec<u32>,
}

/// One half: whole subtrees, each a run of supernodes, in one column range.
#[derive(Debug, Clone)]
pub struct Half {
    /// Each subtree's supernodes, ascending.
    pub subtrees: Vec<std::ops::Range<usize>>,
    /// The columns from the first subtree's first to the last one's last (shared columns
    /// between them are read and written only through the shared rows' buffers).
    pub columns: std::ops::Range<usize>,
}

impl Half {
    /// The half's supernodes, ascending.
    pub fn supernodes(&self) -> impl DoubleEndedIterator<Item = usize> + '_ {
        self.subtrees.iter().flat_map(|r| r.clone())
    }
}

impl TreeSplit {
    /// The halves' columns of x and y, as two disjoint pieces (each with its first column).
    pub fn halves<'a, R>(
        &self,
        x: &'a mut [R],
        y: &'a mut [R],
    ) -> [(usize, &'a mut [R], &'a mut [R]); 2] {
        let [a, b] = &self.groups;
        let (xa, xb) = x.split_at_mut(b.columns.start);
        let (ya, yb) = y.split_at_mut(b.columns.start);
        let len_b = b.columns.len();
        [
            (
                a.columns.start,
                &mut xa[a.columns.clone()],
                &mut ya[a.columns.clone()],
            ),
            (b.columns.start, &mut xb[..len_b], &mut yb[..len_b]),
        ]
    }

    /// Cuts the tree of supernodes `begin` (columns), `pattern` and `row` (their rows below)
    /// into two halves of nearly equal work, or `None` when the tree does not split well
    /// (a chain, or most of the work at the top) or is not in postorder.
    pub fn of(begin: &[usize], pattern: &[usize], row: &[u32]) -> Option<TreeSplit> {
        let n = begin.len() - 1;
        let columns = begin[n];
        let mut supernode_of = vec![0u32; columns];
        for s in 0..n {
            supernode_of[begin[s]..begin[s + 1]].fill(s as u32);
        }
        let rows_below = |s: usize| &row[pattern[s]..pattern[s + 1]];
        let parent: Vec<Option<usize>> = (0..n)
            .map(|s| {
                rows_below(s)
                    .iter()
                    .min()
                    .map(|&r| supernode_of[r as usize] as usize)
            })
            .collect();
        // Work (values of the block), subtree sizes and first descendants, children first.
        let mut work: Vec<f64> = (0..n)
            .map(|s| {
                let cols = begin[s + 1] - begin[s];
                ((cols + rows_below(s).len()) * cols) as f64
            })
            .collect();
        let own = work.clone();
        let mut size = vec![1usize; n];
        let mut first = (0..n).collect::<Vec<_>>();
        let mut children = vec![vec![]; n];
        for s in 0..n {
            if let Some(p) = parent[s] {
                if p <= s {
                    return None;
                }
                work[p] += work[s];
                size[p] += size[s];
                first[p] = first[p].min(first[s]);
                children[p].push(s);
            }
        }
        // Postorder: every subtree is the run of supernodes that ends at its root.
        if (0..n).any(|s| first[s] + size[s] != s + 1) {
            return None;
        }
        let total: f64 = own.iter().sum();
        let mut candidates: Vec<usize> = (0..n).filter(|&s| parent[s].is_none()).collect();
        let mut top = vec![];
        let mut top_work = 0.0;
        loop {
            candidates.sort_unstable();
            // The best cut of the candidates, in order, into a first and a second half.
            let sum: f64 = candidates.iter().map(|&c| work[c]).sum();
            let mut prefix = 0.0;
            let mut best = (f64::INFINITY, 0);
            for (k, &c) in candidates
                .iter()
                .enumerate()
                .take(candidates.len().saturating_sub(1))
            {
                prefix += work[c];
                let worst = prefix.max(sum - prefix);
                if worst < best.0 {
                    best = (worst, k + 1);
                }
            }
            if best.0 <= 0.55 * sum {
                let (a, b) = candidates.split_at(best.1);
                let half = |cs: &[usize]| Half {
                    subtrees: cs.iter().map(|&c| first[c]..c + 1).collect(),
                    columns: begin[first[cs[0]]]..begin[cs[cs.len() - 1] + 1],
                };
                top.sort_unstable();
                let mut slot = vec![NOT_SHARED; columns];
                let mut top_rows = vec![];
                for &t in &top {
                    for (r, q) in slot
                        .iter_mut()
                        .enumerate()
                        .take(begin[t + 1])
                        .skip(begin[t])
                    {
                        *q = top_rows.len() as u32;
                        top_rows.push(r as u32);
                    }
                }
                let mut shared_from = Vec::with_capacity(n);
                for s in 0..n {
                    let rows = rows_below(s);
                    let from = rows.partition_point(|&r| slot[r as usize] == NOT_SHARED);
                    if rows[from..].iter().any(|&r| slot[r as usize] == NOT_SHARED) {
                        return None;
                    }
                    shared_from.push(from as u32);
                }
                return Some(TreeSplit {
                    groups: [half(a), half(b)],
                    top: top.into_iter().map(|t| t as u32).collect(),
                    slot,
                    top_rows,
                    shared_from,
                });
            }
            // Open up the biggest subtree: its root joins the shared top.
            let (i, &c) = candidates
                .iter()
                .enumerate()
                .max_by(|a, b| work[*a.1].total_cmp(&work[*b.1]))?;
            top_work += own[c];
            if children[c].is_empty() || top_work > 0.5 * total {
                return None;
            }
            candidates.swap_remove(i);
            top.push(c);
            candidates.extend(&children[c]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tree of seven one-column supernodes in postorder: 0 and 1 under 2, 3 and 4 under 5,
    /// 2 and 5 under the root 6. Each supernode's rows below are its ancestors' columns.
    #[test]
    fn a_balanced_tree_splits_below_its_root() {
        let parent = [Some(2), Some(2), Some(6), Some(5), Some(5), Some(6), None];
        let (mut pattern, mut row) = (vec![0], vec![]);
        for s in 0..7 {
            let mut p = parent[s];
            while let Some(a) = p {
                row.push(a as u32);
                p = parent[a];
            }
            pattern.push(row.len());
        }
        let begin: Vec<usize> = (0..=7).collect();
        let split = TreeSplit::of(&begin, &pattern, &row).expect("the tree splits");
        let [a, b] = &split.groups;
        assert_eq!(a.supernodes().collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(b.supernodes().collect::<Vec<_>>(), [3, 4, 5]);
        assert_eq!((a.columns.clone(), b.columns.clone()), (0..3, 3..6));
        assert_eq!((split.top, split.top_rows), (vec![6], vec![6]));
        assert_eq!(split.shared_from, [1, 1, 0, 1, 1, 0, 0]);
        assert_eq!(
            split.slot,
            [
                NOT_SHARED, NOT_SHARED, NOT_SHARED, NOT_SHARED, NOT_SHARED, NOT_SHARED, 0
            ]
        );
        // A chain does not split: 0 under 1 under 2 under 3, each one's rows below its
        // ancestors'.
        let chain_row: Vec<u32> = vec![1, 2, 3, 2, 3, 3];
        let chain_pattern = [0, 3, 5, 6, 6];
        assert!(TreeSplit::of(&[0, 1, 2, 3, 4], &chain_pattern, &chain_row).is_none());
    }
}
