use super::*;

use super::functions::{
    minimize as run, rastrigin, rosenbrock, sphere, start_in_box, target_config,
};

#[test]
fn default_parameters_match_the_tutorial() {
    let es = Cmaes::new(&[0.0; 10], 1.0, CmaesConfig::default(), 1);
    assert_eq!(es.population(), 10);
    assert_eq!(es.parents(), 5);
    let s: f64 = es.weights.iter().sum();
    assert!((s - 1.0).abs() < 1e-15);
    assert!(es.weights.windows(2).all(|w| w[0] > w[1]));
    // mu_eff for lambda = 10 is about 3.17 (tutorial, Table 1 formulas).
    assert!((es.mu_eff() - 3.1672).abs() < 1e-3, "{}", es.mu_eff());
    assert!((es.cs - (es.mueff + 2.0) / (10.0 + es.mueff + 5.0)).abs() < 1e-15);
    assert_eq!(CmaesConfig::default_population(1), 4);
    assert_eq!(CmaesConfig::default_population(100), 17);
    assert_eq!(CmaesConfig::tutorial_tolfun_window(10, 10), 40);
}

/// Sphere, n = 10, default lambda = 10, x0 = (1, ..., 1), sigma0 = 1, target 1e-10.
/// pycma 4.5.0 (without active CMA) needs 1,410-1,780 evaluations over 21 seeds with
/// this setup. The bound of 2,000 leaves room for seed-to-seed spread but fails on a
/// step-size rule that is off by as little as 10 % (measured: median 2,060).
#[test]
fn sphere_10d_reaches_1e_minus_10() {
    for seed in 0..5 {
        let (es, reason) = run(sphere, &[1.0; 10], 1.0, target_config(1e-10), seed);
        assert_eq!(reason, StopReason::TargetReached, "seed {seed}");
        assert!(es.best().1 < 1e-10);
        assert!(
            (1_000..=2_000).contains(&es.evaluations()),
            "seed {seed}: {} evaluations",
            es.evaluations()
        );
        // The best point is a real candidate: re-evaluating it gives its value.
        assert_eq!(sphere(es.best().0), es.best().1);
    }
}

/// Rosenbrock, n = 10, default lambda, x0 = 0, sigma0 = 0.5, target 1e-10. Without
/// restarts a run may end in the local minimum near x1 = -1, so 4 of 5 seeds must
/// succeed, each within 10,000 evaluations and 7,500 on average (pycma 4.5.0 without
/// active CMA: 20 of 21 runs succeed, mean 6,180, maximum 7,070).
#[test]
fn rosenbrock_10d_reaches_1e_minus_10_in_most_runs() {
    let mut counts = Vec::new();
    for seed in 0..5 {
        let (es, reason) = run(rosenbrock, &[0.0; 10], 0.5, target_config(1e-10), seed);
        if reason == StopReason::TargetReached {
            assert!(
                es.evaluations() <= 10_000,
                "seed {seed}: {} evaluations",
                es.evaluations()
            );
            counts.push(es.evaluations());
        }
    }
    assert!(
        counts.len() >= 4,
        "only {}/5 runs reached 1e-10",
        counts.len()
    );
    let mean = counts.iter().sum::<usize>() / counts.len();
    assert!(mean <= 7_500, "{counts:?}");
}

/// Rastrigin, n = 10, lambda = 400, start mean uniform in [1, 5]^10 (a box that
/// excludes the optimum) and sigma0 = 2, in the style of Hansen & Kern (2004): a
/// large population smooths out the local minima so that most runs find the global
/// optimum. pycma 4.5.0 without active CMA finds it in 19 of 21 runs with this setup;
/// this implementation in 178 of 200 seeds (182 with the Jacobi eigensolver); 15 of
/// these 20 seeds must succeed.
#[test]
fn rastrigin_10d_large_population_finds_global_optimum() {
    let mut successes = 0;
    for seed in 0..20 {
        let x0 = start_in_box(seed, 10, 1.0, 5.0);
        let config = CmaesConfig {
            population: Some(400),
            ..target_config(1e-8)
        };
        let (es, reason) = run(rastrigin, &x0, 2.0, config, seed);
        if reason == StopReason::TargetReached {
            successes += 1;
            assert!(es.evaluations() <= 60_000, "{}", es.evaluations());
        }
    }
    assert!(
        successes >= 15,
        "only {successes}/20 runs found the global optimum"
    );
}

