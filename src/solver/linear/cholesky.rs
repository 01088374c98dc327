//! The Cholesky factor L of projective dynamics' global matrix, kept in faer's supernodal
//! layout, and the two substitutions that solve L Lᵀ u = b for the x and y components at once.
//!
//! faer factors the matrix; the substitutions are written here because each projective
//! dynamics iteration is one solve with a two-column right-hand side, and faer's general
//! supernodal solve, with its per-supernode dense kernels and workspace, measured about 2×
//! slower on these factors (thousands of supernodes, most of them a few columns wide).
//!
//! A supernode is a run of columns with one shared pattern below its diagonal block, stored as
//! one dense column-major block. [`Factor::finish`] rewrites each block as the inverse of its
//! diagonal block over W = L_B L_D⁻¹ ([`super::supernode::invert`]), so that a supernode's
//! share of either substitution is one dense product with no column waiting on another: the
//! forward substitution multiplies the block by the supernode's right-hand side, keeps the top
//! rows as its solution and scatters the rest to the rows below once; the back substitution
//! gathers those rows once and takes each column's dot product with them and the supernode's
//! own values ([`super::supernode`] has the dense kernels, portable and AVX, with the same
//! bits). Solving through the triangles instead, column by column, took about twice as long a
//! value on the 4–15-column supernodes that hold half of the 256² cloth's factor.
//!
//! What a solve costs is its work per value and per supernode (the 256² cloth's factor has
//! 3.5 M values in 10 k supernodes, and a solve reads each value twice), and then the bytes it
//! reads. Two things cut both:
//! * the values are stored as f32, and the substitutions compute in f32: the gather that puts
//!   the right-hand side in the factor's order rounds it to f32, and the correction is added
//!   back in f64. Eight lanes to a register instead of four, and no conversion as a value is
//!   loaded: a solve of the 256² cloth's factor took about a quarter less time than with f32
//!   values and f64 arithmetic. Projective dynamics solves for the correction of its iterate
//!   from a residual it computes in f64, so the rounding (a solve is then good to about 1e-6)
//!   leaves its fixed point exactly where it was ([`crate::solver::methods::projective`]). A matrix whose
//!   condition number may be too large for that keeps its values, and the arithmetic, in f64,
//!   through the same kernels;
//! * the substitutions walk the values in address order, but in blocks of a few hundred
//!   bytes, which the hardware prefetcher does not follow; they ask for the values 8 KB ahead.
//!
//! The lane order is fixed, so the result is the same bits on every CPU and thread count.

use super::etree::TreeSplit;
use super::supernode::{Block, Real, invert};
use crate::solver::threads::Threads;
use faer::perm::Perm;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use rayon::prelude::*;

/// The factor L: supernode s spans columns `begin[s]..begin[s + 1]`; its values are a dense
/// column-major block of (columns + pattern rows) × columns starting at `values[s]`, the
/// diagonal block on top and then the rows `row[pattern[s]..pattern[s + 1]]` below it.
#[derive(Debug, Default, Clone)]
pub struct Factor {
    begin: Vec<usize>,
    values: Vec<usize>,
    pattern: Vec<usize>,
    row: Vec<u32>,
    /// The blocks' values, as faer's numeric factorisation writes them (emptied by
    /// [`Self::finish`] when it rounds them to f32).
    pub l: Vec<f64>,
    /// The blocks' values rounded to f32, which the substitutions use instead of [`Self::l`],
    /// computing in f32, when the matrix is well enough conditioned ([`Self::finish`]).
    single: Vec<f32>,
    /// The two halves that a solve runs at once, if the tree splits well.
    split: Option<TreeSplit>,
}

/// The permutation that numbers row `forward[p]` of a matrix p (faer's forward array), for a
/// custom fill-reducing order.
pub fn permutation(forward: Vec<usize>) -> Perm<usize> {
    let n = forward.len();
    let mut inverse = vec![0; n];
    for (p, &r) in forward.iter().enumerate() {
        inverse[r] = p;
    }
    Perm::new_checked(forward.into_boxed_slice(), inverse.into_boxed_slice(), n)
}

/// Values for a supernode's pattern rows, or for the shared rows, x and y apart.
#[derive(Debug, Clone)]
pub struct Below<R> {
    x: Vec<R>,
    y: Vec<R>,
}

/// The buffers of a solve, kept from solve to solve.
#[derive(Debug, Clone)]
pub struct Substitution<R> {
    /// Each half's supernode at hand.
    below: [Below<R>; 2],
    /// Each half's updates of the shared rows in the forward pass.
    spill: [Below<R>; 2],
    /// The shared rows' values in the backward pass.
    top: Below<R>,
}

/// A part of the right-hand side, rows `lo..lo + x.len()`.
struct Span<'a, R> {
    lo: usize,
    x: &'a mut [R],
    y: &'a mut [R],
}

