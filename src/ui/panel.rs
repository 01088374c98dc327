//! The control panel: the scene and the run, the parameter grid ([`super::parameters`]), what
//! the estimate expects of the step ([`super::readouts`]), the live figures and the plots.

use super::actions::{self, Notice, SceneList, reset, save};
use super::controls;
use super::history::{self, History};
use super::parameters::{PanelState, parameter_grid};
use super::plots::{self, Timeline};
use super::readouts::{AMBER, GREEN, RED, accuracy_readout, stability_readout};
use super::stats::LiveStats;
use super::view::CanvasView;
use crate::readable::number;
use crate::scene::{CurrentScene, presets};
use crate::sim::*;
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy_egui::{EguiContexts, egui};

/// The panel's label for what changed between two parameter sets (run state aside), for the
/// undo history; `None` when nothing did.
fn edit_label(old: &SimParams, new: &SimParams) -> Option<&'static str> {
    if old.integrator != new.integrator {
        Some("integrator")
    } else if old.stiffness_override != new.stiffness_override {
        Some("stiffness")
    } else if old.damping != new.damping {
        Some("damping")
    } else if old.spring_damping != new.spring_damping {
        Some("spring damping")
    } else if old.drag_in_solve != new.drag_in_solve {
        Some("drag in the solve")
    } else if old.dt != new.dt {
        Some("dt")
    } else if old.ground != new.ground {
        Some("ground")
    } else if old.tear != new.tear {
        Some("tearing")
    } else if old.contact != new.contact {
        Some("contact")
    } else if old.gravity != new.gravity {
        Some("gravity")
    } else if old.iterations != new.iterations {
        Some("iterations")
    } else {
        None
    }
}

#[allow(clippy::too_many_arguments)]
pub fn side_panel(
    mut commands: Commands,
    mut contexts: EguiContexts,
    mut params: ResMut<SimParams>,
    mut state: ResMut<PanelState>,
    mut view: ResMut<CanvasView>,
    notice: Option<Res<Notice>>,
    scene: Option<Res<CurrentScene>>,
    solver: Res<Solver>,
    clock: Res<SimClock>,
    status: Res<SimStatus>,
    stats: Res<LiveStats>,
    stability: Res<Stability>,
    extra: PanelExtras,
) -> Result {
    let PanelExtras {
        timeline,
        history,
        mut attraction,
        scene_list,
        mut card,
        coupling,
    } = extra;
    let ctx = contexts.ctx_mut()?;
    let mut root = egui::Ui::new(
        ctx.clone(),
        "hooke-root".into(),
        egui::UiBuilder::new()
            .layer_id(egui::LayerId::background())
            .max_rect(ctx.viewport_rect()),
    );
    if let Some(scene) = scene.as_ref().filter(|s| s.is_changed()) {
        state.follow(&scene.0.scene);
    }
    let mut p = params.clone();
    let scene_name = scene.as_ref().map(|s| s.0.name()).unwrap_or_default();
    let response = egui::Panel::left("controls")
        .resizable(false)
        .exact_size(290.0)
        .show(&mut root, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.add_space(6.0);
                ui.heading("hooke");
                ui.label("2D mass-spring simulator");
                ui.separator();

                scene_rows(
                    ui,
                    &mut commands,
                    &scene_list,
                    &scene_name,
                    &mut p.paused,
                    &history,
                );
                status_rows(ui, &mut commands, &status, p.paused, notice.as_deref());
                ui.separator();

                parameter_grid(
                    ui,
                    &mut p,
                    &mut state,
                    &mut card,
                    &mut attraction,
                    solver.materials(),
                );
                // Why the GPU switch is on but the steps are not (a sentence: wrapped below the
                // grid, whose columns do not wrap).
                if let Some(why) = &card.why_not {
                    ui.colored_label(AMBER, format!("Stepping on the CPU: {why}."));
                }
                ui.separator();

                // Stability and accuracy
                stability_readout(ui, &stability, p.integrator);
                let particles = solver.particle_count();
                let touches = p.ground.is_some() || p.contact.is_some();
                accuracy_readout(ui, p.integrator, p.dt, particles, (p.contact, touches));
                if p.integrator == Integrator::Xpbd
                    && let Some(line) = crate::readable::xpbd_softness(&solver.solve_stats())
                {
                    ui.colored_label(AMBER, line);
                }
                let pushed = coupling.as_ref().is_some_and(|c| c.dynamic > 0);
                if let Some(line) =
                    crate::readable::bodies_caution(p.integrator, p.dt).filter(|_| pushed)
                {
                    ui.colored_label(AMBER, line);
                }
                ui.separator();

                let bodies = coupling
                    .as_ref()
                    .filter(|c| c.dynamic > 0)
                    .map(|c| c.energy);
                live_figures(
                    ui,
                    &solver,
                    &clock,
                    &stats,
                    (timeline.energy, bodies),
                    p.paused,
                );
                ui.separator();
                egui::CollapsingHeader::new("Plots")
                    .default_open(true)
                    .show(ui, |ui| plots::show(ui, &timeline, &stability));
                egui::CollapsingHeader::new("Controls (H)")
                    .default_open(false)
                    .show(ui, |ui| controls::controls_grid(ui, "panel-controls"));
            });
        });
    view.panel_width = response.response.rect.width();
    if let Some(label) = edit_label(&params, &p) {
        let before = params.clone();
        commands.queue(move |w: &mut World| history::record_burst(w, label, Some(before)));
    }
    params.set_if_neq(p);
    Ok(())
}

