//! Scenes built as rapier's own examples build them — boxes stacked exactly touching on a
//! ground box, a tower of crossed planks, a wall of bricks, spheres poured into a box, the
//! drop-in's bin — each run with rapier's own contacts and with the discrete contact, in one
//! process, at a chosen Young's modulus. Rapier's `length_unit` is the bodies' size, as its
//! docs advise, and the step is 1/60 s unless a scene says otherwise.
//!
//! A run reports what became of the scene: whether it stood (every body within a tenth of its
//! size of where it rests, for the stacks; every sphere inside the box and at rest, for the
//! pour), was refused with a message, or failed (moved, or its energy grew), with the largest
//! indentation, the kinetic energy at the end, the sub-steps per step and both wall times.

use std::time::Instant;

use discrete_contact::error::Result;
use discrete_contact::material::{Friction, Material};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};
use discrete_contact::rapier3d_f64::prelude::*;

/// One scene of the suite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scene {
    /// A pyramid of 10 cm boxes in one vertical plane, `base` boxes in its lowest row (10 boxes
    /// for a base of 4, 55 for 10), on a ground box, 1000 kg/m³.
    Pyramid {
        /// Boxes in the lowest row.
        base: usize,
    },
    /// A tower of planks 22.5 × 1.5 × 2.5 cm, three to a layer 7.5 cm apart, each layer
    /// crossed over the one below, 600 kg/m³.
    PlankTower {
        /// Layers.
        layers: usize,
    },
    /// A wall of bricks 20 × 10 × 10 cm in running bond (every other row a brick shorter and
    /// shifted half a brick), 2000 kg/m³.
    BrickWall {
        /// Rows.
        rows: usize,
        /// Bricks in a row.
        per_row: usize,
    },
    /// Spheres of 1 cm radius released on a grid above a 20 × 20 cm box (a ground box and
    /// four walls) and left to fall in and settle, 2500 kg/m³.
    Pour {
        /// Spheres.
        spheres: usize,
    },
    /// The drop-in example's bin ([`crate::drop_in::bin_scene`]), 180 bodies, its own step of
    /// 1/240 s, rapier's `length_unit` 0.02 m.
    Bin {
        /// Falling bodies.
        bodies: usize,
    },
}

impl Scene {
    /// A short name for a table row.
    pub fn name(&self) -> String {
        match *self {
            Scene::Pyramid { base } => format!("pyramid of {}", base * (base + 1) / 2),
            Scene::PlankTower { layers } => format!("plank tower {layers}×3"),
            Scene::BrickWall { rows, per_row } => format!("brick wall {rows}×{per_row}"),
            Scene::Pour { spheres } => format!("pour of {spheres} spheres"),
            Scene::Bin { bodies } => format!("drop_in bin, {bodies} bodies"),
        }
    }

    /// Whether the scene starts at rest and must stay so (a stack), rather than settle.
    pub fn is_stack(&self) -> bool {
        matches!(self, Scene::Pyramid { .. } | Scene::PlankTower { .. } | Scene::BrickWall { .. })
    }
}

/// A built scene: the world and the bodies whose fate the run reports.
pub struct Built {
    /// The world, gravity on, its step and `length_unit` set.
    pub world: PhysicsWorld,
    /// The bodies that must stand (stacks) or settle (pour, bin).
    pub bodies: Vec<RigidBodyHandle>,
    /// The size of the bodies (m): what "within a tenth of its size" measures against.
    pub size: Real,
    /// For a pour: the box's inner half-width and top (m), which every sphere must end inside.
    pub container: Option<(Real, Real)>,
}

/// Rapier's own friction coefficient in every scene (the discrete contact sets its own law).
pub const RAPIER_FRICTION: Real = 0.6;

/// A world with gravity, step `dt` and rapier's `length_unit`.
fn world(dt: Real, length_unit: Real) -> PhysicsWorld {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    world.integration_parameters.dt = dt;
    world.integration_parameters.length_unit = length_unit;
    world
}

/// A fixed ground box whose top face is `y = 0`, `half` wide.
fn ground(world: &mut PhysicsWorld, half: Real) {
    let ground =
        world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.1, 0.0)));
    world.insert_collider(
        ColliderBuilder::cuboid(half, 0.1, half).friction(RAPIER_FRICTION),
        Some(ground),
    );
}

