//! The contact forces inside the global solves of projective dynamics, BDF2 and implicit Euler:
//! what each particle's contact gives it, learned over the solve's iterations ([`Support`]),
//! and, under projective dynamics and BDF2's backward Euler steps, one line search that sizes
//! each iteration's change of those forces by how the whole iterate answers it
//! ([`Support::line_search`]).
//!
//! Why the line search: the forces are learned particle by particle, each from its own push
//! with its own mass as the step, over-relaxed up to [`SUPPORT_GAIN`] where springs tie it to
//! the rest of its body. But a body meets the surfaces as a whole: a strip two particles deep
//! landing flat was stopped by its lower row's forces at four times that row's own mass, twice
//! the strip's, and was thrown up (its energy rose from 3.9 J to 25 J at 1/60 s and 44 J at
//! 1/30 s); a box eight rows high needs eight times its bottom row's. One more solve with the
//! kept factor answers how every particle would move under the change, and that answer sizes
//! it (`docs/performance-log.md`, 2026-12-07).

use super::inside::{Held, InSolve};
use crate::solver::state::State;
use glam::DVec2;

/// The largest over-relaxation of the contact forces' update (see [`Support`]): on the shipped
/// pile at 1/60 s (2-core AMD EPYC, 2026-12-04), 1 left pairs at 86 % of 2r under projective
/// dynamics, 4 at 98 % with the energy falling every step, 20 made BDF2 gain energy (181 J to
/// 358 J).
const SUPPORT_GAIN: f64 = 4.0;

/// The over-relaxation g from which a particle's change of force enters the line search:
/// springs at least as stiff, on the step's scale, as the particle's own inertia
/// (ĥ² Σk ≥ s m). Below it each particle moves on its own within a step, its own mass is its
/// step already, and the search only stirred a resting stack (two soft boxes at 1e-4 s kept
/// 5.6e-6 J of motion after 5 s, against 2.5e-14 J; `docs/performance-log.md`, 2026-12-07).
const LINE_SEARCH_FROM: f64 = 2.0;

/// The contact forces that the solves of projective dynamics, BDF2 and implicit Euler build
/// up over their iterations, so that their global solves see the support that contact gives a
/// particle, and the bodies above it rest on it.
///
/// Why: those solves are global (a factor, a conjugate gradient) and know nothing of contact.
/// Holding their iterate out of the surfaces after each solve is not enough at a frame's
/// step: the next solve pulls the particles back in by the weight above them, and the
/// projection's fixed point is not the constrained step (30 and 100 iterations of projective
/// dynamics left the pile at 354 J and 220 J from 181 J).
///
/// How: a particle pushed by Δ after a solve gains the force ρΔ with ρ = g s m/ĥ² (Uzawa's
/// update on the contact constraints, with the particle's own mass as its step: the solve's
/// matrix is at least s M/ĥ², so with g = 1 the update never moves a particle further than
/// Δ); one that moved away from its contact since the last projection loses that share along
/// its force, down to none. A particle joined to others by springs stiff at the step's scale
/// carries the whole body along, which its own mass underestimates, so its update is
/// over-relaxed: g = min([`SUPPORT_GAIN`], 1 + ĥ² Σk/(s m)), with Σk its springs' stiffness. A
/// lone particle keeps g = 1 (with 4 it overshot the surface and left it, every other
/// iteration). The push's tangential part, friction's hold, enters the force too. The forces
/// start from none each step: carried over from the last step (as rigid-body engines
/// warm-start their impulses), an impact's force launched the particles on the next step (the
/// pile rose to 893 J under projective dynamics and 11,932 J under BDF2).
///
/// Under projective dynamics, BDF2's backward Euler steps and implicit Euler's Newton steps,
/// [`Self::line_search`] then resizes each iteration's change of the forces (under implicit
/// Euler body by body, [`Self::search_by_body`]).
#[derive(Debug, Default, Clone)]
pub struct Support {
    /// Each particle's contact force, N.
    force: Vec<DVec2>,
    /// Each particle's over-relaxation g.
    gain: Vec<f64>,
    /// Whether each particle's change of force enters the line search ([`LINE_SEARCH_FROM`]).
    searched: Vec<bool>,
    /// The normal of each particle's last contact (a surface's, or a pair push's direction).
    normal: Vec<DVec2>,
    /// Where each particle was after the last projection.
    last: Vec<DVec2>,
    /// The iterate before this projection.
    before: Vec<DVec2>,
    /// The obstacle whose surface last held each particle ([`NO_OBSTACLE`]: the ground, a
    /// pair, or none), and the push of the last projection.
    obstacle: Vec<u32>,
    push: Vec<DVec2>,
    /// The last projection's s/ĥ².
    stiffness: f64,
    /// Each particle's body for the line search ([`Self::search_by_body`]): all 0, one body,
    /// unless a method asks for each body alone.
    body: Vec<u32>,
    /// Each body's free particles' mass, kg: the line search's bound ([`Self::line_search`]).
    free_mass: Vec<f64>,
    /// The line search's sums (descent, curvature, changed mass) and step α, body by body.
    sums: Vec<(f64, f64, f64)>,
    alpha: Vec<f64>,
    /// The change of each particle's force in the last projection, where it enters the line
    /// search (zero elsewhere).
    change: Vec<DVec2>,
    /// How much of each particle's force the last projection eased away: the solve before it
    /// still carried that much ([`Self::note_reactions`]).
    eased: Vec<DVec2>,
    /// Whether a projection of this step has pushed any particle ([`Self::acted`]).
    acted: bool,
    /// The surface each particle last touched in a projection's earlier passes
    /// ([`InSolve::project`]).
    touched: Vec<Option<Held>>,
}

