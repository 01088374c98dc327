//! Expands [`Generator`]s into explicit particles and springs.
//!
//! The expansion is streamed: [`Scene::particle_defs`] and [`Scene::spring_defs`] yield the
//! scene's particles and springs one by one, each with its exact count, so that loading a cloth
//! of millions of springs spawns them straight from the generator (the ECS reserves exactly
//! what they need) instead of first building the whole list. [`Scene::expand`] collects them
//! where a list is wanted.

use super::format::*;
use bevy::math::DVec2;

/// Particles and springs of a scene with every generator expanded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Expanded {
    /// Explicit then generated particles.
    pub particles: Vec<ParticleDef>,
    /// Explicit then generated springs, by particle index.
    pub springs: Vec<SpringDef>,
    /// Explicit then generated gas-filled loops.
    pub pressure: Vec<PressureDef>,
}

impl Scene {
    /// The scene's explicit particles and springs followed by the generated ones.
    pub fn expand(&self) -> Expanded {
        Expanded {
            particles: self.particle_defs().collect(),
            springs: self.spring_defs().collect(),
            pressure: self.pressure_defs(),
        }
    }

    /// The scene's gas-filled loops: its `pressure` entries, then each ring's with gas.
    pub fn pressure_defs(&self) -> Vec<PressureDef> {
        let mut out = self.pressure.clone();
        for (g, base) in self.generators_at() {
            if let Generator::Ring {
                segments, pressure, ..
            } = *g
                && pressure > 0.0
            {
                out.push(PressureDef {
                    particles: (base..base + segments).collect(),
                    nrt: pressure,
                });
            }
        }
        out
    }

    /// Whether some spring has a material beyond the Hooke spring (a dashpot of its own, a
    /// muscle, plasticity), without expanding the generators.
    pub fn has_spring_materials(&self) -> bool {
        self.springs.iter().any(SpringDef::has_material)
            || self.generate.iter().any(|g| match *g {
                Generator::Grid {
                    damping, plastic, ..
                } => damping.is_some() || plastic.is_some(),
                Generator::Ring { damping, .. } => damping.is_some(),
                Generator::Chain { .. } => false,
            })
    }

    /// How many particles and springs the scene has, generators included (saturating).
    pub fn counts(&self) -> (usize, usize) {
        let explicit = (self.particles.len(), self.springs.len());
        self.generate.iter().fold(explicit, |(p, s), g| {
            let (gp, gs) = g.counts();
            (p.saturating_add(gp), s.saturating_add(gs))
        })
    }

    /// The explicit particles, then each generator's, in index order.
    pub fn particle_defs(&self) -> impl Iterator<Item = ParticleDef> + '_ {
        let generated = self.generate.iter().flat_map(|g| g.particle_defs());
        Exact::new(
            self.particles.iter().copied().chain(generated),
            self.counts().0,
        )
    }

    /// Each generator with the index of its first particle: after the explicit particles and
    /// the generators before it.
    fn generators_at(&self) -> impl Iterator<Item = (&Generator, usize)> + '_ {
        self.generate.iter().scan(self.particles.len(), |base, g| {
            let at = *base;
            *base += g.counts().0;
            Some((g, at))
        })
    }

    /// Where the scene places particle `i` (explicit or generated), if there is one.
    pub fn position(&self, i: usize) -> Option<(f64, f64)> {
        if let Some(p) = self.particles.get(i) {
            return Some(p.pos);
        }
        let (g, base) = self
            .generators_at()
            .find(|(g, base)| i < base + g.counts().0)?;
        Some(g.position(i - base))
    }

    /// The explicit springs, then each generator's (by particle index, rest at the initial
    /// distance), in order. Every one has its rest length: an explicit spring written without
    /// one gets the distance between its ends where the scene places them.
    pub fn spring_defs(&self) -> impl Iterator<Item = SpringDef> + '_ {
        let explicit = self.springs.iter().map(|s| SpringDef {
            rest: s.rest.or_else(|| {
                let (a, b) = (self.position(s.a)?, self.position(s.b)?);
                Some((DVec2::from(a) - DVec2::from(b)).length())
            }),
            ..*s
        });
        let generated = self
            .generators_at()
            .flat_map(|(g, base)| g.spring_defs(base));
        Exact::new(explicit.chain(generated), self.counts().1)
    }
}

