//! The rapier3d multi-body continuation: motion after `t`, or after a contact, with
//! collisions, landing and bouncing. This is what exports animate after the exact flight.
//!
//! Main types: [`ContinuationConfig`] (engine tunables with units), [`BodyState`] (the
//! exact state handed to rapier), [`Until`] (a number of steps, or until every body is at
//! rest) and [`Frames`] (poses at every timestep, and [`Rest`]: whether and when the
//! motion ended).
//!
//! Data flow: [`simulate`] builds a rapier `PhysicsWorld` from the scene (one dynamic
//! body per occluder with the mass properties we computed ourselves, the table as a fixed
//! box, the receiver as a fixed half-space), sets each body's state, steps it at the
//! scene's timestep and records every pose.
//!
//! **Rest.** A body is at rest when every point of it moves slower than
//! [`REST_SPEED_M_S`] (1 cm/s), measured on the recorded poses as [`point_speed`] does;
//! the motion is over once every body has been at rest for [`REST_HOLD_S`] (0.25 s, so
//! that the top of a vertical throw does not count). rapier has no rolling resistance: a
//! ball would roll on forever, so a body that touches anything slows down at
//! `rolling_resistance * g` (and its spin in proportion, see [`ContinuationConfig`]).
//!
//! Two traps from the field notes are handled here:
//! - rapier integrates with symplectic Euler per substep `h = dt / substeps`, so a body
//!   launched at `v` follows the exact parabola of `v + g h / 2`. We hand rapier
//!   `v - g h / 2`, which makes its trajectory the exact one (up to f32 rounding), and
//!   add `g h / 2` back when reading velocities.
//! - rapier's own principal-axis computation is wrong for tiny inertia tensors, so mass
//!   properties are passed explicitly (principal inertia and frame from [`crate::geometry::shape`])
//!   and colliders get zero density.

use glam::{DQuat, DVec3, Vec3};
use rapier3d::parry::math::Pose;
use rapier3d::parry::shape::ConvexPolyhedron;
use rapier3d::prelude::{
    ColliderBuilder, ColliderHandle, MassProperties, PhysicsWorld, RigidBodyBuilder,
    RigidBodyHandle, SharedShape,
};

use crate::geometry::shape::Shape;
use crate::scene::Scene;

/// Tunables of the continuation.
#[derive(Clone, Debug)]
pub struct ContinuationConfig {
    /// Solver substeps per timestep (rapier's `num_solver_iterations`; default 4).
    pub substeps: usize,
    /// Coefficient of restitution of every contact (default 0.3: wood or hard plastic on a table).
    pub restitution: f64,
    /// Coulomb friction coefficient of every contact (default 0.5).
    pub friction: f64,
    /// Rolling resistance coefficient (dimensionless, default 0.1, a ball on carpet): a
    /// body pressed against anything (a contact at most [`TOUCH_DISTANCE_M`] apart that
    /// took an impulse in the last step) loses `rolling_resistance * |g| * dt` of speed
    /// per step, and its angular speed the same divided by its bounding radius (a rolling
    /// ball stays rolling). A 2.5 m/s ball stops within about 2.5 s. 0 turns it off.
    pub rolling_resistance: f64,
}

impl Default for ContinuationConfig {
    fn default() -> Self {
        ContinuationConfig {
            substeps: 4,
            restitution: 0.3,
            friction: 0.5,
            rolling_resistance: 0.1,
        }
    }
}

/// A body is at rest when no point of it moves faster than this (m/s), as measured by
/// [`point_speed`] between consecutive keys.
pub const REST_SPEED_M_S: f64 = 0.01;
/// The motion is over when every body has been at rest for this long (s): long enough
/// that the top of a vertical throw (where the speed passes through zero) does not count.
pub const REST_HOLD_S: f64 = 0.25;
/// A contact this close (m, rapier's signed distance) counts as touching for the rolling
/// resistance.
pub const TOUCH_DISTANCE_M: f64 = 1e-3;

/// How long [`simulate`] runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Until {
    /// Exactly this many timesteps.
    Steps(usize),
    /// Until every body has been at rest for [`REST_HOLD_S`], or `max_steps` timesteps.
    Rest { max_steps: usize },
}

/// How the motion ended.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rest {
    /// Every body was at rest for [`REST_HOLD_S`] at the last key ([`Until::Rest`] only).
    pub at_rest: bool,
    /// When the last body came to rest (s), if every body was at rest at the last key.
    pub since: Option<f64>,
    /// Each body's [`point_speed`] over the last step (m/s); empty without a step.
    pub last_speeds: Vec<f64>,
}

