//! The dense work of one supernode in the substitutions of [`super::cholesky`], for the x and
//! y right-hand sides at once. The block holds the inverse of the factor's diagonal block and
//! the pattern rows times that inverse ([`invert`]), so that the forward substitution of a
//! supernode is one product of its block with a vector and the back substitution one product
//! of the block's transpose: sums that do not wait on one another.
//!
//! Each kernel has a portable form and an AVX form that do the same operations on every
//! element in the same order (a product and then a sum, each rounded, never fused), so the
//! two give the same bits. The AVX forms are written with intrinsics because the compiler's
//! own vectorisation of the portable loops came out as 128-bit and scalar code with register
//! shuffles (seen with `perf annotate`), at about 2 ns a value. What they gain:
//! * the product keeps 16 rows of both sums in registers over all the supernode's columns, so
//!   each value is loaded once and no sum goes back to memory;
//! * the back substitution takes four columns' dot products at once, eight independent sums,
//!   so no add waits on the one before it.
//!
//! A dot product here sums in four lanes (element k in lane k mod 4, over whole fours), folds
//! them as (0 + 1) + (2 + 3), and then adds the last elements in order.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// How the factor's values are stored: f32 (half the bytes) or f64 (for a matrix too
/// ill-conditioned for f32, as projective dynamics decides when it factors). The kernels convert each to f64 as they load
/// it; the conversion is exact.
pub(super) trait Value: Copy + Into<f64> {
    /// Four values from `p` as f64 lanes.
    ///
    /// # Safety
    /// The CPU must support AVX, and `p` must point to four readable values; always inlined,
    /// this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    unsafe fn load4(p: *const Self) -> __m256d;
}

impl Value for f32 {
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn load4(p: *const f32) -> __m256d {
        // SAFETY: the caller's.
        unsafe { _mm256_cvtps_pd(_mm_loadu_ps(p)) }
    }
}

impl Value for f64 {
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn load4(p: *const f64) -> __m256d {
        // SAFETY: the caller's.
        unsafe { _mm256_loadu_pd(p) }
    }
}

/// One supernode's values: a dense column-major block of `rows` × `cols`, holding in its top
/// `cols` rows the inverse of the factor's diagonal block L_D (zero above the diagonal) and
/// below them W = L_B L_D⁻¹, the factor's pattern rows times that inverse ([`invert`]).
#[derive(Clone, Copy)]
pub(super) struct Block<'a, T> {
    pub values: &'a [T],
    pub cols: usize,
    pub rows: usize,
}

