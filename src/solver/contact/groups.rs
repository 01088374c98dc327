//! Particles joined into groups by springs: a union–find over particle indices, each group
//! named by its smallest index. The outlines find bodies with it (every spring joins), and a
//! landing body's start its landing groups (a spring joins two particles that both land), and
//! the contact pass after a backward Euler step the bodies it stops (`methods::projective`).

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
