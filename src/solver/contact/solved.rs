//! Rigid bodies among a solve's unknowns: each dynamic body that the particles touch moves
//! inside the solve, one 3×3 block (its centre of mass and its turn) beside the particles' own,
//! and its engine is given the impulse that takes it where the solve left it.
//!
//! Why: coupled explicitly, a body stands where its engine put it for the whole step, a wall
//! moving at its velocity, and the particles answer it with whatever holds them there. At a
//! frame's step that answer is not the body's weight but the pushed vertex's springs stretched
//! against neighbours that have not followed: under VBD a 0.5 kg crate landing at 1.6 m/s on a
//! net of 10 g particles took 3.7 N·s in one step and left at 5.7 m/s upward, and the crates
//! left their net at 1/60 s (docs/performance-log.md, "crates at a frame's step").
//!
//! How (block descent, as VBD treats a vertex, and as Giles et al. 2025, "Augmented Vertex
//! Block Descent", treat a rigid body): the body's objective over the step is its inertia,
//! M/(2h²)|c − c̃|² + I/(2h²)(θ − θ̃)² with c̃, θ̃ where its engine would take it alone, plus
//! its contacts. Were the body to stand at c, θ, each particle's block would end at its
//! unconstrained step pushed out of the body, at the cost ½ nᵀHn d² (d the depth of that step
//! in the body, H the block's Hessian, n the normal), and friction's share as the block takes
//! it. After each sweep the body takes up to [`NEWTON_STEPS`] Newton steps on that objective
//! with the particles held, each halved until it lowers it; the next sweep keeps the particles
//! out of the body where it now stands. At convergence the body's momentum change,
//! M (c − c̃)/h, is minus the contacts' impulse; the engine is given that change, so that it
//! ends the step where the particles were kept out of it.

use super::inside::InSolve;
use super::obstacle::{Lead, Placed};
use super::reaction::Inertia;
use glam::{DMat3, DVec2, DVec3};

/// The Newton steps of a body's step: its contacts are piecewise quadratic in its pose, so a
/// step whose contacts did not change ends it.
const NEWTON_STEPS: usize = 4;

/// The most halvings of a Newton step that does not lower the objective.
const HALVINGS: usize = 10;

/// No body: an obstacle that is a wall, or a body the solve does not move.
const NONE: u32 = u32::MAX;

/// The bodies a step's solve moves, and its obstacles as the solve now sees them.
#[derive(Debug, Default, Clone)]
pub(crate) struct SolvedBodies {
    bodies: Vec<Body>,
    /// Each obstacle's body (an index of `bodies`), or [`NONE`].
    of: Vec<u32>,
    /// The obstacles where the step began.
    start: Vec<Placed>,
    /// The obstacles where the solve has them now, each read over the step from its start.
    placed: Vec<Placed>,
    lead: Vec<Lead>,
    dt: f64,
    /// The particles that can touch a body in this step, found at its first body step
    /// ([`Self::step`]); `None` until then.
    near: Option<Vec<u32>>,
}

/// One body among the unknowns.
#[derive(Debug, Clone, Copy)]
struct Body {
    /// One of its obstacles, to give the impulse through.
    obstacle: usize,
    inertia: Inertia,
    /// M/h² and I/h² (0: a body that does not move that way).
    mass: f64,
    turning: f64,
    /// Where its engine takes it alone, from where it began: h v of its centre, h ω.
    target: DVec3,
    /// The iterate: its centre's move and its turn since the step began.
    q: DVec3,
}

