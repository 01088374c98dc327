//! Figures as people read them: fixed decimals up to a billion, and scientific notation past
//! it, so that a scene with a mass of 1e300 (valid, if odd) shows its energy as `4.900e300 J`
//! in the panel and on the command line, not as 301 digits that push the panel off the window.
//! Small values keep their fixed decimals: a resting cloth's kinetic energy reads 0.000000 J,
//! not its round-off.

/// `x` with `decimals` decimals below 10⁹ in magnitude (and when it is not finite); as
/// `4.900e300` from there up.
pub fn number(x: f64, decimals: usize) -> String {
    if !x.is_finite() || x.abs() < 1e9 {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn fixed_up_to_a_billion_and_scientific_past_it() {
        assert_eq!(number(4786.501277, 6), "4786.501277");
        assert_eq!(number(0.0, 6), "0.000000");
        assert_eq!(number(1.56e-14, 6), "0.000000");
        assert_eq!(number(-9.8, 2), "-9.80");
        assert_eq!(number(999_999_999.0, 0), "999999999");
        assert_eq!(number(4.9e300, 6), "4.900e300");
        assert_eq!(number(-2.5e12, 6), "-2.500e12");
        assert_eq!(number(f64::NAN, 3), "NaN");
        assert_eq!(number(f64::INFINITY, 3), "inf");
    }
}
