//! Hindered settling of many spheres or cubes in a triply periodic box (Marquardt, Hafen & Krause §5):
//! rapier bodies, the HLBM fluid and periodic discrete contacts in one four-way coupled step.
//!
//! The particles are placed at random without overlap, released from rest, and settle along
//! −z; the fluid carries the balance acceleration of [`Fluid::balance_weight`], so the
//! suspension as a whole does not accelerate. The mean settling velocity is measured in the
//! frame of zero volume flux — the frame of a closed settling column, the one the
//! correlations refer to: `⟨v⟩ = (1 − φ)(⟨v_p⟩ − ⟨u_f⟩)` with `⟨u_f⟩` the mean velocity of
//! the fluid outside the particles — and averaged after the initial transient. It is compared
//! with Richardson–Zaki and Garside–Al-Dibouni, `(1 − φ)^n`, scaled by the single sphere's
//! Schiller–Naumann terminal velocity `v_s`.
//!
//! [`HinderedSettling::seed_002`] holds the seed's values (and those of its authors' public
//! example where the text lost them); every field can be changed.

use std::time::Instant;

use discrete_contact::parry3d_f64::query;
use discrete_contact::rapier3d_f64::prelude::{
    ColliderBuilder, ColliderHandle, InteractionGroups, PhysicsWorld, RigidBodyBuilder,
    RigidBodyHandle, SharedShape,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use discrete_contact::coupling::{Fluid, FluidSettings, FluidStepReport, ForceMethod};
use discrete_contact::error::{Error, Result};
use discrete_contact::hlbm::correlations::{
    garside_al_dibouni_exponent, richardson_zaki_exponent, schiller_naumann_terminal_velocity,
};
use discrete_contact::material::{Friction, Material};
use discrete_contact::math::{Pose, Real, Rotation, Vector};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};
use discrete_contact::periodic::{CellGrid, PeriodicBox};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};
use discrete_contact::tangential::TangentialLaw;

use crate::wet_rebound::{FILM_MIN_GAP, FILM_MODEL_VIRTUAL_MASS};

/// Standard gravity (m/s²).
const G: Real = 9.81;

/// The particles' shape; a cube has the volume of the sphere of diameter `D`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ParticleShape {
    /// Spheres of diameter `D`.
    Sphere,
    /// Cubes of edge `D (π/6)^(1/3)`, randomly oriented.
    Cube,
}

impl ParticleShape {
    /// Volume of the points within `r` of the particle of volume-equivalent diameter `d`
    /// (Steiner's formula: volume, surface area × r, mean-curvature integral × r², 4π r³/3).
    pub fn covered_volume(self, d: Real, r: Real) -> Real {
        let pi = std::f64::consts::PI;
        let ball = 4.0 / 3.0 * pi * r.powi(3);
        match self {
            Self::Sphere => pi / 6.0 * (d + 2.0 * r).powi(3),
            Self::Cube => {
                let a = d * (pi / 6.0).cbrt();
                a.powi(3) + 6.0 * a * a * r + 3.0 * pi * a * r * r + ball
            }
        }
    }

    /// The name used in reports (`sphere`, `cube`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Sphere => "sphere",
            Self::Cube => "cube",
        }
    }
}

/// Where the balance force — the uniform acceleration of the fluid that holds the suspension
/// as a whole at rest in the periodic box — acts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Balance {
    /// On every lattice node, those a particle covers too: each particle receives the body
    /// force of its nodes, its smoothing band's included (about `ρ_f V_c a`, `V_c` the volume
    /// within half the smoothing width outside its surface).
    #[default]
    Lattice,
    /// As a closed column's mean pressure gradient: each particle receives exactly `ρ_f V a`,
    /// so drag carries `(1 − φ)` of its submerged weight.
    Column,
    /// On the fluid outside the particles alone: drag carries each particle's whole submerged
    /// weight (the convention of the reference code's example).
    FluidAlone,
}

