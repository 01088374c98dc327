//! Reading scene files and putting scenes into a Bevy world.

use super::despawn::despawn_all;
use super::format::{Actuation, ParticleDef, Plasticity, PressureDef, Scene, SpringDef};
use super::generate::Expanded;
use super::reserve::Reserved;
use super::validate::validate;
use crate::sim::*;
use bevy::math::DVec2;
use bevy::prelude::*;
use std::fmt;
use std::path::{Path, PathBuf};

/// Why a scene could not be loaded. Every variant names the file.
#[derive(Debug)]
pub enum SceneError {
    /// The file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The file is not valid RON for the schema.
    Parse {
        /// The file.
        path: PathBuf,
        /// Line of the error (1-based).
        line: usize,
        /// Column of the error (1-based).
        col: usize,
        /// What the parser expected.
        message: String,
    },
    /// No such file, and no built-in scene of that name.
    Unknown {
        /// The name as given.
        name: String,
        /// The built-in names near it (a typo's), nearest first; empty when none is.
        near: Vec<&'static str>,
    },
    /// The file parses but describes an impossible scene.
    Invalid {
        /// The file.
        path: PathBuf,
        /// Every problem found (up to 20, then a count).
        problems: Vec<String>,
    },
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneError::Io { path, error } if error.kind() == std::io::ErrorKind::InvalidData => {
                write!(
                    f,
                    "cannot read scene {}: it is not UTF-8 text ({error}); save it as UTF-8",
                    path.display()
                )
            }
            SceneError::Io { path, error } => {
                write!(f, "cannot read scene {}: {error}", path.display())?;
                // `--scene rope.ron` outside the repository: the name was meant.
                let stem = path.file_stem().and_then(|s| s.to_str());
                match stem.filter(|s| super::builtin::names().contains(s)) {
                    Some(name) if error.kind() == std::io::ErrorKind::NotFound => {
                        write!(
                            f,
                            "; the built-in scene of that name is `{name}`, without `.ron`"
                        )
                    }
                    _ => Ok(()),
                }
            }
            SceneError::Parse {
                path,
                line,
                col,
                message,
            } => write!(f, "{}:{line}:{col}: {message}", path.display()),
            SceneError::Unknown { name, near } => {
                write!(f, "no scene file or built-in scene named `{name}`")?;
                if near.is_empty() {
                    let all = super::builtin::names();
                    write!(f, " (built-in scenes: {})", all.join(", "))
                } else {
                    let listed: Vec<String> = near.iter().map(|n| format!("`{n}`")).collect();
                    write!(f, "; did you mean {}?", listed.join(" or "))
                }
            }
            SceneError::Invalid { path, problems } => {
                write!(f, "invalid scene {}:", path.display())?;
                for p in problems {
                    write!(f, "\n  - {p}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for SceneError {}

/// A scene that passed validation. Its generators stay as written: loading streams their
/// particles and springs into the world ([`Scene::particle_defs`]), and
/// [`LoadedScene::expanded`] lists them where a list is wanted.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// Where it came from, if from a file.
    pub path: Option<PathBuf>,
    /// The scene as written.
    pub scene: Scene,
}

impl LoadedScene {
    /// Validates a scene built in code; `path` only names it in errors.
    pub fn from_scene(scene: Scene, path: Option<PathBuf>) -> Result<Self, SceneError> {
        let invalid = |problems| SceneError::Invalid {
            path: path.clone().unwrap_or_else(|| "<scene>".into()),
            problems,
        };
        validate(&scene).map_err(invalid)?;
        Ok(LoadedScene { path, scene })
    }

    /// Its particles and springs, generators expanded.
    pub fn expanded(&self) -> Expanded {
        self.scene.expand()
    }

    /// Parses and validates RON text; `path` only names the source in errors. A byte-order mark
    /// at the start (as some Windows editors save UTF-8) is no part of the scene and is skipped.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SceneError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let scene: Scene = super::ron_options()
            .from_str(text)
            .map_err(|e| SceneError::Parse {
                path: path.to_owned(),
                line: e.span.start.line,
                col: e.span.start.col,
                message: super::typo::message(&e.code, text, e.span.start.line, e.span.start.col),
            })?;
        Self::from_scene(scene, Some(path.to_owned()))
    }

    /// Reads, parses and validates a scene file.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|error| SceneError::Io {
            path: path.to_owned(),
            error,
        })?;
        Self::parse(&text, path)
    }

    /// The scene's name: its file stem, or `untitled`.
    pub fn name(&self) -> String {
        self.path
            .as_ref()
            .and_then(|p| p.file_stem())
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "untitled".into())
    }
}

