//! A sphere released in a viscous liquid, falling onto the floor of a closed box and bouncing
//! (Marquardt et al. §5, the experiment of Li 2010), four-way coupled: rapier bodies, the
//! HLBM fluid and the discrete contact in one step.
//!
//! [`WetRebound::li_2010`] holds the experiment's values; every field can be changed, so other
//! immersed-collision experiments run through the same code.

use std::time::Instant;

use discrete_contact::rapier3d_f64::prelude::{
    ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle, SharedShape,
};

use discrete_contact::coupling::{Fluid, FluidSettings, ForceMethod, FILM_CUTOFF};
use discrete_contact::error::Result;
use discrete_contact::lubrication::Lubrication;
use discrete_contact::material::Material;
use discrete_contact::math::{Real, Vector};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};

/// One immersed sphere–wall collision experiment (SI units).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WetRebound {
    /// Sphere radius (m).
    pub radius: Real,
    /// Sphere density (kg/m³).
    pub particle_density: Real,
    /// Fluid density (kg/m³).
    pub fluid_density: Real,
    /// Dynamic viscosity (Pa s).
    pub viscosity: Real,
    /// Release gap between the sphere's surface and the floor (m).
    pub release_gap: Real,
    /// Closed box, from the origin to this corner (m); the sphere falls along −z in its middle.
    pub box_size: Vector,
    /// Dry coefficient of restitution of the sphere on the floor.
    pub dry_restitution: Real,
    /// Sphere's and floor's elastic constants.
    pub sphere_material: Material,
    /// The floor's (and walls').
    pub wall_material: Material,
    /// Lattice spacing (m).
    pub dx: Real,
    /// Fluid time step (s).
    pub dt: Real,
    /// Overlap resolution of the contact.
    pub n_c: usize,
    /// The sphere's facet layer in the overlap (`OverlapSettings::with_facet_bulge`; a case
    /// saved before it existed resumes without it).
    #[serde(default)]
    pub facet_bulge: bool,
    /// Contact enlargement (m): the gap at which the contact starts, standing for the
    /// lubrication film the lattice cannot resolve.
    pub enlargement: Real,
    /// The liquid film's force below this gap (m; see [`Lubrication`]), for the gaps the
    /// lattice does not resolve; `None`: no film force, the enlargement stands for it.
    #[serde(default)]
    pub film_cutoff: Option<Real>,
    /// The film's minimum gap (m): surface roughness.
    #[serde(default = "default_film_min_gap")]
    pub film_min_gap: Real,
    /// Smoothing width of the solid fraction `d_B` (m).
    pub smoothing: Real,
    /// Virtual mass coefficient `C_V` (see `FluidSettings::with_virtual_mass`; 0: none).
    #[serde(default)]
    pub virtual_mass: Real,
    /// With the discrete contact (otherwise nothing but the fluid stops the sphere).
    pub contact: bool,
    /// How the lattice measures the fluid's force on the sphere.
    pub force_method: ForceMethod,
    /// Stop at this time (s) if the sphere is not at rest before.
    pub end_time: Real,
}

impl WetRebound {
    /// Li (2010) as in Marquardt et al.: steel sphere R = 4.75 mm, ρ_p = 7780 kg/m³ in a glycerol–water
    /// mixture ρ = 1230 kg/m³, μ = 50.2 mPa s; box 42 × 42 × 50 mm; E = 20 GPa / ν = 0.33
    /// (sphere), 3 GPa / 0.24 (wall); N_c = 16; enlargement Δx/7. Seed 000 uses a constant
    /// damping c = 0.12 s/m, which at the impact speeds here (0.2–0.6 m/s) is a dry restitution of
    /// 0.96–0.98; we set e_dry = 0.97, the measured dry value of steel on glass (Gondret et
    /// al. 2002). At `dx` the time step keeps the paper's relaxation time (Δx = 0.3 mm,
    /// Δt = 5 µs, τ = 7.3): `Δt = 5 µs (Δx / 0.3 mm)²`.
    pub fn li_2010(release_gap: Real, dx: Real) -> Self {
        Self {
            radius: 4.75e-3,
            particle_density: 7780.0,
            fluid_density: 1230.0,
            viscosity: 50.2e-3,
            release_gap,
            box_size: Vector::new(0.042, 0.042, 0.05),
            dry_restitution: 0.97,
            sphere_material: Material::new(20e9, 0.33).expect("valid"),
            wall_material: Material::new(3e9, 0.24).expect("valid"),
            dx,
            dt: 5e-6 * (dx / 0.3e-3).powi(2),
            n_c: 16,
            facet_bulge: true,
            enlargement: dx / 7.0,
            film_cutoff: None,
            film_min_gap: default_film_min_gap(),
            smoothing: 0.5 * dx,
            virtual_mass: 0.0,
            contact: true,
            force_method: ForceMethod::default(),
            end_time: 0.25,
        }
    }

