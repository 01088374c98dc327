//! Contact with bodies' outlines: a particle is kept out of every other body's boundary
//! springs, each taken as a capsule of the contact radius r, as JellyCar-style soft-body
//! engines keep bodies apart. Particle pairs alone ([`super::pairs`]) leave holes wherever a
//! body's particles sit farther apart than 2r: the shipped balloons are rings spaced about six
//! contact diameters, and under pairs alone 9 particles of one ended inside the other.
//!
//! **Which springs.** A body is a connected part of the spring graph. A spring is on its
//! outline when the particles it shares a spring neighbour with (the triangles it is an edge
//! of) all lie on one side of it, or when it has none: a ring's springs, a rope's, the sides
//! of a soft box or a cloth (not their inner rows, whose triangles lie on both sides, nor the
//! cells' diagonals). The outline is found from the positions when the spring graph changes.
//!
//! **Which side.** A particle within reach of an edge at the start of the step records the
//! side of the edge's line it is on. Wherever an iterate has carried it across the edge, it is
//! put back on that side: no step, however large, passes it through an outline. Apart from
//! that, contact is the distance to the capsule: under 2r it pushes apart.
//!
//! **The push** moves the particle and the edge's two ends by their inverse-mass shares of the
//! depth, the ends weighted by where along the edge the contact is (the constraint's gradient,
//! as position-based dynamics projects any constraint), in one Gauss–Seidel pass over the
//! candidates: outlines are few next to the particles, and a serial pass is cheap. The
//! velocity pass removes the approach of the particle relative to the edge's point, with
//! friction and restitution ([`respond`]), the impulse shared the same way.
//!
//! **Candidates** are listed at the start of each step: each particle against the outline edges
//! of other bodies within the contact distance plus how far the two can close in the step,
//! through a grid of cells at least one edge long, with each edge in every cell its reach
//! covers.
//!
//! **Obstacles' corners.** A particle's own test keeps it out of an obstacle, but not the
//! springs between particles: a slope's end or a box's corner passed between two of a ball's
//! particles, 26 mm apart, and the ball hung on it, pierced (the shipped `balloon` scene,
//! rolling off its slope). So each obstacle's corners (`Placed::corners`: a box's, a segment's
//! ends, a circle's centre, each with the radius of its round) are candidates as a particle is,
//! one that nothing moves, and are kept the corner's radius plus r from every outline edge,
//! on the side they start on. They act after the step (pass 6), for every method: the edge's
//! two ends take the whole push and the velocity pass, and an obstacle that stands for a body
//! takes back the impulse ([`Reactions`]).

use super::groups::bodies;
use super::obstacle::{Placed, SLOP, Surface, respond};
use super::reaction::Reactions;
use crate::solver::state::State;
use glam::DVec2;

/// A particle near an outline edge at the start of the step.
#[derive(Debug, Clone, Copy)]
struct Near {
    particle: u32,
    edge: u32,
    /// +1 when the particle belongs left of the edge (a to b), −1 when right.
    side: f64,
    /// Where the particle started in the edge's frame: along it (0 at a, 1 at b, unclamped)
    /// and its distance in front of the edge's line (on `side`, negative behind it).
    start: (f64, f64),
}

/// An obstacle's corner, where it stands for the step: the point, the radius of its round, and
/// the velocity of the obstacle's material there (the pose stays until the step has collided).
#[derive(Debug, Clone, Copy)]
struct Corner {
    obstacle: u32,
    at: DVec2,
    radius: f64,
    velocity: DVec2,
}

/// The outlines of a state's bodies and the step's candidates, kept from step to step.
#[derive(Debug, Default)]
pub struct Outlines {
    /// The outline edges: particle indices.
    edges: Vec<[u32; 2]>,
    /// Each edge's outside: +1 left of a to b, −1 right, 0 both (a rope's, an open chain's).
    outward: Vec<f64>,
    /// Each particle's body (its connected part of the spring graph).
    body: Vec<u32>,
    /// What the outline was found for: particles and spring-graph revision.
    built: Option<(usize, u64)>,
    /// The step's candidates.
    near: Vec<Near>,
    /// The obstacles' corners this step.
    corners: Vec<Corner>,
    /// The step's corner candidates: [`Near::particle`] is the corner's index in `corners`.
    near_corners: Vec<Near>,
    /// Scratch for one obstacle's corners.
    found: Vec<(DVec2, f64)>,
    /// The broad phase's (cell, edge) keys, sorted.
    cells: Vec<(u64, u32)>,
    /// Steps the candidates were listed for.
    pub steps: u64,
}

