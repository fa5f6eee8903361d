use super::*;
use crate::geometry::shape::tests::*;
use crate::geometry::shape::Shape;
use glam::DMat3;
use std::sync::Arc;

// ---------------------------------------------------------------- flight

/// Independent reference: Euler's equations for the principal-frame angular velocity
/// together with the body quaternion, by classical RK4 with a fixed small step.
fn reference_rotation(mp: &MassProperties, q0: DQuat, w0: DVec3, t: f64, steps: usize) -> DQuat {
    let inertia = mp.principal_inertia.to_array();
    let p = mp.principal_frame;
    let wp0 = (q0 * p).conjugate() * w0;
    // State: [w1, w2, w3, qx, qy, qz, qw], q = body -> world.
    let f = |s: &[f64; 7]| -> [f64; 7] {
        let [i1, i2, i3] = inertia;
        let (w1, w2, w3) = (s[0], s[1], s[2]);
        let dw = [
            (i2 - i3) * w2 * w3 / i1,
            (i3 - i1) * w3 * w1 / i2,
            (i1 - i2) * w1 * w2 / i3,
        ];
        // Body-frame angular velocity; q' = q (0, w_body) / 2.
        let wb = p * DVec3::new(w1, w2, w3);
        let q = DQuat::from_xyzw(s[3], s[4], s[5], s[6]);
        let dq = q * DQuat::from_xyzw(wb.x, wb.y, wb.z, 0.0) * 0.5;
        [dw[0], dw[1], dw[2], dq.x, dq.y, dq.z, dq.w]
    };
    let mut s = [wp0.x, wp0.y, wp0.z, q0.x, q0.y, q0.z, q0.w];
    let h = t / steps as f64;
    let add = |a: &[f64; 7], b: &[f64; 7], c: f64| -> [f64; 7] {
        std::array::from_fn(|i| a[i] + c * b[i])
    };
    for _ in 0..steps {
        let k1 = f(&s);
        let k2 = f(&add(&s, &k1, h / 2.0));
        let k3 = f(&add(&s, &k2, h / 2.0));
        let k4 = f(&add(&s, &k3, h));
        s = std::array::from_fn(|i| s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    }
    DQuat::from_xyzw(s[3], s[4], s[5], s[6]).normalize()
}

/// A body with mass properties `mp` launched at the origin in `orientation` with spin
/// `w` and no velocity or gravity, flown to `t_max` with `cfg`.
fn spun(
    mp: &MassProperties,
    orientation: DQuat,
    w: DVec3,
    t_max: f64,
    cfg: &FlightConfig,
) -> FreeFlight {
    let mut f = FreeFlight::default();
    let launch = LaunchState {
        origin: DVec3::ZERO,
        orientation,
        velocity: DVec3::ZERO,
        angular_velocity: w,
    };
    f.reset(mp, launch, DVec3::ZERO, t_max, cfg);
    f
}

fn world_inertia(mp: &MassProperties, r: DQuat) -> DMat3 {
    let m = DMat3::from_quat(r);
    m * mp.inertia_tensor() * m.transpose()
}

/// Checks that L = I(t) w(t) stays the launch value and returns the largest relative
/// deviations of L and of the kinetic energy 1/2 w . L over `times`.
fn conservation(f: &FreeFlight, mp: &MassProperties, times: &[f64]) -> (f64, f64) {
    let l0 = f.angular_momentum();
    let e0 = 0.5 * f.angular_velocity(0.0).dot(l0);
    let (mut dl, mut de) = (0.0f64, 0.0f64);
    for &t in times {
        let r = f.orientation(t);
        let w = f.angular_velocity(t);
        let l = world_inertia(mp, r) * w;
        dl = dl.max((l - l0).length() / l0.length());
        de = de.max(rel(0.5 * w.dot(l), e0));
    }
    (dl, de)
}

fn brick() -> MassProperties {
    Shape::Cuboid {
        half_extents: DVec3::new(0.05, 0.025, 0.0125),
    }
    .mass_properties(600.0)
}

fn grid(t_end: f64, n: usize) -> Vec<f64> {
    // Irregular sample times so that queries fall between grid points.
    (0..=n)
        .map(|i| t_end * (i as f64 / n as f64).powf(1.1))
        .collect()
}

#[test]
fn isotropic_body_spins_about_fixed_axis() {
    let mp = Shape::Sphere { radius: 0.02 }.mass_properties(1000.0);
    let q0 = DQuat::from_axis_angle(DVec3::Y, 0.3);
    let w = DVec3::new(1.0, -4.0, 9.0);
    let mut f = FreeFlight::default();
    f.reset(
        &mp,
        LaunchState {
            origin: DVec3::ONE,
            orientation: q0,
            velocity: DVec3::X,
            angular_velocity: w,
        },
        DVec3::NEG_Z * 9.81,
        1.5,
        &FlightConfig::default(),
    );
    assert_eq!(f.rotation_kind(), RotationKind::Isotropic);
    let r = f.orientation(1.5);
    let want = reference_rotation(&mp, q0, w, 1.5, 20_000);
    assert!(angle_between(r, want) < 1e-10);
    assert!(angle_between(r, DQuat::from_scaled_axis(w * 1.5) * q0) < 1e-14);
    assert!((f.max_angular_speed() - w.length()).abs() < 1e-10);
}

#[test]
fn torque_free_symmetric_top_matches_closed_form_precession() {
    // A symmetric top (I1 = I2 != I3) whose principal frame is rotated against the body
    // frame, launched in a tilted pose: the closed form must agree with an
    // independent fine RK4 of Euler's equations to 1e-9 rad after 1.5 s.
    for (i_perp, i3) in [(2.0e-5, 0.8e-5), (1.0e-5, 1.7e-5)] {
        let mp = MassProperties {
            mass: 0.03,
            local_com: DVec3::new(0.0, 0.0, 0.01),
            principal_inertia: DVec3::new(i_perp, i_perp, i3),
            principal_frame: DQuat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 0.2),
        };
        let q0 = DQuat::from_axis_angle(DVec3::new(0.3, 1.0, -0.2).normalize(), 1.2);
        let w = DVec3::new(6.0, -14.0, 9.0);
        let f = spun(&mp, q0, w, 1.5, &FlightConfig::default());
        assert_eq!(f.rotation_kind(), RotationKind::Axisymmetric);
        let reference = reference_rotation(&mp, q0, w, 1.5, 150_000);
        let err = angle_between(f.orientation(1.5), reference);
        assert!(err < 1e-9, "closed form vs reference: {err}");
        // The naive constant-w rotation is far off, so the comparison has teeth.
        assert!(angle_between(DQuat::from_scaled_axis(w * 1.5) * q0, reference) > 0.1);
        let (dl, de) = conservation(&f, &mp, &grid(1.5, 37));
        assert!(dl < 1e-13 && de < 1e-13, "{dl} {de}");
        let max_w = (0..=30)
            .map(|i| f.angular_velocity(i as f64 * 0.05).length())
            .fold(0.0, f64::max);
        assert!(max_w <= f.max_angular_speed());
    }
}

