//! The pull toward a point: the app's right button, or a library user's. Particles within
//! `radius` of the point feel f = m · `strength` · (point − x) / radius, on top of their own
//! [`ExternalForce`](super::ExternalForce).
//!
//! The pull depends on the positions, so it is evaluated every step, from the step's start
//! positions, in the force set, where every integrator reads the external forces. Held for a
//! whole frame of steps instead (500 steps at 20 frames/s and dt = 1e-4 s), it overshot and
//! flung the pulled particles out of its reach.

use super::components::SolverIndex;
use super::solver::Solver;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Where and how hard the pull acts (`at: None`: nowhere).
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

/// The particles the last step pulled, with their own external forces to give back (by
/// entity: a repack between two steps renumbers the particles).
#[derive(Debug, Default)]
pub struct Pulled {
    own: Vec<(Entity, DVec2)>,
}

/// Gives back the last step's pulled particles their own external forces, then pulls the
/// particles now within reach.
pub fn pull(
    attraction: Res<Attraction>,
    mut solver: ResMut<Solver>,
    index: Query<&SolverIndex>,
    mut pulled: Local<Pulled>,
) {
    if attraction.active_at.is_none() && pulled.own.is_empty() {
        return;
    }
    let solver = &mut *solver;
    let s = &mut solver.state;
    for &(e, own) in &pulled.own {
        if let Ok(i) = index.get(e)
            && (i.0 as usize) < s.x.len()
        {
            s.set_external(i.0 as usize, own);
        }
    }
    pulled.own.clear();
    if let Some(c) = attraction.active_at {
        let (radius, k) = (attraction.radius, attraction.strength / attraction.radius);
        for i in 0..s.x.len() {
            let x = s.x[i];
            if x.distance(c) < radius {
                let own = s.external_force(i);
                pulled.own.push((solver.entities[i], own));
                let m = s.mass[i];
                s.set_external(i, own + (c - x) * (m * k));
            }
        }
    }
    s.refresh_external();
}
