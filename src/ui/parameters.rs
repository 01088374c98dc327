//! The panel's parameter grid: the method and its iterations, the device, stiffness, damping,
//! the dashpots, dt, the ground, contact, tearing and the attraction; and what the grid's
//! fields keep between frames ([`PanelState`]).

use super::readouts::AMBER;
use crate::sim::*;
use bevy::prelude::*;
use bevy_egui::egui;

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

impl PanelState {
    /// Shows a newly opened scene's values: its first spring's stiffness (else what a click
    /// would use), and its tearing strain where it tears.
    pub(super) fn follow(&mut self, scene: &crate::scene::Scene) {
        self.stiffness = (scene.spring_defs().next())
            .map(|s| s.stiffness)
            .or(scene.click.map(|c| c.stiffness))
            .unwrap_or(DEFAULT_STIFFNESS);
        if let Some(strain) = scene.tear {
            self.tear = strain;
        }
    }
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

/// The method and its settings, the device, and the physics' parameters, as one grid.
pub(super) fn parameter_grid(
    ui: &mut egui::Ui,
    p: &mut SimParams,
    state: &mut PanelState,
    card: &mut crate::sim::gpu::CardStep,
    attraction: &mut Attraction,
    materials: &crate::solver::Materials,
) {
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
        device_rows(ui, card);

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
                    if text.len() <= 7 {
                        text
                    } else {
                        field_number(v)
                    }
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
        if let Some(line) = materials_line(materials) {
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

        contact_rows(ui, p, state);

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
            if ui
                .add_enabled(on, tear)
                .on_hover_text("strain at which a spring breaks")
                .changed()
            {
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
}

/// The contact rows of the parameter grid: on or off, friction, restitution and radius; pairs
/// and outlines. Switched off, the fields keep what switching on will apply.
fn contact_rows(ui: &mut egui::Ui, p: &mut SimParams, state: &mut PanelState) {
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

/// The step to offer when a method made for large steps (stable at any dt) runs at a step the
/// explicit methods could take: picked from the combo box, it keeps the scene's dt (1e-4 s in
/// the assignment's scenes) and runs a big cloth in slow motion for no gain in stability.
fn large_step_suggestion(integrator: Integrator, dt: f64) -> Option<f64> {
    const FRAME: f64 = 1.0 / 60.0;
    (integrator.unconditionally_stable() && dt < FRAME / 4.0).then_some(FRAME)
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