#[test]
fn asymmetric_brick_conserves_l_and_energy_and_converges() {
    let mp = brick();
    let q0 = DQuat::from_axis_angle(DVec3::new(1.0, -0.5, 0.3).normalize(), 0.8);
    let w = DVec3::new(11.0, -13.0, 9.0); // |w| ~ 19.3 rad/s
    let cfg = FlightConfig::default();
    let f = spun(&mp, q0, w, 2.0, &cfg);
    assert_eq!(f.rotation_kind(), RotationKind::Asymmetric);
    let times = grid(2.0, 101);
    let (dl, de) = conservation(&f, &mp, &times);
    assert!(dl < 1e-12, "L drift {dl}");
    // Measured 4.6e-8 with the default 0.05 rad per step (error ~ angle^4).
    assert!(de < 1e-7, "energy drift {de}");
    // 10x finer steps: measured difference 2.9e-5 rad after 2 s; require 6e-5.
    let fine_cfg = FlightConfig {
        rk4_max_step: cfg.rk4_max_step / 10.0,
        rk4_max_angle: cfg.rk4_max_angle / 10.0,
    };
    let fine = spun(&mp, q0, w, 2.0, &fine_cfg);
    let ratio = fine.rk4_steps() as f64 / f.rk4_steps() as f64;
    assert!((ratio - 10.0).abs() < 0.01, "{ratio}");
    let err = times
        .iter()
        .map(|&t| angle_between(f.orientation(t), fine.orientation(t)))
        .fold(0.0, f64::max);
    assert!(err < 6e-5, "vs 10x finer: {err}");
    // Independent Euler-equation reference.
    let reference = reference_rotation(&mp, q0, w, 2.0, 200_000);
    let err = angle_between(f.orientation(2.0), reference);
    assert!(err < 6e-5, "vs Euler reference: {err}");
    // The gyroscopic motion matters: constant-w rotation is far off.
    assert!(angle_between(DQuat::from_scaled_axis(w * 2.0) * q0, reference) > 0.1);
    // The speed bound holds and is tight (the exact polhode maximum): 2 s covers
    // more than one polhode period here.
    let max_w = times
        .iter()
        .map(|&t| f.angular_velocity(t).length())
        .fold(0.0, f64::max);
    assert!(max_w <= f.max_angular_speed());
    assert!(
        f.max_angular_speed() < 1.001 * max_w,
        "{} {max_w}",
        f.max_angular_speed()
    );
}

