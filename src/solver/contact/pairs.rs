//! Contact between particles: two particles closer than twice the contact radius are pushed
//! apart, whether they belong to two bodies or to one (self-collision), and their relative
//! velocity loses its approach (keeping the restitution's share) and, by friction, up to μ
//! times that of its sliding.
//!
//! **Which pairs.** Every pair not joined by a spring: its spring already keeps it apart, and
//! in a cloth or a soft box neighbours sit one spacing apart, closer than 2r once r is over half
//! of it. Pairs two springs apart do collide, so that a strip folded flat keeps its thickness
//! and the particles of a fold do not pass each other. So the radius must leave every pair not
//! joined by a spring apart at rest: in a grid with shear springs the nearest such pairs are two
//! spacings apart (r up to one spacing), in one without shear springs the diagonals at √2
//! spacings (r up to 0.7 of one). A radius of 0.4 to 0.5 spacings closes the gaps that another
//! body's particle could slip through.
//!
//! **Neighbour lists with a skin**, as molecular dynamics keeps them: every pair within
//! `2r + skin` is listed, through a spatial hash of cells that wide, and the lists are kept
//! until the particles may have moved far enough for an unlisted pair to touch. That bound is
//! on the displacements since the build *less a common shift*: if every displacement lies
//! within `skin/2` of one vector c, no pair's distance changed by more than the skin. c is the
//! centre of the displacements' bounding box, so a body that falls or slides as a whole keeps
//! its lists (a falling cloth rebuilds only once it starts to fold).
//!
//! **The solve**, after the step, before the obstacles and the ground (which have the last
//! word, being immovable): Jacobi iterations on positions, each particle moving by its inverse
//! mass share of each overlap it is in, averaged over those contacts (so that a particle
//! squeezed from two sides does not overshoot, with some over-relaxation), held out of the
//! ground and the obstacles between iterations; until the deepest overlap is under 1 % of 2r,
//! at most [`MAX_ITERATIONS`] times. Friction acts on velocities only: a position-level
//! friction like the obstacles' (taking back the step's relative sliding) fed energy into two
//! boxes stacked under projective dynamics at dt = 1/600 s (70 J of kinetic energy from a 17 J
//! drop). Then one velocity pass: each touching pair's relative
//! velocity goes through [`respond`], each particle taking its share. Every particle writes
//! only itself (into a buffer written back after the pass), and only the particles with listed
//! neighbours are visited, so the passes split over threads and cost what the contacts cost.
//!
//! **XPBD** also gets one Jacobi pass after each substep's sweeps (`Pairs::push_apart`, on
//! one thread while the others wait), so that the push enters the next substep's velocity as
//! the constraints' corrections do; implicit Euler and projective dynamics take the push of
//! the pass after the step into their velocity.

use super::obstacle::{SLOP, Surface, respond};
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// What two particles can close by in a step, for the lists of one step
/// ([`Pairs::ready_for_step`]): their relative velocity over `dt`, and `accel`, the body
/// forces' share (their spread over dt², doubled).
struct PairMotion<'a> {
    v: &'a [DVec2],
    dt: f64,
    accel: f64,
}

/// The largest distance of the vectors from the centre of their bounding box: half the
/// largest difference of two of them, at most.
fn spread(vectors: impl Iterator<Item = DVec2> + Clone) -> f64 {
    let (lo, hi) = vectors.clone().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v), hi.max(v)),
    );
    let centre = (lo + hi) / 2.0;
    vectors.fold(0.0f64, |m, v| m.max((v - centre).length()))
}

/// Each particle's spring neighbours, sorted: particle i's are `adjacent[span.0..span.1]`
/// for `span = spans[i]` (a pair that two springs join is listed twice).
pub(super) fn spring_neighbours(s: &State) -> (Vec<(u32, u32)>, Vec<u32>) {
    let n = s.x.len();
    let (start, entries) = s.spring_adjacency();
    let mut adjacent: Vec<u32> = entries.into_iter().map(|(other, _)| other).collect();
    let spans: Vec<(u32, u32)> = (0..n).map(|i| (start[i], start[i + 1])).collect();
    for &(a, b) in &spans {
        adjacent[a as usize..b as usize].sort_unstable();
    }
    (spans, adjacent)
}

