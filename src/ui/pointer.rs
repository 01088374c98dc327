//! Mouse gestures on the canvas: a press on a particle grabs it, a click on empty canvas adds
//! one (shift: pinned), ctrl + drag cuts springs, the right button attracts. With O, B or L
//! held a left drag builds an obstacle (a circle, a box, a segment), with J a ball of
//! particles, with K a crate (a rigid body), and a press on an obstacle moves it.
//!
//! The grab is kinematic: while held, the particle is placed at the cursor every frame and
//! moves with the cursor's velocity during the ticks in between (the solver treats it as
//! infinitely heavy, [`Kinematic`]); on release it keeps that velocity. A stiff mouse spring
//! would lag behind the cursor and, stiff enough not to, would set the stable step of the whole
//! scene; a kinematic particle follows exactly and costs the integrators nothing. While paused
//! the grab moves the particle and leaves it at rest.

use super::edit;
use super::events::PressedAt;
use super::pick::Picking;
use super::view::CanvasView;
use crate::scene::{ClickRules, CurrentScene};
use crate::sim::*;
use crate::solver::{Placed, Shape};
use bevy::ecs::entity::{Entities, EntityHashSet};
use bevy::ecs::system::SystemParam;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy_egui::input::EguiWantsInput;

/// How close, in logical pixels, a press must be to a particle to pick it.
pub const PICK_PX: f32 = 10.0;
/// How far, in logical pixels, the cursor may move between press and release for a press on
/// empty canvas to count as a click that adds a particle. A press inside a cloth that misses
/// every particle and drags on (an attempt to grab it) would otherwise add a particle joined
/// to every particle within the click radius.
pub const CLICK_SLOP_PX: f32 = 5.0;
/// Time constant of the grabbed particle's velocity estimate, s.
const VELOCITY_SMOOTHING: f64 = 0.04;

/// The gesture under way.
#[derive(Resource, Debug, Default)]
pub enum Gesture {
    #[default]
    None,
    Grab {
        particle: Entity,
        last: DVec2,
        velocity: DVec2,
    },
    Cut {
        last: DVec2,
        cut: EntityHashSet,
    },
    /// A press on empty canvas: a particle is added there if the button comes up within
    /// [`CLICK_SLOP_PX`] of it (a click), and nothing if the press turns into a drag.
    Add {
        at: DVec2,
        pinned: bool,
    },
    /// A drag with O, B or L held: the obstacle from where it began to the cursor, built when
    /// the button comes up.
    Build {
        kind: Build,
        from: DVec2,
        to: DVec2,
    },
    /// A press on an obstacle: it follows the cursor (kept at `offset` from it), moved there by
    /// the steps at a velocity, which what it meets feels: struck ahead of it, or carried by
    /// friction. It keeps its own spin while held, and on release its own motion comes back
    /// (`own`, read when the drag begins; none: it stops).
    MoveObstacle {
        obstacle: Entity,
        offset: DVec2,
        own: Option<ObstacleVelocity>,
    },
}

/// The obstacle a build drag makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Build {
    /// O: a circle, centred where the drag began, through the cursor.
    Circle,
    /// B: a box, with corners where the drag began and at the cursor.
    Box,
    /// L: a segment (a line of thickness 0) from where the drag began to the cursor.
    Segment,
    /// J: a ball (a ring of particles filled with gas, a pressure body), centred where the
    /// drag began, through the cursor. Not an obstacle: it falls, bounces and squashes.
    Ball,
    /// K: a crate, a rigid box of avian's, with corners where the drag began and at the
    /// cursor. Not an obstacle either: it falls, the particles push it and it pushes them.
    Crate,
}

impl Build {
    /// The build key held now, if any.
    fn held(keys: &ButtonInput<KeyCode>) -> Option<Build> {
        [
            (KeyCode::KeyO, Build::Circle),
            (KeyCode::KeyB, Build::Box),
            (KeyCode::KeyL, Build::Segment),
            (KeyCode::KeyJ, Build::Ball),
            (KeyCode::KeyK, Build::Crate),
        ]
        .into_iter()
        .find(|(k, _)| keys.pressed(*k) || keys.just_released(*k))
        .map(|(_, b)| b)
    }

