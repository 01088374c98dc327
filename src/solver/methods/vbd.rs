//! Vertex block descent (Chen, Liu, Yang and Yuksel 2024, "Vertex Block Descent"), the
//! integrator `vbd`: backward Euler's variational problem,
//!
//! G(x) = Σ_i s m_i/(2h²) |x_i − y_i|² + Σ_springs ½ k (|x_a − x_b| − L)² + D(x),
//! y = x₀ + (h/s)(v₀ + h f_body/m),  s = 1 + hμ (μ = 0 unless the drag is in the solve),
//!
//! minimised by block coordinate descent with one 2×2 block per vertex. Each iteration visits
//! the vertices colour by colour (no two vertices of a colour share a spring) and moves each
//! free vertex by one Newton step on G with the other vertices held: x_i += H_i⁻¹ f_i, with
//!
//! * f_i = −s m_i/h² (x_i − y_i) − Σ k (l − L) n (each spring at the vertex, n from the other
//!   end to it, l its length) + the gas force, and
//! * H_i = s m_i/h² I + Σ [k n nᵀ + k max(0, 1 − L/l) (I − n nᵀ)].
//!
//! A spring's Hessian k n nᵀ + k (1 − L/l)(I − n nᵀ) is indefinite when the spring is compressed
//! (l < L): its transverse eigenvalue k (1 − L/l) is negative. That eigenvalue is clamped at 0
//! (the projection onto the positive semi-definite cone, eigenvector by eigenvector), so H_i ⪰
//! s m_i/h² I and every block step descends. A step whose determinant is below 1e-12 of its
//! trace squared is skipped (only a vertex of no mass could have one). Without the clamp, a
//! stiff cloth crushed to 40 % of its rest size (k = 1e6, 1/60 s) went to NaN in its first
//! step (`tests/bdf2_vbd.rs`).
//!
//! Dashpots enter as their Rayleigh dissipation D = c/(2h) (n·(Δx_a − Δx_b))², Δx = x − x₀,
//! with n the spring's current direction: force −(c/h) n nᵀ (Δx_i − Δx_j), Hessian (c/h) n nᵀ.
//! Gas bodies add their pressure force, evaluated once per iteration at its start (as
//! projective dynamics does), and nothing to the Hessian.
//!
//! Initialisation (the paper's adaptive one, section 3.7): x = x₀ + h v₀ + h² ã with ã the part
//! of the last step's acceleration (v₀ − v₋₁)/h along the body force's direction, clamped
//! between 0 and the body force's acceleration. At rest ã = 0 and the start is x₀, so a settled
//! state is the exact equilibrium for any iteration count (a fixed point of the descent is a
//! stationary point of G). The first step, or the first after an edit, takes ã = 0.
//!
//! Chebyshev acceleration (the paper's section 3.8) is optional, with an estimate ρ of the
//! spectral radius (`iterations.vbd_chebyshev`, 0 = off): after iteration k ≥ 2,
//! x ← ω_k (x − x_{k−2}) + x_{k−2}, ω₂ = 2/(2 − ρ²), ω_k = 4/(4 − ρ² ω_{k−1}).
//!
//! Rigid bodies of another engine (the obstacles whose [`crate::solver::Reactions`] give them a
//! mass) are blocks of the descent too: after each sweep each takes Newton steps on its inertia
//! plus its contacts with the particles held, and the next sweep keeps the particles out of it
//! where it then stands (`contact::solved`). The body starts where the step began; the step ends
//! on a sweep, with the particles out of the body where the solve left it, and its engine is
//! given the impulse that takes it there.
//!
//! Nothing is factorised: the colouring (linear in the springs) is all a change of the spring
//! graph or the pins costs. Threads: the pool's threads work through each colour's vertices in
//! shares as one team ([`crate::solver::threads::team`]), meeting at a barrier after each colour, so the sweep is
//! the one-thread sweep bit for bit.

use crate::solver::contact::inside::InSolve;
use crate::solver::contact::landing::Landing;
use crate::solver::contact::slide::{Contact, Slides};
use crate::solver::contact::solved::SolvedBodies;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use crate::solver::threads::team::Shared;
use glam::DVec2;