impl SolvedBodies {
    /// The bodies behind `contact`'s obstacles for a step of `dt`, each starting where the
    /// step began (started where its engine alone would take it, a step of gravity into a net,
    /// the first sweep pushed the net down by that step, and a box rested 11 cm too low at
    /// 1/30 s). Returns whether there are any.
    pub(crate) fn ready(&mut self, contact: &InSolve, dt: f64) -> bool {
        self.clear();
        self.start.clear();
        self.near = None;
        self.dt = dt;
        let Some(reactions) = contact.reactions() else {
            return false;
        };
        let obstacles = contact.obstacles();
        for (k, o) in obstacles.iter().enumerate() {
            let Some(inertia) = reactions.body(k) else {
                self.of.push(NONE);
                continue;
            };
            let index = match self
                .bodies
                .iter()
                .position(|b| b.inertia.body == inertia.body)
            {
                Some(b) => b,
                None => {
                    // A velocity change at the step's start moves the body by its share
                    // kept (its engine's damping takes the rest), so that its mass over the
                    // step is M/kept.
                    let (linear, angular) = inertia.kept(dt);
                    let per = |inverse: f64, kept: f64| {
                        if inverse > 0.0 {
                            1.0 / (inverse * kept * dt * dt)
                        } else {
                            0.0
                        }
                    };
                    let v = o.velocity_at(inertia.center_of_mass);
                    let target = DVec3::new(v.x * dt, v.y * dt, o.pose.angular_velocity * dt);
                    self.bodies.push(Body {
                        obstacle: k,
                        inertia,
                        mass: per(inertia.inverse_mass, linear),
                        turning: per(inertia.inverse_inertia, angular),
                        target,
                        q: DVec3::ZERO,
                    });
                    self.bodies.len() - 1
                }
            };
            self.of.push(index as u32);
        }
        if self.bodies.is_empty() {
            return false;
        }
        self.start.extend_from_slice(obstacles);
        self.placed.clone_from(&self.start);
        self.lead.clear();
        let leads = contact.leads();
        self.lead
            .extend((0..obstacles.len()).map(|k| leads.get(k).copied().unwrap_or_default()));
        self.place();
        true
    }

