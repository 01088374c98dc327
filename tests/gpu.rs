//! The step on the graphics card (the `gpu` feature), on whatever adapter this machine has:
//! Mesa's software Vulkan (lavapipe) in CI, so that the real shaders are tested there. A
//! machine with no adapter prints why and skips, unless `HOOKE_REQUIRE_GPU` is set (CI sets
//! it): then no adapter is a failure, not a silent pass.
#![cfg(feature = "gpu")]

mod common;
use common::*;
use hooke::scene::presets;
use hooke::sim::{self, Integrator, SimClock, SimParams};
use hooke::solver::gpu::{Gpu, GpuStep, Precision};

/// The card, or `None` (with the reason printed) where this machine has none and none is
/// required.
fn card() -> Option<Gpu> {
    match Gpu::open() {
        Ok(gpu) => {
            println!("adapter: {}", gpu.adapter());
            Some(gpu)
        }
        Err(e) if std::env::var_os("HOOKE_REQUIRE_GPU").is_none() => {
            println!("skipped: {e}");
            None
        }
        Err(e) => panic!("HOOKE_REQUIRE_GPU is set and {e}"),
    }
}

/// Σ(x + y) after 1000 steps, from shared/reference.md (an independent NumPy implementation).
const REFERENCE: [(Integrator, f64); 2] = [
    (Integrator::SymplecticEuler, 998.4039018283542),
    (Integrator::ExplicitEuler, 998.4254532335524),
];

fn cloth32(integrator: Integrator) -> bevy::app::App {
    let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
    scene.integrator = integrator;
    app_with(scene)
}

/// The 32×32 cloth, 1000 steps on the card in f32 (in submits of 1000 and of 7 steps), and
/// in f64 where the adapter has it: the reference sum to 1e-5 relative in f32, 1e-12 in f64.
#[test]
fn cloth32_on_the_card_matches_the_reference_sum() {
    let Some(gpu) = card() else { return };
    for (integrator, expected) in REFERENCE {
        for precision in gpu.precisions() {
            let tolerance = match precision {
                Precision::F32 => 1e-5,
                Precision::F64 => 1e-12,
            };
            for per_read in [1000, 7] {
                let mut app = cloth32(integrator);
                let world = app.world_mut();
                let mut taken = 0;
                while taken < 1000 {
                    let n = per_read.min(1000 - taken);
                    taken += sim::gpu::advance_on_gpu(world, &gpu, precision, n).unwrap();
                }
                assert_eq!(world.resource::<SimClock>().steps, 1000);
                let s = solver(&app);
                let sum: f64 = s.x().iter().map(|p| p.x + p.y).sum();
                let rel = (sum - expected).abs() / expected;
                println!("{integrator} {precision:?} in submits of {per_read}: rel {rel:e}");
                assert!(
                    rel < tolerance,
                    "{integrator} in {precision:?}: Σ(x+y) = {sum}, reference {expected}, rel {rel:e}"
                );
            }
        }
    }
}

/// Every particle of the card's cloth against the CPU's after 1000 steps, in f32: within the
/// f32 tolerance of the cloth's size, and the pinned row exactly where it was.
#[test]
fn the_card_and_the_cpu_agree_particle_by_particle() {
    let Some(gpu) = card() else { return };
    let mut cpu = cloth32(Integrator::SymplecticEuler);
    step(&mut cpu, 1000);
    let mut card_app = cloth32(Integrator::SymplecticEuler);
    sim::gpu::advance_on_gpu(card_app.world_mut(), &gpu, Precision::F32, 1000).unwrap();
    let (a, b) = (solver(&cpu), solver(&card_app));
    let mut worst: f64 = 0.0;
    for i in 0..a.particle_count() {
        worst = worst.max((a.x()[i] - b.x()[i]).length());
        if a.is_pinned(i) {
            assert_eq!(a.x()[i], b.x()[i], "pinned particle {i} moved");
        }
    }
    println!("largest difference: {worst:e} m");
    assert!(worst < 1e-4, "a particle is {worst} m from the CPU's");
}

/// What the card does not run stays on the CPU, and the reason names it.
#[test]
fn the_card_names_what_it_does_not_run() {
    let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
    scene.integrator = Integrator::Xpbd;
    let app = app_with(scene);
    let why = sim::gpu::unsupported(app.world()).expect("XPBD is not on the card");
    assert!(why.contains("XPBD") || why.contains("xpbd"), "{why}");
    let pile = app_with(presets::resolve("pile").unwrap().scene.clone());
    let why = sim::gpu::unsupported(pile.world()).expect("the pile has contact");
    assert!(why.contains("contact"), "{why}");
    let Some(gpu) = card() else { return };
    let mut app = app;
    let before = solver(&app).x().to_vec();
    assert!(sim::gpu::advance_on_gpu(app.world_mut(), &gpu, Precision::F32, 10).is_err());
    assert_eq!(solver(&app).x(), &before[..], "a refused run stepped");
    assert_eq!(
        app.world().resource::<SimParams>().integrator,
        Integrator::Xpbd
    );
    let _ = GpuStep::unsupported;
}
