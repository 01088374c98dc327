//! The scene file format (RON). `docs/scene-format.md` lists every field with an example.
//!
//! Every struct and struct variant denies unknown fields: a misspelled optional field would
//! otherwise be ignored and the scene run with its default (see `scene::typo`).

use crate::sim::Integrator;
use serde::{Deserialize, Serialize};

/// A scene as written in a `.ron` file. A field left out takes [`Scene::default`]'s value, the
/// app's own (`SimParams::default`), so that a file of a generator alone runs as the app would
/// run it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scene {
    /// Gravitational acceleration (x, y), m/s²; default (0, −9.8).
    pub gravity: (f64, f64),
    /// Velocity damping rate μ, 1/s (0 = off): air drag, which slows every motion alike;
    /// default 10, the app's.
    pub damping: f64,
    /// The dashpot c (N·s/m) of every spring without a `damping` of its own; default 0 (off).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub spring_damping: f64,
    /// Projective dynamics and VBD take `damping` inside their solve as the force −μ m v
    /// (BDF2 always does); default false: exp(−μ dt) after the step.
    #[serde(default, skip_serializing_if = "is_false")]
    pub drag_in_solve: bool,
    /// Height of the ground; `None` = no ground; default 0.
    pub ground: Option<f64>,
    /// The time integrator; default symplectic Euler.
    pub integrator: Integrator,
    /// Time step, s; default 1e-4.
    pub dt: f64,
    #[serde(default)]
    /// Explicit particles, indexed from 0.
    pub particles: Vec<ParticleDef>,
    #[serde(default)]
    /// Explicit springs between them.
    pub springs: Vec<SpringDef>,
    /// Particles and springs generated from a few parameters, appended after the explicit ones
    /// (their indices continue the explicit particle list).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub generate: Vec<Generator>,
    /// What a mouse click adds in the app.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub click: Option<ClickRules>,
    /// Start the app paused (the assignment's empty canvas does).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub start_paused: bool,
    /// Tearing: `Some(strain)` breaks a spring stretched past (1 + strain) × rest.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tear: Option<f64>,
    /// Iteration counts of the iterative integrators (Newton steps, projective dynamics'
    /// iterations, XPBD's substeps and sweeps); any left out keep their defaults:
    /// `iterations: (projective: 20)`.
    #[serde(default, skip_serializing_if = "is_default_iterations")]
    pub iterations: crate::sim::Iterations,
    /// Static shapes every particle collides with (whatever `contact` says: as points when it
    /// gives no radius).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<ObstacleDef>,
    /// Contact: the particles' radius and the friction and restitution of every contact.
    /// `None` keeps the assignment's ground: points, clamped, frictionless.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<crate::sim::ContactSettings>,
    /// Gas-filled loops of explicit or generated particles (a `Ring` generator adds its own).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pressure: Vec<PressureDef>,
    /// Rigid bodies of avian2d, which the particles push and which push them (a build with the
    /// `avian` feature, the default one, runs them; another refuses the scene and says so).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodyDef>,
}

/// A rigid body as written in a scene: a shape of the obstacles' kinds where it starts, its
/// mass and its motion: `(shape: Box(center: (0.5, 0.6), half: (0.1, 0.05)), mass: 0.5)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyDef {
    /// Its shape and where it starts (its centre is its position; a polygon's centre need not
    /// be its centre of mass).
    pub shape: ObstacleDef,
    /// Its mass, kg; default 1. Its moment of inertia is the shape's, of uniform density.
    #[serde(default = "default_body_mass")]
    pub mass: f64,
    /// Its velocity (x, y), m/s; default at rest.
    #[serde(default, skip_serializing_if = "is_zero_pair")]
    pub velocity: (f64, f64),
    /// Its angular velocity, rad/s (counter-clockwise); default 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub spin: f64,
    /// A body that never moves (avian's static body); default false: it falls, is pushed, turns.
    #[serde(default, skip_serializing_if = "is_false")]
    pub fixed: bool,
}

fn default_body_mass() -> f64 {
    1.0
}

fn is_zero_pair(v: &(f64, f64)) -> bool {
    *v == (0.0, 0.0)
}

/// A closed loop of particles filled with gas: `pressure: [(particles: [0, 1, 2, 3], nrt: 20.0)]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureDef {
    /// The loop's particles by index, in order around it (either way round).
    pub particles: Vec<usize>,
    /// nRT, N·m: the pressure at area A is nRT/A.
    pub nrt: f64,
}

/// A muscle's oscillation: the rest length is L₀ (1 + amplitude · sin(2π frequency t + phase)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Actuation {
    /// A, a fraction of L₀.
    pub amplitude: f64,
    /// f, Hz.
    pub frequency: f64,
    /// φ, rad; default 0.
    #[serde(default)]
    pub phase: f64,
}