    /// `contact` with the obstacles where the solve has them now.
    pub(crate) fn seen_by<'b>(&'b self, contact: &'b InSolve<'b>) -> InSolve<'b> {
        contact.with_obstacles(&self.placed, &self.lead)
    }

    /// Forgets the bodies (a step that moves none).
    pub(crate) fn clear(&mut self) {
        self.bodies.clear();
        self.of.clear();
    }

    /// Each obstacle of a body the solve moved, with the velocities that take it from where
    /// the step began to where the solve left it: its centre's, and the angular.
    pub(crate) fn motion(&self) -> impl Iterator<Item = (usize, DVec2, f64)> + '_ {
        self.of
            .iter()
            .enumerate()
            .filter(|(_, b)| **b != NONE)
            .map(|(k, _)| {
                let pose = self.placed[k].pose;
                (k, pose.velocity, pose.angular_velocity)
            })
    }

    /// Each body's step on its objective with the particles held: a few Newton steps, the
    /// contacts found again at each. Particle i's block, were the body to stand at q, would
    /// end at its unconstrained step `free[i]` pushed out of the body, at the cost
    /// ½ nᵀH_i n d² (d the depth of `free[i]` in the body, H_i the block's Hessian, `blocks[i]`
    /// as (h00, h01, h11)): that is the body's contact term, and the push's force on the body.
    /// `x0` is where the particles began (their paths are read from there in the body's frame),
    /// `w` their inverse masses (0: held, out of it), with the contact radius and friction
    /// coefficient.
    pub(crate) fn step(
        &mut self,
        free: &[DVec2],
        blocks: &[[f64; 3]],
        x0: &[DVec2],
        w: &[f64],
        (radius, friction): (f64, f64),
    ) {
        let near = match self.near.take() {
            Some(near) => near,
            None => self.near_particles(free, x0, w, radius),
        };
        let particles = Particles {
            free,
            blocks,
            x0,
            near: &near,
            radius,
            friction,
        };
        for b in 0..self.bodies.len() {
            let mut now = self.objective(b, &particles);
            for _ in 0..NEWTON_STEPS {
                let Some(d) = now.newton_step(&self.bodies[b]) else {
                    break;
                };
                // Backtracking (Armijo): a full step can leave the contacts it was taken for
                // (the body rises off the particles, and the next step, with none, would fall
                // all the way back), so each step must lower the objective.
                let start = self.bodies[b].q;
                let slope = -now.gradient.dot(d);
                let mut t = 1.0;
                let mut taken = None;
                for _ in 0..HALVINGS {
                    self.bodies[b].q = start - d * t;
                    self.place();
                    let next = self.objective(b, &particles);
                    if next.value <= now.value + 1e-4 * t * slope {
                        taken = Some(next);
                        break;
                    }
                    t *= 0.5;
                }
                match taken {
                    Some(next) => now = next,
                    None => {
                        self.bodies[b].q = start;
                        self.place();
                        break;
                    }
                }
                if (d * t).length_squared() < 1e-24 {
                    break;
                }
            }
        }
        self.near = Some(near);
    }

    /// The free particles (inverse mass `w` ≠ 0) that can touch a body in this step: within
    /// reach of one of its obstacles where the step began, the reach grown by twice the
    /// body's move to where its engine alone takes it and twice the particle's first
    /// unconstrained step. Read once a step, so that a body's steps on a large cloth visit the
    /// particles about it, not all of them.
    fn near_particles(&self, free: &[DVec2], x0: &[DVec2], w: &[f64], radius: f64) -> Vec<u32> {
        let mut near = vec![];
        for i in 0..free.len() {
            if w[i] == 0.0 {
                continue;
            }
            let travel = 2.0 * (free[i] - x0[i]).length();
            let reaches = self.start.iter().enumerate().any(|(k, o)| {
                let Some(&b) = self.of.get(k).filter(|&&b| b != NONE) else {
                    return false;
                };
                let t = self.bodies[b as usize].target;
                let bound = o.bound();
                let moves = 2.0 * (t.truncate().length() + bound * t.z.abs());
                let reach = bound + radius + moves + travel;
                (x0[i] - o.pose.center).length_squared() <= reach * reach
                    || (free[i] - o.pose.center).length_squared() <= reach * reach
            });
            if reaches {
                near.push(i as u32);
            }
        }
        near
    }

    /// Body `b`'s objective where it now stands, with its gradient and Hessian: its inertia,
    /// and each particle's contact ½ κ d², κ = nᵀHn its block's stiffness along the normal and
    /// d the depth of its unconstrained step in the body.
    fn objective(&self, b: usize, p: &Particles) -> Objective {
        let body = &self.bodies[b];
        let inertia = DVec3::new(body.mass, body.mass, body.turning);
        let off = body.q - body.target;
        let mut value = 0.5 * off.dot(inertia * off);
        let mut gradient = inertia * off;
        let mut hessian = DMat3::from_diagonal(inertia);
        let com = body.inertia.center_of_mass + body.q.truncate();
        for (k, placed) in self.placed.iter().enumerate() {
            if self.of[k] != b as u32 {
                continue;
            }
            let reach = placed.bound() + p.radius;
            for &i in p.near {
                let (i, x) = (i as usize, p.free[i as usize]);
                if (x - placed.pose.center).length_squared() > reach * reach {
                    continue;
                }
                let from = placed.carried_by(p.x0[i], self.lead[k]);
                let Some(t) = placed.touch(x, from, DVec2::ZERO, p.radius) else {
                    continue;
                };
                let n = t.normal;
                let [h00, h01, h11] = p.blocks[i];
                let along = |d: DVec2| h00 * d.x * d.x + 2.0 * h01 * d.x * d.y + h11 * d.y * d.y;
                let stiffness = along(n);
                // The push's force on the particle, and where it acts on the body.
                let force = n * (stiffness * t.depth);
                let point = x + n * (t.depth - p.radius);
                let arm = point - com;
                value += 0.5 * stiffness * t.depth * t.depth;
                gradient += DVec3::new(force.x, force.y, arm.perp_dot(force));
                let a = DVec3::new(n.x, n.y, arm.perp_dot(n));
                hessian += outer(a, a * stiffness);
                // Friction, as the particle's block takes it (`pass::hold`): its slide along
                // the surface since the step began, relative to the surface's own move, taken
                // back by up to μ times the depth. Taken back whole (sticking), it is a spring
                // of the block's stiffness along the tangent, ½ κₜ s²; past the limit the
                // particle slides and the force stays at κₜ μ d (its limit held at this depth).
                if p.friction > 0.0 {
                    let tangent = n.perp();
                    let shift = placed.velocity_at(point) * self.dt;
                    let slide = tangent.dot(x - p.x0[i] - shift);
                    let limit = p.friction * t.depth;
                    let stiffness = along(tangent);
                    let held = slide.clamp(-limit, limit);
                    value += if slide.abs() <= limit {
                        0.5 * stiffness * slide * slide
                    } else {
                        stiffness * limit * (slide.abs() - 0.5 * limit)
                    };
                    // The surface moves with the body: ∂s/∂q = −(t, arm × t).
                    let a = DVec3::new(tangent.x, tangent.y, arm.perp_dot(tangent));
                    gradient -= a * (stiffness * held);
                    if slide.abs() <= limit {
                        hessian += outer(a, a * stiffness);
                    }
                }
            }
        }
        Objective {
            value,
            gradient,
            hessian,
        }
    }

    /// Gives each body, through `contact`'s reactions, the impulse that takes it from where
    /// its engine would take it alone to where the solve left it: M (c − c̃)/(h ρ) and
    /// I (θ − θ̃)/(h ρ') about its centre of mass (ρ, ρ' the shares its engine's damping keeps,
    /// [`Inertia::kept`]).
    pub(crate) fn give(&self, contact: &InSolve) {
        let Some(reactions) = contact.reactions() else {
            return;
        };
        for b in &self.bodies {
            let change = (b.q - b.target) / self.dt;
            let impulse = if b.mass > 0.0 {
                change.truncate() * (b.mass * self.dt * self.dt)
            } else {
                DVec2::ZERO
            };
            let angular = b.turning * self.dt * self.dt * change.z;
            if impulse != DVec2::ZERO || angular != 0.0 {
                reactions.give(b.obstacle, b.inertia.center_of_mass, impulse, angular);
            }
        }
    }

    /// Puts each body's obstacles where the body now is, each read over the step from where
    /// it began (moving at the velocities that take it there in one step).
    fn place(&mut self) {
        let dt = self.dt;
        for (k, &b) in self.of.iter().enumerate() {
            if b == NONE {
                continue;
            }
            let body = &self.bodies[b as usize];
            let start = self.start[k];
            let com = body.inertia.center_of_mass;
            let turn = DVec2::from_angle(body.q.z);
            let center = com + body.q.truncate() + turn.rotate(start.pose.center - com);
            let placed = &mut self.placed[k];
            placed.pose.center = center;
            placed.pose.angle = start.pose.angle + body.q.z;
            placed.pose.velocity = (center - start.pose.center) / dt;
            placed.pose.angular_velocity = body.q.z / dt;
            self.lead[k] = placed.lead(dt);
        }
    }
}

