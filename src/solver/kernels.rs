//! The step's kernels: plain loops over the packed arrays.
//!
//! Each function is one pass of the step, or a piece of one; [`super::step`] calls them in
//! order.

use super::spring::scatter_pairs;
use super::state::PackedSpring;
use glam::DVec2;

pub use super::spring::spring_force;

/// f = m g: starts the force accumulation.
pub fn apply_gravity(f: &mut [DVec2], mass: &[f64], gravity: DVec2) {
    for (f, &m) in f.iter_mut().zip(mass) {
        *f = gravity * m;
    }
}

/// f = m g + f_ext: starts the force accumulation when some external force is set.
pub fn apply_gravity_and_external(f: &mut [DVec2], mass: &[f64], external: &[DVec2], g: DVec2) {
    for ((f, &m), &e) in f.iter_mut().zip(mass).zip(external) {
        *f = g * m + e;
    }
}

/// Calls `add(i, force)` with every spring's forces on its ends: four springs at a time where
/// the CPU has AVX (see [`super::wide`]; the same IEEE operations, so the same bits), else one
/// by one.
#[inline(always)]
pub fn for_each_spring_force(x: &[DVec2], springs: &[PackedSpring], add: impl FnMut(usize, DVec2)) {
    #[cfg(target_arch = "x86_64")]
    if super::wide::available() {
        // SAFETY: the CPU has AVX, checked just above.
        unsafe { super::wide::for_each_spring_force(x, springs, add) };
        return;
    }
    scatter_pairs(springs, |s| spring_force(s, x), add);
}

/// v += dt f / m. Pinned particles have inverse mass 0 and stay at rest.
pub fn kick(v: &mut [DVec2], f: &[DVec2], inv_mass: &[f64], dt: f64) {
    for ((v, f), &w) in v.iter_mut().zip(f).zip(inv_mass) {
        *v += *f * dt * w;
    }
}

/// The damping factor of one step, exp(−μ dt): what [`damp`] and the fused sweep multiply by.
pub fn decay(damping: f64, dt: f64) -> f64 {
    (-damping * dt).exp()
}

/// v *= exp(-μ dt).
pub fn damp(v: &mut [DVec2], damping: f64, dt: f64) {
    let decay = decay(damping, dt);
    for v in v {
        *v *= decay;
    }
}

/// Ground contact: a free particle below the ground is put on it and its vertical velocity is
/// zeroed. Which position is tested is the method's ([`Contact`]): where the particle is at
/// the start of the step, or where the position update will put it.
pub fn ground_contact(
    x: &mut [DVec2],
    v: &mut [DVec2],
    inv_mass: &[f64],
    ground: f64,
    contact: Contact,
) {
    for ((x, v), &w) in x.iter_mut().zip(v).zip(inv_mass) {
        contact.apply(x, v, w, ground);
    }
}

/// Which position the ground test reads.
///
/// The assignment's rule tests the start-of-step position: a particle may end a step below the
/// ground by dt·|v_y| and is put back at the start of the next. At its dt of 1e-4 s that is a
/// micrometre. The methods made for large steps (implicit Euler, projective dynamics) would
/// end every step of a resting cloth 1–2 cm under the ground at 1/30 s, bunching its bottom
/// rows there; they test where the step ends instead, x + dt v with the velocity that
/// moves the particle, so that a particle ends each step on or above the ground. (XPBD
/// resolves contact inside its substeps.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Contact {
    /// The start-of-step position x.
    Start,
    /// The end-of-step position x + dt v, for a method whose position update moves with v.
    End {
        /// The step, s.
        dt: f64,
    },
}

impl Contact {
    /// The height tested: x_y, or x_y + dt v_y computed as the position update computes it
    /// (so a particle put on the ground ends the step exactly there, and one not put there
    /// ends at or above it).
    #[inline(always)]
    pub fn height(self, x: DVec2, v: DVec2) -> f64 {
        match self {
            Contact::Start => x.y,
            Contact::End { dt } => (x + v * dt).y,
        }
    }

    /// The contact rule on one particle: a free one whose tested height is below the ground is
    /// put on it and its vertical velocity zeroed (what the ground pass,
    /// [`super::step::ground`], and the particle sweep both do).
    #[inline(always)]
    pub fn apply(self, x: &mut DVec2, v: &mut DVec2, w: f64, ground: f64) {
        if w != 0.0 && self.height(*x, *v) < ground {
            x.y = ground;
            v.y = 0.0;
        }
    }
}

/// x += dt u for the given drift velocities. Returns whether every resulting position and
/// every velocity is finite (folded into the same pass, so blow-up detection is almost free).
pub fn advance(x: &mut [DVec2], drift: &[DVec2], v: &[DVec2], dt: f64) -> bool {
    let mut probe = DVec2::ZERO;
    for ((x, u), v) in x.iter_mut().zip(drift).zip(v) {
        *x += *u * dt;
        probe += finite_probe(*x, *v);
    }
    probe == DVec2::ZERO
}

/// How the particle sweep moves a particle (see [`super::step::sweep`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// Explicit Euler: the kick v += dt f/m, and the position update with the velocity from
    /// before it.
    ExplicitEuler,
    /// Symplectic Euler: the kick, and the position update with the velocity after it (and
    /// after damping and ground).
    SymplecticEuler,
    /// No kick (the integrator solved for v already); the position update with the end
    /// velocity (implicit Euler, projective dynamics).
    EndVelocity,
    /// No kick; the position update with the integrator's drift velocities (velocity Verlet,
    /// RK4, XPBD).
    Drift,
}

