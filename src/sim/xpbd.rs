//! XPBD (Macklin, Müller and Chentanez 2016, "XPBD: Position-Based Simulation of Compliant
//! Constrained Dynamics"), with substeps (Macklin et al. 2019, "Small Steps in Physics
//! Simulation"). Each spring is the distance constraint C = |x_a − x_b| − L with compliance
//! α = 1/k. A step of size h is n substeps of size hₛ = h/n; each substep is
//!
//! 1. v += hₛ f_body/m, p = x, x += hₛ v (free particles; a held one moves with its velocity),
//!    and a free particle that x puts below the ground is put on it,
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
//! particle), and a colour's springs are projected in parallel chunks. The sweep is then the
//! same Gauss-Seidel sweep whatever the thread count: the result is bit for bit that of one
//! thread. (Jacobi with averaging would need no colouring, but it converges more slowly, by a
//! factor that grows with the number of constraints on a particle.)

use super::parallel::SolverThreads;
use super::solver::Solver;
use bevy::math::DVec2;

/// A constraint in colour order: the packed spring's ends, rest length and compliance, and the
/// coefficients of its projection at the current substep size (so that the sweep reads no
/// inverse masses and divides once): with den = w_a + w_b + α̃,
/// Δλ = g/den and x_a += w_a Δλ n = (w_a/den) g n, for g = −C − α̃λ.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Constraint {
    a: u32,
    b: u32,
    rest: f64,
    /// α = 1/k (0 for an infinitely stiff spring).
    compliance: f64,
    /// α̃ = α/hₛ².
    alpha: f64,
    /// 1/den (0 when both ends are fixed and the spring is rigid: nothing moves).
    inv_den: f64,
    /// w_a/den and w_b/den.
    ca: f64,
    cb: f64,
}

/// The colouring and buffers, kept from step to step.
#[derive(Debug, Default, Clone)]
pub struct Xpbd {
    /// The [`Solver::revision`] the colouring is for.
    revision: Option<u64>,
    /// The revision and substep size (bits) the coefficients are for.
    coefficients: Option<(u64, u64)>,
    /// Constraints grouped by colour.
    constraints: Vec<Constraint>,
    /// Start of each colour in `constraints`, and the end.
    colour_starts: Vec<usize>,
    /// Per constraint, the multiplier of the current substep.
    lambda: Vec<f64>,
    /// Positions during the step, and at the start of the substep.
    x: Vec<DVec2>,
    prev: Vec<DVec2>,
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

    /// Greedy colouring in packed order: each spring takes the lowest colour neither of its ends
    /// has yet. Within a colour the springs keep the packed order (by first end), which keeps
    /// the sweep's memory access local.
    fn colour(&mut self, s: &Solver) {
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
        for (sp, &c) in s.springs.iter().zip(&colour_of) {
            let slot = &mut at[c as usize];
            self.constraints[*slot] = Constraint {
                a: sp.a,
                b: sp.b,
                rest: sp.rest,
                compliance: 1.0 / sp.k,
                ..Default::default()
            };
            *slot += 1;
        }
        self.lambda = vec![0.0; s.springs.len()];
        self.revision = Some(s.revision);
        self.coefficients = None;
    }

    /// The projections' coefficients for substeps of `hs` (see [`Constraint`]).
    fn prepare(&mut self, s: &Solver, hs: f64) {
        let key = (s.revision, hs.to_bits());
        if self.coefficients == Some(key) {
            return;
        }
        let inv_h2 = 1.0 / (hs * hs);
        let w = &s.inv_mass;
        for c in &mut self.constraints {
            let (wa, wb) = (w[c.a as usize], w[c.b as usize]);
            c.alpha = c.compliance * inv_h2;
            let den = wa + wb + c.alpha;
            c.inv_den = if den > 0.0 { 1.0 / den } else { 0.0 };
            c.ca = wa * c.inv_den;
            c.cb = wb * c.inv_den;
        }
        self.coefficients = Some(key);
    }
}

/// Positions written by the parallel chunks of one colour.
///
/// Within a colour no two constraints share a particle, so the chunks of a colour pass read
/// and write disjoint sets of positions; the passes of successive colours are separated by the
/// pool's join. That is the whole safety argument for the raw pointer.
#[derive(Clone, Copy)]
struct Positions {
    ptr: *mut DVec2,
    len: usize,
}

// SAFETY: see the type's docs: concurrent chunks touch disjoint elements.
unsafe impl Send for Positions {}
// SAFETY: as above.
unsafe impl Sync for Positions {}

impl Positions {
    /// # Safety
    /// No other thread may access element `i` during the colour pass.
    #[inline(always)]
    unsafe fn get(self, i: usize) -> DVec2 {
        debug_assert!(i < self.len);
        // SAFETY: in bounds (the packed springs' ends are particle indices) and unshared.
        unsafe { *self.ptr.add(i) }
    }
    /// # Safety
    /// As for [`Positions::get`].
    #[inline(always)]
    unsafe fn set(self, i: usize, p: DVec2) {
        debug_assert!(i < self.len);
        // SAFETY: as above.
        unsafe { *self.ptr.add(i) = p }
    }
}

