//! The step's kernels: plain loops over the packed arrays.
//!
//! Each function is one pass of the step, or a piece of one; [`crate::solver::step`] calls them in
//! order. Where the CPU has AVX they hand the spring pass and the particle sweep to
//! [`super::wide`]'s forms, which give the same bits.

use super::spring::{energy_total, one_spring_energy, scatter_pairs};
use super::sweep::{Contact, Motion, Sweep, SweepArrays, finite_probe, sweep_portable};
use crate::solver::packed::PackedSpring;
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

/// Σ ½k(|x_a − x_b| − L)² over `springs`: eight running sums, spring i of each eight into sum
/// i, so that no addition waits on the one before; four springs at a time where the CPU has
/// AVX ([`super::wide::spring_energy`], the same operations in the same order, so the same
/// bits).
pub fn spring_energy(x: &[DVec2], springs: &[PackedSpring]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if super::wide::available() {
        // SAFETY: the CPU has AVX, checked just above.
        return unsafe { super::wide::spring_energy(x, springs) };
    }
    spring_energy_portable(x, springs)
}

/// [`spring_energy`] one spring at a time.
pub(crate) fn spring_energy_portable(x: &[DVec2], springs: &[PackedSpring]) -> f64 {
    let mut sums = [0.0; 8];
    let mut octs = springs.chunks_exact(8);
    for oct in &mut octs {
        for (sum, s) in sums.iter_mut().zip(oct) {
            *sum += one_spring_energy(s, x);
        }
    }
    energy_total(sums, octs.remainder(), x)
}

/// (Σ ½m|v|², −Σ m g·x) over the particles of `x` (and as many of `v` and `mass`). One running
/// sum each: four, as the springs have, measured no faster on the 256² cloth (2026-12-05).
pub fn particle_energy(x: &[DVec2], v: &[DVec2], mass: &[f64], gravity: DVec2) -> (f64, f64) {
    let (mut kinetic, mut potential) = (0.0, 0.0);
    for ((x, v), m) in x.iter().zip(v).zip(mass) {
        kinetic += 0.5 * m * v.length_squared();
        potential -= m * gravity.dot(*x);
    }
    (kinetic, potential)
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
