//! Four-way coupling of rapier bodies with the bundled HLBM lattice (feature `fluid`).
//!
//! The bodies stay in the user's rapier [`PhysicsWorld`] — the one source of truth for their
//! poses and velocities, so the same scene and the same [`DiscreteContacts`] serve dry and wet
//! runs. One [`Fluid::step`] is seed 000's Algorithm 2:
//!
//! 1. every coupled body is written onto the lattice from its SDF: the solid fraction
//!    `d_B = cos²(π (d/ε + 1/2))` in the smoothing band of width `ε`, 1 inside, and the body's
//!    velocity `v + ω × (x − x_cm)` at each node it covers (solid wall nodes excepted);
//! 2. one lattice step with EDM forcing returns each body's hydrodynamic force and moment;
//! 3. that force, with buoyancy `−ρ_f V g`, is held on the body while rapier integrates one
//!    fluid step `Δt` — with contact sub-steps when a [`DiscreteContacts`] is given (the
//!    hydrodynamic force frozen over them, as in the paper).
//!
//! **The fluid inside a body.** HLBM forces the lattice nodes inside a body to the body's
//! velocity; the momentum that gives this inner fluid comes back as a reaction in the lattice
//! force. It is a numerical artefact (a rigid body carries no fluid), and at an impact it is
//! large: the inner fluid's mass (ρ_f/ρ_p of the body's) would be stopped and turned around
//! with the body and would eat about 2 ρ_f/ρ_p of the rebound. The coupling removes it exactly as
//! the lattice applies it: per node `d_B (v_p,now − v_p,before)`, summed with the forces.
//!
//! ```
//! use discrete_contact::coupling::{Fluid, FluidSettings};
//! use discrete_contact::rapier3d_f64::prelude::*;
//! use discrete_contact::math::Vector;
//! let mut world = PhysicsWorld::new();
//! world.gravity = Vector::new(0.0, 0.0, -9.81);
//! let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.0, 0.0)));
//! let ball = world.insert_collider(ColliderBuilder::ball(2e-3).density(2500.0), Some(ball));
//! // Water in a closed 16 mm box, Δx = 1 mm, Δt = 0.2 ms.
//! let settings = FluidSettings::new(1e-3, 2e-4, 1e-6, 1000.0)?;
//! let mut fluid = Fluid::closed_box(Vector::splat(-8e-3), Vector::splat(8e-3), settings)?;
//! fluid.couple(&world, ball)?;
//! for _ in 0..20 {
//!     fluid.step(&mut world, None)?;
//! }
//! let rb = &world.bodies[world.colliders[ball].parent().unwrap()];
//! assert!(rb.linvel().z < 0.0);                        // sinking…
//! assert!(rb.linvel().z > -20.0 * 2e-4 * 9.81);         // …slower than in vacuum
//! # Ok::<(), discrete_contact::Error>(())
//! ```

use hlbm::{solid_fraction, Lattice, UnitConverter};
use rapier3d_f64::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle};

use crate::error::{check_positive, Error, Result};
use crate::math::{Real, Vector};
use crate::rapier::{DiscreteContacts, StepStats};
use crate::shape::{ConvexShape, Sdf};

/// The fluid's physical parameters and resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluidSettings {
    units: UnitConverter,
    smoothing: Real,
}

impl FluidSettings {
    /// Lattice spacing `dx` (m), time step `dt` (s), kinematic viscosity `nu` (m²/s) and
    /// density `rho` (kg/m³); refuses a relaxation time `τ = 1/2 + 3 ν Δt/Δx² ≤ 1/2`. The
    /// smoothing width of `d_B` is one `dx` (change it with [`with_smoothing`](Self::with_smoothing)).
    pub fn new(dx: Real, dt: Real, nu: Real, rho: Real) -> Result<Self> {
        Ok(Self { units: UnitConverter::new(dx, dt, nu, rho)?, smoothing: dx })
    }

    /// With a smoothing width `eps` (m) of the solid fraction, `0 < eps <= 4 dx`.
    pub fn with_smoothing(mut self, eps: Real) -> Result<Self> {
        self.smoothing = crate::error::check_range("smoothing", eps, 0.0, false, 4.0 * self.units.dx(), true, "0 < eps <= 4 dx")?;
        Ok(self)
    }

    /// The unit converter (Δx, Δt, ν, ρ, τ).
    pub fn units(&self) -> &UnitConverter {
        &self.units
    }
}

/// A body the fluid sees.
#[derive(Clone, Debug)]
struct Coupled {
    collider: ColliderHandle,
    body: RigidBodyHandle,
    shape: ConvexShape,
    /// Physical volume (m³), for buoyancy.
    volume: Real,
    /// Linear and angular velocity and centre of mass at the last mapping: the velocity the
    /// inner fluid was forced to (zero before the first step, the fluid's initial state).
    previous: (Vector, Vector, Vector),
    /// Hydrodynamic force and torque (about the centre of mass) of the last step (N, N m).
    force: Vector,
    torque: Vector,
}

