//! The search's machinery below the schedule's passes: the [`Pool`] that evaluates a
//! population in parallel, the rank CMA-ES sorts by ([`rank_value`]), the seeds of
//! stages and runs, and one CMA-ES run of a few bodies ([`local_run`]) that the
//! polish refines with.

use std::sync::Mutex;

use rayon::prelude::*;

use crate::energy::DIVERGED_ENERGY;
use crate::evaluate::{Evaluation, Held, Problem, Workspace};
use crate::optimize::cmaes::{Cmaes, CmaesConfig, StopReason};
use crate::scene::{Contacts, Stage};

/// Per-thread workspaces, indexed by rayon's thread index. Each is only ever locked by
/// its own thread, so the locks are uncontended; they exist to satisfy the borrow rules.
pub(super) struct Pool {
    pool: rayon::ThreadPool,
    workspaces: Vec<Mutex<Workspace>>,
}

impl Pool {
    pub(super) fn new(problem: &Problem, threads: usize) -> Pool {
        Pool::build(
            problem,
            rayon::ThreadPoolBuilder::new().num_threads(threads),
        )
    }

    /// A pool whose workers each run `on_start` first (the attempt run ahead lowers
    /// their priority there).
    pub(super) fn with_start(
        problem: &Problem,
        threads: usize,
        on_start: impl Fn() + Send + Sync + 'static,
    ) -> Pool {
        let builder = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .start_handler(move |_| on_start());
        Pool::build(problem, builder)
    }

    fn build(problem: &Problem, builder: rayon::ThreadPoolBuilder) -> Pool {
        let pool = builder
            .build()
            .expect("building a rayon thread pool only fails if threads cannot be spawned");
        let threads = pool.current_num_threads();
        let workspaces = (0..threads)
            .map(|_| Mutex::new(problem.workspace()))
            .collect();
        Pool { pool, workspaces }
    }

    /// The pool's threads, for work that is not a population (the moves' parts).
    pub(super) fn rayon(&self) -> &rayon::ThreadPool {
        &self.pool
    }

    /// The worker threads.
    pub(super) fn threads(&self) -> usize {
        self.workspaces.len()
    }

    /// Evaluate every row of `candidates` (`n` values each, the stage's subset) into `out`;
    /// `draw` seeds the launch errors of a robust plan (the same for the whole population).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn evaluate(
        &self,
        problem: &Problem,
        held: &Held,
        stage: &Stage,
        candidates: &[f64],
        n: usize,
        draw: u64,
        out: &mut [Evaluation],
    ) {
        let base = held.base();
        let full = base.len();
        // Batches of samples (their flights' grids integrated side by side), as many as
        // the threads need to share the population evenly, at most the problem's batch.
        let per = out
            .len()
            .div_ceil(self.workspaces.len())
            .clamp(1, problem.batch_size(held));
        self.pool.install(|| {
            out.par_chunks_mut(per).enumerate().for_each_init(
                || vec![vec![0.0; full]; per],
                |params, (c, slots)| {
                    for (j, params) in params[..slots.len()].iter_mut().enumerate() {
                        let k = c * per + j;
                        problem.expand(base, &stage.vary, &candidates[k * n..(k + 1) * n], params);
                    }
                    let idx = rayon::current_thread_index().unwrap_or(0) % self.workspaces.len();
                    let mut ws = self.workspaces[idx]
                        .lock()
                        .unwrap_or_else(|e| e.into_inner());
                    let params = &params[..slots.len()];
                    problem.evaluate_held_draws(held, params, &stage.weights, draw, &mut ws, slots);
                },
            );
        });
    }
}

/// Samples with a contact rank above this under [`Contacts::Constraint`]: above every
/// real energy and far below [`DIVERGED_ENERGY`].
const INFEASIBLE: f64 = 1e12;

/// The value CMA-ES ranks a sample by. Under [`Contacts::Constraint`] a sample with a
/// contact before `t` that involves a body the stage varies ranks after every sample
/// without one, by its contact time (`(t - t_first) n`, [`Outcome::own_contact`]) and
/// then by its energy: `INFEASIBLE (1 + contact time) + energy`, where a microsecond of
/// contact time (1e6) outweighs any energy below 1e5 (the energy is capped there, so
/// the order is lexicographic). Under [`Contacts::Penalty`] it is the weighted energy,
/// as in the paper.
///
/// [`Outcome::own_contact`]: crate::evaluate::Outcome::own_contact
pub(super) fn rank_value(e: &Evaluation, contacts: Contacts) -> f64 {
    match contacts {
        Contacts::Constraint if e.outcome.own_contact > 0.0 && e.total < DIVERGED_ENERGY => {
            INFEASIBLE * (1.0 + e.outcome.own_contact) + e.total.min(1e5)
        }
        _ => e.total,
    }
}

/// Whether a run (its moves and its CMA-ES) moved the stage's picture enough to be worth
/// a restart: it found a better-ranked sample, and either it started with a contact of
/// the stage's own or the IoU rose by at least `gain` (the stage's `restart_gain`). A run
/// that left the picture as it was has settled, and a wider run from the same best rarely
/// finds more: on the examples, the final joint stage's restarts after such a run never
/// did, and cost half of the solve's time (`git show c030f18:docs/results.md`, "Restarts within a
/// budget").
pub(super) fn run_moved_picture(
    gain: f64,
    start: &Evaluation,
    end: &Evaluation,
    contacts: Contacts,
) -> bool {
    let (a, b) = (rank_value(start, contacts), rank_value(end, contacts));
    let better = b < a - 1e-9 * a.abs();
    better && (start.outcome.own_contact > 0.0 || end.iou - start.iou >= gain)
}

