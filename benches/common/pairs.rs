//! The three contact pairs the `contact` bench times and the `contact_profile` example loops
//! over: two touching spheres, a tilted cylinder on a plane, two cubes, each overlapping.

use discrete_contact::prelude::*;

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
            "cube_cube",
            ConvexShape::cuboid(Vector::splat(0.005)).unwrap(),
            Pose::from_parts(Vector::new(0.001, 0.0098, 0.0), Rotation::from_rotation_y(0.3)),
            ConvexShape::cuboid(Vector::splat(0.005)).unwrap(),
            Pose::IDENTITY,
        ),
    ]
}
