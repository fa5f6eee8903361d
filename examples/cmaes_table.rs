//! Prints the evaluation counts of `bsa::optimize::cmaes` reported in docs/cmaes.md
//! (10-D sphere, Rosenbrock and Rastrigin, 21 seeds each). Run in release (about 3 s):
//! `cargo run --release --example cmaes_table`.

use bsa::optimize::cmaes::{Cmaes, CmaesConfig, StopReason};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[0] * w[0] - w[1]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

fn rastrigin(x: &[f64]) -> f64 {
    10.0 * x.len() as f64
        + x.iter()
            .map(|v| v * v - 10.0 * (2.0 * std::f64::consts::PI * v).cos())
            .sum::<f64>()
}

/// Runs the ask/evaluate/tell loop until a stop reason appears.
fn run(
    f: impl Fn(&[f64]) -> f64,
    x0: &[f64],
    sigma: f64,
    config: CmaesConfig,
    seed: u64,
) -> (Cmaes, StopReason) {
    let mut es = Cmaes::new(x0, sigma, config, seed);
    let n = es.dim();
    let mut fit = vec![0.0; es.population()];
    loop {
        let xs = es.ask();
        for (k, v) in fit.iter_mut().enumerate() {
            *v = f(&xs[k * n..(k + 1) * n]);
        }
        es.tell(&fit);
        if let Some(reason) = es.stop() {
            return (es, reason);
        }
    }
}

fn target_config(target: f64) -> CmaesConfig {
    CmaesConfig {
        f_target: Some(target),
        max_generations: 20_000,
        // Keep the stall and flatness criteria out of the way of the target.
        tol_fun: 0.0,
        stagnation_window: 1_000,
        ..CmaesConfig::default()
    }
}

/// The start of a Rastrigin run: uniform in `[lo, hi)^n`, from its own seeded stream.
fn start_in_box(seed: u64, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5eed);
    (0..n).map(|_| rng.random_range(lo..hi)).collect()
}

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
