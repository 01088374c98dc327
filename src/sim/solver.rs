//! The packed solver state: the hot data of every particle and spring in dense arrays.
//!
//! The ECS components stay the source of truth; this is a copy laid out for the step loop
//! (structure of arrays, dense `u32` indices), rebuilt or patched by the crate's sync when
//! entities change. The crate's kernels run on these slices and know nothing of Bevy.

use bevy::math::DVec2;
use bevy::prelude::*;

/// A spring between two dense particle indices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackedSpring {
    /// Dense index of one end.
    pub a: u32,
    /// Dense index of the other end.
    pub b: u32,
    /// Rest length, m.
    pub rest: f64,
    /// The stiffness in effect: the spring's own, or the global override.
    pub k: f64,
}

/// The packed copy of the simulation the step loop runs on (see the module docs). Read it;
/// change the simulation through the components and resources.
///
/// ```
/// # use bevy::math::DVec2;
/// # use hooke::sim::Solver;
/// let loaded = hooke::scene::presets::resolve("rope").unwrap();
/// let app = hooke::running_app(&loaded).unwrap();
/// let solver = app.world().resource::<Solver>();
/// let lowest = solver.x().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
/// let energy = solver.energy(DVec2::new(0.0, -9.8)).total();
/// assert_eq!(solver.particle_count(), 16);
/// # let _ = (lowest, energy);
/// ```
#[derive(Resource, Debug, Default)]
pub struct Solver {
    /// Particle entity of each dense index, in creation order.
    pub(crate) entities: Vec<Entity>,
    pub(crate) x: Vec<DVec2>,
    pub(crate) v: Vec<DVec2>,
    /// Force at the start of the current step.
    pub(crate) f: Vec<DVec2>,
    pub(crate) mass: Vec<f64>,
    /// 1/m, and 0 for a pinned particle: the velocity update then leaves it at rest, with no
    /// branch in the loop.
    pub(crate) inv_mass: Vec<f64>,
    /// Each particle's [`crate::sim::ExternalForce`], added to gravity wherever forces are
    /// evaluated; stored only while one is set (`external_active`), else empty.
    pub(crate) external: Vec<DVec2>,
    /// Some external force is non-zero. When false, the force passes skip `external` entirely.
    pub(crate) external_active: bool,
    /// How many particles are [`crate::sim::Kinematic`] (held by the user).
    pub(crate) kinematic: usize,
    /// The velocity the position update moves each particle with (explicit Euler: the velocity
    /// at the start of the step), for the integrators whose drift is not the end velocity;
    /// empty until one of them runs ([`Solver::drift_buffer`]).
    pub(crate) drift: Vec<DVec2>,
    /// Spring entity of each packed spring, in creation order.
    pub(crate) spring_entities: Vec<Entity>,
    pub(crate) springs: Vec<PackedSpring>,
    /// Each spring's own stiffness while a stiffness override replaces it in `springs`, so that
    /// clearing the override restores it; empty while none is applied.
    pub(crate) own_stiffness: Vec<f64>,
    /// The stiffness override the packed `k` values reflect.
    pub(crate) applied_override: Option<f64>,
    /// Set by the position update when the step produced a non-finite position or velocity.
    pub(crate) non_finite: bool,
    /// Work buffers of the multi-stage integrators and the implicit solve's counters.
    pub(crate) scratch: super::integrators::Scratch,
    /// Per-thread buffers of the parallel spring pass.
    pub(crate) spring_buffers: super::parallel::SpringBuffers,
    /// Bumped whenever the spring graph, a stiffness, a mass or a pin changes: the methods
    /// that precompute from these (projective dynamics' factor, XPBD's colouring) redo it.
    pub(crate) revision: u64,
    /// Projective dynamics' factored matrix and counters.
    pub(crate) projective: super::projective::Projective,
    /// XPBD's constraint colouring and counters.
    pub(crate) xpbd: super::xpbd::Xpbd,
}

/// Read access for users: the packed state is the solver's own (the sync writes it, the
/// passes step it), so it is read through these and changed through the components.
impl Solver {
    /// Particle entity of each dense index, in creation order.
    pub fn entities(&self) -> &[Entity] {
        &self.entities
    }
    /// Positions, m.
    pub fn x(&self) -> &[DVec2] {
        &self.x
    }
    /// Velocities, m/s.
    pub fn v(&self) -> &[DVec2] {
        &self.v
    }
    /// The force on each particle at the start of the last step, N.
    pub fn f(&self) -> &[DVec2] {
        &self.f
    }
    /// Masses, kg.
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }
    /// 1/m, and 0 for a pinned or kinematic particle.
    pub fn inv_mass(&self) -> &[f64] {
        &self.inv_mass
    }
    /// Each particle's external force, N (see [`crate::sim::ExternalForce`]); empty while
    /// none is set.
    pub fn external(&self) -> &[DVec2] {
        &self.external
    }
    /// Whether some external force is non-zero.
    pub fn external_active(&self) -> bool {
        self.external_active
    }
    /// How many particles are [`crate::sim::Kinematic`].
    pub fn kinematic(&self) -> usize {
        self.kinematic
    }
    /// The packed springs (ends as dense particle indices; `k` the stiffness in effect).
    pub fn springs(&self) -> &[PackedSpring] {
        &self.springs
    }
    /// Spring entity of each packed spring.
    pub fn spring_entities(&self) -> &[Entity] {
        &self.spring_entities
    }
    /// Mean conjugate-gradient iterations per implicit Euler step so far, if any were taken.
    pub fn cg_iterations_per_step(&self) -> Option<f64> {
        self.scratch.cg_iterations_per_step()
    }
    /// What the iterative methods did so far: iterations per step, factorisations and their
    /// time, colours.
    pub fn solve_stats(&self) -> SolveStats {
        let pd = &self.projective;
        SolveStats {
            newton_iterations_per_step: self.scratch.newton_iterations_per_step(),
            cg_iterations_per_step: self.scratch.cg_iterations_per_step(),
            projective_iterations_per_step: pd.iterations_per_step(),
            factorizations: pd.factorizations,
            factorization_seconds: pd.factor_seconds,
            factor_nonzeros: pd.factor_nonzeros(),
            xpbd_sweeps_per_step: self.xpbd.sweeps_per_step(),
            xpbd_colours: self.xpbd.colours(),
        }
    }

    /// Marks the spring graph, a stiffness, a mass or a pin as changed.
    pub(crate) fn touch(&mut self) {
        self.revision = self.revision.wrapping_add(1);
    }
}

