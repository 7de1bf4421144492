//! Triangle meshes and height fields as walls of the drop-in: a flat mesh is its plane to the
//! bodies on it — resting across an edge or a vertex, rolling over its triangles, struck — and
//! what has no solid side, or moves under forces, is refused by name.
#![cfg(feature = "rapier")]

use discrete_contact::rapier::DiscreteContacts;
use discrete_contact::rapier3d_f64::prelude::*;
use discrete_contact::{Error, IntegrationMode, Material, OverlapSettings};

type V = discrete_contact::math::Vector;

const RADIUS: f64 = 0.05;
const DENSITY: f64 = 1000.0;

/// A flat square mesh in the plane `y = 0`, `n` × `n` quads of side `cell` from the origin's
/// corner `-n cell / 2`, each quad split along its diagonal; triangles facing up.
fn flat_mesh(n: u32, cell: f64) -> (Vec<V>, Vec<[u32; 3]>) {
    let half = 0.5 * n as f64 * cell;
    let mut vertices = Vec::new();
    for i in 0..=n {
        for k in 0..=n {
            vertices.push(V::new(i as f64 * cell - half, 0.0, k as f64 * cell - half));
        }
    }
    let at = |i: u32, k: u32| i * (n + 1) + k;
    let mut indices = Vec::new();
    for i in 0..n {
        for k in 0..n {
            // Counter-clockwise seen from +y: x then z turns clockwise, so z first.
            indices.push([at(i, k), at(i, k + 1), at(i + 1, k + 1)]);
            indices.push([at(i, k), at(i + 1, k + 1), at(i + 1, k)]);
        }
    }
    (vertices, indices)
}

/// What the floor of a scene is.
#[derive(Clone, Copy, Debug)]
enum Floor {
    /// The half-space `y <= 0`.
    Plane,
    /// [`flat_mesh`] of `n` quads of side `cell`.
    Mesh { n: u32, cell: f64 },
    /// A flat height field of `n` × `n` quads over a square of side `side`.
    HeightField { n: usize, side: f64 },
}

/// A rapier scene as a user builds it (60 Hz steps, `length_unit` the ball's size): one ball of
/// radius [`RADIUS`] at `centre` with velocity `linvel` and spin `angvel` over `floor`, all
/// handled with `material`, restitution `e` and `friction`. Returns the world, the contacts,
/// the ball's body and the floor's collider.
fn scene(
    floor: Floor,
    centre: V,
    (linvel, angvel): (V, V),
    material: Material,
    e: f64,
    friction: Option<discrete_contact::Friction>,
) -> (PhysicsWorld, DiscreteContacts, RigidBodyHandle, ColliderHandle) {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    world.integration_parameters.length_unit = 2.0 * RADIUS;
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let collider = match floor {
        Floor::Plane => ColliderBuilder::new(SharedShape::halfspace(V::Y)),
        Floor::Mesh { n, cell } => {
            let (vertices, indices) = flat_mesh(n, cell);
            ColliderBuilder::trimesh(vertices, indices).unwrap()
        }
        Floor::HeightField { n, side } => ColliderBuilder::heightfield(
            discrete_contact::parry3d_f64::utils::Array2::zeros(n + 1, n + 1),
            V::new(side, 1.0, side),
        ),
    };
    let floor_collider = world.insert_collider(collider, Some(ground));
    let ball = world
        .insert_body(RigidBodyBuilder::dynamic().translation(centre).linvel(linvel).angvel(angvel));
    world.insert_collider(ColliderBuilder::ball(RADIUS).density(DENSITY), Some(ball));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), e)
            .unwrap();
    if let Some(f) = friction {
        contacts = contacts.with_friction(f);
    }
    let left = contacts.handle_all(&mut world, material).unwrap();
    assert!(left.is_empty(), "colliders left to rapier: {left:?}");
    (world, contacts, ball, floor_collider)
}

fn weight() -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3) * DENSITY * 9.81
}