/// No obstacle holds the particle.
const NO_OBSTACLE: u32 = u32::MAX;

impl Support {
    /// Readies the buffers for a step of the state's particles starting from `start`, with no
    /// force; `h2_over_s` is ĥ²/s.
    pub(crate) fn start(&mut self, s: &State, start: &[DVec2], h2_over_s: f64) {
        let n = start.len();
        let free = s.mass.iter().zip(&s.inv_mass).filter(|(_, w)| **w != 0.0);
        self.body.clear();
        self.body.resize(n, 0);
        self.free_mass.clear();
        self.free_mass.push(free.map(|(m, _)| m).sum());
        self.force.clear();
        self.force.resize(n, DVec2::ZERO);
        self.gain.clear();
        self.gain.resize(n, 0.0);
        self.normal.clear();
        self.normal.resize(n, DVec2::ZERO);
        for sp in &s.springs {
            self.gain[sp.a as usize] += sp.k;
            self.gain[sp.b as usize] += sp.k;
        }
        self.searched.clear();
        self.searched.resize(n, false);
        for ((g, &m), searched) in self.gain.iter_mut().zip(&s.mass).zip(&mut self.searched) {
            let stiff = 1.0 + h2_over_s * *g / m;
            *searched = stiff >= LINE_SEARCH_FROM;
            *g = stiff.min(SUPPORT_GAIN);
        }
        self.last.clear();
        self.last.extend_from_slice(start);
        self.obstacle.clear();
        self.obstacle.resize(n, NO_OBSTACLE);
        self.push.clear();
        self.push.resize(n, DVec2::ZERO);
        self.change.clear();
        self.change.resize(n, DVec2::ZERO);
        self.eased.clear();
        self.eased.resize(n, DVec2::ZERO);
        self.acted = false;
    }

    /// Notes, for the obstacles that stand for bodies, the impulse each gave its particles
    /// in the step ([`super::reaction`]): the contact force of the solve's equation after its
    /// last projection (the force the last solve carried, plus the last push at the particle's
    /// own mass: the learned force, less the over-relaxation of the last push, plus what the
    /// last projection eased away) times the equation's step `h`, M (z − y)/h² = f. That is
    /// the momentum the contact gave the particle: h = dt under projective dynamics and
    /// implicit Euler; h = 2/3 dt under BDF2, whose history forgets a held particle's jump, so
    /// that no later step carries a third of it again. Without the eased part, a soft ball
    /// hitting a free box head-on under projective dynamics with the line search, whose steps
    /// lift some particles off their contact by the last projection, lost 7.9e-4 of the
    /// pair's momentum (2.1e-3 of the impact step's impulse).
    pub(crate) fn note_reactions(&self, c: &InSolve, mass: &[f64], h: f64) {
        if !c.notes() {
            return;
        }
        for (i, f) in self.force.iter().enumerate() {
            let o = self.obstacle[i];
            if (*f == DVec2::ZERO && self.eased[i] == DVec2::ZERO) || o == NO_OBSTACLE {
                continue;
            }
            let held = self.held_force(i, mass[i]);
            c.note(
                o as usize,
                i,
                (self.last[i], self.normal[i]),
                held * h,
                None,
            );
        }
    }

