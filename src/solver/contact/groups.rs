//! Particles joined into groups by springs: a union–find over particle indices, each group
//! named by its smallest index. The outlines and the bodies that slide as a whole find bodies
//! with it (every spring joins, [`bodies`]), a landing body's start its landing groups (a
//! spring joins two particles that both land), and the contact pass after a backward Euler step
//! the bodies it stops (`methods::projective`).

use crate::solver::state::PackedSpring;

/// The root of `i`'s group in `parent`, halving the path on the way.
pub(crate) fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

/// Joins the groups of `a` and `b` in `parent`, under the smaller root.
pub(crate) fn join(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (root(parent, a), root(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// Each of `n` particles' body: the smallest index among the particles `springs` join it to.
pub(crate) fn bodies(springs: &[PackedSpring], n: usize) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for sp in springs {
        join(&mut parent, sp.a, sp.b);
    }
    (0..n as u32).map(|i| root(&mut parent, i)).collect()
}