/// A ball set down on a flat mesh across a diagonal edge, on a vertex where six triangles meet,
/// and inside a triangle, and on a flat height field: once at rest its contact carries its
/// weight within 1 % and its indentation is the plane's within 1 %.
#[test]
fn a_ball_at_rest_on_a_flat_mesh_feels_the_planes_force_across_edges_and_vertices() {
    let material = Material::new(1e7, 0.3).unwrap();
    let rest = |floor: Floor, x: V| {
        let (mut world, mut contacts, ball, floor_collider) =
            scene(floor, x + V::Y * RADIUS, (V::ZERO, V::ZERO), material, 0.5, None);
        for _ in 0..120 {
            contacts.step(&mut world).unwrap_or_else(|e| panic!("{floor:?} at {x:?}: {e}"));
        }
        let c = contacts
            .contacts_with(floor_collider)
            .next()
            .unwrap_or_else(|| panic!("{floor:?} at {x:?}: no contact"));
        let on_ball = if c.colliders.0 == floor_collider { -c.force_on_a } else { c.force_on_a };
        let b = &world.bodies[ball];
        assert!(b.linvel().length() < 1e-3, "{floor:?} at {x:?}: not at rest {:?}", b.linvel());
        (on_ball, c.indentation, b.translation())
    };
    let (_, plane_depth, _) = rest(Floor::Plane, V::ZERO);
    let mesh = Floor::Mesh { n: 4, cell: 0.1 };
    // A diagonal edge (x = z within a quad), a vertex (six triangles meet at the origin), the
    // middle of a triangle; a height field's vertex.
    for (floor, x) in [
        (mesh, V::new(0.025, 0.0, 0.025)),
        (mesh, V::ZERO),
        (mesh, V::new(0.07, 0.0, 0.02)),
        (Floor::HeightField { n: 4, side: 0.4 }, V::ZERO),
    ] {
        let (force, depth, at) = rest(floor, x);
        assert!((force.y / weight() - 1.0).abs() < 0.01, "{floor:?} at {x:?}: force {force:?}");
        assert!(force.x.hypot(force.z) < 1e-3 * weight(), "{floor:?} at {x:?}: {force:?}");
        assert!((depth / plane_depth - 1.0).abs() < 0.01, "{floor:?}: {depth} vs {plane_depth}");
        assert!((at.x - x.x).hypot(at.z - x.z) < 1e-6, "{floor:?}: drifted to {at:?}");
    }
}

/// A ball rolling without slipping over a flat mesh's triangles (crossing a dozen edges and
/// vertices) keeps the speed it keeps on the plane within 1 %, and stays on the plane's height:
/// no bumps at the edges.
#[test]
fn a_ball_rolling_over_a_flat_mesh_keeps_the_planes_speed() {
    let material = Material::new(1e7, 0.3).unwrap();
    let friction = discrete_contact::Friction::new(0.5, 0.4, 1e-3).unwrap();
    let v = 0.6;
    let roll = |floor: Floor| {
        let start = V::new(-0.45, RADIUS - 1e-4, 0.013);
        let motion = (V::new(v, 0.0, 0.1 * v), V::new(0.1 * v / RADIUS, 0.0, -v / RADIUS));
        let (mut world, mut contacts, ball, _) =
            scene(floor, start, motion, material, 0.5, Some(friction));
        let mut lowest = f64::INFINITY;
        let mut highest = f64::NEG_INFINITY;
        for k in 0..90 {
            contacts.step(&mut world).unwrap();
            if k >= 30 {
                let y = world.bodies[ball].translation().y;
                (lowest, highest) = (lowest.min(y), highest.max(y));
            }
        }
        let b = &world.bodies[ball];
        (b.linvel(), b.translation(), lowest, highest)
    };
    let (v_plane, x_plane, low_plane, high_plane) = roll(Floor::Plane);
    let (v_mesh, x_mesh, low_mesh, high_mesh) = roll(Floor::Mesh { n: 20, cell: 0.05 });
    assert!(x_plane.x > 0.3, "the ball rolled across the mesh: {x_plane:?}");
    assert!(
        (v_mesh - v_plane).length() < 0.01 * v_plane.length(),
        "mesh {v_mesh:?} against plane {v_plane:?}"
    );
    assert!((x_mesh - x_plane).length() < 0.01 * 0.75, "{x_mesh:?} against {x_plane:?}");
    // The plane's own height wobble, and no more on the mesh.
    let wobble = (high_plane - low_plane).max(1e-7);
    assert!(high_mesh - low_mesh < 2.0 * wobble + 1e-7, "heights {low_mesh}..{high_mesh}");
    assert!((low_mesh - low_plane).abs() < 1e-6, "{low_mesh} against {low_plane}");
}