impl Generator {
    /// How many particles and springs this generator makes (for validation before expanding).
    pub fn counts(&self) -> (usize, usize) {
        match *self {
            Generator::Grid {
                cols, rows, shear, ..
            } => {
                let (c, r) = (cols.saturating_sub(1), rows.saturating_sub(1));
                let structural = c * rows + r * cols;
                (cols * rows, structural + if shear { 2 * c * r } else { 0 })
            }
            Generator::Chain { segments, .. } => (segments + 1, segments),
            Generator::Ring { segments, .. } => (segments, segments),
        }
    }

    /// The generator's particles, in index order.
    fn particle_defs(&self) -> impl Iterator<Item = ParticleDef> + '_ {
        let n = self.counts().0;
        (0..n).map(move |i| match *self {
            Generator::Grid {
                cols,
                mass,
                pin,
                vel,
                ..
            } => {
                let (r, c) = (i / cols, i % cols);
                let pinned = match pin {
                    Pin::None => false,
                    Pin::First => r == 0,
                    Pin::Ends => r == 0 && (c == 0 || c == cols - 1),
                    Pin::Left => c == 0,
                };
                ParticleDef {
                    pos: self.position(i),
                    vel: if pinned { (0.0, 0.0) } else { vel },
                    mass,
                    pinned,
                }
            }
            Generator::Chain {
                segments,
                mass,
                pin,
                ..
            } => ParticleDef {
                pos: self.position(i),
                vel: (0.0, 0.0),
                mass,
                pinned: match pin {
                    Pin::None => false,
                    Pin::First | Pin::Left => i == 0,
                    Pin::Ends => i == 0 || i == segments,
                },
            },
            Generator::Ring { mass, .. } => ParticleDef {
                pos: self.position(i),
                vel: (0.0, 0.0),
                mass,
                pinned: false,
            },
        })
    }

    /// The position of the generator's particle `i`.
    fn position(&self, i: usize) -> (f64, f64) {
        match *self {
            Generator::Grid {
                cols,
                rows,
                min,
                max,
                ..
            } => {
                let (w, h) = (max.0 - min.0, max.1 - min.1);
                let (r, c) = (i / cols, i % cols);
                let x = min.0 + c as f64 / (cols - 1) as f64 * w;
                let y = max.1 - r as f64 / (rows - 1) as f64 * h;
                (x, y)
            }
            Generator::Chain {
                from, to, segments, ..
            } => {
                let (a, b) = (DVec2::from(from), DVec2::from(to));
                let p = a + (b - a) * (i as f64 / segments as f64);
                (p.x, p.y)
            }
            Generator::Ring {
                center,
                radius,
                segments,
                ..
            } => {
                let t = std::f64::consts::TAU * i as f64 / segments as f64;
                (center.0 + radius * t.cos(), center.1 + radius * t.sin())
            }
        }
    }

    /// The generator's springs between its particles `base + i`, rest at the initial distance.
    fn spring_defs(&self, base: usize) -> impl Iterator<Item = SpringDef> + '_ {
        let (damping, plastic) = match *self {
            Generator::Grid {
                damping, plastic, ..
            } => (damping, plastic),
            Generator::Ring { damping, .. } => (damping, None),
            Generator::Chain { .. } => (None, None),
        };
        let spring = move |a: usize, b: usize, stiffness: f64| {
            let (pa, pb) = (self.position(a), self.position(b));
            let rest = (DVec2::from(pa) - DVec2::from(pb)).length();
            SpringDef {
                damping,
                plastic,
                ..SpringDef::new(base + a, base + b, rest, stiffness)
            }
        };
        let (cells, per_cell) = match *self {
            Generator::Grid { cols, rows, .. } => (cols * rows, 4),
            Generator::Chain { segments, .. } => (segments, 1),
            Generator::Ring { segments, .. } => (segments, 1),
        };
        (0..cells).flat_map(move |i| {
            let mut out = [None; 4];
            match *self {
                Generator::Grid {
                    cols,
                    rows,
                    stiffness,
                    shear,
                    ..
                } => {
                    // Per (r, c): right, down, and with shear both diagonals.
                    let (r, c) = (i / cols, i % cols);
                    if c + 1 < cols {
                        out[0] = Some(spring(i, i + 1, stiffness));
                    }
                    if r + 1 < rows {
                        out[1] = Some(spring(i, i + cols, stiffness));
                    }
                    if shear && r + 1 < rows && c + 1 < cols {
                        out[2] = Some(spring(i, i + cols + 1, stiffness));
                        out[3] = Some(spring(i + 1, i + cols, stiffness));
                    }
                }
                Generator::Chain { stiffness, .. } => out[0] = Some(spring(i, i + 1, stiffness)),
                Generator::Ring {
                    stiffness,
                    segments,
                    ..
                } => out[0] = Some(spring(i, (i + 1) % segments, stiffness)),
            }
            out.into_iter().take(per_cell).flatten()
        })
    }
}