/// What a pass over the candidates found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OutlineReport {
    /// Particle–edge contacts.
    pub contacts: usize,
    /// The deepest, m.
    pub deepest: f64,
}

/// One contact: where along the edge (t), the normal towards the particle, the depth, and the
/// particle's and ends' indices.
struct Touch {
    p: usize,
    a: usize,
    b: usize,
    t: f64,
    normal: DVec2,
    depth: f64,
}

impl Outlines {
    /// The outline edges (particle indices), as last found.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Particle candidates listed this step.
    pub fn candidates(&self) -> usize {
        self.near.len()
    }

    /// Lists the step's candidates: pairs of a particle and another body's outline edge
    /// closer than `reach` at the start of the step (the state's positions), and pairs of an
    /// obstacle's corner and an outline edge closer than `reach` plus the corner's radius.
    /// Finds the outline again when the spring graph changed. Returns whether any pair was
    /// listed.
    pub(crate) fn ready(&mut self, s: &State, reach: f64, obstacles: &[Placed]) -> bool {
        let key = (s.x.len(), s.revision);
        if self.built != Some(key) {
            self.find(s);
            self.built = Some(key);
        }
        self.steps += 1;
        self.near.clear();
        self.near_corners.clear();
        self.corners.clear();
        if self.edges.is_empty() || reach <= 0.0 {
            return false;
        }
        let x = &s.x;
        let longest = self.edges.iter().fold(0.0f64, |m, &[a, b]| {
            m.max((x[a as usize] - x[b as usize]).length())
        });
        let cell = reach.max(longest);
        if !cell.is_finite() {
            return false;
        }
        let at = |p: DVec2| cell_of(p, cell);
        self.cells.clear();
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let (pa, pb) = (x[a as usize], x[b as usize]);
            let lo = at(pa.min(pb) - DVec2::splat(reach));
            let hi = at(pa.max(pb) + DVec2::splat(reach));
            for i in lo.0..=hi.0 {
                for j in lo.1..=hi.1 {
                    self.cells.push((cell_key((i, j)), e as u32));
                }
            }
        }
        self.cells.sort_unstable();
        let mut near = std::mem::take(&mut self.near);
        for (p, &xp) in x.iter().enumerate() {
            for e in self.edges_in(at(xp)) {
                let [a, _] = self.edges[e as usize];
                if self.body[a as usize] == self.body[p] {
                    continue;
                }
                near.extend(self.candidate(x, e, p as u32, xp, reach));
            }
        }
        self.near = near;
        self.ready_corners(x, reach, cell, obstacles);
        !self.near.is_empty() || !self.near_corners.is_empty()
    }

    /// Lists the obstacles' corners and their candidates, through the cells of [`Self::ready`]
    /// (`cell` wide, each edge in every cell within `reach` of it).
    fn ready_corners(&mut self, x: &[DVec2], reach: f64, cell: f64, obstacles: &[Placed]) {
        let at = |p: DVec2| cell_of(p, cell);
        let (mut found, mut corners, mut near) = (
            std::mem::take(&mut self.found),
            std::mem::take(&mut self.corners),
            std::mem::take(&mut self.near_corners),
        );
        for (o, obstacle) in obstacles.iter().enumerate() {
            found.clear();
            obstacle.corners(&mut found);
            for &(point, radius) in found.iter().filter(|(p, _)| p.is_finite()) {
                let corner = corners.len() as u32;
                corners.push(Corner {
                    obstacle: o as u32,
                    at: point,
                    radius,
                    velocity: obstacle.velocity_at(point),
                });
                let within = radius + reach;
                let first = near.len();
                let lo = at(point - DVec2::splat(radius));
                let hi = at(point + DVec2::splat(radius));
                // In f64: a disc of 1e200 m spans more cells than an i64 counts.
                let span = |a: i64, b: i64| (b as i128 - a as i128 + 1) as f64;
                let cells = span(lo.0, hi.0) * span(lo.1, hi.1);
                if cells > self.edges.len() as f64 {
                    // A round wider than the outlines' cells (a large disc): every edge.
                    near.extend(
                        (0..self.edges.len() as u32)
                            .filter_map(|e| self.candidate(x, e, corner, point, within)),
                    );
                    continue;
                }
                for i in lo.0..=hi.0 {
                    for j in lo.1..=hi.1 {
                        near.extend(
                            (self.edges_in((i, j)))
                                .filter_map(|e| self.candidate(x, e, corner, point, within)),
                        );
                    }
                }
                // An edge in several of the corner's cells was found once in each.
                let mut listed = near.split_off(first);
                listed.sort_unstable_by_key(|n| n.edge);
                listed.dedup_by_key(|n| n.edge);
                near.append(&mut listed);
            }
        }
        (self.found, self.corners, self.near_corners) = (found, corners, near);
    }

    /// The edges listed in cell `(i, j)` of the last [`Self::ready`].
    fn edges_in(&self, cell: (i64, i64)) -> impl Iterator<Item = u32> + '_ {
        let k = cell_key(cell);
        let from = self.cells.partition_point(|&(c, _)| c < k);
        self.cells[from..]
            .iter()
            .take_while(move |&&(c, _)| c == k)
            .map(|&(_, e)| e)
    }

    /// The candidate of the point `xp` (particle or corner `who`) and edge `e`, if it is
    /// within `reach` of the edge at the start of the step. Another body's particle, or an
    /// obstacle, belongs outside the body; where both sides are outside (a rope), on the side
    /// it starts on. One behind the edge's span at the start is not this edge's: inside the
    /// body already, or beyond it.
    fn candidate(&self, x: &[DVec2], e: u32, who: u32, xp: DVec2, reach: f64) -> Option<Near> {
        let [a, b] = self.edges[e as usize];
        let (pa, pb) = (x[a as usize], x[b as usize]);
        let (t, q) = closest(pa, pb, xp);
        if (xp - q).length_squared() >= reach * reach {
            return None;
        }
        let start = if (pb - pa).perp_dot(xp - pa) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let side = match self.outward[e as usize] {
            0.0 => start,
            outward if start != outward && t > 0.0 && t < 1.0 => return None,
            outward => outward,
        };
        Some(Near {
            particle: who,
            edge: e,
            side,
            start: frame(pa, pb, side, xp),
        })
    }

    /// The contact of candidate `n`, its point at `xp`, with the edge at positions `x` and
    /// distance `contact`, if it touches.
    fn touch(&self, n: &Near, xp: DVec2, x: &[DVec2], contact: f64) -> Option<Touch> {
        let [a, b] = self.edges[n.edge as usize];
        let (p, a, b) = (n.particle as usize, a as usize, b as usize);
        let (pa, pb) = (x[a], x[b]);
        let (t, q) = closest(pa, pb, xp);
        let ab = pb - pa;
        let d = xp - q;
        let dist = d.length();
        // Behind the edge within its span, having passed its line within the span during the
        // step (the swept test in the edge's frame, its motion taken as linear): carried
        // across. Behind it otherwise, the particle is inside the body by another edge, or
        // beyond it: not this edge's.
        let (along, front) = frame(pa, pb, n.side, xp);
        let behind = front < 0.0 && t > 0.0 && t < 1.0;
        let (t0, front0) = n.start;
        let crossed = behind && front0 >= 0.0 && {
            // Within the capsule's end caps too: a particle that passes an outline's corner
            // head on crosses both its edges' lines at the corner itself.
            let at = t0 + (along - t0) * front0 / (front0 - front);
            let slack = contact / ab.length();
            (-slack..=1.0 + slack).contains(&at)
        };
        if behind && !crossed {
            return None;
        }
        let (normal, depth) = if crossed {
            // Carried across the edge: back to the side it started on.
            (ab.perp().normalize_or_zero() * n.side, contact + dist)
        } else if dist < contact {
            let normal = if dist > 0.0 {
                d / dist
            } else {
                ab.perp().normalize_or_zero() * n.side
            };
            (normal, contact - dist)
        } else {
            return None;
        };
        (normal != DVec2::ZERO).then_some(Touch {
            p,
            a,
            b,
            t,
            normal,
            depth,
        })
    }

    /// One Gauss–Seidel pass pushing every touching candidate apart in `x` (inverse masses
    /// `w`) to the contact distance `contact`. With `velocity: Some((v, dt))` each push over
    /// dt is added to the velocity too (the methods whose velocity is where the step went).
    pub(crate) fn push_apart(
        &self,
        x: &mut [DVec2],
        w: &[f64],
        contact: f64,
        mut velocity: Option<(&mut [DVec2], f64)>,
    ) -> OutlineReport {
        let mut report = OutlineReport::default();
        for n in &self.near {
            let Some(c) = self.touch(n, x[n.particle as usize], x, contact) else {
                continue;
            };
            report.contacts += 1;
            report.deepest = report.deepest.max(c.depth);
            let (sa, sb) = (1.0 - c.t, c.t);
            let wsum = w[c.p] + sa * sa * w[c.a] + sb * sb * w[c.b];
            if wsum == 0.0 {
                continue;
            }
            let lambda = c.depth / wsum;
            let moves = [
                (c.p, c.normal * (w[c.p] * lambda)),
                (c.a, -c.normal * (sa * w[c.a] * lambda)),
                (c.b, -c.normal * (sb * w[c.b] * lambda)),
            ];
            for (i, d) in moves {
                x[i] += d;
                if let Some((v, dt)) = velocity.as_mut() {
                    v[i] += d / *dt;
                }
            }
        }
        report
    }

    /// The contact of corner candidate `n` with its edge at positions `x`, for particles of
    /// radius `r`, if it touches (`slop` farther counts too): the corner is the candidate's
    /// point, and the contact distance its radius plus r.
    fn touch_corner(&self, n: &Near, x: &[DVec2], r: f64, slop: f64) -> Option<(Touch, Corner)> {
        let corner = self.corners[n.particle as usize];
        let contact = corner.radius + r + slop;
        self.touch(n, corner.at, x, contact).map(|c| (c, corner))
    }

    /// One Gauss–Seidel pass pushing every outline edge that an obstacle's corner touches
    /// out to the corner's radius plus `r`, its ends taking the whole push by their
    /// inverse-mass shares (the corner does not move). With `velocity: Some((v, dt))` each
    /// push over dt is added to the velocity too, and noted in `reactions` as the ends'
    /// impulse where the obstacle stands for a body.
    fn push_corners(
        &self,
        x: &mut [DVec2],
        w: &[f64],
        r: f64,
        mut velocity: Option<(&mut [DVec2], f64)>,
        reactions: Option<&Reactions>,
    ) -> OutlineReport {
        let mut report = OutlineReport::default();
        for n in &self.near_corners {
            let Some((c, corner)) = self.touch_corner(n, x, r, 0.0) else {
                continue;
            };
            report.contacts += 1;
            report.deepest = report.deepest.max(c.depth);
            let (sa, sb) = (1.0 - c.t, c.t);
            let wsum = sa * sa * w[c.a] + sb * sb * w[c.b];
            if wsum == 0.0 {
                continue;
            }
            let lambda = c.depth / wsum;
            for (i, share) in [(c.a, sa), (c.b, sb)] {
                let d = -c.normal * (share * w[i] * lambda);
                x[i] += d;
                if let Some((v, dt)) = velocity.as_mut() {
                    let approach = v[i].dot(c.normal);
                    v[i] += d / *dt;
                    if let Some(log) = reactions.filter(|_| w[i] > 0.0) {
                        let on = d / (*dt * w[i]);
                        log.note(corner.obstacle as usize, i, corner.at, on, approach);
                    }
                }
            }
        }
        report
    }

    /// Pushes the candidates apart in the state's positions until the deepest is under 1 % of
    /// `contact` (at most `passes` passes), then the velocity pass; the obstacles' corners the
    /// same way, their impulses noted in `reactions`. `velocity_follows: Some(dt)` adds the
    /// push over dt to the velocities.
    /// Returns the contacts of the first pass.
    pub(crate) fn collide(
        &self,
        s: &mut State,
        contact: f64,
        surface: Surface,
        velocity_follows: Option<f64>,
        passes: usize,
        reactions: Option<&Reactions>,
    ) -> usize {
        if self.near.is_empty() && self.near_corners.is_empty() {
            return 0;
        }
        let r = 0.5 * contact;
        let mut first = None;
        for _ in 0..passes {
            let velocity = velocity_follows.map(|dt| (&mut s.v[..], dt));
            let p = self.push_apart(&mut s.x, &s.inv_mass, contact, velocity);
            let velocity = velocity_follows.map(|dt| (&mut s.v[..], dt));
            let c = self.push_corners(&mut s.x, &s.inv_mass, r, velocity, reactions);
            first.get_or_insert(p.contacts + c.contacts);
            if p.deepest.max(c.deepest) <= 0.01 * contact {
                break;
            }
        }
        self.respond(s, contact, surface);
        self.respond_corners(s, r, surface, reactions);
        first.unwrap_or(0)
    }

    /// The velocity pass of the corners: each touching edge point's velocity relative to the
    /// obstacle's material there through [`respond`], the impulse shared by the ends' inverse
    /// masses and noted in `reactions`.
    fn respond_corners(
        &self,
        s: &mut State,
        r: f64,
        surface: Surface,
        reactions: Option<&Reactions>,
    ) {
        let (x, v, w) = (&s.x, &mut s.v, &s.inv_mass);
        for n in &self.near_corners {
            let Some((c, corner)) = self.touch_corner(n, x, r, SLOP) else {
                continue;
            };
            let (sa, sb) = (1.0 - c.t, c.t);
            let wsum = sa * sa * w[c.a] + sb * sb * w[c.b];
            if wsum == 0.0 {
                continue;
            }
            // The edge's point against the obstacle's surface, whose normal points from the
            // corner to the edge.
            let rel = v[c.a] * sa + v[c.b] * sb - corner.velocity;
            let change = respond(rel, DVec2::ZERO, -c.normal, surface) - rel;
            if change == DVec2::ZERO {
                continue;
            }
            let impulse = change / wsum;
            for (i, share) in [(c.a, sa), (c.b, sb)] {
                v[i] += impulse * (share * w[i]);
                if let Some(log) = reactions.filter(|_| w[i] > 0.0) {
                    let approach = rel.dot(c.normal);
                    log.note(
                        corner.obstacle as usize,
                        i,
                        corner.at,
                        impulse * share,
                        approach,
                    );
                }
            }
        }
    }

    /// The velocity pass: each touching candidate's relative velocity (the particle's against
    /// the edge's point) through [`respond`], the impulse shared by inverse mass.
    fn respond(&self, s: &mut State, contact: f64, surface: Surface) {
        let (x, v, w) = (&s.x, &mut s.v, &s.inv_mass);
        for n in &self.near {
            let Some(c) = self.touch(n, x[n.particle as usize], x, contact + SLOP) else {
                continue;
            };
            let (sa, sb) = (1.0 - c.t, c.t);
            let wsum = w[c.p] + sa * sa * w[c.a] + sb * sb * w[c.b];
            if wsum == 0.0 {
                continue;
            }
            let rel = v[c.p] - (v[c.a] * sa + v[c.b] * sb);
            let change = respond(rel, DVec2::ZERO, c.normal, surface) - rel;
            if change == DVec2::ZERO {
                continue;
            }
            let impulse = change / wsum;
            v[c.p] += impulse * w[c.p];
            v[c.a] -= impulse * (sa * w[c.a]);
            v[c.b] -= impulse * (sb * w[c.b]);
        }
    }

    /// Finds the bodies and their outline edges from the state's springs and positions.
    fn find(&mut self, s: &State) {
        let n = s.x.len();
        self.body = bodies(&s.springs, n);
        let (spans, adjacent) = super::pairs::spring_neighbours(s);
        let neighbours = |i: u32| {
            let (a, b) = spans[i as usize];
            &adjacent[a as usize..b as usize]
        };
        let x = &s.x;
        self.edges.clear();
        self.outward.clear();
        let mut seen = std::collections::HashSet::new();
        for sp in &s.springs {
            let (a, b) = (sp.a.min(sp.b), sp.a.max(sp.b));
            if a == b || !seen.insert((a, b)) {
                continue;
            }
            let (pa, pb) = (x[a as usize], x[b as usize]);
            let ab = pb - pa;
            let (mut left, mut right) = (false, false);
            let (na, nb) = (neighbours(a), neighbours(b));
            let (mut i, mut j) = (0, 0);
            while i < na.len() && j < nb.len() {
                match na[i].cmp(&nb[j]) {
                    std::cmp::Ordering::Less => i += 1,
                    std::cmp::Ordering::Greater => j += 1,
                    std::cmp::Ordering::Equal => {
                        let cross = ab.perp_dot(x[na[i] as usize] - pa);
                        left |= cross > 0.0;
                        right |= cross < 0.0;
                        i += 1;
                        j += 1;
                    }
                }
            }
            if !(left && right) {
                self.edges.push([a, b]);
                // The triangles' side is the inside.
                self.outward.push(match (left, right) {
                    (true, _) => -1.0,
                    (_, true) => 1.0,
                    _ => 0.0,
                });
            }
        }
        self.orient_loops(x);
    }

    /// The outside of the edges that no triangle borders, where they close a loop (a ring, a
    /// balloon): the side away from the loop's enclosed area. The others (a rope) stay open.
    fn orient_loops(&mut self, x: &[DVec2]) {
        let bare: Vec<usize> = (0..self.edges.len())
            .filter(|&e| self.outward[e] == 0.0)
            .collect();
        let mut at: std::collections::HashMap<u32, Vec<usize>> = Default::default();
        for &e in &bare {
            for end in self.edges[e] {
                at.entry(end).or_default().push(e);
            }
        }
        let mut done = vec![false; self.edges.len()];
        for &first in &bare {
            if done[first] {
                continue;
            }
            // Walk from the edge's b end through particles with exactly two bare edges.
            let [start, mut here] = self.edges[first];
            let (mut walk, mut edge) = (vec![(first, start)], first);
            let closed = loop {
                let next = match at.get(&here).map(Vec::as_slice) {
                    Some(&[p, q]) => {
                        if p == edge {
                            q
                        } else {
                            p
                        }
                    }
                    _ => break false,
                };
                if next == first {
                    break true;
                }
                if done[next] || walk.len() > bare.len() {
                    break false;
                }
                walk.push((next, here));
                let [a, b] = self.edges[next];
                here = if a == here { b } else { a };
                edge = next;
            };
            for &(e, _) in &walk {
                done[e] = true;
            }
            if !closed {
                continue;
            }
            // The loop's signed area (shoelace over the walk's vertices, each edge from its
            // `from` end): positive when the walk goes round counter-clockwise, inside left.
            let mut area = 0.0;
            for &(e, from) in &walk {
                let [a, b] = self.edges[e];
                let to = if a == from { b } else { a };
                area += x[from as usize].perp_dot(x[to as usize]);
            }
            for &(e, from) in &walk {
                let forward = self.edges[e][0] == from;
                // Walking a to b with the inside on the left: the outside is right (−1).
                let inside_left = (area > 0.0) == forward;
                self.outward[e] = if inside_left { -1.0 } else { 1.0 };
            }
        }
    }
}

