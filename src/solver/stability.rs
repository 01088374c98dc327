//! How close a scene is to its integrator's stability limit.
//!
//! The fastest mode of the linearised system x'' = −M⁻¹K x has frequency ω_max = sqrt(λ_max(M⁻¹K)).
//! Two estimates:
//! * the Gershgorin bound ω_max² ≤ 2 max_i Σ_j k_ij / m_i over free particles (cheap, never
//!   below the truth; for a uniform cloth about 1.3× above it),
//! * power iteration on M⁻¹K in the M inner product (a lower estimate that converges to the
//!   truth from below; 40 iterations).
//!
//! Limits on h·ω for an undamped oscillator: symplectic Euler and velocity Verlet 2, RK4
//! 2√2 ≈ 2.83, implicit Euler none. Explicit Euler grows every mode by sqrt(1 + h²ω²) per
//! step, so it is stable only thanks to damping. The damping scales the velocity alone by
//! e^(−μh), so the one-step map's determinant, the square of its eigenvalues' modulus, is
//! (1 + h²ω²) e^(−μh): stable while that is below 1, about h < μ/ω².
//!
//! Dashpots damp a mode in proportion to its stiffness: where every spring has the same ratio
//! c/k, the damping matrix is (c/k) K and the fastest mode obeys x'' + γ x' + ω² x = 0 with
//! γ = (c/k) ω² (Rayleigh damping). An explicit method that evaluates that force can fail
//! through it: explicit damping at rate γ needs h γ below about 2. With dashpots the limit is
//! found for that oscillator, with the largest c/k of the scene, from each method's own
//! one-step map ([`stable_dt_damped`]): the largest h below which its spectral radius stays
//! at most 1.

use super::forces::stiffness;
use super::method::{Integrator, Iterations};
use super::state::State;
use glam::DVec2;

/// The stability picture of the current scene and settings ([`estimate`]; the Bevy layer's
/// [`crate::sim::stability::estimate`] reads them from the app).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StabilityEstimate {
    /// Gershgorin upper bound on ω_max (rad/s).
    pub omega_bound: f64,
    /// Lanczos estimate of ω_max (rad/s).
    pub omega_estimate: f64,
    /// h · ω_max with the Lanczos estimate.
    pub h_omega: f64,
    /// The integrator's limit on h·ω (infinite for implicit Euler; for explicit Euler, the
    /// limit that the damping buys at this dt).
    pub limit: f64,
    /// The largest stable dt for this scene and integrator (infinite when unconditional).
    pub stable_dt: f64,
    /// The fraction of the fastest mode's amplitude the method itself keeps per step, before
    /// damping μ ([`amplitude_kept`]): below 1 for the implicit methods, the cost of their
    /// stability.
    pub fastest_mode_kept: f64,
    /// The dashpots' damping rate γ = (c/k)_max ω² of the fastest mode, 1/s (0 without
    /// dashpots).
    pub dashpot_rate: f64,
}

impl StabilityEstimate {
    /// h·ω as a fraction of the limit: < 0.8 comfortable, < 1 close, ≥ 1 unstable.
    pub fn margin(&self) -> f64 {
        if self.limit.is_finite() && self.limit > 0.0 {
            self.h_omega / self.limit
        } else if self.limit == 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }
}

/// Gershgorin bound on ω_max: sqrt(2 max_i Σ_j k_ij / m_i) over free particles.
pub fn omega_bound(s: &State) -> f64 {
    let mut row = vec![0.0; s.x.len()];
    for sp in &s.springs {
        row[sp.a as usize] += sp.k;
        row[sp.b as usize] += sp.k;
    }
    row.iter()
        .zip(&s.inv_mass)
        .map(|(k, w)| 2.0 * k * w)
        .fold(0.0, f64::max)
        .sqrt()
}

