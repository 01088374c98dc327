//! The pull toward a point: the app's right button, or a library user's. Particles within
//! `radius` of the point feel f = m · `strength` · (point − x) / radius, on top of their own
//! [`ExternalForce`].
//!
//! The pull depends on the positions, so it is evaluated every step, from the step's start
//! positions, in the force set, where every integrator reads the external forces. Held for a
//! whole frame of steps instead (500 steps at 20 frames/s and dt = 1e-4 s), it overshot and
//! flung the pulled particles out of its reach.

use super::components::{ExternalForce, SolverIndex};
use super::solver::Solver;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Where and how hard the pull acts (`active_at: None`: nowhere).
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct Attraction {
    /// m.
    pub radius: f64,
    /// m/s² at the rim.
    pub strength: f64,
    /// Where it pulls, while it does.
    pub active_at: Option<DVec2>,
}

impl Default for Attraction {
    fn default() -> Self {
        Attraction {
            radius: 0.12,
            strength: 200.0,
            active_at: None,
        }
    }
}

/// The particles the last step pulled (by entity: a repack between two steps renumbers them).
#[derive(Debug, Default)]
pub struct Pulled(Vec<Entity>);

/// Gives the last step's pulled particles back their own external forces (their
/// [`ExternalForce`], which stays the truth: a user may change it while the pull is on), then
/// pulls the particles now within reach.
pub fn pull(
    attraction: Res<Attraction>,
    mut solver: ResMut<Solver>,
    own: Query<(&SolverIndex, &ExternalForce)>,
    mut pulled: Local<Pulled>,
) {
    if attraction.active_at.is_none() && pulled.0.is_empty() {
        return;
    }
    let solver = &mut *solver;
    let s = &mut solver.state;
    for e in pulled.0.drain(..) {
        if let Ok((i, f)) = own.get(e)
            && (i.0 as usize) < s.x.len()
        {
            s.set_external(i.0 as usize, f.0);
        }
    }
    if let Some(c) = attraction.active_at {
        let (radius, k) = (attraction.radius, attraction.strength / attraction.radius);
        for i in 0..s.x.len() {
            let x = s.x[i];
            if x.distance(c) < radius {
                pulled.0.push(solver.entities[i]);
                let own = s.external_force(i);
                s.set_external(i, own + (c - x) * (s.mass[i] * k));
            }
        }
    }
    s.refresh_external();
}