/// Position iterations per step at most (a pile at dt = 1/60 s needs a few; at dt = 1e-4 s the
/// first one leaves under 1 % of overlap).
pub const MAX_ITERATIONS: usize = 32;

/// Jacobi's over-relaxation: a particle in `c` contacts moves by `min(1, 1.5/c)` of the sum of
/// its shares. Averaging alone (1/c) never overshoots but converged slowly in a pile (a fold of
/// cloth landing on the ground still overlapped by 5 % after 16 iterations); 1.5/c took a
/// third of the iterations there.
const RELAXATION: f64 = 1.5;

/// The pair passes split their particles over the threads in chunks of at least this many:
/// each comes with its list (about ten neighbours in a crumpled cloth), and the 256² cloth on
/// a disc has a few thousand listed particles, under the particle passes' threshold, through
/// up to 32 iterations a step.
const PAIR_CHUNK: usize = 1024;

/// The overlap, as a share of 2r, under which the position iterations stop.
pub const TOLERANCE: f64 = 0.01;

/// The particle-pair contact's lists and buffers, kept from step to step.
#[derive(Debug, Default)]
pub struct Pairs {
    /// The listed neighbours, each active particle's at `list[active_span.0..active_span.1]`.
    list: Vec<u32>,
    /// Positions at the last build.
    reference: Vec<DVec2>,
    /// What the lists were built for: particles, spring-graph revision, contact radius.
    built: Option<(usize, u64, f64)>,
    /// Spring neighbours of each particle, sorted: `adjacent[adjacency_span.0..]`.
    adjacency_span: Vec<(u32, u32)>,
    adjacent: Vec<u32>,
    adjacency_for: Option<(usize, u64)>,
    /// The skin the lists were built with.
    skin: f64,
    /// 0, 1, …, n − 1: a chunk of it tells a pass which particles it has.
    ids: Vec<u32>,
    /// The particles with listed neighbours (the only ones the passes visit), and their spans.
    active: Vec<u32>,
    active_span: Vec<(u32, u32)>,
    /// The passes' results for the active particles, written back after each pass.
    out: Vec<DVec2>,
    /// Positions before the iterations, when the velocity follows the push.
    before: Vec<DVec2>,
    /// Lists built so far.
    pub rebuilds: u64,
    /// Position iterations so far.
    pub iterations: u64,
    /// Steps the pass ran.
    pub steps: u64,
}

/// What one step's pair contact did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PairReport {
    /// Pairs touching at the end of the position iterations.
    pub contacts: usize,
    /// Pairs listed (within 2r + skin), each counted once.
    pub listed: usize,
}

impl Pairs {
    /// The skin for contact radius r: a wider one keeps the lists longer but lists more pairs;
    /// r itself (cells of 3r) kept the 256² cloth's lists for tens of steps at dt = 1e-4 s
    /// while they stayed short.
    pub fn skin(radius: f64) -> f64 {
        radius
    }

