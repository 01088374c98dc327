//! Scene validation: every problem is named with where it is, so a user can fix the file.

use super::format::*;

/// Scenes larger than this are refused before anything is allocated for them.
pub const MAX_PARTICLES: usize = 20_000_000;
/// Scenes with more springs than this are refused before anything is allocated for them.
pub const MAX_SPRINGS: usize = 80_000_000;
/// At most this many problems are listed; the rest are counted.
const MAX_LISTED: usize = 20;

/// Checks a scene (its generators by their parameters, without expanding them). On failure,
/// returns every problem found.
pub fn validate(scene: &Scene) -> Result<(), Vec<String>> {
    let mut p = Problems::default();
    let finite2 = |v: (f64, f64)| v.0.is_finite() && v.1.is_finite();

    if !finite2(scene.gravity) {
        p.push(format!("gravity: must be finite, got {:?}", scene.gravity));
    }
    if !(scene.damping.is_finite() && scene.damping >= 0.0) {
        p.push(format!(
            "damping: must be finite and >= 0, got {}",
            scene.damping
        ));
    }
    if let Some(g) = scene.ground.filter(|g| !g.is_finite()) {
        p.push(format!("ground: must be finite, got {g}"));
    }
    if !(scene.spring_damping.is_finite() && scene.spring_damping >= 0.0) {
        p.push(format!(
            "spring_damping: must be finite and >= 0, got {}",
            scene.spring_damping
        ));
    }
    if let Some(rule) = crate::sim::dt_problem(scene.dt) {
        p.push(format!("dt: {rule}, got {}", scene.dt));
    }
    if let Some(s) = scene.tear.filter(|s| !(s.is_finite() && *s > 0.0)) {
        p.push(format!("tear: the strain must be finite and > 0, got {s}"));
    }
    if let Some((field, v)) = scene.iterations.out_of_range() {
        use crate::sim::Iterations;
        let (name, rule) = (Iterations::NAMES[field], Iterations::RULE);
        p.push(format!("iterations.{name}: {rule}, got {v}"));
    }
    if let Some((name, v, rule)) = scene.iterations.bad_real() {
        p.push(format!("iterations.{name}: {rule}, got {v}"));
    }
    if let Some(c) = &scene.contact
        && let Some((field, v, rule)) = c.problem()
    {
        p.push(format!("contact.{field}: {rule}, got {v}"));
    }
    for (i, o) in scene.obstacles.iter().enumerate() {
        let placed = match o.placed() {
            Ok(placed) => placed,
            Err(e) => {
                p.push(format!("obstacles[{i}]: {e}"));
                continue;
            }
        };
        if let Some((what, v, rule)) = placed.problem() {
            // A bound's value is worth showing; a NaN or a zero length is the rule itself.
            let got = if v.is_finite() && what != "length" {
                format!(", got {v}")
            } else {
                String::new()
            };
            // As the file names them: a moving obstacle's motion beside its shape.
            let what = match (o, what) {
                (ObstacleDef::Moving { .. }, "velocity.x" | "velocity.y") => what.to_string(),
                (ObstacleDef::Moving { .. }, "angular velocity") => "spin".to_string(),
                (ObstacleDef::Moving { .. }, _) => format!("shape.{what}"),
                _ => what.to_string(),
            };
            p.push(format!("obstacles[{i}]: {what}: {rule}{got}"));
        }
    }
    check_bodies(&mut p, &scene.bodies);
    if let Some(c) = &scene.click {
        if !(c.radius.is_finite() && c.radius >= 0.0) {
            p.push(format!(
                "click.radius: must be finite and >= 0, got {}",
                c.radius
            ));
        }
        check_mass(&mut p, "click", c.mass);
        check_stiffness(&mut p, "click", c.stiffness);
    }

    for (i, g) in scene.generate.iter().enumerate() {
        let at = format!("generate[{i}]");
        match *g {
            Generator::Grid {
                cols,
                rows,
                min,
                max,
                mass,
                stiffness,
                vel,
                damping,
                plastic,
                ..
            } => {
                check_damping(&mut p, &at, damping);
                if let Some(plastic) = plastic {
                    check_plastic(&mut p, &at, &plastic);
                }
                if cols < 2 || rows < 2 {
                    p.push(format!(
                        "{at}: a grid needs cols >= 2 and rows >= 2, got {cols} x {rows}"
                    ));
                }
                if !(finite2(min) && finite2(max) && finite2(vel)) {
                    p.push(format!("{at}: min, max and vel must be finite"));
                } else if !(min.0 < max.0 && min.1 < max.1) {
                    // Swapped corners mirror the grid (its top row, which `pin` names, at the
                    // bottom); equal ones pile its particles on each other.
                    p.push(format!(
                        "{at}: min {min:?} must lie below and left of max {max:?} (min is the \
                         lower-left corner, max the upper-right)"
                    ));
                }
                check_mass(&mut p, &at, mass);
                check_stiffness(&mut p, &at, stiffness);
            }
            Generator::Chain {
                from,
                to,
                segments,
                mass,
                stiffness,
                ..
            } => {
                if segments < 1 {
                    p.push(format!("{at}: a chain needs segments >= 1"));
                }
                if !(finite2(from) && finite2(to)) {
                    p.push(format!("{at}: from and to must be finite"));
                } else if from == to {
                    p.push(format!(
                        "{at}: a chain needs two different ends, not from = to = {from:?}"
                    ));
                }
                check_mass(&mut p, &at, mass);
                check_stiffness(&mut p, &at, stiffness);
            }
            Generator::Ring {
                center,
                radius,
                segments,
                mass,
                stiffness,
                pressure,
                damping,
            } => {
                if segments < 3 {
                    p.push(format!("{at}: a ring needs segments >= 3, got {segments}"));
                }
                if !finite2(center) {
                    p.push(format!("{at}: center must be finite"));
                }
                if !(radius.is_finite() && radius > 0.0) {
                    p.push(format!("{at}: radius must be finite and > 0, got {radius}"));
                }
                if !(pressure.is_finite() && pressure >= 0.0) {
                    p.push(format!(
                        "{at}: pressure (nRT) must be finite and >= 0, got {pressure}"
                    ));
                }
                check_mass(&mut p, &at, mass);
                check_stiffness(&mut p, &at, stiffness);
                check_damping(&mut p, &at, damping);
            }
        }
    }
    let (n_particles, n_springs) = scene.counts();
    if n_particles > MAX_PARTICLES || n_springs > MAX_SPRINGS {
        p.push(format!(
            "the scene has {n_particles} particles and {n_springs} springs; at most \
             {MAX_PARTICLES} particles and {MAX_SPRINGS} springs are supported"
        ));
    }
    if !p.list.is_empty() {
        return Err(p.finish());
    }

    for (i, q) in scene.particles.iter().enumerate() {
        let at = format!("particles[{i}]");
        if !finite2(q.pos) {
            p.push(format!("{at}: pos must be finite, got {:?}", q.pos));
        }
        if !finite2(q.vel) {
            p.push(format!("{at}: vel must be finite, got {:?}", q.vel));
        }
        check_mass(&mut p, &at, q.mass);
    }
    for (i, s) in scene.springs.iter().enumerate() {
        let at = format!("springs[{i}]");
        for (end, idx) in [("a", s.a), ("b", s.b)] {
            if idx >= n_particles {
                p.push(format!(
                    "{at}: {end} = {idx} is out of range ({})",
                    indices(n_particles)
                ));
            }
        }
        if s.a == s.b {
            p.push(format!(
                "{at}: a and b are both {}: a spring joins two different particles",
                s.a
            ));
        }
        check_stiffness(&mut p, &at, s.stiffness);
        if let Some(rest) = s.rest.filter(|r| !(r.is_finite() && *r >= 0.0)) {
            p.push(format!("{at}: rest must be finite and >= 0, got {rest}"));
        }
        check_damping(&mut p, &at, s.damping);
        if let Some(a) = s.actuation {
            if !(a.amplitude.is_finite() && a.amplitude.abs() < 1.0) {
                p.push(format!(
                    "{at}: actuation.amplitude must be finite and between -1 and 1 (the rest \
                     length L0 (1 + A sin) must stay positive), got {}",
                    a.amplitude
                ));
            }
            if !(a.frequency.is_finite() && a.frequency >= 0.0) {
                p.push(format!(
                    "{at}: actuation.frequency must be finite and >= 0, got {}",
                    a.frequency
                ));
            }
            if !a.phase.is_finite() {
                p.push(format!(
                    "{at}: actuation.phase must be finite, got {}",
                    a.phase
                ));
            }
        }
        if let Some(plastic) = s.plastic {
            check_plastic(&mut p, &at, &plastic);
            if s.actuation.is_some() {
                p.push(format!(
                    "{at}: a spring is a muscle or plastic, not both (a muscle's rest length \
                     follows its actuation, so it cannot yield)"
                ));
            }
        }
    }
    for (i, body) in scene.pressure.iter().enumerate() {
        let at = format!("pressure[{i}]");
        if body.particles.len() < 3 {
            p.push(format!(
                "{at}: a loop needs at least 3 particles, got {}",
                body.particles.len()
            ));
        }
        if let Some(&bad) = body.particles.iter().find(|&&j| j >= n_particles) {
            p.push(format!(
                "{at}: particle {bad} is out of range ({})",
                indices(n_particles)
            ));
        }
        let mut seen = body.particles.clone();
        seen.sort_unstable();
        if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
            p.push(format!(
                "{at}: particle {} appears twice: a loop visits each particle once",
                w[0]
            ));
        }
        if !(body.nrt.is_finite() && body.nrt >= 0.0) {
            p.push(format!(
                "{at}: nrt must be finite and >= 0, got {}",
                body.nrt
            ));
        }
    }
    if !p.list.is_empty() {
        return Err(p.finish());
    }
    if let Some(c) = scene.contact.filter(|c| c.particles && c.radius > 0.0)
        && let Some(problem) = super::start_apart::pairs_start_apart(scene, c.radius)
    {
        return Err(vec![problem]);
    }
    Ok(())
}

