//! Expands [`Generator`]s into explicit particles and springs.

use super::format::*;
use bevy::math::DVec2;

/// Particles and springs of a scene with every generator expanded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Expanded {
    /// Explicit then generated particles.
    pub particles: Vec<ParticleDef>,
    /// Explicit then generated springs, by particle index.
    pub springs: Vec<SpringDef>,
}

impl Scene {
    /// The scene's explicit particles and springs followed by the generated ones.
    pub fn expand(&self) -> Expanded {
        let mut out = Expanded {
            particles: self.particles.clone(),
            springs: self.springs.clone(),
        };
        for g in &self.generate {
            g.expand_into(&mut out);
        }
        out
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
        }
    }

    fn expand_into(&self, out: &mut Expanded) {
        let base = out.particles.len();
        match *self {
            Generator::Grid {
                cols,
                rows,
                min,
                max,
                mass,
                stiffness,
                shear,
                pin,
                vel,
            } => {
                let (w, h) = (max.0 - min.0, max.1 - min.1);
                for r in 0..rows {
                    for c in 0..cols {
                        let pinned = match pin {
                            Pin::None => false,
                            Pin::First => r == 0,
                            Pin::Ends => r == 0 && (c == 0 || c == cols - 1),
                        };
                        let x = min.0 + c as f64 / (cols - 1) as f64 * w;
                        let y = max.1 - r as f64 / (rows - 1) as f64 * h;
                        out.particles.push(ParticleDef {
                            pos: (x, y),
                            vel: if pinned { (0.0, 0.0) } else { vel },
                            mass,
                            pinned,
                        });
                    }
                }
                let id = |r: usize, c: usize| base + r * cols + c;
                for r in 0..rows {
                    for c in 0..cols {
                        if c + 1 < cols {
                            push_spring(out, id(r, c), id(r, c + 1), stiffness);
                        }
                        if r + 1 < rows {
                            push_spring(out, id(r, c), id(r + 1, c), stiffness);
                        }
                        if shear && r + 1 < rows && c + 1 < cols {
                            push_spring(out, id(r, c), id(r + 1, c + 1), stiffness);
                            push_spring(out, id(r, c + 1), id(r + 1, c), stiffness);
                        }
                    }
                }
            }
            Generator::Chain {
                from,
                to,
                segments,
                mass,
                stiffness,
                pin,
            } => {
                let (a, b) = (DVec2::from(from), DVec2::from(to));
                for i in 0..=segments {
                    let p = a + (b - a) * (i as f64 / segments as f64);
                    let pinned = match pin {
                        Pin::None => false,
                        Pin::First => i == 0,
                        Pin::Ends => i == 0 || i == segments,
                    };
                    out.particles.push(ParticleDef {
                        pos: (p.x, p.y),
                        vel: (0.0, 0.0),
                        mass,
                        pinned,
                    });
                }
                for i in 0..segments {
                    push_spring(out, base + i, base + i + 1, stiffness);
                }
            }
        }
    }
}

/// Adds a spring whose rest length is the current distance of its ends.
fn push_spring(out: &mut Expanded, a: usize, b: usize, stiffness: f64) {
    let (pa, pb) = (out.particles[a].pos, out.particles[b].pos);
    let rest = (DVec2::from(pa) - DVec2::from(pb)).length();
    out.springs.push(SpringDef {
        a,
        b,
        stiffness,
        rest,
    });
}
