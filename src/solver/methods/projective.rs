//! Projective dynamics (Liu, Bargteil, O'Brien and Kavan 2013, "Fast Simulation of
//! Mass-Spring Systems"): backward Euler as the minimisation of
//!
//! Φ(x) = 1/(2h²) ‖x − y‖²_M + Σ_s ½ k_s ‖x_a − x_b − d_s‖²,  y = x0 + h v0 + h² M⁻¹ f_body,
//!
//! over the positions x and, per spring, a vector d_s of length L_s (for the best d_s,
//! ‖x_a − x_b − d_s‖ = | |x_a − x_b| − L_s |, so the minimum over x is the backward Euler step).
//! Each iteration alternates
//! * the local step: d_s = L_s (x_a − x_b)/|x_a − x_b| for every spring (a pair pass, threaded
//!   like the spring forces), and
//! * the global step: (M + h² L) x = M y + h² J d, with L = Σ k_s A_s A_sᵀ the weighted graph
//!   Laplacian. The matrix depends only on masses, stiffnesses, the spring graph, the pins and
//!   h, so it is factored once (faer's sparse Cholesky, in the cheaper for the substitutions of
//!   two orders: faer's minimum degree, and nested dissection from the particles' positions,
//!   [`crate::solver::linear::ordering`]) and every iteration costs one forward and one backward substitution,
//!   for x and y together (an n × 2 right-hand side: the factor is read once per iteration).
//!
//! The global step is solved for the correction: x ← x + Ã⁻¹ r with the residual
//! r = M y + h² J d − (M + h² L) x = M (y − x) + Σ_s h² k_s (d_s − (x_a − x_b)), one pair pass
//! in f64. With the exact inverse this is the textbook update (x + A⁻¹(b − A x) = A⁻¹ b); the
//! factor's values are stored in f32 and the solve computes in f32, which halves what each
//! iteration reads and doubles the lanes of its arithmetic ([`crate::solver::linear::cholesky`]), and in this
//! form that rounding costs only a little of each iteration's progress: the fixed point, r = 0,
//! is Φ's minimiser in f64 whatever Ã is.
//!
//! Particles with inverse mass 0 (pinned or held) are eliminated: their end-of-step position
//! x0 + h v0 is known, and their springs' terms at the free end carry it. Every iteration lowers
//! Φ (up to the solve's rounding, about 1e-6 of the correction), and the iterations start from
//! x0 + h v0 (the inertial guess without the body forces):
//! at rest that is the previous step's shape, so a settled state is the exact equilibrium for
//! any iteration count (the fixed points of a descent step are Φ's minimisers). The step ends
//! with v1 = (x1 − x0)/h; damping, ground contact and the position update follow as for
//! implicit Euler.

use crate::solver::contact::groups::{join, root};
use crate::solver::contact::inside::InSolve;
use crate::solver::contact::support::Support;
use crate::solver::forces::spring::{projection_residual, scatter_pairs};
#[cfg(target_arch = "x86_64")]
use crate::solver::forces::wide;
use crate::solver::linear::cholesky::{Factor, Stored, Substitution, permutation};
use crate::solver::linear::ordering::{adjacency, nested_dissection};
use crate::solver::state::{PackedSpring, State};
use crate::solver::threads::{PairPass, SpringBuffers, Threads, scatter_from};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Par, Side};
use glam::DVec2;
use std::time::Instant;

/// The largest bound on the global matrix's condition number for which its factor is stored
/// in f32 (above it, in f64; see [`Projective::prepare`]).
pub const MAX_CONDITION_FOR_F32: f64 = 1e5;

/// The fill-reducing orders projective dynamics chooses from for its factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FactorOrder {
    /// faer's approximate minimum degree.
    MinimumDegree,
    /// Nested dissection by coordinate bisection of the particles' positions.
    NestedDissection,
}

/// A symbolic factorisation and the pattern it was made for.
struct Structure {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// The order that was asked for ([`Projective::fill_order`]).
    asked: Option<FactorOrder>,
    symbolic: SymbolicCholesky<usize>,
    order: FactorOrder,
}

/// What the factorisation was computed for: redone when any of it changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Key {
    /// the state's revision: the spring graph, stiffnesses, masses and pins.
    revision: u64,
    /// The solve's step ĥ, and the mass scale 1 + ĥμ, as bits.
    h: u64,
    scale: u64,
}

/// The variational problem of one implicit step, in the form every method of the backward
/// differentiation family shares: minimise over the end positions x
///
/// Φ(x) = s/(2ĥ²) ‖x − y‖²_M + E(x) + D(x),  y = x̂ + (ĥ/s)(v̂ + ĥ M⁻¹ f_body),  s = 1 + ĥμ,
///
/// whose stationarity is M(v − v̂) = ĥ (f(x) − μ M v) with v = (x − x̂)/ĥ. Backward Euler is
/// ĥ = h, x̂ = x₀, v̂ = v₀; BDF2 is ĥ = 2h/3, x̂ = (4x₀ − x₋₁)/3, v̂ = (4v₀ − v₋₁)/3
/// ([`super::bdf2`]). The air drag μ enters as the force −μMv (the mass scale s) when the
/// method takes it inside the solve, and is 0 here when the damping pass applies it after the
/// step. D is the dashpots' dissipation, c/(2ĥ) (n·(Δx_a − Δx_b))² with Δx = x − x̂.
#[derive(Debug, Clone, Copy)]
pub struct Target<'a> {
    /// ĥ, s.
    pub h: f64,
    /// μ inside the solve, 1/s (0: the damping pass applies it).
    pub drag: f64,
    /// x̂, every particle (only the free ones are read).
    pub base: &'a [DVec2],
    /// v̂, every particle (only the free ones are read).
    pub velocity: &'a [DVec2],
}