/// Iteration cap of a stage's run: each restart doubles the population and halves the
/// cap, so that every run draws about as many samples as the first (IPOP within a budget
/// of `restarts + 1` first runs).
pub(super) fn run_iterations(
    max_iterations: usize,
    first_population: usize,
    population: usize,
) -> usize {
    (max_iterations * first_population)
        .div_ceil(population.max(1))
        .max(1)
}

/// Seed of stage `k`'s CMA-ES: a SplitMix64 step, so that every stage of every seed has
/// its own stream and a resumed solve draws exactly what an uninterrupted one would.
pub(super) fn stage_seed(seed: u64, k: usize) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k as u64 + 1));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of a stage's CMA-ES run: the first run of stage `k` keeps [`stage_seed`], so
/// that a stage without restarts draws what it always drew; each restart draws its own.
pub(super) fn restart_seed(seed: u64, k: usize, restart: usize) -> u64 {
    if restart == 0 {
        stage_seed(seed, k)
    } else {
        stage_seed(stage_seed(seed, k) ^ restart as u64, restart)
    }
}

pub(super) fn stop_name(s: Option<StopReason>, interrupted: bool, stopped: bool) -> String {
    if stopped {
        return "stopped (Ctrl-C twice)".into();
    }
    if interrupted {
        return "interrupted (Ctrl-C: next stage)".into();
    }
    match s {
        Some(StopReason::TargetReached) => "target energy reached",
        Some(StopReason::TolFun) => "energy tolerance",
        Some(StopReason::TolX) => "step tolerance",
        Some(StopReason::Stagnation) => "stagnation",
        Some(StopReason::MaxGenerations) => "iteration cap",
        Some(StopReason::ConditionNumber) => "ill-conditioned covariance",
        None => "iteration cap",
    }
    .into()
}

/// One CMA-ES run of `run` (its bodies, step, population, iteration cap and stagnation)
/// from `from`, the other bodies held: the best launch (`from` itself when no sample
/// ranks better), its rank, and the samples drawn.
#[allow(clippy::too_many_arguments)]
pub(super) fn local_run(
    problem: &Problem,
    pool: &Pool,
    run: &Stage,
    from: &[f64],
    seed: u64,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (Vec<f64>, f64, usize) {
    let contacts = problem.scene.contacts;
    let held = problem.hold(from, &run.vary).for_stage(run);
    // The start is a sample like any other: counted, and a row of the record.
    let start = problem.evaluate_held(&held, from, &run.weights, ws);
    record(&start);
    let mut best = rank_value(&start, contacts);
    let n = problem.stage_variable_count(&run.vary);
    let mut x0 = vec![0.0; n];
    problem.stage_start(from, &run.vary, &mut x0);
    let config = CmaesConfig {
        population: Some(run.population),
        max_generations: run.max_iterations,
        tol_fun: run.tol_fun,
        stagnation_window: run.stagnation,
        ..CmaesConfig::default()
    };
    let mut cma = Cmaes::new(&x0, run.step, config, seed);
    let pop = cma.population();
    let mut evals = vec![Evaluation::diverged(); pop];
    let mut fitness = vec![0.0; pop];
    let mut candidates = vec![0.0; pop * n];
    // The best sample's values, once one ranks better than `from`.
    let mut best_x: Option<Vec<f64>> = None;
    let mut samples = 1;
    loop {
        candidates.copy_from_slice(cma.ask());
        pool.evaluate(problem, &held, run, &candidates, n, 0, &mut evals);
        for (j, e) in evals.iter().enumerate() {
            fitness[j] = rank_value(e, contacts);
            record(e);
            if fitness[j] < best {
                best = fitness[j];
                let x = best_x.get_or_insert_with(|| vec![0.0; n]);
                x.copy_from_slice(&candidates[j * n..(j + 1) * n]);
            }
        }
        samples += pop;
        cma.tell(&fitness);
        if cma.stop().is_some() {
            break;
        }
    }
    let mut launch = from.to_vec();
    if let Some(xs) = best_x {
        problem.expand(from, &run.vary, &xs, &mut launch);
    }
    (launch, best, samples)
}

/// The robust stage's bookkeeping of its best: the iteration's best-ranked candidate,
/// evaluated on the reference draw, replaces `best` if it does better there. Returns its
/// index if it did.
#[allow(clippy::too_many_arguments)]
pub(super) fn best_on_reference(
    problem: &Problem,
    held: &Held,
    stage: &Stage,
    params: &[f64],
    candidates: &[f64],
    fitness: &[f64],
    best: &mut Evaluation,
    scratch: &mut [f64],
    ws: &mut Workspace,
) -> Option<usize> {
    let n = candidates.len() / fitness.len();
    let j = (0..fitness.len()).min_by(|&a, &b| fitness[a].total_cmp(&fitness[b]))?;
    problem.expand(
        params,
        &stage.vary,
        &candidates[j * n..(j + 1) * n],
        scratch,
    );
    let e = problem.evaluate_held(held, scratch, &stage.weights, ws);
    let contacts = problem.scene.contacts;
    (rank_value(&e, contacts) < rank_value(best, contacts)).then(|| {
        *best = e;
        j
    })
}