/// The fastest a point of a body can move between two poses `dt` apart (m/s): the
/// origin's speed plus the rotation angle's rate times `radius`, the body's bounding
/// radius about its origin (a point `p` moves at `v + w x (p - o)`).
pub fn point_speed(a: (DVec3, DQuat), b: (DVec3, DQuat), dt: f64, radius: f64) -> f64 {
    (a.0.distance(b.0) + a.1.angle_between(b.1) * radius) / dt
}

/// The exact state of one occluder handed to the engine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// Body-frame origin (m, world).
    pub origin: DVec3,
    /// Body frame -> world.
    pub orientation: DQuat,
    /// Centre-of-mass velocity (m/s).
    pub velocity: DVec3,
    /// Angular velocity (rad/s, world).
    pub angular_velocity: DVec3,
}

/// Poses at every step: `poses[k][i]` is occluder `i` at `times[k]`.
#[derive(Clone, Debug, Default)]
pub struct Frames {
    pub times: Vec<f64>,
    pub poses: Vec<Vec<(DVec3, DQuat)>>,
    /// Velocities (COM, angular) at every step, corrected back to exact-flight meaning.
    pub velocities: Vec<Vec<(DVec3, DVec3)>>,
    /// Whether and when the motion came to rest.
    pub rest: Rest,
}

/// Simulate the scene's occluders with rapier from `start` (one state per occluder) at
/// time `t0`, in timesteps of `scene.dt`, for as long as `until` says. Frame 0 is the
/// start state itself.
pub fn simulate(
    scene: &Scene,
    start: &[BodyState],
    t0: f64,
    until: Until,
    cfg: &ContinuationConfig,
) -> Frames {
    assert_eq!(start.len(), scene.occluders.len());
    let mut world = PhysicsWorld::new();
    world.gravity = scene.gravity.as_vec3();
    world.integration_parameters.dt = scene.dt as f32;
    world.integration_parameters.num_solver_iterations = cfg.substeps.max(1);
    let h = scene.dt / cfg.substeps.max(1) as f64;
    let half_gh = scene.gravity * (h / 2.0);
    insert_surfaces(&mut world, scene, cfg);
    let (handles, colliders) = insert_bodies(&mut world, scene, start, half_gh, cfg);
    // Bounding radii about the centre of mass (for the rolling resistance's spin-down)
    // and about the body origin (for the point speed of the rest test).
    let com_radius: Vec<f64> = scene.occluders.iter().map(|o| o.bounding_radius).collect();
    let origin_radius: Vec<f64> = scene
        .occluders
        .iter()
        .map(|o| o.shape.bounding_radius(DVec3::ZERO))
        .collect();
    let slow_down = cfg.rolling_resistance.max(0.0) * scene.gravity.length() * scene.dt;

    let mut frames = Frames::default();
    let record = |world: &PhysicsWorld, frames: &mut Frames, time: f64| {
        let mut poses = Vec::with_capacity(handles.len());
        let mut vels = Vec::with_capacity(handles.len());
        for h in &handles {
            let b = &world.bodies[*h];
            let p = b.position();
            poses.push((p.translation.as_dvec3(), p.rotation.as_dquat().normalize()));
            vels.push((b.linvel().as_dvec3() + half_gh, b.angvel().as_dvec3()));
        }
        frames.times.push(time);
        frames.poses.push(poses);
        frames.velocities.push(vels);
    };
    record(&world, &mut frames, t0);
    let (max_steps, stop_at_rest) = match until {
        Until::Steps(n) => (n, false),
        Until::Rest { max_steps } => (max_steps, true),
    };
    let hold_steps = (REST_HOLD_S / scene.dt).ceil() as usize;
    // Consecutive steps at which every body has been at rest.
    let mut still = 0usize;
    for k in 1..=max_steps {
        world.step();
        if slow_down > 0.0 {
            roll_resistance(&mut world, &handles, &colliders, &com_radius, slow_down);
        }
        record(&world, &mut frames, t0 + k as f64 * scene.dt);
        let speeds = last_speeds(&frames, &origin_radius, scene.dt);
        if speeds.iter().all(|&s| s < REST_SPEED_M_S) {
            still += 1;
        } else {
            still = 0;
        }
        frames.rest.last_speeds = speeds;
        if stop_at_rest && still >= hold_steps {
            frames.rest.at_rest = true;
            frames.rest.since = Some(t0 + (k - still) as f64 * scene.dt);
            break;
        }
    }
    frames
}