/// A dynamic box of half-extents `half` at `at`, turned `turn` about y, `density`.
fn block(
    world: &mut PhysicsWorld,
    at: Vector,
    half: Vector,
    turn: Real,
    density: Real,
) -> RigidBodyHandle {
    let body = world.insert_body(
        RigidBodyBuilder::dynamic().translation(at).rotation(Vector::new(0.0, turn, 0.0)),
    );
    world.insert_collider(
        ColliderBuilder::cuboid(half.x, half.y, half.z).density(density).friction(RAPIER_FRICTION),
        Some(body),
    );
    body
}

/// Builds `scene` with rapier's `length_unit` at the bodies' size.
pub fn build(scene: Scene) -> Built {
    build_at(scene, None)
}

/// Builds `scene`, with rapier's `length_unit` set to `length_unit` (m) where given.
pub fn build_at(scene: Scene, length_unit: Option<Real>) -> Built {
    let mut built = built(scene);
    if let Some(unit) = length_unit {
        built.world.integration_parameters.length_unit = unit;
    }
    built
}

/// The scene as [`build`] builds it.
fn built(scene: Scene) -> Built {
    match scene {
        Scene::Pyramid { base } => {
            let h = 0.05;
            let mut w = world(1.0 / 60.0, 2.0 * h);
            ground(&mut w, 5.0);
            let mut bodies = Vec::new();
            for row in 0..base {
                let n = base - row;
                for i in 0..n {
                    let x = (2 * i) as Real * h - (n - 1) as Real * h;
                    let y = h + 2.0 * h * row as Real;
                    bodies.push(block(
                        &mut w,
                        Vector::new(x, y, 0.0),
                        Vector::splat(h),
                        0.0,
                        1000.0,
                    ));
                }
            }
            Built { world: w, bodies, size: 2.0 * h, container: None }
        }
        Scene::PlankTower { layers } => {
            let (long, tall, wide) = (0.1125, 0.0075, 0.0125);
            let mut w = world(1.0 / 60.0, 2.0 * wide);
            ground(&mut w, 5.0);
            let mut bodies = Vec::new();
            for layer in 0..layers {
                let y = tall + 2.0 * tall * layer as Real;
                let crossed = layer % 2 == 1;
                for k in [-1.0, 0.0, 1.0] {
                    let offset = 0.075 * k;
                    let (at, turn) = if crossed {
                        (Vector::new(offset, y, 0.0), core::f64::consts::FRAC_PI_2)
                    } else {
                        (Vector::new(0.0, y, offset), 0.0)
                    };
                    bodies.push(block(&mut w, at, Vector::new(long, tall, wide), turn, 600.0));
                }
            }
            Built { world: w, bodies, size: 2.0 * tall, container: None }
        }
        Scene::BrickWall { rows, per_row } => {
            let half = Vector::new(0.1, 0.05, 0.05);
            let mut w = world(1.0 / 60.0, 0.1);
            ground(&mut w, 5.0);
            let mut bodies = Vec::new();
            for row in 0..rows {
                // Every other row a brick shorter, shifted half a brick: a long row's end
                // bricks rest on half their length, their centres over the edge below.
                let n = per_row - row % 2;
                for i in 0..n {
                    let x = (2 * i) as Real * half.x - (n - 1) as Real * half.x;
                    let y = half.y + 2.0 * half.y * row as Real;
                    bodies.push(block(&mut w, Vector::new(x, y, 0.0), half, 0.0, 2000.0));
                }
            }
            Built { world: w, bodies, size: 2.0 * half.y, container: None }
        }
        Scene::Pour { spheres } => {
            let r = 0.01;
            let inner = 0.1;
            let wall = 0.01;
            let height = 0.3;
            let mut w = world(1.0 / 60.0, 2.0 * r);
            ground(&mut w, inner + 2.0 * wall);
            let walls = w.insert_body(RigidBodyBuilder::fixed());
            for side in crate::drop_in::bin_walls(inner, wall, height) {
                w.insert_collider(side.friction(RAPIER_FRICTION), Some(walls));
            }
            // A grid of 8 × 8 per layer, 2.4 r apart, starting a radius above the floor.
            let per_row = 8;
            let spacing = 2.4 * r;
            let mut bodies = Vec::new();
            let mut random = crate::drop_in::xorshift(0x9e37_79b9_7f4a_7c15);
            for i in 0..spheres {
                let (layer, k) = (i / (per_row * per_row), i % (per_row * per_row));
                let x = ((k % per_row) as Real - 3.5) * spacing + 0.2 * r * (random() - 0.5);
                let z = ((k / per_row) as Real - 3.5) * spacing + 0.2 * r * (random() - 0.5);
                let y = 2.0 * r + layer as Real * spacing;
                let body =
                    w.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(x, y, z)));
                w.insert_collider(
                    ColliderBuilder::ball(r).density(2500.0).friction(RAPIER_FRICTION),
                    Some(body),
                );
                bodies.push(body);
            }
            Built { world: w, bodies, size: 2.0 * r, container: Some((inner, 2.0 * height)) }
        }
        Scene::Bin { bodies } => {
            let mut s = crate::drop_in::bin_scene(bodies);
            s.world.integration_parameters.length_unit = 2.0 * crate::drop_in::BODY_RADIUS;
            Built {
                world: s.world,
                bodies: s.bodies,
                size: 2.0 * crate::drop_in::BODY_RADIUS,
                container: Some((s.half_width, 1.0)),
            }
        }
    }
}