impl Target<'_> {
    /// s = 1 + ĥμ.
    pub fn scale(&self) -> f64 {
        1.0 + self.h * self.drag
    }
}

/// The factored global matrix and the buffers of the iterations, kept from step to step.
#[derive(Default)]
pub struct Projective {
    key: Option<Key>,
    /// Dense index of each free particle's row (`u32::MAX` for an eliminated particle).
    row: Vec<u32>,
    /// Particle of each row.
    particle: Vec<u32>,
    /// The factor, supernode by supernode.
    factor: Factor,
    /// Particle of each row of the factor (the fill-reducing order).
    order: Vec<u32>,
    /// Row of the factor of each particle (`u32::MAX` for an eliminated one): `order` inverted,
    /// so that the correction is gathered particle by particle, on the pool's threads.
    factor_row: Vec<u32>,
    /// The iterate, all particles.
    z: Vec<DVec2>,
    /// M y, all particles (constant over the step).
    my: Vec<DVec2>,
    /// The residual, all particles, before the gather.
    r: Vec<DVec2>,
    /// The global step's right-hand side and the solve's buffers, in the factor's precision.
    global: Global,
    buffers: SpringBuffers,
    /// The pair push's scratch, when contact runs inside the solve.
    contact_scratch: Vec<DVec2>,
    /// Whether each iteration's change of the contact forces is sized by a line search
    /// ([`Support::line_search`]): projective dynamics' steps and BDF2's backward Euler ones;
    /// not BDF2's own, where it left a body resting on the ground rocking (the `soft_box` at
    /// 1/60 s still moved at 0.2 m/s after 6 s, against 0.03 m/s without it), and where BDF2
    /// takes no step the contact acts in (`methods::bdf2`).
    pub(crate) line_search: bool,
    /// ĥ² times the change of the contact forces the line search sizes (or the impulses
    /// [`Self::spread`] spreads), and the solve's answer to it.
    change: Vec<DVec2>,
    answer: Vec<DVec2>,
    /// The contact forces, carried from step to step.
    support: Support,
    /// The last solve's s = 1 + μĥ (1 with the drag after the step): its matrix is
    /// s M + ĥ² L ([`Self::spread`]).
    scale: f64,
    /// [`Self::spread`]'s bodies (a union–find over the free particles joined by springs),
    /// and its sums at each body's root.
    bodies: Vec<u32>,
    body_sums: Vec<BodySums>,
    /// The fill-reducing order to use; `None` picks the cheaper ([`Self::symbolic`]).
    pub(crate) fill_order: Option<FactorOrder>,
    /// The symbolic factorisation of the last matrix, kept while its pattern stays.
    structure: Option<Structure>,
    /// Symbolic factorisations (orderings) so far: fewer than [`Self::factorizations`] when
    /// only values changed.
    pub symbolic_factorizations: u64,
    /// Factorisations so far.
    pub factorizations: u64,
    /// Wall time of the factorisations so far, s.
    pub factor_seconds: f64,
    /// Local/global iterations so far.
    pub iterations: u64,
    /// Line searches of the contact forces so far (each one more solve with the factor).
    pub line_searches: u64,
    /// Steps so far.
    pub steps: u64,
}

impl std::fmt::Debug for Projective {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Projective")
            .field("rows", &self.particle.len())
            .field("factor_nonzeros", &self.factor.len())
            .field("factorizations", &self.factorizations)
            .finish_non_exhaustive()
    }
}

/// The local step's share of the residual: h² k_s (d_s − (z_a − z_b)) to end a, its negative to
/// end b, four springs at a time where the CPU has AVX.
struct LocalStep<'z> {
    z: &'z [DVec2],
    h2: f64,
}

impl PairPass for LocalStep<'_> {
    type Pair = PackedSpring;
    #[inline(always)]
    fn run(&self, springs: &[PackedSpring], add: impl FnMut(usize, DVec2)) {
        #[cfg(target_arch = "x86_64")]
        if wide::available() {
            // SAFETY: the CPU has AVX, checked just above.
            unsafe { wide::for_each_projection(self.z, springs, self.h2, add) };
            return;
        }
        scatter_pairs(
            springs,
            |s| Some(projection_residual(s, self.z, self.h2)),
            add,
        );
    }
}