/// The valid indices, for an index out of range: "the scene has 3 particles: indices 0 to 2".
fn indices(n_particles: usize) -> String {
    match n_particles {
        0 => "the scene has no particles".into(),
        1 => "the scene has 1 particle: index 0".into(),
        n => format!("the scene has {n} particles: indices 0 to {}", n - 1),
    }
}

fn check_damping(p: &mut Problems, at: &str, c: Option<f64>) {
    if let Some(c) = c.filter(|c| !(c.is_finite() && *c >= 0.0)) {
        p.push(format!("{at}: damping must be finite and >= 0, got {c}"));
    }
}

fn check_plastic(p: &mut Problems, at: &str, plastic: &Plasticity) {
    if !(plastic.yield_strain.is_finite() && plastic.yield_strain >= 0.0) {
        p.push(format!(
            "{at}: plastic.yield must be finite and >= 0, got {}",
            plastic.yield_strain
        ));
    }
    if !(plastic.rate.is_finite() && plastic.rate >= 0.0) {
        p.push(format!(
            "{at}: plastic.rate must be finite and >= 0, got {}",
            plastic.rate
        ));
    }
}

fn check_mass(p: &mut Problems, at: &str, mass: f64) {
    if !(mass.is_finite() && mass > 0.0) {
        p.push(format!("{at}: mass must be finite and > 0, got {mass}"));
    }
}

