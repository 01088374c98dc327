//! The dense work of one supernode in the substitutions of [`super::cholesky`], for the x and
//! y right-hand sides at once. The block holds the inverse of the factor's diagonal block and
//! the pattern rows times that inverse ([`invert`]), so that the forward substitution of a
//! supernode is one product of its block with a vector and the back substitution one product
//! of the block's transpose: sums that do not wait on one another.
//!
//! The kernels compute in the precision of the values ([`Real`]: f32, or f64 for an
//! ill-conditioned matrix). Each has a portable form and an AVX form that do the same
//! operations on every element in the same order (a product and then a sum, each rounded,
//! never fused), so the two give the same bits. The AVX forms are written with intrinsics
//! because the compiler's own vectorisation of the portable loops came out as 128-bit and
//! scalar code with register shuffles (seen with `perf annotate`), at about 2 ns a value. What
//! they gain:
//! * the product keeps four registers of rows (32 in f32, 16 in f64) of both sums in
//!   registers over all the supernode's columns, so each value is loaded once and no sum goes
//!   back to memory;
//! * the back substitution takes four columns' dot products at once, eight independent sums,
//!   so no add waits on the one before it.
//!
//! A dot product here sums in a register's lanes (element k in lane k mod [`Real::LANES`], the
//! last register's missing elements as zeros, which the AVX forms read with masked loads) and
//! folds them by halves ([`fold`]). A block's last rows, fewer than a register, are one masked
//! register too.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// The precision of a factor's values and of the substitutions' arithmetic: f32 (half the
/// bytes and twice the lanes) or f64 (for a matrix too ill-conditioned for f32, as projective
/// dynamics decides when it factors).
pub(crate) trait Real:
    Copy
    + Default
    + PartialEq
    + Send
    + Sync
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    /// Lanes in a 256-bit register.
    const LANES: usize;
    /// An AVX register of [`Self::LANES`] values.
    #[cfg(target_arch = "x86_64")]
    type V: Copy;
    /// `v`, rounded to this precision.
    fn of(v: f64) -> Self;
    /// This value in f64 (exact).
    fn get(self) -> f64;

    // The register operations below: each one's safety is that the CPU supports AVX (always
    // inlined, they inherit it from their caller) and that a pointer points to LANES values.

    /// All lanes zero.
    #[cfg(target_arch = "x86_64")]
    unsafe fn zero() -> Self::V;
    /// All lanes `v`.
    #[cfg(target_arch = "x86_64")]
    unsafe fn splat(v: Self) -> Self::V;
    #[cfg(target_arch = "x86_64")]
    unsafe fn load(p: *const Self) -> Self::V;
    #[cfg(target_arch = "x86_64")]
    unsafe fn store(p: *mut Self, v: Self::V);
    /// a + b · c, the product rounded and then the sum (never fused).
    #[cfg(target_arch = "x86_64")]
    unsafe fn add_product(a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// The first `n` < LANES values from `p` (only those are read), the other lanes zero.
    #[cfg(target_arch = "x86_64")]
    unsafe fn load_first(p: *const Self, n: usize) -> Self::V;
    /// The first `n` < LANES lanes to `p` (only those are written).
    #[cfg(target_arch = "x86_64")]
    unsafe fn store_first(p: *mut Self, v: Self::V, n: usize);
    /// Each of four registers' lanes summed as [`fold`] sums them, into `out[0..4]`.
    #[cfg(target_arch = "x86_64")]
    unsafe fn fold_four(a: [Self::V; 4], out: *mut Self);
}

/// Lane masks for [`Real::load_first`]: the `LANES` words from `LANES - n` have their first n
/// set.
#[cfg(target_arch = "x86_64")]
static MASK32: [i32; 16] = [-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0];
#[cfg(target_arch = "x86_64")]
static MASK64: [i64; 8] = [-1, -1, -1, -1, 0, 0, 0, 0];