/// Insert the fixed surfaces: the table, if the scene has one, as a box, then the
/// receiver as a half-space.
fn insert_surfaces(world: &mut PhysicsWorld, scene: &Scene, cfg: &ContinuationConfig) {
    if let Some(table) = &scene.table {
        let body = RigidBodyBuilder::fixed().translation(table.center.as_vec3());
        let h = table.half_extents.as_vec3();
        let collider = ColliderBuilder::cuboid(h.x, h.y, h.z)
            .restitution(cfg.restitution as f32)
            .friction(cfg.friction as f32);
        world.insert(body, collider);
    }
    // The receiver is a real surface (a floor or a wall): bodies must not pass through it.
    let rc = &scene.receiver;
    let body = RigidBodyBuilder::fixed().translation(rc.center.as_vec3());
    let collider = ColliderBuilder::new(SharedShape::halfspace(rc.normal.as_vec3()))
        .restitution(cfg.restitution as f32)
        .friction(cfg.friction as f32);
    world.insert(body, collider);
}

/// Insert one dynamic body per occluder in its `start` state, its velocity lowered by
/// `half_gh` (see the module's notes), with our mass properties and a zero-density
/// collider; returns the bodies' and colliders' handles in occluder order.
fn insert_bodies(
    world: &mut PhysicsWorld,
    scene: &Scene,
    start: &[BodyState],
    half_gh: DVec3,
    cfg: &ContinuationConfig,
) -> (Vec<RigidBodyHandle>, Vec<ColliderHandle>) {
    let mut handles: Vec<RigidBodyHandle> = Vec::with_capacity(start.len());
    let mut colliders: Vec<ColliderHandle> = Vec::with_capacity(start.len());
    for (o, s) in scene.occluders.iter().zip(start) {
        let mp = &o.mass;
        let mprops = MassProperties::with_principal_inertia_frame(
            mp.local_com.as_vec3(),
            mp.mass as f32,
            mp.principal_inertia.as_vec3(),
            mp.principal_frame.as_quat(),
        );
        let body = RigidBodyBuilder::dynamic()
            .pose(Pose::from_parts(
                s.origin.as_vec3(),
                s.orientation.as_quat(),
            ))
            .linvel((s.velocity - half_gh).as_vec3())
            .angvel(s.angular_velocity.as_vec3())
            .additional_mass_properties(mprops)
            .allow_fast_rotation(true)
            .ccd_enabled(true);
        let collider = match &o.shape {
            Shape::Sphere { radius } => ColliderBuilder::ball(*radius as f32),
            Shape::Cuboid { half_extents } => {
                let e = half_extents.as_vec3();
                ColliderBuilder::cuboid(e.x, e.y, e.z)
            }
            Shape::Mesh(m) => {
                let pts: Vec<_> = m.vertices.iter().map(|v| v.as_vec3()).collect();
                ColliderBuilder::new(mesh_hull(&pts, o.bounding_radius))
            }
        }
        .density(0.0)
        .restitution(cfg.restitution as f32)
        .friction(cfg.friction as f32);
        let (handle, collider) = world.insert(body, collider);
        handles.push(handle);
        colliders.push(collider);
    }
    (handles, colliders)
}

/// Each body's [`point_speed`] between the last two recorded keys.
fn last_speeds(frames: &Frames, radius: &[f64], dt: f64) -> Vec<f64> {
    let n = frames.poses.len();
    if n < 2 {
        return Vec::new();
    }
    let (a, b) = (&frames.poses[n - 2], &frames.poses[n - 1]);
    (0..radius.len())
        .map(|i| point_speed(a[i], b[i], dt, radius[i]))
        .collect()
}

