//! The whole motion of a solution, for animation and for building it: [`Track`] (poses of
//! every occluder at every timestep) and [`LaunchRow`] (one row of `launch.csv` per
//! occluder).
//!
//! Data flow of [`track`]: from launch to `t` the poses come from the solver's own model
//! ([`Problem::fly`] and [`Problem::state_at`]: exact free flight, landings absorbed by the
//! table), with a key at every timestep and one exactly at `t`, so that the animation
//! shows at `t` exactly the shadow the solver scored. A scene with several pictures has a
//! key exactly at each picture's instant, and one with a hold window at each frame of
//! the window; the solver's model runs to the end of the last window. From there on,
//! rapier3d continues the motion with collisions, landing and bouncing
//! ([`crate::sim::continuation`]) until every body is at rest on the table or the floor,
//! or a cap (by default [`DEFAULT_MAX_AFTER`] seconds); [`Track::rest`] says which.

use glam::{DQuat, DVec3};
use serde::Serialize;

use crate::evaluate::Problem;
use crate::geometry::shape::Shape;
use crate::scene::Launch;
use crate::sim::continuation::{self, BodyState, ContinuationConfig, Rest, Until};

/// The sampled flight of all occluders, one key per simulation step: what the animated
/// glTF, `trajectory.csv` and Blender show.
#[derive(Clone, Debug, Default)]
pub struct Track {
    /// Key times (s), strictly increasing from 0; contains `t` exactly (at `t_index`).
    pub times: Vec<f64>,
    /// `poses[k][i]`: occluder `i` at `times[k]` (body origin, body -> world orientation,
    /// Z-up world).
    pub poses: Vec<Vec<(DVec3, DQuat)>>,
    /// Index of the key at exactly `t`.
    pub t_index: usize,
    /// Frames per second the animation is meant for (1 / timestep).
    pub fps: f64,
    /// Keys from `continuation_from` on come from the rapier continuation (the key at
    /// `t`, or at the end of the last hold window).
    pub continuation_from: usize,
    /// How the continuation ended: every body at rest, or stopped at the cap.
    pub rest: Rest,
    /// Index of the key at each picture's instant (`scene.pictures`).
    pub instant_indices: Vec<usize>,
}

impl Track {
    /// The poses at any `time` (s): linear between keys for the origins, slerp for the
    /// orientations (the glTF LINEAR rule); clamped to the first and last keys.
    pub fn poses_at(&self, time: f64) -> Vec<(DVec3, DQuat)> {
        let k = self.times.partition_point(|&x| x <= time);
        if k == 0 {
            return self.poses[0].clone();
        }
        if k == self.times.len() {
            return self.poses[k - 1].clone();
        }
        let (t0, t1) = (self.times[k - 1], self.times[k]);
        let s = (time - t0) / (t1 - t0);
        self.poses[k - 1]
            .iter()
            .zip(&self.poses[k])
            .map(|(a, b)| (a.0.lerp(b.0, s), a.1.slerp(b.1, s)))
            .collect()
    }
}

/// Default cap of the continuation after `t` (s): the motion runs until every body is at
/// rest, or this long.
pub const DEFAULT_MAX_AFTER: f64 = 30.0;