/// The colouring, the adjacency and the buffers, kept from step to step.
#[derive(Debug, Default)]
pub struct Vbd {
    /// The state revision the colouring is for.
    revision: Option<u64>,
    /// Each particle's springs from `adjacency_start[i]`, with what the block step reads of
    /// them (kept beside the vertex, so the sweep reads no spring through an index).
    adjacency_start: Vec<u32>,
    adjacency: Vec<Edge>,
    /// Free vertices grouped by colour, and each colour's start (and the end).
    vertices: Vec<u32>,
    colour_starts: Vec<usize>,
    /// The iterate, the inertial target y, the iterate two iterations back (Chebyshev), the
    /// gas forces of the iteration.
    x: Vec<DVec2>,
    y: Vec<DVec2>,
    before: Vec<DVec2>,
    previous: Vec<DVec2>,
    gas: Vec<DVec2>,
    /// Each vertex's last unconstrained block step and its block's Hessian (h00, h01, h11),
    /// when bodies move among the unknowns.
    free: Vec<DVec2>,
    blocks: Vec<[f64; 3]>,
    /// The bodies the particles touch, moved among the unknowns.
    bodies: SolvedBodies,
    /// Each vertex's acceleration over the last step as its solve found it (before the passes
    /// after the step: the air damping, contact), and the edits it was under (for the adaptive
    /// initialisation).
    last_a: Vec<DVec2>,
    last_edits: Option<u64>,
    /// The buffers that hold a landing body's start back ([`Landing`]).
    landing: Landing,
    /// The groups that slide along a surface as a whole, with each vertex's contact from the
    /// last sweep ([`Slides`]).
    slides: Slides,
    /// Colourings so far, and their wall time, s.
    pub colourings: u64,
    pub colouring_seconds: f64,
    /// Iterations so far.
    pub iterations: u64,
    /// Steps so far.
    pub steps: u64,
}

impl Vbd {
    /// For a repacked state: the counters carry on; the colouring is redone (the new
    /// revision) and the adaptive start waits a step (the indices changed).
    pub(crate) fn repacked(mut self) -> Vbd {
        self.last_edits = None;
        self.revision = None;
        self
    }

    /// The obstacles whose bodies the last step moved among its unknowns, with their
    /// velocities over the step ([`crate::solver::Workspace::solved_motion`]).
    pub(crate) fn solved_motion(&self) -> impl Iterator<Item = (usize, DVec2, f64)> + '_ {
        self.bodies.motion()
    }

    /// Colours of the vertex graph (0 before the first step).
    pub fn colours(&self) -> usize {
        self.colour_starts.len().saturating_sub(1)
    }

    /// Mean iterations per step so far.
    pub fn iterations_per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.iterations as f64 / self.steps as f64)
    }

    /// The adjacency and a greedy colouring of the free vertices in index order: each takes
    /// the lowest colour none of its neighbours has.
    fn colour(&mut self, s: &State) {
        let start = std::time::Instant::now();
        let n = s.x.len();
        let (starts, entries) = s.spring_adjacency();
        self.adjacency_start = starts;
        self.adjacency = entries
            .into_iter()
            .map(|(other, k)| {
                let sp = &s.springs[k as usize];
                Edge {
                    other,
                    spring: k,
                    rest: sp.rest,
                    k: sp.k,
                }
            })
            .collect();
        const NONE: u32 = u32::MAX;
        let mut colour_of = vec![NONE; n];
        let mut taken: Vec<bool> = vec![];
        let mut colours = 0usize;
        for i in 0..n {
            if s.inv_mass[i] == 0.0 {
                continue;
            }
            taken.clear();
            taken.resize(colours + 1, false);
            for e in self.neighbours(i) {
                let c = colour_of[e.other as usize];
                if c != NONE {
                    taken[c as usize] = true;
                }
            }
            let c = taken.iter().position(|t| !t).unwrap_or(colours);
            colour_of[i] = c as u32;
            colours = colours.max(c + 1);
        }
        let mut starts = vec![0usize; colours + 1];
        for &c in colour_of.iter().filter(|&&c| c != NONE) {
            starts[c as usize + 1] += 1;
        }
        for c in 0..colours {
            starts[c + 1] += starts[c];
        }
        self.vertices = vec![0; starts[colours]];
        let mut at = starts.clone();
        for (i, &c) in colour_of.iter().enumerate() {
            if c != NONE {
                self.vertices[at[c as usize]] = i as u32;
                at[c as usize] += 1;
            }
        }
        self.colour_starts = starts;
        self.revision = Some(s.revision);
        self.colourings += 1;
        self.colouring_seconds += start.elapsed().as_secs_f64();
    }

    fn neighbours(&self, i: usize) -> &[Edge] {
        let (a, b) = (self.adjacency_start[i], self.adjacency_start[i + 1]);
        &self.adjacency[a as usize..b as usize]
    }
}