/// The iterative methods' work so far (see [`Solver::solve_stats`]); a figure is `None` (or 0)
/// when its method has not run.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SolveStats {
    /// Implicit Euler: Newton steps per time step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub newton_iterations_per_step: Option<f64>,
    /// Implicit Euler: conjugate-gradient iterations per time step, all Newton steps together.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cg_iterations_per_step: Option<f64>,
    /// Projective dynamics: local/global iterations per time step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projective_iterations_per_step: Option<f64>,
    /// Projective dynamics: factorisations of M + h²L.
    pub factorizations: u64,
    /// Projective dynamics: their wall time, s.
    pub factorization_seconds: f64,
    /// Projective dynamics: nonzeros of the last Cholesky factor.
    pub factor_nonzeros: usize,
    /// XPBD: constraint sweeps per time step (substeps × sweeps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub xpbd_sweeps_per_step: Option<f64>,
    /// XPBD: colours of the constraint graph (sweeps run colour by colour).
    pub xpbd_colours: usize,
}

impl Solver {
    /// Particles in the packed state.
    pub fn particle_count(&self) -> usize {
        self.x.len()
    }

    /// Springs in the packed state.
    pub fn spring_count(&self) -> usize {
        self.springs.len()
    }

    /// Whether forces leave particle `i` in place (pinned or kinematic).
    pub fn is_pinned(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }

    /// Applies (or clears) a global stiffness override to every spring.
    pub fn apply_stiffness_override(&mut self, k: Option<f64>) {
        match k {
            Some(k) => {
                if self.own_stiffness.len() != self.springs.len() {
                    self.own_stiffness = self.springs.iter().map(|s| s.k).collect();
                }
                self.springs.iter_mut().for_each(|s| s.k = k);
            }
            None => {
                let own = std::mem::take(&mut self.own_stiffness);
                for (s, own) in self.springs.iter_mut().zip(own) {
                    s.k = own;
                }
            }
        }
        self.applied_override = k;
        self.touch();
    }

    /// Sets packed spring `i`'s own stiffness: in effect now, or restored when the override
    /// is cleared.
    pub(crate) fn set_own_stiffness(&mut self, i: usize, k: f64) {
        match self.own_stiffness.get_mut(i) {
            Some(own) => *own = k,
            None => self.springs[i].k = k,
        }
    }

    /// The packed index of spring entity `e` between dense particles `a` and `b`: a binary
    /// search of the springs, which are sorted by their ends.
    pub(crate) fn find_spring(&self, a: u32, b: u32, e: Entity) -> Option<usize> {
        let start = self.springs.partition_point(|s| (s.a, s.b) < (a, b));
        (start..self.springs.len())
            .take_while(|&i| (self.springs[i].a, self.springs[i].b) == (a, b))
            .find(|&i| self.spring_entities[i] == e)
    }

    /// Sets particle `i`'s external force, storing the array when the first one is set.
    pub(crate) fn set_external(&mut self, i: usize, f: DVec2) {
        if self.external.is_empty() {
            if f == DVec2::ZERO {
                return;
            }
            self.external = vec![DVec2::ZERO; self.x.len()];
        }
        self.external[i] = f;
    }

    /// Recomputes whether some external force is set, dropping the array when none is.
    pub(crate) fn refresh_external(&mut self) {
        let active = self.external.iter().any(|f| *f != DVec2::ZERO);
        if !active && !self.external.is_empty() {
            self.external = vec![];
        }
        if self.external_active != active {
            self.external_active = active;
        }
    }

    /// The drift buffer, sized to the particles (allocated on first use).
    pub(crate) fn drift_buffer(&mut self) -> &mut Vec<DVec2> {
        if self.drift.len() != self.x.len() {
            self.drift = vec![DVec2::ZERO; self.x.len()];
        }
        &mut self.drift
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
    /// Σ ½ m |v|², J.
    pub kinetic: f64,
    /// −Σ m g·x, J.
    pub potential_gravity: f64,
    /// Σ ½ k (|x_a − x_b| − L)², J.
    pub potential_springs: f64,
}

impl Energy {
    /// The sum of the three.
    pub fn total(&self) -> f64 {
        self.kinetic + self.potential_gravity + self.potential_springs
    }
}
