//! Obstacles: static or moving shapes that particles collide with, and the response of one
//! particle to one of them (Coulomb friction and restitution on the velocity relative to the
//! obstacle's surface).
//!
//! A shape is written in the obstacle's own frame and placed by a pose (its centre and angle);
//! the pose's velocities are what a particle in contact feels through friction. A particle of
//! radius r is in contact when its centre is within r of the shape, so a shape is tested as if
//! inflated by r: a circle of radius R as one of R + r, a segment of thickness t as a capsule of
//! radius t + r, a box by its distance plus r.

use glam::DVec2;

/// A shape in its obstacle's frame (its centre at the origin, unrotated).
///
/// A polygon is kept inline, so the enum is as large as its 16 corners: the passes copy a few
/// shapes, not millions, and inline they stay `Copy` with no allocation to follow.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A disc.
    Circle {
        /// Its radius, m.
        radius: f64,
    },
    /// A rectangle of half-extents `half` along the frame's axes.
    Box {
        /// Half its width and height, m.
        half: DVec2,
    },
    /// A segment from `a` to `b`, a capsule of radius `thickness` when that is > 0.
    Segment {
        /// One end, in the obstacle's frame.
        a: DVec2,
        /// The other end.
        b: DVec2,
        /// The capsule's radius, m (0: a line a particle cannot cross).
        thickness: f64,
    },
    /// A convex polygon ([`Polygon::new`]).
    Polygon(Polygon),
}

/// A convex polygon of at most [`Polygon::MAX_VERTICES`] corners, counter-clockwise, in its
/// obstacle's frame. Kept inline (not on the heap) so that a shape stays `Copy`, as the passes
/// read it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polygon {
    corners: [DVec2; Polygon::MAX_VERTICES],
    count: u8,
}

impl Polygon {
    /// The most corners a polygon obstacle has (avian's boxes, hexagons and hulls of a
    /// dozen points fit).
    pub const MAX_VERTICES: usize = 16;

    /// A convex polygon through `corners`, in either turning order; an error names what is
    /// wrong: fewer than 3 or more than [`Self::MAX_VERTICES`] corners, a corner that is not
    /// finite, no area, or a corner that turns the other way (not convex).
    pub fn new(corners: &[DVec2]) -> Result<Polygon, String> {
        let n = corners.len();
        if !(3..=Self::MAX_VERTICES).contains(&n) {
            return Err(format!(
                "a convex polygon needs 3 to {} corners, not {n}",
                Self::MAX_VERTICES
            ));
        }
        if let Some(c) = corners.iter().find(|c| !c.is_finite()) {
            return Err(format!("a polygon's corner must be finite, not {c}"));
        }
        let area: f64 = (0..n)
            .map(|i| corners[i].perp_dot(corners[(i + 1) % n]))
            .sum::<f64>()
            * 0.5;
        if area.abs() <= 0.0 || !area.is_finite() {
            return Err("a polygon needs an area".into());
        }
        let mut p = Polygon {
            corners: [DVec2::ZERO; Self::MAX_VERTICES],
            count: n as u8,
        };
        for (i, c) in corners.iter().enumerate() {
            // Counter-clockwise, whichever way they came.
            p.corners[i] = if area > 0.0 { *c } else { corners[n - 1 - i] };
        }
        for i in 0..n {
            let (a, b, c) = (p.corners[i], p.corners[(i + 1) % n], p.corners[(i + 2) % n]);
            if (b - a).perp_dot(c - b) < -1e-12 * (b - a).length() * (c - b).length() {
                return Err(format!(
                    "a polygon must be convex: it turns back at corner {b}"
                ));
            }
        }
        Ok(p)
    }

    /// The corners, counter-clockwise.
    pub fn corners(&self) -> &[DVec2] {
        &self.corners[..self.count as usize]
    }

    /// The edges, each from a corner to the next.
    fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        let c = self.corners();
        (0..c.len()).map(move |i| (c[i], c[(i + 1) % c.len()]))
    }

    /// Signed distance from `q` (negative inside) and the outward normal: outside, to the
    /// nearest edge; inside, out through the nearest edge's line.
    fn distance(&self, q: DVec2) -> (f64, DVec2) {
        let mut inside = true;
        let (mut deepest, mut out) = (f64::NEG_INFINITY, DVec2::Y);
        let (mut nearest, mut toward) = (f64::INFINITY, DVec2::Y);
        for (a, b) in self.edges() {
            let ab = b - a;
            let len = ab.length();
            if len == 0.0 {
                continue;
            }
            // Counter-clockwise: the outward normal is the edge turned clockwise.
            let n = DVec2::new(ab.y, -ab.x) / len;
            let side = (q - a).dot(n);
            if side > 0.0 {
                inside = false;
            }
            if side > deepest {
                (deepest, out) = (side, n);
            }
            let t = ((q - a).dot(ab) / (len * len)).clamp(0.0, 1.0);
            let d = q - (a + ab * t);
            let l = d.length();
            if l < nearest {
                nearest = l;
                // On the edge itself, to round-off (a nanometre: a path caught where it
                // enters, `Placed::first_hit`), the direction from it is noise: the edge's
                // normal.
                toward = if l > 1e-9 { d / l } else { n };
            }
        }
        if inside {
            (deepest, out)
        } else {
            (nearest, toward)
        }
    }
}

