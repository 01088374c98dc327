//! The control panel: scene, run state, integrator, stiffness, damping, dt, live figures.

use super::actions::{self, Notice, SceneList, reset, save};
use super::controls;
use super::history::{self, History};
use super::plots::{self, Timeline};
use super::stats::LiveStats;
use super::view::CanvasView;
use crate::readable::number;
use crate::scene::{CurrentScene, presets};
use crate::sim::*;
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy_egui::{EguiContexts, egui};

/// The panel's slider: it keeps a value outside its range (a scene's damping of 250 1/s, a dt
/// of 1e-7 s, 80 Newton steps: all valid) until the user moves it. egui's default clamps the
/// value as soon as the slider is drawn, which changed the loaded scene's physics and recorded
/// an edit nobody made. (The attraction's fields, which a library user may set too, keep theirs
/// the same way.)
fn slider<Num: egui::emath::Numeric>(
    value: &mut Num,
    range: std::ops::RangeInclusive<Num>,
) -> egui::Slider<'_> {
    egui::Slider::new(value, range).clamping(egui::SliderClamping::Edits)
}

/// Panel state that is not simulation state.
#[derive(Resource, Debug, Clone)]
pub struct PanelState {
    /// The stiffness slider's value (applied to every spring when moved).
    stiffness: f64,
    /// The tearing slider's strain (applied while tearing is on). It starts at 60 %: cloth32
    /// hanging at rest strains its top springs by 40-50 % (`hooke run --scene cloth32 --tear
    /// 0.4` tears 4 springs in 3 s, 0.5 none), so it holds until pulled.
    tear: f64,
    /// The contact settings applied when contact is switched on (friction 0.5, points).
    contact: ContactSettings,
}

impl Default for PanelState {
    fn default() -> Self {
        PanelState {
            stiffness: DEFAULT_STIFFNESS,
            tear: 0.6,
            contact: ContactSettings {
                friction: 0.5,
                ..ContactSettings::default()
            },
        }
    }
}