/// Plasticity: past a strain `yield`, the rest length creeps toward the length at `rate`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plasticity {
    /// ε_y, the strain |l − L|/L past which the spring yields.
    #[serde(rename = "yield")]
    pub yield_strain: f64,
    /// r, 1/s.
    pub rate: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_false(v: &bool) -> bool {
    !*v
}

/// An obstacle as written in a scene: a shape where it stands, or ([`ObstacleDef::Moving`])
/// where it starts and how it moves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ObstacleDef {
    /// A disc.
    Circle {
        /// Its centre (x, y), m.
        center: (f64, f64),
        /// Its radius, m.
        radius: f64,
    },
    /// A rectangle.
    Box {
        /// Its centre (x, y), m.
        center: (f64, f64),
        /// Half its width and height, m.
        half: (f64, f64),
        /// Its rotation, rad (counter-clockwise); default 0.
        #[serde(default)]
        angle: f64,
    },
    /// A segment from `a` to `b`; a capsule when `thickness` > 0.
    Segment {
        /// One end (x, y), m.
        a: (f64, f64),
        /// The other end.
        b: (f64, f64),
        /// The capsule's radius, m; default 0 (a line).
        #[serde(default)]
        thickness: f64,
    },
    /// A convex polygon of 3 to 16 corners.
    Polygon {
        /// The point its corners are given about (x, y), m: the centre it turns about.
        center: (f64, f64),
        /// Its corners (x, y) about `center`, m, in either turning order.
        corners: Vec<(f64, f64)>,
        /// Its rotation, rad (counter-clockwise); default 0.
        #[serde(default)]
        angle: f64,
    },
    /// One of the shapes above, moving at a constant velocity and spin, as a kinematic body
    /// does: nothing pushes it, it strikes what lies in its way, and it carries what rests on
    /// it by friction (a conveyor, a paddle, a press).
    Moving {
        /// The shape where it starts: a `Circle`, `Box`, `Segment` or `Polygon`.
        shape: std::boxed::Box<ObstacleDef>,
        /// Its centre's velocity (x, y), m/s; default 0.
        #[serde(default)]
        velocity: (f64, f64),
        /// Its angular velocity about its centre (a segment's midpoint), rad/s,
        /// counter-clockwise; default 0.
        #[serde(default)]
        spin: f64,
    },
}

impl ObstacleDef {
    /// The shape in its own frame, where it stands and how it moves: a segment's frame is
    /// centred on its midpoint. An error says what is wrong with a polygon's corners, or with
    /// a moving obstacle's shape.
    pub fn placed(&self) -> Result<crate::solver::Placed, String> {
        use crate::solver::{Placed, Polygon, Shape};
        use glam::DVec2;
        let (shape, center, angle) = match *self {
            ObstacleDef::Moving {
                ref shape,
                velocity,
                spin,
            } => {
                if let ObstacleDef::Moving { .. } = **shape {
                    return Err(
                        "shape: a moving obstacle's shape is a Circle, Box, Segment or Polygon, \
                         not another Moving"
                            .into(),
                    );
                }
                let mut placed = shape.placed()?;
                placed.pose.velocity = DVec2::from(velocity);
                placed.pose.angular_velocity = spin;
                return Ok(placed);
            }
            ObstacleDef::Circle { center, radius } => {
                (Shape::Circle { radius }, DVec2::from(center), 0.0)
            }
            ObstacleDef::Box {
                center,
                half,
                angle,
            } => (
                Shape::Box {
                    half: DVec2::from(half),
                },
                DVec2::from(center),
                angle,
            ),
            ObstacleDef::Segment { a, b, thickness } => {
                let (a, b) = (DVec2::from(a), DVec2::from(b));
                let mid = (a + b) * 0.5;
                let shape = Shape::Segment {
                    a: a - mid,
                    b: b - mid,
                    thickness,
                };
                (shape, mid, 0.0)
            }
            ObstacleDef::Polygon {
                center,
                ref corners,
                angle,
            } => {
                let corners: Vec<DVec2> = corners.iter().map(|&c| DVec2::from(c)).collect();
                let shape = Shape::Polygon(Polygon::new(&corners)?);
                (shape, DVec2::from(center), angle)
            }
        };
        Ok(Placed::at(shape, center, angle))
    }

    /// The obstacle as written for a placed shape (the inverse of [`Self::placed`], with a
    /// segment's ends in the world): [`ObstacleDef::Moving`] when it moves.
    pub fn from_placed(p: &crate::solver::Placed) -> Self {
        let shape = Self::shape_of(p);
        if p.moves() {
            let v = p.pose.velocity;
            return ObstacleDef::Moving {
                shape: std::boxed::Box::new(shape),
                velocity: (v.x, v.y),
                spin: p.pose.angular_velocity,
            };
        }
        shape
    }