impl Balance {
    /// The convention named `lattice`, `column` or `fluid`.
    pub fn named(name: &str) -> Option<Self> {
        [Self::Lattice, Self::Column, Self::FluidAlone].into_iter().find(|b| b.name() == name)
    }

    /// The name used on the command line and in reports (`lattice`, `column`, `fluid`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Lattice => "lattice",
            Self::Column => "column",
            Self::FluidAlone => "fluid",
        }
    }
}

/// One hindered-settling run (SI units).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HinderedSettling {
    /// Particle shape.
    pub shape: ParticleShape,
    /// Solid volume fraction `φ`.
    pub volume_fraction: Real,
    /// Archimedes number `Ar = (ρ_p/ρ_f − 1) g D³ / ν²`; sets the viscosity.
    pub archimedes: Real,
    /// Volume-equivalent diameter `D` (m).
    pub diameter: Real,
    /// `ρ_p / ρ_f`.
    pub density_ratio: Real,
    /// Fluid density `ρ_f` (kg/m³).
    pub fluid_density: Real,
    /// Lattice nodes per diameter, `D / Δx`.
    pub nodes_per_diameter: Real,
    /// Lattice nodes along each edge of the cubic box (box edge = this × Δx).
    pub box_nodes: usize,
    /// Relaxation time `τ` (sets `Δt`).
    pub tau: Real,
    /// Restitution of particle contacts.
    pub restitution: Real,
    /// Friction of particle contacts.
    pub friction: Friction,
    /// Particles' elastic constants (softened, as in the seed).
    pub material: Material,
    /// Overlap resolution of the contacts.
    pub n_c: usize,
    /// Contact sub-steps per Hertz contact time (see
    /// [`DiscreteContacts::with_substeps_per_contact`]): 15 keeps a head-on collision of two
    /// particles within 0.1 % of `e` at 0.02–0.3 m/s (E = 50 kPa, one fluid step of
    /// 0.17 ms per sub-step); the drop-in's default 30 serves restitution measurements.
    pub substeps_per_contact: Real,
    /// Contact enlargement in lattice spacings (split over the two bodies).
    pub enlargement_cells: Real,
    /// Smoothing width of `d_B` in lattice spacings.
    pub smoothing_cells: Real,
    /// Virtual mass coefficient `C_V` (see `FluidSettings::with_virtual_mass`; 0: none).
    #[serde(default)]
    pub virtual_mass: Real,
    /// The liquid film's force between particles closer than `FILM_CUTOFF` Δx, with this
    /// minimum gap (m; see `FluidSettings::lubrication`); `None`: no film.
    #[serde(default)]
    pub film_min_gap: Option<Real>,
    /// The film's sliding and rolling terms too (see `Lubrication::with_shear`).
    #[serde(default)]
    pub film_shear: bool,
    /// With the discrete contact (without it particles pass through each other).
    pub contacts: bool,
    /// How the lattice measures the fluid's force on the particles.
    pub force_method: ForceMethod,
    /// Sphere pairs' overlaps in closed form instead of on the `N_c` grid
    /// ([`OverlapSettings::with_closed_form_spheres`]).
    pub closed_form_spheres: bool,
    /// Cube pairs' overlaps exactly, as the clipped polyhedron, instead of on the `N_c` grid
    /// ([`OverlapSettings::with_exact_polyhedra`]; the enlargement then moves the faces out
    /// instead of rounding edges and corners).
    pub exact_polyhedra: bool,
    /// Simulated time in units of `D / U`, `U` the Stokes velocity `(ρ_p/ρ_f − 1) g D² / (18 ν)`.
    pub duration: Real,
    /// Averaging starts at this fraction of the duration (after the transient).
    pub averaging_start: Real,
    /// Seed of the random placement.
    pub seed: u64,
    /// Where the balance force acts ([`Balance`]).
    #[serde(default)]
    pub balance: Balance,
}