    /// The normal of the contact holding particle `i` at the end of the last solve, if one
    /// does.
    pub(crate) fn held_along(&self, i: usize) -> Option<DVec2> {
        let held = self.force.get(i).is_some_and(|f| *f != DVec2::ZERO);
        held.then(|| self.normal[i])
    }

    /// Particle `i`'s contact with an obstacle at the end of the step's last solve, if one held
    /// it: the obstacle, the surface's normal, and the contact force of the solve's equation
    /// (as [`Self::note_reactions`] reads it), `mass` the particle's.
    pub(crate) fn on_obstacle(&self, i: usize, mass: f64) -> Option<(usize, DVec2, DVec2)> {
        let o = *self.obstacle.get(i)?;
        let force = self.held_force(i, mass);
        (o != NO_OBSTACLE && force != DVec2::ZERO).then(|| (o as usize, self.normal[i], force))
    }

    /// Particle `i`'s contact force in the solve's equation after the last projection, `mass`
    /// the particle's: the learned force, less the over-relaxation of the last push, plus what
    /// the last projection eased away (see [`Self::note_reactions`]).
    fn held_force(&self, i: usize, mass: f64) -> DVec2 {
        let own = self.push[i] * ((self.gain[i] - 1.0) * self.stiffness * mass);
        self.force[i] - own + self.eased[i]
    }

    /// Particle `i`'s contact force, N (none where no contact acted this step).
    pub(crate) fn force(&self, i: usize) -> DVec2 {
        self.force.get(i).copied().unwrap_or(DVec2::ZERO)
    }

    /// No contact this step: no force.
    pub(crate) fn start_without(&mut self) {
        self.force.clear();
        self.acted = false;
    }

    /// Whether the contact acted in this step's solve: some projection pushed a particle.
    pub(crate) fn acted(&self) -> bool {
        self.acted
    }

    /// Adds each particle's force times `scale` (ĥ² for a residual in force·ĥ², ĥ for an
    /// impulse) to `out`.
    pub(crate) fn add_to(&self, out: &mut [DVec2], scale: f64) {
        for (o, f) in out.iter_mut().zip(&self.force) {
            *o += *f * scale;
        }
    }

