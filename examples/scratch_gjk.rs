use bsa::contact::{signed_distance, ContactShape};
use glam::{DQuat, DVec3};
fn main() {
    let m =
        bsa::body::load_obj(std::path::Path::new("scenes/thinker/pieces/king.obj"), 1.0).unwrap();
    let s = ContactShape::new(&bsa::body::Shape::Mesh(std::sync::Arc::new(m)));
    let n = 20000;
    let t0 = std::time::Instant::now();
    let mut acc = 0.0;
    for i in 0..n {
        let a = i as f64 * 1e-3;
        let qa = DQuat::from_scaled_axis(DVec3::new(0.3 * a, 0.1, 0.2));
        let qb = DQuat::from_scaled_axis(DVec3::new(0.1, -0.2 * a, 0.5));
        acc += signed_distance(
            &s,
            DVec3::ZERO,
            qa,
            &s,
            DVec3::new(0.085 + 0.001 * (a.sin()), 0.03, 0.01),
            qb,
        );
    }
    println!(
        "{} us per call, acc {acc}",
        t0.elapsed().as_secs_f64() * 1e6 / n as f64
    );
    let p = s.polytope().unwrap();
    println!("hull vertices {}", p.points().len());
    for tol in [1e-6, 0.05] {
        let mut warm = bsa::gjk::Warm::default();
        let t0 = std::time::Instant::now();
        let mut acc = 0.0;
        for i in 0..n {
            let a = i as f64 * 1e-3;
            let qa = DQuat::from_scaled_axis(DVec3::new(0.3 * a, 0.1, 0.2));
            let qb = DQuat::from_scaled_axis(DVec3::new(0.1, -0.2 * a, 0.5));
            let pb = DVec3::new(0.085 + 0.001 * (a.sin()), 0.03, 0.01);
            let rel_q = qa.inverse() * qb;
            let rel_p = qa.inverse() * pb;
            acc += bsa::gjk::distance_lower_bound_warm(p, p, rel_q, rel_p, tol, &mut warm);
        }
        println!(
            "iters {} climbs {}",
            bsa::gjk::ITERS.swap(0, std::sync::atomic::Ordering::Relaxed) as f64 / n as f64,
            bsa::gjk::CLIMB.swap(0, std::sync::atomic::Ordering::Relaxed) as f64 / n as f64
        );
        println!(
            "tol {tol}: {} us per warm call, acc {acc}",
            t0.elapsed().as_secs_f64() * 1e6 / n as f64
        );
    }
}
#[allow(dead_code)]
fn warm_bench() {}
