//! Four-way coupling of rapier bodies with the bundled HLBM lattice (feature `fluid`).
//!
//! The bodies stay in the user's rapier [`PhysicsWorld`] — the one source of truth for their
//! poses and velocities, so the same scene and the same [`DiscreteContacts`] serve dry and wet
//! runs. One [`Fluid::step`] is Marquardt et al.'s Algorithm 2:
//!
//! 1. every coupled body is written onto the lattice from its SDF: the solid fraction
//!    `d_B = cos²(π/2 (d/ε + 1/2))` in the smoothing band of width `ε`, 1 inside, at each node
//!    it covers (solid wall nodes excepted), and its rigid motion once (the lattice takes the
//!    velocity `v + ω × (x − x_cm)` at a node from it);
//! 2. one lattice step with EDM forcing returns each body's hydrodynamic force and moment;
//! 3. that force, with buoyancy `−ρ_f V g`, is held on the body while rapier integrates one
//!    fluid step `Δt` — with contact sub-steps when a [`DiscreteContacts`] is given (the
//!    hydrodynamic force frozen over them, as in the paper).
//!
//! **The fluid inside a body.** HLBM forces the lattice nodes inside a body to the body's
//! velocity; the momentum that gives this inner fluid comes back as a reaction in the lattice
//! force. It is a numerical artefact (a rigid body carries no fluid), and at an impact it is
//! large: the inner fluid's mass (ρ_f/ρ_p of the body's) would be stopped and turned around
//! with the body and would eat about 2 ρ_f/ρ_p of the rebound. Wen et al.'s momentum exchange
//! (the default [`ForceMethod`]) measures only what crosses the body's outer surface and does
//! not see it. With [`ForceMethod::Forcing`] the coupling removes it as the lattice applies it:
//! per node `d_B (v_p,now − v_p,before)`, summed with the forces.
//!
//! **Contact candidates come from bounding spheres, not from the lattice.** The paper finds
//! a wet pair's rough box where two bodies write `d_B` on the same nodes. Those bands (±ε/2
//! around each surface) only meet when the gap is below ε, and a node must lie where they
//! meet; to catch every pair that can touch within a step (gap up to twice the contact
//! enlargement plus the step's travel, ~0.6 Δx in the settling runs) each body would have to
//! be mapped out to ~1.2 Δx beyond its surface — for a small sphere most of its mapped nodes
//! again, in a mapping that is already a large part of a step. Candidates therefore come from
//! rapier's broad phase or, in a periodic box, the bounding-sphere cell list of
//! [`DiscreteContacts::with_periodic`], which is cheap beside the step.
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

pub use hlbm::ForceMethod;
use hlbm::{solid_fraction, Lattice, ParticleBody, ParticleNode, UnitConverter};
use rapier3d_f64::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle};
use std::ops::Bound::{Excluded, Included};

use crate::error::{check_positive, Error, Result};
use crate::lubrication::Lubrication;
use crate::math::{Real, Vector};
use crate::periodic::PeriodicBox;
use crate::rapier::{DiscreteContacts, StepStats};
use crate::shape::{ConvexShape, Sdf};

mod virtual_mass;

/// The fluid's physical parameters and resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluidSettings {
    units: UnitConverter,
    smoothing: Real,
    force: ForceMethod,
    virtual_mass: Real,
}

impl FluidSettings {
    /// Lattice spacing `dx` (m), time step `dt` (s), kinematic viscosity `nu` (m²/s) and
    /// density `rho` (kg/m³); refuses a relaxation time `τ = 1/2 + 3 ν Δt/Δx² ≤ 1/2`. The
    /// smoothing width of `d_B` is one `dx` (change it with [`with_smoothing`](Self::with_smoothing)).
    pub fn new(dx: Real, dt: Real, nu: Real, rho: Real) -> Result<Self> {
        Ok(Self {
            units: UnitConverter::new(dx, dt, nu, rho)?,
            smoothing: dx,
            force: ForceMethod::default(),
            virtual_mass: 0.0,
        })
    }

    /// How the lattice measures the fluid's force on the bodies (see [`ForceMethod`]): Wen et
    /// al.'s link-wise momentum exchange (the default), which leaves the fluid inside a body out
    /// by construction, or the EDM forcing's own momentum with that inner fluid's share removed.
    pub fn with_force_method(mut self, method: ForceMethod) -> Self {
        self.force = method;
        self
    }

