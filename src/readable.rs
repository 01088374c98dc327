//! Figures as people read them: fixed decimals in the range where those say something, and
//! scientific notation outside it, so that a scene with a mass of 1e300 (valid, if odd) shows its
//! energy as `4.900e300 J` in the panel and on the command line, not as 301 digits that push the
//! panel off the window.

/// `x` with `decimals` decimals when it is 0, not finite, or between 10^−decimals and 10⁹ in
/// magnitude; else as `1.234e-7`.
pub fn number(x: f64, decimals: usize) -> String {
    let a = x.abs();
    let smallest = 10f64.powi(-(decimals as i32));
    if x == 0.0 || !x.is_finite() || (smallest..1e9).contains(&a) {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn fixed_where_it_reads_well_and_scientific_outside() {
        assert_eq!(number(4786.501277, 6), "4786.501277");
        assert_eq!(number(0.0, 6), "0.000000");
        assert_eq!(number(-9.8, 2), "-9.80");
        assert_eq!(number(4.9e300, 6), "4.900e300");
        assert_eq!(number(-2.5e-9, 6), "-2.500e-9");
        assert_eq!(number(0.5, 0), "5.000e-1");
        assert_eq!(number(306.4, 0), "306");
        assert_eq!(number(f64::NAN, 3), "NaN");
        assert_eq!(number(f64::INFINITY, 3), "inf");
    }
}