/// The scene the world was loaded from, kept for reset and the click rules.
#[derive(Resource, Debug, Clone)]
pub struct CurrentScene(pub LoadedScene);

/// Replaces everything in the world's simulation with the scene: despawns all particles and
/// springs, sets the parameters, resets clock, status and counters, and spawns the scene.
pub fn load_into_world(world: &mut World, loaded: &LoadedScene) {
    let s = &loaded.scene;
    let params = SimParams {
        gravity: DVec2::from(s.gravity),
        damping: s.damping,
        spring_damping: s.spring_damping,
        drag_in_solve: s.drag_in_solve,
        ground: s.ground,
        integrator: s.integrator,
        dt: s.dt,
        paused: s.start_paused,
        stiffness_override: None,
        tear: s.tear,
        iterations: s.iterations,
        contact: s.contact,
    };
    despawn_contents(world, params);
    replace_obstacles(world, &s.obstacles);
    super::bodies::replace_bodies(world, &s.bodies, DVec2::from(s.gravity));
    let particles = spawn_streamed(
        world,
        loaded.scene.particle_defs(),
        loaded.scene.spring_defs(),
        loaded.scene.has_spring_materials(),
    );
    spawn_pressure(world, &particles, &loaded.scene.pressure_defs());
    world.insert_resource(SimClock::default());
    world.insert_resource(SimStatus::default());
    world.insert_resource(PassCounts::default());
    world.insert_resource(Tearing::default());
    world.insert_resource(CurrentScene(loaded.clone()));
}

/// Despawns every particle and spring, sets the parameters and spawns `expanded` in their
/// place (the solver repacks on the next tick). Clock, status and counters are left alone:
/// a scene load resets them, an undo restores its own.
pub fn replace_contents(world: &mut World, params: SimParams, expanded: &Expanded) {
    despawn_contents(world, params);
    spawn_expanded(world, expanded);
}

/// Despawns every particle and spring and sets the parameters; a new, empty solver.
fn despawn_contents(world: &mut World, params: SimParams) {
    despawn_all::<Or<(With<Particle>, With<Spring>, With<PressureBody>)>>(world);
    *world.resource_mut::<SimParams>() = params;
    world.insert_resource(Solver::default());
}

/// Despawns every obstacle and spawns the scene's, in its order.
pub fn replace_obstacles(world: &mut World, obstacles: &[super::format::ObstacleDef]) {
    despawn_all::<With<Obstacle>>(world);
    // Validated before: a polygon that does not make one is not in a loaded scene.
    for placed in obstacles.iter().filter_map(|o| o.placed().ok()) {
        let pose = placed.pose;
        world.spawn((
            Obstacle(placed.shape),
            ObstaclePose {
                center: pose.center,
                angle: pose.angle,
            },
            ObstacleVelocity {
                linear: pose.velocity,
                angular: pose.angular_velocity,
            },
        ));
    }
}

/// The world's obstacles at their current poses and velocities, in the order they were made, as
/// a scene writes them.
pub fn obstacle_defs(world: &mut World) -> Vec<super::format::ObstacleDef> {
    let mut all: Vec<((CreationOrder, Entity), crate::solver::Placed)> = world
        .query::<(
            Entity,
            &CreationOrder,
            &Obstacle,
            &ObstaclePose,
            &ObstacleVelocity,
        )>()
        .iter(world)
        .map(|(e, order, o, pose, v)| {
            let placed = crate::sim::obstacles::placed(o, pose, v);
            ((*order, e), placed)
        })
        .collect();
    all.sort_by_key(|(key, _)| *key);
    all.iter()
        .map(|(_, p)| super::format::ObstacleDef::from_placed(p))
        .collect()
}

