//! Figures as people read them: fixed decimals up to a billion, and scientific notation past
//! it, so that a scene with a mass of 1e300 (valid, if odd) shows its energy as `4.900e300 J`
//! in the panel and on the command line, not as 301 digits that push the panel off the window.
//! Small values keep their fixed decimals: a resting cloth's kinetic energy reads 0.000000 J,
//! not its round-off.

/// `x` with `decimals` decimals below 10⁹ in magnitude (and when it is not finite); as
/// `4.900e300` from there up. A value that rounds to zero reads as zero, without the sign of a
/// −0.0 or of round-off under it (an empty scene's spring energy showed as −0.000000 J).
///
/// ```
/// assert_eq!(hooke::readable::number(-0.0, 6), "0.000000");
/// assert_eq!(hooke::readable::number(-4e-9, 6), "0.000000");
/// assert_eq!(hooke::readable::number(-0.25, 2), "-0.25");
/// assert_eq!(hooke::readable::number(4.9e300, 6), "4.900e300");
/// ```
pub fn number(x: f64, decimals: usize) -> String {
    if !x.is_finite() || x.abs() < 1e9 {
        let text = format!("{x:.decimals$}");
        match text.strip_prefix('-') {
            Some(zero) if zero.bytes().all(|b| b == b'0' || b == b'.') => zero.to_string(),
            _ => text,
        }
    } else {
        format!("{x:.3e}")
    }
}

/// A count as a word in running text ("nine integrators"): one to twenty spelled out, digits
/// past that.
///
/// ```
/// assert_eq!(hooke::readable::count(9), "nine");
/// assert_eq!(hooke::readable::count(21), "21");
/// ```
pub fn count(n: usize) -> String {
    const WORDS: [&str; 21] = [
        "zero",
        "one",
        "two",
        "three",
        "four",
        "five",
        "six",
        "seven",
        "eight",
        "nine",
        "ten",
        "eleven",
        "twelve",
        "thirteen",
        "fourteen",
        "fifteen",
        "sixteen",
        "seventeen",
        "eighteen",
        "nineteen",
        "twenty",
    ];
    WORDS
        .get(n)
        .map_or_else(|| n.to_string(), |w| w.to_string())
}

/// A time step in seconds as people write it: a number (`0.0001`, `1e-4`) or a fraction `p/q`
/// (`1/60`, a frame's step), which must come out finite, above 0 and at most
/// [`crate::sim::MAX_DT`] ([`crate::sim::dt_problem`]). What the command line's `--dt` and the
/// panel's dt field read. The error completes a sentence that starts with the field's name
/// ("--dt must be finite and > 0, got -1").
///
/// ```
/// assert_eq!(hooke::readable::seconds("1/60"), Ok(1.0 / 60.0));
/// assert_eq!(hooke::readable::seconds("2.5e-4"), Ok(2.5e-4));
/// assert!(hooke::readable::seconds("1/0").is_err());
/// ```
pub fn seconds(text: &str) -> Result<f64, String> {
    let value = fraction(text)?;
    if let Some(rule) = crate::sim::dt_problem(value) {
        return Err(format!("{rule}, got {}", text.trim()));
    }
    Ok(value)
}

/// A duration in seconds, as [`seconds`] reads it but 0 allowed (`--time 0` runs no step).
pub fn duration(text: &str) -> Result<f64, String> {
    let value = fraction(text)?;
    if !value.is_finite() || value < 0.0 {
        return Err(format!("must be finite and >= 0, got {}", text.trim()));
    }
    Ok(value)
}

/// What keeps a text from being a whole number of 0 or more that fits its type: what
/// [`whole`] says on the command line and the scene loader says of a whole-number field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotWhole {
    /// A number below 0 (`-2`).
    Negative,
    /// A number with a decimal point or an exponent (`1.5`, `1e3`).
    Fraction,
    /// Digits alone, more than the type holds.
    TooLarge,
    /// No number at all (`many`, `NaN`, the empty text).
    NotANumber,
}

impl NotWhole {
    /// Why `text` (trimmed), which did not parse as the whole number wanted, is not one.
    pub fn of(text: &str) -> NotWhole {
        let number = text.parse::<f64>().is_ok_and(f64::is_finite);
        if number && text.starts_with('-') {
            NotWhole::Negative
        } else if number && text.contains(['.', 'e', 'E']) {
            NotWhole::Fraction
        } else if !text.is_empty() && text.bytes().all(|b| b.is_ascii_digit()) {
            NotWhole::TooLarge
        } else {
            NotWhole::NotANumber
        }
    }
}

/// A count as people type it on the command line (`--steps`, `--threads`, the iteration
/// counts): a whole number of 0 or more that fits `T`. The error names the rule the text
/// breaks ([`NotWhole`]), where the parser's own "invalid digit found in string" named none.
///
/// ```
/// assert_eq!(hooke::readable::whole::<u32>("12"), Ok(12));
/// assert!(hooke::readable::whole::<u64>("-1").unwrap_err().contains("0 or more"));
/// assert!(hooke::readable::whole::<u64>("1e3").unwrap_err().contains("exponent"));
/// ```
pub fn whole<T: TryFrom<u64>>(text: &str) -> Result<T, String> {
    let text = text.trim();
    let not = |why| match why {
        NotWhole::Negative => format!("must be a whole number of 0 or more, got {text}"),
        NotWhole::Fraction => format!(
            "must be a whole number, written without a decimal point or an exponent, got {text}"
        ),
        NotWhole::TooLarge => format!("is too large, got {text}"),
        NotWhole::NotANumber => format!("must be a whole number, got {text}"),
    };
    let n = text.parse::<u64>().map_err(|_| not(NotWhole::of(text)))?;
    T::try_from(n).map_err(|_| not(NotWhole::TooLarge))
}

