//! What the committed work-precision report (docs/work-precision.csv) predicts for the current
//! integrator and dt: the panel shows it beside the method's order.

use crate::sim::Integrator;

const REPORT: &str = include_str!("../../docs/reports/work-precision.csv");

/// The order of accuracy of each method.
pub fn order(i: Integrator) -> u32 {
    match i {
        Integrator::ExplicitEuler
        | Integrator::SymplecticEuler
        | Integrator::ImplicitEuler
        | Integrator::ProjectiveDynamics
        | Integrator::Xpbd
        | Integrator::Vbd => 1,
        Integrator::VelocityVerlet | Integrator::Bdf2 => 2,
        Integrator::Rk4 => 4,
    }
}

/// A prediction read off the report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Prediction {
    /// The report's error at this dt (interpolated log-log between swept dts, or extrapolated
    /// from the nearest stable one with the method's order).
    Error {
        error: f64,
        extrapolated: bool,
    },
    /// The report found the method unstable at a dt this large.
    Unstable,
    Unknown,
}

/// The report's rows for `scene` and `integrator`: (dt, error, stable), dt descending.
fn rows(scene: &str, integrator: Integrator) -> Vec<(f64, f64, bool)> {
    let mut out: Vec<(f64, f64, bool)> = REPORT
        .lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            if f.len() < 7 || f[0] != scene || f[1] != integrator.cli_name() {
                return None;
            }
            Some((f[2].parse().ok()?, f[5].parse().ok()?, f[6] == "true"))
        })
        .collect();
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out
}

pub fn predict(scene: &str, integrator: Integrator, dt: f64) -> Prediction {
    let rows = rows(scene, integrator);
    let stable: Vec<&(f64, f64, bool)> = rows.iter().filter(|r| r.2).collect();
    let Some(largest_stable) = stable.first() else {
        return Prediction::Unknown;
    };
    if dt > largest_stable.0 && rows.iter().any(|r| !r.2 && r.0 <= dt) {
        return Prediction::Unstable;
    }
    let p = order(integrator) as f64;
    for w in stable.windows(2) {
        let (hi, lo) = (w[0], w[1]);
        if dt <= hi.0 && dt >= lo.0 {
            let t = (dt.ln() - lo.0.ln()) / (hi.0.ln() - lo.0.ln());
            let error = (lo.1.ln() + t * (hi.1.ln() - lo.1.ln())).exp();
            return Prediction::Error {
                error,
                extrapolated: false,
            };
        }
    }
    let nearest = if dt > largest_stable.0 {
        **largest_stable
    } else {
        *stable[stable.len() - 1]
    };
    Prediction::Error {
        error: nearest.1 * (dt / nearest.0).powf(p),
        extrapolated: true,
    }
}

const CONTACT_REPORT: &str = include_str!("../../docs/reports/contact.csv");

/// What the committed contact report (docs/reports/contact.csv) measured on the pile for a
/// method at the report's step nearest a dt (within a factor of 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactCost {
    /// The report's step, s.
    pub dt: f64,
    /// The closest pair of particles no spring joins, as a share of 2r (0 when it blew up).
    pub closest: f64,
    /// The largest energy gain over the start, J (infinite when it blew up).
    pub energy_gain: f64,
    /// Cells turned inside out at 6 s.
    pub cells_turned: u32,
    /// Wall-clock seconds per simulated second, release build.
    pub cost: f64,
}

/// The contact report's row for `integrator` nearest `dt`, if one is within a factor of 2.
pub fn contact_cost(integrator: Integrator, dt: f64) -> Option<ContactCost> {
    let mut best: Option<(f64, ContactCost)> = None;
    for line in CONTACT_REPORT.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 10 || f[0] != integrator.cli_name() {
            continue;
        }
        let row = ContactCost {
            dt: f[1].parse().ok()?,
            closest: f[4].parse().ok()?,
            energy_gain: f[5].parse().ok()?,
            cells_turned: f[8].parse().ok()?,
            cost: f[9].parse().ok()?,
        };
        let distance = (row.dt / dt).ln().abs();
        if distance <= 2f64.ln() && best.is_none_or(|(d, _)| distance < d) {
            best = Some((distance, row));
        }
    }
    best.map(|(_, row)| row)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every large-step method has a row at 1/60 s, read from the committed report.
    #[test]
    fn the_contact_report_has_every_large_step_method_at_a_frame() {
        for m in [
            Integrator::ImplicitEuler,
            Integrator::ProjectiveDynamics,
            Integrator::Xpbd,
            Integrator::Vbd,
            Integrator::Bdf2,
        ] {
            let row = contact_cost(m, 1.0 / 60.0).expect("a row at 1/60 s");
            assert!((row.dt - 1.0 / 60.0).abs() < 1e-12, "{m:?}: {row:?}");
            assert!(row.cost > 0.0 && row.closest > 0.0, "{m:?}: {row:?}");
        }
        // No row near 1 s.
        assert_eq!(contact_cost(Integrator::Xpbd, 1.0), None);
    }
}
