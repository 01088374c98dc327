//! What the particles' contacts give back to the obstacles: the equal and opposite impulse of
//! every particle–obstacle contact, so that an obstacle standing for a body of another engine
//! (a dynamic rigid body) can be pushed by the particles.
//!
//! Why a log of impulses and not forces: each method changes a particle's momentum by contact
//! in its own place. The contact pass and the velocity pass after a solve change its velocity
//! by Δv (an impulse m Δv); XPBD pushes its positions inside a substep of length hₛ, and the
//! push δx becomes the velocity δx/hₛ (an impulse m δx/hₛ). Each place notes the impulse it
//! gave, at the point of the surface it touched; the obstacle takes minus their sum. Springs
//! are internal and pass momentum only between particles, so the particles and the obstacles
//! together keep theirs.
//!
//! Why sorted before summing: the passes run on several threads, which note in no fixed order.
//! The impulses are summed in an order of their own values, so that the same step gives the
//! same bits however the threads ran.

use glam::DVec2;
use std::sync::Mutex;

/// What one obstacle took from the particles over the steps since it was last read.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Reaction {
    /// The sum of the impulses on the obstacle, N·s.
    pub impulse: DVec2,
    /// Their moment about the world's origin, Σ p × J, N·m·s: about a point c the moment is
    /// `moment - c.perp_dot(impulse)`.
    pub moment: f64,
    /// How many contacts gave them.
    pub contacts: u32,
}

impl Reaction {
    /// The angular impulse about the point `c`, N·m·s.
    pub fn moment_about(&self, c: DVec2) -> f64 {
        self.moment - c.perp_dot(self.impulse)
    }
}

/// One contact's impulse on its obstacle.
#[derive(Debug, Clone, Copy)]
struct Note {
    obstacle: u32,
    point: DVec2,
    impulse: DVec2,
}

/// The log of one step's contact impulses, and the reactions summed from it.
#[derive(Debug, Default)]
pub struct Reactions {
    notes: Mutex<Vec<Note>>,
    summed: Vec<Reaction>,
}

impl Reactions {
    /// Notes that a contact with obstacle `obstacle` at the surface point `point` changed a
    /// particle's momentum by `on_particle`: the obstacle takes minus that.
    pub(crate) fn note(&self, obstacle: usize, point: DVec2, on_particle: DVec2) {
        if on_particle == DVec2::ZERO {
            return;
        }
        let note = Note {
            obstacle: obstacle as u32,
            point,
            impulse: -on_particle,
        };
        // A poisoned lock only means another thread panicked mid-push; the log is still a
        // list of whole notes.
        let mut notes = self.notes.lock().unwrap_or_else(|e| e.into_inner());
        notes.push(note);
    }

    /// Sums the notes taken so far into the reactions of `obstacles` obstacles, in an order of
    /// their values (the same bits whatever order the threads noted in), and clears the log.
    pub fn gather(&mut self, obstacles: usize) {
        if self.summed.len() != obstacles {
            self.summed.resize(obstacles, Reaction::default());
        }
        let notes = self.notes.get_mut().unwrap_or_else(|e| e.into_inner());
        if notes.is_empty() {
            return;
        }
        let key = |n: &Note| {
            (
                n.obstacle,
                n.point.x.to_bits(),
                n.point.y.to_bits(),
                n.impulse.x.to_bits(),
                n.impulse.y.to_bits(),
            )
        };
        notes.sort_unstable_by_key(key);
        for n in notes.drain(..) {
            if let Some(r) = self.summed.get_mut(n.obstacle as usize) {
                r.impulse += n.impulse;
                r.moment += n.point.perp_dot(n.impulse);
                r.contacts += 1;
            }
        }
    }

    /// The reactions summed since the last [`Self::take`], one per obstacle.
    pub fn summed(&self) -> &[Reaction] {
        &self.summed
    }

    /// Returns the reactions summed so far and starts again from none.
    pub fn take(&mut self) -> Vec<Reaction> {
        let n = self.summed.len();
        std::mem::replace(&mut self.summed, vec![Reaction::default(); n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sum is the same bits whatever order the notes came in, and the moment about a point
    /// is the moment of the impulses about it.
    #[test]
    fn the_sum_does_not_depend_on_the_order_of_the_notes() {
        let notes: Vec<(usize, DVec2, DVec2)> = (0..50)
            .map(|i| {
                let t = i as f64 * 0.37;
                (
                    i % 2,
                    DVec2::new(t.sin(), t.cos() * 3.0),
                    DVec2::new(1e-3 * t.cos(), 0.1 + t),
                )
            })
            .collect();
        let mut forward = Reactions::default();
        for &(o, p, j) in &notes {
            forward.note(o, p, j);
        }
        forward.gather(2);
        let mut backward = Reactions::default();
        for &(o, p, j) in notes.iter().rev() {
            backward.note(o, p, j);
        }
        backward.gather(2);
        assert_eq!(forward.summed(), backward.summed());
        let c = DVec2::new(0.3, -0.2);
        let direct: f64 = notes
            .iter()
            .filter(|n| n.0 == 1)
            .map(|&(_, p, j)| (p - c).perp_dot(-j))
            .sum();
        let r = forward.summed()[1];
        assert!((r.moment_about(c) - direct).abs() < 1e-12 * direct.abs().max(1.0));
        assert_eq!(r.contacts, 25);
    }
}