impl Projective {
    /// Builds and factors s M + ĥ² L over the free particles when the key changed.
    fn prepare(&mut self, s: &State, t: &Target, threads: &Threads) -> Result<(), String> {
        let (dt, scale) = (t.h, t.scale());
        let key = Key {
            revision: s.revision,
            h: dt.to_bits(),
            scale: scale.to_bits(),
        };
        if self.key == Some(key) {
            return Ok(());
        }
        let start = Instant::now();
        let n = s.mass.len();
        self.row.clear();
        self.particle.clear();
        for (i, &w) in s.inv_mass.iter().enumerate() {
            if w != 0.0 {
                self.row.push(self.particle.len() as u32);
                self.particle.push(i as u32);
            } else {
                self.row.push(u32::MAX);
            }
        }
        let rows = self.particle.len();
        let mut diagonal: Vec<f64> = (self.particle.iter())
            .map(|&i| s.mass[i as usize] * scale)
            .collect();
        let mut entries = Vec::with_capacity(rows + s.springs.len());
        for (spring, sp) in s.springs.iter().enumerate() {
            let (ra, rb) = (self.row[sp.a as usize], self.row[sp.b as usize]);
            let c = s.materials.projective_weight(spring, sp, dt);
            match (ra != u32::MAX, rb != u32::MAX) {
                (true, true) => {
                    diagonal[ra as usize] += c;
                    diagonal[rb as usize] += c;
                    // The lower triangle only.
                    let (r, col) = (ra.max(rb) as usize, ra.min(rb) as usize);
                    entries.push(Triplet::new(r, col, -c));
                }
                (true, false) => diagonal[ra as usize] += c,
                (false, true) => diagonal[rb as usize] += c,
                (false, false) => {}
            }
        }
        entries.extend(
            diagonal
                .iter()
                .enumerate()
                .map(|(r, &d)| Triplet::new(r, r, d)),
        );
        let mut matrix = SparseColMat::<usize, f64>::try_new_from_triplets(rows, rows, &entries)
            .map_err(|e| format!("projective dynamics: cannot assemble M + h²L: {e:?}"))?;
        // The symbolic factorisation (the order and the factor's structure) depends only on the
        // matrix's pattern: a change of stiffness, mass or dt keeps it, and so do springs that
        // tore (or were cut) since it was made, their entries kept as zeros
        // ([`within_pattern`]).
        let on_kept = (self.structure.as_ref())
            .filter(|k| k.asked == self.fill_order)
            .and_then(|k| within_pattern(&matrix, &k.col_ptr, &k.row_idx));
        let kept = on_kept.is_some();
        if let Some(on_kept) = on_kept {
            matrix = on_kept;
        }
        let pattern = matrix.symbolic();
        if !kept {
            let (symbolic, order) = self.symbolic(t.base, &matrix)?;
            self.structure = Some(Structure {
                col_ptr: pattern.col_ptr().to_vec(),
                row_idx: pattern.row_idx().to_vec(),
                asked: self.fill_order,
                symbolic,
                order,
            });
            self.symbolic_factorizations += 1;
        }
        let Some(Structure { symbolic, .. }) = &self.structure else {
            unreachable!("the structure was just made");
        };
        let par = parallelism(threads, s.springs.len());
        self.factor = Factor::of(symbolic)?;
        let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut stack = MemBuffer::try_new(scratch)
            .map_err(|_| "projective dynamics: out of memory for the factorisation".to_string())?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.factor.l,
                matrix.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut stack),
                Default::default(),
            )
            .map_err(|e| format!("projective dynamics: M + h²L is not positive definite: {e:?}"))?;
        // κ(M + h²L) ≤ λ_max / λ_min ≤ max_r (m_r + 2 h² Σ_s k_s) / min_r m_r (Gershgorin above,
        // and M + h²L ⪰ M below): the f32 factor is used where that bound keeps the rounding's
        // share of a solve (about κ · 6e-8 for the values, and as much again for the f32
        // arithmetic) at about 1 % or less. Measured near the bound (the 64² cloth at k = 2e7,
        // κ ≤ 9e4, dt = 1/60 s): ten iterations a step with f32 arithmetic ended 30 steps
        // 7e-14 m from the same f32 values with f64 arithmetic.
        let lowest = self
            .particle
            .iter()
            .map(|&i| s.mass[i as usize] * scale)
            .fold(f64::INFINITY, f64::min);
        let highest = diagonal
            .iter()
            .zip(&self.particle)
            .map(|(&d, &i)| 2.0 * d - s.mass[i as usize] * scale)
            .fold(0.0, f64::max);
        self.factor.finish(
            highest / lowest <= MAX_CONDITION_FOR_F32,
            threads,
            s.springs.len(),
        );
        // Row p of the factor is row fwd[p] of the matrix.
        self.order = match symbolic.perm() {
            Some(perm) => perm.arrays().0.iter().map(|&r| self.particle[r]).collect(),
            None => self.particle.clone(),
        };
        self.factor_row.clear();
        self.factor_row.resize(n, u32::MAX);
        for (k, &i) in self.order.iter().enumerate() {
            self.factor_row[i as usize] = k as u32;
        }
        drop(stack);
        for buf in [&mut self.z, &mut self.my, &mut self.r] {
            buf.resize(n, DVec2::ZERO);
        }
        self.global.fit(self.factor.single_precision(), rows);
        self.buffers = SpringBuffers::default();
        self.key = Some(key);
        self.factorizations += 1;
        self.factor_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// The symbolic factorisation of `matrix` (M + h² L over the free particles) in the cheaper
    /// of two orders for the substitutions: faer's approximate minimum degree, and nested
    /// dissection from the particles' positions ([`crate::solver::linear::ordering`]), tried on systems of
    /// [`DISSECTION_MIN_ROWS`] rows or more.
    fn symbolic(
        &self,
        x: &[DVec2],
        matrix: &SparseColMat<usize, f64>,
    ) -> Result<(SymbolicCholesky<usize>, FactorOrder), String> {
        let factorize = |ordering| {
            // Supernodal always: the substitutions walk supernodes (dense column blocks).
            let params = CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            };
            factorize_symbolic_cholesky(matrix.symbolic(), Side::Lower, ordering, params)
                .map_err(|e| format!("projective dynamics: symbolic factorisation failed: {e:?}"))
        };
        let amd = factorize(SymmetricOrdering::Amd)?;
        let rows = self.particle.len();
        if rows < DISSECTION_MIN_ROWS || self.fill_order == Some(FactorOrder::MinimumDegree) {
            return Ok((amd, FactorOrder::MinimumDegree));
        }
        // The rows joined by springs: the matrix's pattern (lower triangle, by column).
        let pattern = matrix.symbolic();
        let (start, neighbours) = adjacency(
            rows,
            (0..rows).flat_map(|col| {
                pattern
                    .row_idx_of_col_raw(col)
                    .iter()
                    .map(move |&r| (r, col))
            }),
        );
        let position: Vec<DVec2> = self.particle.iter().map(|&i| x[i as usize]).collect();
        let perm = permutation(
            nested_dissection(&position, &start, &neighbours)
                .into_iter()
                .map(|r| r as usize)
                .collect(),
        );
        let dissected = factorize(SymmetricOrdering::Custom(perm.as_ref()))?;
        let dissect = match self.fill_order {
            Some(order) => order == FactorOrder::NestedDissection,
            None => solve_cost(&dissected) < solve_cost(&amd),
        };
        Ok(if dissect {
            (dissected, FactorOrder::NestedDissection)
        } else {
            (amd, FactorOrder::MinimumDegree)
        })
    }

    /// Nonzeros of the Cholesky factor (0 before the first step).
    pub fn factor_nonzeros(&self) -> usize {
        self.factor.len()
    }

    /// Supernodes of the Cholesky factor (0 before the first step).
    pub fn factor_supernodes(&self) -> usize {
        self.factor.supernodes()
    }

    /// The parts of the factor's elimination tree that the substitutions run at once on two or
    /// more threads (0 before the first step; see [`Factor::halves`]).
    pub fn factor_halves(&self) -> usize {
        self.factor.halves()
    }

    /// The fill-reducing order of the factor in use (`None` before the first step).
    pub fn factor_order(&self) -> Option<FactorOrder> {
        self.structure.as_ref().map(|k| k.order)
    }

    /// Bytes the substitutions read per value of the factor: 4 (f32) or 8 (f64, for an
    /// ill-conditioned matrix); 0 before the first step.
    pub fn factor_bytes_per_value(&self) -> usize {
        match (self.key, self.factor.single_precision()) {
            (None, _) => 0,
            (_, true) => 4,
            (_, false) => 8,
        }
    }

    /// Mean iterations per step so far, if any step was taken.
    pub fn iterations_per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.iterations as f64 / self.steps as f64)
    }

    /// Mean line searches of the contact forces per step so far (`contact::support`: each one
    /// more solve with the factor), if any step was taken.
    pub fn line_searches_per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.line_searches as f64 / self.steps as f64)
    }
}