/// Spawns particles and springs (in that order, so their creation order is the list's);
/// springs index into the particles given here. Returns the particles.
pub fn spawn_expanded(world: &mut World, expanded: &Expanded) -> Vec<Entity> {
    let particles = spawn_streamed(
        world,
        expanded.particles.iter().copied(),
        expanded.springs.iter().copied(),
        expanded.springs.iter().any(SpringDef::has_material),
    );
    spawn_pressure(world, &particles, &expanded.pressure);
    particles
}

/// Spawns a [`PressureBody`] for each loop, over the particles just spawned.
fn spawn_pressure(world: &mut World, particles: &[Entity], loops: &[PressureDef]) {
    for def in loops {
        world.spawn(PressureBody {
            particles: def.particles.iter().map(|&i| particles[i]).collect(),
            nrt: def.nrt,
        });
    }
}

/// A spring's material components, inserted beside its [`Spring`].
fn insert_materials(world: &mut World, e: Entity, def: &SpringDef) {
    let mut spring = world.entity_mut(e);
    if let Some(c) = def.damping {
        spring.insert(Dashpot(c));
    }
    if let Some(a) = def.actuation {
        spring.insert(Muscle {
            amplitude: a.amplitude,
            frequency: a.frequency,
            phase: a.phase,
        });
    }
    if let Some(p) = def.plastic {
        spring.insert(Plastic {
            yield_strain: p.yield_strain,
            rate: p.rate,
        });
    }
}

/// [`spawn_expanded`] from streams, in batches that the ECS sizes from the streams' lengths,
/// with ids reserved so that its per-entity storage grows once ([`Reserved`]): a cloth of
/// millions of springs then never doubles a table, and no list of the whole scene is built
/// first. The particles are one batch, the springs two (a batch holds at most half of them;
/// the second doubles the first's table, to exactly their number). Pinned particles get
/// [`Pinned`] after their batch; creation order is the streams' either way.
fn spawn_streamed(
    world: &mut World,
    particles: impl Iterator<Item = ParticleDef>,
    springs: impl Iterator<Item = SpringDef>,
    materials: bool,
) -> Vec<Entity> {
    let exact = |(lower, upper): (usize, Option<usize>)| (upper == Some(lower)).then_some(lower);
    let counts = exact(particles.size_hint()).zip(exact(springs.size_hint()));
    let mut reserved = counts.and_then(|(p, s)| Reserved::new(world, p + s));
    let release = |reserved: &mut Option<Reserved>, world: &mut World, n: usize| {
        if let Some(r) = reserved {
            r.release(world, n);
        }
    };
    let mut pinned = vec![];
    let bundles = particles.enumerate().map(|(i, p)| {
        if p.pinned {
            pinned.push(i);
        }
        let vel = if p.pinned {
            DVec2::ZERO
        } else {
            DVec2::from(p.vel)
        };
        (
            Particle,
            Position(DVec2::from(p.pos)),
            Velocity(vel),
            Mass(p.mass),
        )
    });
    release(&mut reserved, world, counts.map_or(0, |c| c.0));
    let entities: Vec<Entity> = world.spawn_batch(bundles).collect();
    for &i in &pinned {
        world.entity_mut(entities[i]).insert(Pinned);
    }
    if materials {
        // Springs with materials of their own: one by one, each with its components (such
        // scenes are small).
        if let Some(r) = reserved {
            r.finish(world);
        }
        for s in springs {
            let e = world
                .spawn(Spring::new(
                    entities[s.a],
                    entities[s.b],
                    s.rest.unwrap_or_default(),
                    s.stiffness,
                ))
                .id();
            insert_materials(world, e, &s);
        }
        return entities;
    }
    let mut springs = springs.map(|s| {
        Spring::new(
            entities[s.a],
            entities[s.b],
            s.rest.unwrap_or_default(),
            s.stiffness,
        )
    });
    let half = counts.map_or(0, |c| c.1 / 2);
    release(&mut reserved, world, half);
    world.spawn_batch(springs.by_ref().take(half));
    release(&mut reserved, world, usize::MAX);
    world.spawn_batch(springs);
    if let Some(r) = reserved {
        r.finish(world);
    }
    entities
}