/// The ground as a position constraint of each substep's prediction (as position-based methods
/// treat contact): a free particle predicted below it is put on it, so the substep's velocity
/// (x − p)/hₛ carries it no further down. The schedule's ground pass then finds nothing to do.
#[inline(always)]
fn on_ground(mut x: DVec2, w: f64, ground: f64) -> DVec2 {
    if x.y < ground && w != 0.0 {
        x.y = ground;
    }
    x
}

/// Projects a run of constraints of one colour. `MULTIPLIERS`: keep λ across sweeps (more
/// than one sweep a substep); with one sweep λ is 0 at the projection and is never read again.
fn project<const MULTIPLIERS: bool>(constraints: &[Constraint], lambda: &mut [f64], x: Positions) {
    for (c, lambda) in constraints.iter().zip(lambda) {
        let (a, b) = (c.a as usize, c.b as usize);
        // SAFETY: a and b belong to this constraint alone within the colour.
        let (xa, xb) = unsafe { (x.get(a), x.get(b)) };
        let l = xa - xb;
        let len = l.length();
        if len == 0.0 {
            continue; // no direction (the spring force kernel exerts none either)
        }
        let mut g = c.rest - len; // −C
        if MULTIPLIERS {
            g -= c.alpha * *lambda;
            *lambda += g * c.inv_den;
        }
        let s = g / len;
        // SAFETY: as above.
        unsafe {
            x.set(a, xa + l * (c.ca * s));
            x.set(b, xb - l * (c.cb * s));
        }
    }
}

/// One XPBD step (see the module docs): sets v to the end velocity and the drift to the mean
/// velocity over the step. `s.f` holds the body forces.
pub fn step(
    s: &mut Solver,
    dt: f64,
    substeps: u32,
    sweeps: u32,
    ground: Option<f64>,
    threads: &SolverThreads,
) {
    let mut xp = std::mem::take(&mut s.xpbd);
    if xp.revision != Some(s.revision) || xp.constraints.len() != s.springs.len() {
        xp.colour(s);
    }
    let n = s.x.len();
    let springs = s.springs.len();
    xp.x.clear();
    xp.x.extend_from_slice(&s.x);
    xp.prev.resize(n, DVec2::ZERO);
    let substeps = substeps.max(1);
    let hs = dt / substeps as f64;
    let inv_hs = 1.0 / hs;
    let floor = ground.unwrap_or(f64::NEG_INFINITY);
    xp.prepare(s, hs);
    // The first substep's prediction: v += hₛ f/m, p = x, x += hₛ v.
    let data = (
        &mut xp.x[..],
        &mut xp.prev[..],
        &mut s.v[..],
        &s.f[..],
        &s.inv_mass[..],
    );
    threads.each(springs, data, |(x, prev, v, f, w)| {
        for i in 0..x.len() {
            v[i] += f[i] * (hs * w[i]);
            let start = x[i];
            prev[i] = start;
            x[i] = on_ground(start + v[i] * hs, w[i], floor);
        }
    });
    for substep in 0..substeps {
        let positions = Positions {
            ptr: xp.x.as_mut_ptr(),
            len: n,
        };
        if sweeps > 1 {
            xp.lambda.iter_mut().for_each(|l| *l = 0.0);
        }
        for _ in 0..sweeps {
            for colour in xp.colour_starts.windows(2) {
                let range = colour[0]..colour[1];
                let data = (&xp.constraints[range.clone()], &mut xp.lambda[range]);
                if sweeps > 1 {
                    threads.each(springs, data, |(c, l)| project::<true>(c, l, positions));
                } else {
                    threads.each(springs, data, |(c, l)| project::<false>(c, l, positions));
                }
            }
        }
        if substep + 1 < substeps {
            // This substep's velocity, v = (x − p)/hₛ, fused with the next one's prediction.
            let data = (
                &mut xp.x[..],
                &mut xp.prev[..],
                &mut s.v[..],
                &s.f[..],
                &s.inv_mass[..],
            );
            threads.each(springs, data, |(x, prev, v, f, w)| {
                for i in 0..x.len() {
                    let end = x[i];
                    if w[i] != 0.0 {
                        v[i] = (end - prev[i]) * inv_hs;
                    }
                    v[i] += f[i] * (hs * w[i]);
                    prev[i] = end;
                    x[i] = on_ground(end + v[i] * hs, w[i], floor);
                }
            });
        }
    }
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
            if w[i] != 0.0 {
                v[i] = (x[i] - prev[i]) * inv_hs;
            }
            u[i] = (x[i] - x0[i]) * inv_h;
        }
    });
    xp.sweeps += substeps as u64 * sweeps as u64;
    xp.steps += 1;
    s.xpbd = xp;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::solver::PackedSpring;

    /// Zero compliance (k = ∞, α = 0) makes the springs rigid rods: with enough sweeps a
    /// hanging chain keeps every link at its rest length to 1e-6 while it swings, on one
    /// thread and on two.
    #[test]
    fn zero_compliance_holds_a_chain_at_its_rest_length() {
        let (n, rest, dt) = (12usize, 0.05, 1.0 / 60.0);
        for threads in [1, 2] {
            let threads = SolverThreads::new(threads).unwrap();
            let mut s = Solver::default();
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
                step(&mut s, dt, 20, 200, None, &threads);
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
            assert_eq!(s.xpbd.colours(), 2, "a chain needs two colours");
        }
    }
}