    /// The obstacle a drag from `from` to `to` builds, as its shape and centre: `None` when it
    /// is smaller than `least` (m), a click rather than a drag.
    pub fn shape(self, from: DVec2, to: DVec2, least: f64) -> Option<(Shape, DVec2)> {
        let d = to - from;
        match self {
            Build::Circle | Build::Ball => (d.length() >= least).then(|| {
                let radius = d.length();
                (Shape::Circle { radius }, from)
            }),
            Build::Box | Build::Crate => (d.x.abs() >= least && d.y.abs() >= least).then(|| {
                let half = d.abs() * 0.5;
                (Shape::Box { half }, from + d * 0.5)
            }),
            Build::Segment => (d.length() >= least).then(|| {
                let half = d * 0.5;
                let segment = Shape::Segment {
                    a: -half,
                    b: half,
                    thickness: 0.0,
                };
                (segment, from + half)
            }),
        }
    }
}

/// The cursor in window and world coordinates, and whether it may start a gesture (on the
/// canvas, not over a panel or window of egui's).
#[derive(SystemParam)]
pub struct Cursor<'w, 's> {
    window: Single<'w, 's, &'static Window, With<PrimaryWindow>>,
    egui: Res<'w, EguiWantsInput>,
    view: Res<'w, CanvasView>,
    pressed: Res<'w, PressedAt>,
}

impl Cursor<'_, '_> {
    /// The world point where the left button went down this frame, when that was on the
    /// canvas and free.
    pub fn left_press(&self) -> Option<DVec2> {
        self.free(self.pressed.left.or(self.window.cursor_position())?)
    }

    pub fn world(&self) -> Option<DVec2> {
        let p = self.window.cursor_position()?;
        Some(self.view.window_to_world(p))
    }

    /// The world point under the cursor, when the cursor is on the canvas and free.
    pub fn on_canvas(&self) -> Option<DVec2> {
        self.free(self.window.cursor_position()?)
    }

    /// The world point of window point `p`, when it is free for a gesture.
    fn free(&self, p: Vec2) -> Option<DVec2> {
        self.view
            .free_for_gesture(p, &self.egui)
            .then(|| self.view.window_to_world(p))
    }

    /// The pick radius in metres.
    pub fn pick_radius(&self) -> f64 {
        PICK_PX as f64 * self.view.pixel()
    }

    /// [`CLICK_SLOP_PX`] in metres.
    pub fn click_slop(&self) -> f64 {
        CLICK_SLOP_PX as f64 * self.view.pixel()
    }
}

