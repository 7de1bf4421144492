//! The exact forms: closed-form sphere overlaps and exact polyhedra, against the fine grid and
//! against hand-computed overlaps.

use approx::assert_relative_eq;
use discrete_contact::prelude::*;
use discrete_contact::OverlapGeometry;

#[path = "common/contact.rs"]
mod shared;
use shared::*;

/// An exact form's overlap against the fine grid's: the relative volume difference, the
/// contact points' distance against the overlap's width (a thin lens is far wider than deep),
/// the normals' difference and the relative indentation difference; `worst` keeps the largest
/// of each.
fn differences(exact: &OverlapGeometry, grid: &OverlapGeometry, worst: &mut [f64; 4]) -> [f64; 4] {
    let errs = [
        (exact.volume / grid.volume - 1.0).abs(),
        (exact.contact_point - grid.contact_point).length()
            / (exact.volume / exact.indentation).sqrt(),
        (exact.normal - grid.normal).length(),
        (exact.indentation / grid.indentation - 1.0).abs(),
    ];
    for (w, e) in worst.iter_mut().zip(errs) {
        *w = w.max(e);
    }
    errs
}

/// The closed-form overlap of sphere pairs (a lens of two caps; one cap on a half-space) is what
/// the grid integration converges to: against sub-cell N_c = 64 on random pairs of radii,
/// depths, orientations and contact enlargements, with either body as A. Apart pairs are
/// apart in both.
#[test]
fn closed_form_sphere_overlaps_match_the_fine_grid() {
    use discrete_contact::compute_overlap;
    let fine = settings(64, IntegrationMode::Subcell);
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut worst = [0.0f64; 4];
    for k in 0..40 {
        let (ra, rb) = (0.5 + rnd(), 0.5 + rnd());
        let eps = [0.02 * rnd(), 0.02 * rnd()];
        let dir = Vector::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
        let depth = 0.3 * rnd() * ra.min(rb);
        let rot =
            Rotation::from_axis_angle(Vector::new(rnd(), rnd(), 1.0).normalize(), 6.0 * rnd());
        let half_space = k % 2 == 1;
        let b = if half_space {
            ConvexShape::half_space(dir).unwrap()
        } else {
            ConvexShape::ball(rb).unwrap()
        };
        let pose_b = Pose::from_parts(
            Vector::new(rnd(), rnd(), rnd()),
            if half_space { Rotation::IDENTITY } else { rot },
        );
        let reach = if half_space { ra } else { ra + rb };
        let pose_a =
            Pose::from_parts(pose_b.translation + dir * (reach + eps[0] + eps[1] - depth), rot);
        let a = ConvexShape::ball(ra).unwrap();
        for swap in [false, true] {
            let s = fine.with_enlargement(eps[0], eps[1]).unwrap();
            let (s, x, px, y, py) = if swap {
                (fine.with_enlargement(eps[1], eps[0]).unwrap(), &b, &pose_b, &a, &pose_a)
            } else {
                (s, &a, &pose_a, &b, &pose_b)
            };
            let grid =
                compute_overlap(x, px, y, py, &s, None).unwrap().expect("overlap on the grid");
            let exact = compute_overlap(x, px, y, py, &s.with_closed_form_spheres(true), None)
                .unwrap()
                .expect("overlap in closed form");
            let errs = differences(&exact, &grid, &mut worst);
            assert!(
                errs[0] < 2e-3 && errs[1] < 1e-2 && errs[2] < 1e-3 && errs[3] < 1e-2,
                "pair {k} swap {swap}: {errs:?}"
            );
            // Pulled apart: no overlap either way.
            let apart = Pose::from_parts(
                px.translation + exact.normal * (1.01 * exact.indentation),
                px.rotation,
            );
            assert!(compute_overlap(x, &apart, y, py, &s.with_closed_form_spheres(true), None)
                .unwrap()
                .is_none());
        }
    }
    println!("largest differences (volume, point / width, normal, indentation): {:.2e} {:.2e} {:.2e} {:.2e}", worst[0], worst[1], worst[2], worst[3]);
}

