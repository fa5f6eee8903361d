//! The classic test functions of the CMA-ES literature and a serial minimisation loop:
//! what the unit tests and `examples/cmaes_table.rs` (the table of docs/cmaes.md) check
//! the optimizer against. The solver runs its own parallel loop.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Cmaes, CmaesConfig, StopReason};

/// `sum x_i^2`; minimum 0 at the origin.
pub fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

/// Rosenbrock's valley; minimum 0 at `(1, ..., 1)`.
pub fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[0] * w[0] - w[1]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

/// Rastrigin's multimodal function; minimum 0 at the origin.
pub fn rastrigin(x: &[f64]) -> f64 {
    10.0 * x.len() as f64
        + x.iter()
            .map(|v| v * v - 10.0 * (2.0 * std::f64::consts::PI * v).cos())
            .sum::<f64>()
}

/// Runs the ask/evaluate/tell loop on `f` from `x0` until a stop reason appears; returns
/// the final state and the reason.
pub fn minimize(
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

/// A configuration that stops only on reaching `target` (or after 20,000 generations):
/// the stall and flatness criteria are kept out of the way.
pub fn target_config(target: f64) -> CmaesConfig {
    CmaesConfig {
        f_target: Some(target),
        max_generations: 20_000,
        tol_fun: 0.0,
        stagnation_window: 1_000,
        ..CmaesConfig::default()
    }
}

/// The start of a Rastrigin run: uniform in `[lo, hi)^n`, from its own seeded stream.
pub fn start_in_box(seed: u64, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5eed);
    (0..n).map(|_| rng.random_range(lo..hi)).collect()
}