/// A ball dropped at 1 m/s onto a mesh — on an edge, and on a vertex — rebounds as from the
/// plane: its rebound velocity within 1 % of the plane's, straight up.
#[test]
fn an_impact_on_a_mesh_rebounds_as_on_the_plane() {
    let material = Material::new(1e8, 0.3).unwrap();
    let bounce = |floor: Floor, x: V| {
        let (mut world, mut contacts, ball, _) = scene(
            floor,
            x + V::Y * (RADIUS + 0.005),
            (V::new(0.0, -1.0, 0.0), V::ZERO),
            material,
            0.7,
            None,
        );
        world.gravity = V::ZERO;
        for _ in 0..6 {
            contacts.step(&mut world).unwrap();
        }
        world.bodies[ball].linvel()
    };
    let plane = bounce(Floor::Plane, V::ZERO);
    assert!(plane.y > 0.5, "the plane's rebound {plane:?}");
    let mesh = Floor::Mesh { n: 4, cell: 0.1 };
    for x in [V::new(0.025, 0.0, 0.025), V::ZERO, V::new(0.07, 0.0, 0.02)] {
        let v = bounce(mesh, x);
        assert!((v - plane).length() < 0.01 * plane.y, "at {x:?}: {v:?} against {plane:?}");
    }
}

/// What the drop-in cannot take as a wall is refused with its shape named: a mesh on a dynamic
/// body (a wall does not move under forces), and triangles that have no solid side (an edge
/// shared by three triangles).
#[test]
fn meshes_that_cannot_be_walls_are_refused_by_name() {
    let mut world = PhysicsWorld::new();
    let (vertices, indices) = flat_mesh(2, 0.1);
    let body = world.insert_body(RigidBodyBuilder::dynamic());
    let moving = world.insert_collider(
        ColliderBuilder::trimesh(vertices.clone(), indices.clone()).unwrap(),
        Some(body),
    );
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    let material = Material::new(1e7, 0.3).unwrap();
    let refused = contacts.handle(&mut world, moving, material);
    assert!(
        matches!(&refused, Err(Error::UnsupportedShape { shape, why })
            if shape == "TriMesh" && why.contains("dynamic")),
        "{refused:?}"
    );
    // A fin: a third triangle on the edge two triangles share.
    let fin = vec![V::ZERO, V::X, V::Z, V::new(1.0, 0.0, 1.0), V::new(0.5, 1.0, 0.5)];
    let fin_indices = vec![[0, 2, 3], [0, 3, 1], [0, 3, 4]];
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let collider =
        world.insert_collider(ColliderBuilder::trimesh(fin, fin_indices).unwrap(), Some(ground));
    let refused = contacts.handle(&mut world, collider, material);
    assert!(
        matches!(&refused, Err(Error::UnsupportedShape { shape, why })
            if shape == "TriMesh" && why.contains("manifold")),
        "{refused:?}"
    );
}

/// The f32 drop-in takes the same walls: a ball set down on an f32 triangle mesh across its
/// diagonal edge carries its weight within 1 % once at rest.
#[cfg(feature = "rapier-f32")]
#[test]
fn the_f32_drop_in_takes_a_mesh_as_a_wall() {
    use discrete_contact::rapier3d::prelude::*;
    use discrete_contact::rapier_f32::DiscreteContacts;
    type V32 = discrete_contact::rapier3d::math::Vector;
    let (vertices, indices) = flat_mesh(4, 0.1);
    let vertices = vertices.iter().map(|v| V32::new(v.x as f32, v.y as f32, v.z as f32)).collect();
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    world.integration_parameters.length_unit = 2.0 * RADIUS as f32;
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let floor =
        world.insert_collider(ColliderBuilder::trimesh(vertices, indices).unwrap(), Some(ground));
    let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(V32::new(
        0.025,
        RADIUS as f32,
        0.025,
    )));
    world.insert_collider(ColliderBuilder::ball(RADIUS as f32).density(DENSITY as f32), Some(ball));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    let left = contacts.handle_all(&mut world, Material::new(1e7, 0.3).unwrap()).unwrap();
    assert!(left.is_empty(), "{left:?}");
    for _ in 0..120 {
        contacts.step(&mut world).unwrap();
    }
    let c = contacts.contacts_with(floor).next().expect("resting on the mesh");
    let on_ball = if c.colliders.0 == floor { -c.force_on_a } else { c.force_on_a };
    assert!((on_ball.y / weight() - 1.0).abs() < 0.01, "force {on_ball:?}");
}

