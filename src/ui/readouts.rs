//! What the panel reads out under the grid: the stability estimate against the method's
//! limit, the accuracy to expect at this step, and contact's cost; and the panel's colours.

use crate::readable::number;
use crate::sim::*;
use bevy_egui::egui;

/// A problem: a blow-up, a bad input, an unstable step.
pub(super) const RED: egui::Color32 = egui::Color32::from_rgb(255, 110, 90);

/// A caution: a step near its limit, a switch that did not take.
pub(super) const AMBER: egui::Color32 = egui::Color32::from_rgb(240, 190, 70);

/// All is well: a step well within its limit, a saved file.
pub(super) const GREEN: egui::Color32 = egui::Color32::from_rgb(140, 200, 140);

/// h·ω_max against the integrator's limit: green below 80 %, amber below 100 %, red past it.
pub(super) fn stability_readout(ui: &mut egui::Ui, s: &StabilityEstimate, integrator: Integrator) {
    let margin = s.margin();
    let color = if margin < 0.8 {
        GREEN
    } else if margin < 1.0 {
        AMBER
    } else {
        RED
    };
    let limit = if s.limit.is_finite() {
        format!("{:.2}", s.limit)
    } else {
        "none".into()
    };
    ui.horizontal(|ui| {
        ui.label("Stability");
        ui.colored_label(
            color,
            format!("h·ω_max = {}  (limit {limit})", number(s.h_omega, 3)),
        );
    });
    let stable_dt = if !s.stable_dt.is_finite() {
        "stable at any dt".to_string()
    } else if s.stable_dt > 0.0 {
        format!("stable dt < {:.2e} s", s.stable_dt)
    } else {
        "unstable at any dt".to_string()
    };
    let note = if integrator == Integrator::ExplicitEuler {
        " (explicit Euler is stable only through damping)"
    } else {
        ""
    };
    ui.small(format!(
        "ω_max ≈ {} rad/s (Gershgorin bound {}); {stable_dt}{note}",
        number(s.omega_estimate, 0),
        number(s.omega_bound, 0)
    ));
    if integrator.unconditionally_stable() && s.h_omega > 0.0 {
        ui.small(numerical_damping_note(s.fastest_mode_kept));
    }
}

/// What unconditional stability costs: the fastest mode's amplitude left per step by the method
/// itself, and after how many steps it is down to 1/e.
fn numerical_damping_note(kept: f64) -> String {
    let e_fold = if kept > 0.0 && kept < 1.0 {
        format!(", 1/e after {:.1} steps", -1.0 / kept.ln())
    } else {
        String::new()
    };
    format!(
        "the method's own damping keeps {:.1} % of the fastest mode per step{e_fold}",
        kept * 100.0
    )
}

/// The method's order and what the work-precision report measured at this dt. `touches`:
/// the scene has a ground or contact settings, where BDF2 takes a backward Euler step while
/// contact acts (`solver::methods::bdf2`).
pub(super) fn accuracy_readout(
    ui: &mut egui::Ui,
    integrator: Integrator,
    dt: f64,
    particles: usize,
    (contact, touches): (Option<ContactSettings>, bool),
) {
    use super::predict::{Prediction, predict};
    let order = |i: Integrator| match i {
        Integrator::Bdf2 if touches => "2 (1 while contact acts)".to_string(),
        _ => super::predict::order(i).to_string(),
    };
    // Large scenes compare best with the cloth, small ones with the oscillator.
    let class = if particles > 100 {
        "cloth32"
    } else {
        "oscillator"
    };
    let text = match predict(class, integrator, dt) {
        Prediction::Error {
            error,
            extrapolated,
        } => format!(
            "order {}; report error at this dt on the {class}: {error:.1e} m{}",
            order(integrator),
            if extrapolated { " (extrapolated)" } else { "" }
        ),
        Prediction::Unstable => format!(
            "order {}; the report found it unstable at this dt on the {class}",
            order(integrator)
        ),
        Prediction::Unknown => format!("order {}", order(integrator)),
    };
    ui.label("Accuracy");
    ui.small(text);
    if let Some(contact) = contact {
        ui.small(contact_readout(integrator, dt, contact));
    }
}

/// What contact costs the method at this dt, read off the contact report's pile (six soft
/// boxes in a bin), for a scene with contact.
fn contact_readout(integrator: Integrator, dt: f64, settings: ContactSettings) -> String {
    use super::predict::contact_cost;
    let pairs = settings.particles;
    let Some(row) = contact_cost(integrator, dt) else {
        return "contact: the report measured no step near this one".to_string();
    };
    let frames = 1.0 / row.dt;
    let step = if (frames - frames.round()).abs() < 1e-6 {
        format!("1/{} s", frames.round())
    } else {
        format!("{:.0e} s", row.dt)
    };
    if !row.energy_gain.is_finite() {
        return format!("contact: the report's pile blew up at {step}");
    }
    let gain = if row.energy_gain > 0.0 {
        format!(", gained {:.0} J", row.energy_gain)
    } else {
        String::new()
    };
    let closest = if pairs {
        format!(", pairs at {:.0} % of 2r", row.closest * 100.0)
    } else {
        String::new()
    };
    format!(
        "contact: the report's pile at {step} costs {:.3} s per simulated s{closest}{gain}, {} of 96 cells turned",
        row.cost, row.cells_turned
    )
}