impl HinderedSettling {
    /// Seed 002's case at volume fraction `phi` and Archimedes number `ar`: D = 3 mm resolved by
    /// 9 nodes, box 15 D (135³ nodes), ρ_p/ρ_f = 3.3 (ρ_f = 1000 kg/m³), τ = 0.55, e = 0.926,
    /// μ_s = 0.32, μ_k = 0.16, v_s = 1 mm/s, E = 5 kPa, ν = 0.245, N_c = 8, enlargement
    /// Δx/5, smoothing Δx/2, 200 D/U, averaged over the second half; contacts resolved with
    /// 15 sub-steps per Hertz contact time (ours, not the seed's).
    pub fn seed_002(shape: ParticleShape, phi: Real, ar: Real) -> Result<Self> {
        Ok(Self {
            shape,
            volume_fraction: phi,
            archimedes: ar,
            diameter: 3e-3,
            density_ratio: 3.3,
            fluid_density: 1000.0,
            nodes_per_diameter: 9.0,
            box_nodes: 135,
            tau: 0.55,
            restitution: 0.926,
            friction: Friction::new(0.32, 0.16, 1e-3)?,
            material: Material::new(5e3, 0.245)?,
            n_c: 8,
            substeps_per_contact: 15.0,
            enlargement_cells: 0.2,
            smoothing_cells: 0.5,
            virtual_mass: 0.0,
            film_min_gap: None,
            film_shear: false,
            contacts: true,
            force_method: ForceMethod::default(),
            closed_form_spheres: false,
            exact_polyhedra: false,
            duration: 200.0,
            averaging_start: 0.5,
            seed: 2,
            balance: Balance::default(),
        })
    }

    /// The film model of the wet rebound ([`WetRebound::with_film_model`](crate::wet_rebound::WetRebound::with_film_model))
    /// in place of the seed's enlargement: the liquid film below `FILM_CUTOFF` Δx with the
    /// minimum gap [`FILM_MIN_GAP`], the virtual mass [`FILM_MODEL_VIRTUAL_MASS`] and no
    /// enlargement.
    pub fn with_film_model(mut self) -> Self {
        self.enlargement_cells = 0.0;
        self.virtual_mass = FILM_MODEL_VIRTUAL_MASS;
        self.film_min_gap = Some(FILM_MIN_GAP);
        self
    }

    /// Kinematic viscosity from the Archimedes number (m²/s).
    pub fn viscosity(&self) -> Real {
        ((self.density_ratio - 1.0) * G * self.diameter.powi(3) / self.archimedes).sqrt()
    }

    /// Lattice spacing (m).
    pub fn dx(&self) -> Real {
        self.diameter / self.nodes_per_diameter
    }

    /// Fluid time step from `τ` (s).
    pub fn dt(&self) -> Real {
        (self.tau - 0.5) * self.dx() * self.dx() / (3.0 * self.viscosity())
    }

    /// Box edge (m).
    pub fn box_length(&self) -> Real {
        self.box_nodes as Real * self.dx()
    }

    /// Particles for the volume fraction.
    pub fn particle_count(&self) -> usize {
        let v = std::f64::consts::PI / 6.0 * self.diameter.powi(3);
        (self.volume_fraction * self.box_length().powi(3) / v).round() as usize
    }

    /// Stokes velocity `U` (m/s), the time scale of the run.
    pub fn stokes_velocity(&self) -> Real {
        (self.density_ratio - 1.0) * G * self.diameter.powi(2) / (18.0 * self.viscosity())
    }

    /// The single sphere's terminal velocity `v_s` (Schiller–Naumann, m/s).
    pub fn terminal_velocity(&self) -> Real {
        schiller_naumann_terminal_velocity(self.diameter, self.viscosity(), self.density_ratio, G)
    }

    /// The single sphere's Reynolds number `v_s D / ν`.
    pub fn reynolds(&self) -> Real {
        self.terminal_velocity() * self.diameter / self.viscosity()
    }

    /// Richardson–Zaki's `⟨v⟩/v_s = (1 − φ)^n`.
    pub fn richardson_zaki(&self) -> Real {
        (1.0 - self.volume_fraction).powf(richardson_zaki_exponent(self.reynolds()))
    }

