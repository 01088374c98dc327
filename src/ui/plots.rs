//! The panel's plots: the energy over the last [`WINDOW`] seconds of simulated time, by kind,
//! and h·ω_max against the integrator's stability limit.

use crate::sim::{SimClock, SimParams, Solver, StabilityEstimate};
use bevy::prelude::*;
use bevy_egui::egui;
use egui_plot::{HLine, Legend, Line, Plot};
use std::collections::VecDeque;

/// Simulated seconds shown.
pub const WINDOW: f64 = 10.0;
/// At most this many samples per simulated second.
const RATE: f64 = 60.0;

#[derive(Debug, Clone, Copy)]
struct Sample {
    time: f64,
    kinetic: f64,
    gravity: f64,
    springs: f64,
    h_omega: f64,
}

/// Samples of the last [`WINDOW`] seconds.
#[derive(Resource, Debug, Default)]
pub struct Timeline {
    samples: VecDeque<Sample>,
}

/// Samples the energy and h·ω_max once the clock has moved on by 1/[`RATE`] s; a clock that
/// went back (reset, undo, restore) drops the samples after it.
pub fn sample(
    clock: Res<SimClock>,
    solver: Res<Solver>,
    params: Res<SimParams>,
    stability: Res<StabilityEstimate>,
    mut timeline: ResMut<Timeline>,
) {
    let t = clock.time;
    let samples = &mut timeline.samples;
    while samples.back().is_some_and(|s| s.time > t) {
        samples.pop_back();
    }
    if samples.back().is_some_and(|s| t - s.time < 1.0 / RATE) {
        return;
    }
    let e = solver.energy(params.gravity);
    samples.push_back(Sample {
        time: t,
        kinetic: e.kinetic,
        gravity: e.potential_gravity,
        springs: e.potential_springs,
        h_omega: stability.h_omega,
    });
    while samples.front().is_some_and(|s| s.time < t - WINDOW) {
        samples.pop_front();
    }
}

/// The two plots.
pub fn show(ui: &mut egui::Ui, timeline: &Timeline, stability: &StabilityEstimate) {
    let series = |f: fn(&Sample) -> f64| -> Vec<[f64; 2]> {
        timeline.samples.iter().map(|s| [s.time, f(s)]).collect()
    };
    ui.label("Energy (J) over simulated time (s)");
    Plot::new("energy")
        .height(130.0)
        .legend(Legend::default())
        .allow_scroll(false)
        .allow_drag(false)
        .allow_zoom(false)
        .show(ui, |plot| {
            plot.line(Line::new("kinetic", series(|s| s.kinetic)));
            plot.line(Line::new("gravity", series(|s| s.gravity)));
            plot.line(Line::new("springs", series(|s| s.springs)));
            plot.line(Line::new("total", series(|s| s.kinetic + s.gravity + s.springs)).width(2.0));
        });
    ui.label("h·ω_max against the limit");
    Plot::new("stability")
        .height(90.0)
        .legend(Legend::default())
        .include_y(0.0)
        .allow_scroll(false)
        .allow_drag(false)
        .allow_zoom(false)
        .show(ui, |plot| {
            plot.line(Line::new("h·ω_max", series(|s| s.h_omega)));
            if stability.limit.is_finite() {
                plot.hline(
                    HLine::new("limit", stability.limit)
                        .color(egui::Color32::from_rgb(255, 110, 90)),
                );
            }
        });
}
