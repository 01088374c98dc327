//! XPBD (Macklin, Müller and Chentanez 2016, "XPBD: Position-Based Simulation of Compliant
//! Constrained Dynamics"), with substeps (Macklin et al. 2019, "Small Steps in Physics
//! Simulation"). Each spring is the distance constraint C = |x_a − x_b| − L with compliance
//! α = 1/k. A step of size h is n substeps of size hₛ = h/n; each substep is
//!
//! 1. a free particle that the last sweeps left below the ground is put on it, then
//!    v += hₛ f_body/m, p = x, x += hₛ v (free particles; a held one moves with its velocity);
//!    the prediction itself may go below the ground, where the sweeps start,
//! 2. λ = 0, then `sweeps` Gauss-Seidel sweeps over the constraints, colour by colour:
//!    α̃ = α/hₛ², Δλ = (−C − α̃ λ)/(w_a + w_b + α̃), λ += Δλ, x_a += w_a Δλ n, x_b −= w_b Δλ n,
//!    with n = (x_a − x_b)/|x_a − x_b| and w = 1/m (0 for pinned and held particles),
//! 3. v = (x − p)/hₛ.
//!
//! The step leaves the end velocity in v and the mean velocity (x_end − x0)/h as the drift,
//! so that the schedule's damping, ground contact and position update follow as for velocity
//! Verlet and RK4.
//!
//! Threads: the constraint graph is coloured greedily (no two springs of a colour share a
//! particle), and the pool's threads, as one team ([`crate::solver::threads::team`]), project each colour's
//! springs in shares, meeting at a barrier after every colour: at 64² a colour is a few
//! microseconds of work, too little to pay for a fork and a join. The sweep is then the
//! same Gauss-Seidel sweep whatever the thread count: the result is bit for bit that of one
//! thread. (Jacobi with averaging would need no colouring, but it converges more slowly, by a
//! factor that grows with the number of constraints on a particle.)

use crate::solver::contact::inside::{InSolve, SubstepPoses};
use crate::solver::method::Iterations;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use crate::solver::threads::team::Shared;
use glam::DVec2;

/// A constraint in colour order: the packed spring's ends and rest length, and the projection's
/// coefficients at the current substep size, so that the sweep reads no inverse masses and
/// divides once: with den = w_a + w_b + α̃, Δλ = g/den and x_a += w_a Δλ n = (w_a/den) g n, for
/// g = −C − α̃λ. All that one sweep a substep reads (32 bytes; the multipliers' data is apart).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Constraint {
    a: u32,
    b: u32,
    rest: f64,
    /// w_a/den and w_b/den.
    ca: f64,
    cb: f64,
}

/// A constraint's compliance and multiplier, read only with more than one sweep a substep.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Multiplier {
    /// α = 1/k (0 for an infinitely stiff spring).
    compliance: f64,
    /// α̃ = α/hₛ².
    alpha: f64,
    /// 1/den (0 when both ends are fixed and the spring is rigid: nothing moves).
    inv_den: f64,
    /// λ of the current substep.
    lambda: f64,
}

/// A dashpot's damped projection (Macklin et al. 2016, eq. 26): with γ = α̃ β̃/hₛ = α c/hₛ,
/// Δλ = (−C − α̃λ − γ ∇C·(x − p)) / ((1 + γ)(w_a + w_b) + α̃). The coefficients play the
/// undamped ones' parts: x_a += (w_a/den) g n with den the damped denominator.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Damped {
    gamma: f64,
    ca: f64,
    cb: f64,
    inv_den: f64,
}

/// The colouring and buffers, kept from step to step.
#[derive(Debug, Default, Clone)]
pub struct Xpbd {
    /// The state revision the colouring is for.
    revision: Option<u64>,
    /// The revision and substep size (bits) the coefficients are for.
    coefficients: Option<(u64, u64)>,
    /// Constraints grouped by colour.
    constraints: Vec<Constraint>,
    /// Start of each colour in `constraints`, and the end.
    colour_starts: Vec<usize>,
    /// Per constraint, in the same order, its compliance and multiplier.
    multipliers: Vec<Multiplier>,
    /// Per constraint, the packed spring it stands for; and per packed spring, its constraint.
    spring_of: Vec<u32>,
    slot_of: Vec<u32>,
    /// Per constraint, the damped projection's coefficients, when some spring has a dashpot
    /// (else empty).
    damped: Vec<Damped>,
    /// The gas forces of the current substep, when the scene has gas bodies (else empty).
    gas: Vec<DVec2>,
    /// Positions during the step, and at the start of the substep.
    x: Vec<DVec2>,
    prev: Vec<DVec2>,
    /// Where the moving obstacles stand at each substep (empty when none moves).
    stages: SubstepPoses,
    /// The last substep's size, for the constraint error (0 before the first step).
    last_hs: f64,
    /// Sweeps so far.
    pub sweeps: u64,
    /// Steps so far.
    pub steps: u64,
}