/// Systems this big or bigger try nested dissection beside minimum degree.
pub const DISSECTION_MIN_ROWS: usize = 1024;

/// What a substitution costs per supernode beyond its values, in values: measured on the
/// 256² cloth's factor (`substitutions_against`), the supernodes of under 4 columns take
/// about 50 ns each beyond their values' 0.58 ns, about 90 values' worth.
const SUPERNODE_COST_IN_VALUES: usize = 90;

/// Of the kept pattern's entries, at most this share may be zeros left by springs that tore
/// before the matrix is ordered anew: the kept order was chosen for the cloth before the tears,
/// and its factor keeps their fill.
const MAX_KEPT_ZEROS: f64 = 0.25;

/// `matrix` on the pattern `(col_ptr, row_idx)` of an earlier matrix, with zeros where it has no
/// entry, when its own pattern is that one (a change of values alone) or a part of it with few
/// zeros ([`MAX_KEPT_ZEROS`]): springs removed since (torn, cut) leave the symbolic factorisation
/// valid, and a refactorisation then redoes only the numbers. The matrix is the same, so the
/// factor is, up to rounding; a spring added, or a pin, changes the pattern's rows and is not
/// within it.
fn within_pattern(
    matrix: &SparseColMat<usize, f64>,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Option<SparseColMat<usize, f64>> {
    let (n, new_ptr, new_rows) = (
        matrix.ncols(),
        matrix.symbolic().col_ptr(),
        matrix.symbolic().row_idx(),
    );
    let values = matrix.val();
    if matrix.nrows() != n || col_ptr.len() != n + 1 || new_rows.len() > row_idx.len() {
        return None;
    }
    let zeros = row_idx.len() - new_rows.len();
    if zeros as f64 > MAX_KEPT_ZEROS * row_idx.len() as f64 {
        return None;
    }
    let mut on_kept = vec![0.0; row_idx.len()];
    for j in 0..n {
        let mut at = col_ptr[j];
        for q in new_ptr[j]..new_ptr[j + 1] {
            // Both columns' rows ascend: skip the kept rows the new column lacks.
            while at < col_ptr[j + 1] && row_idx[at] < new_rows[q] {
                at += 1;
            }
            if at == col_ptr[j + 1] || row_idx[at] != new_rows[q] {
                return None;
            }
            on_kept[at] = values[q];
            at += 1;
        }
    }
    let symbolic = faer::sparse::SymbolicSparseColMat::new_checked(
        n,
        n,
        col_ptr.to_vec(),
        None,
        row_idx.to_vec(),
    );
    Some(SparseColMat::new(symbolic, on_kept))
}

/// The model of a substitution's cost that picks the order: values, and supernodes.
fn solve_cost(symbolic: &SymbolicCholesky<usize>) -> usize {
    let supernodes = match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => s.n_supernodes(),
        SymbolicCholeskyRaw::Simplicial(s) => s.nrows(),
    };
    symbolic.len_val() + SUPERNODE_COST_IN_VALUES * supernodes
}