#[test]
fn intermediate_axis_flips_and_still_conserves() {
    // Tennis-racket theorem: spin about the middle axis (y for this brick) with a tiny
    // perturbation flips over repeatedly.
    let mp = brick();
    let w = DVec3::new(0.05, 20.0, 0.0);
    let f = spun(&mp, DQuat::IDENTITY, w, 2.0, &FlightConfig::default());
    let times = grid(2.0, 400);
    let body_wy: Vec<f64> = times
        .iter()
        .map(|&t| (f.orientation(t).conjugate() * f.angular_velocity(t)).y)
        .collect();
    assert!(body_wy.iter().any(|&y| y < -19.0), "the body never flipped");
    let (dl, de) = conservation(&f, &mp, &times);
    // Measured energy drift 5.8e-8 at the default 0.05 rad per step.
    assert!(dl < 1e-12 && de < 1.5e-7, "{dl} {de}");
}

#[test]
fn angular_velocity_is_the_derivative_of_orientation() {
    // Central differences inside one grid step, so the partial-step interpolant and
    // the angular velocity must agree.
    let mp = brick();
    let mut f = FreeFlight::default();
    let w = DVec3::new(-7.0, 15.0, 10.0);
    f.reset(
        &mp,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        1.0,
        &FlightConfig::default(),
    );
    let h = 1.0 / f.rk4_steps() as f64;
    for k in [3usize, 100, 700] {
        let t = (k as f64 + 0.5) * h;
        let d = 1e-3 * h;
        let dq = f.orientation(t + d) * f.orientation(t - d).conjugate();
        let w_fd = dq.to_scaled_axis() / (2.0 * d);
        let w_an = f.angular_velocity(t);
        assert!(
            (w_fd - w_an).length() < 1e-6 * w_an.length(),
            "{w_fd} {w_an}"
        );
    }
}

#[test]
fn the_pose_at_t_is_continuous_in_the_spin_across_a_change_of_step_count() {
    // Coarse steps make the integration error, and so any jump, large. The step count
    // ceil(t / h) changes where t / h crosses an integer; a grid shrunk to end at t
    // exactly jumped there by about the error of one step.
    let mp = brick();
    let cfg = FlightConfig {
        rk4_max_step: 1.0,
        rk4_max_angle: 0.3,
    };
    let t = 1.0;
    let flown = |w: DVec3| {
        let f = spun(&mp, DQuat::IDENTITY, w, t, &cfg);
        (f.rk4_steps(), f.orientation(t))
    };
    let axis = DVec3::new(-7.0, 15.0, 10.0).normalize();
    // Bisect on the speed for the change of step count from 40 to 41.
    let (mut lo, mut hi) = (1.0, 40.0);
    assert!(flown(axis * lo).0 <= 40 && flown(axis * hi).0 > 40);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if flown(axis * mid).0 <= 40 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let ((n_lo, q_lo), (n_hi, q_hi)) = (flown(axis * lo), flown(axis * hi));
    assert_eq!((n_lo, n_hi), (40, 41));
    let jump = angle_between(q_lo, q_hi);
    assert!(
        jump < 1e-9,
        "the pose jumps by {jump} rad where the step count changes"
    );
    // The coarse flight is still far off the true one: the test would see a jump.
    let reference = reference_rotation(&mp, DQuat::IDENTITY, axis * lo, t, 100_000);
    assert!(angle_between(q_lo, reference) > 1e-5);
}

