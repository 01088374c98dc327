//! Obstacles as entities: a shape ([`Obstacle`]), where it is ([`ObstaclePose`]) and how it
//! moves ([`ObstacleVelocity`]). The step collides every particle with them
//! ([`crate::solver::contact`]).
//!
//! An obstacle is kinematic, as a kinematic rigid body is in avian: the step moves it by its
//! velocity and nothing pushes it, so a user system that sets the velocity (a rotating
//! paddle, a moving platform) moves it, and what rests on it feels that motion through
//! friction. Its pose is written back after every tick. The three components are plain f64
//! data, so an adapter could copy a rigid body's pose and velocity into them each tick, and
//! read the contacts back, without this crate knowing the rigid-body engine.

use super::components::CreationOrder;
use crate::solver::{Inertia, Placed, Pose, Shape};
use bevy::math::DVec2;
use bevy::prelude::*;

/// An obstacle's shape, in its own frame (centred on [`ObstaclePose::center`], unrotated).
///
/// ```
/// # use bevy::math::DVec2;
/// # use hooke::sim::{Obstacle, ObstaclePose, ObstacleVelocity};
/// # use hooke::solver::Shape;
/// let mut app = hooke::headless_app();
/// // A disc of radius 0.1 m at (0.5, 0.3), turning at one radian a second.
/// app.world_mut().spawn((
///     Obstacle(Shape::Circle { radius: 0.1 }),
///     ObstaclePose { center: DVec2::new(0.5, 0.3), angle: 0.0 },
///     ObstacleVelocity { linear: DVec2::ZERO, angular: 1.0 },
/// ));
/// ```
#[derive(Component, Debug, Clone, Copy, PartialEq)]
#[require(ObstaclePose, ObstacleVelocity, CreationOrder)]
#[component(on_add = super::components::assign_creation_order)]
pub struct Obstacle(pub Shape);

/// Where an obstacle is: its centre (m) and its rotation (rad, counter-clockwise).
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ObstaclePose {
    /// Its centre, m.
    pub center: DVec2,
    /// Its rotation, rad.
    pub angle: f64,
}

/// How an obstacle moves: the step advances its pose by these (m/s, rad/s).
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ObstacleVelocity {
    /// Its centre's velocity, m/s.
    pub linear: DVec2,
    /// Its angular velocity, rad/s.
    pub angular: f64,
}

/// The obstacles as the step reads them, gathered at the start of every tick in the order they
/// were made ([`CreationOrder`], as particles are: a scene's order survives a save),
/// and how many contacts the last step resolved.
#[derive(Resource, Debug, Default)]
pub struct Obstacles {
    pub(crate) placed: Vec<Placed>,
    pub(crate) entities: Vec<Entity>,
    /// The contacts the last step resolved: particle–surface (ground and obstacles) and
    /// particle pairs.
    pub contacts: crate::solver::Contacts,
    /// Whether the steps note what each obstacle takes back from the particles' contacts
    /// ([`crate::solver::contact::reaction`]): set by an adapter whose obstacles stand for
    /// bodies that feel them (the `avian` feature's). Off, no pass notes anything.
    pub feel: bool,
    /// The impulses noted since the adapter last took them ([`Self::take_reactions`]).
    pub(crate) reactions: crate::solver::Reactions,
}

impl Obstacles {
    /// The obstacles at their current poses.
    pub fn placed(&self) -> &[Placed] {
        &self.placed
    }

    /// The entity of each, in the same order.
    pub fn entities(&self) -> &[Entity] {
        &self.entities
    }

    /// What each obstacle took from the particles since the last call, in the order of
    /// [`Self::placed`] (empty while [`Self::feel`] is off).
    pub fn take_reactions(&mut self) -> Vec<crate::solver::Reaction> {
        self.reactions.take()
    }

