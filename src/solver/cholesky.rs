//! The Cholesky factor L of projective dynamics' global matrix, kept in faer's supernodal
//! layout, and the two substitutions that solve L Lᵀ u = b for the x and y components at once.
//!
//! faer factors the matrix; the substitutions are written here because each projective
//! dynamics iteration is one solve with a two-column right-hand side, and faer's general
//! supernodal solve, with its per-supernode dense kernels and workspace, measured about 2×
//! slower on these factors (thousands of supernodes, most of them a few columns wide).
//!
//! A supernode is a run of columns with one shared pattern below its diagonal block, stored as
//! one dense column-major block. Per supernode, the forward substitution solves the diagonal
//! block, then sums the block's updates to the rows below in a contiguous buffer four columns
//! at a time and scatters them once; the back substitution gathers those rows once, takes each
//! column's dot product with them, and then solves the diagonal block from its last column.
//! The long loops run over contiguous memory in independent lanes, so the compiler vectorises
//! them (with AVX where the CPU has it, detected at run time); the diagonal is multiplied by
//! its reciprocal rather than divided by, which would put a division's latency on every
//! column's critical path. The lane order is fixed, so the result is the same bits on every
//! CPU and thread count.

use super::etree::{NOT_SHARED, TreeSplit};
use super::parallel::Threads;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// The factor L: supernode s spans columns `begin[s]..begin[s + 1]`; its values are a dense
/// column-major block of (columns + pattern rows) × columns starting at `values[s]`, the
/// diagonal block on top and then the rows `row[pattern[s]..pattern[s + 1]]` below it.
#[derive(Debug, Default, Clone)]
pub struct Factor {
    begin: Vec<usize>,
    values: Vec<usize>,
    pattern: Vec<usize>,
    row: Vec<u32>,
    /// The blocks' values, as faer's numeric factorisation writes them.
    pub l: Vec<f64>,
    /// 1 / L_jj for every column j ([`Self::finish`]): a substitution multiplies by it,
    /// because a division on each column's critical path would cost its latency per column.
    inv_diagonal: Vec<f64>,
    /// The two halves that a solve runs at once, if the tree splits well.
    split: Option<TreeSplit>,
}

/// Values for a supernode's pattern rows, or for the shared rows, x and y apart.
#[derive(Debug, Default, Clone)]
pub struct Below {
    x: Vec<f64>,
    y: Vec<f64>,
}

/// The buffers of a solve, kept from solve to solve.
#[derive(Debug, Default, Clone)]
pub struct Substitution {
    /// Each half's supernode at hand.
    below: [Below; 2],
    /// Each half's updates of the shared rows in the forward pass.
    spill: [Below; 2],
    /// The shared rows' values in the backward pass.
    top: Below,
}

/// A part of the right-hand side, rows `lo..lo + x.len()`.
struct Span<'a> {
    lo: usize,
    x: &'a mut [f64],
    y: &'a mut [f64],
}

