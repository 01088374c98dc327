//! The documented step semantics, checked against the reference figures in shared/reference.md:
//! the 32x32 cloth after 1000 steps in f64.

mod common;
use common::*;
use hooke::scene::presets;
use hooke::sim::{Integrator, SimParams};

/// Σ(x + y) after 1000 steps, from shared/reference.md (an independent NumPy implementation).
const REFERENCE: [(Integrator, f64, &str); 2] = [
    (Integrator::SymplecticEuler, 998.4039018283542, "symplectic"),
    (Integrator::ExplicitEuler, 998.4254532335524, "explicit"),
];

fn run_cloth(integrator: Integrator) -> bevy::app::App {
    let loaded = presets::resolve("cloth32").unwrap();
    let mut scene = loaded.scene.clone();
    scene.integrator = integrator;
    let mut app = app_with(scene);
    assert_eq!(app.world().resource::<SimParams>().integrator, integrator);
    step(&mut app, 1000);
    app
}

#[test]
fn cloth32_checksums_match_the_reference() {
    for (integrator, expected, _) in REFERENCE {
        let app = run_cloth(integrator);
        let s = solver(&app);
        assert_eq!((s.particle_count(), s.spring_count()), (1024, 3906));
        let sum: f64 = s.x().iter().map(|p| p.x + p.y).sum();
        let rel = (sum - expected).abs() / expected;
        assert!(
            rel < 1e-12,
            "{integrator}: Σ(x+y) = {sum:?}, reference {expected:?}, rel {rel:e}"
        );
    }
}

/// Every particle's final position against the peer's full state (shared/peer/ref), when the
/// shared folder is beside the project.
#[test]
fn cloth32_positions_match_the_peer_state() {
    let Some(shared) = shared_dir() else {
        println!("skipped: no shared/ beside the project");
        return;
    };
    for (integrator, _, name) in REFERENCE {
        let path = shared.join(format!("peer/ref/cloth32_{name}_1000.csv"));
        let text = std::fs::read_to_string(&path).unwrap();
        let app = run_cloth(integrator);
        let s = solver(&app);
        let mut rows = 0;
        for line in text.lines().skip(1) {
            let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
            let i = f[0] as usize;
            let d = (s.x()[i].x - f[1]).abs().max((s.x()[i].y - f[2]).abs());
            assert!(
                d < 1e-12,
                "{integrator}: particle {i} is {d:e} from the reference"
            );
            rows += 1;
        }
        assert_eq!(rows, 1024);
    }
}