    /// The pair contact of the state's particles, at contact radius `radius`, with the
    /// velocity response of `surface` (its friction and restitution), and `keep_out` holding
    /// positions out of the ground and the obstacles. `velocity_follows: Some(dt)` adds each
    /// particle's push over dt to its velocity (the methods whose velocity is where the step
    /// went: a push the velocity did not see was taken back by the next step, the velocity
    /// kept, for ever). Returns what it did.
    pub fn collide(
        &mut self,
        s: &mut State,
        radius: f64,
        surface: Surface,
        keep_out: &(dyn Fn(DVec2, DVec2) -> DVec2 + Sync),
        velocity_follows: Option<f64>,
        threads: &Threads,
    ) -> PairReport {
        let n = s.x.len();
        if radius <= 0.0 || n < 2 {
            return PairReport::default();
        }
        self.steps += 1;
        let springs = s.springs.len();
        if self.ids.len() != n {
            self.ids = (0..n as u32).collect();
        }
        self.adjacency(s);
        if velocity_follows.is_some() {
            self.before.clear();
            self.before.extend_from_slice(&s.x);
        }
        let contact = 2.0 * radius;
        // The pairs the step left touching: the first iteration's (the later ones see them
        // pushed apart).
        let mut contacts = None;
        // The iterations move particles too, by up to an overlap: when that leaves the lists
        // stale they are built again and the iterations go on with them (once).
        for _ in 0..2 {
            if self.stale(s, radius, threads) {
                self.build(
                    &s.x,
                    radius,
                    Self::skin(radius),
                    s.revision,
                    threads,
                    springs,
                    None,
                );
            }
            if self.list.is_empty() {
                break;
            }
            let mut moved = false;
            for _ in 0..MAX_ITERATIONS {
                self.iterations += 1;
                let (touching, deepest) = self.separate(s, contact, keep_out, threads, springs);
                contacts.get_or_insert(touching / 2);
                moved |= touching > 0;
                if deepest <= TOLERANCE * contact {
                    break;
                }
            }
            if !moved || !self.stale(s, radius, threads) {
                break;
            }
        }
        let listed = self.list.len() / 2;
        if listed == 0 {
            return PairReport::default();
        }
        let pushed = contacts.unwrap_or(0);
        if let Some(dt) = velocity_follows
            && pushed > 0
        {
            for &i in &self.active {
                let i = i as usize;
                s.v[i] += (s.x[i] - self.before[i]) / dt;
            }
        }
        // Pairs at rest against each other touch without overlapping (explicit Euler moves with
        // the start-of-step velocity): the velocity pass runs whenever pairs are listed.
        let touching = self.respond(s, contact, surface, threads, springs);
        PairReport {
            contacts: pushed.max(touching),
            listed,
        }
    }

    /// Readies the lists for a solver that pushes pairs apart inside its own iterations
    /// (XPBD's substeps, [`Self::push_apart`]): built, if stale, with a skin that also covers
    /// how far two particles can close during the step (twice the fastest speed over dt, and
    /// the body forces' largest acceleration over dt², each relative to the others'). With
    /// `per_pair`, a step that moves particles farther than the skin gets lists of its own,
    /// each pair kept within its own relative closing. Returns whether any pair is listed.
    pub(crate) fn ready_for_step(
        &mut self,
        s: &State,
        radius: f64,
        dt: f64,
        per_pair: bool,
        threads: &Threads,
    ) -> bool {
        let n = s.x.len();
        if radius <= 0.0 || n < 2 {
            return false;
        }
        if self.ids.len() != n {
            self.ids = (0..n as u32).collect();
        }
        self.adjacency(s);
        // Two particles close by their relative motion only: each velocity's (and body-force
        // acceleration's) distance from the centre of their bounding box bounds half of it. A
        // falling cloth then lists its neighbours, not every pair within a step's fall (at
        // 1/60 s the 256² cloth listed thousands of pairs a particle, and stepped at 0.34
        // steps/s against 164 without contact).
        let fastest = spread(s.v.iter().copied());
        let accel = spread(s.f.iter().zip(&s.inv_mass).map(|(f, w)| *f * *w));
        let closing = 2.0 * (fastest * dt + accel * dt * dt);
        let base = Self::skin(radius);
        let skin = base + 2.0 * closing;
        // A step that moves particles farther than the skin, with `per_pair`: this step's
        // lists, each pair with what the two can close by their own relative velocity (twice
        // it, for the solve's corrections) and the body forces' spread. Searched within the
        // widest such reach, but short: neighbours falling together list each other only when
        // near.
        let per_step = per_pair && 2.0 * closing > base;
        if per_step || self.stale(s, radius, threads) || self.skin < skin {
            let motion = per_step.then_some(PairMotion {
                v: &s.v,
                dt,
                accel: 2.0 * accel * dt * dt,
            });
            let springs = s.springs.len();
            self.build(&s.x, radius, skin, s.revision, threads, springs, motion);
            if per_step {
                // Valid for this step only, as lists of the base skin for the pass after it.
                self.skin = base;
            }
        }
        !self.active.is_empty()
    }