/// Where an obstacle is and how it moves.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// Its centre, m.
    pub center: DVec2,
    /// Its rotation, rad (counter-clockwise).
    pub angle: f64,
    /// Its centre's velocity, m/s.
    pub velocity: DVec2,
    /// Its angular velocity, rad/s.
    pub angular_velocity: f64,
}

/// A shape at a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// The shape.
    pub shape: Shape,
    /// Its pose.
    pub pose: Pose,
}

/// A particle's contact with an obstacle: how deep it is (the radius included) and the
/// surface's outward normal at the nearest point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// Penetration depth, m (> 0 in contact).
    pub depth: f64,
    /// Outward unit normal.
    pub normal: DVec2,
}

/// A direction in the frame of an obstacle turned by `rotation` ([`Placed::rotation`]), in the
/// world.
fn world_direction(rotation: Option<DVec2>, d: DVec2) -> DVec2 {
    rotation.map_or(d, |r| r.rotate(d))
}

/// How long a moving obstacle has been moving onto the particles when a path is read against
/// it ([`super::Surroundings::leads`], [`Placed::carried_by`]), and its turn over that time as
/// (cos, sin) (`None`: it does not turn).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Lead {
    pub time: f64,
    pub turn: Option<DVec2>,
}

/// The least thickness a segment collides with, m. A zero-thickness segment is a line, and a
/// point resting on it sits on it to round-off, on one side or the other of it by 1e-17 m:
/// which side it is on would be a coin toss. A millionth of a metre of thickness, invisible at
/// any zoom the app allows, gives it an inside, so that its normal and the side a particle is
/// on are never in doubt.
pub const MIN_THICKNESS: f64 = 1e-6;

/// How far from a surface a particle still counts as touching it, m: one left exactly on the
/// surface by the last step's push-out, which its next step did not move (explicit Euler moves
/// with the start-of-step velocity), must still lose the velocity it gained towards the surface,
/// or it carries g·dt of it into the next step for ever.
pub const SLOP: f64 = 1e-9;

impl Shape {
    /// The shape as contact sees it: a segment at least [`MIN_THICKNESS`] thick.
    fn for_contact(self) -> Shape {
        match self {
            Shape::Segment { a, b, thickness } => Shape::Segment {
                a,
                b,
                thickness: thickness.max(MIN_THICKNESS),
            },
            other => other,
        }
    }
}

impl Placed {
    /// A shape standing still at `center`, turned by `angle`.
    pub fn at(shape: Shape, center: DVec2, angle: f64) -> Placed {
        Placed {
            shape,
            pose: Pose {
                center,
                angle,
                ..Pose::default()
            },
        }
    }

    /// The obstacle's rotation, (cos, sin) of its angle; `None` when it is unrotated (most
    /// obstacles) or round, which need no sine and cosine (they were a quarter of the 256²
    /// cloth's step on a disc, asked for every particle and every pair iteration). A query
    /// works it out once for all its points and directions: one for each took 27 % of the
    /// instructions of the `paddle` scene (docs/performance-log.md, 2026-12-07).
    fn rotation(&self) -> Option<DVec2> {
        (!self.unturned()).then(|| DVec2::from_angle(self.pose.angle))
    }

    /// The point `p` (world) in the frame of the obstacle turned by `rotation`
    /// ([`Self::rotation`]).
    fn local(&self, rotation: Option<DVec2>, p: DVec2) -> DVec2 {
        let q = p - self.pose.center;
        // The inverse rotation: (cos, −sin), which is (cos, sin) of −angle to the bit.
        rotation.map_or(q, |r| DVec2::new(r.x, -r.y).rotate(q))
    }

    /// The radius of a circle about its centre that holds it: a particle farther than this
    /// plus its radius from the centre cannot touch it.
    pub fn bound(&self) -> f64 {
        match self.shape.for_contact() {
            Shape::Circle { radius } => radius,
            Shape::Box { half } => half.length(),
            Shape::Segment { a, b, thickness } => a.length().max(b.length()) + thickness,
            Shape::Polygon(p) => p.corners().iter().fold(0.0, |m, c| m.max(c.length())),
        }
    }

    /// Whether its frame is the world's but for the shift: no rotation, or a circle.
    fn unturned(&self) -> bool {
        self.pose.angle == 0.0 || matches!(self.shape, Shape::Circle { .. })
    }