/// The world's current particles and springs as an explicit scene (for saving what a user made).
/// Springs carry the stiffness in effect (the override, when set).
pub fn snapshot(world: &mut World) -> Scene {
    let params = world.resource::<SimParams>().clone();
    let state = explicit_state(world, params.stiffness_override);
    let click = world
        .get_resource::<CurrentScene>()
        .and_then(|c| c.0.scene.click);
    let obstacles = obstacle_defs(world);
    let bodies = super::bodies::body_defs(world);
    Scene {
        gravity: (params.gravity.x, params.gravity.y),
        damping: params.damping,
        spring_damping: params.spring_damping,
        drag_in_solve: params.drag_in_solve,
        ground: params.ground,
        integrator: params.integrator,
        dt: params.dt,
        particles: state.particles,
        springs: state.springs,
        generate: vec![],
        click,
        start_paused: false,
        tear: params.tear,
        iterations: params.iterations,
        obstacles,
        contact: params.contact,
        pressure: state.pressure,
        bodies,
    }
}

/// Every particle in creation order and every spring by its ends' indices (the solver's
/// order): what
/// [`spawn_expanded`] takes to make the same network again. Springs get `stiffness` when it is
/// set, else their own. Springs whose ends are not both particles are left out.
pub fn explicit_state(world: &mut World, stiffness: Option<f64>) -> Expanded {
    let mut particles: Vec<(CreationOrder, Entity, ParticleDef)> = world
        .query_filtered::<(
            Entity,
            &CreationOrder,
            &Position,
            &Velocity,
            &Mass,
            Has<Pinned>,
        ), With<Particle>>()
        .iter(world)
        .map(|(e, p, x, v, m, pinned)| {
            let def = ParticleDef {
                pos: (x.0.x, x.0.y),
                vel: (v.0.x, v.0.y),
                mass: m.0,
                pinned,
            };
            (*p, e, def)
        })
        .collect();
    particles.sort_by_key(|p| p.0);
    let index: bevy::ecs::entity::EntityHashMap<usize> = particles
        .iter()
        .enumerate()
        .map(|(i, p)| (p.1, i))
        .collect();
    let mut springs: Vec<(Entity, SpringDef)> = world
        .query::<(
            Entity,
            &Spring,
            Option<&Dashpot>,
            Option<&Muscle>,
            Option<&Plastic>,
        )>()
        .iter(world)
        .filter_map(|(e, s, dashpot, muscle, plastic)| {
            let def = SpringDef {
                damping: dashpot.map(|d| d.0),
                actuation: muscle.map(|m| Actuation {
                    amplitude: m.amplitude,
                    frequency: m.frequency,
                    phase: m.phase,
                }),
                plastic: plastic.map(|p| Plasticity {
                    yield_strain: p.yield_strain,
                    rate: p.rate,
                }),
                ..SpringDef::new(
                    *index.get(&s.a)?,
                    *index.get(&s.b)?,
                    s.rest,
                    stiffness.unwrap_or(s.stiffness),
                )
            };
            Some((e, def))
        })
        .collect();
    // Loops by their particles' indices; a despawned particle leaves its loop.
    let mut pressure: Vec<(Entity, PressureDef)> = world
        .query::<(Entity, &PressureBody)>()
        .iter(world)
        .map(|(e, body)| {
            let particles = body.particles.iter().filter_map(|p| index.get(p).copied());
            let def = PressureDef {
                particles: particles.collect(),
                nrt: body.nrt,
            };
            (e, def)
        })
        .filter(|(_, def)| def.particles.len() >= 3)
        .collect();
    pressure.sort_by_key(|(e, _)| *e);
    // In the solver's order: by ends, ties by entity.
    springs.sort_by_key(|(e, s)| (s.a, s.b, *e));
    Expanded {
        particles: particles.into_iter().map(|p| p.2).collect(),
        springs: springs.into_iter().map(|s| s.1).collect(),
        pressure: pressure.into_iter().map(|p| p.1).collect(),
    }
}

/// Writes a scene as RON.
pub fn to_ron(scene: &Scene) -> Result<String, ron::Error> {
    let config = ron::ser::PrettyConfig::new()
        .depth_limit(2)
        .struct_names(false);
    ron::ser::to_string_pretty(scene, config)
}