    /// Garside–Al-Dibouni's `⟨v⟩/v_s = (1 − φ)^n`.
    pub fn garside_al_dibouni(&self) -> Real {
        (1.0 - self.volume_fraction).powf(garside_al_dibouni_exponent(self.reynolds()))
    }

    /// Fluid steps of the run.
    pub fn steps(&self) -> u64 {
        (self.duration * self.diameter / self.stokes_velocity() / self.dt()).ceil() as u64
    }

    fn check(&self) -> Result<()> {
        let bad = |name, value, allowed| Err(Error::InvalidParameter { name, value, allowed });
        if !(self.volume_fraction > 0.0 && self.volume_fraction <= 0.35) {
            return bad(
                "volume_fraction",
                self.volume_fraction,
                "0 < phi <= 0.35 (random placement)",
            );
        }
        if !(self.density_ratio > 1.0 && self.density_ratio.is_finite()) {
            return bad("density_ratio", self.density_ratio, "> 1 (the particles settle)");
        }
        if !(self.averaging_start >= 0.0 && self.averaging_start < 1.0) {
            return bad("averaging_start", self.averaging_start, "0 <= start < 1");
        }
        if !(self.duration > 0.0 && self.duration.is_finite()) {
            return bad("duration", self.duration, "> 0 (in D/U)");
        }
        if !(self.archimedes > 0.0 && self.archimedes.is_finite()) {
            return bad("archimedes", self.archimedes, "> 0, finite");
        }
        if !(self.diameter > 0.0 && self.diameter.is_finite()) {
            return bad("diameter", self.diameter, "> 0 m, finite");
        }
        if !(self.nodes_per_diameter >= 2.0 && self.nodes_per_diameter.is_finite()) {
            return bad(
                "nodes_per_diameter",
                self.nodes_per_diameter,
                ">= 2 lattice nodes per diameter",
            );
        }
        if self.particle_count() == 0 {
            return bad(
                "volume_fraction",
                self.volume_fraction,
                "enough for at least one particle in the box (or a larger box_nodes)",
            );
        }
        Ok(())
    }
}

/// What a run measured.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SettlingResult {
    /// Particles placed.
    pub particles: usize,
    /// (time (s), `⟨v⟩/v_s`) at every sample.
    pub samples: Vec<(Real, Real)>,
    /// `⟨v⟩/v_s` averaged after the transient.
    pub v_mean_over_vs: Real,
    /// Fluid steps run.
    pub steps: u64,
    /// Lattice nodes.
    pub cells: usize,
    /// Wall-clock time of the steps (s), without the `⟨v⟩/v_s` samples (each a sum over the
    /// whole lattice, not part of the method being timed).
    pub wall_time: Real,
    /// Wall-clock time of the set-up: placement, bodies, lattice (s).
    pub setup_time: Real,
    /// Wall-clock seconds in mapping, lattice and bodies (rapier + contacts), summed.
    pub seconds: discrete_contact::coupling::StepSeconds,
    /// Most contacts alive at once.
    pub max_contacts: usize,
    /// Total momentum along `z` (up; gravity is −z) at every sample — bodies plus the fluid
    /// outside them, all at rest at the start — over `N m_p v_s`. The balance force keeps it
    /// constant; a slope means the coupling loses or makes momentum
    /// ([`momentum_imbalance`](Self::momentum_imbalance)).
    pub momentum: Vec<Real>,
    /// The mean net force on the suspension along `z` over the averaging window (the slope of
    /// [`momentum`](Self::momentum)), over the bodies' net weight `N (m_p − ρ_f V) g`: zero
    /// when momentum is conserved, negative when the suspension is pushed down.
    pub momentum_imbalance: Real,
}

impl SettlingResult {
    /// Million lattice-node updates per second over the whole run (fluid, mapping, contacts).
    pub fn mlups(&self) -> Real {
        self.cells as Real * self.steps as Real / self.wall_time.max(1e-12) / 1e6
    }

