//! Speed targets of the solver core, measured with criterion:
//! `cargo bench --bench solver` (all), or e.g. `cargo bench --bench solver -- xor`.
//!
//! - `xor_640x480`: the XOR term alone (target <= 2 us).
//! - `sample_mickey_stage2`: one Mickey sample on one core (flight, contacts, shadow,
//!   every term of stage 2; target <= 50 us).
//! - `sample_mickey_all_terms`: the same with all ten terms on.
//! - `sample_thinker_start_all_terms`: one sample of THE THINKER on one core: 16 chess
//!   pieces (10,946 triangles) in flight, every pair and the table checked for contact,
//!   the exact shadow of every mesh, all ten terms; at the scene's start guess, every
//!   piece launched (target <= 1 ms).
//! - `sample_thinker_one_varying`: one sample of a sequential stage of THE THINKER (the
//!   first, `rook_a1`, its weights): the other 15 pieces held fixed
//!   (`Problem::hold`), so the sample flies, checks and draws one piece
//!   (`Problem::evaluate_held`; target <= 0.08 ms).
//! - `solve_mickey_2_threads`: the whole two-stage Mickey solve on 2 threads (target <= 5 s).
//!
//! The wall times of the fly, tbc and thinker solves (targets 10 s, 27 s, 4 min) are
//! measured by `scripts/bench-solves.sh`: each takes too long for criterion's repeats.
//! - `budget_mickey_10k_2_threads`: the error budget's Monte Carlo, 10,000 samples of the
//!   drag-compensated Mickey launch in air at the default tolerances, on 2 threads
//!   (target <= 10 s).

use std::hint::black_box;
use std::path::Path;
use std::sync::atomic::AtomicUsize;

use criterion::{criterion_group, criterion_main, Criterion};

use bsa::energy::Weights;
use bsa::evaluate::Problem;
use bsa::optimize::solver::{self, SolveOptions};

fn mickey() -> Problem {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mickey");
    Problem::new(bsa::scene::load(&dir).expect("scenes/mickey loads"))
}

/// The launch found by `bsa solve scenes/mickey` (seed 1), rounded: a realistic sample.
const NEAR_SOLUTION: [f64; 18] = [
    0.0, 1.5015, 6.3545, 0.22, 0.54, 0.23, //
    1.461, -0.3887, 7.0623, -0.17, -0.04, 0.0, //
    -1.461, -0.3887, 7.0624, 0.14, 0.13, 0.0,
];

fn benches(c: &mut Criterion) {
    let p = mickey();
    let mut ws = p.workspace();
    let stage2 = p.scene.stages[1].weights;
    p.evaluate(&NEAR_SOLUTION, &stage2, &mut ws);
    let shadow = ws.mask.clone();
    let target = p.target.mask.clone();

    c.bench_function("xor_640x480", |b| {
        b.iter(|| black_box(&shadow).xor_count(black_box(&target)))
    });
    c.bench_function("sample_mickey_stage2", |b| {
        b.iter(|| black_box(p.evaluate(black_box(&NEAR_SOLUTION), &stage2, &mut ws)))
    });
    let all = Weights::all_ones();
    c.bench_function("sample_mickey_all_terms", |b| {
        b.iter(|| black_box(p.evaluate(black_box(&NEAR_SOLUTION), &all, &mut ws)))
    });

    // The hand-made THE THINKER, on which "Pay only for what varies" set its targets.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/hand-made/thinker");
    let thinker = Problem::new(bsa::scene::load(&dir).expect("benches/hand-made/thinker loads"));
    let start = thinker.scene.start_parameters();
    let mut tws = thinker.workspace();
    c.bench_function("sample_thinker_start_all_terms", |b| {
        b.iter(|| black_box(thinker.evaluate(black_box(&start), &all, &mut tws)))
    });
    let stage = &thinker.scene.stages[0];
    let held = thinker.hold(&start, &stage.vary);
    let mut sample = start.clone();
    // A candidate near the start, as CMA-ES draws them.
    for x in &mut sample[6 * stage.vary[0]..6 * stage.vary[0] + 6] {
        *x += 0.02;
    }
    c.bench_function("sample_thinker_one_varying", |b| {
        b.iter(|| {
            black_box(thinker.evaluate_held(&held, black_box(&sample), &stage.weights, &mut tws))
        })
    });

    let mut group = c.benchmark_group("solve");
    group.sample_size(10);
    group.bench_function("solve_mickey_2_threads", |b| {
        b.iter(|| {
            let none = AtomicUsize::new(0);
            let opts = SolveOptions {
                threads: Some(2),
                ..SolveOptions::default()
            };
            black_box(solver::solve(&p, &opts, &mut solver::Silent, &none))
        })
    });
    group.bench_function("budget_mickey_10k_2_threads", |b| {
        let budget =
            bsa::budget::Budget::new(&p, &NEAR_SOLUTION, bsa::sim::drag::DragConfig::default())
                .expect("valid drag config");
        let (comp, _) = budget.compensate();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("thread pool");
        let tol = bsa::budget::Tolerances::default();
        b.iter(|| black_box(budget.monte_carlo(&comp, &tol, 10_000, 1, &pool, &())))
    });
    group.finish();
}

criterion_group!(solver_benches, benches);
criterion_main!(solver_benches);
