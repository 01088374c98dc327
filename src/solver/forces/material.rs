//! Materials beyond the Hooke spring: dashpots along springs, gas-filled loops (pressure
//! bodies), muscles (springs whose rest length oscillates) and plastic springs (whose rest
//! length yields). Each is a list that is empty when no spring or body of the scene has the
//! material, and every pass here runs only over its own list: a scene without materials pays
//! one emptiness test per force evaluation.
//!
//! Where each enters the integrators (`docs/integrators.md` has the table):
//! * **Dashpot**, f_a = −c ((v_a − v_b)·n) n: a force at every stage of the explicit methods
//!   ([`Materials::add_forces`]); its damping matrix c n nᵀ in implicit Euler's Newton matrix
//!   ([`Materials::add_dashpot_blocks`]); its Rayleigh dissipation (c/2h)(n·Δ(x_a − x_b))² as a
//!   projective term in projective dynamics ([`Materials::add_projective_terms`], weight h·c in
//!   the global matrix); Macklin et al.'s damped projection in XPBD.
//! * **Gas pressure**, P = nRT/A on every edge along its outward normal: a force wherever
//!   forces are evaluated (and in XPBD's prediction); implicit Euler's Newton matrix takes the
//!   positive semi-definite part of its Jacobian ([`GasJacobian`]).
//! * **Muscles and plasticity** change rest lengths between steps ([`Materials::actuate`],
//!   [`Materials::yield_springs`]), which every method reads.

use super::spring::MIN_SPRING_LENGTH;
use super::stiffness::{Block, Sym2};
use crate::solver::packed::PackedSpring;
use glam::DVec2;
use std::f64::consts::TAU;

/// A spring whose rest length oscillates: L(t) = L₀ (1 + A sin(2π f t + φ)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackedMuscle {
    /// The packed spring.
    pub spring: u32,
    /// L₀, m.
    pub rest: f64,
    /// A, a fraction of L₀.
    pub amplitude: f64,
    /// f, Hz.
    pub frequency: f64,
    /// φ, rad.
    pub phase: f64,
}

impl PackedMuscle {
    /// The rest length at time `t`.
    pub fn rest_at(&self, t: f64) -> f64 {
        self.rest * (1.0 + self.amplitude * (TAU * self.frequency * t + self.phase).sin())
    }
}

/// A spring that yields: past a strain ε_y its rest length creeps toward its length at rate r.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackedPlastic {
    /// The packed spring.
    pub spring: u32,
    /// ε_y, the strain |l − L|/L past which it yields.
    pub yield_strain: f64,
    /// r, 1/s: each step moves L by (1 − e^(−r dt)) of the way to l.
    pub rate: f64,
}

/// A closed loop of particles filled with an ideal gas of nRT = `nrt` (N·m in 2D): the
/// pressure at area A is nRT/A, and it pushes every edge outward with pressure × length. Its
/// potential is −nRT ln A, so its force on a particle is nRT ∇A / A.
#[derive(Debug, Clone, PartialEq)]
pub struct GasBody {
    /// The loop's particles in order around it (either way round).
    pub particles: Vec<u32>,
    /// nRT, N·m.
    pub nrt: f64,
    /// +1 when the loop ran counter-clockwise when packed, −1 clockwise: its area is the
    /// signed area times this, positive while the loop keeps its orientation.
    pub(crate) orientation: f64,
    /// The smallest area the pressure is computed at (a thousandth of the packed area): a loop
    /// squashed flat or turned inside out pushes out hard, but finitely.
    pub(crate) floor: f64,
}

impl GasBody {
    /// A body around `particles` at positions `x` (its orientation and floor are taken there).
    pub fn new(particles: Vec<u32>, nrt: f64, x: &[DVec2]) -> GasBody {
        let mut body = GasBody {
            particles,
            nrt,
            orientation: 1.0,
            floor: 0.0,
        };
        let signed = body.signed_area(x);
        body.orientation = if signed < 0.0 { -1.0 } else { 1.0 };
        body.floor = 1e-3 * signed.abs();
        body
    }

    /// The shoelace area, positive for a counter-clockwise loop.
    pub fn signed_area(&self, x: &[DVec2]) -> f64 {
        let p = &self.particles;
        let mut twice = 0.0;
        for (k, &i) in p.iter().enumerate() {
            let (a, b) = (x[i as usize], x[p[(k + 1) % p.len()] as usize]);
            twice += a.perp_dot(b);
        }
        0.5 * twice
    }

    /// The area the pressure acts on: positive while the loop keeps the orientation it was
    /// packed with, and never below the floor.
    pub fn area(&self, x: &[DVec2]) -> f64 {
        (self.orientation * self.signed_area(x)).max(self.floor)
    }