#[test]
fn exact_polyhedron_overlap_of_a_cube_corner_in_a_plane() {
    use discrete_contact::compute_overlap;
    // A unit cube standing on a corner: its body diagonal along y, the lowest corner δ below
    // the ground. The overlap is the corner tetrahedron: legs √3 δ, volume (√3/2) δ³, centroid
    // a quarter of its height below the ground, on the diagonal; chord along the normal δ.
    let tilt = Rotation::from_rotation_arc(Vector::new(1.0, 1.0, 1.0).normalize(), Vector::NEG_Y);
    let cube = ConvexShape::cuboid(Vector::splat(0.5)).unwrap();
    let ground = ConvexShape::half_space(Vector::Y).unwrap();
    let s = settings(8, IntegrationMode::Subcell).with_exact_polyhedra(true);
    for (k, delta) in [1e-6, 1e-3, 0.05, 0.3].into_iter().enumerate() {
        let spin = Rotation::from_rotation_y(0.7 * k as f64);
        let centre = Vector::new(0.3 * k as f64, 0.75f64.sqrt() - delta, -0.2);
        let pose = Pose::from_parts(centre, spin * tilt);
        let g = compute_overlap(&cube, &pose, &ground, &Pose::IDENTITY, &s, None)
            .unwrap()
            .expect("a corner in the ground");
        assert_relative_eq!(g.volume, 0.75f64.sqrt() * delta.powi(3), max_relative = 1e-9);
        assert_relative_eq!(g.indentation, delta, max_relative = 1e-9);
        assert!((g.normal - Vector::Y).length() < 1e-9, "normal {:?}", g.normal);
        let expected = Vector::new(centre.x, -0.25 * delta, centre.z);
        assert!(
            (g.contact_point - expected).length() < 1e-9 * delta,
            "point {:?} vs {expected:?}",
            g.contact_point
        );
        // Lifted clear of the ground: no overlap.
        let lifted = Pose::from_parts(centre + Vector::Y * 2.0 * delta, spin * tilt);
        assert!(compute_overlap(&cube, &lifted, &ground, &Pose::IDENTITY, &s, None)
            .unwrap()
            .is_none());
    }
}

/// A user SDF's face planes need not have unit normals: the exact overlap scales each plane
/// (the same half-space). A zero normal cannot be scaled: the pair goes to the grid.
#[test]
fn exact_polyhedra_take_a_user_sdfs_planes_at_any_scale_and_refuse_zero_ones_to_the_grid() {
    use discrete_contact::compute_overlap;
    use discrete_contact::parry3d_f64::bounding_volume::Aabb;
    struct Planes {
        cube: ConvexShape,
        scale: [f64; 6],
    }
    impl Sdf for Planes {
        fn distance(&self, p: Vector) -> f64 {
            self.cube.distance(p)
        }
        fn gradient(&self, p: Vector) -> Vector {
            self.cube.gradient(p)
        }
        fn local_bounds(&self) -> Aabb {
            self.cube.local_bounds()
        }
        fn face_planes(&self) -> Option<Vec<(Vector, f64)>> {
            let planes = self.cube.face_planes()?;
            Some(planes.into_iter().zip(self.scale).map(|((n, h), k)| (n * k, h * k)).collect())
        }
    }
    let cube = ConvexShape::cuboid(Vector::new(0.5, 0.4, 0.3)).unwrap();
    let pose_a = Pose::from_parts(
        Vector::new(0.1, 0.2, -0.1),
        Rotation::from_scaled_axis(Vector::new(0.3, -0.2, 0.5)),
    );
    let pose_b = Pose::from_parts(
        Vector::new(0.8, 0.5, 0.2),
        Rotation::from_scaled_axis(Vector::new(-0.4, 0.6, 0.1)),
    );
    let exact = settings(8, IntegrationMode::Subcell)
        .with_enlargement(0.01, 0.02)
        .unwrap()
        .with_exact_polyhedra(true);
    let reference = compute_overlap(&cube, &pose_a, &cube, &pose_b, &exact, None)
        .unwrap()
        .expect("the boxes overlap");
    let scaled = Planes { cube: cube.clone(), scale: [3.0, 0.2, 1.0, 7.5, 0.01, 2.0] };
    let g = compute_overlap(&scaled, &pose_a, &cube, &pose_b, &exact, None)
        .unwrap()
        .expect("the boxes overlap");
    assert_relative_eq!(g.volume, reference.volume, max_relative = 1e-12);
    assert!((g.contact_point - reference.contact_point).length() < 1e-12);
    assert!((g.normal - reference.normal).length() < 1e-12);
    assert_relative_eq!(g.indentation, reference.indentation, max_relative = 1e-12);
    // A zero plane: the grid's answer, not a wrong exact one.
    let zero = Planes { cube: cube.clone(), scale: [1.0, 1.0, 0.0, 1.0, 1.0, 1.0] };
    let grid = settings(8, IntegrationMode::Subcell).with_enlargement(0.01, 0.02).unwrap();
    let on_grid = compute_overlap(&zero, &pose_a, &cube, &pose_b, &grid, None).unwrap().unwrap();
    let g = compute_overlap(&zero, &pose_a, &cube, &pose_b, &exact, None).unwrap().unwrap();
    assert_eq!(g.volume, on_grid.volume);
    assert!(
        (g.volume / reference.volume - 1.0).abs() > 1e-9,
        "the grid differs from the exact volume"
    );
}