/// The motion of launch values `params` from 0 until every body is at rest after `t`
/// (see [`crate::sim::continuation::REST_SPEED_M_S`]), or `t + max_after`.
pub fn track(problem: &Problem, params: &[f64], max_after: f64) -> Track {
    let scene = &problem.scene;
    let (t, dt, end) = (scene.t, scene.dt, scene.horizon());
    let n = scene.occluders.len();
    let mut ws = problem.workspace();
    problem.fly(params, &mut ws);
    let mut out = Track {
        fps: 1.0 / dt,
        ..Track::default()
    };
    // Keys at every step before the end of the model; a step closer than a thousandth of
    // a step to an instant a picture is scored at is replaced by the key at that instant.
    let exact = exact_keys(scene);
    let mut next = 0;
    let mut k = 0usize;
    loop {
        let time = k as f64 * dt;
        if time >= end - 1e-3 * dt {
            break;
        }
        while next < exact.len() && exact[next] < time - 1e-3 * dt {
            out.times.push(exact[next]);
            next += 1;
        }
        if next < exact.len() && (exact[next] - time).abs() <= 1e-3 * dt {
            out.times.push(exact[next]);
            next += 1;
        } else {
            out.times.push(time);
        }
        k += 1;
    }
    out.times
        .extend(exact[next..].iter().filter(|&&e| e < end - 1e-3 * dt));
    for &time in &out.times {
        out.poses
            .push((0..n).map(|i| problem.state_at(&ws, i, time).0).collect());
    }
    let start: Vec<BodyState> = (0..n)
        .map(|i| {
            let ((origin, orientation), (velocity, angular_velocity)) =
                problem.state_at(&ws, i, end);
            BodyState {
                origin,
                orientation,
                velocity,
                angular_velocity,
            }
        })
        .collect();
    let max_steps = (max_after / dt).round().max(0.0) as usize;
    let frames = continuation::simulate(
        scene,
        &start,
        end,
        Until::Rest { max_steps },
        &ContinuationConfig::default(),
    );
    out.rest = frames.rest;
    out.continuation_from = out.times.len();
    for (time, poses) in frames.times.into_iter().zip(frames.poses) {
        out.times.push(time);
        out.poses.push(poses);
    }
    // Frame 0 of the continuation is the start state itself: the exact pose at the end.
    out.poses[out.continuation_from] = start.iter().map(|s| (s.origin, s.orientation)).collect();
    let index_of = |time: f64| {
        out.times
            .iter()
            .position(|&k| k == time)
            .unwrap_or(out.continuation_from)
    };
    out.t_index = index_of(t);
    out.instant_indices = scene.pictures.iter().map(|p| index_of(p.t)).collect();
    out
}

/// The instants the animation has a key at exactly, in order, before the end of the
/// model: every picture's instant and every frame of its hold window.
fn exact_keys(scene: &crate::scene::Scene) -> Vec<f64> {
    let offsets = scene.hold.as_ref().map_or(vec![0.0], |h| h.frame_offsets());
    let mut keys: Vec<f64> = scene
        .pictures
        .iter()
        .flat_map(|p| offsets.iter().map(move |o| p.t + o))
        .filter(|&k| k > 0.0 && k < scene.horizon())
        .collect();
    keys.sort_by(f64::total_cmp);
    keys.dedup();
    keys
}

/// Rounds to 6 decimals: micrometres, micrometres per second, microradians per second
/// and microdegrees, the precision a launcher or a reader can use; more digits are the
/// solver's and rapier's (f32) noise.
fn micro<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64((x * 1e6).round() / 1e6)
}

/// Rounds to 9 decimals, for unit quaternions and unit axes.
fn nano<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64((x * 1e9).round() / 1e9)
}

/// Rounds to 9 significant digits, for masses and moments of inertia, whose scale
/// differs from scene to scene.
fn sig9<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(format!("{x:.8e}").parse().unwrap_or(*x))
}