impl Xpbd {
    /// Colours of the constraint graph (0 before the first step).
    pub fn colours(&self) -> usize {
        self.colour_starts.len().saturating_sub(1)
    }

    /// Mean sweeps per step so far.
    pub fn sweeps_per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.sweeps as f64 / self.steps as f64)
    }

    /// The constraints at the end of the last step: the positions the sweeps left, each
    /// spring's C = |x_a − x_b| − L, its α̃ and its λ of the last substep.
    fn ends(&self) -> impl Iterator<Item = (f64, &Constraint, &Multiplier)> {
        let (x, stepped) = (&self.x, self.steps > 0 && self.last_hs > 0.0);
        let constraints = if stepped { &self.constraints[..] } else { &[] };
        constraints
            .iter()
            .zip(&self.multipliers)
            .map(move |(c, m)| {
                let l = (x[c.a as usize] - x[c.b as usize]).length();
                (l - c.rest, c, m)
            })
    }

    /// After the last step, the largest error of a compliant constraint, |C + α̃λ|/L (|C + α̃λ|
    /// for a spring of rest length 0): how far the sweeps left each spring from the force
    /// balance its stiffness asks for, relative to its length. `None` before the first step.
    pub fn constraint_error(&self) -> Option<f64> {
        let worst = self
            .ends()
            .filter(|(_, _, m)| m.inv_den != 0.0)
            .map(|(cv, c, m)| relative(cv + m.alpha * m.lambda, c.rest))
            .fold(None, |w: Option<f64>, e| Some(w.map_or(e, |w| w.max(e))));
        worst.filter(|w| w.is_finite())
    }

    /// After the last step, the force the springs carry, Σ|λ|/hₛ², over the force their
    /// stiffness asks for at the same stretch, Σ k|C|: 1 when the sweeps converged; below 1 the
    /// cloth is that much softer than k says. `None` before the first step or when nothing is
    /// stretched.
    pub fn force_carried(&self) -> Option<f64> {
        let inv_h2 = 1.0 / (self.last_hs * self.last_hs);
        let (mut carried, mut asked) = (0.0, 0.0);
        for (cv, _, m) in self.ends().filter(|(_, _, m)| m.alpha > 0.0) {
            carried += m.lambda.abs() * inv_h2;
            asked += cv.abs() / m.compliance;
        }
        (asked > 0.0 && carried.is_finite()).then(|| carried / asked)
    }

    /// Greedy colouring in packed order: each spring takes the lowest colour neither of its ends
    /// has yet. Within a colour the springs keep the packed order (by first end), which keeps
    /// the sweep's memory access local.
    fn colour(&mut self, s: &State) {
        let n = s.x.len();
        let mut used: Vec<u64> = vec![0; n]; // colours 0..64 taken at each particle
        let mut colour_of = Vec::with_capacity(s.springs.len());
        let mut colours = 0usize;
        // Colours past 64, per particle (only a particle with very many springs needs them).
        let mut overflow: std::collections::HashMap<u32, Vec<u32>> = Default::default();
        for sp in &s.springs {
            let (a, b) = (sp.a as usize, sp.b as usize);
            let taken = used[a] | used[b];
            let c = if taken != u64::MAX {
                let c = (!taken).trailing_zeros();
                used[a] |= 1 << c;
                used[b] |= 1 << c;
                c
            } else {
                // Rare: a particle with more than 64 springs' worth of colours.
                let busy = |p: u32, c: u32, o: &std::collections::HashMap<u32, Vec<u32>>| {
                    o.get(&p).is_some_and(|v| v.contains(&c))
                };
                let mut c = 64;
                while busy(sp.a, c, &overflow) || busy(sp.b, c, &overflow) {
                    c += 1;
                }
                overflow.entry(sp.a).or_default().push(c);
                overflow.entry(sp.b).or_default().push(c);
                c
            };
            colours = colours.max(c as usize + 1);
            colour_of.push(c);
        }
        let mut counts = vec![0usize; colours + 1];
        for &c in &colour_of {
            counts[c as usize + 1] += 1;
        }
        for c in 1..=colours {
            counts[c] += counts[c - 1];
        }
        self.colour_starts = counts.clone();
        let mut at = counts;
        self.constraints = vec![Constraint::default(); s.springs.len()];
        self.multipliers = vec![Multiplier::default(); s.springs.len()];
        self.spring_of = vec![0; s.springs.len()];
        self.slot_of = vec![0; s.springs.len()];
        for (i, (sp, &c)) in s.springs.iter().zip(&colour_of).enumerate() {
            let slot = &mut at[c as usize];
            self.spring_of[*slot] = i as u32;
            self.slot_of[i] = *slot as u32;
            self.constraints[*slot] = Constraint {
                a: sp.a,
                b: sp.b,
                rest: sp.rest,
                ..Default::default()
            };
            self.multipliers[*slot].compliance = 1.0 / sp.k;
            *slot += 1;
        }
        self.revision = Some(s.revision);
        self.coefficients = None;
    }

    /// The projections' coefficients for substeps of `hs` (see [`Constraint`]).
    fn prepare(&mut self, s: &State, hs: f64) {
        let key = (s.revision, hs.to_bits());
        if self.coefficients == Some(key) {
            return;
        }
        let inv_h2 = 1.0 / (hs * hs);
        let w = &s.inv_mass;
        for (c, m) in self.constraints.iter_mut().zip(&mut self.multipliers) {
            let (wa, wb) = (w[c.a as usize], w[c.b as usize]);
            m.alpha = m.compliance * inv_h2;
            let den = wa + wb + m.alpha;
            // A spring of stiffness 0 (infinite compliance) pulls on nothing; its α̃ is kept
            // finite so that α̃λ cannot become ∞·0.
            let inert = !m.alpha.is_finite() || den <= 0.0;
            if inert {
                m.alpha = 0.0;
            }
            m.inv_den = if inert { 0.0 } else { 1.0 / den };
            c.ca = wa * m.inv_den;
            c.cb = wb * m.inv_den;
        }
        self.damped.clear();
        if s.materials.has_dashpots() {
            let dashpot = s.materials.dashpot();
            for ((c, m), &spring) in self
                .constraints
                .iter()
                .zip(&self.multipliers)
                .zip(&self.spring_of)
            {
                let (wa, wb) = (w[c.a as usize], w[c.b as usize]);
                let gamma = m.compliance * dashpot[spring as usize] / hs;
                let d = if m.inv_den == 0.0 || !gamma.is_finite() {
                    Damped {
                        gamma: 0.0,
                        ca: c.ca,
                        cb: c.cb,
                        inv_den: m.inv_den,
                    }
                } else {
                    let den = (1.0 + gamma) * (wa + wb) + m.alpha;
                    Damped {
                        gamma,
                        ca: wa / den,
                        cb: wb / den,
                        inv_den: 1.0 / den,
                    }
                };
                self.damped.push(d);
            }
        }
        self.coefficients = Some(key);
    }

    /// The rest lengths of the constraints whose springs' rest lengths move (muscles, plastic
    /// springs), from the packed springs.
    fn refresh_rest_lengths(&mut self, s: &State) {
        let m = &s.materials;
        let springs = m
            .muscles()
            .iter()
            .map(|m| m.spring)
            .chain(m.plastic().iter().map(|p| p.spring));
        for i in springs {
            let slot = self.slot_of[i as usize] as usize;
            self.constraints[slot].rest = s.springs[i as usize].rest;
        }
    }
}