/// λ_max(M⁻¹K) by Lanczos on the symmetric M^(−½) K M^(−½), K the spring stiffness
/// linearised at the current state (the stiffness blocks), pinned particles held. The largest Ritz value approaches the truth from below and,
/// unlike power iteration, converges in a few dozen steps even where the top of the spectrum is
/// dense (a cloth's).
pub fn omega_estimate(s: &State, steps: usize) -> f64 {
    let n = s.x.len();
    if n == 0 || s.springs.is_empty() {
        return 0.0;
    }
    let inv_sqrt_m: Vec<f64> = s.inv_mass.iter().map(|w| w.sqrt()).collect();
    let mut blocks = vec![];
    stiffness::blocks(&s.springs, &s.x, &mut blocks);
    let apply = |y: &[DVec2], out: &mut [DVec2], tmp: &mut [DVec2]| {
        for i in 0..n {
            tmp[i] = y[i] * inv_sqrt_m[i];
        }
        stiffness::apply(out, tmp, &blocks);
        for i in 0..n {
            out[i] *= inv_sqrt_m[i];
        }
    };
    // A deterministic pseudo-random start (zero on pinned particles).
    let mut q: Vec<DVec2> = (0..n)
        .map(|i| {
            let h = |k: u64| {
                let z = (i as u64 * 2 + k).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                ((z >> 40) as f64 / (1u64 << 24) as f64) - 0.5
            };
            DVec2::new(h(0), h(1)) * inv_sqrt_m[i].signum()
        })
        .collect();
    let norm = |v: &[DVec2]| v.iter().map(|p| p.length_squared()).sum::<f64>().sqrt();
    let q_norm = norm(&q);
    if q_norm == 0.0 {
        return 0.0;
    }
    q.iter_mut().for_each(|p| *p /= q_norm);
    let (mut q_prev, mut w, mut tmp) = (
        vec![DVec2::ZERO; n],
        vec![DVec2::ZERO; n],
        vec![DVec2::ZERO; n],
    );
    let (mut alphas, mut betas) = (vec![], vec![]);
    let mut beta_prev = 0.0;
    for _ in 0..steps.min(2 * n) {
        apply(&q, &mut w, &mut tmp);
        let mut alpha = 0.0;
        for i in 0..n {
            w[i] -= q_prev[i] * beta_prev;
            alpha += w[i].dot(q[i]);
        }
        for i in 0..n {
            w[i] -= q[i] * alpha;
        }
        alphas.push(alpha);
        let beta = norm(&w);
        if !beta.is_finite() || beta <= 1e-12 * alpha.abs().max(1e-300) {
            break;
        }
        betas.push(beta);
        for i in 0..n {
            q_prev[i] = q[i];
            q[i] = w[i] / beta;
        }
        beta_prev = beta;
    }
    betas.truncate(alphas.len().saturating_sub(1));
    largest_eigenvalue(&alphas, &betas).max(0.0).sqrt()
}

/// The largest eigenvalue of the symmetric tridiagonal matrix (diagonal `a`, off-diagonal `b`),
/// by Sturm-sequence bisection.
fn largest_eigenvalue(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    let off = |i: usize| if i < b.len() { b[i].abs() } else { 0.0 };
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for (i, &ai) in a.iter().enumerate() {
        let r = off(i) + if i > 0 { off(i - 1) } else { 0.0 };
        lo = lo.min(ai - r);
        hi = hi.max(ai + r);
    }
    // Number of eigenvalues below x.
    let count_below = |x: f64| {
        let (mut count, mut d) = (0, 1.0);
        for (i, &ai) in a.iter().enumerate() {
            let b2 = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            d = ai - x - if i > 0 { b2 / d } else { 0.0 };
            if d == 0.0 {
                d = -1e-300;
            }
            if d < 0.0 {
                count += 1;
            }
        }
        count
    };
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if count_below(mid) >= a.len() {
            hi = mid
        } else {
            lo = mid
        }
        if hi - lo <= 1e-14 * hi.abs() {
            break;
        }
    }
    hi
}

