//! The packed state: the hot data of every particle and spring in dense arrays (structure of
//! arrays, dense `u32` indices), which the step's kernels run on.
//!
//! It holds the simulation's numbers only. Who owns a particle (an ECS entity, a row of a
//! file) is the adapter's business: the Bevy layer keeps the entities beside it
//! ([`crate::sim::Solver`]) and rebuilds or patches it when they change.

use super::forces::kernels;
use super::forces::material::Materials;
pub use super::packed::PackedSpring;
use super::threads::Threads;
use glam::DVec2;

/// The particles' and springs' packed arrays. Read it through the accessors; the adapter
/// that owns it writes it, and the step's passes ([`super::step`]) step it.
#[derive(Debug, Default)]
pub struct State {
    pub(crate) x: Vec<DVec2>,
    pub(crate) v: Vec<DVec2>,
    /// Force at the start of the current step.
    pub(crate) f: Vec<DVec2>,
    pub(crate) mass: Vec<f64>,
    /// 1/m, and 0 for a pinned particle: the velocity update then leaves it at rest, with no
    /// branch in the loop.
    pub(crate) inv_mass: Vec<f64>,
    /// Each particle's external force, added to gravity wherever forces are evaluated; stored
    /// only while one is set (`external_active`), else empty.
    pub(crate) external: Vec<DVec2>,
    /// Some external force is non-zero. When false, the force passes skip `external` entirely.
    pub(crate) external_active: bool,
    /// How many particles are held kinematic (moved by the user, not by forces).
    pub(crate) kinematic: usize,
    /// The velocity the position update moves each particle with, for the integrators whose
    /// drift is not the end velocity; empty until one of them runs ([`State::drift_buffer`]).
    pub(crate) drift: Vec<DVec2>,
    pub(crate) springs: Vec<PackedSpring>,
    /// Each spring's own stiffness while a stiffness override replaces it in `springs`, so that
    /// clearing the override restores it; empty while none is applied.
    pub(crate) own_stiffness: Vec<f64>,
    /// The stiffness override the packed `k` values reflect.
    pub(crate) applied_override: Option<f64>,
    /// Set by the position update when the step produced a non-finite position or velocity.
    pub(crate) non_finite: bool,
    /// Bumped whenever the spring graph, a stiffness, a dashpot, a mass or a pin changes: the
    /// methods that precompute from these (projective dynamics' factor, XPBD's colouring)
    /// redo it.
    pub(crate) revision: u64,
    /// Bumped whenever a free particle's position or velocity is set from outside the step
    /// (a drag, an undo, a restored state): the multistep method (BDF2) restarts its history.
    pub(crate) edits: u64,
    /// Dashpots, gas bodies, muscles and plastic springs ([`Materials`]); empty lists when the
    /// scene has none.
    pub(crate) materials: Materials,
}

/// Read access: the adapter writes the state and the passes step it.
impl State {
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
    /// Each particle's external force, N; empty while none is set (see
    /// [`Self::external_force`] for one particle's).
    pub fn external(&self) -> &[DVec2] {
        &self.external
    }
    /// Particle i's external force, N (zero while none is set).
    pub fn external_force(&self, i: usize) -> DVec2 {
        self.external.get(i).copied().unwrap_or(DVec2::ZERO)
    }
    /// Whether some external force is non-zero.
    pub fn external_active(&self) -> bool {
        self.external_active
    }
    /// How many particles are held kinematic.
    pub fn kinematic(&self) -> usize {
        self.kinematic
    }
    /// The packed springs (ends as dense particle indices; `k` the stiffness in effect).
    pub fn springs(&self) -> &[PackedSpring] {
        &self.springs
    }
    /// The materials beyond the Hooke spring.
    pub fn materials(&self) -> &Materials {
        &self.materials
    }
    /// Marks the spring graph, a stiffness, a mass or a pin as changed.
    pub(crate) fn touch(&mut self) {
        self.revision = self.revision.wrapping_add(1);
    }
    /// Marks a free particle's position or velocity as set from outside the step.
    pub(crate) fn edited(&mut self) {
        self.edits = self.edits.wrapping_add(1);
    }
}

impl State {
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

    /// Each particle's springs, by a counting sort of the packed springs: where each particle's
    /// list starts (n + 1 values), and each entry's other end and spring, in spring order (a
    /// spring's entry at its end a before its entry at b). VBD's blocks, the particle pairs'
    /// exclusions and the card's gather all read this one listing.
    pub(crate) fn spring_adjacency(&self) -> (Vec<u32>, Vec<(u32, u32)>) {
        let n = self.x.len();
        let mut starts = vec![0u32; n + 1];
        for s in &self.springs {
            starts[s.a as usize + 1] += 1;
            starts[s.b as usize + 1] += 1;
        }
        for i in 0..n {
            starts[i + 1] += starts[i];
        }
        let mut fill = starts.clone();
        let mut entries = vec![(0, 0); starts[n] as usize];
        for (k, s) in self.springs.iter().enumerate() {
            for (from, to) in [(s.a, s.b), (s.b, s.a)] {
                entries[fill[from as usize] as usize] = (to, k as u32);
                fill[from as usize] += 1;
            }
        }
        (starts, entries)
    }

