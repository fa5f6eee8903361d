//! Prints the evaluation counts of `bsa::optimize::cmaes` reported in docs/cmaes.md
//! (10-D sphere, Rosenbrock and Rastrigin, 21 seeds each). Run in release (about 3 s):
//! `cargo run --release --example cmaes_table`.

use bsa::optimize::cmaes::functions::{
    minimize as run, rastrigin, rosenbrock, sphere, start_in_box, target_config,
};
use bsa::optimize::cmaes::{CmaesConfig, StopReason};

fn main() {
    const SEEDS: u64 = 21;
    let report = |name: &str, counts: &mut Vec<usize>, runs: u64| {
        counts.sort_unstable();
        if counts.is_empty() {
            println!("{name}: 0/{runs} successes");
            return;
        }
        let mean = counts.iter().sum::<usize>() as f64 / counts.len() as f64;
        println!(
            "{name}: {}/{runs} successes, evaluations min {} median {} mean {:.0} max {}",
            counts.len(),
            counts[0],
            counts[counts.len() / 2],
            mean,
            counts[counts.len() - 1]
        );
    };

    let mut counts = Vec::new();
    for seed in 0..SEEDS {
        let (es, r) = run(sphere, &[1.0; 10], 1.0, target_config(1e-10), seed);
        if r == StopReason::TargetReached {
            counts.push(es.evaluations());
        }
    }
    report(
        "sphere 10-D, lambda 10, x0=1, sigma0=1, f<1e-10",
        &mut counts,
        SEEDS,
    );

    let mut counts = Vec::new();
    for seed in 0..SEEDS {
        let (es, r) = run(rosenbrock, &[0.0; 10], 0.5, target_config(1e-10), seed);
        if r == StopReason::TargetReached {
            counts.push(es.evaluations());
        }
    }
    report(
        "rosenbrock 10-D, lambda 10, x0=0, sigma0=0.5, f<1e-10",
        &mut counts,
        SEEDS,
    );

    for lambda in [100, 200, 400] {
        let mut counts = Vec::new();
        for seed in 0..SEEDS {
            let x0 = start_in_box(seed, 10, 1.0, 5.0);
            let config = CmaesConfig {
                population: Some(lambda),
                ..target_config(1e-8)
            };
            let (es, r) = run(rastrigin, &x0, 2.0, config, seed);
            if r == StopReason::TargetReached {
                counts.push(es.evaluations());
            }
        }
        let name = format!("rastrigin 10-D, lambda {lambda}, x0 in [1,5]^10, sigma0=2, f<1e-8");
        report(&name, &mut counts, SEEDS);
    }
}