/// The factorisation may share the pool on a big scene (it runs once); the substitutions run on
/// the calling thread.
fn parallelism(threads: &Threads, springs: usize) -> Par {
    if threads.threads() > 1 && springs >= crate::solver::threads::PARALLEL_MIN_SPRINGS {
        Par::rayon(threads.threads())
    } else {
        Par::Seq
    }
}

/// One projective dynamics step of `iterations` local/global iterations: sets v to
/// (x1 − x0)/h for the free particles (see the module docs). `s.f` holds the body forces.
/// `drag` is μ when the air drag enters the solve ([`Target`]), 0 when the damping pass
/// applies it after the step.
pub fn step(
    s: &mut State,
    pd: &mut Projective,
    dt: f64,
    drag: f64,
    iterations: u32,
    contact: Option<&InSolve>,
    threads: &Threads,
) -> Result<(), String> {
    let target = Target {
        h: dt,
        drag,
        base: &s.x,
        velocity: &s.v,
    };
    pd.line_search = true;
    pd.solve(s, &target, dt, iterations, contact, threads)?;
    let inv_h = 1.0 / dt;
    let data = (&mut s.v[..], &pd.z[..], &s.x[..], &s.inv_mass[..]);
    threads.each(s.springs.len(), data, |(v, z, x, w)| {
        for i in 0..v.len() {
            if w[i] != 0.0 {
                v[i] = (z[i] - x[i]) * inv_h;
            }
        }
    });
    Ok(())
}

impl Projective {
    /// The end positions of one implicit step ([`Target`]) by `iterations` local/global
    /// iterations, left in [`Self::end`]: every particle's, the eliminated ones (inverse mass
    /// 0) at x₀ + dt v₀ (the target's base and velocity are x₀ and v₀ for them). `s.f`
    /// holds the body forces. With `contact`, every global step's iterate is kept out of the
    /// surfaces and the other particles ([`InSolve`]; a pair that meets within the step along
    /// the line it met on, [`InSolve::holding_sides`]) before the next local step reads it, and
    /// where [`Self::line_search`] is set (projective dynamics' steps, BDF2's backward Euler
    /// ones) the change of the contact forces is sized by a line search (`contact::support`).
    pub fn solve(
        &mut self,
        s: &State,
        t: &Target,
        dt: f64,
        iterations: u32,
        contact: Option<&InSolve>,
        threads: &Threads,
    ) -> Result<(), String> {
        self.prepare(s, t, threads)?;
        self.run(s, t, dt, iterations, contact, threads);
        Ok(())
    }

    /// The end positions of the last [`Self::solve`].
    pub fn end(&self) -> &[DVec2] {
        &self.z
    }

    /// Whether the contact acted in the last solve: some projection pushed a particle.
    pub(crate) fn contact_acted(&self) -> bool {
        self.support.acted()
    }

    /// The direction of the contact force holding particle `i` at the end of the last solve
    /// (contact inside it), if one does.
    pub(crate) fn held_along(&self, i: usize) -> Option<DVec2> {
        self.support.held_along(i)
    }

    fn run(
        &mut self,
        s: &State,
        t: &Target,
        dt: f64,
        iterations: u32,
        contact: Option<&InSolve>,
        threads: &Threads,
    ) {
        let (h, scale) = (t.h, t.scale());
        self.scale = scale;
        let h2 = h * h;
        let springs = s.springs.len();
        // z = x̂ + (ĥ/s) v̂ for the free particles, x0 + dt v0 for the eliminated ones (their
        // final positions); s M y = s m x̂ + ĥ m v̂ + ĥ² f.
        let h_over_s = h / scale;
        let data = (
            &mut self.z[..],
            &mut self.my[..],
            (t.base, t.velocity),
            &s.f[..],
            (&s.mass[..], &s.inv_mass[..]),
        );
        threads.each(springs, data, |(z, my, (x, v), f, (m, w))| {
            for i in 0..z.len() {
                z[i] = if w[i] != 0.0 {
                    x[i] + v[i] * h_over_s
                } else {
                    x[i] + v[i] * dt
                };
                my[i] = (x[i] * scale + v[i] * h) * m[i] + f[i] * h2;
            }
        });
        // The contact engages once it can act on the iterate (at once, but for the ground
        // alone): until then holding the iterate would move nothing and learn no force, and
        // its bookkeeping cost a 256² cloth hanging clear of the ground a quarter of its
        // step on two threads.
        self.support.start_without();
        let h2_over_s = h2 / scale;
        let engage = |this: &mut Self| {
            let c = contact.filter(|c| c.reaches(&this.z))?;
            this.support.start(s, &this.z, h2_over_s);
            this.contact_scratch.resize(c.pair_scratch(), DVec2::ZERO);
            Some(c)
        };
        let mut live = engage(self);
        for iteration in 0..iterations {
            // r = s M y − (s M + ĥ² L) z: s M (y − z), and each spring's ĥ² k (d − (z_a − z_b)).
            let local = LocalStep { z: &self.z, h2 };
            let (my, z, m) = (&self.my[..], &self.z[..], &s.mass[..]);
            let start = |lo: usize, r: &mut [DVec2]| {
                for (i, r) in (lo..).zip(r) {
                    *r = my[i] - z[i] * (m[i] * scale);
                }
            };
            scatter_from(
                threads,
                &mut self.buffers,
                &mut self.r,
                &s.springs,
                &local,
                &start,
            );
            if s.materials.exerts_forces() {
                s.materials
                    .add_projective_terms(&s.springs, t.base, &self.z, h, &mut self.r);
            }
            if live.is_some() {
                self.support.add_to(&mut self.r, h2);
            }
            let global = GlobalStep {
                factor: &self.factor,
                order: &self.order,
                factor_row: &self.factor_row,
                r: &self.r,
                z: &mut self.z,
                springs,
                threads,
            };
            self.global.correct(global);
            live = live.or_else(|| engage(self));
            if let Some(c) = live {
                // Each pair that meets within the step is held to the side it met on
                // ([`InSolve::holding_sides`]).
                let c = &c.holding_sides(&s.x);
                let (m, w) = (&s.mass[..], &s.inv_mass[..]);
                let scratch = &mut self.contact_scratch;
                let stiffness = scale / h2;
                (self.support).project(c, &mut self.z, &s.x, m, w, scratch, stiffness);
                // The last iteration ends on the projection: the step ends with every particle
                // where its contact holds it.
                let more = iteration + 1 < iterations;
                if more && self.line_search && self.search_line(s, h2, springs, threads) {
                    let scratch = &mut self.contact_scratch;
                    (self.support).project(c, &mut self.z, &s.x, m, w, scratch, stiffness);
                }
            }
        }
        if let Some(c) = live {
            // The force over the equation's own step ĥ: dt here, 2/3 dt under BDF2.
            self.support.note_reactions(c, &s.mass, t.h);
        }
        self.iterations += iterations as u64;
        self.steps += 1;
    }
}

