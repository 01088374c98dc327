//! Where a descent starts when a body lands: the particles whose start lies inside a surface,
//! taken in groups joined by springs, each group held back along its way to where the first of
//! it touches, so that the group lands together and keeps its shape.
//!
//! Why: vertex block descent (`methods::vbd`) starts from each particle's inertial guess, and
//! holds each vertex step out of the surfaces on its own. At a frame's step a falling layer's
//! guess lies wholly under the ground, so each row was held out on the ground's line: a strip
//! of cloth two particles deep (1 cm) dropped 0.2 m flat lost its height, its energy rose from
//! 3.9 J to 34.4 J at 1/60 and 1/30 s, and at 1/30 s every one of its 47 cells turned over; the
//! `soft_box` at 1/30 s rose from 38.4 J to 89.2 J and turned 7 of its 49 cells
//! (`docs/performance-log.md`, 2026-12-07). Block descent moves a stiff body as a whole only
//! slowly, so where it starts is where it lands.
//!
//! How: a particle whose guess the surfaces push out by a depth d, while it comes at them by
//! a (its way from the step's start, along the surface's normal), could go the share 1 − d/a
//! of its way. Each group of such particles joined by springs goes the least share of any of
//! them, so that the first to touch starts on its surface and the rest where the body held
//! them, a rung above. A particle that a spring stood upright on at the step's start (within
//! 60° of the normal), whose guess would keep less than half of that height above it, is held
//! back with the group below it ([`Landing::bring_down`]): a box's upper rows, their guesses
//! clear of the ground, would otherwise start under its held-back lower rows. The share is of
//! the whole way, along the surface too: held back along the normals alone, the pile's boxes at
//! 1/30 s gained energy as they settled (180.6 J to 187.4 J, and 154 J at 6 s against 72 J). A
//! particle resting on a surface comes at it by nothing and starts where its guess is, as does
//! every particle clear of the surfaces.

use super::groups::{join, root};
use super::inside::InSolve;
use crate::solver::state::State;
use glam::DVec2;

/// The buffers of [`Landing::hold_back`], kept from step to step.
#[derive(Debug, Default, Clone)]
pub(crate) struct Landing {
    /// Each particle's share of its approach ([`NOT_LANDING`] where it is not landing), then
    /// its group's least share.
    share: Vec<f64>,
    /// The normal of the surface each landing particle came at (or, for one the body brings
    /// down onto it, the normal of the particle below it).
    normal: Vec<DVec2>,
    /// Union–find over the landing particles: each one's group.
    group: Vec<u32>,
}

/// The share of a particle that is not landing.
const NOT_LANDING: f64 = 2.0;

impl Landing {
    /// Holds back the guesses `x` of the particles landing on `c`'s surfaces in a step from
    /// the state's positions (see the module's notes). Returns how many were held back.
    pub(crate) fn hold_back(&mut self, x: &mut [DVec2], s: &State, c: &InSolve) -> usize {
        let n = x.len();
        self.share.clear();
        self.share.resize(n, NOT_LANDING);
        self.normal.resize(n, DVec2::ZERO);
        let mut landing = 0;
        for (i, (&guess, &from)) in x.iter().zip(&s.x).enumerate() {
            if s.inv_mass[i] == 0.0 {
                continue;
            }
            let mut out = guess;
            let Some(held) = c.keep_out(i, &mut out, from) else {
                continue;
            };
            let approach = -held.normal.dot(guess - from);
            let depth = held.normal.dot(out - guess);
            if approach <= 0.0 || depth <= 0.0 {
                continue;
            }
            self.share[i] = (1.0 - depth / approach).clamp(0.0, 1.0);
            self.normal[i] = held.normal;
            landing += 1;
        }
        if landing == 0 {
            return 0;
        }
        let group = &mut self.group;
        group.clear();
        group.extend(0..n as u32);
        for sp in &s.springs {
            let (a, b) = (sp.a as usize, sp.b as usize);
            if self.share[a] != NOT_LANDING && self.share[b] != NOT_LANDING {
                join(group, sp.a, sp.b);
            }
        }
        // Each group's least share, kept at its root (a root's own share is never larger:
        // it is lowered to the least of its group before any other member reads it).
        for i in 0..n {
            if self.share[i] != NOT_LANDING {
                let r = root(group, i as u32) as usize;
                self.share[r] = self.share[r].min(self.share[i]);
            }
        }
        // Each member held back to its group's least share, which it keeps for
        // [`Self::bring_down`].
        for (i, (guess, &from)) in x.iter_mut().zip(&s.x).enumerate() {
            if self.share[i] != NOT_LANDING {
                let least = self.share[root(group, i as u32) as usize];
                self.share[i] = least;
                *guess = from + (*guess - from) * least;
            }
        }
        landing + self.bring_down(x, s)
    }

