//! The methods: which integrator steps the state, and how much work the iterative ones do.

use serde::{Deserialize, Serialize};

/// The time integrators. Every one is followed by the same damping and ground passes
/// (see `docs/integrators.md`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, clap::ValueEnum,
)]
pub enum Integrator {
    /// x uses the velocity at the start of the step.
    ExplicitEuler,
    /// x uses the velocity at the end of the step (symplectic; the assignment's default).
    #[default]
    SymplecticEuler,
    /// Kick-drift-kick velocity Verlet (symplectic, second order).
    VelocityVerlet,
    /// Classic four-stage Runge-Kutta on x'' = f(x)/m (fourth order, not symplectic).
    Rk4,
    /// Backward Euler by Newton's method, each step solved by conjugate gradients (first
    /// order, dissipative). Newton steps per step (`iterations.newton`; the default 1 is
    /// the classic linearised step).
    ImplicitEuler,
    /// Projective dynamics (Liu et al. 2013): local/global iterations on the backward Euler
    /// objective, the constant global matrix factored once by sparse Cholesky
    /// (`iterations.projective` per step).
    ProjectiveDynamics,
    /// XPBD (Macklin et al. 2016): springs as compliant distance constraints (α = 1/k),
    /// `iterations.xpbd_substeps` substeps of `iterations.xpbd_sweeps` Gauss-Seidel
    /// sweeps each.
    Xpbd,
}

impl Integrator {
    /// Every integrator, in the order of the table in `docs/integrators.md`.
    pub const ALL: [Integrator; 7] = [
        Integrator::ExplicitEuler,
        Integrator::SymplecticEuler,
        Integrator::VelocityVerlet,
        Integrator::Rk4,
        Integrator::ImplicitEuler,
        Integrator::ProjectiveDynamics,
        Integrator::Xpbd,
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
        }
    }

    /// Whether the method needs the spring forces at the start of the step (the force pass's
    /// spring sweep). Projective dynamics and XPBD work on positions and read only the body
    /// forces (gravity and external forces).
    pub fn reads_spring_forces(self) -> bool {
        !matches!(self, Integrator::ProjectiveDynamics | Integrator::Xpbd)
    }

    /// Stable for any dt (the implicit methods).
    pub fn unconditionally_stable(self) -> bool {
        matches!(
            self,
            Integrator::ImplicitEuler | Integrator::ProjectiveDynamics | Integrator::Xpbd
        )
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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
    /// XPBD: constraint sweeps per substep.
    pub xpbd_sweeps: u32,
}

impl Iterations {
    /// The largest count a field may hold (a typo of 10⁹ iterations is an error, not a hang).
    pub const MAX: u32 = 100_000;
    /// The rule every count must meet, as the error messages say it.
    pub const RULE: &'static str = "must be between 1 and 100000";

    /// The fields' names, as a scene file writes them.
    pub const NAMES: [&'static str; 4] = ["newton", "projective", "xpbd_substeps", "xpbd_sweeps"];
    /// The counts, in the order of [`Iterations::NAMES`].
    pub fn values(&self) -> [u32; 4] {
        [
            self.newton,
            self.projective,
            self.xpbd_substeps,
            self.xpbd_sweeps,
        ]
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
        }
    }
}

impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.cli_name())
    }
}