impl Motion {
    /// Whether the step's velocity update is the Euler kick (run in the sweep or the kick pass).
    pub fn kicks(self) -> bool {
        matches!(self, Motion::ExplicitEuler | Motion::SymplecticEuler)
    }

    /// Which position the ground test reads: where the step ends for the methods that move
    /// with their end velocity (implicit Euler, projective dynamics: their large steps would
    /// otherwise end below the ground), the start of the step for the others ([`Contact`]).
    pub fn contact(self, dt: f64) -> Contact {
        match self {
            Motion::EndVelocity => Contact::End { dt },
            _ => Contact::Start,
        }
    }
}

/// The particle passes of a step that run after the forces, as one sweep: what the sweep does
/// is assembled from what is on, and each combination is its own loop (a const-generic
/// kernel), so a sweep without damping has no damping in it and one without a ground no
/// contact test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sweep {
    /// The kick, and which velocity moves the particle.
    pub motion: Motion,
    /// exp(−μ dt) while damping is on.
    pub decay: Option<f64>,
    /// The ground's height, when the scene has one.
    pub ground: Option<f64>,
}

/// The particle sweep's arrays, cut alike for the threads: x, v, f, 1/m and the drift.
pub type SweepArrays<'a> = (
    &'a mut [DVec2],
    &'a mut [DVec2],
    &'a [DVec2],
    &'a [f64],
    &'a [DVec2],
);

/// One sweep over the particles doing, for each, what the separate passes do in their order:
/// the Euler methods' kick ([`kick`]), damping ([`damp`]), ground contact ([`ground_contact`],
/// on the end-of-step position for [`Motion::EndVelocity`]) and the position update
/// ([`advance`]). The same operations in the same order on each
/// particle, so the result is the separate passes' bit for bit; each array is read and written
/// once instead of once per pass. `f` is read only by the kicks and `drift` only by
/// [`Motion::Drift`]; pass any array of the particles' length otherwise. Returns whether every
/// position and velocity is finite.
pub fn particle_sweep((x, v, f, inv_mass, drift): SweepArrays, dt: f64, sweep: Sweep) -> bool {
    const EXPLICIT: u8 = 0;
    const SYMPLECTIC: u8 = 1;
    const END: u8 = 2;
    const DRIFT: u8 = 3;
    let motion = match sweep.motion {
        Motion::ExplicitEuler => EXPLICIT,
        Motion::SymplecticEuler => SYMPLECTIC,
        Motion::EndVelocity => END,
        Motion::Drift => DRIFT,
    };
    let (decay, ground) = (sweep.decay.unwrap_or(1.0), sweep.ground.unwrap_or(0.0));
    let ground = (ground, sweep.motion.contact(dt));
    let a = (x, v, f, inv_mass, drift);
    // Two particles at a time where the CPU has AVX ([`super::wide::particle_sweep`], the same
    // bits), else one by one.
    macro_rules! one {
        ($m:ident, $d:literal, $g:literal) => {{
            #[cfg(target_arch = "x86_64")]
            if super::wide::available() {
                // SAFETY: the CPU has AVX, checked just above.
                return unsafe { super::wide::particle_sweep::<$m, $d, $g>(a, dt, decay, ground) };
            }
            sweep_portable::<$m, $d, $g>(a, dt, decay, ground)
        }};
    }
    macro_rules! dispatch {
        ($($m:ident),+) => {
            match (motion, sweep.decay.is_some(), sweep.ground.is_some()) {
                $(
                    ($m, false, false) => one!($m, false, false),
                    ($m, true, false) => one!($m, true, false),
                    ($m, false, true) => one!($m, false, true),
                    ($m, true, true) => one!($m, true, true),
                )+
                _ => unreachable!("motion is one of the four"),
            }
        };
    }
    dispatch!(EXPLICIT, SYMPLECTIC, END, DRIFT)
}

/// [`particle_sweep`] for one combination of passes (`MOTION` as there), one particle at a
/// time.
#[inline(always)]
pub(super) fn sweep_portable<const MOTION: u8, const DAMP: bool, const GROUND: bool>(
    (x, v, f, inv_mass, drift): SweepArrays,
    dt: f64,
    decay: f64,
    (ground, contact): (f64, Contact),
) -> bool {
    let kick = MOTION <= 1;
    let mut probe = DVec2::ZERO;
    for ((((x, v), f), &w), d) in x.iter_mut().zip(v).zip(f).zip(inv_mass).zip(drift) {
        let before = *v;
        if kick {
            *v += *f * dt * w;
        }
        if DAMP {
            *v *= decay;
        }
        if GROUND {
            contact.apply(x, v, w, ground);
        }
        let u = match MOTION {
            0 => before,
            1 | 2 => *v,
            _ => *d,
        };
        *x += u * dt;
        probe += finite_probe(*x, *v);
    }
    probe == DVec2::ZERO
}

/// 0 in each lane when both vectors are finite there, NaN otherwise (∞ · 0 and NaN · 0 are
/// NaN; the compiler keeps the products, which are not 0 for every input). Summed over the particles it stays exactly 0 while everything is finite: a
/// finiteness check with no compare or branch in the loop (a per-particle `is_finite` chain
/// held the position update at the latency of its mask moves).
#[inline(always)]
fn finite_probe(x: DVec2, v: DVec2) -> DVec2 {
    x * 0.0 + v * 0.0
}