impl Projective {
    /// The line search along the last projection's change of the contact forces
    /// ([`Support::line_search`]): one more solve with the factor answers how the iterate
    /// would move under that change, the change is resized by it, and the iterate moves where
    /// the next solve would put it. Returns whether anything changed (the iterate then wants
    /// projecting again).
    fn search_line(&mut self, s: &State, h2: f64, springs: usize, threads: &Threads) -> bool {
        let n = self.z.len();
        self.change.resize(n, DVec2::ZERO);
        // The residual is in force · ĥ², as the contact forces enter it (`Support::add_to`).
        if !(self.support).change_to_answer(h2, &mut self.change) {
            return false;
        }
        self.answer_change(springs, threads);
        (self.support).line_search(&mut self.z, &s.mass, &self.answer);
        self.line_searches += 1;
        true
    }

    /// The factor's answer to [`Self::change`], A⁻¹ change, into [`Self::answer`]: one more
    /// solve, for the line search and [`Self::spread`].
    fn answer_change(&mut self, springs: usize, threads: &Threads) {
        self.answer.clear();
        self.answer.resize(self.change.len(), DVec2::ZERO);
        let answer = GlobalStep {
            factor: &self.factor,
            order: &self.order,
            factor_row: &self.factor_row,
            r: &self.change,
            z: &mut self.answer,
            springs,
            threads,
        };
        self.global.correct(answer);
    }
}

impl Projective {
    /// Spreads the velocity jumps `jump` that the contact would give the particles touching a
    /// surface at the end of a backward Euler step (zero elsewhere) through the bodies they
    /// belong to, with the last solve's factor, into the state's velocities.
    ///
    /// Why: a backward Euler step ends with its mean velocity over the step, (x₁ − x₀)/h: a
    /// body that lands within it ends with the landing speed in every particle, and the contact
    /// pass after the step takes it only from those touching. A strip two particles deep
    /// dropped flat at 1/60 s had its lower row stopped and its upper row still coming at
    /// 0.78 m/s, 1 cm above it: in the next step the upper row went through, and the strip lay
    /// turned over (`docs/performance-log.md`, 2026-12-07).
    ///
    /// How: the jumps as impulses P = s M Δv on the touching particles; the body's answer
    /// u = (s M + ĥ² L)⁻¹ P, the velocity change the impulses give it with its springs acting
    /// over the step (the step's own matrix, so one more solve with the factor); taken α times,
    /// the exact line search along P of the contact's dual, α = Σ P·Δv / Σ P·u over each body
    /// (1 for a lone particle, 2 for the strip, whose lower row carries half its mass), at most
    /// the body's mass over its touching particles'. The contact pass then takes what approach
    /// is left.
    pub(crate) fn spread(&mut self, s: &mut State, jump: &[DVec2], threads: &Threads) {
        let n = s.v.len();
        if self.z.len() != n || self.steps == 0 || jump.iter().all(|j| *j == DVec2::ZERO) {
            return;
        }
        self.change.resize(n, DVec2::ZERO);
        for (i, p) in self.change.iter_mut().enumerate() {
            *p = if s.inv_mass[i] != 0.0 {
                jump[i] * (self.scale * s.mass[i])
            } else {
                DVec2::ZERO
            };
        }
        self.answer_change(s.springs.len(), threads);
        // The matrix joins only particles that springs join (a pinned one is eliminated), so
        // each body answers its own impulses alone, and takes its own α.
        let bodies = &mut self.bodies;
        bodies.clear();
        bodies.extend(0..n as u32);
        for sp in &s.springs {
            if s.inv_mass[sp.a as usize] != 0.0 && s.inv_mass[sp.b as usize] != 0.0 {
                join(bodies, sp.a, sp.b);
            }
        }
        self.body_sums.clear();
        self.body_sums.resize(n, BodySums::default());
        for (i, &jump) in jump.iter().enumerate() {
            if s.inv_mass[i] == 0.0 {
                continue;
            }
            let sums = &mut self.body_sums[root(bodies, i as u32) as usize];
            let (p, m) = (self.change[i], s.mass[i]);
            sums.free += m;
            if p != DVec2::ZERO {
                sums.touching += m;
                sums.along += p.dot(jump);
                sums.answered += p.dot(self.answer[i]);
            }
        }
        for i in 0..n {
            if s.inv_mass[i] == 0.0 {
                continue;
            }
            let sums = self.body_sums[root(bodies, i as u32) as usize];
            if sums.along > 0.0 && sums.answered > 0.0 {
                let alpha = (sums.along / sums.answered).min(sums.free / sums.touching);
                s.v[i] += self.answer[i] * alpha;
            }
        }
    }
}