    /// The gas pressure nRT/A, N/m.
    pub fn pressure(&self, x: &[DVec2]) -> f64 {
        self.nrt / self.area(x)
    }

    /// ∂A/∂x of the loop's `k`-th particle: half the sum of its two edges' outward normals
    /// times their lengths.
    fn gradient(&self, x: &[DVec2], k: usize) -> DVec2 {
        let p = &self.particles;
        let n = p.len();
        let (prev, next) = (x[p[(k + n - 1) % n] as usize], x[p[(k + 1) % n] as usize]);
        DVec2::new(next.y - prev.y, prev.x - next.x) * (0.5 * self.orientation)
    }

    /// Adds P ∂A/∂x_i to every particle's force.
    fn add_forces(&self, x: &[DVec2], f: &mut [DVec2]) {
        self.add_scaled_forces(x, f, 1.0);
    }

    /// Adds `scale` P ∂A/∂x_i to every particle's entry of `f` (scale 1: the forces, whose
    /// bits it then gives, the product being exact).
    fn add_scaled_forces(&self, x: &[DVec2], f: &mut [DVec2], scale: f64) {
        let pressure = self.pressure(x) * scale;
        for (k, &i) in self.particles.iter().enumerate() {
            f[i as usize] += self.gradient(x, k) * pressure;
        }
    }

    /// The gas's potential, −nRT ln A, J.
    fn energy(&self, x: &[DVec2]) -> f64 {
        -self.nrt * self.area(x).ln()
    }
}

/// The materials of the packed springs and particles (see the module docs). Built by the
/// adapter when it packs; every list is empty when the scene has none.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Materials {
    /// Each packed spring's dashpot c, N·s/m; empty when every spring's is 0.
    pub(crate) dashpot: Vec<f64>,
    /// Springs with a dashpot of their own (NaN: the scene-wide default); empty when none has.
    pub(crate) own_dashpot: Vec<f64>,
    /// The scene-wide default the dashpots reflect.
    pub(crate) default_dashpot: f64,
    pub(crate) muscles: Vec<PackedMuscle>,
    pub(crate) plastic: Vec<PackedPlastic>,
    pub(crate) gas: Vec<GasBody>,
}

impl Materials {
    /// Each packed spring's dashpot c (empty: none has one).
    pub fn dashpot(&self) -> &[f64] {
        &self.dashpot
    }
    /// The muscles.
    pub fn muscles(&self) -> &[PackedMuscle] {
        &self.muscles
    }
    /// The plastic springs.
    pub fn plastic(&self) -> &[PackedPlastic] {
        &self.plastic
    }
    /// The pressure bodies.
    pub fn gas(&self) -> &[GasBody] {
        &self.gas
    }
    /// Whether some spring has a dashpot.
    pub fn has_dashpots(&self) -> bool {
        !self.dashpot.is_empty()
    }
    /// Whether some force beyond the springs' is evaluated: dashpots or gas.
    pub fn exerts_forces(&self) -> bool {
        !self.dashpot.is_empty() || !self.gas.is_empty()
    }
    /// Whether rest lengths change between steps: muscles or plasticity.
    pub fn moves_rest_lengths(&self) -> bool {
        !self.muscles.is_empty() || !self.plastic.is_empty()
    }
    /// Whether the scene has any material beyond the Hooke spring.
    pub fn any(&self) -> bool {
        self.exerts_forces() || self.moves_rest_lengths() || !self.own_dashpot.is_empty()
    }

    /// Sets every spring's dashpot from its own value or, for the others, `default`; returns
    /// whether any changed (projective dynamics' matrix holds them).
    pub fn apply_default_dashpot(&mut self, default: f64, springs: usize) -> bool {
        let own = &self.own_dashpot;
        let c = |i: usize| match own.get(i) {
            Some(c) if !c.is_nan() => *c,
            _ => default,
        };
        let any = (0..springs).any(|i| c(i) != 0.0);
        let dashpot: Vec<f64> = if any {
            (0..springs).map(c).collect()
        } else {
            vec![]
        };
        self.default_dashpot = default;
        let changed = dashpot != self.dashpot;
        self.dashpot = dashpot;
        changed
    }

    /// Adds the dashpot and gas forces at positions `x` and velocities `v` to `f`.
    pub fn add_forces(&self, springs: &[PackedSpring], x: &[DVec2], v: &[DVec2], f: &mut [DVec2]) {
        self.add_dashpot_forces(springs, x, v, f);
        self.add_gas_forces(x, f);
    }