    /// Seconds per fluid step.
    pub fn seconds_per_step(&self) -> Real {
        self.wall_time / self.steps.max(1) as Real
    }
}

/// Random non-overlapping poses of `n` particles in the periodic box, gap at least a quarter
/// `Δx` so no contact starts at once: random sequential addition; where that finds no free
/// spot (randomly oriented cubes jam before φ = 30 %), a simple or face-centred cubic lattice
/// of at least `n` sites (whichever spaces them wider) filled in random order, each particle
/// at its site with a random orientation redrawn until it clears its neighbours (a site with
/// no room stays empty) — the settling transient then randomises the arrangement.
pub fn place_particles(case: &HinderedSettling, n: usize) -> Result<Vec<Pose>> {
    case.check()?;
    let l = case.box_length();
    let domain = PeriodicBox::new(Vector::ZERO, Vector::splat(l), [true; 3])?;
    let shape = particle_shape(case);
    let radius = shape.compute_local_bounding_sphere().radius();
    let gap = 0.25 * case.dx();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(case.seed);
    // The placed particles filed by cell, cells at least one bounding diameter wide.
    // Whether `pose` keeps the gap to every particle placed so far.
    let free = |pose: &Pose, placed: &[Pose], grid: &CellGrid| {
        let centre = pose.translation;
        grid.near(centre).all(|j| {
            let mut other = placed[j];
            other.translation += domain.nearest_image_shift(centre, other.translation);
            let d = (other.translation - centre).length();
            d > 2.0 * radius + gap
                || (case.shape == ParticleShape::Cube
                    && query::distance(pose, shape.as_ref(), &other, shape.as_ref())
                        .is_ok_and(|d| d.distance > gap))
        })
    };
    let orientation = |rng: &mut Xoshiro256PlusPlus| match case.shape {
        ParticleShape::Sphere => Rotation::IDENTITY,
        ParticleShape::Cube => {
            let q = [0; 4].map(|_| rng.random::<Real>() * 2.0 - 1.0);
            Rotation::from_xyzw(q[0], q[1], q[2], q[3]).normalize()
        }
    };
    let tries = 200_000;
    let mut grid = CellGrid::new(2.0 * radius + gap, Some(&domain));
    let mut placed: Vec<Pose> = Vec::with_capacity(n);
    'rsa: for _ in 0..n {
        for _ in 0..tries {
            let centre = Vector::new(
                rng.random::<Real>() * l,
                rng.random::<Real>() * l,
                rng.random::<Real>() * l,
            );
            let pose = Pose::from_parts(centre, orientation(&mut rng));
            if free(&pose, &placed, &grid) {
                grid.insert(placed.len(), centre);
                placed.push(pose);
                continue 'rsa;
            }
        }
        // Jammed: start again on a lattice — simple cubic (m³ sites) or face-centred (4 k³),
        // whichever keeps neighbours further apart for n particles.
        let m = (1..).find(|m| m * m * m >= n).unwrap_or(1);
        let k = (1..).find(|k| 4 * k * k * k >= n).unwrap_or(1);
        let fcc = l / k as Real / std::f64::consts::SQRT_2 > l / m as Real;
        // Cell `c` of an `a × a × a` split of the box, as its corner in cell widths.
        let corner = |c: usize, a: usize| {
            Vector::new((c % a) as Real, ((c / a) % a) as Real, (c / (a * a)) as Real)
        };
        let mut sites: Vec<Vector> = if fcc {
            let basis =
                [[0.25, 0.25, 0.25], [0.75, 0.75, 0.25], [0.75, 0.25, 0.75], [0.25, 0.75, 0.75]];
            (0..k * k * k)
                .flat_map(|c| {
                    basis.map(|b| (corner(c, k) + Vector::from_array(b)) * (l / k as Real))
                })
                .collect()
        } else {
            (0..m * m * m).map(|c| (corner(c, m) + Vector::splat(0.5)) * (l / m as Real)).collect()
        };
        for i in (1..sites.len()).rev() {
            sites.swap(i, rng.random_range(0..=i));
        }
        grid.clear();
        placed.clear();
        for &centre in &sites {
            if placed.len() == n {
                break;
            }
            // A site its placed neighbours leave no room at stays empty (there are spares).
            if let Some(pose) = (0..200)
                .map(|_| Pose::from_parts(centre, orientation(&mut rng)))
                .find(|p| free(p, &placed, &grid))
            {
                grid.insert(placed.len(), centre);
                placed.push(pose);
            }
        }
        break;
    }
    if placed.len() < n {
        return Err(Error::InvalidParameter {
            name: "volume_fraction",
            value: case.volume_fraction,
            allowed: "a fraction random sequential addition or a randomly filled cubic lattice reaches (no free spot found)",
        });
    }
    Ok(placed)
}