    /// The film model in place of the enlargement model that [`li_2010`](Self::li_2010) sets
    /// (Marquardt et al.'s `Δx/7`, which stands for the film): the liquid film below
    /// [`FILM_CUTOFF`] `Δx`, the virtual mass [`FILM_MODEL_VIRTUAL_MASS`] and no enlargement.
    /// It follows e/e_dry(St) within 0.1 from St ≈ 20 to ≈ 950 at 10 and 16 nodes across the
    /// diameter, where the enlargement rebounds too high at low Stokes numbers and falls short
    /// above St ≈ 200 (`docs/wet.md`).
    pub fn with_film_model(mut self) -> Self {
        self.enlargement = 0.0;
        self.virtual_mass = FILM_MODEL_VIRTUAL_MASS;
        self.film_cutoff = Some(FILM_CUTOFF * self.dx);
        self
    }

    /// Stokes number `St = (ρ_p + ρ_f/2) U D / (9 μ)` at impact speed `u` (added mass included).
    pub fn stokes_number(&self, u: Real) -> Real {
        (self.particle_density + 0.5 * self.fluid_density) * u * 2.0 * self.radius
            / (9.0 * self.viscosity)
    }

    /// Legendre et al. (2006): `e_wet / e_dry = exp(−35 / St)`.
    pub fn legendre_ratio(&self, u: Real) -> Real {
        (-35.0 / self.stokes_number(u)).exp()
    }

    /// The gap (m) at which approach and rebound speeds are taken: 5 % of the diameter, about
    /// what a high-speed camera resolves in the experiments the correlation rests on.
    pub fn measuring_gap(&self) -> Real {
        0.1 * self.radius
    }
}

/// The film's minimum gap unless set (m): 16 µm, fitted to a 6 mm steel sphere in silicone
/// oil at St = 19 and Δx = 0.6 mm (`docs/wet.md`) — more than a polished sphere's roughness, as
/// the film also stands for what the contact model leaves out there.
pub const FILM_MIN_GAP: Real = 16e-6;

/// The film model's virtual mass coefficient `C_V` (with the film and no enlargement): 0.8,
/// potential flow's added mass of a sphere touching a plane; chosen by the e/e_dry sweep over
/// the Stokes number at 10 and 16 nodes per diameter (`docs/wet.md`).
pub const FILM_MODEL_VIRTUAL_MASS: Real = 0.8;

fn default_film_min_gap() -> Real {
    FILM_MIN_GAP
}

/// What a run recorded.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trajectory {
    /// (time (s), gap between the sphere's surface and the floor (m), vertical velocity (m/s))
    /// after every step.
    pub samples: Vec<(Real, Real, Real)>,
    /// Time (s) and speed (m/s) when the sphere first touched (the contact started), or — without
    /// contact — when its surface first reached the floor.
    pub impact: Option<(Real, Real)>,
    /// Upward speed (m/s) when the first contact ended.
    pub rebound_speed: Option<Real>,
    /// Largest gap (m) between the first and the second contact.
    pub rebound_height: Option<Real>,
    /// Smallest gap (m) reached.
    pub min_gap: Real,
    /// Fluid steps run.
    pub steps: u64,
    /// Lattice nodes (fluid and wall).
    pub cells: usize,
    /// Wall-clock time of the run (s).
    pub wall_time: Real,
}