    /// Adds the gas forces at positions `x` to `f`.
    pub fn add_gas_forces(&self, x: &[DVec2], f: &mut [DVec2]) {
        for body in &self.gas {
            body.add_forces(x, f);
        }
    }

    /// Each spring with a dashpot and a length: its ends, its unit direction from b to a at
    /// positions `x`, and its c: what the dashpot's force and its projective term start from.
    fn dashpots<'a>(
        &'a self,
        springs: impl IntoIterator<Item = (usize, usize)> + 'a,
        x: &'a [DVec2],
    ) -> impl Iterator<Item = (usize, usize, DVec2, f64)> + 'a {
        (springs.into_iter().zip(&self.dashpot))
            .filter(|(_, c)| **c != 0.0)
            .filter_map(move |((a, b), &c)| {
                let d = x[a] - x[b];
                let l = d.length();
                (l >= MIN_SPRING_LENGTH).then(|| (a, b, d / l, c))
            })
    }

    /// Adds the dashpot forces at positions `x` for velocities `v` (linear in `v`: the
    /// Verlet correction passes a velocity difference).
    pub fn add_dashpot_forces(
        &self,
        springs: &[PackedSpring],
        x: &[DVec2],
        v: &[DVec2],
        f: &mut [DVec2],
    ) {
        let ends = springs.iter().map(|s| (s.a as usize, s.b as usize));
        for (a, b, n, c) in self.dashpots(ends, x) {
            let g = n * (-c * (v[a] - v[b]).dot(n));
            f[a] += g;
            f[b] -= g;
        }
    }

    /// Implicit Euler: adds each dashpot's c n nᵀ / h to its spring's stiffness block, so that
    /// the Newton matrix M + h² Σ blocks becomes M − h² K − h D (D = ∂f/∂v = −Σ c n nᵀ).
    pub fn add_dashpot_blocks(&self, blocks: &mut [Block], x: &[DVec2], h: f64) {
        for (block, &c) in blocks.iter_mut().zip(&self.dashpot) {
            if c == 0.0 {
                continue;
            }
            let d = x[block.a as usize] - x[block.b as usize];
            let l = d.length();
            if l < MIN_SPRING_LENGTH {
                continue;
            }
            let n = d / l;
            let nn = Sym2 {
                xx: n.x * n.x,
                xy: n.x * n.y,
                yy: n.y * n.y,
            };
            block.m.add_scaled(nn, c / h);
        }
    }

    /// Projective dynamics: adds to the residual `r` the dashpots' terms and the gas forces at
    /// the iterate `z`, times h². A dashpot's Rayleigh dissipation (c/2h)(n·(Δ_a − Δ_b))², with
    /// Δ = z − x0 and n the spring's direction at the step's start, is the distance of the ends'
    /// relative displacement from the line across n: a projective term of weight h c (in the
    /// global matrix, beside h² k), whose residual is −h c n (n·(Δ_a − Δ_b)).
    pub fn add_projective_terms(
        &self,
        springs: &[PackedSpring],
        x0: &[DVec2],
        z: &[DVec2],
        h: f64,
        r: &mut [DVec2],
    ) {
        let ends = springs.iter().map(|s| (s.a as usize, s.b as usize));
        for (a, b, n, c) in self.dashpots(ends, x0) {
            let g = n * (-h * c * n.dot((z[a] - x0[a]) - (z[b] - x0[b])));
            r[a] += g;
            r[b] -= g;
        }
        for body in &self.gas {
            body.add_scaled_forces(z, r, h * h);
        }
    }

    /// Projective dynamics' global matrix: each spring's weight, h² k + h c.
    pub fn projective_weight(&self, spring: usize, s: &PackedSpring, h: f64) -> f64 {
        h * h * s.k + self.dashpot.get(spring).map_or(0.0, |c| h * c)
    }

    /// Sets the muscles' rest lengths for time `t`.
    pub fn actuate(&self, springs: &mut [PackedSpring], t: f64) {
        for m in &self.muscles {
            springs[m.spring as usize].rest = m.rest_at(t);
        }
    }

    /// Moves the rest length of every plastic spring strained past its yield toward its
    /// length; returns whether any moved.
    pub fn yield_springs(&self, springs: &mut [PackedSpring], x: &[DVec2], dt: f64) -> bool {
        let mut moved = false;
        for p in &self.plastic {
            let s = &mut springs[p.spring as usize];
            let l = (x[s.a as usize] - x[s.b as usize]).length();
            if !l.is_finite() || s.rest <= 0.0 {
                continue;
            }
            if (l - s.rest).abs() > p.yield_strain * s.rest {
                s.rest += (l - s.rest) * -(-p.rate * dt).exp_m1();
                moved = true;
            }
        }
        moved
    }

    /// Writes the gas forces at `x` into `out` (their particles' entries; the others are left
    /// as they are, zero when `out` was zeroed once).
    pub fn gas_forces_into(&self, x: &[DVec2], out: &mut [DVec2]) {
        for body in &self.gas {
            for &i in &body.particles {
                out[i as usize] = DVec2::ZERO;
            }
        }
        for body in &self.gas {
            body.add_forces(x, out);
        }
    }

    /// The gas bodies' potential, J.
    pub fn gas_energy(&self, x: &[DVec2]) -> f64 {
        // From +0.0: a float `sum` starts at −0.0, which a scene without gas kept.
        self.gas
            .iter()
            .map(|b| b.energy(x))
            .fold(0.0, |sum, e| sum + e)
    }

    /// The muscle of packed spring `i`, if it is one (for a patched rest length).
    pub(crate) fn muscle_mut(&mut self, i: usize) -> Option<&mut PackedMuscle> {
        self.muscles.iter_mut().find(|m| m.spring as usize == i)
    }
}

