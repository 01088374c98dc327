//! The force evaluation that every method starts from: the body forces (gravity plus the
//! particles' external forces, held constant over the step), then the springs and the
//! materials. An external force is taken as independent of x, so implicit Euler's Jacobian
//! has no external term.

use crate::solver::forces::kernels::{apply_gravity, apply_gravity_and_external};
use crate::solver::forces::passes::{damped_spring_forces_from, spring_forces_from};
use crate::solver::state::State;
use crate::solver::threads::{SpringBuffers, Threads};
use glam::DVec2;

/// f = m g + f_ext, the forces that do not depend on the springs: the start of every force
/// evaluation (the schedule's gravity pass and every integrator stage). `external` is `None`
/// when every external force is zero.
pub fn body_forces(
    threads: &Threads,
    springs: usize,
    f: &mut [DVec2],
    mass: &[f64],
    external: Option<&[DVec2]>,
    g: DVec2,
) {
    match external {
        None => threads.each(springs, (f, mass), |(f, m)| apply_gravity(f, m, g)),
        Some(e) => threads.each(springs, (f, mass, e), |(f, m, e)| {
            apply_gravity_and_external(f, m, e, g)
        }),
    }
}

/// f = m g + f_ext + Σ spring forces at positions `x`, in one parallel region: each thread
/// starts its own particles with their body forces, then adds its springs' (bit for bit
/// [`body_forces`] then the spring pass). Every force evaluation with springs runs it: the
/// step's force pass and every stage. The materials' forces (dashpots at velocities `v`, gas
/// pressure) follow, when the scene has them.
pub fn forces_at(
    s: &State,
    pairs: &mut SpringBuffers,
    f: &mut [DVec2],
    (x, v): (&[DVec2], &[DVec2]),
    g: DVec2,
    threads: &Threads,
) {
    let (mass, external) = (&s.mass[..], s.external_active.then_some(&s.external[..]));
    let init = |start: usize, f: &mut [DVec2]| {
        let m = &mass[start..start + f.len()];
        match external {
            None => apply_gravity(f, m, g),
            Some(e) => apply_gravity_and_external(f, m, &e[start..start + f.len()], g),
        }
    };
    if s.materials.has_dashpots() && s.materials.dashpot().len() == s.springs.len() {
        let springs = (&s.springs[..], s.materials.dashpot());
        damped_spring_forces_from(threads, pairs, f, (x, v), springs, &init);
        s.materials.add_gas_forces(x, f);
    } else {
        spring_forces_from(threads, pairs, f, x, &s.springs, &init);
        if s.materials.exerts_forces() {
            s.materials.add_forces(&s.springs, x, v, f);
        }
    }
}