    /// The signed distance from `p` to the shape's surface (negative inside) and the outward
    /// normal at the nearest surface point.
    pub fn distance(&self, p: DVec2) -> (f64, DVec2) {
        let rotation = self.rotation();
        let q = self.local(rotation, p);
        let (d, n) = match self.shape.for_contact() {
            Shape::Circle { radius } => {
                let l = q.length();
                let n = if l > 0.0 { q / l } else { DVec2::Y };
                (l - radius, n)
            }
            Shape::Box { half } => box_distance(q, half),
            Shape::Segment { a, b, thickness } => {
                let ab = b - a;
                let len2 = ab.length_squared();
                let t = if len2 > 0.0 {
                    ((q - a).dot(ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = q - (a + ab * t);
                let l = d.length();
                // On the line itself, to round-off (a nanometre, a thousandth of the least
                // thickness), the direction from it is noise: take the line's left normal, and
                // let the caller pick the side ([`Self::touch`], [`Self::hit_normal`]).
                let n = if l > 1e-9 {
                    d / l
                } else {
                    let perp = ab.perp();
                    if perp.length_squared() > 0.0 {
                        perp.normalize()
                    } else {
                        DVec2::Y
                    }
                };
                (l - thickness, n)
            }
            Shape::Polygon(p) => p.distance(q),
        };
        (d, world_direction(rotation, n))
    }

    /// The contact of a particle of radius `r` at `p`, if it is within `r` of the surface.
    /// `from` is where it came from and `heading` where it is going: a particle that crossed a
    /// segment's line within the step is put back on the side it came from, not pushed on
    /// through, and one that sits on the line itself (to round-off, with no side of its own) is
    /// put on the side it is not heading to. One that ends inside a closed shape past its
    /// middle, from a start outside it, goes back out on the start's side, not the far one.
    pub fn touch(&self, p: DVec2, from: DVec2, heading: DVec2, r: f64) -> Option<Touch> {
        let (d, mut normal) = self.distance(p);
        if d >= r + SLOP {
            return None;
        }
        let mut depth = (r - d).max(0.0);
        if let Shape::Segment { thickness, .. } = self.shape.for_contact() {
            // The point of the line nearest p, and the sides of it p and `from` are on.
            let core = p - normal * (d + thickness);
            let (side_from, off_line) = ((from - core).dot(normal), (p - core).length());
            let flip = if side_from.abs() > 0.5 * MIN_THICKNESS {
                side_from < 0.0
            } else {
                off_line < 0.5 * MIN_THICKNESS && heading.dot(normal) > 0.0
            };
            if flip {
                normal = -normal;
                depth = r + 2.0 * thickness + d;
            }
        } else if d < 0.0 {
            // Inside a closed shape the nearest surface is the way out, unless the particle
            // came from the other side: then it crossed the shape's middle within the step and
            // would leave through the far side. The swept test leaves two such paths to this
            // push: a start in contact (a particle resting on the surface whose iterate a
            // solve pulled deep in), and a path whose hit faced the particle's heading, away
            // from the surface. Out on the start's side instead, to the tangent at the surface
            // point nearest the start: a convex shape lies wholly behind it.
            let (d0, n0) = self.distance(from);
            if d0 >= 0.0 && n0.dot(normal) < 0.0 {
                let surface = from - n0 * d0;
                normal = n0;
                depth = r - (p - surface).dot(n0);
            }
        }
        Some(Touch { depth, normal })
    }

    /// Where the path `from` → `to` crosses the shape itself, as a fraction of the path: a
    /// segment's line within its length (in (0, 1]), or a closed shape passed through from
    /// side to side (in [0, 1]). `None` for a path that stays on one side, a start on a
    /// segment's line (which has no side to keep), and a path that starts or ends inside a
    /// closed shape.
    pub fn crossing(&self, from: DVec2, to: DVec2) -> Option<f64> {
        match self.shape.for_contact() {
            Shape::Segment { a, b, .. } => {
                let rotation = self.rotation();
                let (from, to) = (self.local(rotation, from), self.local(rotation, to));
                line_crossing(from, to, a, b).filter(|&t| t > 0.0)
            }
            _ => self.passes_through(from, self.distance(from), to),
        }
    }

    /// `p`, or for a point inside a closed shape, the point just outside it by the nearest
    /// surface: the side a path that starts inside is taken to come from.
    pub fn out_by_nearest(&self, p: DVec2) -> DVec2 {
        let (d, n) = self.distance(p);
        if d < 0.0 && !self.is_segment() {
            p + n * (0.5 * MIN_THICKNESS - d)
        } else {
            p
        }
    }

    /// Whether the shape is a segment: thin, with a side that only the way a particle came can
    /// tell.
    pub fn is_segment(&self) -> bool {
        matches!(self.shape, Shape::Segment { .. })
    }

    /// The outward normal where a path moving by `step` first touched the shape at `p`: the
    /// surface's normal there, turned to face the path (a particle exactly on a line has no
    /// side of its own; it is on the side it came from).
    pub fn hit_normal(&self, p: DVec2, step: DVec2) -> DVec2 {
        let (_, n) = self.distance(p);
        if n.dot(step) > 0.0 { -n } else { n }
    }

    /// Moves the obstacle by its velocities over `dt` (a kinematic body: nothing pushes it).
    pub fn advance(&mut self, dt: f64) {
        self.pose.center += self.pose.velocity * dt;
        self.pose.angle += self.pose.angular_velocity * dt;
    }

    /// Whether the obstacle moves: a velocity or an angular velocity other than zero.
    pub fn moves(&self) -> bool {
        self.pose.velocity != DVec2::ZERO || self.pose.angular_velocity != 0.0
    }

    /// Where the point of the obstacle that was at `p` a time `lead` ago is now, the
    /// obstacle having moved by its velocities since ([`Self::advance`]); `p` itself for an
    /// obstacle that does not move or a lead of 0.
    ///
    /// Why: a step's contact sees a moving obstacle where the step ends, and reads a
    /// particle's path against it from where the particle's start was on the obstacle's
    /// frame (the contact pass's `place`). A box moving at 2 m/s moves 3.3 cm in a step of
    /// 1/60 s: a particle lying still in its way is struck though its own path has no length.
    pub fn carried(&self, p: DVec2, lead: f64) -> DVec2 {
        self.carried_by(p, self.lead(lead))
    }

    /// [`Self::carried`] with the lead's turn worked out ([`Self::lead`]): a contact pass
    /// carries every particle's start by the same lead, and a sine and cosine for each were
    /// a tenth of the `paddle` scene's instructions (docs/performance-log.md, 2026-12-07).
    pub(crate) fn carried_by(&self, p: DVec2, lead: Lead) -> DVec2 {
        if lead.time == 0.0 || !self.moves() {
            return p;
        }
        let start = self.pose.center - self.pose.velocity * lead.time;
        let arm = p - start;
        let arm = lead.turn.map_or(arm, |turn| turn.rotate(arm));
        self.pose.center + arm
    }

    /// A lead of `time` for this obstacle: its turn over that time worked out.
    pub(crate) fn lead(&self, time: f64) -> Lead {
        let turn = self.pose.angular_velocity * time;
        Lead {
            time,
            turn: (turn != 0.0).then(|| DVec2::from_angle(turn)),
        }
    }

    /// What is wrong with the shape or pose, as (what, value, rule), if anything: a radius or
    /// half-extent that is not finite and positive, a thickness that is not finite and >= 0,
    /// a segment of zero length, or a non-finite pose or velocity.
    pub fn problem(&self) -> Option<(&'static str, f64, &'static str)> {
        const FINITE: &str = "must be finite";
        let p = &self.pose;
        for (what, v) in [
            ("center.x", p.center.x),
            ("center.y", p.center.y),
            ("angle", p.angle),
            ("velocity.x", p.velocity.x),
            ("velocity.y", p.velocity.y),
            ("angular velocity", p.angular_velocity),
        ] {
            if !v.is_finite() {
                return Some((what, v, FINITE));
            }
        }
        const POSITIVE: &str = "must be finite and > 0";
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match self.shape {
            Shape::Circle { radius } if !positive(radius) => Some(("radius", radius, POSITIVE)),
            Shape::Box { half } if !positive(half.x) => Some(("half.x", half.x, POSITIVE)),
            Shape::Box { half } if !positive(half.y) => Some(("half.y", half.y, POSITIVE)),
            Shape::Segment { a, b, thickness } => {
                if !(thickness.is_finite() && thickness >= 0.0) {
                    Some(("thickness", thickness, "must be finite and >= 0"))
                } else if !(a.is_finite() && b.is_finite()) {
                    Some(("end", f64::NAN, FINITE))
                } else if a == b {
                    Some(("length", 0.0, "a segment needs two different ends"))
                } else {
                    None
                }
            }
            _ => None,
        }
    }

    /// The points where the shape could pass between two of a body's particles, each with
    /// the radius of the round it carries, in the world: a box's or polygon's corners (0), a
    /// segment's ends (its thickness), a circle's centre (its radius). Contact by outlines
    /// keeps them out of the bodies' outline edges ([`super::outline`]); a particle's own
    /// test ([`Self::touch`]) keeps only the particles out.
    pub(crate) fn corners(&self, out: &mut Vec<(DVec2, f64)>) {
        let rotation = self.rotation();
        let at = |q: DVec2| self.pose.center + world_direction(rotation, q);
        match self.shape.for_contact() {
            Shape::Circle { radius } => out.push((self.pose.center, radius)),
            Shape::Box { half } => out.extend(
                [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
                    .map(|(x, y)| (at(half * DVec2::new(x, y)), 0.0)),
            ),
            Shape::Segment { a, b, thickness } => {
                out.extend([(at(a), thickness), (at(b), thickness)]);
            }
            Shape::Polygon(p) => out.extend(p.corners().iter().map(|&c| (at(c), 0.0))),
        }
    }

    /// The velocity of the obstacle's material at the world point `p`.
    pub fn velocity_at(&self, p: DVec2) -> DVec2 {
        let arm = p - self.pose.center;
        self.pose.velocity + self.pose.angular_velocity * arm.perp()
    }

    /// The first fraction t in [0, 1] of the path `from` → `to` at which a particle of radius
    /// `r` touches the shape, for a path that starts outside it; `None` when the path stays
    /// clear. A path that starts in contact is already touching: it is caught only where it
    /// crosses the shape itself, a segment's line or a closed shape from side to side
    /// ([`Self::crossing`]); a path that ends inside a closed shape is left to
    /// [`Self::touch`]. The shape is taken at its pose (its motion over the step is small
    /// against a thrown particle's). This is what keeps a fast particle from passing through
    /// a thin obstacle within one step.
    pub fn first_hit(&self, from: DVec2, to: DVec2, r: f64) -> Option<Hit> {
        let start = self.distance(from);
        // A start on the surface, to round-off (a particle put there by the last step), is a
        // start in contact.
        if start.0 < r + 0.5 * MIN_THICKNESS {
            // A particle resting on a thin obstacle moves more than its thickness in a step
            // when something strikes it: a disc of radius r, struck at 2 m/s for 1/60 s, is
            // passed clean through.
            return match self.shape.for_contact() {
                Shape::Segment { a, b, .. } => {
                    let rotation = self.rotation();
                    let (from, to) = (self.local(rotation, from), self.local(rotation, to));
                    line_crossing(from, to, a, b).map(Hit::along)
                }
                _ => self.passes_through(from, start, to).map(Hit::through_shape),
            };
        }
        self.sweep(from, to, r).map(Hit::along)
    }

    /// The first fraction t in [0, 1] of the path `from` → `to` that comes within `r` of the
    /// shape (the shape itself for `r` = 0), for a start farther out.
    fn sweep(&self, from: DVec2, to: DVec2, r: f64) -> Option<f64> {
        let rotation = self.rotation();
        let (p0, p1) = (self.local(rotation, from), self.local(rotation, to));
        match self.shape.for_contact() {
            Shape::Circle { radius } => ray_circle(p0, p1, DVec2::ZERO, radius + r),
            Shape::Segment { a, b, thickness } => ray_capsule(p0, p1, a, b, thickness + r),
            Shape::Box { half } => ray_rounded_box(p0, p1, half, r),
            Shape::Polygon(p) => p
                .edges()
                .filter_map(|(a, b)| ray_capsule(p0, p1, a, b, r))
                .min_by(f64::total_cmp),
        }
    }

    /// Where a path that starts and ends outside a closed shape passes through it: the
    /// fraction of the path at which it enters, in [0, 1]; `start` is the shape's
    /// [`Self::distance`] from `from`. `None` for a path that misses the shape or ends in it
    /// (and for a segment, whose side [`line_crossing`] reads).
    fn passes_through(&self, from: DVec2, (d0, n0): (f64, DVec2), to: DVec2) -> Option<f64> {
        if self.is_segment() {
            return None;
        }
        // How far the path goes toward the surface point nearest its start. The shape (convex)
        // lies wholly behind the tangent there: a path that stops short of it, as a resting
        // particle's does, cannot enter.
        let toward = -(to - from).dot(n0);
        if d0 < -0.5 * MIN_THICKNESS || toward < d0 || self.distance(to).0 < 0.0 {
            return None;
        }
        if d0 < 0.5 * MIN_THICKNESS {
            // On the surface (a point particle resting on it): in at once, if it heads in.
            return (toward > 0.0).then_some(0.0);
        }
        self.sweep(from, to, 0.0)
    }
}

/// Where a path first touches an obstacle ([`Placed::first_hit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// The fraction of the path, in [0, 1].
    pub t: f64,
    /// The path started in contact and passes through a closed shape: the hit is where it
    /// enters the shape itself, and its side is the one the path came from, whatever the
    /// particle's heading.
    pub through: bool,
}

impl Hit {
    fn along(t: f64) -> Self {
        Hit { t, through: false }
    }

    fn through_shape(t: f64) -> Self {
        Hit { t, through: true }
    }
}

/// Signed distance to an axis-aligned box centred at the origin, and the outward normal.
fn box_distance(q: DVec2, half: DVec2) -> (f64, DVec2) {
    let d = q.abs() - half;
    let outside = d.max(DVec2::ZERO);
    if outside.length_squared() > 0.0 {
        let n = (outside * q.signum()).normalize();
        (outside.length(), n)
    } else if d.x > d.y {
        // Inside: out through the nearer side.
        (d.x, DVec2::new(q.x.signum(), 0.0))
    } else {
        (d.y, DVec2::new(0.0, q.y.signum()))
    }
}

/// Where the path p0 → p1 crosses the line of the segment a–b within its length, as a
/// fraction of the path. A start on the line (within half the least thickness) has no side of
/// its own: it counts as crossing at once when the path leaves the line, which puts the
/// particle back on the side it is not heading to.
fn line_crossing(p0: DVec2, p1: DVec2, a: DVec2, b: DVec2) -> Option<f64> {
    let ab = b - a;
    let len = ab.length();
    if len == 0.0 {
        return None;
    }
    let n = ab.perp() / len;
    let (s0, s1) = ((p0 - a).dot(n), (p1 - a).dot(n));
    let on_line = |s: f64| s.abs() < 0.5 * MIN_THICKNESS;
    let t = if on_line(s0) {
        if on_line(s1) {
            return None;
        }
        0.0
    } else if (s0 > 0.0) != (s1 > 0.0) {
        s0 / (s0 - s1)
    } else {
        return None;
    };
    let along = (p0 + (p1 - p0) * t - a).dot(ab) / (len * len);
    (0.0..=1.0).contains(&along).then_some(t)
}

/// The first t in [0, 1] at which p0 + t (p1 − p0) is within `radius` of `c`.
fn ray_circle(p0: DVec2, p1: DVec2, c: DVec2, radius: f64) -> Option<f64> {
    let d = p1 - p0;
    let m = p0 - c;
    let a = d.length_squared();
    if a == 0.0 {
        return None;
    }
    let b = m.dot(d);
    let cc = m.length_squared() - radius * radius;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    (0.0..=1.0).contains(&t).then_some(t)
}

/// The first t at which the path comes within `radius` of the segment a–b (a capsule).
fn ray_capsule(p0: DVec2, p1: DVec2, a: DVec2, b: DVec2, radius: f64) -> Option<f64> {
    let ab = b - a;
    let mut best: Option<f64> = None;
    let mut keep = |t: Option<f64>| {
        if let Some(t) = t {
            best = Some(best.map_or(t, |b: f64| b.min(t)));
        }
    };
    keep(ray_circle(p0, p1, a, radius));
    keep(ray_circle(p0, p1, b, radius));
    let len = ab.length();
    if len > 0.0 {
        // The two long sides: lines parallel to ab at ±radius.
        let n = ab.perp() / len;
        let d = p1 - p0;
        for side in [radius, -radius] {
            let s0 = (p0 - a).dot(n) - side;
            let s1 = (p1 - a).dot(n) - side;
            if s0.signum() == s1.signum() || s0 == s1 {
                continue;
            }
            let t = s0 / (s0 - s1);
            let hit = p0 + d * t;
            let along = (hit - a).dot(ab) / (len * len);
            if (0.0..=1.0).contains(&along) && (0.0..=1.0).contains(&t) {
                keep(Some(t));
            }
        }
    }
    best
}

/// The first t at which the path comes within `r` of the box (the box's sides pushed out by r,
/// its corners rounded by r).
fn ray_rounded_box(p0: DVec2, p1: DVec2, half: DVec2, r: f64) -> Option<f64> {
    let corners = [
        DVec2::new(-half.x, -half.y),
        DVec2::new(half.x, -half.y),
        DVec2::new(half.x, half.y),
        DVec2::new(-half.x, half.y),
    ];
    let mut best: Option<f64> = None;
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        if let Some(t) = ray_capsule(p0, p1, a, b, r) {
            best = Some(best.map_or(t, |x: f64| x.min(t)));
        }
    }
    best
}

/// The contact's materials: Coulomb friction and restitution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Coulomb coefficient μ: the tangential velocity change is at most μ times the normal one.
    pub friction: f64,
    /// The share of the normal approach speed kept after an impact, 0..=1.
    pub restitution: f64,
    /// Below this approach speed an impact keeps nothing (m/s): a resting particle's approach
    /// is one step of gravity, and bouncing it back would make it jitter for ever.
    pub rest_speed: f64,
}

/// The velocity response of a particle in contact: its velocity relative to the surface
/// (`surface_velocity`) loses its approach along `normal` (and keeps `restitution` of it, above
/// the rest speed), and its tangential part shrinks by at most `friction` times that normal
/// change (to zero: static friction). A particle moving away from the surface is left as it is.
pub fn respond(v: DVec2, surface_velocity: DVec2, normal: DVec2, s: Surface) -> DVec2 {
    let rel = v - surface_velocity;
    let vn = rel.dot(normal);
    if vn >= 0.0 {
        return v;
    }
    let kept = if -vn > s.rest_speed {
        -vn * s.restitution
    } else {
        0.0
    };
    let dvn = kept - vn;
    let vt = rel - normal * vn;
    let speed_t = vt.length();
    let vt = if speed_t > s.friction * dvn {
        vt * (1.0 - s.friction * dvn / speed_t)
    } else {
        DVec2::ZERO
    };
    surface_velocity + normal * kept + vt
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(shape: Shape, center: DVec2, angle: f64) -> Placed {
        Placed::at(shape, center, angle)
    }

    /// A particle whose end lies past a closed shape's middle, from a start outside it, goes
    /// back out on the start's side: from a start in contact (resting on the surface) and from
    /// one clear of it, for a disc, a turned box and a turned hexagon, with ends at several
    /// depths past the middle. Out by the nearest surface it left through the far side.
    #[test]
    fn an_end_past_a_closed_shapes_middle_goes_back_out_on_its_start_side() {
        let r = 0.01;
        let hexagon: Vec<DVec2> = (0..6)
            .map(|k| DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_3) * 0.2)
            .collect();
        let shapes = [
            at(Shape::Circle { radius: 0.2 }, DVec2::new(0.5, 0.5), 0.0),
            at(
                Shape::Box {
                    half: DVec2::new(0.3, 0.1),
                },
                DVec2::new(0.5, 0.5),
                0.4,
            ),
            at(
                Shape::Polygon(Polygon::new(&hexagon).unwrap()),
                DVec2::new(0.5, 0.5),
                0.3,
            ),
        ];
        let mut tried = 0;
        for o in &shapes {
            for k in 0..16 {
                let dir = DVec2::from_angle(k as f64 * std::f64::consts::TAU / 16.0);
                // The surface point along `dir` from the centre, by bisection on the distance.
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if o.distance(o.pose.center + dir * mid).0 < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let edge = o.pose.center + dir * lo;
                for start_gap in [0.5 * r, 3.0 * r] {
                    let from = edge + o.distance(edge).1 * start_gap;
                    let (_, n0) = o.distance(from);
                    for past in [0.2, 0.5, 0.8] {
                        // An end past the middle, toward the far side.
                        let p = o.pose.center - dir * (lo * past);
                        let (d, far) = o.distance(p);
                        if d >= 0.0 || far.dot(n0) >= 0.0 {
                            // Nearest to a side of the start's own, or to one across: no far
                            // side to leave through.
                            continue;
                        }
                        tried += 1;
                        let t = o
                            .touch(p, from, -dir, r)
                            .expect("a particle inside touches");
                        let out = p + t.normal * t.depth;
                        assert!(
                            t.normal.dot(n0) > 0.99 && o.distance(out).0 >= r - 1e-9,
                            "{:?}: from {from} to {p}, out at {out} along {}",
                            o.shape,
                            t.normal
                        );
                    }
                }
            }
        }
        assert!(tried >= 100, "only {tried} ends past a middle");
    }

