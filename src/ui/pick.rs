//! What is under the cursor: the particle to grab, pin or delete, the neighbours a click joins,
//! the springs a cut crosses. Queries go through uniform grids built from the solver's arrays
//! (what is drawn), rebuilt only when the solver changed since they were built: while paused,
//! editing click by click costs O(1) per neighbour and a cut O(springs near its path).

use crate::sim::Solver;
use crate::sim::grid::SpatialGrid;
use bevy::ecs::change_detection::Tick;
use bevy::math::DVec2;
use bevy::prelude::*;

/// The grids, and the solver change they were built for.
#[derive(Resource, Default)]
pub struct Picking {
    particles: Option<(Tick, f64, SpatialGrid<Entity>)>,
    springs: Option<(Tick, SpringGrid)>,
}

/// Spring midpoints in cells of the longest spring's length: a spring that crosses a segment
/// has its midpoint within half its length of it.
struct SpringGrid {
    reach: f64,
    cells: SpatialGrid<u32>,
}

impl Picking {
    fn particle_grid(&mut self, solver: &Res<Solver>, cell: f64) -> &mut SpatialGrid<Entity> {
        let tick = solver.last_changed();
        let fresh = self
            .particles
            .as_ref()
            .is_some_and(|(t, c, _)| *t == tick && *c == cell);
        if !fresh {
            let mut grid = SpatialGrid::new(cell);
            for (x, e) in solver.x.iter().zip(&solver.entities) {
                grid.insert(*x, *e);
            }
            self.particles = Some((tick, cell, grid));
        }
        &mut self.particles.as_mut().expect("just built").2
    }

    /// Every particle within `radius` of `at`, with its distance. `cell` is the grid's cell
    /// size (the scene's click radius); the grid is kept between queries of the same size.
    pub fn within(
        &mut self,
        solver: &Res<Solver>,
        at: DVec2,
        radius: f64,
        cell: f64,
    ) -> Vec<(Entity, f64)> {
        self.particle_grid(solver, cell).within(at, radius)
    }

    /// The particle nearest to `at` within `radius`.
    pub fn nearest(
        &mut self,
        solver: &Res<Solver>,
        at: DVec2,
        radius: f64,
        cell: f64,
    ) -> Option<Entity> {
        self.within(solver, at, radius, cell)
            .into_iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(e, _)| e)
    }

    /// Records a particle added since the grid was built, so that the next click sees it.
    pub fn note_added(&mut self, solver: &Res<Solver>, at: DVec2, e: Entity, cell: f64) {
        self.particle_grid(solver, cell).insert(at, e);
    }

    /// The springs (as solver indices) whose segments cross the segment from `p` to `q`.
    pub fn springs_crossing(&mut self, solver: &Res<Solver>, p: DVec2, q: DVec2) -> Vec<u32> {
        let tick = solver.last_changed();
        if self.springs.as_ref().is_none_or(|(t, _)| *t != tick) {
            self.springs = Some((tick, SpringGrid::build(solver)));
        }
        let grid = &self.springs.as_ref().expect("just built").1;
        let (min, max) = (p.min(q) - grid.reach, p.max(q) + grid.reach);
        let mut out = vec![];
        let mut test = |i: u32| {
            let s = &solver.springs[i as usize];
            if crosses(p, q, solver.x[s.a as usize], solver.x[s.b as usize]) {
                out.push(i);
            }
        };
        // A cell far smaller than the path (a scene of tiny springs and a fast stroke): every
        // spring is cheaper than every cell.
        if grid.cells.cells_in_box(min, max) > solver.springs.len() as f64 {
            (0..solver.springs.len() as u32).for_each(test);
        } else {
            grid.cells.in_box(min, max, |_, i| test(i));
        }
        out.sort_unstable();
        out
    }
}

impl SpringGrid {
    fn build(solver: &Solver) -> Self {
        let ends = |s: &crate::sim::PackedSpring| (solver.x[s.a as usize], solver.x[s.b as usize]);
        let longest = solver
            .springs
            .iter()
            .map(|s| {
                let (a, b) = ends(s);
                a.distance(b)
            })
            .filter(|l| l.is_finite())
            .fold(0.0, f64::max)
            .max(1e-4);
        let mut cells = SpatialGrid::new(longest);
        for (i, s) in solver.springs.iter().enumerate() {
            let (a, b) = ends(s);
            cells.insert((a + b) / 2.0, i as u32);
        }
        SpringGrid {
            reach: longest / 2.0,
            cells,
        }
    }
}

/// Does the segment p→q cross the segment a–b? a and b must lie strictly on opposite sides of
/// the line pq; p and q on opposite sides of the line ab, counting a point on it with the
/// positive side, so that a path of several segments through a point of ab crosses it once.
pub fn crosses(p: DVec2, q: DVec2, a: DVec2, b: DVec2) -> bool {
    let side = |o: DVec2, d: DVec2, x: DVec2| d.perp_dot(x - o);
    let (sa, sb) = (side(p, q - p, a), side(p, q - p, b));
    let (sp, sq) = (side(a, b - a, p), side(a, b - a, q));
    sa * sb < 0.0 && (sp < 0.0) != (sq < 0.0)
}

#[cfg(test)]
mod tests {
    use super::crosses;
    use bevy::math::DVec2;

    #[test]
    fn segments_cross_once_along_a_path() {
        let (a, b) = (DVec2::new(0.0, -1.0), DVec2::new(0.0, 1.0));
        let c = |x: f64, y: f64| DVec2::new(x, y);
        assert!(crosses(c(-1.0, 0.0), c(1.0, 0.0), a, b));
        assert!(!crosses(c(-1.0, 0.0), c(-0.5, 0.0), a, b));
        assert!(!crosses(c(-1.0, 2.0), c(1.0, 2.0), a, b), "past its end");
        // A path through a point of the spring: crossed by exactly one of its two segments.
        let path = [c(-1.0, 0.0), c(0.0, 0.0), c(1.0, 0.0)];
        let n = path
            .windows(2)
            .filter(|w| crosses(w[0], w[1], a, b))
            .count();
        assert_eq!(n, 1);
    }
}
