//! The contact pairs the `contact` bench times and the `contact_profile` example loops over:
//! two touching spheres, a tilted cylinder on a plane, two cylinders crossed on their curved
//! sides (the `drop_in` scene's costliest kind of pair), two cubes, two rocks (convex hulls of
//! twelve points, as in the `drop_in` scene) and a capsule across a cylinder, each overlapping.

use core::f64::consts::FRAC_PI_2;

use discrete_contact::prelude::*;
use discrete_contact_validation::drop_in::{rock_points, xorshift};

/// A rock of radius ~`r` as in the `drop_in` scene, from the xorshift sequence of `seed`.
fn rock(r: Real, seed: u64) -> ConvexShape {
    let points = rock_points(r, &mut xorshift(seed));
    ConvexShape::convex_hull(&points).expect("twelve points in general position")
}

/// `(name, shape A, pose A, shape B, pose B)` of each pair.
pub fn pairs() -> Vec<(&'static str, ConvexShape, Pose, ConvexShape, Pose)> {
    let tilt = Rotation::from_axis_angle(Vector::new(1.0, 0.0, 1.0).normalize(), 0.4);
    vec![
        (
            "sphere_sphere",
            ConvexShape::ball(0.01).unwrap(),
            Pose::from_translation(Vector::new(0.001, 0.0198, 0.0)),
            ConvexShape::ball(0.01).unwrap(),
            Pose::IDENTITY,
        ),
        (
            "cylinder_plane",
            ConvexShape::cylinder(0.00265, 0.004).unwrap(),
            Pose::from_parts(Vector::new(0.0, 0.0039, 0.0), tilt),
            ConvexShape::half_space(Vector::Y).unwrap(),
            Pose::IDENTITY,
        ),
        (
            "cylinder_cylinder",
            ConvexShape::cylinder(0.01, 0.005).unwrap(),
            Pose::from_parts(Vector::new(0.0, 0.0099, 0.0), Rotation::from_rotation_z(FRAC_PI_2)),
            ConvexShape::cylinder(0.01, 0.005).unwrap(),
            Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(FRAC_PI_2)),
        ),
        (
            "cube_cube",
            ConvexShape::cuboid(Vector::splat(0.005)).unwrap(),
            Pose::from_parts(Vector::new(0.001, 0.0098, 0.0), Rotation::from_rotation_y(0.3)),
            ConvexShape::cuboid(Vector::splat(0.005)).unwrap(),
            Pose::IDENTITY,
        ),
        (
            "hull_hull",
            rock(0.005, 0x9E37_79B9_7F4A_7C15),
            Pose::from_parts(Vector::new(0.001, 0.0085, 0.0), tilt),
            rock(0.005, 0x2545_F491_4F6C_DD1D),
            Pose::IDENTITY,
        ),
        (
            "capsule_cylinder",
            ConvexShape::capsule(
                Vector::new(-0.004, 0.0, 0.0),
                Vector::new(0.004, 0.0, 0.0),
                0.002,
            )
            .unwrap(),
            Pose::from_parts(Vector::new(0.0, 0.0058, 0.0), Rotation::from_rotation_y(0.5)),
            ConvexShape::cylinder(0.004, 0.004).unwrap(),
            Pose::IDENTITY,
        ),
    ]
}