fn check_stiffness(p: &mut Problems, at: &str, k: f64) {
    if !(k.is_finite() && k >= 0.0) {
        p.push(format!("{at}: stiffness must be finite and >= 0, got {k}"));
    }
}

#[derive(Default)]
struct Problems {
    list: Vec<String>,
    more: usize,
}

impl Problems {
    fn push(&mut self, s: String) {
        if self.list.len() < MAX_LISTED {
            self.list.push(s);
        } else {
            self.more += 1;
        }
    }

    fn finish(mut self) -> Vec<String> {
        if self.more > 0 {
            self.list
                .push(format!("... and {} more problems", self.more));
        }
        self.list
    }
}

/// The rigid bodies: each a shape that makes a collider, a mass, a finite motion; and a build
/// that runs them.
fn check_bodies(p: &mut Problems, bodies: &[super::format::BodyDef]) {
    if !bodies.is_empty() && !cfg!(feature = "avian") {
        p.push(format!(
            "bodies: {} rigid {}, but this build of hooke has no rigid bodies (build it with \
             the `avian` feature, as the default build is)",
            bodies.len(),
            if bodies.len() == 1 { "body" } else { "bodies" }
        ));
        return;
    }
    for (i, b) in bodies.iter().enumerate() {
        if let ObstacleDef::Moving { .. } = b.shape {
            p.push(format!(
                "bodies[{i}].shape: a body moves by its own `velocity` and `spin`: its shape is \
                 a Circle, Box, Segment or Polygon, not Moving"
            ));
            continue;
        }
        match b.shape.placed() {
            Ok(placed) => {
                if let Some((what, v, rule)) = placed.problem() {
                    p.push(format!("bodies[{i}].shape: {what}: {rule}, got {v}"));
                }
            }
            Err(e) => p.push(format!("bodies[{i}].shape: {e}")),
        }
        if !(b.mass.is_finite() && b.mass > 0.0) {
            p.push(format!(
                "bodies[{i}].mass: must be finite and > 0, got {}",
                b.mass
            ));
        }
        let (vx, vy) = b.velocity;
        if !(vx.is_finite() && vy.is_finite()) {
            p.push(format!(
                "bodies[{i}].velocity: must be finite, got ({vx}, {vy})"
            ));
        }
        if !b.spin.is_finite() {
            p.push(format!("bodies[{i}].spin: must be finite, got {}", b.spin));
        }
    }
}

#[cfg(test)]
mod tests {
    /// A build without rigid bodies refuses a scene that has some, and says how to get them.
    #[test]
    fn bodies_need_a_build_that_has_them() {
        let mut scene = super::Scene::default();
        scene.bodies.push(crate::scene::BodyDef {
            shape: crate::scene::ObstacleDef::Circle {
                center: (0.5, 0.5),
                radius: 0.1,
            },
            mass: 1.0,
            velocity: (0.0, 0.0),
            spin: 0.0,
            fixed: false,
        });
        let result = super::validate(&scene);
        if cfg!(feature = "avian") {
            assert_eq!(result, Ok(()));
        } else {
            let e = result.unwrap_err().join("\n");
            assert!(
                e.contains("bodies:") && e.contains("`avian` feature"),
                "{e}"
            );
        }
    }
}