impl<'a, T: Value> Block<'a, T> {
    /// Column j, all rows.
    #[inline(always)]
    fn column(&self, j: usize) -> &'a [T] {
        &self.values[j * self.rows..(j + 1) * self.rows]
    }

    /// (bx, by)[k] = Σ_j B[k, j] (xs, ys)[j] for every row k, summed over j in order from 0:
    /// the forward substitution of the supernode (its solution, then its updates of the rows
    /// below).
    #[inline(always)]
    pub fn product<const AVX: bool>(&self, xs: &[f64], ys: &[f64], bx: &mut [f64], by: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: AVX is only asked for where the CPU has it.
            unsafe { self.product_avx(xs, ys, bx, by) };
            return;
        }
        bx.fill(0.0);
        by.fill(0.0);
        for j in 0..self.cols {
            let (u, w) = (xs[j], ys[j]);
            for ((x, y), &v) in bx.iter_mut().zip(by.iter_mut()).zip(self.column(j)) {
                let v: f64 = v.into();
                *x += v * u;
                *y += v * w;
            }
        }
    }

    /// (xs, ys)[j] = Σ_k B[k, j] (bx, by)[k] over every row k: the back substitution of the
    /// supernode, given its own values and the negated solution at its pattern rows.
    #[inline(always)]
    pub fn dots<const AVX: bool>(&self, bx: &[f64], by: &[f64], xs: &mut [f64], ys: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: AVX is only asked for where the CPU has it.
            unsafe { self.dots_avx(bx, by, xs, ys) };
            return;
        }
        for j in 0..self.cols {
            (xs[j], ys[j]) = dot(self.column(j), bx, by);
        }
    }

    /// [`Self::product`] with AVX: 16 rows, then 4, then one at a time.
    ///
    /// # Safety
    /// The CPU must support AVX; always inlined, this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn product_avx(&self, xs: &[f64], ys: &[f64], bx: &mut [f64], by: &mut [f64]) {
        let (cols, rows) = (self.cols, self.rows);
        assert!(xs.len() >= cols && ys.len() >= cols && bx.len() >= rows && by.len() >= rows);
        assert!(self.values.len() >= cols * rows);
        let l = self.values.as_ptr();
        let mut k = 0;
        // SAFETY: the caller guarantees AVX; every load reads column j's rows k .. k + 16 (or
        // + 4) <= rows, and every store bx, by's k .. k + 16 <= rows (asserted).
        unsafe {
            while k + 16 <= rows {
                let mut ax = [_mm256_setzero_pd(); 4];
                let mut ay = [_mm256_setzero_pd(); 4];
                for j in 0..cols {
                    let (u, w) = (_mm256_set1_pd(xs[j]), _mm256_set1_pd(ys[j]));
                    let c = l.add(j * rows + k);
                    for m in 0..4 {
                        let v = T::load4(c.add(4 * m));
                        ax[m] = _mm256_add_pd(ax[m], _mm256_mul_pd(v, u));
                        ay[m] = _mm256_add_pd(ay[m], _mm256_mul_pd(v, w));
                    }
                }
                for m in 0..4 {
                    _mm256_storeu_pd(bx.as_mut_ptr().add(k + 4 * m), ax[m]);
                    _mm256_storeu_pd(by.as_mut_ptr().add(k + 4 * m), ay[m]);
                }
                k += 16;
            }
            while k + 4 <= rows {
                let (mut ax, mut ay) = (_mm256_setzero_pd(), _mm256_setzero_pd());
                for j in 0..cols {
                    let v = T::load4(l.add(j * rows + k));
                    ax = _mm256_add_pd(ax, _mm256_mul_pd(v, _mm256_set1_pd(xs[j])));
                    ay = _mm256_add_pd(ay, _mm256_mul_pd(v, _mm256_set1_pd(ys[j])));
                }
                _mm256_storeu_pd(bx.as_mut_ptr().add(k), ax);
                _mm256_storeu_pd(by.as_mut_ptr().add(k), ay);
                k += 4;
            }
        }
        for k in k..rows {
            let (mut x, mut y) = (0.0, 0.0);
            for j in 0..cols {
                let v: f64 = self.values[j * rows + k].into();
                x += v * xs[j];
                y += v * ys[j];
            }
            bx[k] = x;
            by[k] = y;
        }
    }

    /// [`Self::dots`] with AVX, four columns at a time.
    ///
    /// # Safety
    /// The CPU must support AVX; always inlined, this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn dots_avx(&self, bx: &[f64], by: &[f64], xs: &mut [f64], ys: &mut [f64]) {
        let (cols, rows) = (self.cols, self.rows);
        assert!(xs.len() >= cols && ys.len() >= cols && bx.len() >= rows && by.len() >= rows);
        assert!(self.values.len() >= cols * rows);
        let (l, full) = (self.values.as_ptr(), rows / 4 * 4);
        let mut j = 0;
        // SAFETY: the caller guarantees AVX; the loads read columns j .. j + 4 <= cols at rows
        // k .. k + 4 <= rows, bx, by at k .. k + 4 <= rows, and xs, ys at j .. j + 4 <= cols
        // (asserted).
        unsafe {
            while j + 4 <= cols {
                let mut ax = [_mm256_setzero_pd(); 4];
                let mut ay = [_mm256_setzero_pd(); 4];
                let c = l.add(j * rows);
                let mut k = 0;
                while k < full {
                    let (u, w) = (
                        _mm256_loadu_pd(bx.as_ptr().add(k)),
                        _mm256_loadu_pd(by.as_ptr().add(k)),
                    );
                    for m in 0..4 {
                        let v = T::load4(c.add(m * rows + k));
                        ax[m] = _mm256_add_pd(ax[m], _mm256_mul_pd(v, u));
                        ay[m] = _mm256_add_pd(ay[m], _mm256_mul_pd(v, w));
                    }
                    k += 4;
                }
                let (mut dx, mut dy) = (fold_four(ax), fold_four(ay));
                for k in full..rows {
                    let v = _mm256_set_pd(
                        (*c.add(3 * rows + k)).into(),
                        (*c.add(2 * rows + k)).into(),
                        (*c.add(rows + k)).into(),
                        (*c.add(k)).into(),
                    );
                    dx = _mm256_add_pd(dx, _mm256_mul_pd(v, _mm256_set1_pd(bx[k])));
                    dy = _mm256_add_pd(dy, _mm256_mul_pd(v, _mm256_set1_pd(by[k])));
                }
                _mm256_storeu_pd(xs.as_mut_ptr().add(j), dx);
                _mm256_storeu_pd(ys.as_mut_ptr().add(j), dy);
                j += 4;
            }
            for j in j..cols {
                (xs[j], ys[j]) = dot_avx(self.column(j), bx, by);
            }
        }
    }
}