/// How a run of a scene ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// It stood (stacks) or settled in its box (pour, bin).
    Stands,
    /// A step was refused with this message.
    Refused(String),
    /// It ran, but a body moved off (how far, m) or the energy grew: what went wrong.
    Fails(String),
}

/// What one run measured.
#[derive(Clone, Debug)]
pub struct Run {
    /// How it ended.
    pub outcome: Outcome,
    /// Largest indentation (discrete) or penetration (rapier's own contacts) seen (m).
    pub max_indentation: Real,
    /// Kinetic energy at the end (J).
    pub kinetic_energy: Real,
    /// Sub-steps per step, on average (1 for rapier's own contacts).
    pub substeps_per_step: Real,
    /// Steps taken.
    pub steps: usize,
    /// The most the bodies' mechanical energy (kinetic and gravitational) rose above its value
    /// at the start, over the steps (J): a stack released at rest can only lose energy.
    pub energy_gain: Real,
    /// Wall time (s).
    pub wall: Real,
}

/// Kinetic energy of the dynamic bodies (J).
pub fn kinetic_energy(world: &PhysicsWorld) -> Real {
    world.bodies.iter().filter(|(_, rb)| rb.is_dynamic()).map(|(_, rb)| rb.kinetic_energy()).sum()
}

/// Largest penetration of rapier's own contact points (m).
fn rapier_penetration(world: &PhysicsWorld) -> Real {
    world
        .narrow_phase
        .contact_pairs()
        .flat_map(|p| p.manifolds().iter())
        .flat_map(|m| m.points.iter())
        .map(|p| -p.dist)
        .fold(0.0, Real::max)
}

/// The verdict on a finished run: stacks stand when every body stays within a tenth of the
/// bodies' size of where it started; a pour or bin settles when every body is inside its box
/// and the kinetic energy per body is below what a fall of a tenth of the size gives.
fn verdict(scene: Scene, built: &Built, start: &[Vector], world: &PhysicsWorld) -> Outcome {
    let mut worst: (Real, usize) = (0.0, 0);
    let mut lost = 0;
    for (i, &b) in built.bodies.iter().enumerate() {
        let Some(rb) = world.bodies.get(b) else { continue };
        let x = rb.translation();
        if !x.is_finite() {
            return Outcome::Fails(format!("body {i} at a non-finite position"));
        }
        let moved = (x - start[i]).length();
        if moved > worst.0 {
            worst = (moved, i);
        }
        if let Some((half, top)) = built.container {
            if x.x.abs() > half || x.z.abs() > half || x.y < -0.01 || x.y > top {
                lost += 1;
            }
        }
    }
    let ke = kinetic_energy(world);
    let masses: Real =
        built.bodies.iter().filter_map(|b| world.bodies.get(*b)).map(|rb| rb.mass()).sum();
    let settled_ke = masses * 9.81 * 0.1 * built.size;
    if scene.is_stack() {
        if worst.0 > 0.1 * built.size {
            return Outcome::Fails(format!("body {} moved {:.3} m", worst.1, worst.0));
        }
    } else if lost > 0 {
        return Outcome::Fails(format!("{lost} bodies left the box"));
    }
    if !(ke <= settled_ke) {
        return Outcome::Fails(format!("kinetic energy {ke:.3e} J at the end"));
    }
    Outcome::Stands
}