/// An iterator whose length is known in advance (from [`Generator::counts`]) but not to the
/// iterator adapters that make it (`flat_map` cannot tell): it says its exact length, so that
/// a collect or a `spawn_batch` allocates once, exactly.
struct Exact<I> {
    inner: I,
    remaining: usize,
}

impl<I> Exact<I> {
    fn new(inner: I, len: usize) -> Self {
        Exact {
            inner,
            remaining: len,
        }
    }
}

impl<I: Iterator> Iterator for Exact<I> {
    type Item = I::Item;

    fn next(&mut self) -> Option<I::Item> {
        let item = self.inner.next();
        self.remaining = self.remaining.saturating_sub(item.is_some() as usize);
        item
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.remaining, Some(self.remaining))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each stream yields exactly the count it announces, generators of both kinds after
    /// explicit items, indices continuing across generators.
    #[test]
    fn streams_yield_their_counts_in_index_order() {
        let scene = Scene {
            particles: vec![ParticleDef {
                pos: (0.5, 0.5),
                vel: (0.0, 0.0),
                mass: 1.0,
                pinned: false,
            }],
            generate: vec![
                Generator::Chain {
                    from: (0.0, 0.5),
                    to: (1.0, 0.5),
                    segments: 3,
                    mass: 1.0,
                    stiffness: 1e3,
                    pin: Pin::Ends,
                },
                Generator::Grid {
                    cols: 3,
                    rows: 4,
                    min: (0.0, 0.0),
                    max: (1.0, 1.0),
                    mass: 2.0,
                    stiffness: 1e4,
                    shear: true,
                    pin: Pin::First,
                    vel: (0.1, 0.0),
                    damping: None,
                    plastic: None,
                },
            ],
            ..Scene::default()
        };
        let (np, ns) = scene.counts();
        assert_eq!((np, ns), (1 + 4 + 12, 3 + (2 * 4 + 3 * 3 + 2 * 2 * 3)));
        let particles = scene.particle_defs();
        assert_eq!(particles.size_hint(), (np, Some(np)));
        assert_eq!(particles.count(), np);
        let springs: Vec<SpringDef> = scene.spring_defs().collect();
        assert_eq!(springs.len(), ns);
        // The chain's springs join 1-2, 2-3, 3-4; the grid's first spring joins 5 and 6.
        let ends: Vec<(usize, usize)> = springs.iter().map(|s| (s.a, s.b)).collect();
        assert_eq!(&ends[..4], &[(1, 2), (2, 3), (3, 4), (5, 6)]);
        assert!(
            springs
                .iter()
                .all(|s| s.a < np && s.b < np && s.rest > Some(0.0))
        );
    }
}
