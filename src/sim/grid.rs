//! A uniform hash grid for "every particle within r of p" queries (adding a particle by click)
//! and "every item near this segment" (cutting springs): with cells of side r a point query
//! visits 3×3 cells, O(1) per neighbour instead of a scan of every particle.

use bevy::math::DVec2;
use bevy::platform::collections::HashMap;

#[derive(Debug, Clone)]
/// Items at points, hashed into square cells.
pub struct SpatialGrid<T> {
    cell: f64,
    cells: HashMap<(i64, i64), Vec<(DVec2, T)>>,
}

impl<T: Copy> SpatialGrid<T> {
    /// An empty grid for queries of radius up to `cell`.
    pub fn new(cell: f64) -> Self {
        SpatialGrid {
            cell: if cell.is_finite() && cell > 0.0 {
                cell
            } else {
                1.0
            },
            cells: HashMap::default(),
        }
    }

    /// A point's cell. Clamped to ±1e12 cells, so that the arithmetic on keys (a box's cell
    /// count, a query's neighbouring cells) cannot overflow for a point flung far away.
    fn key(&self, p: DVec2) -> (i64, i64) {
        const LIMIT: f64 = 1e12;
        (
            (p.x / self.cell).floor().clamp(-LIMIT, LIMIT) as i64,
            (p.y / self.cell).floor().clamp(-LIMIT, LIMIT) as i64,
        )
    }

    /// Adds an item at `p` (a non-finite point is left out).
    pub fn insert(&mut self, p: DVec2, item: T) {
        if p.is_finite() {
            self.cells.entry(self.key(p)).or_default().push((p, item));
        }
    }

    /// How many cells the box from `min` to `max` overlaps.
    pub fn cells_in_box(&self, min: DVec2, max: DVec2) -> f64 {
        let (a, b) = (self.key(min), self.key(max));
        (b.0 - a.0 + 1) as f64 * (b.1 - a.1 + 1) as f64
    }

    /// Calls `visit` with every item in the cells that the box from `min` to `max` overlaps
    /// (a superset of the items inside it).
    pub fn in_box(&self, min: DVec2, max: DVec2, mut visit: impl FnMut(DVec2, T)) {
        let (a, b) = (self.key(min), self.key(max));
        for x in a.0..=b.0 {
            for y in a.1..=b.1 {
                for &(p, item) in self.cells.get(&(x, y)).into_iter().flatten() {
                    visit(p, item);
                }
            }
        }
    }

    /// Every item within `radius` (≤ the cell size) of `at`, with its distance.
    pub fn within(&self, at: DVec2, radius: f64) -> Vec<(T, f64)> {
        let (cx, cy) = self.key(at);
        let reach = (radius / self.cell).ceil().max(1.0) as i64;
        let mut out = vec![];
        for x in cx - reach..=cx + reach {
            for y in cy - reach..=cy + reach {
                for &(p, item) in self.cells.get(&(x, y)).into_iter().flatten() {
                    let d = p.distance(at);
                    if d <= radius {
                        out.push((item, d));
                    }
                }
            }
        }
        out
    }
}
