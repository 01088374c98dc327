//! What the particle sweep does to one particle, and the portable loop that does it: the
//! passes after the forces (kick, damping, ground contact, position update) as
//! [`super::kernels::particle_sweep`] assembles them. The AVX form
//! ([`super::wide::particle_sweep`]) reads the same types and runs this loop on a last odd
//! particle; kept here, below both, the dispatch in `kernels` and the AVX form in `wide` do
//! not import each other.

use glam::DVec2;

/// Which position the ground test reads.
///
/// The assignment's rule tests the start-of-step position: a particle may end a step below the
/// ground by dt·|v_y| and is put back at the start of the next. At its dt of 1e-4 s that is a
/// micrometre. The methods made for large steps (implicit Euler, projective dynamics, VBD) would
/// end every step of a resting cloth 1–2 cm under the ground at 1/30 s, bunching its bottom
/// rows there; they test where the step ends instead, x + dt v with the velocity that
/// moves the particle, so that a particle ends each step on or above the ground. (XPBD
/// resolves contact inside its substeps, and BDF2 clamps its end positions inside its step.)
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
    /// [`crate::solver::step::ground`], and the particle sweep both do). Tested at the step's
    /// end, one that ends on the ground heading into it loses that velocity too: the solves
    /// that hold their iterate out of the ground leave a particle on it with a downward
    /// velocity of round-off (−1e-15 m/s, from a start one rounding above it).
    #[inline(always)]
    pub fn apply(self, x: &mut DVec2, v: &mut DVec2, w: f64, ground: f64) {
        if w == 0.0 {
            return;
        }
        let height = self.height(*x, *v);
        let into = matches!(self, Contact::End { .. }) && height == ground && v.y < 0.0;
        if height < ground || into {
            x.y = ground;
            v.y = 0.0;
        }
    }
}

/// How the particle sweep moves a particle (see [`crate::solver::step::sweep`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// Explicit Euler: the kick v += dt f/m, and the position update with the velocity from
    /// before it.
    ExplicitEuler,
    /// Symplectic Euler: the kick, and the position update with the velocity after it (and
    /// after damping and ground).
    SymplecticEuler,
    /// No kick (the integrator solved for v already); the position update with the end
    /// velocity (implicit Euler, projective dynamics, VBD).
    EndVelocity,
    /// No kick; the position update with the integrator's drift velocities (velocity Verlet,
    /// RK4, XPBD, BDF2).
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

/// [`super::kernels::particle_sweep`] for one combination of passes (`MOTION` as there), one
/// particle at a time: the loop the AVX form ([`super::wide::particle_sweep`]) gives the bits
/// of, and which it runs on an odd last particle.
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
pub(super) fn finite_probe(x: DVec2, v: DVec2) -> DVec2 {
    x * 0.0 + v * 0.0
}