impl Trajectory {
    /// Speeds (m/s) with which the sphere passes the gap `level` (m) — falling, before its first
    /// impact, and rising, after it (0 when it does not rise that far) — as a camera resolving
    /// `level` would measure them (experiments define the wet restitution this way: the
    /// velocities just before and just after the collision).
    pub fn speeds_at(&self, level: Real) -> Option<(Real, Real)> {
        let (t_impact, _) = self.impact?;
        let cross = |a: &(Real, Real, Real), b: &(Real, Real, Real)| {
            let s = (level - a.1) / (b.1 - a.1);
            (a.2 + s * (b.2 - a.2)).abs()
        };
        let pairs = || self.samples.windows(2);
        let down = pairs()
            .find(|w| w[0].1 > level && w[1].1 <= level && w[1].0 <= t_impact + 1e-12)
            .map(|w| cross(&w[0], &w[1]))?;
        let up = pairs()
            .find(|w| w[0].0 > t_impact && w[0].1 < level && w[1].1 >= level)
            .map(|w| cross(&w[0], &w[1]))
            .unwrap_or(0.0);
        Some((down, up))
    }

    /// Effective wet restitution `U_out / U_in` with the speeds at gap `level` (see
    /// [`speeds_at`](Self::speeds_at)).
    pub fn restitution_at(&self, level: Real) -> Option<Real> {
        self.speeds_at(level).map(|(down, up)| up / down)
    }
}

/// The label of a rebound run's checkpoints.
pub const CHECKPOINT_KIND: &str = "discrete-contact/wet_rebound";

/// A rebound run in progress: world, fluid, contacts and the trajectory so far. It can be
/// saved at any step and resumed with bit-identical results ([`save`](Self::save),
/// [`load`](Self::load); feature `checkpoint`).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct ReboundRun {
    case: WetRebound,
    world: PhysicsWorld,
    fluid: Fluid,
    contacts: Option<DiscreteContacts>,
    body: RigidBodyHandle,
    out: Trajectory,
    touching: bool,
    contacts_seen: usize,
    last_vz: Real,
    quiet_since: Option<Real>,
    done: bool,
}

impl ReboundRun {
    /// Sets `case` up: the sphere, the fluid in its closed box, the walls' contacts.
    pub fn new(case: &WetRebound) -> Result<Self> {
        let start = Instant::now();
        let r = case.radius;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -9.81);
        let centre =
            Vector::new(0.5 * case.box_size.x, 0.5 * case.box_size.y, r + case.release_gap);
        let body = world.insert_body(RigidBodyBuilder::dynamic().translation(centre));
        let sphere = world
            .insert_collider(ColliderBuilder::ball(r).density(case.particle_density), Some(body));

        let settings = FluidSettings::new(
            case.dx,
            case.dt,
            case.viscosity / case.fluid_density,
            case.fluid_density,
        )?
        .with_smoothing(case.smoothing)?
        .with_force_method(case.force_method)
        .with_virtual_mass(case.virtual_mass)?;
        let mut fluid = Fluid::closed_box(Vector::ZERO, case.box_size, settings)?;
        fluid.couple(&world, sphere)?;

        let contacts = if case.contact {
            // The box's floor and side walls as half-spaces on one fixed body.
            let walls = world.insert_body(RigidBodyBuilder::fixed());
            let mut colliders = Vec::new();
            for (normal, at) in [
                (Vector::Z, Vector::ZERO),
                (Vector::X, Vector::ZERO),
                (Vector::Y, Vector::ZERO),
                (-Vector::X, case.box_size),
                (-Vector::Y, case.box_size),
            ] {
                colliders.push(world.insert_collider(
                    ColliderBuilder::new(SharedShape::halfspace(normal)).translation(at),
                    Some(walls),
                ));
            }
            let settings = OverlapSettings::new(case.n_c, IntegrationMode::Subcell)?
                .with_facet_bulge(case.facet_bulge)
                .with_enlargement(0.5 * case.enlargement, 0.5 * case.enlargement)?;
            let mut c = DiscreteContacts::new(settings, case.dry_restitution)?
                .with_policy(StepPolicy::AutoSubstep { max_substeps: 100_000 });
            if let Some(cutoff) = case.film_cutoff {
                c = c.with_lubrication(Lubrication::new(
                    case.viscosity,
                    cutoff,
                    case.film_min_gap,
                )?);
            }
            c.handle(&mut world, sphere, case.sphere_material)?;
            for h in colliders {
                c.handle(&mut world, h, case.wall_material)?;
            }
            Some(c)
        } else {
            None
        };
        let out = Trajectory {
            cells: fluid.lattice().cells(),
            min_gap: case.release_gap,
            wall_time: start.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Ok(Self {
            case: case.clone(),
            world,
            fluid,
            contacts,
            body,
            out,
            touching: false,
            contacts_seen: 0,
            last_vz: 0.0,
            quiet_since: None,
            done: false,
        })
    }