/// The constraints as the graphics card's XPBD reads them ([`crate::solver::gpu`]): in the
/// CPU's colour order, so that its Gauss-Seidel sweeps are the CPU's.
#[cfg(feature = "gpu")]
pub(crate) struct Coloured {
    /// Each constraint's particles.
    pub ends: Vec<(u32, u32)>,
    /// Each constraint's rest length, c_a, c_b, α̃ and 1/den at substeps of the given size,
    /// and its damped projection's γ, c_a, c_b and 1/den (the undamped ones' where the spring
    /// has no dashpot).
    pub coefficients: Vec<[f64; 9]>,
    /// Where each colour starts, and the end.
    pub colour_starts: Vec<usize>,
}

/// The CPU's colouring and coefficients of `s`'s springs at substeps of `hs`, for the card.
#[cfg(feature = "gpu")]
pub(crate) fn coloured(s: &State, hs: f64) -> Coloured {
    let mut xp = Xpbd::default();
    xp.colour(s);
    xp.prepare(s, hs);
    let coefficients = xp
        .constraints
        .iter()
        .zip(&xp.multipliers)
        .enumerate()
        .map(|(k, (c, m))| {
            let d = xp.damped.get(k).copied().unwrap_or(Damped {
                gamma: 0.0,
                ca: c.ca,
                cb: c.cb,
                inv_den: m.inv_den,
            });
            [
                c.rest, c.ca, c.cb, m.alpha, m.inv_den, d.gamma, d.ca, d.cb, d.inv_den,
            ]
        })
        .collect();
    Coloured {
        ends: xp.constraints.iter().map(|c| (c.a, c.b)).collect(),
        coefficients,
        colour_starts: xp.colour_starts,
    }
}

/// Positions written by the team's members in one colour.
///
/// Within a colour no two constraints share a particle, so the members' shares of a colour
/// read and write disjoint sets of positions; successive colours are separated by the team's
/// barrier. That is the whole safety argument for the shared slice.
type Positions = Shared<DVec2>;

/// Jacobi passes over the particle pairs after each substep's sweeps. One left a strip of
/// cloth folding at 1/60 s with a pair at 89.6 % of 2r; two keep it at 90 % and more.
const PAIR_PASSES: usize = 2;

