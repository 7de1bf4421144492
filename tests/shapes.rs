//! SDFs are exact: checked against parry's own point projection (an independent
//! implementation) inside and outside, and gradients against finite differences.

use discrete_contact::parry3d_f64::math::Vector;
use discrete_contact::parry3d_f64::query::PointQuery;
use discrete_contact::parry3d_f64::shape::{
    Ball, Capsule, Cone, ConvexPolyhedron, Cuboid, Cylinder, RoundCuboid, Shape, SharedShape,
};
use discrete_contact::prelude::*;
use discrete_contact::Error;

/// A small deterministic generator (no test depends on a random seed it cannot reproduce).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn point(&mut self, scale: f64) -> Vector {
        Vector::new(self.next(), self.next(), self.next()) * scale
    }
}

/// An irregular convex polyhedron of six vertices.
fn test_hull() -> ConvexPolyhedron {
    ConvexPolyhedron::from_convex_hull(&[
        Vector::new(0.3, 0.0, 0.0),
        Vector::new(-0.2, 0.25, 0.1),
        Vector::new(-0.1, -0.2, 0.3),
        Vector::new(0.0, 0.1, -0.35),
        Vector::new(0.1, 0.3, 0.2),
        Vector::new(-0.25, -0.1, -0.2),
    ])
    .unwrap()
}

/// A box given by its corners, one corner raised by 3e-5 of the box's size: parry joins the
/// two triangles of that bent side into one face (their normals agree to within its
/// tolerance), so a distance taken from one face plane would be off by ~1e-5.
fn bent_box() -> ConvexPolyhedron {
    let mut corners: Vec<Vector> = (0..8)
        .map(|k| Vector::new([-0.3, 0.3][k & 1], [-0.2, 0.2][(k >> 1) & 1], [-0.1, 0.1][k >> 2]))
        .collect();
    corners[7].z += 3e-5;
    ConvexPolyhedron::from_convex_hull(&corners).unwrap()
}

fn parry_shapes() -> Vec<(&'static str, Box<dyn Shape>)> {
    let hull = test_hull();
    vec![
        ("ball", Box::new(Ball::new(0.3))),
        ("cuboid", Box::new(Cuboid::new(Vector::new(0.3, 0.2, 0.1)))),
        ("cylinder", Box::new(Cylinder::new(0.25, 0.15))),
        ("cone", Box::new(Cone::new(0.25, 0.2))),
        (
            "capsule",
            Box::new(Capsule::new(Vector::new(-0.1, -0.2, 0.0), Vector::new(0.2, 0.1, 0.05), 0.1)),
        ),
        ("polyhedron", Box::new(hull)),
        ("bent box", Box::new(bent_box())),
    ]
}

#[test]
fn distances_match_parry_inside_and_outside() {
    let mut rng = Lcg(7);
    for (name, shape) in parry_shapes() {
        let sdf = ConvexShape::from_parry(shape.as_ref()).unwrap();
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..4000 {
            let p = rng.point(0.5);
            let reference = shape.distance_to_local_point(p, false);
            let ours = sdf.distance(p);
            assert!(
                (ours - reference).abs() <= 1e-9,
                "{name} at {p:?}: {ours} vs parry {reference}"
            );
            if reference < 0.0 {
                inside += 1
            } else {
                outside += 1
            }
        }
        assert!(inside > 50 && outside > 50, "{name}: {inside} inside, {outside} outside");
    }
}

#[test]
fn rounded_shapes_are_the_inner_distance_minus_the_border() {
    let round = SharedShape::round_cuboid(0.2, 0.1, 0.15, 0.05);
    let sdf = ConvexShape::from_parry(round.as_ref()).unwrap();
    let inner = ConvexShape::cuboid(Vector::new(0.2, 0.1, 0.15)).unwrap();
    let rounded = round.as_round_cuboid().unwrap();
    let mut rng = Lcg(3);
    for _ in 0..1000 {
        let p = rng.point(0.4);
        assert!((sdf.distance(p) - (inner.distance(p) - 0.05)).abs() < 1e-12);
        // Outside, parry's (approximate) projection agrees.
        let d = sdf.distance(p);
        if d > 0.01 {
            let reference = rounded.distance_to_local_point(p, false);
            // parry projects onto round shapes with GJK, only to about 1e-5 (ours is exact).
            assert!((d - reference).abs() < 1e-4, "{d} vs {reference}");
        }
    }
    let _: &RoundCuboid = rounded;
}