    /// Holds back, with the group below them, the particles that the body would otherwise
    /// carry down through it: where a spring stood upright on a held-back particle at the
    /// step's start, and the other end's guess keeps less than half of that height above it
    /// (a box's third row, whose guess is clear of the ground but under its second row, held
    /// back above it: the box at 1/30 s turned 7 of its cells). Returns how many it held back.
    fn bring_down(&mut self, x: &mut [DVec2], s: &State) -> usize {
        let mut brought = 0;
        for _ in 0..SWEEPS {
            let mut more = false;
            for sp in &s.springs {
                let (a, b) = (sp.a as usize, sp.b as usize);
                for (low, high) in [(a, b), (b, a)] {
                    if self.share[low] == NOT_LANDING
                        || self.share[high] != NOT_LANDING
                        || s.inv_mass[high] == 0.0
                    {
                        continue;
                    }
                    let n = self.normal[low];
                    let rung = s.x[high] - s.x[low];
                    let height = n.dot(rung);
                    if height > STANDING * rung.length() && n.dot(x[high] - x[low]) < KEEP * height
                    {
                        let least = self.share[low];
                        x[high] = s.x[high] + (x[high] - s.x[high]) * least;
                        self.share[high] = least;
                        self.normal[high] = n;
                        brought += 1;
                        more = true;
                    }
                }
            }
            if !more {
                break;
            }
        }
        brought
    }
}

/// How upright a spring must stand on a held-back particle, at the step's start, for its other
/// end to be held back with it: its height along the normal at least this share of its length
/// (within 60° of the normal). A cloth lying along a surface has no height to keep.
const STANDING: f64 = 0.5;

/// The share of that height below which the other end is held back.
const KEEP: f64 = 0.5;

/// The most sweeps over the springs that bring a body down (each brings at least one more row
/// of a body whose springs come in an unlucky order).
const SWEEPS: usize = 16;

#[cfg(test)]
mod tests {
    use super::super::pass::{Surroundings, reaches};
    use super::*;
    use crate::solver::fixtures::block;

    /// A 3 × 4 block of particles a centimetre apart (rows listed bottom first), falling 3 cm
    /// in the step from 1.5 cm above the ground: its two lower rows' guesses lie under the
    /// ground, and the two upper rows', clear of it, under the rows below them once those are
    /// held back. Every row is held back to the share of the way at which the bottom row
    /// touches, so the block keeps its shape. A block resting on the ground (no way to go) is
    /// left alone.
    #[test]
    fn a_falling_block_starts_whole_where_it_first_touches() {
        let (w, h) = (3u32, 4u32);
        let s = block(w, h, 0.015);
        let around = Surroundings {
            obstacles: &[],
            ground: Some(0.0),
            settings: None,
            reactions: None,
        };
        let lead = around.leads(1.0 / 30.0);
        let reach = reaches(&[], 0.0);
        let c = InSolve::new(&around, None, None, &[], (&reach, &lead), 1.0 / 30.0, true).unwrap();
        let fall = DVec2::new(0.0, -0.03);
        let mut x: Vec<DVec2> = s.x.iter().map(|p| *p + fall).collect();
        let held = Landing::default().hold_back(&mut x, &s, &c);
        assert_eq!(held, (w * h) as usize);
        let share = 0.5;
        for (i, (p, p0)) in x.iter().zip(&s.x).enumerate() {
            let want = *p0 + fall * share;
            assert!(
                (*p - want).length() < 1e-15,
                "particle {i}: {p} against {want}"
            );
        }
        let mut x = s.x.clone();
        let resting: Vec<DVec2> = s.x.iter().map(|p| *p - DVec2::new(0.0, 0.015)).collect();
        let s = State {
            x: resting.clone(),
            ..s
        };
        x.copy_from_slice(&resting);
        assert_eq!(Landing::default().hold_back(&mut x, &s, &c), 0);
        assert_eq!(x, resting);
    }
}