    #[test]
    fn distances_and_normals() {
        let c = at(Shape::Circle { radius: 1.0 }, DVec2::new(1.0, 0.0), 0.0);
        let (d, n) = c.distance(DVec2::new(3.0, 0.0));
        assert!((d - 1.0).abs() < 1e-15 && (n - DVec2::X).length() < 1e-15);

        let b = at(
            Shape::Box {
                half: DVec2::new(2.0, 1.0),
            },
            DVec2::ZERO,
            std::f64::consts::FRAC_PI_2,
        );
        // Rotated a quarter turn, the box is 2 tall: a point 1.5 above its centre is 0.5 inside.
        let (d, n) = b.distance(DVec2::new(0.0, 1.5));
        assert!(
            (d + 0.5).abs() < 1e-12 && (n - DVec2::Y).length() < 1e-12,
            "{d} {n}"
        );

        let s = at(
            Shape::Segment {
                a: DVec2::new(-1.0, 0.0),
                b: DVec2::new(1.0, 0.0),
                thickness: 0.1,
            },
            DVec2::ZERO,
            0.0,
        );
        let (d, n) = s.distance(DVec2::new(0.3, -0.5));
        assert!((d - 0.4).abs() < 1e-12 && (n + DVec2::Y).length() < 1e-12);
    }