#[test]
fn queries_beyond_t_max_extend_the_integration() {
    let mp = brick();
    let w = DVec3::new(5.0, 8.0, -12.0);
    let cfg = FlightConfig::default();
    let (mut short, mut long) = (FreeFlight::default(), FreeFlight::default());
    short.reset(
        &mp,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        0.5,
        &cfg,
    );
    long.reset(
        &mp,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        1.5,
        &cfg,
    );
    for t in [0.7, 1.3] {
        let err = angle_between(short.orientation(t), long.orientation(t));
        assert!(err < 1e-8, "t = {t}: {err}");
    }
    // Negative times integrate backwards: relaunching from the pose and angular
    // velocity at -0.4 s must come back to the launch pose 0.4 s later.
    let (q, wq) = (short.orientation(-0.4), short.angular_velocity(-0.4));
    let back = spun(&mp, q, wq, 0.5, &cfg);
    let err = angle_between(back.orientation(0.4), DQuat::IDENTITY);
    // Two RK4 integrations of 0.4 s, one backwards: measured 5.5e-8 rad apart.
    assert!(err < 1.5e-7, "{err}");
    assert!(angle_between(q, DQuat::IDENTITY) > 0.5);
}

#[test]
fn origin_and_com_stay_consistent_for_off_centre_mesh() {
    let mesh = box_mesh(DVec3::new(0.01, -0.02, 0.0), DVec3::new(0.05, 0.0, 0.01));
    let mp = Shape::Mesh(Arc::new(mesh)).mass_properties(700.0);
    assert!(mp.local_com.length() > 0.01);
    let origin = DVec3::new(0.1, 0.2, 0.8);
    let q0 = DQuat::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), 0.6);
    let (v, w, g) = (
        DVec3::new(1.0, 0.5, 4.0),
        DVec3::new(9.0, -5.0, 14.0),
        DVec3::new(0.0, 0.0, -9.81),
    );
    let mut f = FreeFlight::default();
    f.reset(
        &mp,
        LaunchState {
            origin,
            orientation: q0,
            velocity: v,
            angular_velocity: w,
        },
        g,
        1.5,
        &FlightConfig::default(),
    );
    assert_eq!(f.rotation_kind(), RotationKind::Asymmetric);
    assert!((f.origin(0.0) - origin).length() < 1e-15);
    assert!(angle_between(f.orientation(0.0), q0) < 1e-15);
    let com0 = origin + q0 * mp.local_com;
    for t in [0.0, 0.31, 0.9, 1.5] {
        let (o, r) = f.pose(t);
        assert!((o + r * mp.local_com - f.com(t)).length() < 1e-14);
        assert!((o - f.origin(t)).length() < 1e-15);
        let want = com0 + v * t + 0.5 * g * t * t;
        assert!((f.com(t) - want).length() < 1e-14);
        assert!((f.com_velocity(t) - (v + g * t)).length() < 1e-14);
    }
    // t = 1.5 s under gravity: the COM is 11.04 m below the no-gravity line.
    assert!((f.com(1.5).z - (com0.z + 6.0 - 11.03625)).abs() < 1e-12);
}

#[test]
fn reset_reuses_its_buffer() {
    let mp = brick();
    let cfg = FlightConfig::default();
    let mut f = FreeFlight::default();
    let w = DVec3::new(3.0, 20.0, 1.0);
    f.reset(
        &mp,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        1.5,
        &cfg,
    );
    let (ptr, cap) = (f.states.as_ptr(), f.states.capacity());
    f.reset(
        &mp,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w * 0.9,
        },
        DVec3::ZERO,
        1.5,
        &cfg,
    );
    assert_eq!((ptr, cap), (f.states.as_ptr(), f.states.capacity()));
    // A closed-form reset leaves the buffer alone as well.
    let ball = Shape::Sphere { radius: 0.01 }.mass_properties(1.0);
    f.reset(
        &ball,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        1.5,
        &cfg,
    );
    assert_eq!(f.rk4_steps(), 0);
    assert_eq!(cap, f.states.capacity());
}

// ---------------------------------------------------------------- shapes