    /// The shape as written where `p` stands, whether or not it moves.
    fn shape_of(p: &crate::solver::Placed) -> Self {
        use crate::solver::Shape;
        let c = p.pose.center;
        match p.shape {
            Shape::Circle { radius } => ObstacleDef::Circle {
                center: (c.x, c.y),
                radius,
            },
            Shape::Box { half } => ObstacleDef::Box {
                center: (c.x, c.y),
                half: (half.x, half.y),
                angle: p.pose.angle,
            },
            Shape::Segment { a, b, thickness } => {
                let turn = glam::DVec2::from_angle(p.pose.angle);
                let (a, b) = (c + turn.rotate(a), c + turn.rotate(b));
                ObstacleDef::Segment {
                    a: (a.x, a.y),
                    b: (b.x, b.y),
                    thickness,
                }
            }
            Shape::Polygon(polygon) => ObstacleDef::Polygon {
                center: (c.x, c.y),
                corners: polygon.corners().iter().map(|c| (c.x, c.y)).collect(),
                angle: p.pose.angle,
            },
        }
    }
}

fn is_default_iterations(i: &crate::sim::Iterations) -> bool {
    *i == crate::sim::Iterations::default()
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
/// A particle as written in a scene.
pub struct ParticleDef {
    /// Position (x, y), m.
    pub pos: (f64, f64),
    #[serde(default)]
    /// Velocity (x, y), m/s; default 0.
    pub vel: (f64, f64),
    #[serde(default = "default_mass")]
    /// Mass, kg; default 1.
    pub mass: f64,
    #[serde(default)]
    /// Pinned: never moves; default false.
    pub pinned: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
/// A spring as written in a scene.
pub struct SpringDef {
    /// Index of one end.
    pub a: usize,
    /// Index of the other end.
    pub b: usize,
    #[serde(default = "default_stiffness")]
    /// Stiffness, N/m; default 1e4.
    pub stiffness: f64,
    /// Rest length, m; left out, the distance between its ends where the scene places them (a
    /// spring at rest as drawn; [`Scene::spring_defs`] gives it). Written and read bare
    /// (`rest: 0.1`), as when it was required, whatever ron's options; `Some(0.1)` reads too.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "bare_number",
        deserialize_with = "bare_or_some_number"
    )]
    pub rest: Option<f64>,
    /// Its dashpot c, N·s/m; default: the scene's `spring_damping`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// A muscle: its rest length oscillates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actuation: Option<Actuation>,
    /// Plastic: its rest length yields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plastic: Option<Plasticity>,
}

/// An optional number written as the number itself: `rest: 0.1` is what a person writes.
fn bare_number<S: serde::Serializer>(value: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match value {
        Some(v) => s.serialize_f64(*v),
        None => s.serialize_none(),
    }
}

/// An optional number read bare (`0.1`) or as `Some(0.1)`, with or without ron's implicit
/// `Some`: text written when the field was a plain number reads the same, through
/// [`super::ron_options`] or plain `ron::from_str`.
fn bare_or_some_number<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    struct Number;
    impl<'de> serde::de::Visitor<'de> for Number {
        type Value = Option<f64>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number (m)")
        }
        fn visit_f64<E>(self, v: f64) -> Result<Self::Value, E> {
            Ok(Some(v))
        }
        fn visit_i64<E>(self, v: i64) -> Result<Self::Value, E> {
            Ok(Some(v as f64))
        }
        fn visit_u64<E>(self, v: u64) -> Result<Self::Value, E> {
            Ok(Some(v as f64))
        }
        fn visit_none<E>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_some<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            f64::deserialize(d).map(Some)
        }
    }
    d.deserialize_any(Number)
}

impl SpringDef {
    /// A plain Hooke spring.
    pub fn new(a: usize, b: usize, rest: f64, stiffness: f64) -> SpringDef {
        SpringDef {
            a,
            b,
            stiffness,
            rest: Some(rest),
            damping: None,
            actuation: None,
            plastic: None,
        }
    }

    /// Whether it has a material beyond the Hooke spring.
    pub fn has_material(&self) -> bool {
        self.damping.is_some() || self.actuation.is_some() || self.plastic.is_some()
    }
}