/// One body's sums in [`Projective::spread`]: its free particles' mass, its touching ones',
/// Σ P·Δv and Σ P·u.
#[derive(Debug, Default, Clone, Copy)]
struct BodySums {
    free: f64,
    touching: f64,
    along: f64,
    answered: f64,
}

/// The global step's right-hand side and solution, in the precision of the factor's values.
enum Global {
    Single(Rhs<f32>),
    Double(Rhs<f64>),
}

impl Default for Global {
    fn default() -> Self {
        Global::Double(Rhs::new(0))
    }
}

impl Global {
    /// One global step ([`GlobalStep::correct`]) in the factor's precision.
    fn correct(&mut self, step: GlobalStep) {
        match self {
            Global::Single(rhs) => step.correct(rhs),
            Global::Double(rhs) => step.correct(rhs),
        }
    }

    /// Buffers in the precision asked for with `rows` rows: those already held when their
    /// precision is that one (a tearing cloth refactors at every tear), else new ones.
    fn fit(&mut self, single: bool, rows: usize) {
        match (single, &mut *self) {
            (true, Global::Single(rhs)) => rhs.resize(rows),
            (false, Global::Double(rhs)) => rhs.resize(rows),
            (true, _) => *self = Global::Single(Rhs::new(rows)),
            (false, _) => *self = Global::Double(Rhs::new(rows)),
        }
    }
}

/// The residual in the factor's row order, then the correction, x and y apart, solved together
/// so that each value of the factor is read once for both; and the solve's buffers.
struct Rhs<R> {
    x: Vec<R>,
    y: Vec<R>,
    work: Substitution<R>,
}

impl<R: Stored> Rhs<R> {
    fn new(rows: usize) -> Self {
        let mut rhs = Rhs {
            x: vec![],
            y: vec![],
            work: Substitution::default(),
        };
        rhs.resize(rows);
        rhs
    }

    fn resize(&mut self, rows: usize) {
        self.x.resize(rows, R::default());
        self.y.resize(rows, R::default());
    }
}

/// One global step: the iterate z corrected by the factor's solve with the residual r.
struct GlobalStep<'a> {
    factor: &'a Factor,
    order: &'a [u32],
    factor_row: &'a [u32],
    r: &'a [DVec2],
    z: &'a mut [DVec2],
    springs: usize,
    threads: &'a Threads,
}