/// What one fluid step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FluidStepReport {
    /// The contact sub-steps, when contacts were given.
    pub contacts: Option<StepStats>,
    /// Largest fluid speed (m/s).
    pub max_fluid_speed: Real,
    /// Lattice nodes covered by a body this step.
    pub particle_nodes: usize,
    /// Set when a body moves faster than the lattice's Mach limit allows (the message says by
    /// how much and what to change).
    pub mach_warning: Option<String>,
}

/// A lattice Boltzmann fluid filling a box, coupled to bodies of a rapier world.
pub struct Fluid {
    lattice: Lattice,
    units: UnitConverter,
    smoothing: Real,
    /// Physical position of node (0, 0, 0).
    origin: Vector,
    periodic: [bool; 3],
    bodies: Vec<Coupled>,
}

impl Fluid {
    /// Fluid at rest filling the box `[min, max]` (m), closed by resting walls on every face
    /// (halfway bounce-back: the walls lie exactly on the box faces when the box is a whole
    /// number of `dx`; otherwise the box is rounded to the nearest one).
    pub fn closed_box(min: Vector, max: Vector, settings: FluidSettings) -> Result<Self> {
        Self::new(min, max, [false; 3], settings)
    }

    /// Fluid at rest filling `[min, max]`, periodic along the axes marked `true` and closed by
    /// resting walls on the faces of the others.
    pub fn new(min: Vector, max: Vector, periodic: [bool; 3], settings: FluidSettings) -> Result<Self> {
        crate::error::check_finite_vec("fluid box min", min)?;
        crate::error::check_finite_vec("fluid box max", max)?;
        let dx = settings.units.dx();
        let size = max - min;
        let mut dims = [0usize; 3];
        let mut origin = Vector::ZERO;
        for d in 0..3 {
            check_positive("fluid box size (max - min)", size[d])?;
            let cells = (size[d] / dx).round().max(1.0) as usize;
            // Periodic: cell centres at min + (i + 1/2) dx. Walled: solid layers 0 and n - 1,
            // the halfway walls half a cell inside them, on the box faces.
            (dims[d], origin[d]) = if periodic[d] { (cells, min[d] + 0.5 * dx) } else { (cells + 2, min[d] - 0.5 * dx) };
        }
        let mut lattice = Lattice::new(dims[0], dims[1], dims[2], settings.units.tau())?;
        lattice.close_faces(periodic);
        Ok(Self { lattice, units: settings.units, smoothing: settings.smoothing, origin, periodic, bodies: Vec::new() })
    }

    /// Couples the body of `collider` (a dynamic body with a bounded convex shape) to the fluid.
    pub fn couple(&mut self, world: &PhysicsWorld, collider: ColliderHandle) -> Result<()> {
        let bad = |allowed| Error::InvalidParameter { name: "collider", value: Real::NAN, allowed };
        let co = world.colliders.get(collider).ok_or(bad("a handle of a collider in this world"))?;
        let body = co.parent().filter(|&h| world.bodies.get(h).is_some_and(|rb| rb.is_dynamic()));
        let body = body.ok_or(bad("a collider attached to a dynamic rigid body"))?;
        let shape = ConvexShape::from_parry(co.shape())?;
        if shape.is_unbounded() {
            return Err(bad("a bounded shape (walls of the fluid are lattice walls)"));
        }
        let volume = co.shape().mass_properties(1.0).mass();
        let z = Vector::ZERO;
        self.bodies.push(Coupled { collider, body, shape, volume, previous: (z, z, z), force: z, torque: z });
        Ok(())
    }

    /// One fluid step `Δt`: bodies onto the lattice, one lattice step, hydrodynamic forces and
    /// buoyancy onto the bodies, and rapier's step of `Δt` — through `contacts` (with contact
    /// sub-steps) when given, else `world.step()`. Sets `world.integration_parameters.dt` to
    /// the fluid's `Δt`.
    ///
    /// Fails with the lattice's [`hlbm::Error::Unstable`] (step and node) when the fluid blows
    /// up, and with the contacts' errors.
    pub fn step(&mut self, world: &mut PhysicsWorld, contacts: Option<&mut DiscreteContacts>) -> Result<FluidStepReport> {
        let mut report = FluidStepReport::default();
        let corrections = self.map_bodies(world, &mut report)?;
        let lattice = self.lattice.step()?;
        report.max_fluid_speed = self.units.velocity_to_physical(lattice.max_velocity);
        // Hydrodynamic force plus buoyancy −ρ_f V g, held on each body over the step.
        let buoyancy = -self.units.density() * world.gravity;
        let mut applied = Vec::with_capacity(self.bodies.len());
        for (id, (b, (cf, cm))) in self.bodies.iter_mut().zip(corrections).enumerate() {
            let pf = lattice.particle_forces.get(&(id as u32)).copied().unwrap_or_default();
            let centre = (b.previous.2 - self.origin) / self.units.dx();
            let f = Vector::from(pf.force) + cf;
            let m = Vector::from(pf.moment) - centre.cross(Vector::from(pf.force)) + cm;
            b.force = f * self.units.force_to_physical(1.0);
            b.torque = m * self.units.torque_to_physical(1.0);
            if let Some(rb) = world.bodies.get_mut(b.body) {
                let total = b.force + b.volume * buoyancy;
                rb.add_force(total, true);
                rb.add_torque(b.torque, true);
                applied.push((b.body, total, b.torque));
            }
        }
        world.integration_parameters.dt = self.units.dt();
        let result = match contacts {
            Some(c) => c.step(world).map(Some),
            None => {
                world.step();
                Ok(None)
            }
        };
        crate::rapier::take_back(world, &applied);
        report.contacts = result?;
        Ok(report)
    }