/// The ground as a position constraint (as position-based methods treat contact), applied
/// after each substep's sweeps (where the next prediction starts, and the step's end): a free
/// particle below it is put on it, so the substep's velocity (x − p)/hₛ carries it no further
/// down and the step ends on or above the ground (the sweeps alone left cloth32's bottom row
/// resting 0.2–0.75 mm under it at 1/60–1/30 s). Not after the prediction as well: the sweeps
/// then started from a prediction lifted onto the ground, and restoring the springs from there
/// lifted a body that rests on it, a gas ball's bottom 0.42 mm above it at 1/60 s.
#[inline(always)]
fn on_ground(mut x: DVec2, w: f64, ground: f64) -> DVec2 {
    if x.y < ground && w != 0.0 {
        x.y = ground;
    }
    x
}

/// One constraint's projection: `g` turns −C into g = −C − α̃λ (and updates λ), and the ends
/// move by ±(c_a, c_b)·g along the spring. A spring of no length has no direction and is left
/// alone (the spring force kernel exerts no force there either).
#[inline(always)]
fn project_one(c: &Constraint, x: Positions, mut g: impl FnMut(f64) -> f64) {
    let (a, b) = (c.a as usize, c.b as usize);
    // SAFETY: a and b belong to this constraint alone within the colour.
    let (xa, xb) = unsafe { (x.get(a), x.get(b)) };
    let l = xa - xb;
    let len = l.length();
    if len == 0.0 {
        return;
    }
    let s = g(c.rest - len) / len;
    // SAFETY: as above.
    unsafe {
        x.set(a, xa + l * (c.ca * s));
        x.set(b, xb - l * (c.cb * s));
    }
}

/// One sweep a substep: λ is 0 at the projection and never read again. Four constraints at a
/// time with AVX where the CPU has it (bit for bit the same result).
fn project(constraints: &[Constraint], x: Positions) {
    #[cfg(target_arch = "x86_64")]
    if crate::solver::forces::wide::available() {
        // SAFETY: AVX is available; the positions' safety is the colour's (see `Positions`).
        unsafe { project_avx(constraints, x) };
        return;
    }
    project_scalar(constraints, x);
}

fn project_scalar(constraints: &[Constraint], x: Positions) {
    for c in constraints {
        project_one(c, x, |minus_c| minus_c);
    }
}

/// [`project_scalar`] four constraints at a time: the square roots and divisions, which bound
/// the scalar loop, go four to an instruction. Within a colour the four share no particle, so
/// gathering their ends first and scattering after is the scalar order's result. The
/// operations are the scalar ones in the same order (l = x_a − x_b, |l| = √(l_x² + l_y²),
/// s = (L − |l|)/|l|, x_a + l·(c_a s), x_b − l·(c_b s)), each correctly rounded: bit for bit.
/// The ends stay in registers from gather to scatter (staging them through arrays cost a
/// store-to-load stall per register).
///
/// # Safety
/// The CPU must support AVX, and no other thread may touch these constraints' particles.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn project_avx(constraints: &[Constraint], x: Positions) {
    // Two quads at a time, both computed before either is stored: each waits on its square
    // root and division, and written one after the other the second's did not overlap the
    // first's.
    let mut octs = constraints.chunks_exact(8);
    for o in &mut octs {
        // SAFETY: AVX is this function's; the colour's particles are this thread's (see
        // `Positions`), and within a colour the eight share no particle.
        unsafe {
            let (q0, q1) = o.split_at(4);
            let (m0, m1) = (Moved::of(q0, x), Moved::of(q1, x));
            m0.store(q0, x);
            m1.store(q1, x);
        }
    }
    let rest = octs.remainder();
    let quads = rest.chunks_exact(4);
    let tail = quads.remainder();
    for q in quads {
        // SAFETY: as above.
        unsafe { Moved::of(q, x).store(q, x) };
    }
    project_scalar(tail, x);
}

/// Four constraints' projected ends, two to a register (see [`crate::solver::forces::wide::Quad`]), and which
/// of them have no length and stay.
#[cfg(target_arch = "x86_64")]
struct Moved {
    a01: std::arch::x86_64::__m256d,
    a23: std::arch::x86_64::__m256d,
    b01: std::arch::x86_64::__m256d,
    b23: std::arch::x86_64::__m256d,
    still: i32,
}