/// The halves' columns of x and y ([`TreeSplit::halves`]).
fn spans<'a>(split: &TreeSplit, x: &'a mut [f64], y: &'a mut [f64]) -> [Span<'a>; 2] {
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
                    inv_diagonal: vec![],
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
            inv_diagonal: vec![],
        })
    }

    /// Takes in the values that the numeric factorisation wrote to [`Self::l`].
    pub fn finish(&mut self) {
        let n = self.begin.len() - 1;
        let mut inv = Vec::with_capacity(self.begin[n]);
        for s in 0..n {
            let (start, end, _, block) = self.supernode(s);
            let rows = block.len() / (end - start).max(1);
            inv.extend((0..end - start).map(|j| 1.0 / block[j * rows + j]));
        }
        self.inv_diagonal = inv;
    }

    /// Solves L Lᵀ u = b in place for two right-hand sides, `x` and `y`; with a split tree
    /// ([`TreeSplit`]) its two halves run on two of `threads` (or one after the other on one:
    /// the same arithmetic, so the same bits, on any thread count).
    pub fn solve(&self, x: &mut [f64], y: &mut [f64], work: &mut Substitution, threads: &Threads) {
        let Some(split) = &self.split else {
            let mut all = Span { lo: 0, x, y };
            self.forward(0..self.supernodes(), &mut all, &mut work.below[0], None);
            self.backward(
                (0..self.supernodes()).rev(),
                &mut all,
                &mut work.below[0],
                None,
            );
            return;
        };
        let [ga, gb] = &split.groups;
        let sharing = self.l.len() >= PARALLEL_MIN_VALUES;
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
            buf.resize(split.top_rows.len(), 0.0);
        }
        // Forward: the halves, each sending its updates of the shared rows to its own buffer;
        // those added in a fixed order; then the shared supernodes.
        {
            let [mut a, mut b] = spans(split, x, y);
            let slot = &split.slot[..];
            threads.join(
                sharing,
                || self.forward(ga.supernodes(), &mut a, below_a, Some((slot, spill_a))),
                || self.forward(gb.supernodes(), &mut b, below_b, Some((slot, spill_b))),
            );
        }
        for (q, &r) in split.top_rows.iter().enumerate() {
            let r = r as usize;
            x[r] = x[r] - spill_a.x[q] - spill_b.x[q];
            y[r] = y[r] - spill_a.y[q] - spill_b.y[q];
        }
        let mut all = Span { lo: 0, x, y };
        self.forward(
            split.top.iter().map(|&s| s as usize),
            &mut all,
            below_a,
            None,
        );
        // Backward: the shared supernodes, then the halves, reading the shared rows' values.
        self.backward(
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
        let (slot, top) = (&split.slot[..], &*top);
        threads.join(
            sharing,
            || self.backward(ga.supernodes().rev(), &mut a, below_a, Some((slot, top))),
            || self.backward(gb.supernodes().rev(), &mut b, below_b, Some((slot, top))),
        );
    }

    fn supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    /// L v = b over `supernodes` (ascending), within `span`; updates of rows with a `shared`
    /// slot are summed there instead.
    fn forward(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span,
        below: &mut Below,
        shared: Option<(&[u32], &mut Below)>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if super::wide::available() {
            // SAFETY: the CPU has AVX.
            unsafe { self.forward_avx(supernodes, span, below, shared) };
            return;
        }
        self.forward_pass(supernodes, span, below, shared);
    }

    /// [`Self::forward_pass`] compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn forward_avx(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span,
        below: &mut Below,
        shared: Option<(&[u32], &mut Below)>,
    ) {
        self.forward_pass(supernodes, span, below, shared);
    }

    /// Lᵀ u = v over `supernodes` (descending), within `span`; rows with a `shared` slot are
    /// read from there.
    fn backward(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span,
        below: &mut Below,
        shared: Option<(&[u32], &Below)>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if super::wide::available() {
            // SAFETY: the CPU has AVX.
            unsafe { self.backward_avx(supernodes, span, below, shared) };
            return;
        }
        self.backward_pass(supernodes, span, below, shared);
    }

    /// [`Self::backward_pass`] compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn backward_avx(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span,
        below: &mut Below,
        shared: Option<(&[u32], &Below)>,
    ) {
        self.backward_pass(supernodes, span, below, shared);
    }

    #[inline(always)]
    fn forward_pass(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span,
        below: &mut Below,
        mut shared: Option<(&[u32], &mut Below)>,
    ) {
        for s in supernodes {
            let (start, end, pattern, _) = self.supernode(s);
            let (lo, x, y) = (span.lo, &mut *span.x, &mut *span.y);
            self.forward_block(
                s,
                &mut x[start - lo..end - lo],
                &mut y[start - lo..end - lo],
                below,
            );
            match &mut shared {
                None => {
                    for ((&r, &bx), &by) in pattern.iter().zip(&below.x).zip(&below.y) {
                        let r = r as usize - lo;
                        x[r] -= bx;
                        y[r] -= by;
                    }
                }
                Some((slot, spill)) => {
                    for ((&r, &bx), &by) in pattern.iter().zip(&below.x).zip(&below.y) {
                        match slot[r as usize] {
                            NOT_SHARED => {
                                let r = r as usize - lo;
                                x[r] -= bx;
                                y[r] -= by;
                            }
                            q => {
                                spill.x[q as usize] += bx;
                                spill.y[q as usize] += by;
                            }
                        }
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn backward_pass(
        &self,
        supernodes: impl Iterator<Item = usize>,
        span: &mut Span,
        below: &mut Below,
        shared: Option<(&[u32], &Below)>,
    ) {
        for s in supernodes {
            let (start, end, pattern, _) = self.supernode(s);
            let (lo, x, y) = (span.lo, &mut *span.x, &mut *span.y);
            below.x.clear();
            below.y.clear();
            match shared {
                None => {
                    below.x.extend(pattern.iter().map(|&r| x[r as usize - lo]));
                    below.y.extend(pattern.iter().map(|&r| y[r as usize - lo]));
                }
                Some((slot, top)) => {
                    for &r in pattern {
                        let (u, w) = match slot[r as usize] {
                            NOT_SHARED => (x[r as usize - lo], y[r as usize - lo]),
                            q => (top.x[q as usize], top.y[q as usize]),
                        };
                        below.x.push(u);
                        below.y.push(w);
                    }
                }
            }
            self.backward_block(
                s,
                &mut x[start - lo..end - lo],
                &mut y[start - lo..end - lo],
                below,
            );
        }
    }

    /// Supernode s forward: solves its diagonal block in `xs`, `ys` (its columns) and leaves
    /// Σ_j L[k, j] u_j for its pattern rows k in `below`.
    #[inline(always)]
    fn forward_block(&self, s: usize, xs: &mut [f64], ys: &mut [f64], below: &mut Below) {
        let (start, end, pattern, block) = self.supernode(s);
        let (cols, p) = (end - start, pattern.len());
        let rows = cols + p;
        // The diagonal block, column by column.
        let inv = &self.inv_diagonal[start..end];
        for (j, col) in block.chunks_exact(rows).enumerate() {
            let (xj, yj) = (xs[j] * inv[j], ys[j] * inv[j]);
            xs[j] = xj;
            ys[j] = yj;
            let c = &col[j + 1..cols];
            for ((xi, yi), &v) in xs[j + 1..].iter_mut().zip(&mut ys[j + 1..]).zip(c) {
                *xi -= xj * v;
                *yi -= yj * v;
            }
        }
        below.x.clear();
        below.x.resize(p, 0.0);
        below.y.clear();
        below.y.resize(p, 0.0);
        if p == 0 {
            return;
        }
        // The rows below: Σ_j L[k, j] u_j, four columns at a time, in column order.
        let mut j = 0;
        while j + 4 <= cols {
            let c = |q: usize| &block[(j + q) * rows + cols..(j + q + 1) * rows];
            let (c0, c1, c2, c3) = (c(0), c(1), c(2), c(3));
            let (u0, u1, u2, u3) = (xs[j], xs[j + 1], xs[j + 2], xs[j + 3]);
            for ((((b, &v0), &v1), &v2), &v3) in below.x.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3)
            {
                *b = *b + u0 * v0 + u1 * v1 + u2 * v2 + u3 * v3;
            }
            let (u0, u1, u2, u3) = (ys[j], ys[j + 1], ys[j + 2], ys[j + 3]);
            for ((((b, &v0), &v1), &v2), &v3) in below.y.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3)
            {
                *b = *b + u0 * v0 + u1 * v1 + u2 * v2 + u3 * v3;
            }
            j += 4;
        }
        for j in j..cols {
            let c = &block[j * rows + cols..(j + 1) * rows];
            let u = xs[j];
            for (b, &v) in below.x.iter_mut().zip(c) {
                *b += u * v;
            }
            let u = ys[j];
            for (b, &v) in below.y.iter_mut().zip(c) {
                *b += u * v;
            }
        }
    }

    /// Supernode s backward, its pattern rows' values in `below`: first every column's dot
    /// product with them (independent of each other), then the diagonal block from its last
    /// column, whose short dot products are summed in order.
    #[inline(always)]
    fn backward_block(&self, s: usize, xs: &mut [f64], ys: &mut [f64], below: &Below) {
        let (start, end, pattern, block) = self.supernode(s);
        let cols = end - start;
        let rows = cols + pattern.len();
        let inv = &self.inv_diagonal[start..end];
        if !pattern.is_empty() {
            for (j, col) in block.chunks_exact(rows).enumerate() {
                let (px, py) = dot2(&col[cols..], &below.x, &below.y);
                xs[j] -= px;
                ys[j] -= py;
            }
        }
        for (j, col) in block.chunks_exact(rows).enumerate().rev() {
            let c = &col[j + 1..cols];
            let (dx, dy) = if c.len() < 16 {
                let (mut dx, mut dy) = (0.0, 0.0);
                for ((&v, &u), &w) in c.iter().zip(&xs[j + 1..]).zip(&ys[j + 1..]) {
                    dx += v * u;
                    dy += v * w;
                }
                (dx, dy)
            } else {
                dot2(c, &xs[j + 1..], &ys[j + 1..])
            };
            xs[j] = (xs[j] - dx) * inv[j];
            ys[j] = (ys[j] - dy) * inv[j];
        }
    }

    /// Supernode s: its first and one-past-last column, its pattern and its block.
    #[inline(always)]
    fn supernode(&self, s: usize) -> (usize, usize, &[u32], &[f64]) {
        let (start, end) = (self.begin[s], self.begin[s + 1]);
        let pattern = &self.row[self.pattern[s]..self.pattern[s + 1]];
        let len = (end - start + pattern.len()) * (end - start);
        (
            start,
            end,
            pattern,
            &self.l[self.values[s]..self.values[s] + len],
        )
    }
}

/// (Σ c_k x_k, Σ c_k y_k), each in eight lanes (k mod 8), folded as (l + l+4), then
/// (0 + 1) + (2 + 3): the lanes are independent, so the loop vectorises into independent
/// vector sums, and the order is fixed.
#[inline(always)]
fn dot2(c: &[f64], x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = c.len().min(x.len()).min(y.len());
    let (c, x, y) = (&c[..n], &x[..n], &y[..n]);
    let (mut ax, mut ay) = ([0.0f64; 8], [0.0f64; 8]);
    let (cc, xc, yc) = (c.chunks_exact(8), x.chunks_exact(8), y.chunks_exact(8));
    let (cr, xr, yr) = (cc.remainder(), xc.remainder(), yc.remainder());
    for ((c8, x8), y8) in cc.zip(xc).zip(yc) {
        for l in 0..8 {
            ax[l] += c8[l] * x8[l];
            ay[l] += c8[l] * y8[l];
        }
    }
    for (l, ((&c, &x), &y)) in cr.iter().zip(xr).zip(yr).enumerate() {
        ax[l] += c * x;
        ay[l] += c * y;
    }
    (fold(ax), fold(ay))
}

#[inline(always)]
fn fold(a: [f64; 8]) -> f64 {
    let s: [f64; 4] = std::array::from_fn(|l| a[l] + a[l + 4]);
    (s[0] + s[1]) + (s[2] + s[3])
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

    /// The factor of the matrix `t` (n × n), and faer's symbolic factorisation.
    fn factor(n: usize, t: &[Triplet<usize, usize, f64>]) -> (Factor, SymbolicCholesky<usize>) {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, t).unwrap();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(a.symbolic(), Side::Lower, Default::default(), params)
                .unwrap();
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
        f.finish();
        (f, symbolic)
    }

    /// Figures, no assertion on time: a solve of the 256² grid's factor on 1 and 2 threads
    /// against one plain read of its values, which bounds what any substitution can cost
    /// (`cargo test --release --lib substitutions_against -- --ignored --nocapture`).
    #[test]
    #[ignore = "a measurement: prints figures"]
    fn substitutions_against_one_read_of_the_factor() {
        let (n, t) = grid_matrix(256);
        let (f, _) = factor(n, &t);
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
            for c in f.l.chunks_exact(4) {
                for q in 0..4 {
                    acc[q] += c[q];
                }
            }
            std::hint::black_box(acc);
        });
        let mut line = format!(
            "{}: factor of {} values ({:.1} MB); one read {read:.2} ms",
            crate::bench::machine(),
            f.l.len(),
            f.l.len() as f64 * 8e-6
        );
        for threads in [1, 2] {
            let pool = Threads::new(threads).unwrap();
            let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
            let mut work = Substitution::default();
            let ms = time(&mut || {
                x.fill(1.0);
                y.fill(0.5);
                f.solve(&mut x, &mut y, &mut work, &pool);
            });
            line += &format!("; solve on {threads} thread(s) {ms:.2} ms");
        }
        println!("{line}");
    }

    #[test]
    fn the_substitutions_solve_the_system() {
        for w in [1, 2, 5, 23, 40, 180] {
            let (n, t) = grid_matrix(w);
            let (f, symbolic) = factor(n, &t);
            // b = A u for a known u, permuted into the factor's order.
            let u: Vec<(f64, f64)> = (0..n)
                .map(|i| ((i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()))
                .collect();
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
            let fwd: Vec<usize> = match symbolic.perm() {
                Some(p) => p.arrays().0.to_vec(),
                None => (0..n).collect(),
            };
            let mut x: Vec<f64> = fwd.iter().map(|&r| b[r].0).collect();
            let mut y: Vec<f64> = fwd.iter().map(|&r| b[r].1).collect();
            f.solve(
                &mut x,
                &mut y,
                &mut Substitution::default(),
                &Threads::new(1).unwrap(),
            );
            for (p, &r) in fwd.iter().enumerate() {
                assert!(
                    (x[p] - u[r].0).abs() < 1e-12,
                    "w {w}: x[{r}] {} vs {}",
                    x[p],
                    u[r].0
                );
                assert!(
                    (y[p] - u[r].1).abs() < 1e-12,
                    "w {w}: y[{r}] {} vs {}",
                    y[p],
                    u[r].1
                );
            }
            // Two threads give one thread's bits; the tree splits on the bigger grids.
            let two = Threads::new(2).unwrap();
            let mut x2: Vec<f64> = fwd.iter().map(|&r| b[r].0).collect();
            let mut y2: Vec<f64> = fwd.iter().map(|&r| b[r].1).collect();
            f.solve(&mut x2, &mut y2, &mut Substitution::default(), &two);
            assert_eq!((&x, &y), (&x2, &y2), "w {w}");
            assert_eq!(f.split.is_some(), w >= 23, "w {w}");
            // (The 180² factor is big enough for the halves to run at once.)
            assert_eq!(f.l.len() >= PARALLEL_MIN_VALUES, w == 180, "w {w}");
            // Without the split, the portable and the AVX build agree bit for bit, and with
            // the split to round-off.
            let whole = Factor {
                split: None,
                ..f.clone()
            };
            let solve_with =
                |forward: &dyn Fn(&mut Span, &mut Below),
                 backward: &dyn Fn(&mut Span, &mut Below)| {
                    let mut x3: Vec<f64> = fwd.iter().map(|&r| b[r].0).collect();
                    let mut y3: Vec<f64> = fwd.iter().map(|&r| b[r].1).collect();
                    let mut all = Span {
                        lo: 0,
                        x: &mut x3,
                        y: &mut y3,
                    };
                    let mut below = Below::default();
                    forward(&mut all, &mut below);
                    backward(&mut all, &mut below);
                    (x3, y3)
                };
            let all = 0..whole.supernodes();
            let portable = solve_with(
                &|span, below| whole.forward_pass(all.clone(), span, below, None),
                &|span, below| whole.backward_pass(all.clone().rev(), span, below, None),
            );
            let dispatched = solve_with(
                &|span, below| whole.forward(all.clone(), span, below, None),
                &|span, below| whole.backward(all.clone().rev(), span, below, None),
            );
            assert_eq!(portable, dispatched, "w {w}");
            for (p, q) in portable.0.iter().zip(&x) {
                assert!((p - q).abs() < 1e-12, "w {w}");
            }
        }
    }
}