/// Parametric particle layouts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Generator {
    /// A `cols` × `rows` grid spanning `min`..`max`, row 0 at the top (y = max.y). Particle
    /// `r * cols + c` sits at (min.x + c/(cols-1)·w, max.y − r/(rows-1)·h). Springs, each once, per
    /// (r, c) in this order: right, down and, with `shear`, (r,c)-(r+1,c+1) and (r,c+1)-(r+1,c);
    /// rest = initial distance.
    Grid {
        /// Particles per row.
        cols: usize,
        /// Rows.
        rows: usize,
        /// Lower-left corner (x, y), m.
        min: (f64, f64),
        /// Upper-right corner (x, y), m.
        max: (f64, f64),
        #[serde(default = "default_mass")]
        /// Mass of each particle, kg.
        mass: f64,
        #[serde(default = "default_stiffness")]
        /// Stiffness of each spring, N/m.
        stiffness: f64,
        #[serde(default = "default_true")]
        /// Add both shear diagonals.
        shear: bool,
        #[serde(default)]
        /// Which particles are pinned.
        pin: Pin,
        #[serde(default)]
        /// Initial velocity of every free particle (x, y), m/s.
        vel: (f64, f64),
        /// Every spring's dashpot c, N·s/m; default: the scene's `spring_damping`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        damping: Option<f64>,
        /// Every spring plastic.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        plastic: Option<Plasticity>,
    },
    /// A ring of `segments` particles around `center`, joined neighbour to neighbour, listed
    /// counter-clockwise from angle 0; with `pressure` > 0, a gas of nRT = `pressure` (N·m)
    /// fills it. The springs are at rest at `radius`, so the gas inflates it past that.
    Ring {
        /// The centre (x, y), m.
        center: (f64, f64),
        /// The radius at which the springs are at rest, m.
        radius: f64,
        /// Particles (and springs) around the ring; at least 3.
        segments: usize,
        #[serde(default = "default_mass")]
        /// Mass of each particle, kg.
        mass: f64,
        #[serde(default = "default_stiffness")]
        /// Stiffness of each spring, N/m.
        stiffness: f64,
        /// nRT of the gas inside, N·m; 0 = no gas.
        #[serde(default)]
        pressure: f64,
        /// Every spring's dashpot c, N·s/m; default: the scene's `spring_damping`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        damping: Option<f64>,
    },
    /// `segments` springs in a straight line from `from` to `to` (segments + 1 particles).
    Chain {
        /// First particle (x, y), m.
        from: (f64, f64),
        /// Last particle (x, y), m.
        to: (f64, f64),
        /// Springs along the chain.
        segments: usize,
        #[serde(default = "default_mass")]
        /// Mass of each particle, kg.
        mass: f64,
        #[serde(default = "default_stiffness")]
        /// Stiffness of each spring, N/m.
        stiffness: f64,
        #[serde(default)]
        /// Which particles are pinned.
        pin: Pin,
    },
}

/// Which particles of a generated layout are pinned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Pin {
    #[default]
    /// Nothing pinned.
    None,
    /// A grid's top row; a chain's first particle.
    First,
    /// A grid's two top corners; a chain's two ends.
    Ends,
    /// A grid's left column (a cantilever); a chain's first particle.
    Left,
}

/// What a left click adds: a particle joined to every particle within `radius`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClickRules {
    #[serde(default = "default_radius")]
    /// Join every particle within this distance, m; default 0.15.
    pub radius: f64,
    #[serde(default = "default_stiffness")]
    /// Stiffness of the new springs, N/m.
    pub stiffness: f64,
    #[serde(default = "default_mass")]
    /// Mass of the new particle, kg.
    pub mass: f64,
    /// Pin the particle when it is the scene's first.
    #[serde(default)]
    pub pin_first: bool,
}

impl Default for ClickRules {
    fn default() -> Self {
        ClickRules {
            radius: default_radius(),
            stiffness: default_stiffness(),
            mass: default_mass(),
            pin_first: false,
        }
    }
}

fn default_mass() -> f64 {
    crate::sim::DEFAULT_MASS
}
fn default_stiffness() -> f64 {
    crate::sim::DEFAULT_STIFFNESS
}
fn default_radius() -> f64 {
    0.15
}
fn default_true() -> bool {
    true
}

impl Default for Scene {
    /// The assignment's empty canvas with its defaults.
    fn default() -> Self {
        let p = crate::sim::SimParams::default();
        Scene {
            gravity: (p.gravity.x, p.gravity.y),
            damping: p.damping,
            spring_damping: p.spring_damping,
            drag_in_solve: p.drag_in_solve,
            ground: p.ground,
            integrator: p.integrator,
            dt: p.dt,
            particles: vec![],
            springs: vec![],
            generate: vec![],
            click: None,
            start_paused: false,
            tear: p.tear,
            iterations: p.iterations,
            obstacles: vec![],
            contact: p.contact,
            pressure: vec![],
            bodies: vec![],
        }
    }
}
