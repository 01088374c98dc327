//! The methods: which integrator steps the state, and how much work the iterative ones do.

use serde::{Deserialize, Serialize};

/// The time integrators. Every one is followed by the same damping and ground passes (see
/// `docs/integrators.md`), except that BDF2 takes the damping inside its solve (and projective
/// dynamics and VBD when `drag_in_solve` is set).
///
/// The command line names them in kebab case (`projective-dynamics`) and takes a scene file's
/// name too (`ProjectiveDynamics`), so that one copied from a scene works there.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, clap::ValueEnum,
)]
pub enum Integrator {
    /// x uses the velocity at the start of the step.
    #[value(alias = "ExplicitEuler")]
    ExplicitEuler,
    /// x uses the velocity at the end of the step (symplectic; the assignment's default).
    #[default]
    #[value(alias = "SymplecticEuler")]
    SymplecticEuler,
    /// Kick-drift-kick velocity Verlet (symplectic, second order).
    #[value(alias = "VelocityVerlet")]
    VelocityVerlet,
    /// Classic four-stage Runge-Kutta on x'' = f(x)/m (fourth order, not symplectic).
    #[value(alias = "Rk4")]
    Rk4,
    /// Backward Euler by Newton's method, each step solved by conjugate gradients (first
    /// order, dissipative). Newton steps per step (`iterations.newton`; the default 1 is
    /// the classic linearised step).
    #[value(alias = "ImplicitEuler")]
    ImplicitEuler,
    /// Projective dynamics (Liu et al. 2013): local/global iterations on the backward Euler
    /// objective, the constant global matrix factored once by sparse Cholesky
    /// (`iterations.projective` per step).
    #[value(alias = "ProjectiveDynamics")]
    ProjectiveDynamics,
    /// XPBD (Macklin et al. 2016): springs as compliant distance constraints (α = 1/k),
    /// `iterations.xpbd_substeps` substeps of `iterations.xpbd_sweeps` Gauss-Seidel
    /// sweeps each (or sweeps until the constraint error is under `iterations.xpbd_tolerance`).
    #[value(alias = "Xpbd")]
    Xpbd,
    /// BDF2, second-order backward differentiation, solved by projective dynamics'
    /// local/global iterations with its factor kept (`iterations.bdf2` per step); the air drag
    /// inside the solve. Second order, dissipative; a backward Euler step starts it, and is
    /// taken wherever contact acts.
    #[value(alias = "Bdf2")]
    Bdf2,
    /// Vertex block descent (Chen et al. 2024) on the backward Euler objective: per vertex a
    /// 2×2 Newton step, colour by colour (`iterations.vbd` per step). No factorisation.
    #[value(alias = "Vbd")]
    Vbd,
}

impl Integrator {
    /// Every integrator, in the order of the table in `docs/integrators.md`.
    pub const ALL: [Integrator; 9] = [
        Integrator::ExplicitEuler,
        Integrator::SymplecticEuler,
        Integrator::VelocityVerlet,
        Integrator::Rk4,
        Integrator::ImplicitEuler,
        Integrator::ProjectiveDynamics,
        Integrator::Xpbd,
        Integrator::Bdf2,
        Integrator::Vbd,
    ];

    /// The name used on the command line and in reports (`symplectic-euler`, `rk4`, ...).
    pub fn cli_name(self) -> &'static str {
        match self {
            Integrator::ExplicitEuler => "explicit-euler",
            Integrator::SymplecticEuler => "symplectic-euler",
            Integrator::VelocityVerlet => "velocity-verlet",
            Integrator::Rk4 => "rk4",
            Integrator::ImplicitEuler => "implicit-euler",
            Integrator::ProjectiveDynamics => "projective-dynamics",
            Integrator::Xpbd => "xpbd",
            Integrator::Bdf2 => "bdf2",
            Integrator::Vbd => "vbd",
        }
    }

    /// Whether the method needs the spring forces at the start of the step (the force pass's
    /// spring sweep). Projective dynamics, XPBD, BDF2 and VBD work on positions and read only
    /// the body forces (gravity and external forces).
    pub fn reads_spring_forces(self) -> bool {
        !matches!(
            self,
            Integrator::ProjectiveDynamics | Integrator::Xpbd | Integrator::Bdf2 | Integrator::Vbd
        )
    }

    /// Stable for any dt (the implicit methods).
    pub fn unconditionally_stable(self) -> bool {
        matches!(
            self,
            Integrator::ImplicitEuler
                | Integrator::ProjectiveDynamics
                | Integrator::Xpbd
                | Integrator::Bdf2
                | Integrator::Vbd
        )
    }

    /// Whether the air drag μ enters the method's solve as the force −μ m v (BDF2: applied
    /// after the step as exp(−μh), it would hold the method to first order), so that the
    /// damping pass does not run.
    pub fn drags_in_solve(self) -> bool {
        matches!(self, Integrator::Bdf2)
    }

    /// Whether the method can take the air drag inside its solve when asked
    /// (`drag_in_solve`): projective dynamics and VBD, whose backward Euler objective takes
    /// the force −μ m v as a mass scale 1 + hμ. Measured on cloth32 at dt = 1/60 s against
    /// RK4 (2026-12-04, AMD EPYC Zen 4): projective dynamics errs 8.4e-3 m with the drag inside,
    /// 1.9e-2 m with exp(−μh) after the step.
    pub fn can_drag_in_solve(self) -> bool {
        matches!(self, Integrator::ProjectiveDynamics | Integrator::Vbd)
    }
}

