//! The dense work of one supernode in the substitutions of [`super::cholesky`], for the x and
//! y right-hand sides at once: the triangle on its diagonal, forward and back, and the block
//! below it, as a product (forward) and as dot products (back).
//!
//! Each kernel has a portable form and an AVX form that do the same operations on every
//! element in the same order (a product and then a sum, each rounded, never fused), so the
//! two give the same bits. The AVX forms are written with intrinsics because the compiler's
//! own vectorisation of the portable loops came out as 128-bit and scalar code with register
//! shuffles (seen with `perf annotate`), at about 2 ns a value. What they gain:
//! * the product below the diagonal keeps 16 rows of both sums in registers over all the
//!   supernode's columns, so each value is loaded once and no sum goes back to memory;
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

/// One supernode's values: a dense column-major block of `rows` × `cols`, its diagonal block
/// on top and its pattern rows below.
#[derive(Clone, Copy)]
pub(super) struct Block<'a, T> {
    pub values: &'a [T],
    pub cols: usize,
    pub rows: usize,
}

impl<'a, T: Value> Block<'a, T> {
    /// Column j below the diagonal block.
    #[inline(always)]
    fn below(&self, j: usize) -> &'a [T] {
        &self.values[j * self.rows + self.cols..(j + 1) * self.rows]
    }

    /// Column j within the diagonal block, below the diagonal.
    #[inline(always)]
    fn strictly_lower(&self, j: usize) -> &'a [T] {
        &self.values[j * self.rows + j + 1..j * self.rows + self.cols]
    }

    /// The diagonal block's forward substitution in place: u_j = (b_j − Σ_{i<j} L_ji u_i) / L_jj,
    /// column by column (each column's updates are element-wise, so any vector width gives the
    /// same bits).
    #[inline(always)]
    pub fn solve_diagonal_forward(&self, inv: &[f64], xs: &mut [f64], ys: &mut [f64]) {
        for j in 0..self.cols {
            let (xj, yj) = (xs[j] * inv[j], ys[j] * inv[j]);
            xs[j] = xj;
            ys[j] = yj;
            let c = self.strictly_lower(j);
            for ((xi, yi), &v) in xs[j + 1..].iter_mut().zip(&mut ys[j + 1..]).zip(c) {
                let v: f64 = v.into();
                *xi -= xj * v;
                *yi -= yj * v;
            }
        }
    }

    /// (bx, by)[k] = Σ_j L[cols + k, j] (xs, ys)[j], summed over j in order from 0.
    #[inline(always)]
    pub fn product_below<const AVX: bool>(
        &self,
        xs: &[f64],
        ys: &[f64],
        bx: &mut [f64],
        by: &mut [f64],
    ) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: AVX is only asked for where the CPU has it.
            unsafe { self.product_below_avx(xs, ys, bx, by) };
            return;
        }
        bx.fill(0.0);
        by.fill(0.0);
        for j in 0..self.cols {
            let (u, w) = (xs[j], ys[j]);
            for ((x, y), &v) in bx.iter_mut().zip(by.iter_mut()).zip(self.below(j)) {
                let v: f64 = v.into();
                *x += v * u;
                *y += v * w;
            }
        }
    }

    /// Back substitution's first half: (xs, ys)[j] −= Σ_k L[cols + k, j] (bx, by)[k].
    #[inline(always)]
    pub fn subtract_pattern_dots<const AVX: bool>(
        &self,
        bx: &[f64],
        by: &[f64],
        xs: &mut [f64],
        ys: &mut [f64],
    ) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: AVX is only asked for where the CPU has it.
            unsafe { self.subtract_pattern_dots_avx(bx, by, xs, ys) };
            return;
        }
        for j in 0..self.cols {
            let (dx, dy) = dot(self.below(j), bx, by);
            xs[j] -= dx;
            ys[j] -= dy;
        }
    }

    /// The diagonal block's back substitution in place, from the last column:
    /// u_j = (v_j − Σ_{i>j} L_ij u_i) / L_jj.
    #[inline(always)]
    pub fn solve_diagonal_backward<const AVX: bool>(
        &self,
        inv: &[f64],
        xs: &mut [f64],
        ys: &mut [f64],
    ) {
        for j in (0..self.cols).rev() {
            let (dx, dy) = dot_with::<AVX, T>(self.strictly_lower(j), &xs[j + 1..], &ys[j + 1..]);
            xs[j] = (xs[j] - dx) * inv[j];
            ys[j] = (ys[j] - dy) * inv[j];
        }
    }

    /// [`Self::product_below`] with AVX: 16 rows, then 4, then one at a time.
    ///
    /// # Safety
    /// The CPU must support AVX; always inlined, this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn product_below_avx(&self, xs: &[f64], ys: &[f64], bx: &mut [f64], by: &mut [f64]) {
        let (cols, rows) = (self.cols, self.rows);
        let p = rows - cols;
        assert!(xs.len() >= cols && ys.len() >= cols && bx.len() >= p && by.len() >= p);
        assert!(self.values.len() >= cols * rows);
        let l = self.values.as_ptr();
        let mut k = 0;
        // SAFETY: the caller guarantees AVX; every load reads column j's rows cols + k ..
        // cols + k + 16 (or + 4) < rows, and every store bx, by's k .. k + 16 < p (asserted).
        unsafe {
            while k + 16 <= p {
                let mut ax = [_mm256_setzero_pd(); 4];
                let mut ay = [_mm256_setzero_pd(); 4];
                for j in 0..cols {
                    let (u, w) = (_mm256_set1_pd(xs[j]), _mm256_set1_pd(ys[j]));
                    let c = l.add(j * rows + cols + k);
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
            while k + 4 <= p {
                let (mut ax, mut ay) = (_mm256_setzero_pd(), _mm256_setzero_pd());
                for j in 0..cols {
                    let v = T::load4(l.add(j * rows + cols + k));
                    ax = _mm256_add_pd(ax, _mm256_mul_pd(v, _mm256_set1_pd(xs[j])));
                    ay = _mm256_add_pd(ay, _mm256_mul_pd(v, _mm256_set1_pd(ys[j])));
                }
                _mm256_storeu_pd(bx.as_mut_ptr().add(k), ax);
                _mm256_storeu_pd(by.as_mut_ptr().add(k), ay);
                k += 4;
            }
        }
        for k in k..p {
            let (mut x, mut y) = (0.0, 0.0);
            for j in 0..cols {
                let v: f64 = self.values[j * rows + cols + k].into();
                x += v * xs[j];
                y += v * ys[j];
            }
            bx[k] = x;
            by[k] = y;
        }
    }

    /// [`Self::subtract_pattern_dots`] with AVX, four columns at a time.
    ///
    /// # Safety
    /// The CPU must support AVX; always inlined, this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn subtract_pattern_dots_avx(
        &self,
        bx: &[f64],
        by: &[f64],
        xs: &mut [f64],
        ys: &mut [f64],
    ) {
        let (cols, rows) = (self.cols, self.rows);
        let p = rows - cols;
        assert!(xs.len() >= cols && ys.len() >= cols && bx.len() >= p && by.len() >= p);
        assert!(self.values.len() >= cols * rows);
        let (l, full) = (self.values.as_ptr(), p / 4 * 4);
        let mut j = 0;
        // SAFETY: the caller guarantees AVX; the loads read columns j .. j + 4 < cols at rows
        // cols + k .. cols + k + 4 <= rows, bx, by at k .. k + 4 <= p, and xs, ys at
        // j .. j + 4 <= cols (asserted).
        unsafe {
            while j + 4 <= cols {
                let mut ax = [_mm256_setzero_pd(); 4];
                let mut ay = [_mm256_setzero_pd(); 4];
                let c = l.add(j * rows + cols);
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
                for k in full..p {
                    let v = _mm256_set_pd(
                        (*c.add(3 * rows + k)).into(),
                        (*c.add(2 * rows + k)).into(),
                        (*c.add(rows + k)).into(),
                        (*c.add(k)).into(),
                    );
                    dx = _mm256_add_pd(dx, _mm256_mul_pd(v, _mm256_set1_pd(bx[k])));
                    dy = _mm256_add_pd(dy, _mm256_mul_pd(v, _mm256_set1_pd(by[k])));
                }
                let (px, py) = (xs.as_mut_ptr().add(j), ys.as_mut_ptr().add(j));
                _mm256_storeu_pd(px, _mm256_sub_pd(_mm256_loadu_pd(px), dx));
                _mm256_storeu_pd(py, _mm256_sub_pd(_mm256_loadu_pd(py), dy));
                j += 4;
            }
            for j in j..cols {
                let (dx, dy) = dot_avx(self.below(j), bx, by);
                xs[j] -= dx;
                ys[j] -= dy;
            }
        }
    }
}