/// The halves' columns of x and y ([`TreeSplit::halves`]).
fn spans<'a, R>(split: &TreeSplit, x: &'a mut [R], y: &'a mut [R]) -> [Span<'a, R>; 2] {
    split.halves(x, y).map(|(lo, x, y)| Span { lo, x, y })
}

/// Factors with fewer values than this solve their halves one after the other, on the
/// calling thread. Measured on a 2-core AMD EPYC with the halves at once, alternating runs
/// (projective dynamics, dt = 1/60 s, 2 threads, 600 steps): 64² (150 k values) went from
/// 4.1–4.8 to 3.1–3.9 ms a step, 256² (3.4 M) from 122–137 to 96–112 ms.
const PARALLEL_MIN_VALUES: usize = 1 << 16;

impl Factor {
    /// The structure of `symbolic`'s factor, with room for its values.
    pub fn of(symbolic: &SymbolicCholesky<usize>) -> Result<Factor, String> {
        let s = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            // faer keeps a tiny matrix simplicial whatever is asked: each column, its diagonal
            // first (rows ascending), is then a supernode of one column.
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (col, rows) = (s.col_ptr(), s.row_idx());
                let n = s.nrows();
                let mut pattern = Vec::with_capacity(n + 1);
                let mut row = Vec::new();
                for j in 0..n {
                    pattern.push(row.len());
                    if rows.get(col[j]) != Some(&j) {
                        return Err("projective dynamics: unexpected factor layout".into());
                    }
                    row.extend(rows[col[j] + 1..col[j + 1]].iter().map(|&r| r as u32));
                }
                pattern.push(row.len());
                let begin: Vec<usize> = (0..=n).collect();
                return Ok(Factor {
                    split: TreeSplit::of(&begin, &pattern, &row),
                    begin,
                    values: col[..=n].to_vec(),
                    pattern,
                    row,
                    l: vec![0.0; symbolic.len_val()],
                    single: vec![],
                });
            }
        };
        let n = s.n_supernodes();
        let pattern_start = s.col_ptr_for_row_idx();
        let mut pattern = Vec::with_capacity(n + 1);
        let mut row = Vec::new();
        for (p, &len) in s.nnz_per_super().iter().enumerate().take(n) {
            pattern.push(row.len());
            let start = pattern_start[p];
            row.extend(s.row_idx()[start..start + len].iter().map(|&r| r as u32));
        }
        pattern.push(row.len());
        let begin: Vec<usize> = s
            .supernode_begin()
            .iter()
            .copied()
            .chain(s.supernode_end().last().copied())
            .collect();
        Ok(Factor {
            split: TreeSplit::of(&begin, &pattern, &row),
            begin,
            values: s.col_ptr_for_val()[..=n].to_vec(),
            pattern,
            row,
            l: vec![0.0; symbolic.len_val()],
            single: vec![],
        })
    }

    /// Takes in the values that the numeric factorisation wrote to [`Self::l`]: rewrites each
    /// supernode's block as its diagonal block's inverse over W (in f64, see the module docs)
    /// and, if `single`, rounds every value to f32 for the substitutions, which then read half
    /// the bytes and compute in f32. (Projective dynamics solves for the
    /// correction to its iterate, whose residual it computes in f64, so the rounding slows its
    /// convergence by a little and leaves its fixed point where it was: see
    /// [`crate::solver::methods::projective`].)
    pub fn finish(&mut self, single: bool, threads: &Threads, springs: usize) {
        // Each supernode's block, apart, to invert on the pool's threads.
        let n = self.supernodes();
        let mut blocks = Vec::with_capacity(n);
        let (mut rest, mut at) = (&mut self.l[..], 0);
        for s in 0..n {
            let cols = self.begin[s + 1] - self.begin[s];
            let rows = cols + self.pattern[s + 1] - self.pattern[s];
            let skip = self.values[s] - at;
            let (block, after) = std::mem::take(&mut rest)[skip..].split_at_mut(rows * cols);
            blocks.push((block, rows, cols));
            (rest, at) = (after, self.values[s] + rows * cols);
        }
        threads.run(springs, || {
            blocks
                .into_par_iter()
                .for_each(|(block, rows, cols)| invert(block, rows, cols))
        });
        if single {
            let l = &self.l;
            self.single = threads.run(springs, || l.par_iter().map(|&v| v as f32).collect());
            self.l = Vec::new();
        } else {
            self.single = Vec::new();
        }
    }

    /// Solves L Lᵀ u = b in place for two right-hand sides, `x` and `y`, in the precision of
    /// the factor's values; with a split tree
    /// ([`TreeSplit`]) its two halves run on two of `threads` (or one after the other on one:
    /// the same arithmetic, so the same bits, on any thread count).
    ///
    /// # Panics
    /// If `T` is not the precision of the factor's values ([`Self::single_precision`]).
    pub fn solve<T: Stored>(
        &self,
        x: &mut [T],
        y: &mut [T],
        work: &mut Substitution<T>,
        threads: &Threads,
    ) {
        assert!(
            T::stored(self).len() == self.len(),
            "a solve in the factor's precision"
        );
        let Some(split) = &self.split else {
            let mut all = Span { lo: 0, x, y };
            self.forward::<T>(0..self.supernodes(), &mut all, &mut work.below[0], None);
            self.backward::<T>(
                (0..self.supernodes()).rev(),
                &mut all,
                &mut work.below[0],
                None,
            );
            return;
        };
        let [ga, gb] = &split.groups;
        let sharing = self.len() >= PARALLEL_MIN_VALUES;
        let Substitution { below, spill, top } = work;
        let [below_a, below_b] = below;
        let [spill_a, spill_b] = spill;
        for buf in [
            &mut spill_a.x,
            &mut spill_a.y,
            &mut spill_b.x,
            &mut spill_b.y,
        ] {
            buf.clear();
            buf.resize(split.top_rows.len(), T::default());
        }
        // Forward: the halves, each sending its updates of the shared rows to its own buffer;
        // those added in a fixed order; then the shared supernodes.
        {
            let [mut a, mut b] = spans(split, x, y);
            threads.join(
                sharing,
                || self.forward::<T>(ga.supernodes(), &mut a, below_a, Some((split, spill_a))),
                || self.forward::<T>(gb.supernodes(), &mut b, below_b, Some((split, spill_b))),
            );
        }
        for (q, &r) in split.top_rows.iter().enumerate() {
            let r = r as usize;
            x[r] = x[r] - spill_a.x[q] - spill_b.x[q];
            y[r] = y[r] - spill_a.y[q] - spill_b.y[q];
        }
        let mut all = Span { lo: 0, x, y };
        self.forward::<T>(
            split.top.iter().map(|&s| s as usize),
            &mut all,
            below_a,
            None,
        );
        // Backward: the shared supernodes, then the halves, reading the shared rows' values.
        self.backward::<T>(
            split.top.iter().rev().map(|&s| s as usize),
            &mut all,
            below_a,
            None,
        );
        top.x.clear();
        top.x
            .extend(split.top_rows.iter().map(|&r| all.x[r as usize]));
        top.y.clear();
        top.y
            .extend(split.top_rows.iter().map(|&r| all.y[r as usize]));
        let [mut a, mut b] = spans(split, x, y);
        let top = &*top;
        threads.join(
            sharing,
            || self.backward::<T>(ga.supernodes().rev(), &mut a, below_a, Some((split, top))),
            || self.backward::<T>(gb.supernodes().rev(), &mut b, below_b, Some((split, top))),
        );
    }

    /// The parts of the elimination tree that a solve runs at once on two or more threads: 2,
    /// or 1 when the tree does not split into halves of nearly equal work or the factor is too
    /// small to share ([`PARALLEL_MIN_VALUES`]); 0 for an empty factor.
    pub fn halves(&self) -> usize {
        match (self.supernodes(), &self.split) {
            (0, _) => 0,
            (_, Some(_)) if self.len() >= PARALLEL_MIN_VALUES => 2,
            _ => 1,
        }
    }

    /// Whether the values are f32, and so the solves' right-hand sides and arithmetic.
    pub fn single_precision(&self) -> bool {
        !self.single.is_empty()
    }

    /// The factor's stored values.
    pub fn len(&self) -> usize {
        self.single.len().max(self.l.len())
    }

    /// The factor's supernodes (0 for an empty factor).
    pub fn supernodes(&self) -> usize {
        self.begin.len().saturating_sub(1)
    }

    /// L v = b over `supernodes` (ascending), within `span`; updates of rows with a `shared`
    /// slot are summed there instead.
    fn forward<T: Stored>(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span<T>,
        below: &mut Below<T>,
        shared: Option<(&TreeSplit, &mut Below<T>)>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::solver::threads::machine::avx() {
            // SAFETY: the CPU has AVX.
            unsafe { self.forward_avx::<T>(supernodes, span, below, shared) };
            return;
        }
        self.forward_pass::<false, T>(supernodes, span, below, shared);
    }

    /// [`Self::forward_pass`] compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn forward_avx<T: Stored>(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span<T>,
        below: &mut Below<T>,
        shared: Option<(&TreeSplit, &mut Below<T>)>,
    ) {
        self.forward_pass::<true, T>(supernodes, span, below, shared);
    }

    /// Lᵀ u = v over `supernodes` (descending), within `span`; rows with a `shared` slot are
    /// read from there.
    fn backward<T: Stored>(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span<T>,
        below: &mut Below<T>,
        shared: Option<(&TreeSplit, &Below<T>)>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::solver::threads::machine::avx() {
            // SAFETY: the CPU has AVX.
            unsafe { self.backward_avx::<T>(supernodes, span, below, shared) };
            return;
        }
        self.backward_pass::<false, T>(supernodes, span, below, shared);
    }

    /// [`Self::backward_pass`] compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn backward_avx<T: Stored>(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span<T>,
        below: &mut Below<T>,
        shared: Option<(&TreeSplit, &Below<T>)>,
    ) {
        self.backward_pass::<true, T>(supernodes, span, below, shared);
    }

    #[inline(always)]
    fn forward_pass<const AVX: bool, T: Stored>(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span<T>,
        below: &mut Below<T>,
        mut shared: Option<(&TreeSplit, &mut Below<T>)>,
    ) {
        let mut ahead = Prefetch::default();
        for s in supernodes {
            let (start, end, pattern, block) = self.supernode::<T>(s);
            ahead.forward(T::stored(self), self.values[s] + block.values.len());
            let (lo, x, y) = (span.lo, &mut *span.x, &mut *span.y);
            let (xs, ys) = (&mut x[start - lo..end - lo], &mut y[start - lo..end - lo]);
            let (bx, by) = below.rows_with_room(block.rows);
            block.product::<AVX>(xs, ys, bx, by);
            let ((ux, bx), (uy, by)) = (bx.split_at(block.cols), by.split_at(block.cols));
            xs.copy_from_slice(ux);
            ys.copy_from_slice(uy);
            // The rows below in this span, then (in a half) the shared rows, which come last.
            let from = shared
                .as_ref()
                .map_or(pattern.len(), |(split, _)| split.shared_from[s] as usize);
            for ((&r, &bx), &by) in pattern[..from].iter().zip(bx).zip(by) {
                let r = r as usize - lo;
                x[r] -= bx;
                y[r] -= by;
            }
            if let Some((split, spill)) = &mut shared {
                let rows = pattern[from..].iter().zip(&bx[from..]).zip(&by[from..]);
                for ((&r, &bx), &by) in rows {
                    let q = split.slot[r as usize] as usize;
                    spill.x[q] += bx;
                    spill.y[q] += by;
                }
            }
        }
    }

    #[inline(always)]
    fn backward_pass<const AVX: bool, T: Stored>(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span<T>,
        below: &mut Below<T>,
        shared: Option<(&TreeSplit, &Below<T>)>,
    ) {
        let mut ahead = Prefetch::default();
        for s in supernodes {
            let (start, end, pattern, block) = self.supernode::<T>(s);
            ahead.backward(T::stored(self), self.values[s]);
            let (lo, x, y) = (span.lo, &mut *span.x, &mut *span.y);
            let (bx, by) = below.rows(block.rows);
            let ((ux, bx), (uy, by)) = (bx.split_at_mut(block.cols), by.split_at_mut(block.cols));
            let (xs, ys) = (&mut x[start - lo..end - lo], &mut y[start - lo..end - lo]);
            ux.copy_from_slice(xs);
            uy.copy_from_slice(ys);
            // The solution at the pattern rows, negated: in this span, then (in a half) the
            // shared rows.
            let from = shared.map_or(pattern.len(), |(split, _)| split.shared_from[s] as usize);
            for ((&r, u), w) in pattern[..from].iter().zip(&mut *bx).zip(&mut *by) {
                (*u, *w) = (-x[r as usize - lo], -y[r as usize - lo]);
            }
            if let Some((split, top)) = shared {
                let rows = pattern[from..]
                    .iter()
                    .zip(&mut bx[from..])
                    .zip(&mut by[from..]);
                for ((&r, u), w) in rows {
                    let q = split.slot[r as usize] as usize;
                    (*u, *w) = (-top.x[q], -top.y[q]);
                }
            }
            let (bx, by) = below.rows(block.rows);
            let (xs, ys) = (&mut x[start - lo..end - lo], &mut y[start - lo..end - lo]);
            block.dots::<AVX>(bx, by, xs, ys);
        }
    }

    /// Supernode s: its first and one-past-last column, its pattern and its block.
    #[inline(always)]
    fn supernode<T: Stored>(&self, s: usize) -> (usize, usize, &[u32], Block<'_, T>) {
        let (start, end) = (self.begin[s], self.begin[s + 1]);
        let pattern = &self.row[self.pattern[s]..self.pattern[s + 1]];
        let (cols, rows) = (end - start, end - start + pattern.len());
        let values = &T::stored(self)[self.values[s]..self.values[s] + rows * cols];
        (start, end, pattern, Block { values, cols, rows })
    }
}