#[cfg(target_arch = "x86_64")]
impl Moved {
    /// Written out, not with `array::map`: closures do not inherit AVX, and were not inlined.
    ///
    /// # Safety
    /// AVX, and the particles of `c` (four constraints) are the caller's alone; always
    /// inlined, it inherits AVX from its caller.
    #[inline(always)]
    unsafe fn of(c: &[Constraint], x: Positions) -> Moved {
        use crate::solver::forces::wide::{Quad, lanes, spring_order};
        use std::arch::x86_64::*;
        // SAFETY: the caller's.
        unsafe {
            let (a, b) = (c[0].a as usize, c[0].b as usize);
            let (a0, b0) = (x.get(a), x.get(b));
            let (a, b) = (c[1].a as usize, c[1].b as usize);
            let (a1, b1) = (x.get(a), x.get(b));
            let (a, b) = (c[2].a as usize, c[2].b as usize);
            let (a2, b2) = (x.get(a), x.get(b));
            let (a, b) = (c[3].a as usize, c[3].b as usize);
            let (a3, b3) = (x.get(a), x.get(b));
            let v = Quad::of([a0, a1, a2, a3], [b0, b1, b2, b3]);
            let rest = lanes([c[0].rest, c[1].rest, c[2].rest, c[3].rest]);
            let s = _mm256_div_pd(_mm256_sub_pd(rest, v.l), v.l);
            let sa = _mm256_mul_pd(lanes([c[0].ca, c[1].ca, c[2].ca, c[3].ca]), s);
            let sb = _mm256_mul_pd(lanes([c[0].cb, c[1].cb, c[2].cb, c[3].cb]), s);
            // s is in the lane order [0, 2, 1, 3]: unpacklo gives [s0, s0, s1, s1].
            Moved {
                a01: _mm256_add_pd(v.a01, _mm256_mul_pd(v.d01, _mm256_unpacklo_pd(sa, sa))),
                a23: _mm256_add_pd(v.a23, _mm256_mul_pd(v.d23, _mm256_unpackhi_pd(sa, sa))),
                b01: _mm256_sub_pd(v.b01, _mm256_mul_pd(v.d01, _mm256_unpacklo_pd(sb, sb))),
                b23: _mm256_sub_pd(v.b23, _mm256_mul_pd(v.d23, _mm256_unpackhi_pd(sb, sb))),
                still: spring_order(_mm256_movemask_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(
                    v.l,
                    _mm256_setzero_pd(),
                ))),
            }
        }
    }

    /// Writes the ends back; a spring of no length has no direction, and its ends stay.
    ///
    /// # Safety
    /// As for [`Moved::of`].
    #[inline(always)]
    unsafe fn store(&self, c: &[Constraint], x: Positions) {
        use std::arch::x86_64::*;
        // SAFETY: the caller's.
        unsafe {
            let (a01, a23, b01, b23) = (self.a01, self.a23, self.b01, self.b23);
            // Calls, not a closure: closures do not inherit AVX.
            self.put(
                c,
                0,
                x,
                _mm256_castpd256_pd128(a01),
                _mm256_castpd256_pd128(b01),
            );
            let (a1, b1) = (
                _mm256_extractf128_pd::<1>(a01),
                _mm256_extractf128_pd::<1>(b01),
            );
            self.put(c, 1, x, a1, b1);
            self.put(
                c,
                2,
                x,
                _mm256_castpd256_pd128(a23),
                _mm256_castpd256_pd128(b23),
            );
            let (a3, b3) = (
                _mm256_extractf128_pd::<1>(a23),
                _mm256_extractf128_pd::<1>(b23),
            );
            self.put(c, 3, x, a3, b3);
        }
    }

    /// Writes constraint `k`'s two ends, unless it has no length.
    ///
    /// # Safety
    /// As for [`Moved::of`].
    #[inline(always)]
    unsafe fn put(
        &self,
        c: &[Constraint],
        k: usize,
        x: Positions,
        a: std::arch::x86_64::__m128d,
        b: std::arch::x86_64::__m128d,
    ) {
        use std::arch::x86_64::_mm_storeu_pd;
        if self.still & (1 << k) == 0 {
            // SAFETY: the caller's.
            unsafe {
                _mm_storeu_pd(x.ptr(c[k].a as usize).cast(), a);
                _mm_storeu_pd(x.ptr(c[k].b as usize).cast(), b);
            }
        }
    }
}

/// |e|/L, or |e| for a spring of rest length 0.
#[inline(always)]
fn relative(e: f64, rest: f64) -> f64 {
    if rest > 0.0 { e.abs() / rest } else { e.abs() }
}

/// More than one sweep a substep (or the last substep, whose λ the constraint error reads): λ
/// accumulates over the sweeps. Returns the largest |C + α̃λ|/L met before a projection.
fn project_with_multipliers(
    constraints: &[Constraint],
    multipliers: &mut [Multiplier],
    x: Positions,
) -> f64 {
    let mut worst: f64 = 0.0;
    for (c, m) in constraints.iter().zip(multipliers) {
        project_one(c, x, |minus_c| {
            let g = minus_c - m.alpha * m.lambda;
            if m.inv_den != 0.0 {
                worst = worst.max(relative(g, c.rest));
            }
            m.lambda += g * m.inv_den;
            g
        });
    }
    worst
}