/// A number, or a fraction p/q of two numbers with q ≠ 0.
fn fraction(text: &str) -> Result<f64, String> {
    let text = text.trim();
    let real = |part: &str| {
        part.trim().parse::<f64>().map_err(|_| {
            format!("must be a number of seconds or a fraction p/q such as 1/60, got {text}")
        })
    };
    match text.split_once('/') {
        Some((p, q)) => {
            let (p, q) = (real(p)?, real(q)?);
            if q == 0.0 {
                return Err(format!("must not divide by zero, got {text}"));
            }
            Ok(p / q)
        }
        None => real(text),
    }
}

/// Items in running text: "a", "a and b", "a, b and c".
///
/// ```
/// assert_eq!(hooke::readable::list(&["contact", "tearing", "muscles"]), "contact, tearing and muscles");
/// assert_eq!(hooke::readable::list(&["contact"]), "contact");
/// ```
pub fn list<S: AsRef<str>>(items: &[S]) -> String {
    match items {
        [] => String::new(),
        [one] => one.as_ref().to_string(),
        [rest @ .., last] => {
            let rest: Vec<&str> = rest.iter().map(|s| s.as_ref()).collect();
            format!("{} and {}", rest.join(", "), last.as_ref())
        }
    }
}

/// A caution where the particles push avian's dynamic bodies with a method and step past the
/// largest at which the `crates` were measured to rest in their net (docs/library.md, rigid
/// bodies at a frame's step): 1/15 s under VBD, which moves the bodies inside its solve; 1/30
/// s under XPBD, whose substeps exchange the impulses in small steps; 1/50 s under implicit
/// Euler, whose line search sizes its contact forces by how the whole body answers them;
/// 1/240 s under projective dynamics and BDF2. The panel's amber line and `hooke run`'s
/// summary.
pub fn bodies_caution(integrator: crate::solver::Integrator, dt: f64) -> Option<String> {
    use crate::solver::Integrator::*;
    let (held_up_to, name) = match integrator {
        ImplicitEuler => (1.0 / 50.0, "1/50 s"),
        ProjectiveDynamics | Bdf2 => (1.0 / 240.0, "1/240 s"),
        Xpbd => (1.0 / 30.0, "1/30 s"),
        Vbd => (1.0 / 15.0, "1/15 s"),
        _ => return None,
    };
    (dt > held_up_to * 1.001).then(|| {
        let best = if integrator == Vbd {
            "no method held them past it"
        } else {
            "VBD, which moves the bodies inside its solve, holds them up to 1/15 s"
        };
        format!(
            "Rigid bodies: under {integrator} the coupling held the crates scene in its net \
             only up to {name} (past it the crates left it); {best}."
        )
    })
}

/// XPBD's convergence after the last step, when its springs are softer than k says (they
/// carry under 95 % of its force): the largest constraint error and the share of k's force they
/// carry. The panel's amber line and `hooke run`'s summary; the energy, counted at k, then
/// overstates what such springs hold.
pub fn xpbd_softness(stats: &crate::solver::SolveStats) -> Option<String> {
    let carried = stats.xpbd_force_carried?;
    let error = stats.xpbd_constraint_error.unwrap_or(0.0);
    (carried < 0.95).then(|| {
        format!(
            "XPBD: constraint error {error:.1e} of L; its springs carry {:.0} % of the force k \
             asks, so the cloth is softer than its stiffness (more sweeps or a tolerance fix it)",
            100.0 * carried
        )
    })
}

#[cfg(test)]
mod tests {
    use super::{duration, number, seconds, whole};

    #[test]
    fn whole_numbers_name_the_rule_they_break() {
        assert_eq!(whole::<u64>("0"), Ok(0));
        assert_eq!(whole::<usize>(" 7 "), Ok(7));
        for (text, says) in [
            ("-1", "0 or more"),
            ("1.5", "decimal point"),
            ("2e3", "exponent"),
            ("99999999999999999999999", "too large"),
            ("4294967296", "too large"),
            ("ten", "must be a whole number, got ten"),
            ("", "must be a whole number"),
        ] {
            let e = whole::<u32>(text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }

    #[test]
    fn seconds_read_numbers_and_fractions() {
        assert_eq!(seconds("1/60"), Ok(1.0 / 60.0));
        assert_eq!(seconds(" 1 / 60 "), Ok(1.0 / 60.0));
        assert_eq!(seconds("0.016666666666666666"), Ok(1.0 / 60.0));
        assert_eq!(seconds("1e-4"), Ok(1e-4));
        assert_eq!(seconds("2/3"), Ok(2.0 / 3.0));
        for bad in [
            "1/0", "a/b", "-1/60", "1/-60", "0", "-1e-4", "nan", "inf", "1/60/2", "", "/",
        ] {
            assert!(seconds(bad).is_err(), "{bad} was read");
        }
        assert!(seconds("1/0").unwrap_err().contains("zero"));
        assert_eq!(duration("0"), Ok(0.0));
        assert_eq!(duration("6/1"), Ok(6.0));
        assert!(duration("-1/60").is_err() && duration("x").is_err());
    }

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