/// [`dot_avx`] where `AVX` is asked for, else [`dot`]: the same bits.
#[inline(always)]
fn dot_with<const AVX: bool, T: Value>(c: &[T], x: &[f64], y: &[f64]) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        // SAFETY: AVX is only asked for where the CPU has it.
        return unsafe { dot_avx(c, x, y) };
    }
    dot(c, x, y)
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

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    /// Blocks of every shape that the AVX loops split differently (16, 4 and single rows; 4
    /// and single columns), stored in f32 and in f64, give the portable kernels' bits.
    #[test]
    fn avx_kernels_give_the_portable_bits() {
        if !super::super::wide::available() {
            return;
        }
        check(|v| v as f32);
        check(|v| v);
    }

    fn check<T: Value>(store: fn(f64) -> T) {
        let value = |i: usize| {
            ((i as f64 * 0.7).sin() + 1.5) * if i.is_multiple_of(3) { -1.0 } else { 1.0 }
        };
        for cols in [1, 2, 3, 4, 5, 8, 9, 17] {
            for p in [0, 1, 3, 4, 5, 15, 16, 17, 35] {
                let rows = cols + p;
                let values: Vec<T> = (0..rows * cols).map(|i| store(value(i))).collect();
                let inv: Vec<f64> = (0..cols).map(|j| 1.0 / (2.0 + value(j))).collect();
                let block = Block {
                    values: &values,
                    cols,
                    rows,
                };
                let xs: Vec<f64> = (0..cols).map(|j| value(j + 100)).collect();
                let ys: Vec<f64> = (0..cols).map(|j| value(j + 200)).collect();
                let run = |avx: bool| {
                    let (mut xs, mut ys) = (xs.clone(), ys.clone());
                    let (mut bx, mut by) = (vec![9.0; p], vec![9.0; p]);
                    block.solve_diagonal_forward(&inv, &mut xs, &mut ys);
                    let mut v = (&mut xs[..], &mut ys[..], &mut bx[..], &mut by[..]);
                    if avx {
                        // SAFETY: the CPU has AVX, checked by the caller.
                        unsafe { substitute_avx(&block, &inv, &mut v) };
                    } else {
                        let (xs, ys, bx, by) = v;
                        block.product_below::<false>(xs, ys, bx, by);
                        block.subtract_pattern_dots::<false>(bx, by, xs, ys);
                        block.solve_diagonal_backward::<false>(&inv, xs, ys);
                    }
                    let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                    (bits(&bx), bits(&by), bits(&xs), bits(&ys))
                };
                assert_eq!(run(true), run(false), "{cols} columns, {p} pattern rows");
            }
        }
    }

    type Vectors<'v> = (&'v mut [f64], &'v mut [f64], &'v mut [f64], &'v mut [f64]);

    /// The AVX kernels after the forward diagonal solve, compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[target_feature(enable = "avx")]
    unsafe fn substitute_avx<T: Value>(block: &Block<T>, inv: &[f64], v: &mut Vectors) {
        let (xs, ys, bx, by) = v;
        block.product_below::<true>(xs, ys, bx, by);
        block.subtract_pattern_dots::<true>(bx, by, xs, ys);
        block.solve_diagonal_backward::<true>(inv, xs, ys);
    }
}