/// A sweep over constraints with dashpots (see [`Damped`]), from the substep's start `prev`;
/// λ is kept in `multipliers` when there are several sweeps a substep. Returns the largest
/// |C + α̃λ|/L met before a projection (with λ kept).
fn project_damped(
    constraints: &[Constraint],
    damped: &[Damped],
    mut multipliers: Option<&mut [Multiplier]>,
    x: Positions,
    prev: Positions,
) -> f64 {
    let mut worst: f64 = 0.0;
    for (k, (c, d)) in constraints.iter().zip(damped).enumerate() {
        let (a, b) = (c.a as usize, c.b as usize);
        // SAFETY: a and b belong to this constraint alone within the colour.
        let (xa, xb) = unsafe { (x.get(a), x.get(b)) };
        let l = xa - xb;
        let len = l.length();
        if len == 0.0 {
            continue;
        }
        let n = l / len;
        // SAFETY: the substep's start positions are only read during the sweeps.
        let (pa, pb) = unsafe { (prev.get(a), prev.get(b)) };
        let moved = n.dot((xa - pa) - (xb - pb));
        let mut g = c.rest - len - d.gamma * moved;
        if let Some(m) = multipliers.as_deref_mut().map(|m| &mut m[k]) {
            if m.inv_den != 0.0 {
                worst = worst.max(relative(c.rest - len - m.alpha * m.lambda, c.rest));
            }
            g -= m.alpha * m.lambda;
            m.lambda += g * d.inv_den;
        }
        // SAFETY: as above.
        unsafe {
            x.set(a, xa + n * (d.ca * g));
            x.set(b, xb - n * (d.cb * g));
        }
    }
    worst
}

/// The prediction of one particle (see the module docs): `end` is where the sweeps left it.
#[inline(always)]
fn predict(
    (x, prev, v): (&mut DVec2, &mut DVec2, &mut DVec2),
    f: DVec2,
    w: f64,
    (hs, inv_hs, floor, previous): (f64, f64, f64, bool),
) {
    // The sweeps may have pulled a particle on the ground below it.
    let end = on_ground(*x, w, floor);
    if previous && w != 0.0 {
        *v = (end - *prev) * inv_hs;
    }
    *v += f * (hs * w);
    *prev = end;
    *x = end + *v * hs;
}