#[test]
fn same_seed_and_fitness_give_identical_bits() {
    let config = CmaesConfig::default();
    let mut a = Cmaes::new(&[0.3; 6], 0.7, config.clone(), 42);
    let mut b = Cmaes::new(&[0.3; 6], 0.7, config.clone(), 42);
    let mut c = Cmaes::new(&[0.3; 6], 0.7, config, 43);
    let n = a.dim();
    let mut fit = vec![0.0; a.population()];
    let mut differs_from_other_seed = false;
    for _ in 0..50 {
        let xa = a.ask().to_vec();
        let xb = b.ask();
        assert!(xa.iter().zip(xb).all(|(p, q)| p.to_bits() == q.to_bits()));
        differs_from_other_seed |= xa.iter().zip(c.ask()).any(|(p, q)| p != q);
        for (k, v) in fit.iter_mut().enumerate() {
            *v = rosenbrock(&xa[k * n..(k + 1) * n]);
        }
        a.tell(&fit);
        b.tell(&fit);
        c.tell(&fit);
        assert_eq!(a.sigma().to_bits(), b.sigma().to_bits());
        assert!(a
            .mean()
            .iter()
            .zip(b.mean())
            .all(|(p, q)| p.to_bits() == q.to_bits()));
        assert!(a
            .c
            .iter()
            .zip(&b.c)
            .all(|(p, q)| p.to_bits() == q.to_bits()));
    }
    assert!(differs_from_other_seed);
}

/// Every third candidate "crashes" (NaN, +inf or -inf). The run must neither panic
/// nor pick a non-finite value as best, and must still converge on the finite ones.
#[test]
fn non_finite_fitness_ranks_last_and_does_not_corrupt_state() {
    let mut es = Cmaes::new(&[1.0; 5], 0.5, target_config(1e-8), 7);
    let n = es.dim();
    let mut fit = vec![0.0; es.population()];
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    while es.stop().is_none() {
        let xs = es.ask();
        for (k, v) in fit.iter_mut().enumerate() {
            *v = if k % 3 == 0 {
                bad[(k / 3) % 3]
            } else {
                sphere(&xs[k * n..(k + 1) * n])
            };
        }
        es.tell(&fit);
        assert!(es.sigma().is_finite() && es.sigma() > 0.0);
        assert!(es.mean().iter().all(|v| v.is_finite()));
        assert!(es.best().1.is_finite());
    }
    assert_eq!(es.stop(), Some(StopReason::TargetReached));

    // A generation made only of non-finite values keeps the state finite as well.
    let mut es = Cmaes::new(&[1.0; 3], 0.5, CmaesConfig::default(), 8);
    for _ in 0..20 {
        es.ask();
        es.tell(&vec![f64::NAN; es.population()]);
    }
    assert!(es.mean().iter().all(|v| v.is_finite()));
    assert!(es.sigma().is_finite());
    assert_eq!(es.best().1, f64::INFINITY);
}

#[test]
fn ranking_breaks_ties_by_index() {
    let mut es = Cmaes::new(&[0.0; 2], 1.0, CmaesConfig::default(), 3);
    es.ask();
    let mut fit = vec![1.0; es.population()];
    fit[0] = f64::NAN;
    fit[4] = 0.5;
    es.tell(&fit);
    assert_eq!(es.order[0], 4);
    assert_eq!(es.order[1], 1);
    assert_eq!(*es.order.last().unwrap(), 0);
}

#[test]
fn stops_at_max_generations() {
    let config = CmaesConfig {
        max_generations: 7,
        ..CmaesConfig::default()
    };
    let (es, reason) = run(rosenbrock, &[0.0; 4], 0.5, config, 1);
    assert_eq!(reason, StopReason::MaxGenerations);
    assert_eq!(es.generation(), 7);
    assert_eq!(es.evaluations(), 7 * es.population());
}

#[test]
fn one_dimension_works() {
    let (es, reason) = run(
        |x| (x[0] - 3.0).powi(2),
        &[0.0],
        1.0,
        target_config(1e-12),
        11,
    );
    assert_eq!(es.population(), 4);
    assert_eq!(reason, StopReason::TargetReached);
    assert!((es.best().0[0] - 3.0).abs() < 1e-5);
}

#[test]
fn stops_at_target() {
    let config = CmaesConfig {
        f_target: Some(1e-3),
        ..CmaesConfig::default()
    };
    let (es, reason) = run(sphere, &[1.0; 4], 0.5, config, 2);
    assert_eq!(reason, StopReason::TargetReached);
    assert!(es.best().1 <= 1e-3);
}