/// Implicit Euler's share of the gas Jacobian: −∂f/∂x of a body is
/// nRT (∇A ∇Aᵀ / A² − ∇²A / A); the first part, positive semi-definite, goes into the Newton
/// matrix (a rank-one term per body, applied without forming it), and the indefinite second
/// is left out, as the transverse term of compressed springs is: the residual stays exact,
/// only the convergence rate changes.
#[derive(Debug, Clone, Default)]
pub struct GasJacobian {
    /// Per body: its first entry in `gradients`, one past its last, and nRT/A².
    bodies: Vec<(usize, usize, f64)>,
    /// (particle, ∂A/∂x) of every body's particles, body after body.
    gradients: Vec<(u32, DVec2)>,
}

impl GasJacobian {
    /// The Jacobian's part at positions `x`.
    pub fn at(&mut self, materials: &Materials, x: &[DVec2]) {
        self.bodies.clear();
        self.gradients.clear();
        for body in &materials.gas {
            let start = self.gradients.len();
            for (k, &i) in body.particles.iter().enumerate() {
                self.gradients.push((i, body.gradient(x, k)));
            }
            let area = body.area(x);
            let coefficient = body.nrt / (area * area);
            self.bodies.push((start, self.gradients.len(), coefficient));
        }
    }

    /// Whether there is nothing to apply.
    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }

    /// out += G u, G = Σ nRT/A² ∇A ∇Aᵀ.
    pub fn add_product(&self, u: &[DVec2], out: &mut [DVec2]) {
        for &(start, end, coefficient) in &self.bodies {
            let g = &self.gradients[start..end];
            let s: f64 = g.iter().map(|(i, g)| g.dot(u[*i as usize])).sum();
            for (i, g) in g {
                out[*i as usize] += *g * (coefficient * s);
            }
        }
    }

    /// Adds G's diagonal blocks, times `scale`, to the per-particle blocks `diag`.
    pub fn add_diagonal(&self, diag: &mut [Sym2], scale: f64) {
        for &(start, end, coefficient) in &self.bodies {
            for (i, g) in &self.gradients[start..end] {
                let gg = Sym2 {
                    xx: g.x * g.x,
                    xy: g.x * g.y,
                    yy: g.y * g.y,
                };
                diag[*i as usize].add_scaled(gg, coefficient * scale);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gas force is minus the gradient of −nRT ln A (by central differences), for a loop
    /// listed either way round.
    #[test]
    fn the_gas_force_is_the_gradient_of_its_potential() {
        let x: Vec<DVec2> = (0..7)
            .map(|i| {
                let t = i as f64 / 7.0 * TAU;
                DVec2::new(t.cos() * (1.0 + 0.1 * i as f64), t.sin())
            })
            .collect();
        for reversed in [false, true] {
            let mut loop_: Vec<u32> = (0..7).collect();
            if reversed {
                loop_.reverse();
            }
            let body = GasBody::new(loop_, 3.0, &x);
            let mut f = vec![DVec2::ZERO; 7];
            body.add_forces(&x, &mut f);
            for i in 0..7 {
                for axis in [DVec2::X, DVec2::Y] {
                    let e = 1e-6;
                    let (mut up, mut down) = (x.clone(), x.clone());
                    up[i] += axis * e;
                    down[i] -= axis * e;
                    let slope = (body.energy(&up) - body.energy(&down)) / (2.0 * e);
                    assert!((f[i].dot(axis) + slope).abs() < 1e-7, "{i} {axis}");
                }
            }
        }
    }
}