    /// A hexagon: its distances and normals inside and out, and a fast path into it stops on
    /// its surface; corners given clockwise are turned round, and a dent is refused.
    #[test]
    fn a_convex_polygon_has_an_inside_an_outside_and_a_surface() {
        let hexagon: Vec<DVec2> = (0..6)
            .map(|k| DVec2::from_angle(-(k as f64) * std::f64::consts::FRAC_PI_3))
            .collect();
        let p = at(
            Shape::Polygon(Polygon::new(&hexagon).unwrap()),
            DVec2::new(1.0, 1.0),
            0.0,
        );
        let apothem = 3f64.sqrt() / 2.0;
        // Straight up from the centre: through the flat top edge.
        let (d, n) = p.distance(DVec2::new(1.0, 1.0 + 2.0));
        assert!((d - (2.0 - apothem)).abs() < 1e-12 && (n - DVec2::Y).length() < 1e-12);
        let (d, n) = p.distance(DVec2::new(1.0, 1.0 + 0.5));
        assert!((d - (0.5 - apothem)).abs() < 1e-12 && (n - DVec2::Y).length() < 1e-12);
        // Out past a corner: the distance to the corner.
        let (d, n) = p.distance(DVec2::new(3.0, 1.0));
        assert!(
            (d - 1.0).abs() < 1e-12 && (n - DVec2::X).length() < 1e-12,
            "{d} {n}"
        );
        let t = p
            .first_hit(DVec2::new(1.0, 4.0), DVec2::new(1.0, -2.0), 0.1)
            .expect("hits")
            .t;
        let hit = DVec2::new(1.0, 4.0) + DVec2::new(0.0, -6.0) * t;
        assert!((p.distance(hit).0 - 0.1).abs() < 1e-12, "{hit}");
        assert!(Polygon::new(&[DVec2::ZERO, DVec2::X, DVec2::new(0.2, 0.2), DVec2::Y]).is_err());
        assert!(Polygon::new(&[DVec2::ZERO, DVec2::X]).is_err());
    }

