//! Random polyhedral pairs with a known overlap: boxes of random aspect ratio and convex hulls
//! of twelve points (rocks), at random orientations, pressed together along a random direction
//! until the exact polyhedral overlap (`OverlapSettings::with_exact_polyhedra`) has a random
//! volume of (1–10 % of the smaller body's size)³ × 8 × its volume. Shared by the
//! `polyhedra_grid` test and the `polyhedra_check` example.

use discrete_contact::prelude::*;
use discrete_contact::{compute_overlap, OverlapGeometry};

/// xorshift64: a fixed, portable sequence of cases.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform on [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniformly random rotation (Shoemake's method).
    pub fn rotation(&mut self) -> Rotation {
        let (u1, u2, u3) = (self.next(), self.next(), self.next());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let t = std::f64::consts::TAU;
        Rotation::from_xyzw(
            a * (t * u2).sin(),
            a * (t * u2).cos(),
            b * (t * u3).sin(),
            b * (t * u3).cos(),
        )
        .normalize()
    }

    /// A box (even `k`) with half extents 0.2–0.5, or the hull of twelve points 0.25–0.5 from
    /// its centre in random directions; and its volume.
    fn body(&mut self, k: usize) -> (ConvexShape, f64) {
        if k % 2 == 0 {
            let h = Vector::new(
                0.2 + 0.3 * self.next(),
                0.2 + 0.3 * self.next(),
                0.2 + 0.3 * self.next(),
            );
            (ConvexShape::cuboid(h).unwrap(), 8.0 * h.element_product())
        } else {
            let points: Vec<Vector> = (0..12)
                .map(|_| {
                    let (z, phi) = (2.0 * self.next() - 1.0, std::f64::consts::TAU * self.next());
                    let s = (1.0 - z * z).sqrt();
                    Vector::new(s * phi.cos(), s * phi.sin(), z) * (0.25 + 0.25 * self.next())
                })
                .collect();
            let shape = ConvexShape::convex_hull(&points).unwrap();
            let r = 0.25f64;
            (shape, 4.0 / 3.0 * std::f64::consts::PI * r * r * r)
        }
    }
}

/// One pair and its exact overlap.
pub struct Case {
    pub a: ConvexShape,
    pub pose_a: Pose,
    pub b: ConvexShape,
    pub pose_b: Pose,
    pub exact: OverlapGeometry,
}

/// Case `k` of the sequence: boxes for even `k`, hulls for odd.
pub fn case(rng: &mut Rng, k: usize) -> Case {
    let exact_settings =
        OverlapSettings::new(8, IntegrationMode::Subcell).unwrap().with_exact_polyhedra(true);
    let ((a, va), (b, vb)) = (rng.body(k), rng.body(k));
    let pose_a = Pose::from_parts(Vector::ZERO, rng.rotation());
    let rb = rng.rotation();
    let dir = Vector::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5).normalize();
    let target = (0.01 + 0.09 * rng.next()).powi(3) * va.min(vb);
    let at = |s: f64| Pose::from_parts(dir * s, rb);
    let volume = |s: f64| {
        compute_overlap(&a, &pose_a, &b, &at(s), &exact_settings, None)
            .unwrap()
            .map_or(0.0, |g| g.volume)
    };
    // Bisection on the centre distance for the target volume.
    let (mut lo, mut hi) = (0.0, 2.0);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if volume(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let pose_b = at(lo);
    let exact = compute_overlap(&a, &pose_a, &b, &pose_b, &exact_settings, None)
        .unwrap()
        .expect("overlaps at the bisected depth");
    Case { a, pose_a, b, pose_b, exact }
}

/// Relative volume error and centroid error (per the exact overlap box's diagonal) of `g`
/// against the case's exact overlap.
pub fn errors(case: &Case, g: &OverlapGeometry) -> (f64, f64) {
    let e = &case.exact;
    let size = (e.corrected_box.maxs - e.corrected_box.mins).length();
    ((g.volume - e.volume) / e.volume, (g.contact_point - e.contact_point).length() / size)
}

/// Relative surface-area error and the angle (rad) between `g`'s normal and the exact one.
#[allow(dead_code)]
pub fn facet_errors(case: &Case, g: &OverlapGeometry) -> (f64, f64) {
    let e = &case.exact;
    let angle = g.normal.cross(e.normal).length().atan2(g.normal.dot(e.normal));
    ((g.surface_area - e.surface_area) / e.surface_area, angle)
}