/// The inside of a hollow body as a wall: a closed cubic room (side 0.4 m) whose triangles face
/// inwards is the solid around it, and a ball set on its floor rests there carrying its weight
/// within 1 %. (Before the cutting planes of a mesh were checked
/// against its faces, a wall's plane cut the floor's overlap away and the ball fell through.)
#[test]
fn a_ball_rests_and_stays_inside_a_closed_mesh_facing_inwards() {
    let half = 0.2;
    let corners: Vec<V> = (0..8)
        .map(|k| {
            V::new(
                if k & 1 == 0 { -half } else { half },
                if k & 2 == 0 { -half } else { half },
                if k & 4 == 0 { -half } else { half },
            )
        })
        .collect();
    // Each face as two triangles counter-clockwise seen from inside the room.
    let quads =
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    let indices: Vec<[u32; 3]> =
        quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    // The overlap with the floor near a wall, in either order, is the floor plane's.
    {
        use discrete_contact::math::Pose;
        use discrete_contact::{compute_overlap, ConvexShape, MeshSdf};
        let inside = ConvexShape::Mesh(std::sync::Arc::new(
            MeshSdf::new(corners.clone(), indices.clone()).unwrap(),
        ));
        let floor = ConvexShape::half_space(V::Y).unwrap();
        let ball = ConvexShape::ball(RADIUS).unwrap();
        let s = OverlapSettings::new(4, IntegrationMode::Subcell).unwrap();
        let at = Pose::from_translation(V::new(0.08, RADIUS - half - 2e-4, 0.03));
        let below = Pose::from_translation(V::new(0.0, -half, 0.0));
        let plane = compute_overlap(&ball, &at, &floor, &below, &s, None).unwrap().unwrap();
        for (a, pa, b, pb) in
            [(&ball, at, &inside, Pose::IDENTITY), (&inside, Pose::IDENTITY, &ball, at)]
        {
            let g =
                compute_overlap(a, &pa, b, &pb, &s, None).unwrap().expect("the floor's overlap");
            assert!(
                (g.volume / plane.volume - 1.0).abs() < 1e-6,
                "{} against {}",
                g.volume,
                plane.volume
            );
        }
    }
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    world.integration_parameters.length_unit = 2.0 * RADIUS;
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let room =
        world.insert_collider(ColliderBuilder::trimesh(corners, indices).unwrap(), Some(ground));
    let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(V::new(
        -0.05,
        RADIUS - half,
        0.03,
    )));
    world.insert_collider(ColliderBuilder::ball(RADIUS).density(DENSITY), Some(ball));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap()
            .with_friction(discrete_contact::Friction::new(0.5, 0.4, 1e-3).unwrap());
    let left = contacts.handle_all(&mut world, Material::new(1e7, 0.3).unwrap()).unwrap();
    assert!(left.is_empty(), "{left:?}");
    for step in 0..240 {
        contacts.step(&mut world).unwrap();
        let x = world.bodies[ball].translation();
        assert!(x.abs().max_element() < half - 0.9 * RADIUS, "step {step}: left the room at {x:?}");
    }
    let b = &world.bodies[ball];
    assert!(b.linvel().length() < 1e-2, "still moving: {:?}", b.linvel());
    let on_ball: V = contacts
        .contacts_with(room)
        .map(|c| if c.colliders.0 == room { -c.force_on_a } else { c.force_on_a })
        .sum();
    assert!((on_ball.y / weight() - 1.0).abs() < 0.01, "force {on_ball:?}");
}