    /// With a smoothing width `eps` (m) of the solid fraction, `0 < eps <= 4 dx`.
    pub fn with_smoothing(mut self, eps: Real) -> Result<Self> {
        self.smoothing = crate::error::check_range(
            "smoothing",
            eps,
            (Excluded(0.0), Included(4.0 * self.units.dx())),
            "0 < eps <= 4 dx",
        )?;
        Ok(self)
    }

    /// With a virtual mass `C_V ρ_f V` lent to every coupled body over each fluid step,
    /// `0 <= c <= 4`; 0 (none) by default. A contact that turns a body round within a few fluid
    /// steps then turns the liquid's added mass with it, as in a liquid, instead of leaving the
    /// lattice — whose pressure travels at its sound speed — to take that momentum from the
    /// rebound over the steps after it; the momentum lent comes back over the time the
    /// lattice's own reaction takes, so where the motion is smooth on that time the two cancel.
    /// A point mass at the centre of mass: no rotational added mass. See
    /// [`lent_momentum`](Fluid::lent_momentum).
    pub fn with_virtual_mass(mut self, c: Real) -> Result<Self> {
        self.virtual_mass = crate::error::check_range(
            "virtual mass coefficient",
            c,
            (Included(0.0), Included(4.0)),
            "0 <= c <= 4",
        )?;
        Ok(self)
    }

    /// The unit converter (Δx, Δt, ν, ρ, τ).
    pub fn units(&self) -> &UnitConverter {
        &self.units
    }

    /// The liquid film's force for gaps this lattice does not resolve, for
    /// [`DiscreteContacts::with_lubrication`]: the fluid's dynamic viscosity, cut off at
    /// [`FILM_CUTOFF`] `Δx`, the gap held at `min_gap` (m; `0 < min_gap <` the cut-off).
    pub fn lubrication(&self, min_gap: Real) -> Result<Lubrication> {
        Lubrication::new(
            self.units.viscosity() * self.units.density(),
            FILM_CUTOFF * self.units.dx(),
            min_gap,
        )
    }
}

/// The gap, in lattice spacings, below which [`FluidSettings::lubrication`] adds the film's
/// force: the lattice's own force on a sphere closing in on a wall stops growing once the gap
/// falls below about a spacing, at about Brenner's leading-order force at 1.2 spacings — the
/// same in spacings at 6, 10 and 16 nodes per diameter (measured, `docs/wet.md`). Below it the
/// film adds Brenner's force less its value here, so lattice and film together follow
/// Brenner's.
pub const FILM_CUTOFF: Real = 1.2;

/// A body the fluid sees.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
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
    /// The momentum the virtual mass took from the body and has not yet returned (kg m/s).
    #[cfg_attr(feature = "checkpoint", serde(default))]
    lent_momentum: Vector,
}

/// A body as one mapping sees it.
struct MappedBody<'a> {
    id: usize,
    shape: &'a ConvexShape,
    inverse: crate::math::Pose,
    com: Vector,
    v: Vector,
    w: Vector,
    /// Velocities and centre the inner fluid was forced to last step.
    previous: (Vector, Vector, Vector),
    /// Node index ranges (unwrapped across periodic faces).
    ranges: [(i64, i64); 3],
    /// Whole box lengths (in nodes) that bring the ranges' start into the lattice: relative to
    /// it every node lies on image 0 or 1, whichever box the body has drifted to.
    base: [i64; 3],
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
    /// Wall-clock seconds spent writing the bodies onto the lattice, in the lattice step, and
    /// in the bodies' step (rapier, contacts and their sub-steps).
    pub seconds: StepSeconds,
}

/// Where one fluid step's wall-clock time went (s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct StepSeconds {
    /// Writing bodies onto the lattice (`d_B`, node velocities).
    pub mapping: Real,
    /// The lattice step (collision, streaming, forcing, momentum exchange).
    pub lattice: Real,
    /// Rapier's step with the contacts (candidates, overlap, forces, sub-steps).
    pub bodies: Real,
}