    #[test]
    fn a_fast_path_through_a_thin_segment_is_caught() {
        let s = at(
            Shape::Segment {
                a: DVec2::new(0.0, 0.4),
                b: DVec2::new(0.6, 0.2),
                thickness: 0.0,
            },
            DVec2::ZERO,
            0.0,
        );
        // 10 m/s for 1/60 s: 0.17 m, straight through the line.
        let (from, to) = (DVec2::new(0.3, 0.4), DVec2::new(0.3, 0.4 - 10.0 / 60.0));
        let t = s.first_hit(from, to, 0.0).expect("crosses").t;
        let hit = from + (to - from) * t;
        assert!(s.distance(hit).0.abs() < 1e-12, "{hit}");
        assert_eq!(s.first_hit(from, DVec2::new(0.3, 0.35), 0.0), None);
    }

    /// A point carried by a moving, turning obstacle keeps its place on it: its coordinates
    /// in the obstacle's frame at the step's start are those of the carried point at its end,
    /// for a box moving and turning over steps of several lengths; and nothing moves for a
    /// lead of 0 or an obstacle at rest.
    #[test]
    fn a_carried_point_keeps_its_place_on_the_obstacle() {
        let start = Placed {
            shape: Shape::Box {
                half: DVec2::new(0.2, 0.1),
            },
            pose: Pose {
                center: DVec2::new(0.4, -0.3),
                angle: 0.7,
                velocity: DVec2::new(1.5, -0.5),
                angular_velocity: 3.0,
            },
        };
        for dt in [1e-4, 1.0 / 60.0, 0.25] {
            let mut end = start;
            end.advance(dt);
            for p in [
                DVec2::new(0.1, 0.2),
                DVec2::new(-1.0, 0.5),
                start.pose.center,
            ] {
                let local = |o: &Placed, p| o.local(o.rotation(), p);
                let (before, after) = (local(&start, p), local(&end, end.carried(p, dt)));
                assert!(
                    (before - after).length() < 1e-12,
                    "{dt}: {before} -> {after}"
                );
            }
            assert_eq!(end.carried(DVec2::ONE, 0.0), DVec2::ONE);
        }
        let still = Placed {
            pose: Pose::default(),
            ..start
        };
        assert_eq!(still.carried(DVec2::ONE, 0.5), DVec2::ONE);
    }