/// The precisions a factor stores its values in, and where it keeps each.
pub(crate) trait Stored: Real {
    fn stored(f: &Factor) -> &[Self];
}

impl Stored for f32 {
    #[inline(always)]
    fn stored(f: &Factor) -> &[f32] {
        &f.single
    }
}

impl Stored for f64 {
    #[inline(always)]
    fn stored(f: &Factor) -> &[f64] {
        &f.l
    }
}

/// Asks for the factor's values a fixed distance ahead of the substitution's, which walks them
/// in address order (ascending forward, descending back) but in blocks too small for the
/// hardware prefetcher to follow.
#[derive(Default)]
struct Prefetch {
    /// Values up to here (forward) or from here (backward) were asked for.
    done: Option<usize>,
}

/// Values in a 64-byte cache line.
const fn values_per_line<T>() -> usize {
    64 / std::mem::size_of::<T>()
}

/// How far ahead to ask, in bytes.
const PREFETCH_BYTES: usize = 8192;

impl Prefetch {
    #[inline(always)]
    fn forward<T>(&mut self, l: &[T], upto: usize) {
        let ahead = PREFETCH_BYTES / std::mem::size_of::<T>();
        let target = (upto + ahead).min(l.len());
        let mut at = self.done.unwrap_or(upto).max(upto.saturating_sub(ahead));
        while at < target {
            fetch(l, at);
            at += values_per_line::<T>();
        }
        self.done = Some(at.max(self.done.unwrap_or(0)));
    }