#[test]
fn gradients_are_unit_outward_and_match_finite_differences() {
    let mut rng = Lcg(11);
    for (name, shape) in parry_shapes() {
        let sdf = ConvexShape::from_parry(shape.as_ref()).unwrap();
        for _ in 0..500 {
            let p = rng.point(0.5);
            let g = sdf.gradient(p);
            assert!((g.length() - 1.0).abs() < 1e-9, "{name}: |grad| = {}", g.length());
            let h = 1e-7;
            let fd = Vector::new(
                sdf.distance(p + Vector::X * h) - sdf.distance(p - Vector::X * h),
                sdf.distance(p + Vector::Y * h) - sdf.distance(p - Vector::Y * h),
                sdf.distance(p + Vector::Z * h) - sdf.distance(p - Vector::Z * h),
            ) / (2.0 * h);
            // Away from the medial surface (where the gradient jumps), they agree.
            if (fd.length() - 1.0).abs() < 1e-4 {
                assert!((fd - g).length() < 1e-4, "{name} at {p:?}: {g:?} vs {fd:?}");
            }
        }
    }
}

#[test]
fn half_space_and_custom_sdfs() {
    let hs = ConvexShape::half_space(Vector::new(0.0, 2.0, 0.0)).unwrap();
    assert_eq!(hs.distance(Vector::new(5.0, -0.25, 3.0)), -0.25);
    let custom = ConvexShape::custom(
        |p: Vector| p.length() - 0.3,
        discrete_contact::parry3d_f64::bounding_volume::Aabb::new(
            Vector::splat(-0.3),
            Vector::splat(0.3),
        ),
    )
    .unwrap();
    let ball = ConvexShape::ball(0.3).unwrap();
    // The same contact from a closure and from the built-in ball, against the exact cap. The
    // closure may have edges for all the grid knows (`Sdf::has_edges`), so its cells the
    // sphere's curvature bends are clipped by tangent planes (an outer bound), the ball's are
    // interpolated (an inner one): both within the N_c = 8 grid's error of the cap's volume
    // (measured +0.57 % and −1.29 %), on either side of it, both normals within 1e-4 of the floor's.
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = Material::new(1e9, 0.3).unwrap();
    let model = ContactModel::new(
        PairParameters::new(&m, &m, 0.9).unwrap(),
        OverlapSettings::new(8, IntegrationMode::Subcell).unwrap(),
    );
    let pose = Pose::from_translation(Vector::new(0.0, 0.29, 0.0));
    let w = BodyState::at_rest(&floor, Pose::IDENTITY);
    let a = model.evaluate(&BodyState::at_rest(&custom, pose), &w, &mut None).unwrap().unwrap();
    let b = model.evaluate(&BodyState::at_rest(&ball, pose), &w, &mut None).unwrap().unwrap();
    let d: f64 = 0.01;
    let cap = std::f64::consts::PI * d * d * (3.0 * 0.3 - d) / 3.0;
    let (ea, eb) = (a.geometry.volume / cap - 1.0, b.geometry.volume / cap - 1.0);
    assert!(
        ea > 0.0 && ea < 0.01 && eb < 0.0 && eb > -0.015,
        "closure {ea:+e}, ball {eb:+e} against the cap"
    );
    let tilt = [a.geometry.normal, b.geometry.normal].map(|n| (n - Vector::Y).length());
    assert!(tilt[0] < 1e-4 && tilt[1] < 1e-4, "normals tilted by {tilt:?}");
}