    /// A particle resting on a thin closed shape, struck through it within a step, is caught
    /// where its path enters the shape itself: a disc of radius r, a turned box r thick and a
    /// polygon r thick, from a start in contact (r out, and on the surface for a point), on
    /// paths that end clear of the far side. A path that ends inside is left to `touch`, and
    /// one that heads away or along the surface is not caught.
    #[test]
    fn a_path_through_a_thin_closed_shape_from_contact_is_caught() {
        let r = 0.01;
        let corners = [
            DVec2::new(-0.2, -0.005),
            DVec2::new(0.2, -0.005),
            DVec2::new(0.2, 0.005),
            DVec2::new(-0.2, 0.005),
        ];
        let shapes = [
            at(Shape::Circle { radius: r }, DVec2::new(0.5, 0.4), 0.0),
            at(
                Shape::Box {
                    half: DVec2::new(0.2, 0.005),
                },
                DVec2::new(0.5, 0.4),
                0.3,
            ),
            at(
                Shape::Polygon(Polygon::new(&corners).unwrap()),
                DVec2::new(0.5, 0.4),
                -0.2,
            ),
        ];
        for o in &shapes {
            // The top of the shape, straight above its centre in its own frame.
            let up = o
                .distance(o.pose.center + DVec2::from_angle(o.pose.angle).perp())
                .1;
            let (d, _) = o.distance(o.pose.center + up * 0.001);
            let top = o.pose.center + up * (0.001 - d);
            for radius in [r, 0.0] {
                let from = top + up * radius;
                for travel in [3.0 * r, 5.0 * r, 0.2] {
                    let to = from - up * travel + up.perp() * 0.2 * travel;
                    let hit = o.first_hit(from, to, radius).expect("passes through");
                    assert!(hit.through, "{:?}", o.shape);
                    let entry = from + (to - from) * hit.t;
                    assert!(o.distance(entry).0.abs() < 1e-9, "{entry}");
                    assert!(
                        (entry - o.pose.center).dot(up) > 0.0,
                        "enters on the start's side: {entry}"
                    );
                }
                // Ends inside: `touch` puts it out.
                assert_eq!(o.first_hit(from, top - up * 0.006, radius), None);
                // Heads away, or slides along the surface.
                assert_eq!(o.first_hit(from, from + up * 0.1, radius), None);
                assert_eq!(o.first_hit(from, from + up.perp() * 0.001, radius), None);
            }
        }
    }