/// One row of `launch.csv`: everything a builder needs to launch one occluder. Column
/// names carry their units.
#[derive(Clone, Debug, Serialize)]
pub struct LaunchRow {
    pub name: String,
    pub shape: String,
    pub launched: bool,
    #[serde(serialize_with = "sig9")]
    pub mass_kg: f64,
    /// Centre-of-mass position at launch (m).
    #[serde(serialize_with = "micro")]
    pub com_x_m: f64,
    #[serde(serialize_with = "micro")]
    pub com_y_m: f64,
    #[serde(serialize_with = "micro")]
    pub com_z_m: f64,
    /// Orientation at launch, body -> world (unit quaternion).
    #[serde(serialize_with = "nano")]
    pub qx: f64,
    #[serde(serialize_with = "nano")]
    pub qy: f64,
    #[serde(serialize_with = "nano")]
    pub qz: f64,
    #[serde(serialize_with = "nano")]
    pub qw: f64,
    /// Centre-of-mass launch velocity (m/s). The launch itself keeps every digit (the
    /// shortest decimal that reads back as the same f64), so that `bsa render` of this
    /// table gives the solve's shadow bit for bit; the columns derived from it are
    /// rounded.
    pub vx_m_s: f64,
    pub vy_m_s: f64,
    pub vz_m_s: f64,
    #[serde(serialize_with = "micro")]
    pub speed_m_s: f64,
    /// Angle above the horizontal (deg).
    #[serde(serialize_with = "micro")]
    pub elevation_deg: f64,
    /// Direction in the horizontal plane, from +x toward +y (deg).
    #[serde(serialize_with = "micro")]
    pub azimuth_deg: f64,
    /// Launch angular velocity, world frame (rad/s), every digit as the velocity.
    pub wx_rad_s: f64,
    pub wy_rad_s: f64,
    pub wz_rad_s: f64,
    #[serde(serialize_with = "micro")]
    pub spin_rev_s: f64,
    /// Spin axis in the body frame (unit; zero without spin).
    #[serde(serialize_with = "nano")]
    pub spin_axis_body_x: f64,
    #[serde(serialize_with = "nano")]
    pub spin_axis_body_y: f64,
    #[serde(serialize_with = "nano")]
    pub spin_axis_body_z: f64,
    /// Principal moments of inertia about the centre of mass (kg m^2).
    #[serde(serialize_with = "sig9")]
    pub inertia_1_kg_m2: f64,
    #[serde(serialize_with = "sig9")]
    pub inertia_2_kg_m2: f64,
    #[serde(serialize_with = "sig9")]
    pub inertia_3_kg_m2: f64,
    /// Centre of mass in the body frame (m).
    #[serde(serialize_with = "micro")]
    pub com_offset_x_m: f64,
    #[serde(serialize_with = "micro")]
    pub com_offset_y_m: f64,
    #[serde(serialize_with = "micro")]
    pub com_offset_z_m: f64,
    /// Predicted centre-of-mass position at t (m).
    #[serde(serialize_with = "micro")]
    pub com_at_t_x_m: f64,
    #[serde(serialize_with = "micro")]
    pub com_at_t_y_m: f64,
    #[serde(serialize_with = "micro")]
    pub com_at_t_z_m: f64,
    /// Predicted orientation at t (body -> world).
    #[serde(serialize_with = "nano")]
    pub q_at_t_x: f64,
    #[serde(serialize_with = "nano")]
    pub q_at_t_y: f64,
    #[serde(serialize_with = "nano")]
    pub q_at_t_z: f64,
    #[serde(serialize_with = "nano")]
    pub q_at_t_w: f64,
}

/// The launch table of launch values `params`.
pub fn launch_rows(problem: &Problem, params: &[f64]) -> Vec<LaunchRow> {
    let scene = &problem.scene;
    let mut ws = problem.workspace();
    problem.fly(params, &mut ws);
    scene
        .occluders
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let Launch {
                velocity: v,
                angular_velocity: w,
            } = if o.launched {
                Launch::get(params, i)
            } else {
                Launch::default()
            };
            let com = o.launch_com();
            let speed = v.length();
            let horizontal = v.truncate().length();
            let axis = if w.length() > 0.0 {
                (o.orientation.inverse() * w).normalize()
            } else {
                DVec3::ZERO
            };
            let ((p_t, q_t), _) = problem.state_at(&ws, i, scene.t);
            let com_t = p_t + q_t * o.mass.local_com;
            let shape = match &o.shape {
                Shape::Sphere { radius } => format!("sphere r={radius}"),
                Shape::Cuboid { half_extents: h } => {
                    format!("box {}x{}x{}", 2.0 * h.x, 2.0 * h.y, 2.0 * h.z)
                }
                Shape::Mesh(m) => format!("mesh {} triangles", m.triangles.len()),
            };
            LaunchRow {
                name: o.name.clone(),
                shape,
                launched: o.launched,
                mass_kg: o.mass.mass,
                com_x_m: com.x,
                com_y_m: com.y,
                com_z_m: com.z,
                qx: o.orientation.x,
                qy: o.orientation.y,
                qz: o.orientation.z,
                qw: o.orientation.w,
                vx_m_s: v.x,
                vy_m_s: v.y,
                vz_m_s: v.z,
                speed_m_s: speed,
                elevation_deg: v.z.atan2(horizontal).to_degrees(),
                azimuth_deg: v.y.atan2(v.x).to_degrees(),
                wx_rad_s: w.x,
                wy_rad_s: w.y,
                wz_rad_s: w.z,
                spin_rev_s: w.length() / std::f64::consts::TAU,
                spin_axis_body_x: axis.x,
                spin_axis_body_y: axis.y,
                spin_axis_body_z: axis.z,
                inertia_1_kg_m2: o.mass.principal_inertia.x,
                inertia_2_kg_m2: o.mass.principal_inertia.y,
                inertia_3_kg_m2: o.mass.principal_inertia.z,
                com_offset_x_m: o.mass.local_com.x,
                com_offset_y_m: o.mass.local_com.y,
                com_offset_z_m: o.mass.local_com.z,
                com_at_t_x_m: com_t.x,
                com_at_t_y_m: com_t.y,
                com_at_t_z_m: com_t.z,
                q_at_t_x: q_t.x,
                q_at_t_y: q_t.y,
                q_at_t_z: q_t.z,
                q_at_t_w: q_t.w,
            }
        })
        .collect()
}