    #[inline(always)]
    fn backward<T>(&mut self, l: &[T], from: usize) {
        let ahead = PREFETCH_BYTES / std::mem::size_of::<T>();
        let target = from.saturating_sub(ahead);
        let mut at = self.done.unwrap_or(from).min(from + ahead);
        while at > target {
            at = at.saturating_sub(values_per_line::<T>());
            fetch(l, at);
        }
        self.done = Some(at.min(self.done.unwrap_or(usize::MAX)));
    }
}

#[inline(always)]
fn fetch<T>(l: &[T], at: usize) {
    #[cfg(target_arch = "x86_64")]
    if at < l.len() {
        // SAFETY: a prefetch has no effect beyond the cache, and SSE is part of x86_64.
        unsafe {
            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                l.as_ptr().add(at).cast(),
            )
        };
    }
}

impl<R> Default for Below<R> {
    fn default() -> Self {
        Below {
            x: Vec::new(),
            y: Vec::new(),
        }
    }
}

impl<R> Default for Substitution<R> {
    fn default() -> Self {
        Substitution {
            below: Default::default(),
            spill: Default::default(),
            top: Default::default(),
        }
    }
}

impl<R: Real> Below<R> {
    /// The first `n` values of x and y, grown if need be (their old values are left).
    #[inline(always)]
    fn rows(&mut self, n: usize) -> (&mut [R], &mut [R]) {
        self.room(n);
        (&mut self.x[..n], &mut self.y[..n])
    }

