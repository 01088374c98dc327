//! The scene file format (RON). See the README for the schema and an example.

use crate::sim::Integrator;
use serde::{Deserialize, Serialize};

/// A scene as written in a `.ron` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    pub gravity: (f64, f64),
    pub damping: f64,
    /// Height of the ground; `None` = no ground.
    pub ground: Option<f64>,
    pub integrator: Integrator,
    pub dt: f64,
    #[serde(default)]
    pub particles: Vec<ParticleDef>,
    #[serde(default)]
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
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ParticleDef {
    pub pos: (f64, f64),
    #[serde(default)]
    pub vel: (f64, f64),
    #[serde(default = "default_mass")]
    pub mass: f64,
    #[serde(default)]
    pub pinned: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpringDef {
    pub a: usize,
    pub b: usize,
    #[serde(default = "default_stiffness")]
    pub stiffness: f64,
    pub rest: f64,
}

/// Parametric particle layouts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Generator {
    /// A `cols` × `rows` grid spanning `min`..`max`, row 0 at the top (y = max.y). Particle
    /// `r * cols + c` sits at (min.x + c/(cols-1)·w, max.y − r/(rows-1)·h). Springs, each once, per
    /// (r, c) in this order: right, down and, with `shear`, (r,c)-(r+1,c+1) and (r,c+1)-(r+1,c);
    /// rest = initial distance.
    Grid {
        cols: usize,
        rows: usize,
        min: (f64, f64),
        max: (f64, f64),
        #[serde(default = "default_mass")]
        mass: f64,
        #[serde(default = "default_stiffness")]
        stiffness: f64,
        #[serde(default = "default_true")]
        shear: bool,
        #[serde(default)]
        pin: Pin,
        #[serde(default)]
        vel: (f64, f64),
    },
    /// `segments` springs in a straight line from `from` to `to` (segments + 1 particles).
    Chain {
        from: (f64, f64),
        to: (f64, f64),
        segments: usize,
        #[serde(default = "default_mass")]
        mass: f64,
        #[serde(default = "default_stiffness")]
        stiffness: f64,
        #[serde(default)]
        pin: Pin,
    },
}

/// Which particles of a generated layout are pinned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Pin {
    #[default]
    None,
    /// A grid's top row; a chain's first particle.
    First,
    /// A grid's two top corners; a chain's two ends.
    Ends,
}

/// What a left click adds: a particle joined to every particle within `radius`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClickRules {
    #[serde(default = "default_radius")]
    pub radius: f64,
    #[serde(default = "default_stiffness")]
    pub stiffness: f64,
    #[serde(default = "default_mass")]
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
            ground: p.ground,
            integrator: p.integrator,
            dt: p.dt,
            particles: vec![],
            springs: vec![],
            generate: vec![],
            click: None,
            start_paused: false,
            tear: p.tear,
        }
    }
}