/// One row of `trajectory.csv`: one occluder's pose at one key.
#[derive(Clone, Debug, Serialize)]
pub struct TrajectoryRow {
    #[serde(serialize_with = "micro")]
    pub time_s: f64,
    pub occluder: String,
    /// `flight` (the solver's exact model, up to and including t) or `continuation` (rapier, after t).
    pub phase: &'static str,
    /// Body-frame origin (m).
    #[serde(serialize_with = "micro")]
    pub x_m: f64,
    #[serde(serialize_with = "micro")]
    pub y_m: f64,
    #[serde(serialize_with = "micro")]
    pub z_m: f64,
    /// Body -> world orientation.
    #[serde(serialize_with = "nano")]
    pub qx: f64,
    #[serde(serialize_with = "nano")]
    pub qy: f64,
    #[serde(serialize_with = "nano")]
    pub qz: f64,
    #[serde(serialize_with = "nano")]
    pub qw: f64,
}

/// The rows of `trajectory.csv` for a track.
pub fn trajectory_rows(problem: &Problem, tr: &Track) -> Vec<TrajectoryRow> {
    let mut rows = Vec::with_capacity(tr.times.len() * problem.scene.occluders.len());
    // q and -q are the same rotation; rapier's continuation may hand either, so each
    // body's sign is kept continuous from key to key, which a reader interpolating the
    // table needs.
    let mut previous: Vec<Option<DQuat>> = vec![None; problem.scene.occluders.len()];
    for (k, (time, poses)) in tr.times.iter().zip(&tr.poses).enumerate() {
        for ((o, (p, q)), prev) in problem.scene.occluders.iter().zip(poses).zip(&mut previous) {
            let q = match prev {
                Some(before) if before.dot(*q) < 0.0 => -*q,
                _ => *q,
            };
            *prev = Some(q);
            rows.push(TrajectoryRow {
                time_s: *time,
                occluder: o.name.clone(),
                phase: if k <= tr.continuation_from {
                    "flight"
                } else {
                    "continuation"
                },
                x_m: p.x,
                y_m: p.y,
                z_m: p.z,
                qx: q.x,
                qy: q.y,
                qz: q.z,
                qw: q.w,
            });
        }
    }
    rows
}

#[cfg(test)]
mod csv_precision_tests {
    use super::*;

    #[derive(Serialize)]
    struct Row {
        #[serde(serialize_with = "micro")]
        a: f64,
        #[serde(serialize_with = "nano")]
        b: f64,
        #[serde(serialize_with = "sig9")]
        c: f64,
    }

    #[test]
    fn tables_print_the_digits_that_mean_something() {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(Row {
            a: -0.000_035_271_897_876_898_05,
            b: std::f64::consts::FRAC_1_SQRT_2,
            c: 1.234_567_890_123e-5,
        })
        .unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(text, "a,b,c\n-0.000035,0.707106781,0.0000123456789\n");
    }
}