    /// Total mechanical energy: Σ ½m|v|² − Σ m g·x + Σ ½k(|xa−xb|−L)², and −nRT ln A for each
    /// gas body, on this thread ([`State::energy_on`] shares it among a pool's).
    pub fn energy(&self, gravity: DVec2) -> Energy {
        self.energy_on(gravity, &Threads::serial())
    }

    /// [`State::energy`] on `threads`, with the same bits on any number of them: the sums run
    /// in fixed blocks ([`ENERGY_BLOCK`]), added in order. `hooke run` takes it after every
    /// step for `energy_max`: on one thread, one spring at a time, it cost more than the step it
    /// watched (the 256² cloth, two threads of an Intel Xeon, 2026-12-05: 0.68 ms against
    /// 0.64 ms, the other thread idle); on both, four springs at a time, 0.28 ms.
    pub fn energy_on(&self, gravity: DVec2, threads: &Threads) -> Energy {
        let springs = self.springs.len();
        let particles = threads.blocks(springs, &self.x, ENERGY_BLOCK, |first, x| {
            let (v, m) = (&self.v[first..], &self.mass[first..]);
            kernels::particle_energy(x, v, m, gravity)
        });
        let (kinetic, potential_gravity) = particles
            .into_iter()
            .fold((0.0, 0.0), |(k, g), (bk, bg)| (k + bk, g + bg));
        // Folded from +0.0: a float `sum` starts at −0.0, which a scene without springs kept.
        let potential_springs = threads
            .blocks(springs, &self.springs, ENERGY_BLOCK, |_, s| {
                kernels::spring_energy(&self.x, s)
            })
            .into_iter()
            .fold(0.0, |sum, block| sum + block);
        Energy {
            kinetic,
            potential_gravity,
            potential_springs,
            potential_gas: self.materials.gas_energy(&self.x),
        }
    }

    /// True when every position and velocity is finite.
    pub fn state_is_finite(&self) -> bool {
        self.x.iter().chain(&self.v).all(|p| p.is_finite())
    }
}

/// Particles, or springs, a block of the energy's sums ([`State::energy_on`]).
pub const ENERGY_BLOCK: usize = 8192;

/// Mechanical energy in joules, by kind.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energy {
    /// Σ ½ m |v|², J.
    pub kinetic: f64,
    /// −Σ m g·x, J.
    pub potential_gravity: f64,
    /// Σ ½ k (|x_a − x_b| − L)², J.
    pub potential_springs: f64,
    /// −Σ nRT ln A over the gas bodies, J (0 without them).
    pub potential_gas: f64,
}

impl Energy {
    /// The sum of them all.
    pub fn total(&self) -> f64 {
        self.kinetic + self.potential_gravity + self.potential_springs + self.potential_gas
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::{positions, tangle};

    /// A state with no springs and no gas: their energy is +0.0, not the −0.0 a float `sum`
    /// of nothing gives (the panel showed an empty scene's springs at −0.000000 J).
    #[test]
    fn a_state_without_springs_or_gas_has_zero_energy_in_them_not_minus_zero() {
        let e = State::default().energy(DVec2::new(0.0, -9.8));
        for part in [
            e.kinetic,
            e.potential_gravity,
            e.potential_springs,
            e.potential_gas,
        ] {
            assert!(part == 0.0 && part.is_sign_positive(), "{e:?}");
        }
    }

    /// A scrambled network of 100,000 springs on 20,000 particles (twelve blocks of springs,
    /// three of particles, past the threads' threshold): the energy has the same bits on one,
    /// two and three threads, inside a held run and outside it, and is the plain sum over every
    /// particle and spring to round-off.
    #[test]
    fn energy_has_the_same_bits_on_any_thread_count() {
        let n = 20_000u32;
        let x = positions(n);
        let state = State {
            v: x.iter().map(|p| DVec2::new(p.y.sin(), -p.x)).collect(),
            mass: (0..n).map(|i| 0.01 * (1.0 + (i % 13) as f64)).collect(),
            springs: tangle(n, 100_000),
            x,
            ..State::default()
        };
        let g = DVec2::new(0.0, -9.8);
        let serial = state.energy(g);
        for t in [1, 2, 3] {
            let threads = Threads::new(t).unwrap();
            let outside = state.energy_on(g, &threads);
            let held = threads.run(state.spring_count(), || state.energy_on(g, &threads));
            for e in [outside, held] {
                assert_eq!(e.kinetic.to_bits(), serial.kinetic.to_bits(), "{t} threads");
                let pg = (e.potential_gravity, serial.potential_gravity);
                assert_eq!(pg.0.to_bits(), pg.1.to_bits(), "{t} threads");
                let ps = (e.potential_springs, serial.potential_springs);
                assert_eq!(ps.0.to_bits(), ps.1.to_bits(), "{t} threads");
            }
        }
        let plain_springs: f64 = state
            .springs
            .iter()
            .map(|s| {
                let stretch = (state.x[s.a as usize] - state.x[s.b as usize]).length() - s.rest;
                0.5 * s.k * stretch * stretch
            })
            .sum();
        let plain_kinetic: f64 = (state.v.iter().zip(&state.mass))
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum();
        let plain_gravity: f64 = (state.x.iter().zip(&state.mass))
            .map(|(x, m)| -m * g.dot(*x))
            .sum();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert!(close(serial.potential_springs, plain_springs));
        assert!(close(serial.kinetic, plain_kinetic));
        assert!(close(serial.potential_gravity, plain_gravity));
    }
}