/// The integrator's limit on h·ω at this dt and damping (see the module docs).
pub fn limit(integrator: Integrator, dt: f64, damping: f64) -> f64 {
    match integrator {
        Integrator::SymplecticEuler | Integrator::VelocityVerlet => 2.0,
        Integrator::Rk4 => 2.0 * std::f64::consts::SQRT_2,
        Integrator::ImplicitEuler
        | Integrator::ProjectiveDynamics
        | Integrator::Xpbd
        | Integrator::Bdf2
        | Integrator::Vbd => f64::INFINITY,
        // (1 + (hω)²) e^(−μh) < 1  ⇔  hω < sqrt(e^(μh) − 1).
        Integrator::ExplicitEuler => ((damping * dt).exp() - 1.0).max(0.0).sqrt(),
    }
}

/// The largest stable dt for frequency ω (bisection for explicit Euler, whose limit depends
/// on dt).
pub fn stable_dt(integrator: Integrator, omega: f64, damping: f64) -> f64 {
    if omega <= 0.0 {
        return f64::INFINITY;
    }
    match integrator {
        i if i.unconditionally_stable() => f64::INFINITY,
        Integrator::ExplicitEuler => {
            if damping <= 0.0 {
                return 0.0;
            }
            // ln(1 + h²ω²) − μh < 0 holds on (0, h*): bisect for h*.
            let unstable = |h: f64| (h * omega).powi(2).ln_1p() - damping * h >= 0.0;
            let (mut lo, mut hi) = (0.0, damping / (omega * omega) * 4.0 + 1e-12);
            while !unstable(hi) && hi < 1e6 {
                hi *= 2.0;
            }
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if unstable(mid) { hi = mid } else { lo = mid }
            }
            lo
        }
        _ => limit(integrator, 0.0, 0.0) / omega,
    }
}

/// The largest ratio c/k of a spring's dashpot to its stiffness, s: the factor that turns a
/// mode's ω² into its dashpot damping rate (0 without dashpots).
pub fn dashpot_ratio(s: &State) -> f64 {
    (s.springs.iter().zip(s.materials.dashpot()))
        .filter(|(sp, _)| sp.k > 0.0 && sp.k.is_finite())
        .map(|(sp, c)| c / sp.k)
        .fold(0.0, f64::max)
}

/// One step of the method on the test oscillator x'' = −ω² x − γ x', then the air damping's
/// factor `decay`, as the step's passes do it.
fn step_oscillator(
    integrator: Integrator,
    h: f64,
    (omega2, gamma, decay): (f64, f64, f64),
    (x, v): (f64, f64),
) -> (f64, f64) {
    let a = |x: f64, v: f64| -omega2 * x - gamma * v;
    match integrator {
        Integrator::ExplicitEuler => (x + h * v, (v + h * a(x, v)) * decay),
        Integrator::SymplecticEuler => {
            let v1 = (v + h * a(x, v)) * decay;
            (x + h * v1, v1)
        }
        Integrator::VelocityVerlet => {
            let v_half = v + 0.5 * h * a(x, v);
            let x1 = x + h * v_half;
            // The predicted v1, then the corrected half kick (see the integrator).
            let predicted = v_half + 0.5 * h * a(x1, v_half);
            let v1 = v_half + 0.5 * h * (a(x1, v_half) - gamma * (predicted - v_half));
            (x1, v1 * decay)
        }
        _ => {
            // RK4 on (x, v).
            let k1 = (v, a(x, v));
            let k2 = (
                v + 0.5 * h * k1.1,
                a(x + 0.5 * h * k1.0, v + 0.5 * h * k1.1),
            );
            let k3 = (
                v + 0.5 * h * k2.1,
                a(x + 0.5 * h * k2.0, v + 0.5 * h * k2.1),
            );
            let k4 = (v + h * k3.1, a(x + h * k3.0, v + h * k3.1));
            let x1 = x + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            let v1 = v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            (x1, v1 * decay)
        }
    }
}

/// The spectral radius of the method's one-step map on the test oscillator.
fn spectral_radius(integrator: Integrator, h: f64, omega: f64, gamma: f64, mu: f64) -> f64 {
    let coefficients = (omega * omega, gamma, (-mu * h).exp());
    let (a, c) = step_oscillator(integrator, h, coefficients, (1.0, 0.0));
    let (b, d) = step_oscillator(integrator, h, coefficients, (0.0, 1.0));
    let (trace, det) = (a + d, a * d - b * c);
    let disc = trace * trace - 4.0 * det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        ((trace + r) / 2.0).abs().max(((trace - r) / 2.0).abs())
    } else {
        det.abs().sqrt()
    }
}