    /// One serial Jacobi pass over the listed pairs of positions `x` (inverse masses `w`),
    /// contact distance `contact`, with `out` as scratch of the active particles' length: for a
    /// solver's own iterations, on one thread while the others wait. With `met_from`, where
    /// the step began, a pair that began it apart is pushed along the line it met on
    /// ([`met_along`]).
    pub(crate) fn push_apart(
        &self,
        x: &mut [DVec2],
        met_from: Option<&[DVec2]>,
        w: &[f64],
        contact: f64,
        out: &mut [DVec2],
    ) {
        for ((o, &i), &(a, b)) in out.iter_mut().zip(&self.active).zip(&self.active_span) {
            *o = pushed(
                i as usize,
                (x, met_from),
                w,
                &self.list[a as usize..b as usize],
                contact,
            )
            .0;
        }
        for (&i, o) in self.active.iter().zip(out.iter()) {
            x[i as usize] = *o;
        }
    }

    /// Particles with listed neighbours.
    pub(crate) fn active_count(&self) -> usize {
        self.active.len()
    }

    /// Position iterations per step, once the pass has run.
    pub fn iterations_per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.iterations as f64 / self.steps as f64)
    }

    /// The spring graph's adjacency, sorted, rebuilt when the springs changed.
    fn adjacency(&mut self, s: &State) {
        let key = (s.x.len(), s.revision);
        if self.adjacency_for == Some(key) && self.adjacent.len() == 2 * s.springs.len() {
            return;
        }
        (self.adjacency_span, self.adjacent) = spring_neighbours(s);
        self.adjacency_for = Some(key);
        self.built = None;
    }

    /// Whether the lists may miss a touching pair: built for other particles, springs or
    /// radius, or the displacements since, less their common shift, reach half the skin (a
    /// skin wider than the radius's own, built for XPBD's substeps, is kept while it holds).
    fn stale(&self, s: &State, radius: f64, threads: &Threads) -> bool {
        if self.built != Some((s.x.len(), s.revision, radius)) {
            return true;
        }
        let (lo, hi) = threads.chunked(
            s.springs.len(),
            (&s.x[..], &self.reference[..]),
            |(x, r)| {
                let mut lo = DVec2::splat(f64::INFINITY);
                let mut hi = DVec2::splat(f64::NEG_INFINITY);
                for (x, r) in x.iter().zip(r) {
                    let d = *x - *r;
                    lo = lo.min(d);
                    hi = hi.max(d);
                }
                (lo, hi)
            },
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
        // Every displacement is within half the box's diagonal of its centre; NaN is stale.
        let half_diagonal = 0.5 * (hi - lo).length();
        half_diagonal.is_nan() || half_diagonal > 0.5 * self.skin
    }

    /// Lists every pair within `reach` = 2r + `skin`, not excluded, through a spatial hash of
    /// cells `reach` wide; with `motion`, only the pairs within 2r + the base skin + what the
    /// two can close in the step ([`PairMotion`]).
    #[allow(clippy::too_many_arguments)]
    fn build(
        &mut self,
        x: &[DVec2],
        radius: f64,
        skin: f64,
        revision: u64,
        threads: &Threads,
        springs: usize,
        motion: Option<PairMotion>,
    ) {
        self.rebuilds += 1;
        self.skin = skin;
        let reach = 2.0 * radius + skin;
        let n = x.len();
        let table = (2 * n).next_power_of_two();
        let cell = |p: DVec2| ((p.x / reach).floor() as i64, (p.y / reach).floor() as i64);
        let slot = |c: (i64, i64)| {
            let h = c.0.wrapping_mul(92_837_111) ^ c.1.wrapping_mul(689_287_499);
            // The table's size is a power of two: a mask, not a division per cell.
            (h as u64 & (table as u64 - 1)) as usize
        };
        // Counting sort of the particles by hash slot.
        let mut start = vec![0u32; table + 1];
        let slots: Vec<usize> = x.iter().map(|p| slot(cell(*p))).collect();
        for &h in &slots {
            start[h + 1] += 1;
        }
        for h in 0..table {
            start[h + 1] += start[h];
        }
        // Each entry with its particle's position beside it: a slot's candidates are then read
        // in one run of memory, not one random read of the positions each.
        let mut fill = start.clone();
        let mut entries = vec![0u32; n];
        let mut at = vec![DVec2::ZERO; n];
        for (i, &h) in slots.iter().enumerate() {
            let k = fill[h] as usize;
            (entries[k], at[k]) = (i as u32, x[i]);
            fill[h] += 1;
        }
        let reach2 = reach * reach;
        // With motion: the reach of a pair at rest relative to each other.
        let near = 2.0 * radius + Self::skin(radius);
        let (adjacent, adjacency_span) = (&self.adjacent, &self.adjacency_span);
        let neighbours = |i: usize| -> &[u32] {
            let (a, b) = adjacency_span[i];
            &adjacent[a as usize..b as usize]
        };
        let excluded = |i: usize, j: usize| neighbours(i).binary_search(&(j as u32)).is_ok();
        let query = |ids: &[u32]| -> (Vec<(u32, u32)>, Vec<u32>) {
            let mut spans = Vec::with_capacity(ids.len());
            let mut list = Vec::new();
            for &i in ids {
                let i = i as usize;
                let (cx, cy) = cell(x[i]);
                let mut seen = [usize::MAX; 9];
                let begin = list.len() as u32;
                for (k, (dx, dy)) in (-1..=1)
                    .flat_map(|a| (-1..=1).map(move |b| (a, b)))
                    .enumerate()
                {
                    // Saturating: a particle flung far (a blow-up on its way to being
                    // caught) has its cell clamped at i64's ends, and a neighbour of that cell
                    // must not overflow.
                    let h = slot((cx.saturating_add(dx), cy.saturating_add(dy)));
                    if seen[..k].contains(&h) {
                        continue;
                    }
                    seen[k] = h;
                    let run = start[h] as usize..start[h + 1] as usize;
                    for (&j, &xj) in entries[run.clone()].iter().zip(&at[run]) {
                        let j = j as usize;
                        let d2 = (x[i] - xj).length_squared();
                        if j == i || d2 >= reach2 || excluded(i, j) {
                            continue;
                        }
                        if let Some(m) = &motion {
                            let near = near + 2.0 * (m.v[i] - m.v[j]).length() * m.dt + m.accel;
                            if d2 >= near * near {
                                continue;
                            }
                        }
                        list.push(j as u32);
                    }
                }
                spans.push((begin, list.len() as u32));
            }
            (spans, list)
        };
        let (spans, list) = threads.chunked(springs, &self.ids[..], query, |mut a, b| {
            let offset = a.1.len() as u32;
            a.0.extend(b.0.iter().map(|(s, e)| (s + offset, e + offset)));
            a.1.extend(b.1);
            a
        });
        self.active.clear();
        self.active_span.clear();
        for (i, &(a, b)) in spans.iter().enumerate() {
            if b > a {
                self.active.push(i as u32);
                self.active_span.push((a, b));
            }
        }
        self.list = list;
        self.reference.clear();
        self.reference.extend_from_slice(x);
        self.built = Some((n, revision, radius));
    }

    /// One Jacobi iteration on positions, over the particles with listed neighbours. Returns
    /// the touching (particle, neighbour) entries (each pair twice) and the deepest overlap
    /// before it.
    fn separate(
        &mut self,
        s: &mut State,
        contact: f64,
        keep_out: &(dyn Fn(DVec2, DVec2) -> DVec2 + Sync),
        threads: &Threads,
        springs: usize,
    ) -> (usize, f64) {
        self.out.resize(self.active.len(), DVec2::ZERO);
        let (x, w, list) = (&s.x, &s.inv_mass, &self.list);
        let data = (&mut self.out[..], &self.active[..], &self.active_span[..]);
        let found = threads.chunked_by(
            PAIR_CHUNK,
            springs,
            data,
            |(out, active, span)| {
                let (mut touching, mut deepest) = (0, 0.0f64);
                for ((o, &i), &(a, b)) in out.iter_mut().zip(active).zip(span) {
                    let i = i as usize;
                    let (to, t, d) =
                        pushed(i, (x, None), w, &list[a as usize..b as usize], contact);
                    // Only a particle the pass moved (the obstacles' own pass, swept, handles
                    // the rest).
                    *o = if to != x[i] { keep_out(to, x[i]) } else { to };
                    touching += t;
                    deepest = deepest.max(d);
                }
                (touching, deepest)
            },
            |a, b| (a.0 + b.0, a.1.max(b.1)),
        );
        for (&i, o) in self.active.iter().zip(&self.out) {
            s.x[i as usize] = *o;
        }
        found
    }

    /// The velocity pass: each touching pair's relative velocity through [`respond`], each
    /// particle taking its inverse-mass share, averaged over its contacts. Returns the pairs
    /// touching.
    fn respond(
        &mut self,
        s: &mut State,
        contact: f64,
        surface: Surface,
        threads: &Threads,
        springs: usize,
    ) -> usize {
        self.out.resize(self.active.len(), DVec2::ZERO);
        let (v, x, w, list) = (&s.v, &s.x, &s.inv_mass, &self.list);
        let touching = contact + SLOP;
        let data = (&mut self.out[..], &self.active[..], &self.active_span[..]);
        let pass = |(out, active, span): (&mut [DVec2], &[u32], &[(u32, u32)])| {
            let mut pairs = 0;
            for ((o, &i), &(a, b)) in out.iter_mut().zip(active).zip(span) {
                let i = i as usize;
                let wi = w[i];
                let (mut change, mut count) = (DVec2::ZERO, 0u32);
                for &j in &list[a as usize..b as usize] {
                    let j = j as usize;
                    let d = x[i] - x[j];
                    let dist = d.length();
                    if dist >= touching || dist == 0.0 {
                        continue;
                    }
                    pairs += 1;
                    if wi == 0.0 {
                        continue;
                    }
                    let n = d / dist;
                    let rel = v[i] - v[j];
                    let after = respond(rel, DVec2::ZERO, n, surface);
                    change += (after - rel) * (wi / (wi + w[j]));
                    count += 1;
                }
                *o = if count > 0 {
                    v[i] + change / count as f64
                } else {
                    v[i]
                };
            }
            pairs
        };
        let pairs = threads.chunked_by(PAIR_CHUNK, springs, data, pass, |a, b| a + b) / 2;
        for (&i, o) in self.active.iter().zip(&self.out) {
            s.v[i as usize] = *o;
        }
        pairs
    }
}