    /// The first `n` values of x and y and a register's worth more, for a product to store
    /// its last register whole ([`Block::product`]).
    #[inline(always)]
    fn rows_with_room(&mut self, n: usize) -> (&mut [R], &mut [R]) {
        let n = n + R::LANES;
        self.room(n);
        (&mut self.x[..n], &mut self.y[..n])
    }

    fn room(&mut self, n: usize) {
        if self.x.len() < n {
            self.x.resize(n, R::default());
            self.y.resize(n, R::default());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Side;
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymbolicCholesky, factorize_symbolic_cholesky,
    };
    use faer::sparse::{SparseColMat, Triplet};

    /// The 2D Laplacian of a w × w grid with 8 neighbours, plus a diagonal shift: SPD, and
    /// with supernodes of every width.
    fn grid_matrix(w: usize) -> (usize, Vec<Triplet<usize, usize, f64>>) {
        let n = w * w;
        let mut diagonal = vec![1.0; n];
        let mut t = vec![];
        for i in 0..w {
            for j in 0..w {
                let a = i * w + j;
                for (di, dj) in [(0, 1), (1, 0), (1, 1), (1, -1)] {
                    let (ni, nj) = (i as i64 + di, j as i64 + dj);
                    if ni < w as i64 && nj >= 0 && nj < w as i64 {
                        let b = ni as usize * w + nj as usize;
                        let c = 1.0 + ((a * 7 + b * 3) % 5) as f64;
                        diagonal[a] += c;
                        diagonal[b] += c;
                        t.push(Triplet::new(a.max(b), a.min(b), -c));
                    }
                }
            }
        }
        t.extend(
            diagonal
                .iter()
                .enumerate()
                .map(|(r, &d)| Triplet::new(r, r, d)),
        );
        (n, t)
    }

    /// The nested dissection order of the w × w grid's matrix `t` (its rows at the grid's
    /// points, joined where `t` has an entry), as projective dynamics computes it.
    fn grid_dissection(w: usize, t: &[Triplet<usize, usize, f64>]) -> Vec<usize> {
        let n = w * w;
        let position: Vec<glam::DVec2> = (0..n)
            .map(|r| glam::DVec2::new((r % w) as f64, (r / w) as f64))
            .collect();
        let (start, neighbours) =
            crate::solver::linear::ordering::adjacency(n, t.iter().map(|e| (e.row, e.col)));
        crate::solver::linear::ordering::nested_dissection(&position, &start, &neighbours)
            .into_iter()
            .map(|r| r as usize)
            .collect()
    }

    /// The factor of the matrix `t` (n × n), and faer's symbolic factorisation.
    fn factor(
        n: usize,
        t: &[Triplet<usize, usize, f64>],
        single: bool,
    ) -> (Factor, SymbolicCholesky<usize>) {
        factor_in_order(n, t, single, None)
    }

    /// The factor of the matrix `t` (n × n) in the order `forward` (row p of the factor is row
    /// `forward[p]`), or faer's minimum degree order.
    fn factor_in_order(
        n: usize,
        t: &[Triplet<usize, usize, f64>],
        single: bool,
        forward: Option<&[usize]>,
    ) -> (Factor, SymbolicCholesky<usize>) {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, t).unwrap();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let perm = forward.map(|forward| permutation(forward.to_vec()));
        let ordering = match &perm {
            Some(p) => faer::sparse::linalg::cholesky::SymmetricOrdering::Custom(p.as_ref()),
            None => Default::default(),
        };
        let symbolic =
            factorize_symbolic_cholesky(a.symbolic(), Side::Lower, ordering, params).unwrap();
        let mut f = Factor::of(&symbolic).unwrap();
        let par = faer::Par::Seq;
        let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut stack = faer::dyn_stack::MemBuffer::new(scratch);
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut f.l,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                faer::dyn_stack::MemStack::new(&mut stack),
                Default::default(),
            )
            .unwrap();
        f.finish(single, &Threads::new(1).unwrap(), 0);
        (f, symbolic)
    }

    /// Figures, no assertion on time: a solve of the 256² grid's factor on 1 and 2 threads
    /// against one plain read of its values, which bounds what any substitution can cost, and
    /// each pass over the supernodes of each width alone, and the solve in the two fill orders
    /// projective dynamics chooses from (`W=180` for another grid:
    /// `cargo test --release --lib substitutions_against -- --ignored --nocapture`).
    #[test]
    #[ignore = "a measurement: prints figures"]
    fn substitutions_against_one_read_of_the_factor() {
        let w = std::env::var("W")
            .ok()
            .and_then(|w| w.parse().ok())
            .unwrap_or(256);
        let (n, t) = grid_matrix(w);
        let (f, _) = factor(n, &t, true);
        let time = |run: &mut dyn FnMut()| {
            run();
            let start = std::time::Instant::now();
            for _ in 0..20 {
                run();
            }
            start.elapsed().as_secs_f64() / 20.0 * 1e3
        };
        let read = time(&mut || {
            let mut acc = [0.0f64; 4];
            for c in f.single.chunks_exact(4) {
                for q in 0..4 {
                    acc[q] += f64::from(c[q]);
                }
            }
            std::hint::black_box(acc);
        });
        let mut line = format!(
            "{}: factor of {} values ({:.1} MB); one read {read:.2} ms",
            crate::solver::threads::machine(),
            f.len(),
            f.len() as f64 * 4e-6
        );
        for threads in [1, 2] {
            let pool = Threads::new(threads).unwrap();
            let (mut x, mut y) = (vec![0.0f32; n], vec![0.0f32; n]);
            let mut work = Substitution::default();
            let ms = time(&mut || {
                x.fill(1.0);
                y.fill(0.5);
                f.solve(&mut x, &mut y, &mut work, &pool);
            });
            line += &format!("; solve on {threads} thread(s) {ms:.2} ms");
        }
        println!("{line}");
        let (mut x, mut y) = (vec![0.0f32; n], vec![0.0f32; n]);
        for (lo, hi) in [(0, 4), (4, 16), (16, 64), (64, usize::MAX)] {
            let pick: Vec<usize> = (0..f.supernodes())
                .filter(|&s| (lo..hi).contains(&(f.begin[s + 1] - f.begin[s])))
                .collect();
            let values: usize = pick
                .iter()
                .map(|&s| f.supernode::<f32>(s).3.values.len())
                .sum();
            let mut below = Below::default();
            let fw = time(&mut || {
                let mut all = Span {
                    lo: 0,
                    x: &mut x,
                    y: &mut y,
                };
                f.forward::<f32>(pick.iter().copied(), &mut all, &mut below, None);
            });
            let bw = time(&mut || {
                let mut all = Span {
                    lo: 0,
                    x: &mut x,
                    y: &mut y,
                };
                f.backward::<f32>(pick.iter().rev().copied(), &mut all, &mut below, None);
            });
            println!(
                "cols {lo}..{hi}: {} supernodes, {values} values: forward {fw:.2} ms ({:.2} ns/value), backward {bw:.2} ms ({:.2} ns/value)",
                pick.len(),
                fw * 1e6 / values as f64,
                bw * 1e6 / values as f64
            );
        }
        // The two fill orders projective dynamics chooses from, timed in alternating rounds
        // (the best of each, as this VM's timing noise is one-sided).
        let dissection = grid_dissection(w, &t);
        let orders = [
            ("minimum degree", factor(n, &t, true).0),
            (
                "nested dissection",
                factor_in_order(n, &t, true, Some(&dissection)).0,
            ),
        ];
        let pools = [Threads::new(1).unwrap(), Threads::new(2).unwrap()];
        let mut best = [[f64::INFINITY; 2]; 2];
        for _ in 0..15 {
            for (k, (_, f)) in orders.iter().enumerate() {
                for (q, pool) in pools.iter().enumerate() {
                    let mut work = Substitution::default();
                    let ms = time(&mut || {
                        x.fill(1.0);
                        y.fill(0.5);
                        f.solve(&mut x, &mut y, &mut work, pool);
                    });
                    best[k][q] = best[k][q].min(ms);
                }
            }
        }
        for ((name, f), [one, two]) in orders.iter().zip(best) {
            println!(
                "{name}: {} values, {} supernodes; best solve on 1 thread {one:.2} ms, on 2 {two:.2} ms",
                f.len(),
                f.supernodes()
            );
        }
    }

    /// A torn cloth's dissection still gives two halves to run at once: with springs missing,
    /// a leaf set of the dissection can hold pieces with no spring between them, whose
    /// columns interleave unless the order is postordered ([`crate::solver::linear::ordering::postorder`]).
    /// (Without it, this grid, a third of its springs cut, and nearly every other torn grid
    /// tried, 32² to 64² with a seventh to a half cut, had no split.)
    #[test]
    fn a_torn_grid_still_splits_in_two() {
        let w = 48;
        let (n, full) = grid_matrix(w);
        let t: Vec<_> = full
            .into_iter()
            .filter(|e| e.row == e.col || (e.row * 13 + e.col * 7 + (e.row * e.col) % 17) % 3 != 0)
            .collect();
        let (f, _) = factor_in_order(n, &t, true, Some(&grid_dissection(w, &t)));
        assert_eq!(f.halves(), 2, "{} values", f.len());
        let split = f.split.as_ref().expect("the torn grid's tree splits");
        let [a, b] = &split.groups;
        let (a, b) = (a.columns.len() as f64, b.columns.len() as f64);
        assert!(a.min(b) > 0.3 * (a + b), "halves of {a} and {b} columns");
    }

    #[test]
    fn the_substitutions_solve_the_system() {
        for (w, single) in [1, 2, 5, 23, 40, 180]
            .into_iter()
            .flat_map(|w| [(w, true), (w, false)])
        {
            let (n, t) = grid_matrix(w);
            let (f, symbolic) = factor(n, &t, single);
            assert_eq!(f.single_precision(), single && n > 0);
            // b = A u for a known u, permuted into the factor's order.
            let u: Vec<(f64, f64)> = (0..n)
                .map(|i| ((i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()))
                .collect();
            let times = |u: &[(f64, f64)]| {
                let mut b = vec![(0.0, 0.0); n];
                for e in &t {
                    let (r, c, v) = (e.row, e.col, e.val);
                    b[r].0 += v * u[c].0;
                    b[r].1 += v * u[c].1;
                    if r != c {
                        b[c].0 += v * u[r].0;
                        b[c].1 += v * u[r].1;
                    }
                }
                b
            };
            let b = times(&u);
            let fwd: Vec<usize> = match symbolic.perm() {
                Some(p) => p.arrays().0.to_vec(),
                None => (0..n).collect(),
            };
            let one = Threads::new(1).unwrap();
            let mut x: Vec<f64> = fwd.iter().map(|&r| b[r].0).collect();
            let mut y: Vec<f64> = fwd.iter().map(|&r| b[r].1).collect();
            solve(&f, &mut x, &mut y, &one);
            // In f64 a solve is good to round-off; in f32 (values and arithmetic), to about
            // 1e-6 ...
            let error = |x: &[f64], y: &[f64]| {
                fwd.iter()
                    .enumerate()
                    .map(|(p, &r)| (x[p] - u[r].0).abs().max((y[p] - u[r].1).abs()))
                    .fold(0.0, f64::max)
            };
            let first = error(&x, &y);
            let tolerance = if single { 1e-6 } else { 1e-12 };
            assert!(first < tolerance, "w {w}: error {first:e}");
            // ... and solves for the correction from the f64 residual b − A u converge to u.
            let (mut xr, mut yr) = (x.clone(), y.clone());
            for _ in 0..4 {
                let mut now = vec![(0.0, 0.0); n];
                for (p, &r) in fwd.iter().enumerate() {
                    now[r] = (xr[p], yr[p]);
                }
                let au = times(&now);
                let mut dx: Vec<f64> = fwd.iter().map(|&r| b[r].0 - au[r].0).collect();
                let mut dy: Vec<f64> = fwd.iter().map(|&r| b[r].1 - au[r].1).collect();
                solve(&f, &mut dx, &mut dy, &one);
                for p in 0..n {
                    xr[p] += dx[p];
                    yr[p] += dy[p];
                }
            }
            let refined = error(&xr, &yr);
            assert!(
                refined < 1e-13,
                "w {w}: refined error {refined:e} (first {first:e})"
            );
            // Two threads give one thread's bits; the tree splits on the bigger grids.
            let two = Threads::new(2).unwrap();
            let mut x2: Vec<f64> = fwd.iter().map(|&r| b[r].0).collect();
            let mut y2: Vec<f64> = fwd.iter().map(|&r| b[r].1).collect();
            solve(&f, &mut x2, &mut y2, &two);
            assert_eq!((&x, &y), (&x2, &y2), "w {w}");
            assert_eq!(f.split.is_some(), w >= 23, "w {w}");
            // (The 180² factor is big enough for the halves to run at once.)
            assert_eq!(f.len() >= PARALLEL_MIN_VALUES, w == 180, "w {w}");
            // Without the split, the portable and the AVX build agree bit for bit, and with
            // the split to round-off.
            let whole = Factor {
                split: None,
                ..f.clone()
            };
            let start: (Vec<f64>, Vec<f64>) = fwd.iter().map(|&r| b[r]).unzip();
            let (portable, dispatched) = if single {
                both_builds::<f32>(&whole, &start)
            } else {
                both_builds::<f64>(&whole, &start)
            };
            assert_eq!(portable, dispatched, "w {w}");
            for (p, q) in portable.0.iter().zip(&x) {
                assert!((p - q).abs() < tolerance, "w {w}");
            }
        }
    }

    /// A solve of f64 right-hand sides, rounded to the factor's precision and back.
    fn solve(f: &Factor, x: &mut [f64], y: &mut [f64], threads: &Threads) {
        if f.single_precision() {
            solve_in::<f32>(f, x, y, threads);
        } else {
            solve_in::<f64>(f, x, y, threads);
        }
    }

    fn solve_in<T: Stored>(f: &Factor, x: &mut [f64], y: &mut [f64], threads: &Threads) {
        let (mut xs, mut ys) = (rounded::<T>(x), rounded::<T>(y));
        f.solve(&mut xs, &mut ys, &mut Substitution::default(), threads);
        x.copy_from_slice(&widened(&xs));
        y.copy_from_slice(&widened(&ys));
    }

    /// `v` rounded to the precision `T`.
    fn rounded<T: Real>(v: &[f64]) -> Vec<T> {
        v.iter().map(|&v| T::of(v)).collect()
    }

    /// `v` in f64 (exact).
    fn widened<T: Real>(v: &[T]) -> Vec<f64> {
        v.iter().map(|v| v.get()).collect()
    }

    type Solution = (Vec<f64>, Vec<f64>);

    /// A whole solve of `start` with the portable kernels and with the dispatched ones.
    fn both_builds<T: Stored>(f: &Factor, start: &Solution) -> (Solution, Solution) {
        let solve_with = |forward: &dyn Fn(&mut Span<T>, &mut Below<T>),
                          backward: &dyn Fn(&mut Span<T>, &mut Below<T>)| {
            let (mut x, mut y) = (rounded::<T>(&start.0), rounded::<T>(&start.1));
            let mut all = Span {
                lo: 0,
                x: &mut x,
                y: &mut y,
            };
            let mut below = Below::default();
            forward(&mut all, &mut below);
            backward(&mut all, &mut below);
            (widened(&x), widened(&y))
        };
        let all = 0..f.supernodes();
        let portable = solve_with(
            &|span, below| f.forward_pass::<false, T>(all.clone(), span, below, None),
            &|span, below| f.backward_pass::<false, T>(all.clone().rev(), span, below, None),
        );
        let dispatched = solve_with(
            &|span, below| f.forward::<T>(all.clone(), span, below, None),
            &|span, below| f.backward::<T>(all.clone().rev(), span, below, None),
        );
        (portable, dispatched)
    }
}