    #[test]
    fn friction_stops_slow_sliding_and_slows_fast_sliding() {
        let s = Surface {
            friction: 0.5,
            restitution: 0.0,
            rest_speed: 0.0,
        };
        // Into the floor at 1 m/s: the normal change is 1, so up to 0.5 of sliding goes.
        let v = respond(DVec2::new(0.3, -1.0), DVec2::ZERO, DVec2::Y, s);
        assert_eq!(v, DVec2::ZERO);
        let v = respond(DVec2::new(2.0, -1.0), DVec2::ZERO, DVec2::Y, s);
        assert!((v - DVec2::new(1.5, 0.0)).length() < 1e-15, "{v}");
        // Moving away: untouched.
        assert_eq!(
            respond(DVec2::new(2.0, 1.0), DVec2::ZERO, DVec2::Y, s),
            DVec2::new(2.0, 1.0)
        );
    }

    #[test]
    fn restitution_keeps_its_share_above_the_rest_speed() {
        let s = Surface {
            friction: 0.0,
            restitution: 0.5,
            rest_speed: 0.01,
        };
        assert_eq!(
            respond(DVec2::new(0.0, -2.0), DVec2::ZERO, DVec2::Y, s),
            DVec2::new(0.0, 1.0)
        );
        assert_eq!(
            respond(DVec2::new(0.0, -0.005), DVec2::ZERO, DVec2::Y, s),
            DVec2::ZERO
        );
    }

    #[test]
    fn a_moving_surface_carries_a_resting_particle() {
        let s = Surface {
            friction: 1.0,
            restitution: 0.0,
            rest_speed: 0.0,
        };
        // A belt at 0.5 m/s under a particle at rest pressed on it at 0.1 m/s: friction gives
        // it μ times the normal change, 0.1 m/s, toward the belt's speed.
        let belt = DVec2::new(0.5, 0.0);
        let v = respond(DVec2::new(0.0, -0.1), belt, DVec2::Y, s);
        assert!((v - DVec2::new(0.1, 0.0)).length() < 1e-15, "{v}");
    }
}
