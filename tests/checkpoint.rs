//! Checkpoint and restart, and atomic output: a dry and a wet run stopped at step k, saved,
//! loaded and resumed end bit-identical to the uninterrupted runs; damaged, foreign, other-kind
//! and other-version files are refused by name; a process killed while writing a file leaves
//! the previous complete file, not a truncated one.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use discrete_contact::checkpoint::{self, FORMAT_VERSION};
use discrete_contact::error::CheckpointProblem;
use discrete_contact::math::Vector;
use discrete_contact::parry3d_f64::bounding_volume::Aabb;
use discrete_contact::rapier::DiscreteContacts;
use discrete_contact::rapier3d_f64::prelude::*;
use discrete_contact::{ConvexShape, Error};
use discrete_contact_validation::drop_in::{bin_scene, discrete_contacts, rubber};
use discrete_contact_validation::hindered_settling::{
    HinderedSettling, ParticleShape, SettlingRun,
};
use discrete_contact_validation::wet_rebound::{ReboundRun, WetRebound};

/// A fresh folder for one test's files.
fn scratch(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("checkpoint").join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every body's pose and velocities, bit for bit, in handle order.
fn fingerprint(world: &PhysicsWorld) -> Vec<u64> {
    let mut bodies: Vec<_> = world.bodies.iter().collect();
    bodies.sort_by_key(|(h, _)| h.into_raw_parts());
    bodies
        .iter()
        .flat_map(|(_, rb)| {
            let p = rb.position();
            let (t, q) = (p.translation, p.rotation);
            [t.x, t.y, t.z, q.x, q.y, q.z, q.w]
                .into_iter()
                .chain(rb.linvel().to_array())
                .chain(rb.angvel().to_array())
        })
        .map(f64::to_bits)
        .collect()
}

fn dry_scene() -> (PhysicsWorld, DiscreteContacts) {
    let mut scene = bin_scene(24);
    let mut contacts = discrete_contacts(4, 10.0).unwrap();
    contacts.handle_all(&mut scene.world, rubber().unwrap()).unwrap();
    (scene.world, contacts)
}

#[test]
fn a_dry_run_resumed_from_a_checkpoint_is_bit_identical() {
    // The bin: 24 mixed bodies fall onto the floor and a jointed see-saw (friction on).
    let (stop, total) = (50, 90);
    let (mut world, mut contacts) = dry_scene();
    for _ in 0..total {
        contacts.step(&mut world).unwrap();
    }
    let uninterrupted = (fingerprint(&world), contacts.contact_count());

    let path = scratch("dry").join("bin.ckpt");
    let (mut world, mut contacts) = dry_scene();
    for _ in 0..stop {
        contacts.step(&mut world).unwrap();
    }
    assert!(contacts.contact_count() > 0, "contacts alive when saved");
    checkpoint::save(&path, "test/bin", &(&world, &contacts)).unwrap();
    let before = fingerprint(&world);
    drop((world, contacts));

    let (mut world, mut contacts): (PhysicsWorld, DiscreteContacts) =
        checkpoint::load(&path, "test/bin").unwrap();
    assert_eq!(fingerprint(&world), before, "the saved state itself");
    for _ in stop..total {
        contacts.step(&mut world).unwrap();
    }
    assert_eq!(contacts.contact_count(), uninterrupted.1);
    assert!(
        fingerprint(&world) == uninterrupted.0,
        "resumed run differs from the uninterrupted one"
    );
}

fn small_settling() -> HinderedSettling {
    // 24³ nodes, D = 6 Δx, φ = 30 %: particles touch within a few dozen steps.
    let mut case = HinderedSettling::seed_002(ParticleShape::Sphere, 0.3, 1000.0).unwrap();
    case.nodes_per_diameter = 6.0;
    case.box_nodes = 24;
    case.duration = 160.0 * case.dt() * case.stokes_velocity() / case.diameter;
    case
}

/// With the seed's enlargement and with the film model, whose virtual mass keeps a momentum
/// lent to each body from step to step.
#[test]
fn a_wet_periodic_run_resumed_from_a_checkpoint_is_bit_identical() {
    resumes_bit_identically(&small_settling(), "wet");
    // The film keeps the particles apart for longer.
    let mut film = small_settling().with_film_model();
    film.duration *= 2.5;
    resumes_bit_identically(&film, "wet-film");
}

fn resumes_bit_identically(case: &HinderedSettling, name: &str) {
    let mut whole = SettlingRun::new(case).unwrap();
    while !whole.is_done() {
        whole.step().unwrap();
    }
    let world_bits = fingerprint(whole.world());
    let fluid_bits = whole.fluid().mean_velocity().to_array().map(f64::to_bits);
    let whole = whole.finish();
    assert!(whole.max_contacts > 0, "the run has contacts");

    let path = scratch(name).join("settling.ckpt");
    let mut part = SettlingRun::new(case).unwrap();
    for _ in 0..100 {
        part.step().unwrap();
    }
    part.save(&path).unwrap();
    drop(part);
    let mut resumed = SettlingRun::load(&path, case).unwrap();
    assert_eq!(resumed.steps_done(), 100);
    while !resumed.is_done() {
        resumed.step().unwrap();
    }
    assert!(fingerprint(resumed.world()) == world_bits, "bodies differ after resuming");
    assert_eq!(
        resumed.fluid().mean_velocity().to_array().map(f64::to_bits),
        fluid_bits,
        "fluid differs"
    );
    let resumed = resumed.finish();
    assert_eq!(resumed.samples, whole.samples, "⟨v⟩/v_s series");
    assert_eq!(resumed.v_mean_over_vs.to_bits(), whole.v_mean_over_vs.to_bits());

    // Another case is refused by name, not silently resumed.
    let mut other = case.clone();
    other.seed += 1;
    match SettlingRun::load(&path, &other) {
        Err(Error::InvalidArgument { name: "case", .. }) => {}
        other => panic!("resumed another case: {:?}", other.err()),
    }
}

#[test]
fn a_wet_run_in_a_closed_box_resumed_during_its_impact_is_bit_identical() {
    // The Li sphere at Δx = 1.5 mm, released 5.5 mm above the floor; saved while it touches.
    let mut case = WetRebound::li_2010(5.5e-3, 1.5e-3);
    case.n_c = 4;
    case.end_time = 0.06;
    let mut whole = ReboundRun::new(&case).unwrap();
    let mut stop = None;
    while !whole.is_done() {
        whole.step().unwrap();
        let t = whole.trajectory();
        if stop.is_none() && t.impact.is_some() {
            // The step the contact started: saved with a live contact.
            stop = Some(t.steps);
        }
    }
    let stop = stop.expect("the sphere reaches the floor");
    let whole = whole.finish();
    assert!(whole.rebound_speed.is_some(), "it rebounds");

    let path = scratch("rebound").join("rebound.ckpt");
    let mut part = ReboundRun::new(&case).unwrap();
    while part.trajectory().steps < stop {
        part.step().unwrap();
    }
    part.save(&path).unwrap();
    drop(part);
    let mut resumed = ReboundRun::load(&path, &case).unwrap();
    while !resumed.is_done() {
        resumed.step().unwrap();
    }
    let resumed = resumed.finish();
    let bits = |t: &discrete_contact_validation::wet_rebound::Trajectory| -> Vec<u64> {
        t.samples.iter().flat_map(|s| [s.0, s.1, s.2]).map(f64::to_bits).collect()
    };
    assert!(bits(&resumed) == bits(&whole), "gap and velocity series differ after resuming");
    assert_eq!(
        (resumed.impact, resumed.rebound_speed, resumed.rebound_height),
        (whole.impact, whole.rebound_speed, whole.rebound_height)
    );
}

/// A lattice storing f32 populations (raw bits in the file) saved mid-run and resumed goes on
/// bit-identically, its storage kept.
#[test]
fn an_f32_lattice_resumed_from_a_checkpoint_is_bit_identical() {
    use discrete_contact::hlbm::{Lattice, Storage};
    let dir = scratch("f32_lattice");
    let mut lat = Lattice::new(12, 10, 8, 0.6).unwrap();
    lat.set_storage(Storage::F32);
    lat.set_body_acceleration([1e-5, 0.0, 0.0]);
    lat.particles_mut().add_sphere([5.2, 4.7, 3.9], 2.5, 1.0, [1e-3, 0.0, 0.0], 0).unwrap();
    lat.run(5).unwrap();
    let path = dir.join("lattice.ckpt");
    checkpoint::save(&path, "test/lattice", &lat).unwrap();
    let mut resumed: Lattice = checkpoint::load(&path, "test/lattice").unwrap();
    assert_eq!(resumed.storage(), Storage::F32);
    let (a, b) = (lat.run(6).unwrap(), resumed.run(6).unwrap());
    assert_eq!(a.particle_forces[&0], b.particle_forces[&0]);
    for (x, y, z) in [(0, 0, 0), (5, 4, 3), (11, 9, 7)] {
        assert_eq!(
            lat.populations(x, y, z).map(f64::to_bits),
            resumed.populations(x, y, z).map(f64::to_bits)
        );
    }
}

fn problem(result: discrete_contact::Result<u64>) -> CheckpointProblem {
    match result {
        Err(Error::Checkpoint { problem, .. }) => problem,
        other => panic!("not a checkpoint error: {other:?}"),
    }
}

#[test]
fn damaged_foreign_and_mismatched_files_are_refused_with_the_reason() {
    let dir = scratch("refusals");
    let good = dir.join("good.ckpt");
    checkpoint::save(&good, "test/number", &42u64).unwrap();
    assert_eq!(checkpoint::load::<u64>(&good, "test/number").unwrap(), 42);
    let bytes = std::fs::read(&good).unwrap();
    let variant = |name: &str, edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        edit(&mut b);
        let p = dir.join(name);
        std::fs::write(&p, b).unwrap();
        checkpoint::load::<u64>(&p, "test/number")
    };
    let last = bytes.len() - 1;
    assert_eq!(
        problem(variant("text", &|b| *b = b"t,x\n0,1\n".to_vec())),
        CheckpointProblem::NotACheckpoint
    );
    assert_eq!(problem(variant("empty", &|b| b.clear())), CheckpointProblem::NotACheckpoint);
    assert_eq!(
        problem(
            variant("format", &|b| b[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes()))
        ),
        CheckpointProblem::FormatVersion { found: FORMAT_VERSION + 1, supported: FORMAT_VERSION }
    );
    let writer_at = 14; // signature, format, writer length
    assert!(matches!(
        problem(variant("writer", &|b| b[writer_at] ^= 0x20)),
        CheckpointProblem::WrittenBy { .. }
    ));
    assert!(matches!(
        problem(variant("cut", &|b| b.truncate(last))),
        CheckpointProblem::Length { .. }
    ));
    assert!(matches!(problem(variant("longer", &|b| b.push(0))), CheckpointProblem::Length { .. }));
    assert!(matches!(
        problem(variant("altered", &|b| b[last] ^= 1)),
        CheckpointProblem::Checksum { .. }
    ));
    assert!(matches!(
        problem(checkpoint::load(&good, "test/other")),
        CheckpointProblem::Kind { .. }
    ));
    // Right kind, wrong type: a settling run is not a number.
    let wrong = dir.join("wrong.ckpt");
    checkpoint::save(&wrong, "test/number", &(1.5f64, "x")).unwrap();
    assert!(matches!(
        problem(checkpoint::load(&wrong, "test/number")),
        CheckpointProblem::Decode(_)
    ));
    match SettlingRun::load(&good, &small_settling()) {
        Err(Error::Checkpoint { problem: CheckpointProblem::Kind { .. }, .. }) => {}
        other => panic!("{:?}", other.err()),
    }
    // Parameters read from a file pass their constructors' checks: a material with E < 0 or
    // a grid with N_c = 0 is refused by name, not let through to produce NaNs later.
    let bad = dir.join("bad_material.ckpt");
    checkpoint::save(&bad, "test/material", &(-1.0f64, 0.3f64)).unwrap();
    match checkpoint::load::<discrete_contact::Material>(&bad, "test/material") {
        Err(Error::Checkpoint { problem: CheckpointProblem::Decode(why), .. }) => {
            assert!(why.contains("youngs_modulus"), "{why}")
        }
        other => panic!("{other:?}"),
    }
    checkpoint::save(
        &bad,
        "test/settings",
        &(
            0usize,
            discrete_contact::IntegrationMode::Subcell,
            [0.0f64; 2],
            false,
            false,
            false,
            false,
        ),
    )
    .unwrap();
    match checkpoint::load::<discrete_contact::OverlapSettings>(&bad, "test/settings") {
        Err(Error::Checkpoint { problem: CheckpointProblem::Decode(why), .. }) => {
            assert!(why.contains("n_c"), "{why}")
        }
        other => panic!("{other:?}"),
    }
    // A missing file is an i/o error naming the path.
    match checkpoint::load::<u64>(&dir.join("missing.ckpt"), "test/number") {
        Err(Error::Io { path, .. }) => assert!(path.ends_with("missing.ckpt")),
        other => panic!("{other:?}"),
    }
    // A closure cannot be saved: refused, and nothing is written.
    let custom = ConvexShape::custom(
        |p: Vector| p.length() - 1.0,
        Aabb::new(Vector::splat(-1.0), Vector::splat(1.0)),
    )
    .unwrap();
    let path = dir.join("custom.ckpt");
    match checkpoint::save(&path, "test/shape", &custom) {
        Err(Error::Checkpoint { problem: CheckpointProblem::Encode(why), .. }) => {
            assert!(why.contains("Custom"), "{why}")
        }
        other => panic!("{other:?}"),
    }
    assert!(!path.exists());
}