/// A spring as one of its ends sees it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Edge {
    /// The other end.
    other: u32,
    /// The packed spring.
    spring: u32,
    rest: f64,
    k: f64,
}

/// The settings of one VBD step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Iterations (sweeps over every vertex).
    pub iterations: u32,
    /// The air drag μ inside the solve (0: the damping pass applies it).
    pub drag: f64,
    /// Chebyshev's ρ (0: off).
    pub chebyshev: f64,
}

/// What one vertex's block step reads.
#[derive(Clone, Copy)]
struct Block<'a> {
    s: &'a State,
    vbd_adj_start: &'a [u32],
    adjacency: &'a [Edge],
    y: &'a [DVec2],
    gas: Option<&'a [DVec2]>,
    dashpot: &'a [f64],
    /// Contact inside the solve: each vertex step's result is kept out of the surfaces.
    contact: Option<&'a InSolve<'a>>,
    /// When bodies move among the unknowns: each vertex's unconstrained step and its block's
    /// Hessian, for the bodies' steps.
    free: Option<(Shared<DVec2>, Shared<[f64; 3]>)>,
    /// With contact: each vertex's contact, for the groups' slides ([`Slides`]).
    contacts: Option<Shared<Contact>>,
    /// s/h² and 1/h.
    inertia: f64,
    inv_h: f64,
}

impl Block<'_> {
    /// Vertex i's Newton step on G with the others held (see the module docs), from `x`.
    ///
    /// # Safety
    /// No other thread writes vertex i or its neighbours while this runs (the colouring's
    /// promise).
    #[inline(always)]
    unsafe fn relax<const DASHPOTS: bool>(&self, i: usize, x: Shared<DVec2>) {
        let s = self.s;
        // SAFETY: the caller's.
        let xi = unsafe { x.get(i) };
        let mi = s.mass[i] * self.inertia;
        let mut f = (self.y[i] - xi) * mi;
        let (mut h00, mut h01, mut h11) = (mi, 0.0, mi);

        let (a, b) = (self.vbd_adj_start[i], self.vbd_adj_start[i + 1]);
        for e in &self.adjacency[a as usize..b as usize] {
            let j = e.other as usize;
            // SAFETY: the caller's: a neighbour is of another colour, not written now.
            let xj = unsafe { x.get(j) };
            let d = xi - xj;
            let l2 = d.length_squared();
            if l2 == 0.0 {
                continue;
            }
            let inv_l = 1.0 / l2.sqrt();
            let n = d * inv_l;
            // k n nᵀ + k max(0, 1 − L/l)(I − n nᵀ) = t I + (k − t) n nᵀ, t = k max(0, 1 − L/l).
            let stretch = 1.0 - e.rest * inv_l;
            f -= d * (e.k * stretch);
            let t = e.k * stretch.max(0.0);
            let mut along = e.k - t;
            if DASHPOTS {
                let c = self.dashpot[e.spring as usize];
                let moved = (xi - s.x[i]) - (xj - s.x[j]);
                let g = c * self.inv_h;
                f -= n * (g * n.dot(moved));
                along += g;
            }
            h00 += t + along * n.x * n.x;
            h01 += along * n.x * n.y;
            h11 += t + along * n.y * n.y;
        }
        if let Some(gas) = self.gas {
            f += gas[i];
        }
        let det = h00 * h11 - h01 * h01;
        let trace = h00 + h11;
        // (Written so that a NaN determinant skips too.)
        if det.is_nan() || det <= 1e-12 * trace * trace {
            return;
        }
        let step = DVec2::new(h11 * f.x - h01 * f.y, h00 * f.y - h01 * f.x) / det;
        let mut end = xi + step;
        if let Some(c) = self.contact {
            // Projected block descent: the vertex's constraints (the obstacles, the ground)
            // are its own, so holding each step's result to them descends on the constrained
            // objective.
            let held = c.keep_out(i, &mut end, self.s.x[i]);
            if let Some(contacts) = self.contacts {
                let met = Contact::met(c, held, xi + step, end, [h00, h01, h11]);
                // SAFETY: the caller's: vertex i is this thread's alone now.
                unsafe { contacts.set(i, met) };
            }
        }
        if let Some((free, blocks)) = self.free {
            // SAFETY: the caller's: vertex i is this thread's alone now.
            unsafe {
                free.set(i, xi + step);
                blocks.set(i, [h00, h01, h11]);
            }
        }
        // SAFETY: the caller's.
        unsafe { x.set(i, end) };
    }
}