/// The scene picker, the run, reset and save buttons, and undo and redo.
fn scene_rows(
    ui: &mut egui::Ui,
    commands: &mut Commands,
    scene_list: &SceneList,
    scene_name: &str,
    paused: &mut bool,
    history: &History,
) {
    ui.horizontal(|ui| {
        ui.label("Scene");
        egui::ComboBox::from_id_salt("scene")
            .selected_text(scene_name)
            .width(150.0)
            .show_ui(ui, |ui| {
                for (label, target) in &scene_list.0 {
                    if ui.selectable_label(label == scene_name, label).clicked() {
                        match presets::resolve(target) {
                            Ok(loaded) => {
                                commands.queue(move |w: &mut World| actions::open(w, &loaded))
                            }
                            Err(e) => commands.insert_resource(Notice(Some((e.to_string(), true)))),
                        }
                    }
                }
            });
    });
    ui.horizontal(|ui| {
        let run_label = if *paused {
            "▶ Run (G)"
        } else {
            "⏸ Pause (G)"
        };
        if ui.button(run_label).clicked() {
            *paused = !*paused;
        }
        if ui.button("Reset (R)").clicked() {
            commands.queue(reset);
        }
        if ui.button("Save (S)").clicked() {
            commands.queue(save);
        }
    });
    ui.horizontal(|ui| {
        let undo = ui.add_enabled(!history.undo.is_empty(), egui::Button::new("⮪ Undo"));
        if undo.on_hover_text("ctrl+Z").clicked() {
            commands.queue(actions::undo);
        }
        let redo = ui.add_enabled(!history.redo.is_empty(), egui::Button::new("Redo ⮫"));
        if redo.on_hover_text("ctrl+shift+Z, ctrl+Y").clicked() {
            commands.queue(actions::redo);
        }
        ui.small(format!("{} to undo", history.undo.len()));
    });
}

/// Whether the simulation runs, what stopped it and the way back; the last notice.
fn status_rows(
    ui: &mut egui::Ui,
    commands: &mut Commands,
    status: &SimStatus,
    paused: bool,
    notice: Option<&Notice>,
) {
    let blown = match *status {
        SimStatus::Running => {
            ui.label(if paused { "paused" } else { "running" });
            None
        }
        SimStatus::BlewUp { step, time } => Some(format!(
            "Blew up at step {step} (t = {time:.4} s): a position or velocity became \
                     infinite or NaN."
        )),
        SimStatus::InvalidInput(problem) => Some(format!("Paused on a bad input: {problem}.")),
        SimStatus::EnergyGrew {
            step,
            time,
            energy,
            bound,
        } => Some(format!(
            "Unstable at step {step} (t = {time:.4} s): the energy rose to {energy:.3e} J, \
                     past {bound:.3e} J (10× the energy at the last edit)."
        )),
    };
    if let Some(text) = blown {
        ui.colored_label(RED, text);
        ui.label("Lower dt or the stiffness, or pick a more stable integrator.");
        ui.horizontal(|ui| {
            if ui.button("⟲ Last good state").clicked() {
                commands.queue(|w: &mut World| {
                    crate::sim::watch::restore_last_good_state(w);
                });
            }
            if ui.button("Reset").clicked() {
                commands.queue(reset);
            }
        });
    }
    if let Some((text, is_error)) = notice.and_then(|n| n.0.clone()) {
        let color = if is_error { RED } else { GREEN };
        ui.colored_label(color, text);
    }
}

/// The live figures: counts, simulated time, speed, and the energy by kind.
fn live_figures(
    ui: &mut egui::Ui,
    solver: &Solver,
    clock: &SimClock,
    stats: &LiveStats,
    (energy, bodies): (Energy, Option<f64>),
    paused: bool,
) {
    egui::Grid::new("figures").num_columns(2).show(ui, |ui| {
        let mut row = |name: &str, value: String| {
            ui.label(name);
            ui.monospace(value);
            ui.end_row();
        };
        row("Particles", solver.particle_count().to_string());
        row("Springs", solver.spring_count().to_string());
        row("Simulated time", format!("{} s", number(clock.time, 4)));
        row("Steps", clock.steps.to_string());
        row("Steps / s", format!("{:.0}", stats.steps_per_second));
        row(
            "Real-time factor",
            format!("{:.2}×", stats.real_time_factor),
        );
        // Paused, the app draws only on input (`pace`): say so, lest 4 look slow.
        let fps = format!("{:.0}", stats.fps);
        row(
            "Frames / s",
            if paused {
                fps + ", waits for input"
            } else {
                fps
            },
        );
        let total = energy.total() + bodies.unwrap_or(0.0);
        row("Energy", format!("{} J", number(total, 6)));
        row("  kinetic", format!("{} J", number(energy.kinetic, 6)));
        row(
            "  gravity",
            format!("{} J", number(energy.potential_gravity, 6)),
        );
        row(
            "  springs",
            format!("{} J", number(energy.potential_springs, 6)),
        );
        if !solver.materials().gas().is_empty() {
            // −nRT ln A: its zero is at A = 1 m², so only its changes mean anything.
            row("  gas", format!("{} J", number(energy.potential_gas, 6)));
        }
        if let Some(e) = bodies {
            // avian's dynamic bodies: moving, turning and in gravity.
            row("  rigid bodies", format!("{} J", number(e, 6)));
        }
    });
}

/// The panel's other resources (a system takes at most 16 parameters).
#[derive(SystemParam)]
pub struct PanelExtras<'w> {
    timeline: Res<'w, Timeline>,
    history: Res<'w, History>,
    attraction: ResMut<'w, Attraction>,
    scene_list: Res<'w, SceneList>,
    card: ResMut<'w, crate::sim::gpu::CardStep>,
    coupling: Option<Res<'w, crate::sim::avian::Coupling>>,
}