/// What a body's step reads of the particles: each one's unconstrained block step and its
/// block's Hessian (h00, h01, h11), where it began, its inverse mass, and the contact radius.
struct Particles<'a> {
    free: &'a [DVec2],
    blocks: &'a [[f64; 3]],
    x0: &'a [DVec2],
    /// The free particles that can touch a body in this step ([`SolvedBodies::near_particles`]).
    near: &'a [u32],
    radius: f64,
    friction: f64,
}

/// A body's objective at its pose, with its gradient and Hessian in (x, y, θ).
struct Objective {
    value: f64,
    gradient: DVec3,
    hessian: DMat3,
}

impl Objective {
    /// The Newton step −H⁻¹g (to subtract), with the ways `body` does not move held out;
    /// `None` where H is singular or the step is not finite.
    fn newton_step(&self, body: &Body) -> Option<DVec3> {
        let (mut g, mut h) = (self.gradient, self.hessian);
        let fixed = [body.mass == 0.0, body.mass == 0.0, body.turning == 0.0];
        for (axis, &fixed) in fixed.iter().enumerate() {
            if fixed {
                for j in 0..3 {
                    h.col_mut(j)[axis] = 0.0;
                }
                let mut column = DVec3::ZERO;
                column[axis] = 1.0;
                *h.col_mut(axis) = column;
                g[axis] = 0.0;
            }
        }
        let det = h.determinant();
        if !det.is_finite() || det <= 0.0 {
            return None;
        }
        let d = h.inverse() * g;
        d.is_finite().then_some(d)
    }
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}