/// The cell of side `cell` that holds `p`.
fn cell_of(p: DVec2, cell: f64) -> (i64, i64) {
    ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64)
}

/// A cell's key in the sorted list of (cell, edge).
fn cell_key((i, j): (i64, i64)) -> u64 {
    ((i as u64) << 32) ^ (j as u64 & 0xffff_ffff)
}

/// Point p in the frame of edge a–b: where along it (0 at a, 1 at b, unclamped) and its
/// distance in front of the edge's line on `side` (+1 left of a to b), negative behind.
fn frame(a: DVec2, b: DVec2, side: f64, p: DVec2) -> (f64, f64) {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 == 0.0 {
        return (0.0, (p - a).length());
    }
    (
        (p - a).dot(ab) / len2,
        ab.perp_dot(p - a) * side / len2.sqrt(),
    )
}

/// The point of segment a–b closest to p, and where along it (0 at a, 1 at b).
fn closest(a: DVec2, b: DVec2, p: DVec2) -> (f64, DVec2) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (t, a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::state::State;

    /// A square of side 1 with one diagonal, and a lone particle: the square's four sides are
    /// its outline, the diagonal (triangles on both sides) is not.
    fn square_and_particle(p: DVec2) -> State {
        let x = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
            p,
        ];
        let springs = [(0, 1), (1, 2), (2, 3), (0, 3), (0, 2)]
            .map(|(a, b)| crate::solver::packed::PackedSpring {
                a,
                b,
                rest: 1.0,
                k: 100.0,
            })
            .to_vec();
        State {
            v: vec![DVec2::ZERO; x.len()],
            f: vec![DVec2::ZERO; x.len()],
            mass: vec![1.0; x.len()],
            inv_mass: vec![1.0; x.len()],
            x,
            springs,
            ..State::default()
        }
    }

    #[test]
    fn the_outline_is_the_sides_not_the_diagonal() {
        let s = square_and_particle(DVec2::new(0.5, 1.5));
        let mut o = Outlines::default();
        o.ready(&s, 0.1, &[]);
        let mut edges = o.edges().to_vec();
        edges.sort();
        assert_eq!(edges, vec![[0, 1], [0, 3], [1, 2], [2, 3]]);
    }

    #[test]
    fn an_obstacles_corner_between_a_sides_ends_pushes_the_side_out() {
        use crate::solver::contact::obstacle::Shape;
        // A box standing on its corner, its top corner 1 mm under the square's bottom side.
        let centre_to_corner = std::f64::consts::SQRT_2 * 0.1;
        let spike = Placed::at(
            Shape::Box {
                half: DVec2::splat(0.1),
            },
            DVec2::new(0.5, -0.001 - centre_to_corner),
            std::f64::consts::FRAC_PI_4,
        );
        let mut s = square_and_particle(DVec2::new(3.0, 3.0));
        let mut o = Outlines::default();
        assert!(o.ready(&s, 0.1, &[spike]));
        assert_eq!(
            o.near_corners.len(),
            1,
            "the top corner, against the bottom side"
        );
        // An iterate that carried the square 0.05 down onto it: the corner between the bottom
        // side's ends, 0.049 inside.
        for x in &mut s.x[..4] {
            x.y -= 0.05;
        }
        let w = s.inv_mass.clone();
        let r = o.push_corners(&mut s.x, &w, 0.01, None, None);
        assert_eq!(r.contacts, 1);
        assert!((r.deepest - 0.059).abs() < 1e-9, "{r:?}");
        // The side's ends took the whole push, half each: the side is r above the corner.
        let bottom = (s.x[0].y + s.x[1].y) / 2.0;
        assert!((bottom - (-0.001 + 0.01)).abs() < 1e-9, "{:?}", s.x);
        assert_eq!(s.x[4], DVec2::new(3.0, 3.0));
    }

    /// A disc of 1e200 m (finite, so valid) spans more cells than an i64 counts: the corners'
    /// listing takes every edge instead, without overflowing.
    #[test]
    fn a_huge_disc_does_not_overflow_the_corners_cells() {
        use crate::solver::contact::obstacle::Shape;
        let disc = Placed::at(
            Shape::Circle { radius: 1e200 },
            DVec2::new(0.5, -1e200),
            0.0,
        );
        let s = square_and_particle(DVec2::new(3.0, 3.0));
        let mut o = Outlines::default();
        o.ready(&s, 0.1, &[disc]);
        assert_eq!(o.corners.len(), 1);
    }

    #[test]
    fn a_particle_carried_through_an_edge_goes_back_to_its_side() {
        let mut s = square_and_particle(DVec2::new(0.5, 1.02));
        let mut o = Outlines::default();
        assert!(o.ready(&s, 0.1, &[]));
        // An iterate that carried it 0.1 below the top side, into the square.
        s.x[4] = DVec2::new(0.5, 0.92);
        let w = s.inv_mass.clone();
        let r = o.push_apart(&mut s.x, &w, 0.02, None);
        assert_eq!(r.contacts, 1);
        assert!((r.deepest - 0.1).abs() < 1e-12, "{r:?}");
        // The particle and the top side's ends share the push; they end 2r apart, the particle
        // above.
        let top = (s.x[2].y + s.x[3].y) / 2.0;
        assert!((s.x[4].y - top - 0.02).abs() < 1e-12, "{:?}", s.x);
    }
}