/// A lattice Boltzmann fluid filling a box, coupled to bodies of a rapier world.
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Fluid {
    lattice: Lattice,
    units: UnitConverter,
    smoothing: Real,
    /// The virtual mass coefficient `C_V` ([`FluidSettings::with_virtual_mass`]).
    #[cfg_attr(feature = "checkpoint", serde(default))]
    virtual_mass: Real,
    /// Physical position of node (0, 0, 0).
    origin: Vector,
    /// The fluid's box, rounded to whole cells, with its periodic axes.
    domain: PeriodicBox,
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
    pub fn new(
        min: Vector,
        max: Vector,
        periodic: [bool; 3],
        settings: FluidSettings,
    ) -> Result<Self> {
        crate::error::check_finite_vec("fluid box min", min)?;
        crate::error::check_finite_vec("fluid box max", max)?;
        let dx = settings.units.dx();
        let size = max - min;
        let mut dims = [0usize; 3];
        let mut origin = Vector::ZERO;
        let mut rounded = max;
        for d in 0..3 {
            check_positive("fluid box size (max - min)", size[d])?;
            let cells = (size[d] / dx).round().max(1.0) as usize;
            rounded[d] = min[d] + cells as Real * dx;
            // Periodic: cell centres at min + (i + 1/2) dx. Walled: solid layers 0 and n - 1,
            // the halfway walls half a cell inside them, on the box faces.
            (dims[d], origin[d]) = if periodic[d] {
                (cells, min[d] + 0.5 * dx)
            } else {
                (cells + 2, min[d] - 0.5 * dx)
            };
        }
        let mut lattice = Lattice::new(dims[0], dims[1], dims[2], settings.units.tau())?;
        lattice.close_faces(periodic);
        lattice.set_force_method(settings.force);
        let domain = PeriodicBox::new(min, rounded, periodic)?;
        Ok(Self {
            lattice,
            units: settings.units,
            smoothing: settings.smoothing,
            virtual_mass: settings.virtual_mass,
            origin,
            domain,
            bodies: Vec::new(),
        })
    }

    /// Couples the body of `collider` (a dynamic body with a bounded convex shape) to the fluid.
    pub fn couple(&mut self, world: &PhysicsWorld, collider: ColliderHandle) -> Result<()> {
        let bad = |allowed| Error::InvalidArgument { name: "collider", allowed };
        let co =
            world.colliders.get(collider).ok_or(bad("a handle of a collider in this world"))?;
        let body = co.parent().filter(|&h| world.bodies.get(h).is_some_and(|rb| rb.is_dynamic()));
        let body = body.ok_or(bad("a collider attached to a dynamic rigid body"))?;
        let shape = ConvexShape::from_parry(co.shape())?;
        if shape.is_unbounded() {
            return Err(bad("a bounded shape (walls of the fluid are lattice walls)"));
        }
        let volume = co.shape().mass_properties(1.0).mass();
        let z = Vector::ZERO;
        self.bodies.push(Coupled {
            collider,
            body,
            shape,
            volume,
            previous: (z, z, z),
            force: z,
            torque: z,
            lent_momentum: z,
        });
        Ok(())
    }

    /// One fluid step `Δt`: bodies onto the lattice, one lattice step, hydrodynamic forces and
    /// buoyancy onto the bodies, and rapier's step of `Δt` — through `contacts` (with contact
    /// sub-steps) when given, else `world.step()`. Sets `world.integration_parameters.dt` to
    /// the fluid's `Δt`.
    ///
    /// With a virtual mass ([`FluidSettings::with_virtual_mass`]) each body carries it over the
    /// step (rapier's mass properties and gravity scale are given back after it).
    ///
    /// Fails with the lattice's [`hlbm::Error::Unstable`] (step and node) when the fluid blows
    /// up, with the contacts' errors, and before anything moves with
    /// [`Error::InvalidArgument`] for a body with a virtual mass whose additional mass was set
    /// as a bare mass (`set_additional_mass`) rather than as mass properties.
    pub fn step(
        &mut self,
        world: &mut PhysicsWorld,
        contacts: Option<&mut DiscreteContacts>,
    ) -> Result<FluidStepReport> {
        if let Some(c) = &contacts {
            if c.periodic() != self.periodic_box().as_ref() {
                return Err(Error::InvalidArgument {
                    name: "periodic box of the contacts",
                    allowed: "the fluid's own: DiscreteContacts::with_periodic(fluid.periodic_box()) when the fluid is periodic, none when it is not",
                });
            }
        }
        if self.virtual_mass > 0.0 {
            for b in &self.bodies {
                virtual_mass::check(world, b.body)?;
            }
        }
        let mut report = FluidStepReport::default();
        let clock = std::time::Instant::now();
        let corrections = self.map_bodies(world, &mut report)?;
        report.seconds.mapping = clock.elapsed().as_secs_f64();
        let lattice = self.lattice.step()?;
        report.seconds.lattice = clock.elapsed().as_secs_f64() - report.seconds.mapping;
        report.max_fluid_speed = self.units.velocity_to_physical(lattice.max_velocity);
        // Hydrodynamic force plus buoyancy −ρ_f V g, held on each body over the step.
        let buoyancy = -self.units.density() * world.gravity;
        let mut applied = Vec::with_capacity(self.bodies.len());
        let mut lent = Vec::new();
        let dt = self.units.dt();
        for (id, (b, (cf, cm))) in self.bodies.iter_mut().zip(corrections).enumerate() {
            let pf = lattice.particle_forces.get(&(id as u32)).copied().unwrap_or_default();
            let f = Vector::from(pf.force) + cf;
            let m = Vector::from(pf.moment) + cm;
            b.force = f * self.units.force_to_physical(1.0);
            b.torque = m * self.units.torque_to_physical(1.0);
            if world.bodies.get(b.body).is_none() {
                continue;
            }
            let m_v = self.virtual_mass * self.units.density() * b.volume;
            let mut total = b.force + b.volume * buoyancy;
            if m_v > 0.0 {
                let returned =
                    b.lent_momentum * virtual_mass::returned_share(b.volume, self.units.dx(), dt);
                lent.push((id, m_v, returned, virtual_mass::lend(world, b.body, m_v)));
                total += returned / dt;
            }
            let rb = &mut world.bodies[b.body];
            applied.push((b.body, rb.user_force(), rb.user_torque()));
            rb.add_force(total, true);
            rb.add_torque(b.torque, true);
        }
        world.integration_parameters.dt = dt;
        let result = match contacts {
            Some(c) => c.step(world).map(Some),
            None => {
                world.step();
                Ok(None)
            }
        };
        crate::rapier::take_back(world, &applied);
        for (id, m_v, returned, l) in lent {
            let dv = virtual_mass::give_back(world, l);
            self.bodies[id].lent_momentum += m_v * dv - returned;
        }
        report.seconds.bodies =
            clock.elapsed().as_secs_f64() - report.seconds.mapping - report.seconds.lattice;
        report.contacts = result?;
        Ok(report)
    }

    /// Writes every coupled body onto the lattice; returns per body the inner-fluid correction
    /// (force, moment about the centre of mass; lattice units).
    ///
    /// Slab by slab on all cores: each z-slab evaluates the SDFs of the bodies that reach into
    /// it; the corrections are summed per body in slab order (thread-count independent).
    fn map_bodies(
        &mut self,
        world: &PhysicsWorld,
        report: &mut FluidStepReport,
    ) -> Result<Vec<(Vector, Vector)>> {
        let dx = self.units.dx();
        let dims = self.lattice.dims();
        let to_lattice = self.units.velocity_to_lattice(1.0);
        let half = 0.5 * self.smoothing;
        let periodic = self.domain.periodic();
        let mut placed = Vec::with_capacity(self.bodies.len());
        let mut fastest: Real = 0.0;
        // Which bodies reach into each slab, and as which unwrapped layer k.
        let mut by_slab: Vec<Vec<(usize, i64)>> = vec![Vec::new(); dims[2]];
        for (id, b) in self.bodies.iter_mut().enumerate() {
            let (Some(rb), Some(co)) = (world.bodies.get(b.body), world.colliders.get(b.collider))
            else {
                continue;
            };
            let (pose, com, v, w) = (*co.position(), rb.center_of_mass(), rb.linvel(), rb.angvel());
            crate::error::check_finite_vec("coupled body velocity", v)?;
            crate::error::check_finite_vec("coupled body angular velocity", w)?;
            let aabb = co.compute_aabb();
            fastest = fastest.max(v.length() + w.length() * 0.5 * (aabb.maxs - aabb.mins).length());
            let range = |d: usize| -> (i64, i64) {
                let lo = ((aabb.mins[d] - half - self.origin[d]) / dx).ceil() as i64;
                let hi = ((aabb.maxs[d] + half - self.origin[d]) / dx).floor() as i64;
                if periodic[d] {
                    (lo, hi.min(lo + dims[d] as i64 - 1))
                } else {
                    (lo.max(0), hi.min(dims[d] as i64 - 1))
                }
            };
            let ranges = [range(0), range(1), range(2)];
            for k in ranges[2].0..=ranges[2].1 {
                by_slab[k.rem_euclid(dims[2] as i64) as usize].push((placed.len(), k));
            }
            let base = [0, 1, 2].map(|d| ranges[d].0.div_euclid(dims[d] as i64) * dims[d] as i64);
            placed.push(MappedBody {
                id,
                shape: &b.shape,
                inverse: pose.inverse(),
                com,
                v,
                w,
                previous: b.previous,
                ranges,
                base,
            });
            b.previous = (v, w, com);
        }
        // Each slab's bodies from low x to high, so that a row gets its nodes in order unless
        // two bodies' nodes interleave in it (or one wraps round the x face), and the field
        // sorts only those rows.
        for slab in &mut by_slab {
            slab.sort_by_key(|&(i, _)| (placed[i].ranges[0].0, i));
        }
        // Each body's rigid motion once (lattice units); the nodes name it by its index here.
        let dt = self.units.dt();
        let motions = placed
            .iter()
            .map(|b| ParticleBody {
                id: b.id as u32,
                centre: ((b.com - self.origin) / dx
                    - Vector::from_array(b.base.map(|n| n as Real)))
                .to_array(),
                velocity: (b.v * to_lattice).to_array(),
                spin: (b.w * dt).to_array(),
            })
            .collect();
        let mut field = std::mem::take(self.lattice.particles_mut());
        let (origin, smoothing, lattice) = (self.origin, self.smoothing, &self.lattice);
        let inner_fluid = lattice.force_method() == ForceMethod::Forcing;
        // A fully periodic box without walls need not look up every node's kind.
        let walls = lattice.has_solid();
        let wrap = |i: i64, d: usize| i.rem_euclid(dims[d] as i64) as usize;
        // The periodic image of unwrapped node index `i` (relative to the body's base).
        let image = |i: i64, d: usize| -> i8 {
            if i < 0 {
                -1
            } else if i >= dims[d] as i64 {
                1
            } else {
                0
            }
        };
        let partial = field.fill_slabs(motions, |z, rows| {
            let mut sums: Vec<(usize, Vector, Vector)> = Vec::new();
            for &(body, k) in &by_slab[z] {
                let b = &placed[body];
                let (v0, w0, c0) = b.previous;
                let (mut cf, mut cm) = (Vector::ZERO, Vector::ZERO);
                // The row's first node wrapped once; the rest at most once more (a range spans
                // at most the lattice): no integer division per node.
                let (lo, x_lo) = (b.ranges[0].0, wrap(b.ranges[0].0, 0));
                // Along a row the body-frame position steps by the rotated Δx: the pose's
                // transform once per row, not per node.
                let step = b.inverse.rotation * Vector::new(dx, 0.0, 0.0);
                for j in b.ranges[1].0..=b.ranges[1].1 {
                    let y = wrap(j, 1);
                    let (image_y, image_z) = (image(j - b.base[1], 1), image(k - b.base[2], 2));
                    let first =
                        b.inverse * (origin + Vector::new(lo as Real, j as Real, k as Real) * dx);
                    for i in lo..=b.ranges[0].1 {
                        let d_b = solid_fraction(
                            b.shape.distance(first + step * (i - lo) as Real),
                            smoothing,
                        );
                        let x = x_lo + (i - lo) as usize;
                        let x = if x >= dims[0] { x - dims[0] } else { x };
                        if d_b <= 0.0 || walls && lattice.is_solid(lattice.index(x, y, z)) {
                            continue;
                        }
                        rows.push(
                            y,
                            ParticleNode::new(
                                x,
                                body,
                                [image(i - b.base[0], 0), image_y, image_z],
                                d_b,
                            ),
                        );
                        // The inner fluid's momentum change, removed from the lattice's force.
                        if inner_fluid {
                            let p = origin + Vector::new(i as Real, j as Real, k as Real) * dx;
                            let vel = (b.v + b.w.cross(p - b.com)) * to_lattice;
                            let arm = (p - b.com) / dx;
                            let before = (v0 + w0.cross(p - c0)) * to_lattice;
                            let dm = (vel - before) * d_b;
                            cf += dm;
                            cm += arm.cross(dm);
                        }
                    }
                }
                sums.push((b.id, cf, cm));
            }
            sums
        });
        *self.lattice.particles_mut() = field;
        let partial = partial?;
        let mut corrections = vec![(Vector::ZERO, Vector::ZERO); self.bodies.len()];
        for (id, cf, cm) in partial.into_iter().flatten() {
            corrections[id].0 += cf;
            corrections[id].1 += cm;
        }
        report.particle_nodes = self.lattice.particles().len();
        report.mach_warning = self.units.mach_warning(fastest);
        Ok(corrections)
    }

    /// The fluid's box (rounded to whole cells) when it is periodic along some axis: give it
    /// to [`DiscreteContacts::with_periodic`] so bodies and contacts wrap as the fluid does.
    pub fn periodic_box(&self) -> Option<PeriodicBox> {
        self.domain.is_periodic().then_some(self.domain)
    }

    /// Balances the suspension's weight: in a box periodic along gravity nothing holds the
    /// bodies' net weight `W = Σ (m − ρ_f V) g`, and the whole suspension would accelerate. This
    /// sets the fluid's body acceleration to `a = −W / (ρ_f V_box)` — a uniform pressure
    /// gradient, whose part on the nodes a body covers reaches the body through the coupling
    /// (with either force measure) — so the total momentum of fluid and bodies stays constant
    /// (tested: a sphere in a periodic box settles at a constant speed, as the Stokes cubic
    /// array). With the momentum exchange, fast bodies still leak a little: the nodes a moving
    /// body newly covers are turned to its velocity without the body paying for it (the
    /// `hindered_settling` example reports this momentum imbalance).
    /// Call it after coupling the bodies; returns `a` (m/s²).
    pub fn balance_weight(&mut self, world: &PhysicsWorld) -> Result<Vector> {
        let rho = self.units.density();
        let mut weight = Vector::ZERO;
        for b in &self.bodies {
            if let Some(co) = world.colliders.get(b.collider) {
                weight += (co.mass() - rho * b.volume) * world.gravity;
            }
        }
        let [nx, ny, nz] = self.lattice.dims();
        let periodic = self.domain.periodic();
        let fluid_cells = [nx, ny, nz]
            .iter()
            .zip(periodic)
            .map(|(&n, p)| (if p { n } else { n - 2 }) as Real)
            .product::<Real>();
        let a = -weight / (rho * fluid_cells * self.units.dx().powi(3));
        crate::error::check_finite_vec("balance acceleration", a)?;
        self.lattice
            .set_body_acceleration(a.to_array().map(|c| self.units.acceleration_to_lattice(c)));
        Ok(a)
    }

    /// Mass-weighted mean velocity of the lattice's fluid nodes (m/s), the nodes inside bodies
    /// included (they move with the bodies). A sweep over the whole lattice: call it every few
    /// steps, not every step.
    pub fn mean_velocity(&self) -> Vector {
        let (m, p) = self.lattice.totals();
        Vector::from_array(p.map(|c| self.units.velocity_to_physical(c / m)))
    }

    /// Hydrodynamic force and torque (about the centre of mass) on the body of `collider` in
    /// the last step, without buoyancy (N, N m).
    pub fn hydrodynamic_force(&self, collider: ColliderHandle) -> Option<(Vector, Vector)> {
        self.bodies.iter().find(|b| b.collider == collider).map(|b| (b.force, b.torque))
    }

    /// The momentum the virtual mass ([`FluidSettings::with_virtual_mass`]) has taken from the
    /// body of `collider` and not yet returned (kg m/s): its momentum `m v` is the impulse of
    /// every force on it since it was coupled, less this.
    pub fn lent_momentum(&self, collider: ColliderHandle) -> Option<Vector> {
        self.bodies.iter().find(|b| b.collider == collider).map(|b| b.lent_momentum)
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
        crate::io::write_atomically(path, |w| {
            hlbm::vtk::write_to(
                w,
                &self.lattice,
                self.units.dx(),
                self.units.velocity_to_physical(1.0),
            )
        })
    }
}