/// Rewrites a supernode's block of the Cholesky factor (column-major, `rows` × `cols`: the
/// lower-triangular diagonal block L_D on top, the pattern rows L_B below) into what
/// [`Block`] holds: L_D⁻¹ on top (zero above the diagonal) and W = L_B L_D⁻¹ below.
///
/// Why: a substitution through L_D is a chain, each column waiting on the one before (measured:
/// most of the time of a supernode a few columns wide went there). With the inverse and W,
/// the forward substitution of the supernode is one product of the block with its right-hand
/// side, u_D = L_D⁻¹ b_D and b_B −= W b_D, and the back substitution is one product of its
/// transpose, u_D = L_D⁻ᵀ v_D − Wᵀ u_B: independent sums, as wide as the hardware.
///
/// The inverse of a triangle is formed in f64 by forward substitution on the identity, column
/// by column; its rounding error grows with the condition of L_D, which is at most the square
/// root of the matrix's, and the solves it serves are corrections from an f64 residual.
pub(super) fn invert(values: &mut [f64], rows: usize, cols: usize) {
    let at = |i: usize, j: usize| j * rows + i;
    // L_D⁻¹, column j: solve L_D z = e_j (z_i = 0 for i < j) by columns of L_D, each an
    // update of the z below it that reads the column in address order.
    let mut inv = vec![0.0; cols * cols];
    for (j, z) in inv.chunks_exact_mut(cols).enumerate() {
        z[j] = 1.0;
        for k in j..cols {
            let zk = z[k] / values[at(k, k)];
            z[k] = zk;
            for (zi, &l) in z[k + 1..]
                .iter_mut()
                .zip(&values[at(k + 1, k)..at(cols, k)])
            {
                *zi -= l * zk;
            }
        }
    }
    // W = L_B L_D⁻¹: row r, column j sums L_B[r, k] L_D⁻¹[k, j] over k >= j.
    let mut w = vec![0.0; (rows - cols) * cols];
    for j in 0..cols {
        for k in j..cols {
            let z = inv[j * cols + k];
            for r in cols..rows {
                w[j * (rows - cols) + (r - cols)] += values[at(r, k)] * z;
            }
        }
    }
    for j in 0..cols {
        let column = &mut values[j * rows..(j + 1) * rows];
        column[..cols].copy_from_slice(&inv[j * cols..(j + 1) * cols]);
        column[cols..].copy_from_slice(&w[j * (rows - cols)..(j + 1) * (rows - cols)]);
    }
}

/// (Σ c_k x_k, Σ c_k y_k) over c's length, in the order of the module docs.
#[inline(always)]
fn dot<T: Value>(c: &[T], x: &[f64], y: &[f64]) -> (f64, f64) {
    let (x, y) = (&x[..c.len()], &y[..c.len()]);
    let full = c.len() / 4 * 4;
    let (mut ax, mut ay) = ([0.0f64; 4], [0.0f64; 4]);
    for ((c4, x4), y4) in c[..full]
        .chunks_exact(4)
        .zip(x.chunks_exact(4))
        .zip(y.chunks_exact(4))
    {
        for l in 0..4 {
            let v: f64 = c4[l].into();
            ax[l] += v * x4[l];
            ay[l] += v * y4[l];
        }
    }
    let folded = (
        (ax[0] + ax[1]) + (ax[2] + ax[3]),
        (ay[0] + ay[1]) + (ay[2] + ay[3]),
    );
    dot_tail(c, x, y, full, folded)
}