/// [`Real`]'s register operations for one precision, from the AVX intrinsics that do them
/// (zero, set1, loadu, storeu, add, mul; and the masked load and store with their mask table).
macro_rules! register_ops {
    (
        $t:ty, $v:ty: $zero:ident, $splat:ident, $load:ident, $store:ident, $add:ident, $mul:ident;
        masked by $masks:ident: $mask_load:ident, $mask_store:ident
    ) => {
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn zero() -> $v {
            // SAFETY: the caller's.
            unsafe { $zero() }
        }
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn splat(v: $t) -> $v {
            // SAFETY: the caller's.
            unsafe { $splat(v) }
        }
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn load(p: *const $t) -> $v {
            // SAFETY: the caller's.
            unsafe { $load(p) }
        }
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn store(p: *mut $t, v: $v) {
            // SAFETY: the caller's.
            unsafe { $store(p, v) }
        }
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn add_product(a: $v, b: $v, c: $v) -> $v {
            // SAFETY: the caller's.
            unsafe { $add(a, $mul(b, c)) }
        }
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn load_first(p: *const $t, n: usize) -> $v {
            // SAFETY: the caller's; the mask's load reads the table's LANES words from
            // LANES - n, within its 2 LANES.
            unsafe {
                let mask = _mm256_loadu_si256($masks.as_ptr().add(Self::LANES - n).cast());
                $mask_load(p, mask)
            }
        }
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn store_first(p: *mut $t, v: $v, n: usize) {
            // SAFETY: as for `load_first`.
            unsafe {
                let mask = _mm256_loadu_si256($masks.as_ptr().add(Self::LANES - n).cast());
                $mask_store(p, mask, v)
            }
        }
    };
}

impl Real for f32 {
    const LANES: usize = 8;
    #[cfg(target_arch = "x86_64")]
    type V = __m256;
    #[inline(always)]
    fn of(v: f64) -> f32 {
        v as f32
    }
    #[inline(always)]
    fn get(self) -> f64 {
        self.into()
    }
    register_ops! {
        f32, __m256: _mm256_setzero_ps, _mm256_set1_ps, _mm256_loadu_ps, _mm256_storeu_ps,
        _mm256_add_ps, _mm256_mul_ps; masked by MASK32: _mm256_maskload_ps, _mm256_maskstore_ps
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn fold_four(a: [__m256; 4], out: *mut f32) {
        // SAFETY: the caller's.
        unsafe {
            // [a0₀₁, a0₂₃, a1₀₁, a1₂₃ | a0₄₅, a0₆₇, a1₄₅, a1₆₇] (aᵢⱼₖ = aᵢⱼ + aᵢₖ), and
            // columns 2 and 3 alike; then [a0₀₋₃, a1₀₋₃, a2₀₋₃, a3₀₋₃ | the same of 4..8],
            // and the halves added.
            let h01 = _mm256_hadd_ps(a[0], a[1]);
            let h23 = _mm256_hadd_ps(a[2], a[3]);
            let h = _mm256_hadd_ps(h01, h23);
            let s = _mm_add_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
            _mm_storeu_ps(out, s);
        }
    }
}

impl Real for f64 {
    const LANES: usize = 4;
    #[cfg(target_arch = "x86_64")]
    type V = __m256d;
    #[inline(always)]
    fn of(v: f64) -> f64 {
        v
    }
    #[inline(always)]
    fn get(self) -> f64 {
        self
    }
    register_ops! {
        f64, __m256d: _mm256_setzero_pd, _mm256_set1_pd, _mm256_loadu_pd, _mm256_storeu_pd,
        _mm256_add_pd, _mm256_mul_pd; masked by MASK64: _mm256_maskload_pd, _mm256_maskstore_pd
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn fold_four(a: [__m256d; 4], out: *mut f64) {
        // SAFETY: the caller's.
        unsafe {
            // [a0₀ + a0₁, a1₀ + a1₁, a0₂ + a0₃, a1₂ + a1₃], and the same for columns 2 and 3.
            let h01 = _mm256_hadd_pd(a[0], a[1]);
            let h23 = _mm256_hadd_pd(a[2], a[3]);
            let low = _mm256_permute2f128_pd(h01, h23, 0x20);
            let high = _mm256_permute2f128_pd(h01, h23, 0x31);
            _mm256_storeu_pd(out, _mm256_add_pd(low, high));
        }
    }
}

/// One supernode's values: a dense column-major block of `rows` × `cols`, holding in its top
/// `cols` rows the inverse of the factor's diagonal block L_D (zero above the diagonal) and
/// below them W = L_B L_D⁻¹, the factor's pattern rows times that inverse ([`invert`]).
#[derive(Clone, Copy)]
pub(super) struct Block<'a, R> {
    pub values: &'a [R],
    pub cols: usize,
    pub rows: usize,
}

impl<'a, R: Real> Block<'a, R> {
    /// Column j, all rows.
    #[inline(always)]
    fn column(&self, j: usize) -> &'a [R] {
        &self.values[j * self.rows..(j + 1) * self.rows]
    }

