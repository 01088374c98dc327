//! The panel's plots: the energy over the last [`WINDOW`] seconds of simulated time, by kind,
//! and h·ω_max against the integrator's stability limit.

use crate::sim::{
    Energy, SimClock, SimParams, Solver, SolverThreads, Stability, StabilityEstimate,
};
use bevy::prelude::*;
use bevy_egui::egui;
use egui_plot::{HLine, Line, Plot};
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

/// Samples of the last [`WINDOW`] seconds, and the energy now.
#[derive(Resource, Debug, Default)]
pub struct Timeline {
    samples: VecDeque<Sample>,
    /// The energy of the solver's state now (the panel's figures read it too), computed once
    /// a frame, and only when the solver or the parameters changed.
    pub energy: Energy,
}

/// Updates the energy, and samples it with h·ω_max once the clock has moved on by
/// 1/[`RATE`] s; a clock that went back (reset, undo, restore) drops the samples after it.
pub fn sample(
    clock: Res<SimClock>,
    solver: Res<Solver>,
    params: Res<SimParams>,
    stability: Res<Stability>,
    threads: Res<SolverThreads>,
    mut timeline: ResMut<Timeline>,
) {
    // While the card steps and its state is read on demand, the card's sum comes each tick
    // without the solver changing.
    if solver.is_changed() || params.is_changed() || solver.energy_on_card.is_some() {
        timeline.energy = solver.energy_now(params.gravity, &threads);
    }
    // An empty solver is one not packed yet (a scene load, an undo): its energy is not the
    // scene's.
    if solver.particle_count() == 0 {
        return;
    }
    let t = clock.time;
    let e = timeline.energy;
    let samples = &mut timeline.samples;
    while samples.back().is_some_and(|s| s.time > t) {
        samples.pop_back();
    }
    if samples.back().is_some_and(|s| t - s.time < 1.0 / RATE) {
        return;
    }
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

/// The energy's colours: kinetic, gravity, springs, total.
const COLORS: [egui::Color32; 4] = [
    egui::Color32::from_rgb(240, 110, 90),
    egui::Color32::from_rgb(110, 160, 240),
    egui::Color32::from_rgb(150, 210, 120),
    egui::Color32::from_rgb(235, 235, 235),
];
const LIMIT: egui::Color32 = egui::Color32::from_rgb(255, 110, 90);

/// The two plots. Their keys are coloured labels above them: a legend inside a plot this
/// narrow covers the lines.
pub fn show(ui: &mut egui::Ui, timeline: &Timeline, stability: &StabilityEstimate) {
    let series = |f: fn(&Sample) -> f64| -> Vec<[f64; 2]> {
        timeline.samples.iter().map(|s| [s.time, f(s)]).collect()
    };
    ui.horizontal_wrapped(|ui| {
        ui.label("Energy (J):");
        for (name, color) in ["kinetic", "gravity", "springs", "total"]
            .into_iter()
            .zip(COLORS)
        {
            ui.colored_label(color, name);
        }
    });
    Plot::new("energy")
        .height(130.0)
        .allow_scroll(false)
        .allow_drag(false)
        .allow_zoom(false)
        .show(ui, |plot| {
            let parts: [fn(&Sample) -> f64; 4] = [
                |s| s.kinetic,
                |s| s.gravity,
                |s| s.springs,
                |s| s.kinetic + s.gravity + s.springs,
            ];
            for ((name, part), color) in ["kinetic", "gravity", "springs", "total"]
                .into_iter()
                .zip(parts)
                .zip(COLORS)
            {
                plot.line(Line::new(name, series(part)).color(color));
            }
        });
    ui.horizontal_wrapped(|ui| {
        ui.label("Stability:");
        ui.colored_label(COLORS[3], "h·ω_max");
        ui.label("against");
        ui.colored_label(LIMIT, "the limit");
        ui.label("(simulated time, s)");
    });
    Plot::new("stability")
        .height(90.0)
        .include_y(0.0)
        .allow_scroll(false)
        .allow_drag(false)
        .allow_zoom(false)
        .show(ui, |plot| {
            plot.line(Line::new("h·ω_max", series(|s| s.h_omega)).color(COLORS[3]));
            if stability.limit.is_finite() {
                plot.hline(HLine::new("limit", stability.limit).color(LIMIT));
            }
        });
}