/// The largest stable dt for frequency ω when the dashpots damp that mode at rate
/// `ratio`·ω² and the air at μ: the first step size at which the method's one-step map
/// grows (geometric search, then bisection). With `ratio` 0 it is [`stable_dt`].
pub fn stable_dt_damped(integrator: Integrator, omega: f64, damping: f64, ratio: f64) -> f64 {
    if ratio <= 0.0 || omega <= 0.0 || integrator.unconditionally_stable() {
        return stable_dt(integrator, omega, damping);
    }
    let gamma = ratio * omega * omega;
    let unstable = |h: f64| spectral_radius(integrator, h, omega, gamma, damping) > 1.0 + 1e-12;
    // Every explicit method is stable below both 1/ω and 1/γ by a wide margin.
    let mut lo = 1e-3 / (omega + gamma);
    if unstable(lo) {
        return 0.0;
    }
    let mut hi = lo * 1.25;
    while !unstable(hi) {
        lo = hi;
        hi *= 1.25;
        if hi > 1e6 {
            return f64::INFINITY;
        }
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) { hi = mid } else { lo = mid }
    }
    lo
}

/// The full estimate for a state, an integrator at step `dt` with damping μ, and its
/// iteration counts.
pub fn estimate(
    s: &State,
    integrator: Integrator,
    dt: f64,
    damping: f64,
    iterations: Iterations,
) -> StabilityEstimate {
    let omega_bound = omega_bound(s);
    let omega_estimate = omega_estimate(s, 60);
    let h_omega = dt * omega_estimate;
    let ratio = dashpot_ratio(s);
    let (limit, stable_dt) = if ratio > 0.0 && !integrator.unconditionally_stable() {
        // The limit on hω that the stable dt means, for this scene's fastest mode.
        let stable = stable_dt_damped(integrator, omega_estimate, damping, ratio);
        (stable * omega_estimate, stable)
    } else {
        (
            limit(integrator, dt, damping),
            stable_dt(integrator, omega_estimate, damping),
        )
    };
    StabilityEstimate {
        omega_bound,
        omega_estimate,
        h_omega,
        limit,
        stable_dt,
        fastest_mode_kept: amplitude_kept(integrator, h_omega, iterations),
        dashpot_rate: ratio * omega_estimate * omega_estimate,
    }
}

/// What the method's own numerical damping leaves of the fastest mode's amplitude per step
/// (1: none; damping μ comes on top). The price of unconditional stability:
/// * backward Euler (implicit Euler to convergence, and projective dynamics, which converges to
///   it) maps an undamped mode of frequency ω to 1/sqrt(1 + (hω)²) of its amplitude per step;
/// * XPBD's substep is, for one constraint, exactly backward Euler of size h/n (its projection
///   with compliance α is the implicit spring force), so n substeps keep (1 + (hω/n)²)^(−n/2);
/// * BDF2 keeps the larger root's modulus |ζ| of (1 − ⅔ i hω) ζ² − ⁴⁄₃ ζ + ⅓ = 0, its
///   characteristic equation on x' = iωx: 1 − (hω)⁴/4 + … at small hω (fourth order in hω
///   where backward Euler's loss is second), 0.93 at hω = 1, 0.30 at hω = 10, 0.078 at
///   hω = 100 (backward Euler: 0.71, 0.10 and 0.010);
/// * VBD converges to backward Euler's step (fewer iterations damp more, not less);
/// * the explicit methods below their limit keep it all (symplectic Euler, Verlet) or nearly
///   (RK4, whose small loss is not modelled here); explicit Euler gains.
pub fn amplitude_kept(integrator: Integrator, h_omega: f64, iterations: Iterations) -> f64 {
    let backward = |x: f64| 1.0 / (1.0 + x * x).sqrt();
    match integrator {
        Integrator::ImplicitEuler | Integrator::ProjectiveDynamics | Integrator::Vbd => {
            backward(h_omega)
        }
        Integrator::Bdf2 => bdf2_kept(h_omega),
        Integrator::Xpbd => {
            let n = iterations.xpbd_substeps.max(1) as f64;
            backward(h_omega / n).powf(n)
        }
        Integrator::ExplicitEuler => (1.0 + h_omega * h_omega).sqrt(),
        Integrator::SymplecticEuler | Integrator::VelocityVerlet | Integrator::Rk4 => 1.0,
    }
}