impl GlobalStep<'_> {
    /// Gathers r into the factor's order (rounded to its precision), solves, and adds the
    /// correction to z, each gather on the pool's threads.
    fn correct<R: Stored>(self, rhs: &mut Rhs<R>) {
        let (r, threads) = (self.r, self.threads);
        let data = (&mut rhs.x[..], &mut rhs.y[..], self.order);
        threads.each(self.springs, data, |(rx, ry, order)| {
            for ((rx, ry), &i) in rx.iter_mut().zip(ry).zip(order) {
                let r = r[i as usize];
                (*rx, *ry) = (R::of(r.x), R::of(r.y));
            }
        });
        self.factor
            .solve(&mut rhs.x, &mut rhs.y, &mut rhs.work, threads);
        let (x, y) = (&rhs.x[..], &rhs.y[..]);
        threads.each(self.springs, (self.z, self.factor_row), |(z, row)| {
            for (z, &k) in z.iter_mut().zip(row) {
                if k != u32::MAX {
                    *z += DVec2::new(x[k as usize].get(), y[k as usize].get());
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A w × w cloth with the grid's springs (right, down, both diagonals), its top-left
    /// corner pinned, bent so that its springs are stretched, under gravity.
    fn cloth(w: u32) -> State {
        let mut s = State::default();
        let spacing = 1.0 / w as f64;
        for r in 0..w * w {
            let (i, j) = ((r / w) as f64, (r % w) as f64);
            s.x.push(DVec2::new(
                j * spacing,
                1.0 - i * spacing * (1.0 + 0.1 * j / w as f64),
            ));
            s.v.push(DVec2::ZERO);
            s.mass.push(1.0);
            s.inv_mass.push(if r == 0 { 0.0 } else { 1.0 });
            s.f.push(if r == 0 {
                DVec2::ZERO
            } else {
                DVec2::new(0.0, -9.8)
            });
        }
        for i in 0..w {
            for j in 0..w {
                for (di, dj) in [(0i64, 1i64), (1, 0), (1, 1), (1, -1)] {
                    let (ni, nj) = (i as i64 + di, j as i64 + dj);
                    if ni < w as i64 && (0..w as i64).contains(&nj) {
                        let (a, b) = (i * w + j, ni as u32 * w + nj as u32);
                        s.springs.push(PackedSpring {
                            a: a.min(b),
                            b: a.max(b),
                            rest: spacing * ((di * di + dj * dj) as f64).sqrt(),
                            k: 1e4,
                        });
                    }
                }
            }
        }
        s.springs.sort_by_key(|sp| (sp.a, sp.b));
        s
    }

    /// Two steps from the same start end at the same positions to 1e-12 m: their end
    /// velocities times dt agree.
    fn assert_same_end(a: &[DVec2], b: &[DVec2], dt: f64) {
        let worst = end_gap(a, b, dt);
        assert!(worst < 1e-12, "the end positions differ by {worst:e}");
    }

    /// The largest distance between the end positions of two steps from one state, given
    /// their end velocities: (x₁ − x₀)/dt apart by dt.
    fn end_gap(a: &[DVec2], b: &[DVec2], dt: f64) -> f64 {
        a.iter()
            .zip(b)
            .map(|(a, b)| (*a - *b).length() * dt)
            .fold(0.0, f64::max)
    }

    /// A copy of the state's particles and springs (a fresh revision and workspace).
    fn copy(s: &State) -> State {
        State {
            x: s.x.clone(),
            v: s.v.clone(),
            f: s.f.clone(),
            mass: s.mass.clone(),
            inv_mass: s.inv_mass.clone(),
            springs: s.springs.clone(),
            ..Default::default()
        }
    }

    /// On a cloth big enough to try it, nested dissection is the order chosen (fewer
    /// supernodes for about as many values), and both orders, iterated to convergence, give
    /// the same step: the fixed point does not depend on the order of the factor.
    #[test]
    fn both_fill_orders_give_the_same_converged_step() {
        let threads = Threads::new(1).unwrap();
        let dt = 1.0 / 60.0;
        let mut ends = vec![];
        for order in [
            None,
            Some(FactorOrder::MinimumDegree),
            Some(FactorOrder::NestedDissection),
        ] {
            let mut s = cloth(36);
            assert!(
                s.x.len() > DISSECTION_MIN_ROWS,
                "the free rows try nested dissection"
            );
            let mut pd = Projective {
                fill_order: order,
                ..Default::default()
            };
            step(&mut s, &mut pd, dt, 0.0, 300, None, &threads).unwrap();
            let chosen = pd.factor_order().unwrap();
            assert_eq!(chosen, order.unwrap_or(FactorOrder::NestedDissection));
            ends.push((s.v.clone(), pd.factor_supernodes()));
        }
        let (amd, nd) = (&ends[1], &ends[2]);
        assert!(
            nd.1 < amd.1,
            "supernodes: dissection {}, minimum degree {}",
            nd.1,
            amd.1
        );
        assert_same_end(&amd.0, &nd.0, dt);
        assert!(amd.0.iter().any(|v| v.length() > 0.1), "the cloth moved");
    }

    /// Springs torn since the last factorisation (their entries kept as zeros) refactor with
    /// the kept symbolic factorisation, and give the step a factorisation from scratch gives;
    /// past a quarter of the pattern gone, the matrix is ordered anew.
    #[test]
    fn torn_springs_keep_the_symbolic_factorisation() {
        let threads = Threads::new(1).unwrap();
        let dt = 1.0 / 60.0;
        let mut s = cloth(36);
        let mut pd = Projective::default();
        step(&mut s, &mut pd, dt, 0.0, 10, None, &threads).unwrap();
        let tear = |s: &mut State, every: usize| {
            let mut k = 0;
            s.springs.retain(|_| {
                k += 1;
                k % every != 0
            });
            s.touch();
        };
        tear(&mut s, 9);
        // Two iterations: the correction form converges to the same step with any factor near
        // the matrix's, so it is after a few that a factor of another matrix would show.
        let mut fresh_state = copy(&s);
        step(&mut s, &mut pd, dt, 0.0, 2, None, &threads).unwrap();
        assert_eq!((pd.factorizations, pd.symbolic_factorizations), (2, 1));
        let mut fresh = Projective::default();
        step(&mut fresh_state, &mut fresh, dt, 0.0, 2, None, &threads).unwrap();
        let worst = end_gap(&s.v, &fresh_state.v, dt);
        assert!(worst < 1e-9, "the end positions differ by {worst:e}");
        tear(&mut s, 2);
        step(&mut s, &mut pd, dt, 0.0, 10, None, &threads).unwrap();
        assert_eq!((pd.factorizations, pd.symbolic_factorizations), (3, 2));
    }

    /// A change of stiffness refactors with the kept symbolic factorisation, and gives the step
    /// a factorisation from scratch gives; a new pin changes the pattern and orders anew.
    #[test]
    fn a_stiffness_change_keeps_the_symbolic_factorisation() {
        let threads = Threads::new(1).unwrap();
        let dt = 1.0 / 60.0;
        let mut s = cloth(36);
        let mut pd = Projective::default();
        step(&mut s, &mut pd, dt, 0.0, 10, None, &threads).unwrap();
        assert_eq!((pd.factorizations, pd.symbolic_factorizations), (1, 1));
        for sp in &mut s.springs {
            sp.k *= 3.0;
        }
        s.touch();
        let mut fresh_state = copy(&s);
        step(&mut s, &mut pd, dt, 0.0, 300, None, &threads).unwrap();
        assert_eq!((pd.factorizations, pd.symbolic_factorizations), (2, 1));
        let mut fresh = Projective::default();
        step(&mut fresh_state, &mut fresh, dt, 0.0, 300, None, &threads).unwrap();
        assert_same_end(&s.v, &fresh_state.v, dt);
        s.inv_mass[700] = 0.0;
        s.touch();
        step(&mut s, &mut pd, dt, 0.0, 10, None, &threads).unwrap();
        assert_eq!((pd.factorizations, pd.symbolic_factorizations), (3, 2));
    }
}