    /// The iterate `x`, kept out of contact by `c`, and the forces learned from the push:
    /// `stiffness` is s/ĥ² (the mass of the solve's matrix per kilogram and square metre).
    /// Notes the change of the forces that the line search may resize
    /// ([`Self::line_search`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn project(
        &mut self,
        c: &InSolve,
        x: &mut [DVec2],
        from: &[DVec2],
        mass: &[f64],
        w: &[f64],
        scratch: &mut [DVec2],
        stiffness: f64,
    ) {
        self.before.clear();
        self.before.extend_from_slice(x);
        self.stiffness = stiffness;
        self.change.fill(DVec2::ZERO);
        self.eased.fill(DVec2::ZERO);
        let Support {
            force,
            gain,
            normal,
            last,
            before,
            obstacle,
            push: pushed,
            change,
            eased,
            acted,
            searched,
            touched,
            ..
        } = self;
        c.project(x, from, w, (scratch, touched), |i, x, held| {
            let push = x - before[i];
            if push == DVec2::ZERO && held.is_none() && force[i] == DVec2::ZERO {
                // Neither touching nor held: nothing to learn, and nothing read until a push
                // writes it all (most of a cloth above the ground, at every iteration).
                return;
            }
            // The surface's normal, or a pair's push when no surface touched the particle.
            if let Some(n) = held.map(|h| h.normal).or_else(|| push.try_normalize()) {
                normal[i] = n;
            }
            if let Some(h) = held {
                obstacle[i] = h.obstacle.map_or(NO_OBSTACLE, |o| o as u32);
            } else if push != DVec2::ZERO {
                obstacle[i] = NO_OBSTACLE;
            }
            pushed[i] = push;
            *acted |= push != DVec2::ZERO;
            let rho = gain[i] * stiffness * mass[i];
            let f = &mut force[i];
            if push != DVec2::ZERO {
                *f += push * rho;
                if searched[i] {
                    change[i] = push * rho;
                }
            } else if *f != DVec2::ZERO {
                // Moved away from the contact since the last projection: the force eases.
                let along = *f / f.length();
                let away = (x - last[i]).dot(along);
                if away > 0.0 {
                    // (`away * rho` rounds otherwise: implicit Euler's and BDF2's results keep
                    // their bits with the product in this order.)
                    let left = (f.length() - away * gain[i] * stiffness * mass[i]).max(0.0);
                    eased[i] = *f - along * left;
                    *f = along * left;
                }
            }
            last[i] = x;
        });
    }

    /// ĥ² times the change δf of the forces that the last projection noted for the line
    /// search, into `out`; whether there is any. The solve's answer to it, w = Ã⁻¹ ĥ² δf, is
    /// how the iterate would move under it: [`Self::line_search`] reads it.
    pub(crate) fn change_to_answer(&self, h2: f64, out: &mut [DVec2]) -> bool {
        let mut any = false;
        for (o, &d) in out.iter_mut().zip(&self.change) {
            *o = d * h2;
            any |= d != DVec2::ZERO;
        }
        any
    }

    /// From this step's start on, [`Self::line_search`] takes each body (particles joined by
    /// springs) alone, each with its own step α and its own mass as the bound. Why: bodies
    /// apart share no row of the solve's matrix, so the search's objective is their sum, and
    /// one α for all of them let one body's contact size another's. Under implicit Euler a
    /// box wedged at the `slope`'s foot so set the forces holding the other box on its gentle
    /// slope, which then crept 3.7 mm in 2 s at 1/30 s (1e-9 m alone;
    /// `docs/performance-log.md`, 2026-12-08).
    pub(crate) fn search_by_body(&mut self, s: &State) {
        let n = s.x.len();
        self.body = super::groups::bodies(&s.springs, n);
        self.free_mass.clear();
        self.free_mass.resize(n, 0.0);
        for ((&b, &m), &w) in self.body.iter().zip(&s.mass).zip(&s.inv_mass) {
            if w != 0.0 {
                self.free_mass[b as usize] += m;
            }
        }
    }

    /// The step α along the last projection's change δf of the forces, given `answer`, the
    /// solve's answer w to that change ([`Self::change_to_answer`]), with `mass` the particles'
    /// masses: the forces take α δf instead of δf, and the
    /// iterate `x` moves where the next solve would put it, from where the last solve left it
    /// (before the projection) by α w, body by body where [`Self::search_by_body`] asks.
    /// Returns the least α of a body that changed (1, and nothing moved, where there was no
    /// change).
    ///
    /// α is the exact line search on the contact's dual problem (the forces' own, for which the
    /// iterate's violation of the contacts is the gradient) along δf: Σ δf·δf/ρ over Σ δf·w,
    /// with ρ = g s m/ĥ² the update that made δf. It is held to at most the free particles'
    /// mass over the changed particles' g m, what stopping them all as one rigid body would
    /// take: answered by a stiff body's bending alone, a few particles would learn the force
    /// that crushes it (a soft box thrown at a wall at 10 m/s at 1/60 s, its front column's
    /// forces so learned, rose from 25 J to 333 J and never came to rest; held, it peaks at
    /// 30 J, against 34 J before the line search). A strip two rows deep landing flat takes α = 1/2 of
    /// its lower row's fourfold update (twice that row's mass, the strip's), a box eight rows
    /// high resting on its bottom row α = 2.
    pub(crate) fn line_search(&mut self, x: &mut [DVec2], mass: &[f64], answer: &[DVec2]) -> f64 {
        self.sums.clear();
        self.sums.resize(self.free_mass.len(), (0.0, 0.0, 0.0));
        let mut any = false;
        for (i, d) in self.change.iter().enumerate() {
            if *d != DVec2::ZERO {
                let g = self.gain[i];
                let (descent, curvature, changed) = &mut self.sums[self.body[i] as usize];
                *descent += d.length_squared() / (g * self.stiffness * mass[i]);
                *curvature += d.dot(answer[i]);
                *changed += g * mass[i];
                any = true;
            }
        }
        if !any {
            return 1.0;
        }
        self.alpha.clear();
        let mut least = f64::INFINITY;
        for (&(descent, curvature, changed), &free) in self.sums.iter().zip(&self.free_mass) {
            let alpha = (descent / curvature).min(free / changed);
            let alpha = if changed != 0.0 && alpha.is_finite() && alpha > 0.0 {
                alpha
            } else {
                1.0
            };
            if changed != 0.0 {
                least = least.min(alpha);
            }
            self.alpha.push(alpha);
        }
        let (body, alpha) = (&self.body, &self.alpha);
        for ((f, d), &b) in self.force.iter_mut().zip(&self.change).zip(body) {
            *f += *d * (alpha[b as usize] - 1.0);
        }
        for (((x, &before), &a), &b) in x.iter_mut().zip(&self.before).zip(answer).zip(body) {
            *x = before + a * alpha[b as usize];
        }
        least
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::block;
    use crate::solver::state::PackedSpring;

    /// A block of 3 × 8 particles, its bottom row pushed up by the ground by the same Δ, with a
    /// lone particle beside it (no springs: g = 1, outside the line search) pushed too.
    /// Answered as a rigid block would answer (each of its particles moved by the change's
    /// total over the block's mass: the matrix's s M/ĥ² alone), the step stops the block
    /// whole: α = 24/(3 · 4), and the block's forces sum to its mass times Δ s/ĥ². Answered as
    /// a stiff block would, its bottom row alone moving (as if each of its particles weighed
    /// 40 of them), the exact step, 10, is held to what stopping every free particle whole
    /// would take, 25/12. The iterate moves from where the solve left it by α w.
    #[test]
    fn the_line_search_stops_a_body_whole() {
        let (w, h) = (3u32, 8u32);
        let mut s = block(w, h, 0.0);
        s.x.push(DVec2::new(0.5, 0.0));
        s.v.push(DVec2::ZERO);
        s.f.push(DVec2::ZERO);
        s.mass.push(0.02);
        s.inv_mass.push(50.0);
        let n = s.x.len();
        let h2 = 1.0 / 900.0;
        let stiffness = 1.0 / h2;
        let up = DVec2::new(0.0, 1e-3);
        let bottom: Vec<usize> = (0..w as usize).chain([n - 1]).collect();
        let pushed = |support: &mut Support| {
            support.start(&s, &s.x, h2);
            support.stiffness = stiffness;
            support.before = s.x.clone();
            for &i in &bottom {
                let rho = support.gain[i] * stiffness * s.mass[i];
                support.force[i] = up * rho;
                if support.gain[i] >= LINE_SEARCH_FROM {
                    support.change[i] = up * rho;
                }
            }
        };
        let mut support = Support::default();
        pushed(&mut support);
        assert_eq!(support.gain[n - 1], 1.0);
        assert_eq!(support.gain[0], SUPPORT_GAIN);
        let mut rhs = vec![DVec2::ZERO; n];
        assert!(support.change_to_answer(h2, &mut rhs));
        assert_eq!(rhs[n - 1], DVec2::ZERO);
        let block = 0.02 * (w * h) as f64;
        let total: DVec2 = rhs.iter().sum();
        let rigid: Vec<DVec2> = (0..n)
            .map(|i| {
                if i < n - 1 {
                    total / block
                } else {
                    DVec2::ZERO
                }
            })
            .collect();
        let mut x = s.x.clone();
        let alpha = support.line_search(&mut x, &s.mass, &rigid);
        assert!((alpha - 2.0).abs() < 1e-12, "{alpha}");
        let held: DVec2 = support.force[..n - 1].iter().sum();
        let whole = up * (block * stiffness);
        assert!(
            (held - whole).length() < 1e-9 * whole.length(),
            "{held} against {whole}"
        );
        // The lone particle keeps its plain update, and stays where the solve left it.
        assert_eq!(support.force[n - 1], up * (stiffness * 0.02));
        assert_eq!(x[n - 1], s.x[n - 1]);
        assert!((x[5] - (s.x[5] + rigid[5] * alpha)).length() < 1e-15);
        // A stiff block: the step held to the free particles' mass over the row's g m.
        pushed(&mut support);
        let stiff: Vec<DVec2> = rhs.iter().map(|r| *r / (0.02 * 40.0)).collect();
        let alpha = support.line_search(&mut x, &s.mass, &stiff);
        assert!((alpha - 25.0 / 12.0).abs() < 1e-12, "{alpha}");
    }

    /// Two 3 × 8 blocks side by side, no spring between them, each pushed up on its bottom row
    /// by the same Δ; the solve answers the first as a rigid block (its exact step 2) and the
    /// second as a block whose bottom row weighs four particles each (its exact step 1, under
    /// its bound of 2). Searched body by body, each takes its own step: the first stops whole,
    /// the second keeps its update, and the least step comes back. One search for both gives
    /// them one step.
    #[test]
    fn the_line_search_by_body_sizes_each_body_alone() {
        let (w, h) = (3u32, 8u32);
        let one = (w * h) as usize;
        let mut s = block(w, h, 0.0);
        let other = block(w, h, 0.0);
        s.x.extend(other.x.iter().map(|p| *p + DVec2::new(0.1, 0.0)));
        s.v.extend(&other.v);
        s.f.extend(&other.f);
        s.mass.extend(&other.mass);
        s.inv_mass.extend(&other.inv_mass);
        s.springs
            .extend(other.springs.iter().map(|sp| PackedSpring {
                a: sp.a + one as u32,
                b: sp.b + one as u32,
                ..*sp
            }));
        let n = s.x.len();
        let h2 = 1.0 / 900.0;
        let stiffness = 1.0 / h2;
        let up = DVec2::new(0.0, 1e-3);
        let bottoms: Vec<usize> = (0..w as usize).chain(one..one + w as usize).collect();
        let pushed = |support: &mut Support, by_body: bool| {
            support.start(&s, &s.x, h2);
            if by_body {
                support.search_by_body(&s);
            }
            support.stiffness = stiffness;
            support.before = s.x.clone();
            for &i in &bottoms {
                let rho = support.gain[i] * stiffness * s.mass[i];
                support.force[i] = up * rho;
                support.change[i] = up * rho;
            }
        };
        let mut support = Support::default();
        pushed(&mut support, true);
        let mut rhs = vec![DVec2::ZERO; n];
        assert!(support.change_to_answer(h2, &mut rhs));
        let mass = 0.02 * one as f64;
        let total: DVec2 = rhs[..one].iter().sum();
        let answer: Vec<DVec2> = (0..n)
            .map(|i| {
                if i < one {
                    total / mass
                } else {
                    rhs[i] / (0.02 * 4.0)
                }
            })
            .collect();
        let mut x = s.x.clone();
        let least = support.line_search(&mut x, &s.mass, &answer);
        assert!((least - 1.0).abs() < 1e-12, "{least}");
        let whole = up * (mass * stiffness);
        let held: DVec2 = support.force[..one].iter().sum();
        assert!((held - whole).length() < 1e-9 * whole.length(), "{held}");
        let kept: DVec2 = support.force[one..].iter().sum();
        let update = up * (SUPPORT_GAIN * stiffness * 0.02 * w as f64);
        assert!((kept - update).length() < 1e-9 * update.length(), "{kept}");
        // One search for both: the same step for each.
        pushed(&mut support, false);
        support.line_search(&mut x, &s.mass, &answer);
        let (a, b): (DVec2, DVec2) = (
            support.force[..one].iter().sum(),
            support.force[one..].iter().sum(),
        );
        assert!((a - b).length() < 1e-9 * a.length(), "{a} against {b}");
    }
}