    /// Adds an obstacle that no entity of this crate owns (an adapter's: a rigid body's
    /// collider) for this tick's steps, after the entities' own were gathered; returns its
    /// index. Gathered again each tick, so the adapter adds it again each tick. `body` is how
    /// the body behind it answers the particles' impulses (the default: as a wall), which
    /// counts only while [`Self::feel`] is on.
    pub fn add_for_tick(&mut self, owner: Entity, placed: Placed, body: Inertia) -> usize {
        self.entities.push(owner);
        self.placed.push(placed);
        let index = self.placed.len() - 1;
        if body != Inertia::default() {
            self.reactions.set_inertia(index, body);
        }
        index
    }

    /// Moves the moving obstacles by their velocities over `dt`: with `first`, those that a
    /// step moves at its start, so that its contact sees them where it ends (this crate's,
    /// and an adapter's kinematic bodies); without, those whose bodies feel the particles,
    /// after the step's contact, which saw them where it began (one rule for both:
    /// [`crate::solver::contact::moves_first`]). Returns whether any moved.
    pub(crate) fn advance(&mut self, dt: f64, first: bool) -> bool {
        let mut moved = false;
        for k in 0..self.placed.len() {
            if self.placed[k].moves() && self.moves_first(k) == first {
                self.placed[k].advance(dt);
                moved = true;
            }
        }
        moved
    }

    /// Gives the obstacles a solve moved among its unknowns the velocities it moved them at
    /// ([`crate::solver::Workspace::solved_motion`]): (index, linear, angular).
    pub(crate) fn move_as_solved(&mut self, motion: &[(usize, DVec2, f64)]) {
        for &(k, linear, angular) in motion {
            if let Some(o) = self.placed.get_mut(k) {
                o.pose.velocity = linear;
                o.pose.angular_velocity = angular;
            }
        }
    }

    /// Whether some obstacle that a step moves at its start moves.
    pub(crate) fn any_moves_first(&self) -> bool {
        (0..self.placed.len()).any(|k| self.moves_first(k))
    }

    /// Whether a step moves obstacle `k` at its start.
    fn moves_first(&self, k: usize) -> bool {
        let reactions = self.feel.then_some(&self.reactions);
        crate::solver::contact::moves_first(&self.placed[k], k, reactions)
    }
}

/// An obstacle's components as the step reads them.
pub(crate) fn placed(shape: &Obstacle, pose: &ObstaclePose, velocity: &ObstacleVelocity) -> Placed {
    Placed {
        shape: shape.0,
        pose: Pose {
            center: pose.center,
            angle: pose.angle,
            velocity: velocity.linear,
            angular_velocity: velocity.angular,
        },
    }
}

/// Gathers the obstacles for this tick's steps (a handful of entities: read them all).
pub(crate) fn gather_obstacles(
    mut obstacles: ResMut<Obstacles>,
    query: Query<(
        Entity,
        &CreationOrder,
        &Obstacle,
        &ObstaclePose,
        &ObstacleVelocity,
    )>,
) {
    let mut all: Vec<_> = query.iter().collect();
    all.sort_by_key(|(e, order, ..)| (**order, *e));
    if all.is_empty() && obstacles.placed.is_empty() {
        return;
    }
    let o = obstacles.bypass_change_detection();
    o.placed.clear();
    o.entities.clear();
    o.reactions.clear_inertia();
    for (e, _, shape, pose, vel) in all {
        o.entities.push(e);
        o.placed.push(placed(shape, pose, vel));
    }
}

/// Writes the poses the steps moved back to the moving obstacles.
pub(crate) fn write_back_obstacles(
    obstacles: Res<Obstacles>,
    mut poses: Query<(&mut ObstaclePose, &ObstacleVelocity)>,
) {
    for (e, placed) in obstacles.entities.iter().zip(&obstacles.placed) {
        if let Ok((mut pose, vel)) = poses.get_mut(*e)
            && (vel.linear != DVec2::ZERO || vel.angular != 0.0)
        {
            pose.center = placed.pose.center;
            pose.angle = placed.pose.angle;
        }
    }
}