/// What the scene has beyond Hooke springs, in a line ("24 dashpots, 2 gas bodies"), or
/// `None` when nothing.
fn materials_line(m: &crate::solver::Materials) -> Option<String> {
    let count = |n: usize, one: &str, many: &str| match n {
        0 => None,
        1 => Some(format!("1 {one}")),
        n => Some(format!("{n} {many}")),
    };
    let dashpots = m.dashpot().iter().filter(|c| **c != 0.0).count();
    let parts: Vec<String> = [
        count(dashpots, "dashpot", "dashpots"),
        count(m.gas().len(), "gas body", "gas bodies"),
        count(m.muscles().len(), "muscle", "muscles"),
        count(m.plastic().len(), "plastic spring", "plastic springs"),
    ]
    .into_iter()
    .flatten()
    .collect();
    (!parts.is_empty()).then(|| parts.join(", "))
}

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
        // Show the new scene's stiffness: its first spring's, else what a click would use.
        state.stiffness = (scene.0.scene.spring_defs().next())
            .map(|s| s.stiffness)
            .or(scene.0.scene.click.map(|c| c.stiffness))
            .unwrap_or(DEFAULT_STIFFNESS);
        if let Some(strain) = scene.0.scene.tear {
            state.tear = strain;
        }
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

            // Scene
            ui.horizontal(|ui| {
                ui.label("Scene");
                egui::ComboBox::from_id_salt("scene")
                    .selected_text(&scene_name)
                    .width(150.0)
                    .show_ui(ui, |ui| {
                        for (label, target) in &scene_list.0 {
                            if ui.selectable_label(*label == scene_name, label).clicked() {
                                match presets::resolve(target) {
                                    Ok(loaded) => commands
                                        .queue(move |w: &mut World| actions::open(w, &loaded)),
                                    Err(e) => commands
                                        .insert_resource(Notice(Some((e.to_string(), true)))),
                                }
                            }
                        }
                    });
            });
            ui.horizontal(|ui| {
                let run_label = if p.paused {
                    "▶ Run (G)"
                } else {
                    "⏸ Pause (G)"
                };
                if ui.button(run_label).clicked() {
                    p.paused = !p.paused;
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
            let blown = match *status {
                SimStatus::Running => {
                    ui.label(if p.paused { "paused" } else { "running" });
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
            if let Some((text, is_error)) = notice.as_ref().and_then(|n| n.0.clone()) {
                let color = if is_error { RED } else { GREEN };
                ui.colored_label(color, text);
            }
            ui.separator();

            // Method and parameters
            egui::Grid::new("params").num_columns(2).show(ui, |ui| {
                ui.label("Integrator");
                egui::ComboBox::from_id_salt("integrator")
                    .selected_text(p.integrator.cli_name())
                    .show_ui(ui, |ui| {
                        for i in Integrator::ALL {
                            ui.selectable_value(&mut p.integrator, i, i.cli_name());
                        }
                    });
                ui.end_row();
                iteration_rows(ui, p.integrator, &mut p.iterations);
                device_rows(ui, &mut card);

                ui.label("Stiffness k");
                let stiffness = slider(&mut state.stiffness, 10.0..=1e6)
                    .custom_formatter(|v, _| field_number(v))
                    .logarithmic(true)
                    .suffix(" N/m");
                if ui.add(stiffness).changed() {
                    p.stiffness_override = Some(state.stiffness);
                }
                ui.end_row();
                ui.label("");
                ui.horizontal(|ui| {
                    match p.stiffness_override {
                        Some(_) => ui.small("every spring"),
                        None => ui.small("each spring's own"),
                    };
                    if p.stiffness_override.is_some() && ui.small_button("use own").clicked() {
                        p.stiffness_override = None;
                    }
                });
                ui.end_row();

                ui.label("Damping μ");
                ui.add(
                    slider(&mut p.damping, 0.0..=100.0)
                        .custom_formatter(|v, decimals| {
                            // egui's own figure, unless a scene's damping is too long for it.
                            let text = egui::emath::format_with_decimals_in_range(v, decimals);
                            if text.len() <= 7 { text } else { field_number(v) }
                        })
                        .suffix(" 1/s"),
                )
                .on_hover_text("air drag: slows every motion, falling included");
                ui.end_row();

                if p.integrator.can_drag_in_solve() || p.integrator.drags_in_solve() {
                    ui.label("");
                    let mut inside = p.drag_in_solve || p.integrator.drags_in_solve();
                    let toggle = egui::Checkbox::new(&mut inside, "μ inside the solve");
                    let response = ui
                        .add_enabled(!p.integrator.drags_in_solve(), toggle)
                        .on_hover_text(
                            "the drag as the force −μ m v in the implicit solve, not exp(−μ dt) \
                             after the step: at 1/60 s the splitting doubles the error (BDF2 \
                             always takes it inside)",
                        );
                    if response.changed() {
                        p.drag_in_solve = inside;
                    }
                    ui.end_row();
                }

                ui.label("Dashpot c");
                ui.add(slider(&mut p.spring_damping, 0.0..=20.0).suffix(" N·s/m"))
                    .on_hover_text(
                        "a dashpot along every spring without its own: damps the springs' \
                         vibration and leaves free fall alone",
                    );
                ui.end_row();
                if let Some(line) = materials_line(solver.materials()) {
                    ui.label("Materials");
                    ui.small(line);
                    ui.end_row();
                }

                ui.label("Time step dt");
                ui.add(
                    slider(&mut p.dt, 1e-6..=1.0 / 30.0)
                        .logarithmic(true)
                        .custom_formatter(|v, _| format!("{v:.2e}"))
                        // Typed: a number or a fraction, as 1/60.
                        .custom_parser(|text| crate::readable::seconds(text).ok())
                        .suffix(" s"),
                );
                ui.end_row();
                if let Some(dt) = large_step_suggestion(p.integrator, p.dt) {
                    ui.label("");
                    ui.horizontal(|ui| {
                        ui.small("made for large steps:");
                        if ui.small_button("use 1/60 s").clicked() {
                            p.dt = dt;
                        }
                    });
                    ui.end_row();
                }

                ui.label("Ground");
                let mut ground = p.ground.is_some();
                if ui.checkbox(&mut ground, "y = 0").changed() {
                    p.ground = ground.then_some(0.0);
                }
                ui.end_row();

                ui.label("Contact");
                ui.horizontal(|ui| {
                    let mut on = p.contact.is_some();
                    if ui
                        .checkbox(&mut on, "")
                        .on_hover_text("friction and restitution at the ground and the obstacles")
                        .changed()
                    {
                        p.contact = on.then_some(state.contact);
                    }
                    let c = p.contact.as_mut().unwrap_or(&mut state.contact);
                    let mut changed = false;
                    ui.add_enabled_ui(on, |ui| {
                        let mu = egui::DragValue::new(&mut c.friction)
                            .range(0.0..=2.0)
                            .clamp_existing_to_range(false)
                            .speed(0.01)
                            .prefix("μ ");
                        changed |= ui.add(mu).on_hover_text("Coulomb friction").changed();
                        let e = egui::DragValue::new(&mut c.restitution)
                            .range(0.0..=1.0)
                            .speed(0.01)
                            .prefix("e ");
                        changed |= ui.add(e).on_hover_text("restitution").changed();
                        let r = egui::DragValue::new(&mut c.radius)
                            .range(0.0..=0.1)
                            .clamp_existing_to_range(false)
                            .speed(0.0005)
                            .max_decimals(3)
                            .prefix("r ");
                        changed |= ui.add(r).on_hover_text("particle radius, m").changed();
                    });
                    if changed && let Some(c) = p.contact {
                        state.contact = c;
                    }
                });
                ui.end_row();

                // Its own row: the contact row has no room left for it.
                ui.label("");
                ui.add_enabled_ui(p.contact.is_some(), |ui| {
                    let c = p.contact.as_mut().unwrap_or(&mut state.contact);
                    let hover = "particles collide with each other, in one body and between \
                                 bodies (not those joined by a spring)";
                    let outline = "each particle, and each obstacle's corner, is kept out of \
                                   other bodies' outlines (their boundary springs, as capsules \
                                   of the radius), so that sparse bodies cannot pass into each \
                                   other nor hang pierced on a corner";
                    let changed = ui
                        .horizontal(|ui| {
                            let pairs = ui.checkbox(&mut c.particles, "pairs collide");
                            let pairs = pairs.on_hover_text(hover).changed();
                            let outlines = ui.checkbox(&mut c.outlines, "outlines");
                            pairs | outlines.on_hover_text(outline).changed()
                        })
                        .inner;
                    if changed && let Some(c) = p.contact {
                        state.contact = c;
                    }
                });
                ui.end_row();

                ui.label("Tearing");
                ui.horizontal(|ui| {
                    let mut on = p.tear.is_some();
                    if ui.checkbox(&mut on, "").changed() {
                        p.tear = on.then_some(state.tear);
                    }
                    // Shown and typed in percent: typing 30 sets a strain of 0.3.
                    let tear = slider(&mut state.tear, 0.01..=2.0)
                        .logarithmic(true)
                        .custom_formatter(|v, _| field_number((v * 100.0).round()))
                        .custom_parser(|text| parse_number(text).map(|percent| percent / 100.0))
                        .suffix(" %");
                    if ui.add_enabled(on, tear).on_hover_text("strain at which a spring breaks").changed() {
                        p.tear = Some(state.tear);
                    }
                });
                ui.end_row();

                ui.label("Attraction");
                ui.horizontal(|ui| {
                    ui.add(
                        egui::DragValue::new(&mut attraction.strength)
                            .range(0.0..=5000.0)
                            .clamp_existing_to_range(false)
                            .suffix(" m/s²"),
                    );
                    ui.add(
                        egui::DragValue::new(&mut attraction.radius)
                            .range(0.01..=1.0)
                            .clamp_existing_to_range(false)
                            .speed(0.005)
                            .prefix("r ")
                            .suffix(" m"),
                    );
                });
                ui.end_row();
            });
            // Why the GPU switch is on but the steps are not (a sentence: wrapped below the
            // grid, whose columns do not wrap).
            if let Some(why) = &card.why_not {
                ui.colored_label(AMBER, format!("Stepping on the CPU: {why}."));
            }
            ui.separator();

            // Stability and accuracy
            stability_readout(ui, &stability, p.integrator);
            let particles = solver.particle_count();
            accuracy_readout(ui, p.integrator, p.dt, particles, p.contact);
            if p.integrator == Integrator::Xpbd
                && let Some(line) = crate::readable::xpbd_softness(&solver.solve_stats())
            {
                ui.colored_label(AMBER, line);
            }
            ui.separator();

            // Live figures
            let energy = timeline.energy;
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
                    if p.paused { fps + ", waits for input" } else { fps },
                );
                row("Energy", format!("{} J", number(energy.total(), 6)));
                row("  kinetic", format!("{} J", number(energy.kinetic, 6)));
                row("  gravity", format!("{} J", number(energy.potential_gravity, 6)));
                row("  springs", format!("{} J", number(energy.potential_springs, 6)));
                if !solver.materials().gas().is_empty() {
                    // −nRT ln A: its zero is at A = 1 m², so only its changes mean anything.
                    row("  gas", format!("{} J", number(energy.potential_gas, 6)));
                }
            });
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

/// The selected method's iteration counts, as rows of the parameter grid (none for the
/// explicit methods).
fn iteration_rows(ui: &mut egui::Ui, integrator: Integrator, it: &mut Iterations) {
    let row = |ui: &mut egui::Ui, label: &str, value: &mut u32, max: u32, hint: &str| {
        ui.label(label);
        ui.add(slider(value, 1..=max).logarithmic(true))
            .on_hover_text(hint);
        ui.end_row();
    };
    match integrator {
        Integrator::ImplicitEuler => row(
            ui,
            "Newton steps",
            &mut it.newton,
            50,
            "1: linearised once (the classic step); more converge to exact backward Euler",
        ),
        Integrator::ProjectiveDynamics => row(
            ui,
            "Iterations",
            &mut it.projective,
            500,
            "local/global iterations per step; the matrix is factored once",
        ),
        Integrator::Xpbd => {
            row(
                ui,
                "Substeps",
                &mut it.xpbd_substeps,
                200,
                "substeps per step",
            );
            row(
                ui,
                "Sweeps",
                &mut it.xpbd_sweeps,
                50,
                "constraint sweeps per substep (the least, with a tolerance)",
            );
            ui.label("Tolerance");
            ui.add(
                slider(&mut it.xpbd_tolerance, 0.0..=0.1)
                    .logarithmic(true)
                    .custom_formatter(|v, _| {
                        if v == 0.0 {
                            "off".into()
                        } else {
                            format!("{v:.0e}")
                        }
                    }),
            )
            .on_hover_text(
                "sweep each substep until the largest constraint error |C + α̃λ|/L is under \
                 this, up to the cap; 0 = off",
            );
            ui.end_row();
        }
        Integrator::Bdf2 => row(
            ui,
            "Iterations",
            &mut it.bdf2,
            500,
            "local/global iterations per step; its two matrices are factored once",
        ),
        Integrator::Vbd => {
            row(
                ui,
                "Iterations",
                &mut it.vbd,
                500,
                "sweeps over every vertex per step, colour by colour; nothing is factored",
            );
        }
        _ => {}
    }
}

/// The CPU/GPU switch: steps on the graphics card when it runs the scene (the state carries
/// over both ways), and why not when it does not.
fn device_rows(ui: &mut egui::Ui, card: &mut crate::sim::gpu::CardStep) {
    ui.label("Device");
    ui.horizontal(|ui| {
        let adapter = card.adapter();
        let mut on = card.wanted;
        let toggle = egui::Checkbox::new(&mut on, "GPU");
        let hover = adapter.clone().unwrap_or_else(|| "no graphics card".into());
        if ui
            .add_enabled(adapter.is_some(), toggle)
            .on_hover_text(hover)
            .changed()
        {
            card.wanted = on;
        }
        if card.active() {
            ui.small("stepping on the card");
        } else if card.why_not.is_some() {
            ui.colored_label(AMBER, "on the CPU");
        }
    });
    ui.end_row();
}

/// The panel's other resources (a system takes at most 16 parameters).
#[derive(SystemParam)]
pub struct PanelExtras<'w> {
    timeline: Res<'w, Timeline>,
    history: Res<'w, History>,
    attraction: ResMut<'w, Attraction>,
    scene_list: Res<'w, SceneList>,
    card: ResMut<'w, crate::sim::gpu::CardStep>,
}

const RED: egui::Color32 = egui::Color32::from_rgb(255, 110, 90);
const AMBER: egui::Color32 = egui::Color32::from_rgb(240, 190, 70);
const GREEN: egui::Color32 = egui::Color32::from_rgb(140, 200, 140);

/// The step to offer when a method made for large steps (stable at any dt) runs at a step the
/// explicit methods could take: picked from the combo box, it keeps the scene's dt (1e-4 s in
/// the assignment's scenes) and runs a big cloth in slow motion for no gain in stability.
/// A slider field's number in at most seven characters: up to six digits fit the panel beside
/// a slider. The stiffness slider's top, 10⁶ N/m, and a scene's stiffer springs show as 1.00e6,
/// like the time step (fewer decimals where the exponent is long), and a scene's springs under
/// 10 N/m keep three decimals (a spring of 0.5 N/m read as 0 N/m).
fn field_number(k: f64) -> String {
    match k {
        0.0 => "0".into(),
        k if (9.9995e-3..9.9995).contains(&k) => format!("{k:.3}"),
        k if (9.9995..999_999.5).contains(&k) => format!("{k:.0}"),
        // As many decimals as fit: 1.00e6, 1.0e-10, 1e-100.
        k => (0..=2)
            .rev()
            .map(|d| format!("{k:.d$e}"))
            .find(|t| t.len() <= 7)
            .unwrap_or_else(|| format!("{k:.0e}")),
    }
}

/// A number typed into a field, as egui reads one: spaces anywhere, and the minus sign (−)
/// for a hyphen. A trailing % or unit is not part of it.
fn parse_number(text: &str) -> Option<f64> {
    let text: String = text
        .chars()
        .filter(|c| !c.is_whitespace())
        .map(|c| if c == '−' { '-' } else { c })
        .collect();
    text.trim_end_matches('%').parse().ok()
}

fn large_step_suggestion(integrator: Integrator, dt: f64) -> Option<f64> {
    const FRAME: f64 = 1.0 / 60.0;
    (integrator.unconditionally_stable() && dt < FRAME / 4.0).then_some(FRAME)
}

/// h·ω_max against the integrator's limit: green below 80 %, amber below 100 %, red past it.
fn stability_readout(ui: &mut egui::Ui, s: &StabilityEstimate, integrator: Integrator) {
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

/// The method's order and what the work-precision report measured at this dt.
fn accuracy_readout(
    ui: &mut egui::Ui,
    integrator: Integrator,
    dt: f64,
    particles: usize,
    contact: Option<ContactSettings>,
) {
    use super::predict::{Prediction, order, predict};
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Seven characters at most (the width of "999999"; a longer number ran past the panel's
    /// edge), and within 5 % of the value from 10⁻⁹⁹ to 10³⁰⁰ N/m (below, the decade).
    #[test]
    fn a_fields_number_fits_the_panel() {
        assert_eq!(field_number(0.0), "0");
        for e in -990..=3000 {
            let k = 10f64.powf(e as f64 / 10.0);
            let text = field_number(k);
            assert!(text.len() <= 7, "{k}: {text}");
            let back: f64 = text.parse().unwrap();
            assert!((back - k).abs() <= 0.05 * k, "{k}: {text}");
        }
        assert_eq!(field_number(0.5), "0.500");
        assert_eq!(field_number(10.0), "10");
        assert_eq!(field_number(999_999.0), "999999");
        assert_eq!(field_number(1e6), "1.00e6");
        assert_eq!(field_number(9.99e99), "9.99e99");
        assert_eq!(field_number(1e300), "1.0e300");
        assert_eq!(field_number(1e-10), "1.0e-10");
        assert_eq!(field_number(2e-300), "2e-300");
    }

    /// What the tearing field's parser reads (the field divides it by 100).
    #[test]
    fn a_typed_number_is_read() {
        assert_eq!(parse_number("30"), Some(30.0));
        assert_eq!(parse_number(" 1 5 %"), Some(15.0));
        assert_eq!(parse_number("−2.5e1"), Some(-25.0));
        assert_eq!(parse_number("60 %"), Some(60.0));
        assert_eq!(parse_number("a30"), None);
        assert_eq!(parse_number(""), None);
    }

    /// Offered to the large-step methods at small steps only, never to the explicit ones.
    #[test]
    fn a_real_time_step_is_offered_to_the_large_step_methods_only() {
        for i in Integrator::ALL {
            let offered = large_step_suggestion(i, 1e-4);
            assert_eq!(offered.is_some(), i.unconditionally_stable(), "{i}");
            assert_eq!(large_step_suggestion(i, 1.0 / 60.0), None, "{i}");
        }
        assert_eq!(
            large_step_suggestion(Integrator::Xpbd, 1e-3),
            Some(1.0 / 60.0)
        );
    }
}
