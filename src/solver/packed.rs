//! The records that every room of the core reads, kept below all of them: a spring packed
//! between two dense particle indices. The state (`State`) holds them in its
//! spring array; the force kernels, the thread split of the pair passes, the materials and the
//! methods read them.

/// A spring between two dense particle indices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackedSpring {
    /// Dense index of one end.
    pub a: u32,
    /// Dense index of the other end.
    pub b: u32,
    /// Rest length, m.
    pub rest: f64,
    /// The stiffness in effect: the spring's own, or the global override.
    pub k: f64,
}