/// A dot product's last elements, from `full` on, added in order to the folded lanes.
#[inline(always)]
fn dot_tail<T: Value>(
    c: &[T],
    x: &[f64],
    y: &[f64],
    full: usize,
    (mut dx, mut dy): (f64, f64),
) -> (f64, f64) {
    for k in full..c.len() {
        let v: f64 = c[k].into();
        dx += v * x[k];
        dy += v * y[k];
    }
    (dx, dy)
}

/// [`dot`] with AVX.
///
/// # Safety
/// The CPU must support AVX; always inlined, this inherits AVX from its caller.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn dot_avx<T: Value>(c: &[T], x: &[f64], y: &[f64]) -> (f64, f64) {
    let (x, y) = (&x[..c.len()], &y[..c.len()]);
    let full = c.len() / 4 * 4;
    // SAFETY: the caller guarantees AVX; the loads stay below `full` <= the three lengths.
    let folded = unsafe {
        let (mut ax, mut ay) = (_mm256_setzero_pd(), _mm256_setzero_pd());
        let mut k = 0;
        while k < full {
            let v = T::load4(c.as_ptr().add(k));
            ax = _mm256_add_pd(ax, _mm256_mul_pd(v, _mm256_loadu_pd(x.as_ptr().add(k))));
            ay = _mm256_add_pd(ay, _mm256_mul_pd(v, _mm256_loadu_pd(y.as_ptr().add(k))));
            k += 4;
        }
        // [(x0 + x1), (y0 + y1), (x2 + x3), (y2 + y3)], then the halves added.
        let h = _mm256_hadd_pd(ax, ay);
        let s = _mm_add_pd(_mm256_castpd256_pd128(h), _mm256_extractf128_pd(h, 1));
        (_mm_cvtsd_f64(s), _mm_cvtsd_f64(_mm_unpackhi_pd(s, s)))
    };
    dot_tail(c, x, y, full, folded)
}