/// Shift and ctrl for a mouse gesture: down at any time during this frame (held, pressed or
/// released in it). A quick shift+click can press and release shift within one frame, or
/// release it in the frame that brings the click. (Key chords read [`super::events::KeyPresses`],
/// which keeps each key's own modifiers.)
pub fn modifiers(keys: &ButtonInput<KeyCode>) -> (bool, bool) {
    let held = |pair: [KeyCode; 2]| {
        keys.any_pressed(pair) || keys.any_just_pressed(pair) || keys.any_just_released(pair)
    };
    let shift = held([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    let ctrl = held([KeyCode::ControlLeft, KeyCode::ControlRight]);
    (shift, ctrl)
}

/// Left press: cut (ctrl), grab (on a particle), or on empty canvas the start of a click that
/// adds a particle when the button comes up ([`drag`]; shift pins it).
#[allow(clippy::too_many_arguments)]
pub fn press(
    mut commands: Commands,
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    cursor: Cursor,
    scene: Option<Res<CurrentScene>>,
    solver: Res<Solver>,
    mut picking: ResMut<Picking>,
    mut gesture: ResMut<Gesture>,
    obstacles: ObstacleQuery,
) {
    if !buttons.just_pressed(MouseButton::Left) {
        return;
    }
    let Some(at) = cursor.left_press() else {
        return;
    };
    let (shift, ctrl) = modifiers(&keys);
    if let Some(kind) = Build::held(&keys) {
        *gesture = Gesture::Build {
            kind,
            from: at,
            to: at,
        };
        return;
    }
    if ctrl {
        *gesture = Gesture::Cut {
            last: at,
            cut: EntityHashSet::default(),
        };
        return;
    }
    let cell = click_rules(&scene).radius;
    if let Some(particle) = picking.nearest(&solver, at, cursor.pick_radius(), cell) {
        commands.queue(super::history::before("grab"));
        commands.entity(particle).insert(Kinematic);
        *gesture = Gesture::Grab {
            particle,
            last: at,
            velocity: DVec2::ZERO,
        };
        return;
    }
    if let Some((obstacle, center)) = obstacle_at(&obstacles, at, cursor.pick_radius()) {
        commands.queue(super::history::before("move obstacle"));
        *gesture = Gesture::MoveObstacle {
            obstacle,
            offset: center - at,
            own: None,
        };
        return;
    }
    *gesture = Gesture::Add { at, pinned: shift };
}

/// The cursor's smoothed velocity (time constant [`VELOCITY_SMOOTHING`]) as it moves from
/// `last` to `at` in `dt`; `last` becomes `at`.
fn follow(velocity: &mut DVec2, last: &mut DVec2, at: DVec2, dt: f64) {
    if dt > 0.0 {
        let alpha = 1.0 - (-dt / VELOCITY_SMOOTHING).exp();
        *velocity += ((at - *last) / dt - *velocity) * alpha;
    }
    *last = at;
}

/// The obstacles as entities, for picking.
pub type ObstacleQuery<'w, 's> = Query<'w, 's, (Entity, &'static Obstacle, &'static ObstaclePose)>;

/// The obstacle under `at` (inside it, or within `radius` of its outline), and its centre:
/// the nearest when several are.
pub fn obstacle_at(obstacles: &ObstacleQuery, at: DVec2, radius: f64) -> Option<(Entity, DVec2)> {
    obstacles
        .iter()
        .map(|(e, o, pose)| {
            let (d, _) = Placed::at(o.0, pose.center, pose.angle).distance(at);
            (d, e, pose.center)
        })
        .filter(|(d, ..)| *d <= radius)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, e, c)| (e, c))
}

/// The scene's click rules (radius, stiffness, mass, first pinned), or the assignment's.
fn click_rules(scene: &Option<Res<CurrentScene>>) -> ClickRules {
    scene
        .as_ref()
        .and_then(|s| s.0.scene.click)
        .unwrap_or_default()
}

/// Adds a particle at `at`, joined to every particle within the click radius.
fn add_at(
    commands: &mut Commands,
    at: DVec2,
    shift: bool,
    rules: &ClickRules,
    params: &SimParams,
    solver: &Res<Solver>,
    picking: &mut Picking,
) {
    let cell = rules.radius;
    let neighbours = picking.within(solver, at, rules.radius, cell);
    let pinned =
        shift || (rules.pin_first && solver.particle_count() == 0 && neighbours.is_empty());
    let stiffness = params.stiffness_override.unwrap_or(rules.stiffness);
    let new = edit::add_particle(commands, at, pinned, rules, stiffness, &neighbours);
    picking.note_added(solver, at, new, cell);
}