#[test]
fn non_convex_parry_shapes_are_refused() {
    let mesh = SharedShape::trimesh(
        vec![Vector::ZERO, Vector::X, Vector::Y, Vector::Z],
        vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
    )
    .unwrap();
    assert!(matches!(ConvexShape::from_parry(mesh.as_ref()), Err(Error::UnsupportedShape { .. })));
    let compound = SharedShape::compound(vec![(Pose::IDENTITY, SharedShape::ball(1.0))]);
    assert!(matches!(
        ConvexShape::from_parry(compound.as_ref()),
        Err(Error::UnsupportedShape { .. })
    ));
}

/// Brute force: the distance to the surface is the smallest exact point–triangle distance over
/// the shape's triangulated surface; inside or outside from parry's containment test. Exact for
/// the polyhedron and the cuboid; the cylinder's 512-gon sits within `R (1 - cos(π/512))`.
#[test]
fn distances_match_brute_force_over_the_surface() {
    use discrete_contact::parry3d_f64::shape::Triangle;
    let hull = test_hull();
    let cuboid = Cuboid::new(Vector::new(0.3, 0.2, 0.1));
    let cylinder = Cylinder::new(0.25, 0.15);
    type Mesh = (Vec<Vector>, Vec<[u32; 3]>);
    // A rock (twelve points near a sphere, triangular faces) and a box given by its corners
    // (quadrilateral faces): the hull distance's face, edge and vertex regions.
    let mut points = Lcg(11);
    let rock_points: Vec<Vector> =
        (0..12).map(|_| points.point(1.0).normalize() * (0.25 + 0.1 * points.next())).collect();
    let rock = ConvexPolyhedron::from_convex_hull(&rock_points).unwrap();
    let corners: Vec<Vector> = (0..8)
        .map(|k| Vector::new([-0.3, 0.3][k & 1], [-0.2, 0.2][(k >> 1) & 1], [-0.1, 0.1][k >> 2]))
        .collect();
    let box_hull = ConvexPolyhedron::from_convex_hull(&corners).unwrap();
    let cases: Vec<(&str, &dyn Shape, Mesh, f64)> = vec![
        ("polyhedron", &hull, hull.to_trimesh(), 1e-12),
        ("rock", &rock, rock.to_trimesh(), 1e-12),
        ("box hull", &box_hull, box_hull.to_trimesh(), 1e-12),
        ("cuboid", &cuboid, cuboid.to_trimesh(), 1e-12),
        (
            "cylinder",
            &cylinder,
            cylinder.to_trimesh(512),
            0.15 * (1.0 - (std::f64::consts::PI / 512.0).cos()) + 1e-12,
        ),
    ];
    let mut rng = Lcg(5);
    for (name, shape, (pts, tris), tol) in cases {
        let sdf = ConvexShape::from_parry(shape).unwrap();
        for _ in 0..2000 {
            let p = rng.point(0.45);
            let unsigned = tris
                .iter()
                .map(|t| {
                    Triangle::new(pts[t[0] as usize], pts[t[1] as usize], pts[t[2] as usize])
                        .distance_to_local_point(p, false)
                })
                .fold(f64::INFINITY, f64::min);
            let brute = if shape.contains_local_point(p) { -unsigned } else { unsigned };
            let ours = sdf.distance(p);
            assert!((ours - brute).abs() <= tol, "{name} at {p:?}: {ours} vs brute force {brute}");
        }
    }
}