/// The rolling resistance of [`ContinuationConfig::rolling_resistance`]: every awake body
/// whose collider is pressed against another collider loses `slow_down` m/s of speed and
/// `slow_down / radius` rad/s of spin (never past zero).
fn roll_resistance(
    world: &mut PhysicsWorld,
    handles: &[RigidBodyHandle],
    colliders: &[ColliderHandle],
    com_radius: &[f64],
    slow_down: f64,
) {
    for ((h, c), r) in handles.iter().zip(colliders).zip(com_radius) {
        // Touching and pressed: a body leaving the table (a launch) gets no impulse.
        let touching = world.narrow_phase.contact_pairs_with(*c).any(|p| {
            p.total_impulse_magnitude() > 0.0
                && p.find_deepest_contact()
                    .is_some_and(|(_, contact)| f64::from(contact.dist) <= TOUCH_DISTANCE_M)
        });
        let body = &mut world.bodies[*h];
        if !touching || body.is_sleeping() {
            continue;
        }
        let shrink = |v: DVec3, by: f64| v * ((v.length() - by).max(0.0) / v.length().max(1e-300));
        let v = shrink(body.linvel().as_dvec3(), slow_down);
        let w = shrink(body.angvel().as_dvec3(), slow_down / r.max(1e-6));
        body.set_linvel(v.as_vec3(), false);
        body.set_angvel(w.as_vec3(), false);
    }
}

/// Directions of the support points that the fallback hull is built from: a Fibonacci
/// sphere, evenly spread, so that the points it picks are well apart.
const FALLBACK_DIRECTIONS: usize = 512;