/// While the left button is held: the grabbed particle follows the cursor, or the cut goes on
/// along its path. Release ends the gesture, and completes a click on empty canvas.
#[allow(clippy::too_many_arguments)]
pub fn drag(
    mut commands: Commands,
    buttons: Res<ButtonInput<MouseButton>>,
    cursor: Cursor,
    scene: Option<Res<CurrentScene>>,
    time: Res<Time<Real>>,
    params: Res<SimParams>,
    status: Res<SimStatus>,
    solver: Res<Solver>,
    entities: &Entities,
    springs: Query<&Spring>,
    mut picking: ResMut<Picking>,
    mut gesture: ResMut<Gesture>,
    mut particles: Query<(&mut Position, &mut Velocity), With<Particle>>,
    mut moving: Query<(&mut ObstaclePose, &mut ObstacleVelocity)>,
) {
    let held = buttons.pressed(MouseButton::Left);
    let at = cursor.world();
    match &mut *gesture {
        Gesture::None => {}
        Gesture::Build { kind, from, to } => {
            if let Some(at) = at {
                *to = at;
            }
            if !held {
                match (kind.shape(*from, *to, cursor.click_slop()), *kind) {
                    (Some((Shape::Circle { radius }, center)), Build::Ball) => {
                        let stiffness = params.stiffness_override.unwrap_or(DEFAULT_STIFFNESS);
                        edit::add_ball(&mut commands, center, radius, stiffness);
                    }
                    (Some((Shape::Box { half }, center)), Build::Crate) => {
                        edit::add_crate(&mut commands, half, center);
                    }
                    (Some((shape, center)), _) => edit::add_obstacle(&mut commands, shape, center),
                    (None, _) => {}
                }
                *gesture = Gesture::None;
            }
        }
        Gesture::MoveObstacle {
            obstacle,
            offset,
            own,
        } => {
            let Ok((mut pose, mut vel)) = moving.get_mut(*obstacle) else {
                // Deleted or undone under the cursor.
                *gesture = Gesture::None;
                return;
            };
            let own = *own.get_or_insert(*vel);
            let stepping = held && !params.paused && *status == SimStatus::Running;
            let frame = time.delta_secs_f64();
            let mut v = DVec2::ZERO;
            if let Some(at) = at {
                let target = at + *offset;
                if stepping && frame > 0.0 {
                    // The coming frame's steps take it to the cursor at this velocity, and their
                    // contact strikes what lies in its way. Set down at the cursor instead, it
                    // jumped between two steps, past a strip of cloth lying on a thin shelf.
                    v = (target - pose.center) / frame;
                } else if pose.center != target {
                    pose.center = target;
                }
            }
            let now = if held {
                ObstacleVelocity {
                    linear: v,
                    angular: own.angular,
                }
            } else {
                own
            };
            if *vel != now {
                *vel = now;
            }
            if !held {
                *gesture = Gesture::None;
            }
        }
        &mut Gesture::Add {
            at: pressed,
            pinned,
        } => {
            // Where the button came up: the cursor now (a frame can bring press and release).
            let moved = at.is_none_or(|at| at.distance(pressed) > cursor.click_slop());
            if moved {
                *gesture = Gesture::None;
            } else if !held {
                let rules = click_rules(&scene);
                add_at(
                    &mut commands,
                    pressed,
                    pinned,
                    &rules,
                    &params,
                    &solver,
                    &mut picking,
                );
                *gesture = Gesture::None;
            }
        }
        Gesture::Grab {
            particle,
            last,
            velocity,
        } => {
            let Ok((mut pos, mut vel)) = particles.get_mut(*particle) else {
                // Deleted, cleared or undone under the cursor.
                *gesture = Gesture::None;
                return;
            };
            if let Some(at) = at {
                follow(velocity, last, at, time.delta_secs_f64());
                pos.set_if_neq(Position(at));
            }
            let v = if params.paused {
                DVec2::ZERO
            } else {
                *velocity
            };
            vel.set_if_neq(Velocity(v));
            if !held {
                commands.entity(*particle).remove::<Kinematic>();
                *gesture = Gesture::None;
            }
        }
        Gesture::Cut { last, cut } => {
            if let Some(at) = at
                && at != *last
            {
                let crossed: Vec<Entity> = picking
                    .springs_crossing(&solver, *last, at)
                    .into_iter()
                    .filter_map(|i| {
                        let spring = |e| springs.get(e).ok().copied();
                        solver.spring_entity(i as usize, entities, spring)
                    })
                    .filter(|e| !cut.contains(e))
                    .collect();
                if !crossed.is_empty() {
                    edit::cut(&mut commands, &crossed, cut.is_empty());
                    cut.extend(crossed);
                }
                *last = at;
            }
            if !held {
                *gesture = Gesture::None;
            }
        }
    }
}

/// Right button held: pull the particles near the cursor toward it ([`Attraction`]: the
/// simulation evaluates the pull every step, through the external forces that every
/// integrator reads).
pub fn attract(
    buttons: Res<ButtonInput<MouseButton>>,
    cursor: Cursor,
    mut attraction: ResMut<Attraction>,
) {
    let started = buttons.just_pressed(MouseButton::Right) && cursor.on_canvas().is_some();
    let held = buttons.pressed(MouseButton::Right) && (started || attraction.active_at.is_some());
    let at = held.then(|| cursor.world()).flatten();
    if attraction.active_at != at {
        attraction.active_at = at;
    }
}