/// Four columns' four-lane sums folded as (0 + 1) + (2 + 3), one column to a lane.
///
/// # Safety
/// The CPU must support AVX; always inlined, this inherits AVX from its caller.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn fold_four(a: [__m256d; 4]) -> __m256d {
    // SAFETY: the caller guarantees AVX.
    unsafe {
        // [a0₀ + a0₁, a1₀ + a1₁, a0₂ + a0₃, a1₂ + a1₃], and the same for columns 2 and 3.
        let h01 = _mm256_hadd_pd(a[0], a[1]);
        let h23 = _mm256_hadd_pd(a[2], a[3]);
        let low = _mm256_permute2f128_pd(h01, h23, 0x20);
        let high = _mm256_permute2f128_pd(h01, h23, 0x31);
        _mm256_add_pd(low, high)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(i: usize) -> f64 {
        ((i as f64 * 0.7).sin() + 1.5) * if i.is_multiple_of(3) { -1.0 } else { 1.0 }
    }

    /// A factor's block of `rows` × `cols`: a well-conditioned lower triangle on top, any
    /// values below (those above the diagonal are not read).
    fn factor_block(rows: usize, cols: usize) -> Vec<f64> {
        let mut l: Vec<f64> = (0..rows * cols).map(|i| 0.3 * value(i)).collect();
        for j in 0..cols {
            l[j * rows + j] = 2.0 + value(j).abs();
        }
        l
    }

    /// After [`invert`], [`Block::product`] is the forward substitution of the supernode
    /// (L_D u = b, then the rows below less L_B u) and [`Block::dots`] its back substitution
    /// (L_Dᵀ u = v − L_Bᵀ u_B), both to round-off.
    #[test]
    fn the_inverted_block_substitutes() {
        for (rows, cols) in [(1, 1), (3, 1), (4, 4), (9, 5), (40, 17)] {
            let l = factor_block(rows, cols);
            let at = |i: usize, j: usize| l[j * rows + i];
            let mut inverted = l.clone();
            invert(&mut inverted, rows, cols);
            let block = Block {
                values: &inverted[..],
                cols,
                rows,
            };
            let b: Vec<f64> = (0..cols).map(|j| value(j + 50)).collect();
            let (mut bx, mut by) = (vec![0.0; rows], vec![0.0; rows]);
            block.product::<false>(&b, &b, &mut bx, &mut by);
            // Forward by substitution.
            let mut u = b.clone();
            for j in 0..cols {
                u[j] /= at(j, j);
                for i in j + 1..cols {
                    u[i] -= at(i, j) * u[j];
                }
            }
            for i in 0..rows {
                let expected = if i < cols {
                    u[i]
                } else {
                    (0..cols).map(|j| at(i, j) * u[j]).sum()
                };
                assert!((bx[i] - expected).abs() < 1e-13, "{rows}×{cols} row {i}");
            }
            // Back: v on the diagonal rows, u_B at the pattern rows (given negated).
            let v: Vec<f64> = (0..cols).map(|j| value(j + 70)).collect();
            let below: Vec<f64> = (cols..rows).map(|i| value(i + 90)).collect();
            let mut expected = v.clone();
            for (j, e) in expected.iter_mut().enumerate() {
                *e -= (cols..rows)
                    .map(|i| at(i, j) * below[i - cols])
                    .sum::<f64>();
            }
            for j in (0..cols).rev() {
                expected[j] -= (j + 1..cols).map(|i| at(i, j) * expected[i]).sum::<f64>();
                expected[j] /= at(j, j);
            }
            let given: Vec<f64> = v.iter().copied().chain(below.iter().map(|b| -b)).collect();
            let (mut xs, mut ys) = (vec![0.0; cols], vec![0.0; cols]);
            block.dots::<false>(&given, &given, &mut xs, &mut ys);
            for j in 0..cols {
                assert!((xs[j] - expected[j]).abs() < 1e-13, "{rows}×{cols} col {j}");
            }
        }
    }

    /// Blocks of every shape that the AVX loops split differently (16, 4 and single rows; 4
    /// and single columns), stored in f32 and in f64, give the portable kernels' bits.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_kernels_give_the_portable_bits() {
        if !super::super::wide::available() {
            return;
        }
        check(|v| v as f32);
        check(|v| v);
    }

    #[cfg(target_arch = "x86_64")]
    fn check<T: Value>(store: fn(f64) -> T) {
        for cols in [1, 2, 3, 4, 5, 8, 9, 17] {
            for p in [0, 1, 3, 4, 5, 15, 16, 17, 35] {
                let rows = cols + p;
                let values: Vec<T> = (0..rows * cols).map(|i| store(value(i))).collect();
                let block = Block {
                    values: &values,
                    cols,
                    rows,
                };
                let xs: Vec<f64> = (0..cols).map(|j| value(j + 100)).collect();
                let ys: Vec<f64> = (0..cols).map(|j| value(j + 200)).collect();
                let run = |avx: bool| {
                    let (mut xs, mut ys) = (xs.clone(), ys.clone());
                    let (mut bx, mut by) = (vec![9.0; rows], vec![9.0; rows]);
                    let mut v = (&mut xs[..], &mut ys[..], &mut bx[..], &mut by[..]);
                    if avx {
                        // SAFETY: the CPU has AVX, checked by the caller.
                        unsafe { substitute_avx(&block, &mut v) };
                    } else {
                        let (xs, ys, bx, by) = v;
                        block.product::<false>(xs, ys, bx, by);
                        block.dots::<false>(bx, by, xs, ys);
                    }
                    let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                    (bits(&bx), bits(&by), bits(&xs), bits(&ys))
                };
                assert_eq!(run(true), run(false), "{cols} columns, {p} pattern rows");
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    type Vectors<'v> = (&'v mut [f64], &'v mut [f64], &'v mut [f64], &'v mut [f64]);

    /// The AVX kernels, compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn substitute_avx<T: Value>(block: &Block<T>, v: &mut Vectors) {
        let (xs, ys, bx, by) = v;
        block.product::<true>(xs, ys, bx, by);
        block.dots::<true>(bx, by, xs, ys);
    }
}