const CHILD_TARGET: &str = "DISCRETE_CONTACT_TEST_KILL_TARGET";

/// The child half of the kill test (run by it, skipped otherwise): replaces the target file
/// atomically, slowly, until killed.
#[test]
#[ignore = "run by a_run_killed_while_writing_leaves_no_truncated_file"]
fn child_writes_slowly_until_killed() {
    let Some(target) = std::env::var_os(CHILD_TARGET) else { return };
    let target = PathBuf::from(target);
    let marker = target.with_extension("started");
    discrete_contact::io::write_atomically(&target, |w| {
        for i in 0.. {
            writeln!(w, "{i},{}", "new row ".repeat(1000))?;
            w.flush()?;
            if i == 10 {
                std::fs::write(&marker, "writing")?;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        Ok(())
    })
    .unwrap();
}

#[test]
fn a_run_killed_while_writing_leaves_no_truncated_file() {
    let dir = scratch("kill");
    let target = dir.join("results.csv");
    let complete = "t,x\n0,1\n1,2\n";
    discrete_contact::io::write_atomically(&target, |w| w.write_all(complete.as_bytes())).unwrap();

    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "child_writes_slowly_until_killed",
            "--exact",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_TARGET, &target)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !target.with_extension("started").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "the child never started writing");
        assert!(child.try_wait().unwrap().is_none(), "the child ended before it was killed");
        std::thread::sleep(Duration::from_millis(5));
    }
    // Mid-write: the new content is on its way, in a file of its own.
    let partial = || -> Vec<PathBuf> {
        std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.to_string_lossy().contains(".partial"))
            .collect()
    };
    let pending = partial();
    assert_eq!(pending.len(), 1, "{pending:?}");
    assert!(std::fs::metadata(&pending[0]).unwrap().len() > 10_000);
    child.kill().unwrap();
    child.wait().unwrap();

    assert_eq!(
        std::fs::read_to_string(&target).unwrap(),
        complete,
        "the target holds the last complete file"
    );
    let name = pending[0].file_name().unwrap().to_string_lossy().into_owned();
    assert!(name.starts_with(".results.csv.") && name.ends_with(".partial.csv"), "{name}");

    // A writer that fails leaves the target alone and removes its partial file.
    let e = discrete_contact::io::write_atomically(&target, |w| {
        w.write_all(b"half")?;
        Err(std::io::Error::other("disk full"))
    });
    assert!(matches!(e, Err(Error::Io { .. })));
    assert_eq!(std::fs::read_to_string(&target).unwrap(), complete);
    assert_eq!(partial().len(), 1, "only the killed writer's leftover");
}