/// How much work the iterative methods do each step. Only the selected integrator's counts
/// are read.
///
/// ```
/// # use hooke::sim::{Integrator, SimParams};
/// let mut app = hooke::headless_app();
/// let mut params = app.world_mut().resource_mut::<SimParams>();
/// params.integrator = Integrator::Xpbd;
/// params.iterations.xpbd_substeps = 20;
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Iterations {
    /// Implicit Euler: Newton steps per time step (each a linear solve by CG). 1 is the classic
    /// step linearised at the start of the step; more converge to the exact backward Euler
    /// step.
    pub newton: u32,
    /// Projective dynamics: local/global iterations per time step.
    pub projective: u32,
    /// XPBD: substeps per time step.
    pub xpbd_substeps: u32,
    /// XPBD: constraint sweeps per substep (the least, with a tolerance).
    pub xpbd_sweeps: u32,
    /// BDF2: local/global iterations per time step.
    pub bdf2: u32,
    /// VBD: iterations (sweeps over every vertex) per time step.
    pub vbd: u32,
    /// XPBD: when > 0, each substep sweeps until the largest constraint error |C + α̃λ|/L
    /// (a spring's violation of its compliant constraint, relative to its rest length) is
    /// under it, up to `xpbd_max_sweeps`; 0 runs `xpbd_sweeps` sweeps.
    pub xpbd_tolerance: f64,
    /// XPBD: the most sweeps a substep runs toward `xpbd_tolerance`.
    pub xpbd_max_sweeps: u32,
    /// VBD: Chebyshev acceleration's estimate ρ of the iteration's spectral radius, in
    /// [0, 1); 0 (the default) turns it off.
    pub vbd_chebyshev: f64,
}

impl Iterations {
    /// The largest count a field may hold (a typo of 10⁹ iterations is an error, not a hang).
    pub const MAX: u32 = 100_000;
    /// The rule every count must meet, as the error messages say it.
    pub const RULE: &'static str = "must be between 1 and 100000";

    /// The counts' names, as a scene file writes them.
    pub const NAMES: [&'static str; 7] = [
        "newton",
        "projective",
        "xpbd_substeps",
        "xpbd_sweeps",
        "bdf2",
        "vbd",
        "xpbd_max_sweeps",
    ];
    /// The counts, in the order of [`Iterations::NAMES`].
    pub fn values(&self) -> [u32; 7] {
        [
            self.newton,
            self.projective,
            self.xpbd_substeps,
            self.xpbd_sweeps,
            self.bdf2,
            self.vbd,
            self.xpbd_max_sweeps,
        ]
    }

    /// The first real-valued setting out of its range, as (name, value, rule):
    /// `xpbd_tolerance` finite and ≥ 0, `vbd_chebyshev` in [0, 1).
    pub fn bad_real(&self) -> Option<(&'static str, f64, &'static str)> {
        let t = self.xpbd_tolerance;
        if !(t.is_finite() && t >= 0.0) {
            return Some(("xpbd_tolerance", t, "must be finite and >= 0"));
        }
        let r = self.vbd_chebyshev;
        if !(0.0..1.0).contains(&r) {
            return Some(("vbd_chebyshev", r, "must be in [0, 1)"));
        }
        None
    }

    /// Whether `count` is a usable iteration count: 1..=[`Iterations::MAX`] ([`Iterations::RULE`]).
    pub fn allowed(count: u32) -> bool {
        (1..=Self::MAX).contains(&count)
    }

    /// The first count that is not [`Iterations::allowed`], as (field index, value): the check
    /// that the scene loader and the per-tick input check share (the command line checks each
    /// flag with [`Iterations::allowed`], to name the flag).
    pub fn out_of_range(&self) -> Option<(usize, u32)> {
        self.values()
            .into_iter()
            .enumerate()
            .find(|&(_, v)| !Self::allowed(v))
    }
}

impl Default for Iterations {
    fn default() -> Self {
        Iterations {
            newton: 1,
            projective: 10,
            xpbd_substeps: 10,
            xpbd_sweeps: 1,
            bdf2: 10,
            vbd: 10,
            xpbd_tolerance: 0.0,
            xpbd_max_sweeps: 100,
            vbd_chebyshev: 0.0,
        }
    }
}

impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.cli_name())
    }
}