/// The discrete contact of the suite: sub-cell N_c = 4, restitution 0.5, μ_s = 0.6, μ_k = 0.5,
/// automatic sub-steps up to `max_substeps`.
pub fn discrete_contacts(max_substeps: usize) -> Result<DiscreteContacts> {
    Ok(DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell)?, 0.5)?
        .with_friction(Friction::new(0.6, 0.5, 1e-3)?)
        .with_policy(StepPolicy::AutoSubstep { max_substeps }))
}

/// Runs `scene` for `seconds` with rapier's own contacts.
pub fn run_rapier(scene: Scene, seconds: Real) -> Run {
    let mut built = build(scene);
    let start: Vec<Vector> =
        built.bodies.iter().map(|b| built.world.bodies[*b].translation()).collect();
    let steps = (seconds / built.world.integration_parameters.dt).round() as usize;
    let mut max_pen: Real = 0.0;
    let clock = Instant::now();
    for _ in 0..steps {
        built.world.step();
        max_pen = max_pen.max(rapier_penetration(&built.world));
    }
    let wall = clock.elapsed().as_secs_f64();
    let outcome = verdict(scene, &built, &start, &built.world);
    Run {
        outcome,
        max_indentation: max_pen,
        kinetic_energy: kinetic_energy(&built.world),
        substeps_per_step: 1.0,
        steps,
        energy_gain: 0.0,
        wall,
    }
}

/// The bodies' kinetic energy plus their potential energy in gravity (J).
pub fn mechanical_energy(world: &PhysicsWorld, bodies: &[RigidBodyHandle]) -> Real {
    bodies
        .iter()
        .filter_map(|b| world.bodies.get(*b))
        .map(|rb| rb.kinetic_energy() - rb.mass() * world.gravity.dot(rb.center_of_mass()))
        .sum()
}

/// Runs `scene` for `seconds` with the discrete contact `contacts` at Young's modulus `youngs`
/// (Pa, ν = 0.3) for every collider.
pub fn run_discrete(
    scene: Scene,
    seconds: Real,
    youngs: Real,
    contacts: DiscreteContacts,
    trace: bool,
) -> Result<Run> {
    run_built(scene, build(scene), seconds, youngs, contacts, trace)
}

/// [`run_discrete`] on a scene already built (rapier's `length_unit` chosen, say).
pub fn run_built(
    scene: Scene,
    mut built: Built,
    seconds: Real,
    youngs: Real,
    mut contacts: DiscreteContacts,
    trace: bool,
) -> Result<Run> {
    let start: Vec<Vector> =
        built.bodies.iter().map(|b| built.world.bodies[*b].translation()).collect();
    let steps = (seconds / built.world.integration_parameters.dt).round() as usize;
    contacts.handle_all(&mut built.world, Material::new(youngs, 0.3)?)?;
    let (mut max_ind, mut substeps): (Real, usize) = (0.0, 0);
    let start_energy = mechanical_energy(&built.world, &built.bodies);
    let mut energy_gain: Real = 0.0;
    let clock = Instant::now();
    let mut refused = None;
    let mut taken = 0;
    for _ in 0..steps {
        match contacts.step(&mut built.world) {
            Ok(stats) => {
                if trace {
                    println!(
                        "step {taken:>4}: sub-steps {:>5}, contacts {:>4} (implicit {:>5}, approaching {:>3}, islands {:>3}), d {:.3e} m, KE {:.3e} J",
                        stats.substeps,
                        stats.contacts,
                        stats.implicit_contacts,
                        stats.approaching_contacts,
                        stats.islands,
                        stats.max_indentation,
                        kinetic_energy(&built.world)
                    );
                }
                max_ind = max_ind.max(stats.max_indentation);
                substeps += stats.substeps;
                taken += 1;
                energy_gain =
                    energy_gain.max(mechanical_energy(&built.world, &built.bodies) - start_energy);
            }
            Err(e) => {
                refused = Some(e);
                break;
            }
        }
    }
    let wall = clock.elapsed().as_secs_f64();
    let outcome = match refused {
        Some(e) => Outcome::Refused(e.to_string()),
        None => verdict(scene, &built, &start, &built.world),
    };
    Ok(Run {
        outcome,
        max_indentation: max_ind,
        kinetic_energy: kinetic_energy(&built.world),
        substeps_per_step: substeps as Real / taken.max(1) as Real,
        steps: taken,
        energy_gain,
        wall,
    })
}