/// A constant objective gives no ranking information: the overall best never
/// improves, so the run stalls after exactly `stagnation_window` generations (TolFun
/// is disabled to isolate the stagnation criterion).
#[test]
fn stops_on_stagnation() {
    let config = CmaesConfig {
        stagnation_window: 15,
        tol_fun: 0.0,
        ..CmaesConfig::default()
    };
    let (es, reason) = run(|_| 3.0, &[0.0; 3], 1.0, config, 4);
    assert_eq!(reason, StopReason::Stagnation);
    assert_eq!(es.generation(), 16);
}

/// Noise without signal: the best keeps improving now and then by luck, but not by
/// more than the relative threshold, so stagnation still ends the run.
#[test]
fn stops_on_stagnation_with_relative_threshold() {
    let config = CmaesConfig {
        stagnation_window: 20,
        tol_fun: 1e-3,
        ..CmaesConfig::default()
    };
    let noise = std::cell::Cell::new(0u64);
    let f = |_: &[f64]| {
        noise.set(
            noise
                .get()
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1),
        );
        1e6 + (noise.get() >> 54) as f64 // values in [1e6, 1e6 + 1024)
    };
    let (_, reason) = run(f, &[0.0; 3], 1.0, config, 5);
    assert_eq!(reason, StopReason::Stagnation);
}

#[test]
fn stops_on_tol_fun_and_tol_x() {
    // A flat plateau: all values identical, so TolFun fires once the history is full.
    let config = CmaesConfig {
        stagnation_window: 10,
        ..CmaesConfig::default()
    };
    let (es, reason) = run(|_| 0.0, &[0.0; 3], 1.0, config, 6);
    assert_eq!(reason, StopReason::TolFun);
    assert_eq!(es.generation(), 10);

    // With TolFun disabled, the sphere run shrinks sigma until TolX fires.
    let config = CmaesConfig {
        tol_fun: 0.0,
        tol_x: 1e-6,
        stagnation_window: 10_000,
        ..CmaesConfig::default()
    };
    let (es, reason) = run(sphere, &[1.0; 3], 0.5, config, 7);
    assert_eq!(reason, StopReason::TolX);
    let max_sd = (0..3)
        .map(|i| es.covariance()[i * 4])
        .fold(0.0, f64::max)
        .sqrt();
    assert!(es.sigma() * max_sd < 1e-6);
    assert!(es.best().1 < 1e-9, "{}", es.best().1);
}

/// A badly scaled ellipsoid drives C towards its inverse Hessian; with a condition
/// number beyond 1e14 the run must report ConditionNumber rather than go on.
#[test]
fn stops_on_ill_conditioned_covariance() {
    let elli = |x: &[f64]| x[0] * x[0] + 1e16 * x[1] * x[1];
    let config = CmaesConfig {
        tol_fun: 0.0,
        tol_x: 0.0,
        stagnation_window: 10_000,
        ..CmaesConfig::default()
    };
    let (_, reason) = run(elli, &[1.0, 1e-8], 1.0, config, 8);
    assert_eq!(reason, StopReason::ConditionNumber);
}

#[test]
#[should_panic(expected = "twice")]
fn ask_twice_panics() {
    let mut es = Cmaes::new(&[0.0; 2], 1.0, CmaesConfig::default(), 0);
    es.ask();
    es.ask();
}

#[test]
fn covariance_stays_symmetric() {
    let (es, _) = run(rosenbrock, &[0.0; 7], 0.5, target_config(1e-6), 9);
    let n = es.dim();
    for i in 0..n {
        for j in 0..n {
            assert_eq!(es.c[i * n + j].to_bits(), es.c[j * n + i].to_bits());
        }
    }
}

/// The eigen gap of purecma, in generations: every generation for a one-body run of the
/// examples (n = 6, lambda 12), every second for n = 10, lambda = 10, every twelfth for
/// the joint stage of 64 balls (n = 384, lambda = 32), as docs/cmaes.md says.
#[test]
fn the_eigenbasis_is_refreshed_at_purecmas_gap() {
    let interval = |n: usize, lambda: usize| {
        let config = CmaesConfig {
            population: Some(lambda),
            ..CmaesConfig::default()
        };
        Cmaes::new(&vec![0.0; n], 1.0, config, 1).eigen_interval
    };
    assert!(interval(6, 12) < 1.0, "{}", interval(6, 12));
    assert!(
        (1.0..2.0).contains(&interval(10, 10)),
        "{}",
        interval(10, 10)
    );
    assert!(
        (11.0..12.0).contains(&interval(384, 32)),
        "{}",
        interval(384, 32)
    );
}