    /// Whether the run has ended: the sphere at rest after its first impact (10 ms without a
    /// speed above 2 mm/s), half-way into the floor (no contact), or the end time reached.
    pub fn is_done(&self) -> bool {
        self.done
    }

    /// The trajectory so far.
    pub fn trajectory(&self) -> &Trajectory {
        &self.out
    }

    /// The fluid (for snapshots).
    pub fn fluid(&self) -> &Fluid {
        &self.fluid
    }

    /// One four-way coupled step, recording the gap and the impact and rebound.
    pub fn step(&mut self) -> Result<()> {
        if self.done {
            return Ok(());
        }
        let start = Instant::now();
        self.fluid.step(&mut self.world, self.contacts.as_mut())?;
        let out = &mut self.out;
        out.steps += 1;
        let t = out.steps as Real * self.case.dt;
        let rb = &self.world.bodies[self.body];
        let (gap, vz) = (rb.translation().z - self.case.radius, rb.linvel().z);
        out.samples.push((t, gap, vz));
        out.min_gap = out.min_gap.min(gap);
        let now_touching = match &self.contacts {
            Some(c) => c.contact_count() > 0,
            None => gap <= 0.0,
        };
        if now_touching && !self.touching {
            self.contacts_seen += 1;
            if out.impact.is_none() {
                out.impact = Some((t, -self.last_vz));
            }
        }
        if !now_touching && self.touching && self.contacts_seen == 1 && vz > 0.0 {
            out.rebound_speed = Some(vz);
        }
        if self.contacts_seen == 1 && !now_touching && out.rebound_speed.is_some() {
            out.rebound_height = Some(out.rebound_height.unwrap_or(0.0).max(gap));
        }
        self.touching = now_touching;
        self.last_vz = vz;
        // At rest: after the first impact, 10 ms without a speed above 2 mm/s.
        if out.impact.is_some() && vz.abs() < 2e-3 {
            let since = *self.quiet_since.get_or_insert(t);
            self.done |= t - since > 10e-3;
        } else {
            self.quiet_since = None;
        }
        // Without contact the sphere sinks into the floor: stop once it is half way in.
        self.done |= gap < -0.5 * self.case.radius
            || out.steps as Real >= (self.case.end_time / self.case.dt).ceil();
        out.wall_time += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// The recorded trajectory.
    pub fn finish(self) -> Trajectory {
        self.out
    }

    /// Saves the run to `path` (atomically; see [`discrete_contact::checkpoint`]).
    pub fn save(&self, path: &std::path::Path) -> Result<()> {
        discrete_contact::checkpoint::save(path, CHECKPOINT_KIND, self)
    }

    /// Resumes a run saved with [`save`](Self::save); refused with [`Error::Checkpoint`](discrete_contact::Error::Checkpoint) when
    /// the file is not such a run (or is damaged), and with [`Error::InvalidParameter`](discrete_contact::Error::InvalidParameter) naming
    /// `case` when it holds another case.
    pub fn load(path: &std::path::Path, case: &WetRebound) -> Result<Self> {
        super::resume(
            path,
            CHECKPOINT_KIND,
            case,
            |run: &Self| &run.case,
            "the case the checkpoint was saved from (sizes, densities, viscosity, release gap, resolution, contact)",
        )
    }
}

/// Runs `case`, calling `progress(trajectory, fluid)` after every step.
pub fn run(case: &WetRebound, mut progress: impl FnMut(&Trajectory, &Fluid)) -> Result<Trajectory> {
    let mut run = ReboundRun::new(case)?;
    while !run.is_done() {
        run.step()?;
        progress(&run.out, &run.fluid);
    }
    Ok(run.finish())
}
