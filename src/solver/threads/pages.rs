//! Big arrays on huge pages, where the system offers them.
//!
//! The step reads a spring's two ends and writes their forces all over the particle arrays;
//! on 4 KB pages a 16 M-spring cloth's arrays span a million pages, far more than the
//! translation caches hold. Linux backs memory with 2 MB pages where a program asks for them
//! (`madvise(MADV_HUGEPAGE)`, honoured when transparent huge pages are in `madvise` or `always`
//! mode), and the advice must come before the memory is first touched: so the packing
//! allocates its big arrays through [`filled`] and [`with_capacity`]. Elsewhere, or for small
//! arrays, these are plain `Vec`s.

/// Arrays under this many bytes stay on ordinary pages: a huge page is 2 MB, and the
/// cache-sized scenes gain nothing from fewer of them.
const HUGE_FROM_BYTES: usize = 8 << 20;

/// `Vec::with_capacity(n)`, advised onto huge pages when it is big.
pub fn with_capacity<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    advise(&v);
    v
}

/// `vec![value; n]`, advised onto huge pages (before it is written) when it is big.
pub fn filled<T: Clone>(value: T, n: usize) -> Vec<T> {
    let mut v = with_capacity(n);
    v.resize(n, value);
    v
}

/// Asks the kernel to back `v`'s allocation with huge pages (the 2 MB-aligned part of it).
/// Only advice: where it is refused, or off, nothing changes.
fn advise<T>(v: &Vec<T>) {
    let bytes = v.capacity() * size_of::<T>();
    if bytes < HUGE_FROM_BYTES {
        return;
    }
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = (v.as_ptr() as usize).next_multiple_of(HUGE);
        let end = (v.as_ptr() as usize + bytes) / HUGE * HUGE;
        if end > start {
            // SAFETY: the range lies inside `v`'s own allocation; MADV_HUGEPAGE changes how
            // the kernel backs the pages, never their contents.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Advised or not, the arrays are the plain ones: the same length, capacity and values.
    #[test]
    fn advised_arrays_hold_what_plain_ones_do() {
        for n in [0, 3, HUGE_FROM_BYTES / 8 + 12_345] {
            let v = filled(1.5f64, n);
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|&x| x == 1.5));
            let mut w: Vec<u64> = with_capacity(n);
            assert!(w.capacity() >= n && w.is_empty());
            w.extend(0..n as u64);
            assert!(w.iter().enumerate().all(|(i, &x)| x == i as u64));
        }
    }
}