/// One VBD step (see the module docs): sets v to (x₁ − x₀)/h for the free particles; the
/// position update then moves x₀ there. `s.f` holds the body forces.
pub fn step(
    s: &mut State,
    vb: &mut Vbd,
    dt: f64,
    settings: Settings,
    contact: Option<&InSolve>,
    threads: &Threads,
) {
    if vb.revision != Some(s.revision) || vb.adjacency.len() != 2 * s.springs.len() {
        vb.colour(s);
    } else if s.materials.moves_rest_lengths() {
        // Muscles and plastic springs move rest lengths between steps.
        for e in &mut vb.adjacency {
            e.rest = s.springs[e.spring as usize].rest;
        }
    }
    let n = s.x.len();
    let springs = s.springs.len();
    for buf in [&mut vb.x, &mut vb.y, &mut vb.gas, &mut vb.last_a] {
        buf.resize(n, DVec2::ZERO);
    }
    let scale = 1.0 + dt * settings.drag;
    let h_over_s = dt / scale;
    let h2 = dt * dt;
    // The descent starts from x₀ + h v₀ + h² a, a the body forces' share of the acceleration
    // the last step's solve found (Chen et al.'s adaptive initialisation: a particle resting
    // on a surface starts where it rests), under the same edits; without a last step, all of
    // the body forces' acceleration, as a free particle's is. Block descent moves a stiff body
    // as a whole by about m/(m + h²Σk) of the remaining way a sweep (1/556 for a strip of 20 g
    // particles at k = 1e4 and 1/30 s), so the start must carry the body's motion. Until
    // 2026-12-07 a was 0 without a last step, and measured from the start velocities, after
    // the damping pass had taken its share: a strip dropped from rest under gravity fell
    // 0.17 m in 0.5 s at 1/60 s and 0.04 m at 1/30 s, where it falls 0.90 m (with the
    // scene's damping, μ = 2).
    let adaptive = vb.last_edits == Some(s.edits);
    let data = (
        (&mut vb.x[..], &mut vb.y[..], &vb.last_a[..]),
        (&s.x[..], &s.v[..], &s.f[..]),
        &s.inv_mass[..],
    );
    threads.each(springs, data, |((x, y, last_a), (x0, v0, f), w)| {
        for i in 0..x.len() {
            if w[i] == 0.0 {
                // A pinned or held particle moves as it is moved.
                x[i] = x0[i] + v0[i] * dt;
                y[i] = x[i];
                continue;
            }
            let body = f[i] * w[i];
            y[i] = x0[i] + (v0[i] + body * dt) * h_over_s;
            let mut start = x0[i] + v0[i] * dt;
            let g = body.length();
            if g > 0.0 {
                // The body forces' share of the last step's acceleration, or all of it with no
                // last step to read (see `adaptive` above).
                let along = body / g;
                let a = if adaptive {
                    last_a[i].dot(along).clamp(0.0, g)
                } else {
                    g
                };
                start += along * (a * h2);
            }
            x[i] = start;
        }
    });
    vb.last_edits = Some(s.edits);
    if let Some(c) = contact {
        // A landing body starts where it first touches, whole ([`Landing`]).
        vb.landing.hold_back(&mut vb.x, s, c);
    }
    // The start of the descent: the inertial one, or the start-of-step positions where those
    // give the lower objective (at very large steps, h·ω ≫ 1, the inertial start lies far up
    // the springs' potential and a few iterations from it leave energy in the cloth; from x₀
    // they leave it nearly static, as the converged step is).
    let inertia = scale / h2;
    vb.before.clear();
    vb.before.extend((0..n).map(|i| {
        if s.inv_mass[i] != 0.0 {
            s.x[i]
        } else {
            vb.x[i]
        }
    }));
    let (inertial, still) = objectives(s, (&vb.x, &vb.before), &vb.y, inertia);
    if still < inertial {
        std::mem::swap(&mut vb.x, &mut vb.before);
    }
    let has_gas = !s.materials.gas().is_empty();
    let iterations = settings.iterations.max(1);
    let rho2 = settings.chebyshev * settings.chebyshev;
    let chebyshev = rho2 > 0.0 && iterations > 2;
    // Chebyshev's iterates two and one back.
    vb.before.resize(if chebyshev { n } else { 0 }, DVec2::ZERO);
    vb.previous
        .resize(if chebyshev { n } else { 0 }, DVec2::ZERO);
    // The bodies among the unknowns, when the contacts are noted for bodies, with each
    // vertex's last unconstrained block step and its block's Hessian for their steps.
    vb.bodies.clear();
    let solved = contact.is_some_and(|c| vb.bodies.ready(c, dt));
    let free_len = if solved { n } else { 0 };
    vb.free.clear();
    vb.free.resize(free_len, DVec2::ZERO);
    vb.blocks.clear();
    vb.blocks.resize(free_len, [0.0; 3]);
    let free = solved.then(|| (Shared::new(&mut vb.free), Shared::new(&mut vb.blocks)));
    let surface = contact.map_or((0.0, 0.0), |c| (c.radius(), c.friction()));
    let sliding = contact.is_some();
    if sliding {
        vb.slides.ready(s);
    }
    let contacts = sliding.then(|| Shared::new(&mut vb.slides.contacts[..]));
    let block = Block {
        s,
        vbd_adj_start: &vb.adjacency_start,
        adjacency: &vb.adjacency,
        y: &vb.y,
        gas: None,
        dashpot: s.materials.dashpot(),
        contact,
        free,
        contacts,
        inertia: scale / h2,
        inv_h: 1.0 / dt,
    };
    let dashpots = s.materials.has_dashpots();
    let (x, gas) = (Shared::new(&mut vb.x), Shared::new(&mut vb.gas));
    let (before, previous) = (Shared::new(&mut vb.before), Shared::new(&mut vb.previous));
    let (vertices, starts) = (&vb.vertices[..], &vb.colour_starts[..]);
    let (materials, w, x0) = (&s.materials, &s.inv_mass[..], &s.x[..]);
    let mut pair_scratch = vec![DVec2::ZERO; contact.map_or(0, |c| c.pair_scratch())];
    let pair_len = pair_scratch.len();
    let pair_scratch = Shared::new(&mut pair_scratch);
    let bodies = Shared::new(std::slice::from_mut(&mut vb.bodies));
    let slides = &vb.slides;
    let (y, mass) = (&vb.y[..], &s.mass[..]);
    // The pool's threads as one team for the whole step (a fork and a join per iteration
    // cost as much as an iteration of a 32² cloth).
    threads.team(springs, |team| {
        let mine = team.share(0..n);
        let mut omega = 1.0;
        for k in 0..iterations {
            if has_gas {
                // The gas forces at the iteration's start, on one member.
                if !team.share(0..1).is_empty() {
                    // SAFETY: the others wait at the barrier below, touching nothing.
                    let (x, out) = unsafe { (x.part(0..n), gas.part(0..n)) };
                    materials.gas_forces_into(x, out);
                }
                team.wait();
            }
            if let Some((free, blocks)) = free.filter(|_| k > 0) {
                // The bodies' steps with the particles held, on one member, from the last
                // sweep's blocks; the sweep that follows keeps the particles out of the bodies
                // where they then stand, so that the step ends on a sweep, with the particles
                // out of each body where the solve leaves it.
                if !team.share(0..1).is_empty() {
                    // SAFETY: the other members wait at the barrier below, touching nothing;
                    // the blocks were written before the barrier above.
                    let (bodies, free, blocks) =
                        unsafe { (&mut bodies.part(0..1)[0], free.read(), blocks.read()) };
                    bodies.step(free, blocks, x0, w, surface);
                }
                team.wait();
            }
            if sliding {
                // The groups resting on a surface slide along it as a whole, on one member,
                // from the contacts of the last sweep (of the last step, before the first).
                if !team.share(0..1).is_empty() {
                    // SAFETY: the other members wait at the barrier below, touching nothing;
                    // the contacts were written before the barrier above.
                    let shared = contacts.expect("readied with the slides");
                    let (seen, x) = unsafe { (shared.read(), x.part(0..n)) };
                    slides.step(seen, x, (y, x0, mass), inertia, surface.1);
                }
                team.wait();
            }
            if chebyshev {
                // SAFETY: this member's particles.
                let (x, previous) = unsafe { (x.part(mine.clone()), previous.part(mine.clone())) };
                previous.copy_from_slice(x);
                team.wait();
            }
            // The obstacles where the bodies now stand.
            // SAFETY: written by one member between the barriers after the sweep, read only
            // now.
            let moved = solved.then(|| unsafe { &bodies.read()[0] });
            let here = contact.map(|c| match moved {
                Some(b) => b.seen_by(c),
                None => *c,
            });
            let block = Block {
                // SAFETY: written before the barrier above, read only now.
                gas: has_gas.then(|| unsafe { gas.read() }),
                contact: here.as_ref(),
                ..block
            };
            for colour in starts.windows(2) {
                for &i in &vertices[team.share(colour[0]..colour[1])] {
                    // SAFETY: within a colour no two vertices share a spring, so this member
                    // writes vertex i alone and reads neighbours no member writes now; the
                    // colours are separated by the barrier below.
                    unsafe {
                        if dashpots {
                            block.relax::<true>(i as usize, x)
                        } else {
                            block.relax::<false>(i as usize, x)
                        }
                    };
                }
                team.wait();
            }
            if let Some(c) = contact.filter(|c| c.has_pairs()) {
                // The pairs, pushed apart on one member while the others wait (only the
                // particles with listed neighbours), then held out of the surfaces.
                if !team.share(0..1).is_empty() {
                    // SAFETY: the other members wait at the barrier below, touching nothing.
                    let (x, out) = unsafe { (x.part(0..n), pair_scratch.part(0..pair_len)) };
                    // Not the outlines: pushed between the block descent's iterations they
                    // blew the pile up (180 J to 27,000 J at 1/60 s); after the step (pass 6)
                    // they hold it.
                    let held = &mut Vec::new(); // one pass: none kept between passes
                    c.without_outlines()
                        .project(x, x0, w, (out, held), |_, _, _| {});
                }
                team.wait();
            }
            if chebyshev {
                if k >= 1 {
                    omega = if k == 1 {
                        2.0 / (2.0 - rho2)
                    } else {
                        4.0 / (4.0 - rho2 * omega)
                    };
                    // SAFETY: this member's particles.
                    let (x, before) = unsafe { (x.part(mine.clone()), before.part(mine.clone())) };
                    for ((x, b), &w) in x.iter_mut().zip(before.iter()).zip(&w[mine.clone()]) {
                        if w != 0.0 {
                            *x = *b + (*x - *b) * omega;
                        }
                    }
                }
                // The iterate one back becomes the one two back.
                // SAFETY: this member's particles.
                let (before, previous) =
                    unsafe { (before.part(mine.clone()), previous.part(mine.clone())) };
                before.copy_from_slice(previous);
                team.wait();
            }
        }
    });
    if let Some(c) = contact.filter(|_| solved) {
        // The bodies are given what takes them where the descent left them.
        vb.bodies.give(c);
    }
    let inv_h = 1.0 / dt;
    let data = (
        (&mut s.v[..], &mut vb.last_a[..]),
        &vb.x[..],
        &s.x[..],
        &s.inv_mass[..],
    );
    threads.each(springs, data, |((v, a), x, x0, w)| {
        for i in 0..v.len() {
            if w[i] != 0.0 {
                let end = (x[i] - x0[i]) * inv_h;
                a[i] = (end - v[i]) * inv_h;
                v[i] = end;
            } else {
                // Moved by hand, not by its forces: a particle let go starts with none.
                a[i] = DVec2::ZERO;
            }
        }
    });
    vb.iterations += iterations as u64;
    vb.steps += 1;
}

/// The objective G at two sets of positions in one pass, without the dashpots and gas:
/// Σ s m/(2h²)|x − y|² over the free particles plus the springs' potential.
fn objectives(s: &State, (p, q): (&[DVec2], &[DVec2]), y: &[DVec2], inertia: f64) -> (f64, f64) {
    let (mut gp, mut gq) = (0.0, 0.0);
    for i in 0..p.len() {
        if s.inv_mass[i] != 0.0 {
            let m = 0.5 * inertia * s.mass[i];
            gp += m * (p[i] - y[i]).length_squared();
            gq += m * (q[i] - y[i]).length_squared();
        }
    }
    for sp in &s.springs {
        let (a, b) = (sp.a as usize, sp.b as usize);
        let sp_ = (p[a] - p[b]).length() - sp.rest;
        let sq = (q[a] - q[b]).length() - sp.rest;
        gp += 0.5 * sp.k * sp_ * sp_;
        gq += 0.5 * sp.k * sq * sq;
    }
    (gp, gq)
}
