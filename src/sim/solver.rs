//! The packed solver state: the hot data of every particle and spring in dense arrays.
//!
//! The ECS components stay the source of truth; this is a copy laid out for the step loop
//! (structure of arrays, dense `u32` indices), rebuilt or patched by [`crate::sim::sync`] when
//! entities change. Kernels in [`crate::sim::kernels`] run on these slices and know nothing of Bevy.

use bevy::math::DVec2;
use bevy::prelude::*;

/// A spring between two dense particle indices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackedSpring {
    pub a: u32,
    pub b: u32,
    pub rest: f64,
    /// The stiffness in effect: the spring's own, or the global override.
    pub k: f64,
}

#[derive(Resource, Debug, Default)]
pub struct Solver {
    /// Particle entity of each dense index, in creation order.
    pub entities: Vec<Entity>,
    pub x: Vec<DVec2>,
    pub v: Vec<DVec2>,
    /// Force at the start of the current step.
    pub f: Vec<DVec2>,
    pub mass: Vec<f64>,
    /// 1/m, and 0 for a pinned particle: the velocity update then leaves it at rest, with no
    /// branch in the loop.
    pub inv_mass: Vec<f64>,
    /// Each particle's [`crate::sim::ExternalForce`], added to gravity wherever forces are
    /// evaluated; read only while `external_active`.
    pub external: Vec<DVec2>,
    /// Some external force is non-zero. When false, the force passes skip `external` entirely.
    pub external_active: bool,
    /// How many particles are [`crate::sim::Kinematic`] (held by the user).
    pub kinematic: usize,
    /// The velocity the position update moves each particle with (explicit Euler: the velocity
    /// at the start of the step).
    pub drift: Vec<DVec2>,
    /// Spring entity of each packed spring, in creation order.
    pub spring_entities: Vec<Entity>,
    pub springs: Vec<PackedSpring>,
    /// Each spring's own stiffness, kept so that clearing the override restores it.
    pub own_stiffness: Vec<f64>,
    /// The stiffness override the packed `k` values reflect.
    pub applied_override: Option<f64>,
    /// Set by the position update when the step produced a non-finite position or velocity.
    pub non_finite: bool,
    /// Work buffers of the multi-stage integrators and the implicit solve's counters.
    pub scratch: super::integrators::Scratch,
    /// Per-thread buffers of the parallel spring pass.
    pub spring_buffers: super::parallel::SpringBuffers,
}

impl Solver {
    pub fn particle_count(&self) -> usize {
        self.x.len()
    }

    pub fn spring_count(&self) -> usize {
        self.springs.len()
    }

    pub fn is_pinned(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }

    /// Applies (or clears) a global stiffness override to every spring.
    pub fn apply_stiffness_override(&mut self, k: Option<f64>) {
        for (s, own) in self.springs.iter_mut().zip(&self.own_stiffness) {
            s.k = k.unwrap_or(*own);
        }
        self.applied_override = k;
    }

    /// Total mechanical energy: Σ ½m|v|² − Σ m g·x + Σ ½k(|xa−xb|−L)².
    pub fn energy(&self, gravity: DVec2) -> Energy {
        let mut kinetic = 0.0;
        let mut potential_gravity = 0.0;
        for ((x, v), m) in self.x.iter().zip(&self.v).zip(&self.mass) {
            kinetic += 0.5 * m * v.length_squared();
            potential_gravity -= m * gravity.dot(*x);
        }
        let mut potential_springs = 0.0;
        for s in &self.springs {
            let stretch = (self.x[s.a as usize] - self.x[s.b as usize]).length() - s.rest;
            potential_springs += 0.5 * s.k * stretch * stretch;
        }
        Energy {
            kinetic,
            potential_gravity,
            potential_springs,
        }
    }

    /// True when every position and velocity is finite.
    pub fn state_is_finite(&self) -> bool {
        self.x.iter().chain(&self.v).all(|p| p.is_finite())
    }
}

/// Mechanical energy in joules, by kind.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energy {
    pub kinetic: f64,
    pub potential_gravity: f64,
    pub potential_springs: f64,
}

impl Energy {
    pub fn total(&self) -> f64 {
        self.kinetic + self.potential_gravity + self.potential_springs
    }
}