    /// (bx, by)[k] = Σ_j B[k, j] (xs, ys)[j] for every row k, summed over j in order from 0:
    /// the forward substitution of the supernode (its solution, then its updates of the rows
    /// below). Rows of bx and by past the block's may be overwritten (with zeros) up to the next
    /// register boundary, where the buffers are that long.
    #[inline(always)]
    pub fn product<const AVX: bool>(&self, xs: &[R], ys: &[R], bx: &mut [R], by: &mut [R]) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: AVX is only asked for where the CPU has it.
            unsafe { self.product_avx(xs, ys, bx, by) };
            return;
        }
        bx.fill(R::default());
        by.fill(R::default());
        for j in 0..self.cols {
            let (u, w) = (xs[j], ys[j]);
            for ((x, y), &v) in bx.iter_mut().zip(by.iter_mut()).zip(self.column(j)) {
                *x += v * u;
                *y += v * w;
            }
        }
    }

    /// (xs, ys)[j] = Σ_k B[k, j] (bx, by)[k] over every row k: the back substitution of the
    /// supernode, given its own values and the negated solution at its pattern rows.
    #[inline(always)]
    pub fn dots<const AVX: bool>(&self, bx: &[R], by: &[R], xs: &mut [R], ys: &mut [R]) {
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

    /// [`Self::product`] with AVX: four registers of rows, then one, then the last rows (fewer
    /// than a register) in one masked register.
    ///
    /// # Safety
    /// The CPU must support AVX; always inlined, this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn product_avx(&self, xs: &[R], ys: &[R], bx: &mut [R], by: &mut [R]) {
        let (cols, rows, lanes) = (self.cols, self.rows, R::LANES);
        assert!(xs.len() >= cols && ys.len() >= cols && bx.len() >= rows && by.len() >= rows);
        assert!(self.values.len() >= cols * rows);
        let l = self.values.as_ptr();
        let mut k = 0;
        // SAFETY: the caller guarantees AVX; every load reads column j's rows k .. k + 4 lanes
        // (or + 1) <= rows, or the first rows - k of them masked, and every store writes bx,
        // by's k .. k + 4 lanes (or + 1) <= rows (asserted), or the last register whole only
        // where k + lanes <= their lengths (checked), else masked to rows.
        unsafe {
            while k + 4 * lanes <= rows {
                let mut ax = [R::zero(); 4];
                let mut ay = [R::zero(); 4];
                for j in 0..cols {
                    let (u, w) = (R::splat(xs[j]), R::splat(ys[j]));
                    let c = l.add(j * rows + k);
                    for m in 0..4 {
                        let v = R::load(c.add(lanes * m));
                        ax[m] = R::add_product(ax[m], v, u);
                        ay[m] = R::add_product(ay[m], v, w);
                    }
                }
                for m in 0..4 {
                    R::store(bx.as_mut_ptr().add(k + lanes * m), ax[m]);
                    R::store(by.as_mut_ptr().add(k + lanes * m), ay[m]);
                }
                k += 4 * lanes;
            }
            while k + lanes <= rows {
                let (mut ax, mut ay) = (R::zero(), R::zero());
                for j in 0..cols {
                    let v = R::load(l.add(j * rows + k));
                    ax = R::add_product(ax, v, R::splat(xs[j]));
                    ay = R::add_product(ay, v, R::splat(ys[j]));
                }
                R::store(bx.as_mut_ptr().add(k), ax);
                R::store(by.as_mut_ptr().add(k), ay);
                k += lanes;
            }
            // The last rows, fewer than a register's lanes: the same sums, in the first lanes
            // of a masked register (the others sum zeros).
            let n = rows - k;
            if n > 0 {
                let (mut ax, mut ay) = (R::zero(), R::zero());
                for j in 0..cols {
                    let v = R::load_first(l.add(j * rows + k), n);
                    ax = R::add_product(ax, v, R::splat(xs[j]));
                    ay = R::add_product(ay, v, R::splat(ys[j]));
                }
                // A whole register where the buffers have room for it (a masked store is
                // slow on AMD's cores), else the first n lanes.
                if bx.len().min(by.len()) >= k + lanes {
                    R::store(bx.as_mut_ptr().add(k), ax);
                    R::store(by.as_mut_ptr().add(k), ay);
                } else {
                    R::store_first(bx.as_mut_ptr().add(k), ax, n);
                    R::store_first(by.as_mut_ptr().add(k), ay, n);
                }
            }
        }
    }

    /// [`Self::dots`] with AVX, four columns at a time.
    ///
    /// # Safety
    /// The CPU must support AVX; always inlined, this inherits AVX from its caller.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn dots_avx(&self, bx: &[R], by: &[R], xs: &mut [R], ys: &mut [R]) {
        let (cols, rows, lanes) = (self.cols, self.rows, R::LANES);
        assert!(xs.len() >= cols && ys.len() >= cols && bx.len() >= rows && by.len() >= rows);
        assert!(self.values.len() >= cols * rows);
        let (l, full, last) = (self.values.as_ptr(), rows / lanes * lanes, rows % lanes);
        let mut j = 0;
        // SAFETY: the caller guarantees AVX; the loads read columns j .. j + 4 <= cols at rows
        // k .. k + lanes <= rows, bx, by at k .. k + lanes <= rows, and the folds write xs, ys
        // at j .. j + 4 <= cols (asserted).
        unsafe {
            while j + 4 <= cols {
                let mut ax = [R::zero(); 4];
                let mut ay = [R::zero(); 4];
                let c = l.add(j * rows);
                let mut k = 0;
                while k < full {
                    let (u, w) = (R::load(bx.as_ptr().add(k)), R::load(by.as_ptr().add(k)));
                    for m in 0..4 {
                        let v = R::load(c.add(m * rows + k));
                        ax[m] = R::add_product(ax[m], v, u);
                        ay[m] = R::add_product(ay[m], v, w);
                    }
                    k += lanes;
                }
                if last > 0 {
                    let (u, w) = (
                        R::load_first(bx.as_ptr().add(full), last),
                        R::load_first(by.as_ptr().add(full), last),
                    );
                    for m in 0..4 {
                        let v = R::load_first(c.add(m * rows + full), last);
                        ax[m] = R::add_product(ax[m], v, u);
                        ay[m] = R::add_product(ay[m], v, w);
                    }
                }
                R::fold_four(ax, xs.as_mut_ptr().add(j));
                R::fold_four(ay, ys.as_mut_ptr().add(j));
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

/// The sum of `lanes` by halves: (0 + 1) + (2 + 3) for four, and the two fours' sums added
/// for eight, as [`Real::fold_four`] sums a register.
#[inline(always)]
fn fold<R: Real>(lanes: &[R]) -> R {
    match lanes {
        [a] => *a,
        _ => {
            let (low, high) = lanes.split_at(lanes.len() / 2);
            fold(low) + fold(high)
        }
    }
}

/// (Σ c_k x_k, Σ c_k y_k) over c's length, in the order of the module docs.
#[inline(always)]
fn dot<R: Real>(c: &[R], x: &[R], y: &[R]) -> (R, R) {
    let (x, y, lanes) = (&x[..c.len()], &y[..c.len()], R::LANES);
    let (mut ax, mut ay) = ([R::default(); 8], [R::default(); 8]);
    for start in (0..c.len()).step_by(lanes) {
        for l in 0..lanes {
            // Past the end, a lane adds 0 · 0, as the AVX form's masked load gives it.
            let (c, x, y) = match c.get(start + l) {
                Some(&c) => (c, x[start + l], y[start + l]),
                None => (R::default(), R::default(), R::default()),
            };
            ax[l] += c * x;
            ay[l] += c * y;
        }
    }
    (fold(&ax[..lanes]), fold(&ay[..lanes]))
}

/// [`dot`] with AVX.
///
/// # Safety
/// The CPU must support AVX; always inlined, this inherits AVX from its caller.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn dot_avx<R: Real>(c: &[R], x: &[R], y: &[R]) -> (R, R) {
    let (x, y, lanes) = (&x[..c.len()], &y[..c.len()], R::LANES);
    let (full, last) = (c.len() / lanes * lanes, c.len() % lanes);
    let mut folded = [R::default(); 4];
    // SAFETY: the caller guarantees AVX; the loads stay below the three lengths.
    unsafe {
        let (mut ax, mut ay) = (R::zero(), R::zero());
        let mut k = 0;
        while k < full {
            let v = R::load(c.as_ptr().add(k));
            ax = R::add_product(ax, v, R::load(x.as_ptr().add(k)));
            ay = R::add_product(ay, v, R::load(y.as_ptr().add(k)));
            k += lanes;
        }
        if last > 0 {
            let v = R::load_first(c.as_ptr().add(full), last);
            ax = R::add_product(ax, v, R::load_first(x.as_ptr().add(full), last));
            ay = R::add_product(ay, v, R::load_first(y.as_ptr().add(full), last));
        }
        R::fold_four([ax, ay, ax, ay], folded.as_mut_ptr());
    }
    (folded[0], folded[1])
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

    /// Blocks of every shape that the AVX loops split differently (four registers of rows, one,
    /// and a masked last one; four columns and single ones), in f32 and in f64, give the
    /// portable kernels' bits, and write nothing past their rows unless the buffers have room.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_kernels_give_the_portable_bits() {
        if !crate::solver::threads::machine::avx() {
            return;
        }
        check::<f32>();
        check::<f64>();
    }

    #[cfg(target_arch = "x86_64")]
    fn check<R: Real>() {
        for cols in [1, 2, 3, 4, 5, 8, 9, 17] {
            for p in [0, 1, 3, 4, 5, 7, 8, 15, 16, 17, 31, 32, 35, 41] {
                let rows = cols + p;
                let values: Vec<R> = (0..rows * cols).map(|i| R::of(value(i))).collect();
                let block = Block {
                    values: &values,
                    cols,
                    rows,
                };
                let xs: Vec<R> = (0..cols).map(|j| R::of(value(j + 100))).collect();
                let ys: Vec<R> = (0..cols).map(|j| R::of(value(j + 200))).collect();
                // `room`: the buffers a register longer than the rows, which the product may
                // then write whole; without it nothing past the rows may change.
                let run = |avx: bool, room: bool| {
                    let (mut xs, mut ys) = (xs.clone(), ys.clone());
                    let pad = rows + R::LANES;
                    let (mut bx, mut by) = (vec![R::of(9.0); pad], vec![R::of(9.0); pad]);
                    let len = if room { pad } else { rows };
                    let mut v = (&mut xs[..], &mut ys[..], &mut bx[..len], &mut by[..len]);
                    if avx {
                        // SAFETY: the CPU has AVX, checked by the caller.
                        unsafe { substitute_avx(&block, &mut v) };
                    } else {
                        let (xs, ys, bx, by) = v;
                        block.product::<false>(xs, ys, bx, by);
                        block.dots::<false>(bx, by, xs, ys);
                    }
                    let past = bx[rows..].iter().chain(&by[rows..]);
                    assert!(
                        room || past.into_iter().all(|&v| v == R::of(9.0)),
                        "written past the rows"
                    );
                    let bits = |v: &[R]| v.iter().map(|f| f.get().to_bits()).collect::<Vec<_>>();
                    (bits(&bx[..rows]), bits(&by[..rows]), bits(&xs), bits(&ys))
                };
                let portable = run(false, false);
                for room in [false, true] {
                    let shape = format!("{cols} columns, {p} pattern rows, room {room}");
                    assert_eq!(run(true, room), portable, "{shape}");
                }
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    type Vectors<'v, R> = (&'v mut [R], &'v mut [R], &'v mut [R], &'v mut [R]);

    /// The AVX kernels, compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn substitute_avx<R: Real>(block: &Block<R>, v: &mut Vectors<R>) {
        let (xs, ys, bx, by) = v;
        block.product::<true>(xs, ys, bx, by);
        block.dots::<true>(bx, by, xs, ys);
    }
}