fn particle_shape(case: &HinderedSettling) -> SharedShape {
    match case.shape {
        ParticleShape::Sphere => SharedShape::ball(0.5 * case.diameter),
        ParticleShape::Cube => {
            let half = 0.5 * case.diameter * (std::f64::consts::PI / 6.0).cbrt();
            SharedShape::cuboid(half, half, half)
        }
    }
}

/// Progress of a running case.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    /// Steps done.
    pub step: u64,
    /// Steps planned.
    pub steps: u64,
    /// What the last step did.
    pub report: &'a FluidStepReport,
    /// Latest `⟨v⟩/v_s`.
    pub v_over_vs: Real,
}

/// The label of a settling run's checkpoints.
pub const CHECKPOINT_KIND: &str = "discrete-contact/hindered_settling";

/// A hindered-settling run in progress: the rapier world, the fluid, the contacts and what has
/// been measured so far. It can be saved at any step and resumed with bit-identical results
/// ([`save`](Self::save), [`load`](Self::load); feature `checkpoint`).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct SettlingRun {
    case: HinderedSettling,
    world: PhysicsWorld,
    fluid: Fluid,
    contacts: Option<DiscreteContacts>,
    particles: Vec<(RigidBodyHandle, ColliderHandle)>,
    /// Volume of one particle (m³).
    volume: Real,
    step: u64,
    sample_every: u64,
    latest: Real,
    result: SettlingResult,
}