/// One XPBD step (see the module docs): sets v to the end velocity and the drift to the mean
/// velocity over the step. `s.f` holds the body forces.
pub fn step(
    s: &mut State,
    xp: &mut Xpbd,
    dt: f64,
    it: &Iterations,
    ground: Option<f64>,
    contact: Option<&InSolve>,
    threads: &Threads,
) {
    s.drift_buffer();
    if xp.revision != Some(s.revision) || xp.constraints.len() != s.springs.len() {
        xp.colour(s);
    }
    let n = s.x.len();
    let springs = s.springs.len();
    xp.x.clear();
    xp.x.extend_from_slice(&s.x);
    xp.prev.resize(n, DVec2::ZERO);
    let substeps = it.xpbd_substeps.max(1);
    let sweeps = it.xpbd_sweeps.max(1);
    // With a tolerance, sweeps go on past `sweeps` until the constraint error is under it.
    let tolerance = it.xpbd_tolerance;
    let cap = if tolerance > 0.0 {
        it.xpbd_max_sweeps.max(sweeps)
    } else {
        sweeps
    };
    let hs = dt / substeps as f64;
    xp.last_hs = hs;
    let inv_hs = 1.0 / hs;
    let floor = ground.unwrap_or(f64::NEG_INFINITY);
    xp.prepare(s, hs);
    if s.materials.moves_rest_lengths() {
        xp.refresh_rest_lengths(s);
    }
    let has_gas = !s.materials.gas().is_empty();
    xp.gas.clear();
    if has_gas {
        xp.gas.resize(n, DVec2::ZERO);
    }
    let materials = &s.materials;
    // Contact after each substep's sweeps, so that its push enters the next substep's velocity
    // as the constraints' do: particle pairs pushed apart on one member while the others wait
    // (the pass is short: only the particles with listed neighbours), then each member's
    // particles held out of the obstacles and the ground, with friction on their slide.
    let mut scratch = vec![DVec2::ZERO; contact.map_or(0, |c| c.pair_scratch())];
    // Each substep sees the moving obstacles where it ends (`InSolve::at_substep`).
    xp.stages.ready(contact, substeps as usize);
    let stages = &xp.stages;
    let seen_at =
        |stage: u32| contact.map(|c| c.at_substep(stages, stage as usize, substeps as usize));
    let scratch_len = scratch.len();
    let scratch = Shared::new(&mut scratch);
    // The pool's threads run the substeps together as one team (a fork and a join per colour
    // cost as much as a colour's work at 64²). Between two barriers the members write
    // disjoint elements: their own particles in the prediction, their own constraints'
    // particles and multipliers in a colour (a colour's constraints share no particle).
    let (positions, prev, v) = (
        Shared::new(&mut xp.x),
        Shared::new(&mut xp.prev),
        Shared::new(&mut s.v),
    );
    let multipliers = Shared::new(&mut xp.multipliers);
    let gas = Shared::new(&mut xp.gas);
    // The substep's start positions, which the damped projection reads (written only by the
    // predictions, before their barrier).
    let starts = prev;
    let (f, w) = (&s.f[..], &s.inv_mass[..]);
    // Every particle's inverse mass (the loop below narrows `w` to a member's share).
    let w_all = w;
    let (constraints, colour_starts) = (&xp.constraints[..], &xp.colour_starts[..]);
    let damped = &xp.damped[..];
    // Each member's largest constraint error in the sweep just done, to decide together
    // whether to sweep again; and the sweeps run.
    let mut worst = vec![0.0f64; threads.threads().max(1)];
    let worst = Shared::new(&mut worst);
    let swept = std::sync::atomic::AtomicU64::new(0);
    threads.team(springs, |team| {
        let mine = team.share(0..n);
        for substep in 0..substeps {
            // The prediction, v += hₛ f/m, p = x, x += hₛ v; after the first substep fused
            // with the previous one's velocity, v = (x − p)/hₛ.
            let previous = substep > 0;
            if has_gas {
                // The gas forces at the substep's start, on one member (a body's loop is
                // short) while the others wait.
                if !team.share(0..1).is_empty() {
                    // SAFETY: the other members wait at the barrier below, touching nothing.
                    let (x, out) = unsafe { (positions.part(0..n), gas.part(0..n)) };
                    materials.gas_forces_into(x, out);
                }
                team.wait();
            }
            // SAFETY: this member's particles (see above).
            let (x, prev, v) = unsafe {
                (
                    positions.part(mine.clone()),
                    prev.part(mine.clone()),
                    v.part(mine.clone()),
                )
            };
            let (f, w) = (&f[mine.clone()], &w[mine.clone()]);
            if let Some(c) = seen_at(0).filter(|_| substep == 0) {
                // A particle that starts the step inside a surface is put out of it before the
                // first prediction, as the ground's clamp does: pushed out after it, the push
                // would become velocity (a point resting on a thin segment hopped off it).
                for (i, (x, &w)) in (mine.start..).zip(x.iter_mut().zip(w)) {
                    if w != 0.0 {
                        let from = *x;
                        c.keep_out(i, x, from);
                    }
                }
            }
            let at = (hs, inv_hs, floor, previous);
            // Zipped, so that no index is bounds-checked (the checks kept this loop scalar
            // and cost a fifth of the step).
            let particles = x.iter_mut().zip(prev.iter_mut()).zip(v.iter_mut());
            if has_gas {
                // SAFETY: this member's particles; the gas forces were written before the
                // barrier above.
                let extra = unsafe { gas.part(mine.clone()) };
                for ((((x, prev), v), (f, &w)), g) in particles.zip(f.iter().zip(w)).zip(extra) {
                    predict((x, prev, v), *f + *g, w, at);
                }
            } else {
                for (((x, prev), v), (f, &w)) in particles.zip(f.iter().zip(w)) {
                    predict((x, prev, v), *f, w, at);
                }
            }
            team.wait();
            // λ is kept with several sweeps, a tolerance, and on the last substep (the
            // constraint error reads it).
            let keep = cap > 1 || substep + 1 == substeps;
            let mut sweep = 0;
            loop {
                let mut mine_worst: f64 = 0.0;
                for colour in colour_starts.windows(2) {
                    let range = team.share(colour[0]..colour[1]);
                    let constraints = &constraints[range.clone()];
                    if !damped.is_empty() {
                        // SAFETY: this member's constraints of the colour.
                        let mut m = keep.then(|| unsafe { multipliers.part(range.clone()) });
                        if let Some(m) = m.as_deref_mut().filter(|_| sweep == 0) {
                            m.iter_mut().for_each(|m| m.lambda = 0.0);
                        }
                        let w = project_damped(constraints, &damped[range], m, positions, starts);
                        mine_worst = mine_worst.max(w);
                    } else if keep {
                        // SAFETY: this member's constraints of the colour (see above).
                        let m = unsafe { multipliers.part(range) };
                        if sweep == 0 {
                            m.iter_mut().for_each(|m| m.lambda = 0.0);
                        }
                        mine_worst =
                            mine_worst.max(project_with_multipliers(constraints, m, positions));
                    } else {
                        project(constraints, positions);
                    }
                    team.wait();
                }
                sweep += 1;
                if sweep >= cap {
                    break;
                }
                if sweep >= sweeps {
                    // Past the least count, only with a tolerance: the members' errors
                    // together decide (each reads every member's after the barrier, and
                    // every member decides the same).
                    // SAFETY: each member writes its own slot; the barrier orders the
                    // writes before the reads, and the next sweep's colour barriers order
                    // these reads before the next writes.
                    unsafe { worst.set(team.index(), mine_worst) };
                    team.wait();
                    let all = unsafe { worst.part(0..team.size()) };
                    if all.iter().all(|&w| w < tolerance) {
                        break;
                    }
                }
            }
            if team.index() == 0 {
                swept.fetch_add(sweep as u64, std::sync::atomic::Ordering::Relaxed);
            }
            if let Some(c) = seen_at(substep + 1) {
                if c.has_pairs() {
                    // One member: the one whose share of a single item is not empty.
                    if !team.share(0..1).is_empty() {
                        // SAFETY: the other members wait at the barrier below, touching nothing.
                        let (x, out) =
                            unsafe { (positions.part(0..n), scratch.part(0..scratch_len)) };
                        for _ in 0..PAIR_PASSES {
                            c.separate(x, w_all, out);
                        }
                    }
                    team.wait();
                }
                // SAFETY: this member's particles; the next substep's prediction reads only
                // its own, and its barrier orders these writes before the sweeps' reads.
                let (x, prev) =
                    unsafe { (positions.part(mine.clone()), starts.part(mine.clone())) };
                let particles = x.iter_mut().zip(prev.iter()).zip(w);
                for (i, ((x, &from), &w)) in (mine.start..).zip(particles) {
                    if w != 0.0 {
                        // The push enters this substep's velocity, (x − p)/hₛ: the impulse
                        // m δx/hₛ, which the obstacle takes back.
                        c.keep_out_noting(i, x, from, inv_hs / w);
                    }
                }
            }
        }
    });
    // The last substep's velocity, and the drift that carries x0 to the step's end.
    let inv_h = 1.0 / dt;
    let data = (
        &mut s.v[..],
        &mut s.drift[..],
        &xp.x[..],
        &xp.prev[..],
        &s.x[..],
        &s.inv_mass[..],
    );
    threads.each(springs, data, |(v, u, x, prev, x0, w)| {
        for i in 0..v.len() {
            let end = on_ground(x[i], w[i], floor);
            if w[i] != 0.0 {
                v[i] = (end - prev[i]) * inv_hs;
            }
            u[i] = (end - x0[i]) * inv_h;
        }
    });
    xp.sweeps += swept.into_inner();
    xp.steps += 1;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::state::PackedSpring;

    /// The AVX sweep gives the scalar sweep's positions bit for bit, on a colour of disjoint
    /// constraints of assorted lengths (one of zero length) and coefficients.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx_sweep_is_the_scalar_sweep() {
        if !crate::solver::forces::wide::available() {
            return;
        }
        let h =
            |k: u64| ((k.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f64) / (1u64 << 24) as f64;
        let n = 2 * 23;
        let mut x: Vec<DVec2> = (0..n as u64)
            .map(|i| DVec2::new(h(2 * i), h(2 * i + 1)))
            .collect();
        x[5] = x[4]; // constraint 2 has no length
        let constraints: Vec<Constraint> = (0..n / 2)
            .map(|c| Constraint {
                a: 2 * c as u32,
                b: 2 * c as u32 + 1,
                rest: 0.1 + h(1000 + c as u64),
                ca: h(2000 + c as u64),
                cb: h(3000 + c as u64),
            })
            .collect();
        let mut scalar = x.clone();
        let p = |v: &mut Vec<DVec2>| Positions::new(v);
        project_scalar(&constraints, p(&mut scalar));
        // SAFETY: AVX checked above; one thread.
        unsafe { project_avx(&constraints, p(&mut x)) };
        assert!(
            x.iter()
                .zip(&scalar)
                .all(|(a, b)| a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits())
        );
        assert_ne!(x[0], DVec2::new(h(0), h(1)), "the sweep moved nothing");
    }

    /// Zero compliance (k = ∞, α = 0) makes the springs rigid rods: with enough sweeps a
    /// hanging chain keeps every link at its rest length to 1e-6 while it swings, on one
    /// thread and on two.
    #[test]
    fn zero_compliance_holds_a_chain_at_its_rest_length() {
        let (n, rest, dt) = (12usize, 0.05, 1.0 / 60.0);
        for threads in [1, 2] {
            let threads = Threads::new(threads).unwrap();
            let (mut s, mut xp) = (State::default(), Xpbd::default());
            for i in 0..=n {
                // Start bent (at 45°) so that the chain swings.
                let d = DVec2::new(1.0, -1.0).normalize() * (rest * i as f64);
                s.x.push(DVec2::new(0.5, 0.9) + d);
                s.v.push(DVec2::ZERO);
                s.mass.push(1.0);
                s.inv_mass.push(if i == 0 { 0.0 } else { 1.0 });
                s.f.push(if i == 0 {
                    DVec2::ZERO
                } else {
                    DVec2::new(0.0, -9.8)
                });
            }
            s.drift = s.v.clone();
            s.springs = (0..n as u32)
                .map(|i| PackedSpring {
                    a: i,
                    b: i + 1,
                    rest,
                    k: f64::INFINITY,
                })
                .collect();
            let mut worst: f64 = 0.0;
            for _ in 0..120 {
                let it = Iterations {
                    xpbd_substeps: 20,
                    xpbd_sweeps: 200,
                    ..Default::default()
                };
                step(&mut s, &mut xp, dt, &it, None, None, &threads);
                for i in 0..s.x.len() {
                    s.x[i] += s.drift[i] * dt;
                }
                for sp in &s.springs {
                    let l = (s.x[sp.a as usize] - s.x[sp.b as usize]).length();
                    worst = worst.max((l - rest).abs());
                }
            }
            assert!(
                worst < 1e-6,
                "a link strayed {worst:e} from its rest length"
            );
            let swing = s.x[n].x - 0.5;
            assert!(
                swing.abs() < rest * n as f64,
                "the chain went somewhere odd"
            );
            assert_eq!(xp.colours(), 2, "a chain needs two colours");
        }
    }
}
