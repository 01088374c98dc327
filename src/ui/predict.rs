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