impl SettlingRun {
    /// Sets `case` up: places the particles, builds the bodies, the lattice and the contacts.
    pub fn new(case: &HinderedSettling) -> Result<Self> {
        case.check()?;
        let start = Instant::now();
        let n = case.particle_count();
        let poses = place_particles(case, n)?;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -G);
        // Rapier's broad phase sizes its margins by `length_unit` (1 m by default): left at 1 m
        // for millimetre particles it pairs every body with every other (1.9 M pairs, seconds
        // per step, for the 30 % peer case).
        world.integration_parameters.length_unit = case.diameter;
        let density = case.density_ratio * case.fluid_density;
        let shape = particle_shape(case);
        let mut particles: Vec<(RigidBodyHandle, ColliderHandle)> = Vec::with_capacity(n);
        for pose in &poses {
            let b = world.insert_body(RigidBodyBuilder::dynamic().pose(*pose).can_sleep(false));
            let mut collider = ColliderBuilder::new(shape.clone()).density(density);
            if !case.contacts {
                // No contact of any kind: particles pass through each other (rapier's own
                // contacts would otherwise act).
                collider = collider.collision_groups(InteractionGroups::none());
            }
            let c = world.insert_collider(collider, Some(b));
            particles.push((b, c));
        }
        let l = case.box_length();
        let dx = case.dx();
        let settings = FluidSettings::new(dx, case.dt(), case.viscosity(), case.fluid_density)?
            .with_smoothing(case.smoothing_cells * dx)?
            .with_force_method(case.force_method)
            .with_virtual_mass(case.virtual_mass)?;
        let mut fluid = Fluid::new(Vector::ZERO, Vector::splat(l), [true; 3], settings)?;
        for &(_, c) in &particles {
            fluid.couple(&world, c)?;
        }
        let a = fluid.balance_weight(&world)?;
        let volume = shape.mass_properties(1.0).mass();
        let share = match case.balance {
            Balance::Lattice => None,
            Balance::Column => Some(1.0),
            Balance::FluidAlone => Some(0.0),
        };
        if let Some(share) = share {
            // Each particle receives the body force of every node it covers (`d_B > 0`: the
            // points within half the smoothing width outside its surface), on average `ρ_f
            // V_c a` with `V_c` that set's volume: take off all of it but `share ρ_f V a`, and
            // raise `a` so that the total still balances the weight.
            let covered = case.shape.covered_volume(case.diameter, 0.5 * case.smoothing_cells * dx);
            let removed = covered - share * volume;
            let a = a / (1.0 - particles.len() as Real * removed / case.box_length().powi(3));
            let units = *fluid.units();
            fluid
                .lattice_mut()
                .set_body_acceleration(a.to_array().map(|c| units.acceleration_to_lattice(c)));
            for &(b, _) in &particles {
                world.bodies[b].add_force(-case.fluid_density * removed * a, true);
            }
        }
        let contacts = if case.contacts {
            let half = 0.5 * case.enlargement_cells * dx;
            let overlap = OverlapSettings::new(case.n_c, IntegrationMode::Subcell)?
                .with_enlargement(half, half)?
                .with_closed_form_spheres(case.closed_form_spheres)
                .with_exact_polyhedra(case.exact_polyhedra);
            let mut c = DiscreteContacts::new(overlap, case.restitution)?
                .with_friction(case.friction)
                // The seed's friction law, for the comparison with its runs.
                .with_tangential_law(TangentialLaw::SlipSpeed)
                .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 })
                .with_substeps_per_contact(case.substeps_per_contact)?
                // E = 5 kPa: a head-on collision at the settling speed indents ~30 % of D (Hertz).
                .with_indentation_limit(1.0)?
                .with_periodic(fluid.periodic_box().expect("a triply periodic fluid"));
            if let Some(h_min) = case.film_min_gap {
                c = c.with_lubrication(settings.lubrication(h_min)?.with_shear(case.film_shear));
            }
            for &(_, h) in &particles {
                c.handle(&mut world, h, case.material)?;
            }
            Some(c)
        } else {
            None
        };
        let steps = case.steps();
        let result = SettlingResult {
            particles: n,
            steps,
            cells: fluid.lattice().cells(),
            setup_time: start.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Ok(Self {
            case: case.clone(),
            volume,
            world,
            fluid,
            contacts,
            particles,
            step: 0,
            // About 400 samples, at most one per 10 steps (the fluid's mean is a sweep of its own).
            sample_every: (steps / 400).max(10),
            latest: 0.0,
            result,
        })
    }

    /// The case being run.
    pub fn case(&self) -> &HinderedSettling {
        &self.case
    }

    /// The rapier world of the particles.
    pub fn world(&self) -> &PhysicsWorld {
        &self.world
    }

    /// The fluid.
    pub fn fluid(&self) -> &Fluid {
        &self.fluid
    }

    /// The contacts (`None` for a run without them).
    pub fn contacts(&self) -> Option<&DiscreteContacts> {
        self.contacts.as_ref()
    }

    /// Fluid steps done.
    pub fn steps_done(&self) -> u64 {
        self.step
    }

    /// Whether every planned step has run.
    pub fn is_done(&self) -> bool {
        self.step >= self.result.steps
    }

    /// One four-way coupled step, sampling `⟨v⟩/v_s` when due.
    pub fn step(&mut self) -> Result<FluidStepReport> {
        let start = Instant::now();
        let report = self.fluid.step(&mut self.world, self.contacts.as_mut())?;
        self.step += 1;
        let out = &mut self.result;
        out.wall_time += start.elapsed().as_secs_f64();
        out.seconds.mapping += report.seconds.mapping;
        out.seconds.lattice += report.seconds.lattice;
        out.seconds.bodies += report.seconds.bodies;
        out.max_contacts = out.max_contacts.max(report.contacts.map_or(0, |c| c.contacts));
        if self.step % self.sample_every == 0 || self.step == out.steps {
            // Zero-volume-flux frame: ⟨v⟩ = (1 − φ)(⟨v_p⟩ − ⟨u_f⟩), the fluid's mean from the
            // lattice's (all nodes) less the nodes inside particles.
            let case = &self.case;
            let n = self.particles.len() as Real;
            let vp =
                self.particles.iter().map(|&(b, _)| self.world.bodies[b].linvel().z).sum::<Real>()
                    / n;
            let v_box = case.box_length().powi(3);
            let v_solid = n * self.volume;
            let u_mean = self.fluid.mean_velocity().z;
            let u_f = (u_mean * v_box - vp * v_solid) / (v_box - v_solid);
            self.latest = -(1.0 - case.volume_fraction) * (vp - u_f) / case.terminal_velocity();
            // Bodies (all of mass m_p = ρ_p V: N m_p ⟨v_p⟩) and the fluid outside them (the
            // lattice's less what the bodies carry inside them, which moves with them and is not
            // physical), over N m_p v_s.
            let fluid_over_bodies = (v_box - v_solid) / (v_solid * case.density_ratio);
            out.momentum.push((vp + fluid_over_bodies * u_f) / case.terminal_velocity());
            out.samples.push((self.step as Real * case.dt(), self.latest));
        }
        Ok(report)
    }

    /// Latest sample of `⟨v⟩/v_s`.
    pub fn latest(&self) -> Real {
        self.latest
    }

    /// What was measured, with `⟨v⟩/v_s` averaged over the samples after the transient.
    pub fn finish(mut self) -> SettlingResult {
        let case = &self.case;
        let r = &mut self.result;
        // The samples from the averaging start on (they are in time order).
        let from = case.averaging_start * r.steps as Real * case.dt();
        let first = r.samples.iter().position(|s| s.0 >= from).unwrap_or(r.samples.len());
        let tail = &r.samples[first..];
        r.v_mean_over_vs = tail.iter().map(|s| s.1).sum::<Real>() / tail.len().max(1) as Real;
        // The momentum's slope over the same window, as a force over the net weight:
        // ΔP / (N m_p v_s) over (1 − ρ_f/ρ_p) g Δt / v_s.
        if let (Some(&(t0, _)), Some(&(t1, _)), Some(&p0), Some(&p1)) =
            (tail.first(), tail.last(), r.momentum.get(first), r.momentum.last())
        {
            if t1 > t0 {
                r.momentum_imbalance = (p1 - p0)
                    / ((1.0 - 1.0 / case.density_ratio) * G * (t1 - t0) / case.terminal_velocity());
            }
        }
        self.result
    }

    /// Saves the run to `path` (atomically; see [`discrete_contact::checkpoint`]).
    pub fn save(&self, path: &std::path::Path) -> Result<()> {
        discrete_contact::checkpoint::save(path, CHECKPOINT_KIND, self)
    }

    /// Resumes a run saved with [`save`](Self::save); it goes on exactly as the saved run
    /// would have. Refused with [`Error::Checkpoint`] when the file is not such a run (or is
    /// damaged), and with [`Error::InvalidParameter`] naming `case` when it holds another case.
    pub fn load(path: &std::path::Path, case: &HinderedSettling) -> Result<Self> {
        super::resume(
            path,
            CHECKPOINT_KIND,
            case,
            |run: &Self| &run.case,
            "the case the checkpoint was saved from (its shape, φ, Ar, resolution, contacts, duration, seed)",
        )
    }
}

/// Runs `case`, calling `progress` after every step.
pub fn run(
    case: &HinderedSettling,
    mut progress: impl FnMut(Progress<'_>),
) -> Result<SettlingResult> {
    let mut run = SettlingRun::new(case)?;
    while !run.is_done() {
        let report = run.step()?;
        progress(Progress {
            step: run.steps_done(),
            steps: run.result.steps,
            report: &report,
            v_over_vs: run.latest,
        });
    }
    Ok(run.finish())
}