/// Where particle `i` goes in one Jacobi pass: its inverse-mass share of each overlap with
/// `neighbours`, averaged over those contacts with over-relaxation; with how many of them touch
/// it and the deepest overlap. Each overlap is pushed out along the pair's line, or, with
/// `met_from` and for a pair that began the step apart, along the line it met on
/// ([`met_along`]) until the two stand 2r apart along it.
fn pushed(
    i: usize,
    (x, met_from): (&[DVec2], Option<&[DVec2]>),
    w: &[f64],
    neighbours: &[u32],
    contact: f64,
) -> (DVec2, usize, f64) {
    let wi = w[i];
    let (mut push, mut count, mut touching, mut deepest) = (DVec2::ZERO, 0u32, 0, 0.0f64);
    for &j in neighbours {
        let j = j as usize;
        let d = x[i] - x[j];
        let dist2 = d.length_squared();
        if dist2 >= contact * contact {
            continue;
        }
        let dist = dist2.sqrt();
        deepest = deepest.max(contact - dist);
        touching += 1;
        let wsum = wi + w[j];
        if wi == 0.0 || wsum == 0.0 {
            continue;
        }
        if let Some(n) = met_from.and_then(|f| met_along(d, f[i] - f[j], contact)) {
            push += n * ((contact - d.dot(n)) * wi / wsum);
            count += 1;
            continue;
        }
        let n = if dist > 0.0 {
            d / dist
        } else if i < j {
            DVec2::X
        } else {
            DVec2::NEG_X
        };
        push += n * ((contact - dist) * wi / wsum);
        count += 1;
    }
    let to = if count > 0 {
        x[i] + push * (RELAXATION / count as f64).min(1.0)
    } else {
        x[i]
    };
    (to, touching, deepest)
}