#[test]
fn exact_polyhedron_overlaps_match_the_fine_grid() {
    use discrete_contact::compute_overlap;
    let fine = settings(48, IntegrationMode::Subcell);
    let mut seed = 777u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let hull: Vec<Vector> = (0..12)
        .map(|k| {
            let a = 2.4 * k as f64;
            Vector::new(a.cos(), (0.9 * a).sin(), k as f64 / 5.5 - 1.0) * 0.6
        })
        .collect();
    let shapes = [
        ConvexShape::cuboid(Vector::new(0.5, 0.4, 0.3)).unwrap(),
        ConvexShape::convex_hull(&hull).unwrap(),
        ConvexShape::half_space(Vector::new(0.2, 1.0, -0.1)).unwrap(),
    ];
    let mut worst = [0.0f64; 4];
    for k in 0..12 {
        let a = &shapes[k % 2];
        let b = &shapes[[0, 1, 2][k % 3]];
        let rot = |r: &mut dyn FnMut() -> f64| {
            Rotation::from_axis_angle(
                Vector::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize(),
                6.0 * r(),
            )
        };
        let pose_b = Pose::from_parts(
            Vector::new(rnd(), rnd(), rnd()),
            if k % 3 == 2 { Rotation::IDENTITY } else { rot(&mut rnd) },
        );
        let rot_a = rot(&mut rnd);
        // Push A into B along a random direction until the overlap is a few per cent of A.
        let dir = Vector::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
        let mut t = 3.0;
        let base = pose_b.translation;
        while compute_overlap(
            a,
            &Pose::from_parts(base + dir * t, rot_a),
            b,
            &pose_b,
            &fine.with_exact_polyhedra(true),
            None,
        )
        .unwrap()
        .is_none_or(|g| g.indentation < 0.08 + 0.1 * rnd())
        {
            t -= 0.01;
        }
        let pose_a = Pose::from_parts(base + dir * t, rot_a);
        for swap in [false, true] {
            let (x, px, y, py) =
                if swap { (b, &pose_b, a, &pose_a) } else { (a, &pose_a, b, &pose_b) };
            let grid =
                compute_overlap(x, px, y, py, &fine, None).unwrap().expect("overlap on the grid");
            let exact = compute_overlap(x, px, y, py, &fine.with_exact_polyhedra(true), None)
                .unwrap()
                .expect("exact overlap");
            let errs = differences(&exact, &grid, &mut worst);
            assert!(
                errs[0] < 3e-3 && errs[1] < 1e-2 && errs[2] < 1e-2 && errs[3] < 1e-2,
                "pair {k} swap {swap}: {errs:?}"
            );
        }
    }
    println!("largest differences (volume, point / width, normal, indentation): {:.2e} {:.2e} {:.2e} {:.2e}", worst[0], worst[1], worst[2], worst[3]);
}

#[test]
fn exact_polyhedron_enlargement_moves_the_faces_out_sharp_vertices_included() {
    use discrete_contact::compute_overlap;
    // A square pyramid (half-width 0.05 at height 1), apex δ into the ground, both bodies
    // enlarged. Moving its faces out by ε_A moves the apex down by ε_A √(1 + 0.05²) / 0.05
    // (≈ 20 ε_A, far past the rounded enlargement's bounds, so the first clipping box is too
    // small and a larger one is taken); the ground rises by ε_B. The overlap is the tip of
    // the same slopes, depth H = δ + 20.025 ε_A + ε_B, volume (4/3) 0.05² H³.
    let pyramid = ConvexShape::convex_hull(&[
        Vector::ZERO,
        Vector::new(0.05, 1.0, 0.05),
        Vector::new(-0.05, 1.0, 0.05),
        Vector::new(0.05, 1.0, -0.05),
        Vector::new(-0.05, 1.0, -0.05),
    ])
    .unwrap();
    let ground = ConvexShape::half_space(Vector::Y).unwrap();
    for (delta, eps_a, eps_b) in
        [(0.01, 0.0, 0.0), (0.01, 2e-3, 0.0), (1e-4, 1e-3, 5e-4), (0.05, 4e-3, 1e-3)]
    {
        let s = settings(8, IntegrationMode::Subcell)
            .with_enlargement(eps_a, eps_b)
            .unwrap()
            .with_exact_polyhedra(true);
        let pose = Pose::from_translation(Vector::new(0.4, -delta, -0.3));
        let g = compute_overlap(&pyramid, &pose, &ground, &Pose::IDENTITY, &s, None)
            .unwrap()
            .expect("a tip in the ground");
        let depth = delta + eps_a * (1.0f64 + 0.05 * 0.05).sqrt() / 0.05 + eps_b;
        assert_relative_eq!(g.volume, 4.0 / 3.0 * 0.05 * 0.05 * depth.powi(3), max_relative = 1e-9);
        assert_relative_eq!(g.indentation, depth, max_relative = 1e-9);
        assert!((g.normal - Vector::Y).length() < 1e-9, "normal {:?}", g.normal);
        // The tip's centroid: a quarter of the depth below the (raised) ground, on the axis.
        let expected = Vector::new(0.4, eps_b - 0.25 * depth, -0.3);
        assert!(
            (g.contact_point - expected).length() < 1e-9,
            "point {:?} vs {expected:?}",
            g.contact_point
        );
    }
}