    /// Writes every coupled body onto the lattice; returns per body the inner-fluid correction
    /// (force, moment about the centre of mass; lattice units).
    fn map_bodies(&mut self, world: &PhysicsWorld, report: &mut FluidStepReport) -> Result<Vec<(Vector, Vector)>> {
        let dx = self.units.dx();
        let dims = self.lattice.dims();
        let to_lattice = self.units.velocity_to_lattice(1.0);
        let half = 0.5 * self.smoothing;
        self.lattice.particles.clear();
        let mut corrections = Vec::with_capacity(self.bodies.len());
        let mut fastest: Real = 0.0;
        for (id, b) in self.bodies.iter_mut().enumerate() {
            let (Some(rb), Some(co)) = (world.bodies.get(b.body), world.colliders.get(b.collider)) else {
                corrections.push((Vector::ZERO, Vector::ZERO));
                continue;
            };
            let (pose, com, v, w) = (*co.position(), rb.center_of_mass(), rb.linvel(), rb.angvel());
            crate::error::check_finite_vec("coupled body velocity", v)?;
            crate::error::check_finite_vec("coupled body angular velocity", w)?;
            let (v0, w0, c0) = b.previous;
            let aabb = co.compute_aabb();
            fastest = fastest.max(v.length() + w.length() * 0.5 * (aabb.maxs - aabb.mins).length());
            let range = |d: usize| -> (i64, i64) {
                let lo = ((aabb.mins[d] - half - self.origin[d]) / dx).ceil() as i64;
                let hi = ((aabb.maxs[d] + half - self.origin[d]) / dx).floor() as i64;
                if self.periodic[d] {
                    (lo, hi.min(lo + dims[d] as i64 - 1))
                } else {
                    (lo.max(0), hi.min(dims[d] as i64 - 1))
                }
            };
            let (rx, ry, rz) = (range(0), range(1), range(2));
            let wrap = |i: i64, d: usize| i.rem_euclid(dims[d] as i64) as usize;
            let (mut cf, mut cm) = (Vector::ZERO, Vector::ZERO);
            let inverse = pose.inverse();
            for k in rz.0..=rz.1 {
                for j in ry.0..=ry.1 {
                    for i in rx.0..=rx.1 {
                        let p = self.origin + Vector::new(i as Real, j as Real, k as Real) * dx;
                        let d_b = solid_fraction(b.shape.distance(inverse * p), self.smoothing);
                        let (x, y, z) = (wrap(i, 0), wrap(j, 1), wrap(k, 2));
                        if d_b <= 0.0 || self.lattice.is_solid(self.lattice.index(x, y, z)) {
                            continue;
                        }
                        let vel = (v + w.cross(p - com)) * to_lattice;
                        self.lattice.particles.add(x, y, z, d_b, vel.to_array(), id as u32);
                        let before = (v0 + w0.cross(p - c0)) * to_lattice;
                        let dm = (vel - before) * d_b;
                        cf += dm;
                        cm += ((p - com) / dx).cross(dm);
                    }
                }
            }
            b.previous = (v, w, com);
            corrections.push((cf, cm));
        }
        report.particle_nodes = self.lattice.particles.len();
        report.mach_warning = self.units.mach_warning(fastest);
        Ok(corrections)
    }

    /// Hydrodynamic force and torque (about the centre of mass) on the body of `collider` in
    /// the last step, without buoyancy (N, N m).
    pub fn hydrodynamic_force(&self, collider: ColliderHandle) -> Option<(Vector, Vector)> {
        self.bodies.iter().find(|b| b.collider == collider).map(|b| (b.force, b.torque))
    }

    /// The lattice (read access: fields, populations, dimensions).
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// The lattice, for what this type does not wrap (extra walls, a body force, initial
    /// fields); lattice units.
    pub fn lattice_mut(&mut self) -> &mut Lattice {
        &mut self.lattice
    }

    /// The unit converter.
    pub fn units(&self) -> &UnitConverter {
        &self.units
    }

    /// Physical position (m) of lattice node `(0, 0, 0)`; node `(i, j, k)` lies at
    /// `origin + (i, j, k) Δx`.
    pub fn origin(&self) -> Vector {
        self.origin
    }

    /// Fluid steps taken.
    pub fn steps(&self) -> u64 {
        self.lattice.time()
    }

    /// Writes density, velocity and `d_B` as legacy VTK for ParaView (atomically).
    pub fn write_vtk(&self, path: &std::path::Path) -> Result<()> {
        Ok(hlbm::vtk::write(&self.lattice, path, self.units.dx(), self.units.velocity_to_physical(1.0))?)
    }
}