/// For a pair now at `d` (one particle's position less the other's) that began the step at
/// `d0`, more than `contact` apart: the line the two met on, the direction of their relative
/// position where its straight path from `d0` to `d` first comes within `contact`. `None` for a
/// pair that began the step in contact, whose own line serves.
///
/// Why: a large step's solve moves a layer by many contact distances in one iteration. A fold
/// slapping down onto the strip below it at 1/60 s comes 5 cm a step against a contact
/// distance of 8.6 mm, and lands between that strip's particles or past them; pushed out along
/// their own line, such pairs went sideways or on through, the strip tangled, and its energy
/// rose from 8.8 J to 316 J under projective dynamics and 196 J under BDF2
/// (`folding_cloth`). Held to the side they met on, as a swept test holds a particle on its
/// side of a thin obstacle, the two end 2r apart along the line they met on
/// (`docs/performance-log.md`, 2026-12-07).
fn met_along(d: DVec2, d0: DVec2, contact: f64) -> Option<DVec2> {
    let c2 = contact * contact;
    let l0 = d0.length_squared();
    if l0 <= c2 {
        return None;
    }
    // |d0 + t e|² = c² at the smaller root t, in (0, 1] since |d0| > c ≥ |d|.
    let e = d - d0;
    let (a, b) = (e.length_squared(), d0.dot(e));
    let disc = (b * b - a * (l0 - c2)).max(0.0);
    let t = if a > 0.0 {
        ((-b - disc.sqrt()) / a).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (d0 + e * t).try_normalize()
}

#[cfg(test)]
mod tests {
    use super::met_along;
    use glam::DVec2;

    /// A pair that passed through each other in the step is held to the side it met on; one
    /// that met at an angle, along the line where it came within 2r; one that began the step
    /// in contact keeps its own line.
    #[test]
    fn a_pair_is_pushed_along_the_line_it_met_on() {
        let c = 0.01;
        let close = |a: DVec2, b: DVec2| (a - b).length() < 1e-12;
        // Head on, from 5 cm above to 3 mm below: met straight above.
        let n = met_along(DVec2::new(0.0, -0.003), DVec2::new(0.0, 0.05), c).unwrap();
        assert!(close(n, DVec2::Y), "{n}");
        // From (0.006, 0.05) down to (0.006, 0.002): met where y = √(c² − 0.006²) = 0.008.
        let n = met_along(DVec2::new(0.006, 0.002), DVec2::new(0.006, 0.05), c).unwrap();
        assert!(close(n, DVec2::new(0.6, 0.8)), "{n}");
        // Began the step in contact: its own line.
        assert_eq!(
            met_along(DVec2::new(0.0, 0.005), DVec2::new(0.0, 0.009), c),
            None
        );
    }
}