/// The modulus of BDF2's larger characteristic root on x' = iωx at hω = `x` (see
/// [`amplitude_kept`]): ζ = (⁴⁄₃ ± √(⁴⁄₉ − ⁴⁄₃ (1 − ⅔ i x))) / (2 (1 − ⅔ i x)).
fn bdf2_kept(x: f64) -> f64 {
    // Complex numbers as (re, im).
    let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: (f64, f64), b: (f64, f64)| {
        let d = b.0 * b.0 + b.1 * b.1;
        ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: (f64, f64)| {
        let r = (a.0 * a.0 + a.1 * a.1).sqrt();
        let re = ((r + a.0) / 2.0).max(0.0).sqrt();
        let im = ((r - a.0) / 2.0).max(0.0).sqrt().copysign(a.1);
        (re, im)
    };
    let a = (1.0, -2.0 / 3.0 * x);
    let disc = {
        let four_ac = mul((4.0 / 3.0, 0.0), a);
        (16.0 / 9.0 - four_ac.0, -four_ac.1)
    };
    let root = sqrt(disc);
    let two_a = (2.0 * a.0, 2.0 * a.1);
    let z1 = div((4.0 / 3.0 + root.0, root.1), two_a);
    let z2 = div((4.0 / 3.0 - root.0, -root.1), two_a);
    let modulus = |z: (f64, f64)| (z.0 * z.0 + z.1 * z.1).sqrt();
    modulus(z1).max(modulus(z2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BDF2's kept amplitude: nearly all at small hω (its loss is fourth order, (hω)⁴/4 to
    /// leading order), less than 1 everywhere, more than backward Euler's.
    #[test]
    fn bdf2_keeps_more_than_backward_euler() {
        let small: f64 = 0.01;
        let loss = 1.0 - bdf2_kept(small);
        assert!(
            (loss / (small.powi(4) / 4.0) - 1.0).abs() < 0.01,
            "{loss:e}"
        );
        for x in [0.1, 1.0, 10.0, 100.0, 1e4] {
            let (b, e) = (bdf2_kept(x), 1.0 / (1.0 + x * x).sqrt());
            assert!(b < 1.0 && b > e, "hω = {x}: BDF2 {b}, backward Euler {e}");
        }
    }

    /// With vanishing dashpots the one-step maps find each method's known edge (2/ω, 2√2/ω,
    /// explicit Euler's from μ); strong dashpots bring the edge in, toward 2/γ for the Euler
    /// methods.
    #[test]
    fn the_damped_edge_meets_the_known_ones() {
        let omega = 300.0;
        for (integrator, mu) in [
            (Integrator::SymplecticEuler, 0.0),
            (Integrator::VelocityVerlet, 0.0),
            (Integrator::Rk4, 0.0),
            (Integrator::ExplicitEuler, 10.0),
        ] {
            let known = stable_dt(integrator, omega, mu);
            let found = stable_dt_damped(integrator, omega, mu, 1e-12);
            assert!(
                (found / known - 1.0).abs() < 1e-6,
                "{integrator}: {found} against {known}"
            );
        }
        // c/k = 0.01 s: γ = 900/s at ω = 300, so 2/γ = 2.2 ms is below 2/ω = 6.7 ms.
        let found = stable_dt_damped(Integrator::SymplecticEuler, omega, 0.0, 0.01);
        let gamma = 0.01 * omega * omega;
        assert!(
            found < 2.0 / omega && found <= 2.0 / gamma * 1.01,
            "{found}"
        );
    }
}