/// The closed-form surface crossings (ball, half-space and capsule, also dilated; cuboid, cylinder and
/// polyhedron undilated) equal the root of the distance function along the segment — found
/// here by 200 bisections — for segments from inside to outside and back.
#[test]
fn closed_form_crossings_equal_the_distance_functions_root() {
    let hull: Vec<Vector> = {
        let mut g = Lcg(7);
        (0..20).map(|_| g.point(0.3)).collect()
    };
    let shapes = [
        (ConvexShape::ball(0.3).unwrap(), vec![0.0, 0.02]),
        (ConvexShape::half_space(Vector::new(0.3, 1.0, -0.2)).unwrap(), vec![0.0, 0.02]),
        (ConvexShape::cuboid(Vector::new(0.3, 0.1, 0.2)).unwrap(), vec![0.0]),
        (ConvexShape::cylinder(0.2, 0.15).unwrap(), vec![0.0]),
        (ConvexShape::convex_hull(&hull).unwrap(), vec![0.0]),
        (
            ConvexShape::capsule(Vector::new(-0.2, 0.05, 0.0), Vector::new(0.15, -0.1, 0.1), 0.12)
                .unwrap(),
            vec![0.0, 0.02],
        ),
    ];
    // Compares the closed form with bisection on one segment; false when it does not cross.
    let check = |shape: &ConvexShape, eps: f64, p: Vector, q: Vector| -> bool {
        let d = |x: Vector| shape.distance(x) - eps;
        let (dp, dq) = (d(p), d(q));
        if dp == 0.0 || dq == 0.0 || (dp < 0.0) == (dq < 0.0) {
            return false;
        }
        // The contract: called from the inside end; the fraction is from that end.
        let t = if dp < 0.0 {
            shape.segment_crossing(p, q, eps).expect("a closed form for this shape")
        } else {
            1.0 - shape.segment_crossing(q, p, eps).expect("a closed form for this shape")
        };
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if (d(p + (q - p) * mid) < 0.0) == (dp < 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        assert!(
            (t - lo).abs() * (q - p).length() < 1e-12,
            "{shape:?} ε = {eps}, {p:?} → {q:?}: {t} vs {lo}"
        );
        true
    };
    let mut g = Lcg(11);
    let mut checked = 0;
    for (shape, offsets) in &shapes {
        for &eps in offsets {
            for _ in 0..2000 {
                checked += check(shape, eps, g.point(0.4), g.point(0.4)) as usize;
            }
        }
    }
    assert!(checked > 4000, "{checked} segments checked");
    // Segments at right angles to a capsule's axis (the projection onto the axis constant):
    // from its middle, from inside a cap, both ways.
    let (a, b) = (Vector::new(-0.2, 0.0, 0.0), Vector::new(0.2, 0.0, 0.0));
    let capsule = ConvexShape::capsule(a, b, 0.1).unwrap();
    for p in [Vector::ZERO, a - Vector::new(0.05, 0.0, 0.0), b + Vector::new(0.03, 0.01, 0.0)] {
        let q = p + Vector::new(0.0, 0.3, 0.1);
        assert!(
            check(&capsule, 0.0, p, q) && check(&capsule, 0.0, q, p) && check(&capsule, 0.02, p, q)
        );
    }
    // No closed form: the cone, a dilated cuboid.
    assert!(ConvexShape::cone(0.2, 0.1)
        .unwrap()
        .segment_crossing(Vector::ZERO, Vector::X, 0.0)
        .is_none());
    assert!(ConvexShape::cuboid(Vector::splat(0.1))
        .unwrap()
        .segment_crossing(Vector::ZERO, Vector::X, 0.01)
        .is_none());
}

/// Each built-in shape's bounding sphere holds the whole body and touches it: over 4000
/// directions, parry's support points (the body's extreme points) lie inside the sphere and
/// the farthest reaches its surface (a sphere round the bounding box, √3 times a ball's
/// radius, would fail that). The contact candidates and sub-step estimates rest on it.
#[test]
fn bounding_spheres_enclose_the_body_and_touch_it() {
    let mut rng = Lcg(11);
    let round = SharedShape::round_cuboid(0.2, 0.1, 0.05, 0.03);
    let mut shapes = parry_shapes();
    shapes.push(("round cuboid", Box::new(*round.as_round_cuboid().unwrap())));
    for (name, shape) in shapes {
        let sdf = ConvexShape::from_parry(shape.as_ref()).unwrap();
        let (centre, radius) = sdf.bounding_sphere();
        let support = shape.as_support_map().expect("a support-mapped shape");
        let mut farthest: f64 = 0.0;
        for _ in 0..4000 {
            let u = rng.point(1.0).normalize_or_zero();
            if u == Vector::ZERO {
                continue;
            }
            let s = support.local_support_point(u);
            let reach = (s - centre).length();
            assert!(
                reach <= radius * (1.0 + 1e-12),
                "{name}: extreme point {s:?} at {reach} outside the radius {radius}"
            );
            farthest = farthest.max(reach);
        }
        assert!(
            farthest >= radius * (1.0 - 1e-3),
            "{name}: radius {radius}, the body reaches only {farthest}"
        );
    }
}

/// A cone is its infinite cone cut by its base, and a rounded cuboid its own rounded body with
/// its faces moved out: in both the flat faces and the smooth part bound exactly the body its
/// distance describes, the smooth part's distance is exact (a unit gradient, and the point it
/// leads to lies on its surface), and each flat face touches the body (the body reaches it).
#[test]
fn a_cone_and_a_rounded_cuboid_are_a_smooth_part_cut_by_flat_faces() {
    let cone = ConvexShape::cone(0.3, 0.2).unwrap();
    let cuboid = ConvexShape::cuboid(Vector::new(0.3, 0.2, 0.1)).unwrap();
    let rounded = ConvexShape::rounded(cuboid, 0.05).unwrap();
    for (name, shape, faces) in [("cone", &cone, 1), ("rounded cuboid", &rounded, 6)] {
        let flats = shape.flat_faces().expect("flat faces");
        assert_eq!(flats.len(), faces, "{name}");
        let mut rng = Lcg(11);
        let mut reach = vec![Real::NEG_INFINITY; flats.len()];
        for _ in 0..20000 {
            let p = rng.point(0.6);
            let (d, g) = shape.smooth_part(p);
            assert!((g.length() - 1.0).abs() < 1e-12, "{name} at {p:?}: gradient {g:?}");
            let foot = p - g * d;
            assert!(shape.smooth_part(foot).0.abs() < 1e-12, "{name}: {p:?} leads off the surface");
            let inside = d <= 0.0 && flats.iter().all(|&(n, h)| n.dot(p) <= h);
            assert_eq!(inside, shape.distance(p) <= 0.0, "{name} at {p:?}");
            if shape.distance(p) <= 0.0 {
                for (r, &(n, h)) in reach.iter_mut().zip(&flats) {
                    *r = r.max(n.dot(p) - h);
                }
            }
        }
        // Sampled interior points come within a few per cent of the body's size of each face.
        assert!(reach.iter().all(|&r| r > -0.03), "{name}: a face the body does not reach");
    }
}

/// A cylinder's flat faces and its smooth part bound exactly the body its distance describes:
/// a point is inside the cylinder when it is inside the infinite round cylinder and below
/// both caps, and the smooth part's distance is the distance to that round side.
#[test]
fn a_cylinder_is_its_round_side_cut_by_its_caps() {
    let (half_height, radius) = (0.3, 0.2);
    let cylinder = ConvexShape::cylinder(half_height, radius).unwrap();
    let caps = cylinder.flat_faces().expect("a cylinder has flat faces");
    assert_eq!(caps.len(), 2);
    let mut rng = Lcg(7);
    for _ in 0..4000 {
        let p = rng.point(0.5);
        let (d, g) = cylinder.smooth_part(p);
        let radial = (p.x * p.x + p.z * p.z).sqrt();
        assert!((d - (radial - radius)).abs() < 1e-15);
        assert!((g - Vector::new(p.x, 0.0, p.z) / radial).length() < 1e-12);
        let inside = d <= 0.0 && caps.iter().all(|&(n, h)| n.dot(p) <= h);
        assert_eq!(inside, cylinder.distance(p) <= 0.0, "at {p:?}");
    }
    assert!(ConvexShape::ball(1.0).unwrap().flat_faces().is_none());
}