/// The collider of a mesh: its convex hull, or, where parry's hull of the full point set
/// is unusable, a hull it can use. On finely tessellated curved meshes (spheres of 75k
/// triangles and more) parry's f32 hull can come back with no faces, or with vertices
/// that no face touches, and its contact queries then index an empty list and panic.
/// The fallback is the hull of the mesh's support points in [`FALLBACK_DIRECTIONS`]
/// directions (inscribed in the true hull, within a small fraction of its size for such
/// meshes), and, should that fail too, the bounding ball.
pub(crate) fn mesh_hull(pts: &[Vec3], bounding_radius: f64) -> SharedShape {
    if let Some(hull) = usable_hull(pts) {
        return hull;
    }
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let n = FALLBACK_DIRECTIONS;
    let mut picked: Vec<Vec3> = (0..n)
        .filter_map(|k| {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * k as f32;
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            pts.iter()
                .copied()
                .max_by(|a, b| a.dot(d).total_cmp(&b.dot(d)))
        })
        .collect();
    picked.sort_by(|a, b| {
        a.to_array()
            .partial_cmp(&b.to_array())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    picked.dedup();
    usable_hull(&picked).unwrap_or_else(|| SharedShape::ball(bounding_radius as f32))
}

/// parry's convex hull of `pts` if every query on it is safe: at least one face, and
/// every vertex on a face.
fn usable_hull(pts: &[Vec3]) -> Option<SharedShape> {
    let hull = ConvexPolyhedron::from_convex_hull(pts)?;
    let ok = !hull.faces().is_empty()
        && !hull.points().is_empty()
        && hull.vertices().iter().all(|v| v.num_adj_faces_or_edge > 0)
        && hull.points().iter().all(|p| p.is_finite());
    ok.then(|| SharedShape::new(hull))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vertices of the UV sphere of the audit (`m` meridians, `n` bands): 250 x 151
    /// gives 75,000 triangles, 250 x 201 gives 100,000.
    fn uv_sphere(m: usize, n: usize) -> Vec<Vec3> {
        let mut v = vec![Vec3::Z, -Vec3::Z];
        for i in 1..n {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..m {
                let ph = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
                v.push(DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()).as_vec3());
            }
        }
        v
    }

    #[test]
    fn mesh_hulls_of_finely_tessellated_spheres_are_usable() {
        for (m, n) in [(250, 151), (250, 201)] {
            let pts = uv_sphere(m, n);
            // parry's own hull of these points is the unusable one the fallback exists for.
            assert!(
                usable_hull(&pts).is_none(),
                "{m} x {n}: parry's hull is usable now"
            );
            let shape = mesh_hull(&pts, 1.0);
            let hull = shape
                .as_convex_polyhedron()
                .expect("a polyhedron, not the bounding ball");
            assert!(!hull.faces().is_empty());
            assert!(hull.vertices().iter().all(|v| v.num_adj_faces_or_edge > 0));
            // Inscribed in the unit sphere and close to it.
            let r = hull
                .points()
                .iter()
                .map(|p| p.length())
                .fold(0.0f32, f32::max);
            assert!(r > 0.99 && r <= 1.0 + 1e-6, "{r}");
        }
    }
    use crate::scene::Launch;
    use crate::sim::flight::{FlightConfig, FreeFlight, LaunchState};

    /// A scene of `occluders` and the guard of its folder, which the test keeps so that
    /// the folder is removed when it passes and kept when it fails.
    fn scene_with(occluders: &str) -> (Scene, crate::test_temp::TempPath) {
        // A folder of its own for each call: tests run side by side, and two scenes
        // keyed by their text's length (as they were) shared one when the lengths
        // matched, one test reading the target while the other wrote it.
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = crate::test_temp::TempPath::dir("bsa-cont", &call.to_string());
        image::GrayImage::from_fn(64, 48, |x, _| image::Luma([if x < 10 { 0 } else { 255 }]))
            .save(dir.join("t.png"))
            .unwrap();
        let json = format!(
            r#"{{"target": "t.png", "t": 1.2, "light": [0, 0, 6],
                "receiver": {{"center": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0], "width": 4, "height": 3}},
                "table": {{"center": [0, 0, -0.5], "size": [40, 40, 1]}},
                "occluders": {occluders},
                "stages": [{{"weights": {{"xor": 1}}}}]}}"#
        );
        std::fs::write(dir.join("scene.json"), json).unwrap();
        (crate::scene::load(&dir).unwrap(), dir)
    }

    /// rapier, fed the exact launch state with the half-step correction, follows the exact
    /// flight before the first contact. Tolerance: 0.1 mm in position — one sixtieth of a
    /// Mickey pixel (6.25 mm) and well above f32 rounding over 288 substeps of a
    /// metre-scale trajectory (~1e-5 m); 2 mrad in orientation for spin about a principal
    /// axis of an isotropic body (rapier's linearised quaternion update accumulates
    /// O((w h)^3) per substep). Without the correction the error is 3 cm (checked below).
    #[test]
    fn rapier_agrees_with_exact_flight_before_contact() {
        let (scene, _dir) = scene_with(
            r#"[{"name": "a", "shape": {"sphere": {"radius": 0.3}}, "position": [0, -2, 0.3], "mass": 5},
                {"name": "b", "shape": {"box": {"size": [0.3, 0.3, 0.3]}}, "position": [2, 0.5, 0.15], "mass": 2}]"#,
        );
        let launches = [
            (DVec3::new(0.1, 1.5, 7.5), DVec3::new(0.0, 0.0, 2.0)),
            (DVec3::new(-1.4, -0.3, 8.0), DVec3::new(3.0, -1.0, 4.0)),
        ];
        let mut flights: Vec<FreeFlight> = Vec::new();
        let mut start = Vec::new();
        for (o, (v, w)) in scene.occluders.iter().zip(launches) {
            let mut f = FreeFlight::default();
            f.reset(
                &o.mass,
                LaunchState::of(
                    o,
                    Launch {
                        velocity: v,
                        angular_velocity: w,
                    },
                ),
                scene.gravity,
                scene.t,
                &FlightConfig::default(),
            );
            flights.push(f);
            start.push(BodyState {
                origin: o.position,
                orientation: o.orientation,
                velocity: v,
                angular_velocity: w,
            });
        }
        let steps = (scene.t / scene.dt).round() as usize;
        let frames = simulate(
            &scene,
            &start,
            0.0,
            Until::Steps(steps),
            &ContinuationConfig::default(),
        );
        let mut worst_p: f64 = 0.0;
        let mut worst_q: f64 = 0.0;
        for (k, time) in frames.times.iter().enumerate() {
            for (i, f) in flights.iter().enumerate() {
                let (p, q) = frames.poses[k][i];
                worst_p = worst_p.max(p.distance(f.origin(*time)));
                worst_q = worst_q.max(q.angle_between(f.orientation(*time)));
            }
        }
        eprintln!("rapier vs exact flight: max position error {worst_p:.3e} m, max orientation error {worst_q:.3e} rad");
        assert!(worst_p < 1e-4, "position error {worst_p}");
        assert!(worst_q < 2e-3, "orientation error {worst_q}");

        // The correction matters: without it rapier is centimetres low at t.
        let uncorrected: Vec<BodyState> = start
            .iter()
            .map(|s| BodyState {
                velocity: s.velocity + scene.gravity * (scene.dt / 8.0),
                ..*s
            })
            .collect();
        let frames = simulate(
            &scene,
            &uncorrected,
            0.0,
            Until::Steps(steps),
            &ContinuationConfig::default(),
        );
        let err = frames.poses[steps][0]
            .0
            .distance(flights[0].origin(scene.t));
        assert!(err > 0.02, "{err}");
    }

    #[test]
    fn a_dropped_ball_lands_and_stays_above_the_table() {
        let (scene, _dir) = scene_with(
            r#"[{"name": "a", "shape": {"sphere": {"radius": 0.3}}, "position": [0, 0, 0.3], "mass": 5}]"#,
        );
        let start = [BodyState {
            origin: DVec3::new(0.0, 0.0, 0.3),
            orientation: DQuat::IDENTITY,
            velocity: DVec3::new(0.5, 0.0, 4.0),
            angular_velocity: DVec3::ZERO,
        }];
        let frames = simulate(
            &scene,
            &start,
            0.0,
            Until::Steps(180),
            &ContinuationConfig::default(),
        );
        let lowest = frames
            .poses
            .iter()
            .map(|p| p[0].0.z)
            .fold(f64::INFINITY, f64::min);
        assert!(lowest > 0.3 - 0.02, "ball sank to {lowest}");
        let last = frames.poses.last().unwrap()[0].0;
        assert!(last.z < 0.35, "ball still in the air at {last}");
    }

    fn ball_on_table(velocity: DVec3, angular_velocity: DVec3) -> (Scene, [BodyState; 1]) {
        let (scene, _dir) = scene_with(
            r#"[{"name": "a", "shape": {"sphere": {"radius": 0.3}}, "position": [0, 0, 0.3], "mass": 5}]"#,
        );
        let start = [BodyState {
            origin: DVec3::new(0.0, 0.0, 0.3),
            orientation: DQuat::IDENTITY,
            velocity,
            angular_velocity,
        }];
        (scene, start)
    }

    /// A ball rolling at 2.5 m/s: without rolling resistance rapier lets it roll for
    /// ever (still at speed after 20 s); with the default it comes to rest, and the rest
    /// is real: the last keys do not move.
    #[test]
    fn a_rolling_ball_comes_to_rest_with_rolling_resistance_only() {
        // Rolling without slipping about -y... v = w x r: w = (0, 2.5 / 0.3, 0) rolls +x.
        let (scene, start) =
            ball_on_table(DVec3::new(2.5, 0.0, 0.0), DVec3::new(0.0, 2.5 / 0.3, 0.0));
        let until = Until::Rest {
            max_steps: (20.0 / scene.dt) as usize,
        };
        let none = ContinuationConfig {
            rolling_resistance: 0.0,
            ..ContinuationConfig::default()
        };
        let frames = simulate(&scene, &start, 0.0, until, &none);
        assert!(!frames.rest.at_rest);
        assert!(frames.rest.since.is_none());
        assert!(frames.rest.last_speeds[0] > 1.0, "{:?}", frames.rest);
        assert_eq!(frames.times.len(), 1 + (20.0 / scene.dt) as usize);

        let frames = simulate(&scene, &start, 0.0, until, &ContinuationConfig::default());
        let since = frames.rest.since.expect("at rest");
        assert!(frames.rest.at_rest);
        assert!(since < 4.0, "at rest only after {since} s");
        let last = frames.times.last().unwrap();
        assert!(
            (last - since - REST_HOLD_S).abs() <= scene.dt,
            "{last} {since}"
        );
        let n = frames.poses.len();
        let r = scene.occluders[0].shape.bounding_radius(DVec3::ZERO);
        for k in n - (REST_HOLD_S / scene.dt) as usize..n {
            let s = point_speed(frames.poses[k - 1][0], frames.poses[k][0], scene.dt, r);
            assert!(s < REST_SPEED_M_S, "key {k}: {s} m/s");
        }
        // It rolled on the table, not through it.
        let end = frames.poses[n - 1][0].0;
        assert!(end.x > 1.0 && (end.z - 0.3).abs() < 0.01, "{end}");
    }

    /// The top of a vertical throw, where the speed passes through zero, is not rest:
    /// the ball comes to rest only after it has landed.
    #[test]
    fn the_top_of_a_throw_is_not_rest() {
        let (scene, start) = ball_on_table(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO);
        let frames = simulate(
            &scene,
            &start,
            0.0,
            Until::Rest {
                max_steps: (10.0 / scene.dt) as usize,
            },
            &ContinuationConfig::default(),
        );
        let since = frames.rest.since.expect("at rest");
        let flight = 2.0 * 3.0 / 9.81;
        assert!(
            since > flight,
            "at rest at {since} s, before landing at {flight} s"
        );
        assert!(frames.rest.last_speeds[0] < REST_SPEED_M_S);
    }
}
