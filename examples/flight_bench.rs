//! Accuracy and cost of `FreeFlight` (run with `cargo run --release --example flight_bench`).
use bsa::geometry::shape::{MassProperties, Shape};
use bsa::sim::flight::{integrate_grids, FlightConfig, FreeFlight, LaunchState};
use glam::{DQuat, DVec3};
use std::hint::black_box;
use std::time::Instant;

fn angle(a: DQuat, b: DQuat) -> f64 {
    // Vector part of the relative rotation: acos(|a . b|) cannot resolve below ~3e-8 rad.
    let d = a.conjugate() * b;
    2.0 * d.xyz().length().atan2(d.w.abs())
}

fn energy(f: &FreeFlight, t: f64) -> f64 {
    0.5 * f.angular_velocity(t).dot(f.angular_momentum())
}

/// Cost in microseconds of reset + 4 orientation queries: the best of 5 runs, each the
/// mean over 2000 launches (the machine is shared, so the minimum is the stable figure).
fn cost(mp: &MassProperties, w: DVec3, t_max: f64, cfg: &FlightConfig) -> f64 {
    (0..5)
        .map(|_| cost_once(mp, w, t_max, cfg))
        .fold(f64::INFINITY, f64::min)
}

/// The benchmark's launch with spin `w`.
fn launch(w: DVec3) -> LaunchState {
    LaunchState {
        origin: DVec3::ZERO,
        orientation: DQuat::from_axis_angle(DVec3::new(1.0, -0.5, 0.3).normalize(), 0.8),
        velocity: DVec3::X,
        angular_velocity: w,
    }
}

/// [`cost`] per flight of four flights started together and integrated side by side
/// (`reset_without_grid`, then `integrate_grids`, as a batch of samples is).
fn cost_abreast(mp: &MassProperties, w: DVec3, t_max: f64, cfg: &FlightConfig) -> f64 {
    (0..5)
        .map(|_| {
            let mut flights = vec![FreeFlight::default(); 4];
            let n = 100;
            let start = Instant::now();
            let mut acc = DQuat::IDENTITY;
            for i in 0..n {
                for (j, f) in flights.iter_mut().enumerate() {
                    let wi = w * (1.0 + 1e-4 * (4 * i + j) as f64);
                    f.reset_without_grid(
                        black_box(mp),
                        launch(wi),
                        DVec3::NEG_Z * 9.81,
                        t_max,
                        cfg,
                    );
                }
                integrate_grids(&mut flights);
                for f in &flights {
                    for k in 1..=4 {
                        acc += f.orientation(black_box(t_max * k as f64 / 4.0 - 0.0123));
                    }
                }
            }
            black_box(acc);
            start.elapsed().as_secs_f64() / (4 * n) as f64 * 1e6
        })
        .fold(f64::INFINITY, f64::min)
}

fn cost_once(mp: &MassProperties, w: DVec3, t_max: f64, cfg: &FlightConfig) -> f64 {
    let mut f = FreeFlight::default();
    let n = 400;
    let start = Instant::now();
    let mut acc = DQuat::IDENTITY;
    for i in 0..n {
        let wi = w * (1.0 + 1e-4 * i as f64);
        f.reset(black_box(mp), launch(wi), DVec3::NEG_Z * 9.81, t_max, cfg);
        for k in 1..=4 {
            acc += f.orientation(black_box(t_max * k as f64 / 4.0 - 0.0123));
        }
    }
    black_box(acc);
    start.elapsed().as_secs_f64() / n as f64 * 1e6
}

fn main() {
    let brick = Shape::Cuboid {
        half_extents: DVec3::new(0.05, 0.025, 0.0125),
    }
    .mass_properties(600.0);
    let w = DVec3::new(11.0, -13.0, 9.0);
    let q0 = DQuat::from_axis_angle(DVec3::new(1.0, -0.5, 0.3).normalize(), 0.8);
    let t_end = 2.0;
    println!(
        "asymmetric brick 10x5x2.5 cm, |w0| = {:.2} rad/s, t_max = {t_end} s",
        w.length()
    );
    let reference_cfg = FlightConfig {
        rk4_max_step: 0.01,
        rk4_max_angle: 0.0005,
    };
    let mut reference = FreeFlight::default();
    reference.reset(
        &brick,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: q0,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        t_end,
        &reference_cfg,
    );
    let times: Vec<f64> = (0..=200)
        .map(|i| t_end * i as f64 / 200.0 + 1e-3 * (i % 7) as f64 / 7.0)
        .filter(|&t| t <= t_end)
        .collect();
    let max_w = times
        .iter()
        .map(|&t| reference.angular_velocity(t).length())
        .fold(0.0, f64::max);
    println!(
        "max |w| sampled {max_w:.6}, bound {:.6}",
        reference.max_angular_speed()
    );
    println!("rk4_max_angle  steps  max angle err vs ref (rad)  max rel energy drift  us per reset+4 queries (t_max 1.5)");
    for theta in [0.005, 0.01, 0.02, 0.03, 0.05, 0.1] {
        let cfg = FlightConfig {
            rk4_max_step: 0.01,
            rk4_max_angle: theta,
        };
        let mut f = FreeFlight::default();
        f.reset(
            &brick,
            LaunchState {
                origin: DVec3::ZERO,
                orientation: q0,
                velocity: DVec3::ZERO,
                angular_velocity: w,
            },
            DVec3::ZERO,
            t_end,
            &cfg,
        );
        let e0 = energy(&f, 0.0);
        let err = times
            .iter()
            .map(|&t| angle(f.orientation(t), reference.orientation(t)))
            .fold(0.0, f64::max);
        let de = times
            .iter()
            .map(|&t| ((energy(&f, t) - e0) / e0).abs())
            .fold(0.0, f64::max);
        println!(
            "{theta:>13} {:>6} {err:>27.3e} {de:>21.3e} {:>10.2}",
            f.rk4_steps(),
            cost(&brick, w, 1.5, &cfg)
        );
    }
    let cfg = FlightConfig::default();
    println!("default config {cfg:?}");
    println!("reset + 4 queries, t_max = 1.5 s:");
    println!(
        "  asymmetric brick |w| 19.3: {:.3} us",
        cost(&brick, w, 1.5, &cfg)
    );
    println!(
        "  asymmetric brick |w| 19.3, four side by side: {:.3} us each",
        cost_abreast(&brick, w, 1.5, &cfg)
    );
    println!(
        "  asymmetric brick |w| 5:    {:.3} us",
        cost(&brick, w.normalize() * 5.0, 1.5, &cfg)
    );
    let ball = Shape::Sphere { radius: 0.02 }.mass_properties(1000.0);
    println!(
        "  sphere (isotropic):        {:.3} us",
        cost(&ball, w, 1.5, &cfg)
    );
    let top = MassProperties {
        mass: 0.03,
        local_com: DVec3::new(0.0, 0.0, 0.01),
        principal_inertia: DVec3::new(2e-6, 7e-6, 7e-6),
        principal_frame: DQuat::from_axis_angle(DVec3::Y, 0.3),
    };
    println!(
        "  axisymmetric (pawn-like):  {:.3} us",
        cost(&top, w, 1.5, &cfg)
    );
}
