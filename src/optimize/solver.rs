//! The optimisation driver: stages of CMA-ES over the launch velocities.
//!
//! Main types: [`SolveOptions`], [`Observer`] (how the caller watches and saves: the
//! CLI draws progress bars, writes previews and saves after every stage; this module
//! touches no file), [`Solution`] (what `solution.json` holds) and [`SampleRecord`]
//! (one row of `convergence.csv`).
//!
//! Data flow of [`solve`]: for each stage (a scheduled stage, or one occluder of the
//! sequential strategy, then the final joint stage), CMA-ES starts at the best launch
//! of the previous stage over the stage's varying occluders (the others are held
//! fixed), `ask`s a population, the samples are evaluated in parallel on a rayon pool
//! with one [`Workspace`] per thread, `tell`s the energies back, and stops on target
//! energy, stagnation, tolerance or the iteration cap.
//!
//! Determinism: candidates come from one seeded RNG per stage in `ask`, and each
//! sample's energy is a pure function of its launch values, so the result is
//! bit-identical for a seed whatever the number of threads.
//!
//! Interrupts: the caller passes a counter that a Ctrl-C handler increments. One
//! interrupt ends the current stage (the next one starts from its best); a second one
//! stops the solve, which still returns the best so far.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use crate::energy::DIVERGED_ENERGY;
use crate::energy::{Term, Weights};
use crate::evaluate::{Evaluation, Held, Physics, Problem, Workspace};
use crate::optimize::cmaes::{Cmaes, CmaesConfig, StopReason};
use crate::optimize::moves;
use crate::output::solution::{
    AttemptRecord, FrameRecord, OccluderLaunch, RobustRecord, SampleRecord, Solution, StageReport,
    TermValue,
};
use crate::scene::{Contacts, Launch, Stage};
use crate::shadow::mask::Mask;

/// How to run a solve.
#[derive(Clone, Debug, Default)]
pub struct SolveOptions {
    /// Worker threads (None: one per core).
    pub threads: Option<usize>,
    /// Overrides the scene's seed.
    pub seed: Option<u64>,
    /// Continue a saved solution: its completed stages are skipped and the next stage
    /// starts from its launch values.
    pub resume: Option<Solution>,
    /// Leave out the trades of the last stage (see `TRADE_IOU`). `bsa new` does, in the
    /// trial solves that compare its designs: a trade mends a design's wrong assignment
    /// in one trial and not in another, so that a trial's result would tell less of the
    /// design and more of the trade (with trades, "to fly" kept a design whose seeds 1
    /// to 3 solve to 0.9511 / 0.9465 / 0.9454, against 0.9486 / 0.9492 / 0.9489 for the
    /// one kept without), and each trial would pay for them.
    pub skip_trades: bool,
    /// Leave out the last stage's polish (see [`polish`]). `bsa new` does too, in its
    /// trial solves: the polish refines whichever design is kept by a few thousandths of
    /// IoU, and would cost each trial a run per body.
    pub skip_polish: bool,
    /// Attempts at most (0 and 1: one): see [`solve`]. `bsa solve` makes
    /// [`DEFAULT_ATTEMPTS`]; `bsa new`'s trial solves one.
    pub attempts: usize,
}

/// The attempts `bsa solve` makes at most by default: a second where the first ends
/// below its last stage's `restart_iou`. On the 35 planted problems of seeds 11500 to
/// 11506 (drawn after this code was final), 13 first attempts ended under 0.995 and the
/// second was kept in 5, none made worse, for 1.76 times the solve time
/// (`docs/results.md`, "A second attempt, and block fits evolved in the polish").
pub const DEFAULT_ATTEMPTS: usize = 2;

/// Progress of one iteration, for progress bars and previews.
#[derive(Clone, Debug)]
pub struct IterationInfo<'a> {
    pub stage_index: usize,
    pub stage: &'a Stage,
    /// Iterations of the stage so far, over all its runs.
    pub iteration: usize,
    /// Restarts of the stage so far (0 during its first run).
    pub restart: usize,
    /// Samples of the stage so far, over all its runs.
    pub samples: usize,
    /// Best total energy of the stage so far.
    pub best_energy: f64,
    /// IoU at t of the stage's best so far.
    pub best_iou: f64,
    /// Samples per second over the stage so far.
    pub samples_per_second: f64,
    /// The stage's best shadow at t.
    pub best_shadow: &'a Mask,
}

/// Receives progress; implemented by the CLI (progress bars, preview PNG, saving).
pub trait Observer {
    fn stage_started(&mut self, _index: usize, _stage: &Stage) {}
    fn iteration(&mut self, _info: &IterationInfo) {}
    /// Stage `index` starts its restart number `restart` with `population` samples per
    /// iteration.
    fn restarted(&mut self, _index: usize, _restart: usize, _population: usize) {}
    /// Called after each stage with the solution so far (save it: nothing is lost).
    fn stage_finished(&mut self, _solution: &Solution, _records: &[SampleRecord]) {}
    /// A later attempt `attempt` (counted from 0) of at most `attempts` starts from the
    /// start guess with `seed`, the solution kept so far being `kept`.
    fn attempt_started(&mut self, _attempt: usize, _attempts: usize, _kept: &Solution, _seed: u64) {
    }
    /// A stage of a later attempt ended, with that attempt's solution so far (not to be
    /// saved: the solution kept is the one saved).
    fn attempt_stage_finished(&mut self, _solution: &Solution) {}
}

/// An observer that ignores everything (tests, benchmarks).
pub struct Silent;
impl Observer for Silent {}

/// Per-thread workspaces, indexed by rayon's thread index. Each is only ever locked by
/// its own thread, so the locks are uncontended; they exist to satisfy the borrow rules.
struct Pool {
    pool: rayon::ThreadPool,
    workspaces: Vec<Mutex<Workspace>>,
}

impl Pool {
    fn new(problem: &Problem, threads: usize) -> Pool {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("building a rayon thread pool only fails if threads cannot be spawned");
        let workspaces = (0..threads)
            .map(|_| Mutex::new(problem.workspace()))
            .collect();
        Pool { pool, workspaces }
    }

    /// Evaluate every row of `candidates` (`n` values each, the stage's subset) into `out`;
    /// `draw` seeds the launch errors of a robust plan (the same for the whole population).
    #[allow(clippy::too_many_arguments)]
    fn evaluate(
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
        self.pool.install(|| {
            out.par_iter_mut().enumerate().for_each_init(
                || vec![0.0; full],
                |params, (k, slot)| {
                    problem.expand(base, &stage.vary, &candidates[k * n..(k + 1) * n], params);
                    let idx = rayon::current_thread_index().unwrap_or(0) % self.workspaces.len();
                    let mut ws = self.workspaces[idx]
                        .lock()
                        .unwrap_or_else(|e| e.into_inner());
                    *slot = problem.evaluate_held_draw(held, params, &stage.weights, draw, &mut ws);
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
fn rank_value(e: &Evaluation, contacts: Contacts) -> f64 {
    match contacts {
        Contacts::Constraint if e.outcome.own_contact > 0.0 && e.total < DIVERGED_ENERGY => {
            INFEASIBLE * (1.0 + e.outcome.own_contact) + e.total.min(1e5)
        }
        _ => e.total,
    }
}

/// Repetitions of the per-phase profile in `solution.json`: as many as fit in about
/// 10 ms (a profile repetition costs about two samples), from 5 to 100.
fn profile_reps(problem: &Problem, params: &[f64], ws: &mut Workspace) -> usize {
    let start = Instant::now();
    problem.evaluate(params, &Weights::all_ones(), ws);
    let sample = start.elapsed().as_secs_f64().max(1e-9);
    ((0.01 / (2.0 * sample)) as usize).clamp(5, 100)
}

/// Whether a run (its moves and its CMA-ES) moved the stage's picture enough to be worth
/// a restart: it found a better-ranked sample, and either it started with a contact of
/// the stage's own or the IoU rose by at least `gain` (the stage's `restart_gain`). A run
/// that left the picture as it was has settled, and a wider run from the same best rarely
/// finds more: on the examples, the final joint stage's restarts after such a run never
/// did, and cost half of the solve's time (`docs/results.md`, "Restarts within a
/// budget").
fn run_moved_picture(gain: f64, start: &Evaluation, end: &Evaluation, contacts: Contacts) -> bool {
    let (a, b) = (rank_value(start, contacts), rank_value(end, contacts));
    let better = b < a - 1e-9 * a.abs();
    better && (start.outcome.own_contact > 0.0 || end.iou - start.iou >= gain)
}

/// Iteration cap of a stage's run: each restart doubles the population and halves the
/// cap, so that every run draws about as many samples as the first (IPOP within a budget
/// of `restarts + 1` first runs).
fn run_iterations(max_iterations: usize, first_population: usize, population: usize) -> usize {
    (max_iterations * first_population)
        .div_ceil(population.max(1))
        .max(1)
}

/// Seed of stage `k`'s CMA-ES: a SplitMix64 step, so that every stage of every seed has
/// its own stream and a resumed solve draws exactly what an uninterrupted one would.
fn stage_seed(seed: u64, k: usize) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k as u64 + 1));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of a stage's CMA-ES run: the first run of stage `k` keeps [`stage_seed`], so
/// that a stage without restarts draws what it always drew; each restart draws its own.
fn restart_seed(seed: u64, k: usize, restart: usize) -> u64 {
    if restart == 0 {
        stage_seed(seed, k)
    } else {
        stage_seed(stage_seed(seed, k) ^ restart as u64, restart)
    }
}

fn stop_name(s: Option<StopReason>, interrupted: bool, stopped: bool) -> String {
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

/// Run the optimisation: a first attempt, then, while its picture stays below the last
/// stage's `restart_iou` and `options.attempts` allows, another attempt from the start
/// guess with another seed ([`attempt_seed`]); the best picture is kept (contact-free
/// first, then the higher IoU). Returns the solution (also after interrupts) and every
/// sample of every attempt.
///
/// Why whole attempts: on planted block problems the picture a solve ends with varies
/// from seed to seed by as much as any change of method measured (the planted boxes
/// 11402: 0.9847 with one seed, 0.9888 with the next; boxes12 11406: 0.9965 and 0.9830),
/// because each stage starts where the last ended and a body placed early in a poor
/// pose leaves the later ones around it. The restarts within a stage start from its
/// best; a second attempt leaves all of them.
///
/// Later attempts report progress as the first does ([`Observer::attempt_started`],
/// then the stages), but their stages are reported by
/// [`Observer::attempt_stage_finished`], not saved: the solution saved until then is the
/// first attempt's, complete, so that a stop during a later attempt loses nothing. Not
/// for a robust solve (its picture at `t` is not what it optimises) nor a solve that
/// was interrupted.
pub fn solve(
    problem: &Problem,
    options: &SolveOptions,
    observer: &mut dyn Observer,
    interrupts: &AtomicUsize,
) -> (Solution, Vec<SampleRecord>) {
    let scene = &problem.scene;
    let seed = options.seed.unwrap_or(scene.seed);
    let started = Instant::now();
    let (mut kept, mut records) = attempt(problem, options, seed, observer, interrupts);
    let target = scene.stages.last().map_or(1.0, |s| s.restart_iou);
    let mut tried = vec![attempt_record(&kept, true)];
    let mut iterations = kept.iterations;
    let later = SolveOptions {
        resume: None,
        ..options.clone()
    };
    for a in 1..options.attempts.max(1) {
        let wanted = kept.complete
            && kept.iou < target
            && problem.plan.robust.is_none()
            && interrupts.load(Ordering::SeqCst) == 0;
        if !wanted {
            break;
        }
        let seed_a = attempt_seed(seed, a);
        observer.attempt_started(a, options.attempts, &kept, seed_a);
        let (s, more) = attempt(
            problem,
            &later,
            seed_a,
            &mut LaterAttempt(&mut *observer),
            interrupts,
        );
        records.extend(more);
        iterations += s.iterations;
        let better = s.complete
            && picture_rank(s.n_contacts, s.iou) < picture_rank(kept.n_contacts, kept.iou);
        for t in &mut tried {
            t.kept &= !better;
        }
        tried.push(attempt_record(&s, better));
        if better {
            kept = s;
        }
    }
    if tried.len() > 1 {
        kept.samples = tried.iter().map(|t| t.samples).sum();
        kept.iterations = iterations;
        kept.wall_time_s = options.resume.as_ref().map_or(0.0, |s| s.wall_time_s)
            + started.elapsed().as_secs_f64();
        kept.attempts = tried;
    }
    (kept, records)
}

/// The order in which attempts' pictures rank: contact-free first, then the higher IoU.
fn picture_rank(n_contacts: u32, iou: f64) -> (bool, f64) {
    (n_contacts > 0, -iou)
}

/// What `solution.json` records of an attempt.
fn attempt_record(s: &Solution, kept: bool) -> AttemptRecord {
    AttemptRecord {
        seed: s.seed,
        iou: s.iou,
        n_contacts: s.n_contacts,
        samples: s.samples,
        wall_time_s: s.wall_time_s,
        kept,
    }
}

/// The seed of attempt `a` (0: the solve's own seed, so that a solve whose first
/// attempt reaches its target is the solve of one attempt, bit for bit).
fn attempt_seed(seed: u64, a: usize) -> u64 {
    if a == 0 {
        return seed;
    }
    // SplitMix64's finaliser of the seed and the attempt: seeds of neighbouring
    // solves and attempts draw unrelated streams.
    let mut z = seed ^ (a as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The observer of a later attempt: progress goes to the caller's observer, finished
/// stages to [`Observer::attempt_stage_finished`] (they are not saved).
struct LaterAttempt<'a>(&'a mut dyn Observer);

impl Observer for LaterAttempt<'_> {
    fn stage_started(&mut self, index: usize, stage: &Stage) {
        self.0.stage_started(index, stage);
    }
    fn iteration(&mut self, info: &IterationInfo) {
        self.0.iteration(info);
    }
    fn restarted(&mut self, index: usize, restart: usize, population: usize) {
        self.0.restarted(index, restart, population);
    }
    fn stage_finished(&mut self, solution: &Solution, _records: &[SampleRecord]) {
        self.0.attempt_stage_finished(solution);
    }
}

/// One attempt: the stages from the start guess (or from a resumed solution) with
/// `seed`.
fn attempt(
    problem: &Problem,
    options: &SolveOptions,
    seed: u64,
    observer: &mut dyn Observer,
    interrupts: &AtomicUsize,
) -> (Solution, Vec<SampleRecord>) {
    let scene = &problem.scene;
    let threads = options
        .threads
        .unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        })
        .max(1);
    let pool = Pool::new(problem, threads);
    let start = Instant::now();

    let (mut params, first_stage, mut records, mut reports, prior_time) = match &options.resume {
        // Reports of a stage that a stop cut short are dropped: that stage runs again,
        // starting from the saved best.
        Some(s) => (
            resume_parameters(problem, s),
            s.stages_completed,
            Vec::new(),
            s.stages[..s.stages_completed.min(s.stages.len())].to_vec(),
            s.wall_time_s,
        ),
        None => (problem.start_parameters(), 0, Vec::new(), Vec::new(), 0.0),
    };
    let mut aborted = false;
    // Occluders that no stage has varied yet (a resumed solve has varied those of its
    // completed stages).
    let mut unplaced = vec![true; scene.occluders.len()];
    for stage in &scene.stages[..first_stage.min(scene.stages.len())] {
        for &i in &stage.vary {
            unplaced[i] = false;
        }
    }

    // The scene's last stage of one body: the settings of the one-body runs that refine
    // exchanges, trades and the last stage's polish.
    let one_body = scene.stages.iter().rev().find(|s| s.vary.len() == 1);
    for (k, stage) in scene.stages.iter().enumerate().skip(first_stage) {
        if interrupts.load(Ordering::SeqCst) >= 2 {
            aborted = true;
            break;
        }
        observer.stage_started(k, stage);
        let stage_start = Instant::now();
        let interrupts_at_start = interrupts.load(Ordering::SeqCst);
        let n = problem.stage_variable_count(&stage.vary);
        let mut x0 = vec![0.0; n];
        let mut evals: Vec<Evaluation> = Vec::new();
        let mut fitness: Vec<f64> = Vec::new();
        // What the stage holds fixed, computed once: a sample only pays for what varies.
        let mut held = problem.hold(&params, &stage.vary).for_stage(stage);
        // Bodies no stage has moved yet are still at their start guess: the body being
        // placed need not go around them (they will move), only around those placed.
        held.ignore_contacts_with(&unplaced);
        for &i in &stage.vary {
            unplaced[i] = false;
        }
        let robust = problem.plan.robust.is_some();
        // The stage's own record of its best: the stage starts from the previous best,
        // which it must never end worse than.
        let mut best_params = params.clone();
        let mut ws = problem.workspace();
        let mut best_eval = problem.evaluate_held(&held, &params, &stage.weights, &mut ws);
        let start_eval = best_eval;
        let mut best_mask = ws.mask.clone();
        let mut iteration = 0;
        let mut samples = 0;
        let mut interrupted = false;
        let mut scratch = vec![0.0; params.len()];
        let mut candidates: Vec<f64> = Vec::new();
        let mut restart = 0;
        let (mut lambda, mut population) = (0, stage.population);
        // Trades of places among bodies, tried once in the last stage when its picture
        // stays below `TRADE_IOU`: `trading` while that call of the moves trades,
        // `traded` after. Trades are judged on the picture without the hints, and once
        // one is taken the stage goes on without them: the hints say where the design
        // sent each object, and a cycle of objects each on another's part is the
        // design's own mistake that the hints hold in place (the planted chess 10800: a
        // queen, a king and a bishop each on the next one's part, kept there by 183
        // pixels of hints against 354 wrong ones).
        let (mut trading, mut traded) = (false, false);
        // Whether a trade was taken: the stage then ends judged without its hints.
        let mut trade_taken = false;
        // What the last stage's polish did, for its report line.
        let mut polish_text = None;
        let mut last_stop = None;
        let given = stage;
        let unhinted = {
            let mut s = given.clone();
            s.weights.0[Term::Hint as usize] = 0.0;
            s
        };
        let stop = loop {
            let stage = if trading || traded { &unhinted } else { given };
            // One CMA-ES run from the stage's best so far: the first with the stage's
            // population, each restart (IPOP) with twice the previous one and the
            // stage's initial step, so that it searches wider than the run that stalled.
            // Before each run, moves send the stage's bodies where CMA-ES's local steps
            // would not (see `moves`); a run may start from a better picture with a
            // contact, which only replaces the best once its contact is gone.
            let rank = |e: &Evaluation| rank_value(e, scene.contacts);
            let run_start = best_eval;
            if trading {
                best_eval = problem.evaluate_held(&held, &best_params, &stage.weights, &mut ws);
            }
            let moved = moves::improve(
                problem,
                &held,
                &stage.vary,
                &stage.weights,
                &rank,
                &mut best_params,
                &mut best_eval,
                moves::MoveOptions {
                    max_moves: if trading {
                        TRADE_MOVES
                    } else {
                        stage.vary.len()
                    },
                    polish_single: restart > 0 || stage.vary.len() > 1,
                    trades: trading,
                    seat_blocks: false,
                    evolve_fits: false,
                },
                &mut ws,
                &mut |e: &Evaluation| records.push(sample_record(k, iteration, stage, e)),
            );
            samples += moved.samples;
            if moved.accepted > 0 {
                best_mask.copy_from(&ws.mask);
            }
            let was_trading = std::mem::take(&mut trading);
            if was_trading && moved.accepted == 0 {
                // No trade drew a better picture as seated; a trade of pieces may once
                // its pieces are searched (`trade_trials`). The first that does is
                // taken, and the stage goes on from it as after a trade taken.
                let kept = rank_value(&best_eval, scene.contacts);
                let (better, used) = match one_body {
                    Some(template) => trade_trials(
                        problem,
                        &pool,
                        stage,
                        template,
                        &moved.trades,
                        kept,
                        stage_seed(seed, k),
                        &mut ws,
                        &mut |e: &Evaluation| records.push(sample_record(k, iteration, stage, e)),
                    ),
                    None => (None, 0),
                };
                samples += used;
                if let Some(launch) = better {
                    best_params.copy_from_slice(&launch);
                    best_eval = problem.evaluate_held(&held, &best_params, &stage.weights, &mut ws);
                    best_mask.copy_from(&ws.mask);
                    trade_taken = true;
                    continue;
                }
                // No trade drew a better picture: the stage ends as its last run did,
                // judged with its hints again.
                best_eval = problem.evaluate_held(&held, &best_params, &given.weights, &mut ws);
                break last_stop;
            }
            // Exchanges of two bodies' poses and places, each refined by rounds of
            // one-body runs, before the stage's first run (see `exchange`).
            if let Some(template) = one_body.filter(|_| restart == 0 && !traded && !robust) {
                // What the solve drew before this stage, and the stage so far.
                let drawn = reports.iter().map(|r| r.samples).sum::<usize>() + samples;
                let better = exchange(
                    problem,
                    &pool,
                    template,
                    &moved,
                    EXCHANGE_SHARE * drawn as f64,
                    rank_value(&best_eval, scene.contacts),
                    stage_seed(seed, k),
                    &mut ws,
                    &mut |e: &Evaluation| records.push(sample_record(k, iteration, stage, e)),
                );
                samples += better.1;
                if let Some(launch) = better.0 {
                    best_params.copy_from_slice(&launch);
                    best_eval = problem.evaluate_held(&held, &best_params, &stage.weights, &mut ws);
                    best_mask.copy_from(&ws.mask);
                }
            }
            // A run starts from the promising launch (a better picture with a contact)
            // only when no move was taken: after a move, the new best is the better
            // place to refine.
            let start_from = moved
                .promising
                .filter(|_| moved.accepted == 0 || was_trading);
            let from = start_from.as_deref().unwrap_or(&best_params);
            problem.stage_start(from, &stage.vary, &mut x0);
            let config = CmaesConfig {
                population: Some(population),
                max_generations: run_iterations(stage.max_iterations, stage.population, population),
                f_target: stage.target_energy,
                tol_fun: stage.tol_fun,
                stagnation_window: stage.stagnation,
                ..CmaesConfig::default()
            };
            let mut cma = Cmaes::new(&x0, stage.step, config, restart_seed(seed, k, restart));
            if restart == 0 {
                lambda = cma.population();
            }
            let pop = cma.population();
            evals.resize(pop, Evaluation::diverged());
            fitness.resize(pop, 0.0);
            candidates.resize(pop * n, 0.0);
            let stop = loop {
                if interrupts.load(Ordering::SeqCst) > interrupts_at_start {
                    interrupted = true;
                    break None;
                }
                candidates.copy_from_slice(cma.ask());
                // Common random numbers: one draw of launch errors per iteration.
                let draw = stage_seed(stage_seed(seed, k), iteration);
                pool.evaluate(problem, &held, stage, &candidates, n, draw, &mut evals);
                let mut improved = None;
                for (j, e) in evals.iter().enumerate() {
                    fitness[j] = rank_value(e, scene.contacts);
                    records.push(sample_record(k, iteration, stage, e));
                    if !robust && fitness[j] < rank_value(&best_eval, scene.contacts) {
                        best_eval = *e;
                        improved = Some(j);
                    }
                }
                if robust {
                    // Energies of different iterations met different errors: the
                    // iteration's best is compared with the stage's best on the
                    // reference draw.
                    improved = best_on_reference(
                        problem,
                        &held,
                        stage,
                        &params,
                        &candidates,
                        &fitness,
                        &mut best_eval,
                        &mut scratch,
                        &mut ws,
                    );
                }
                if let Some(j) = improved {
                    problem.expand(
                        &params,
                        &stage.vary,
                        &candidates[j * n..(j + 1) * n],
                        &mut scratch,
                    );
                    best_params.copy_from_slice(&scratch);
                    problem.evaluate_held(&held, &best_params, &stage.weights, &mut ws);
                    best_mask.copy_from(&ws.mask);
                }
                cma.tell(&fitness);
                iteration += 1;
                samples += pop;
                let elapsed = stage_start.elapsed().as_secs_f64();
                observer.iteration(&IterationInfo {
                    stage_index: k,
                    stage,
                    iteration,
                    restart,
                    samples,
                    best_energy: best_eval.total,
                    best_iou: best_eval.iou,
                    samples_per_second: samples as f64 / elapsed.max(1e-9),
                    best_shadow: &best_mask,
                });
                if let Some(s) = cma.stop() {
                    break Some(s);
                }
            };
            let restartable = !interrupted
                && stop != Some(StopReason::TargetReached)
                && restart < stage.restarts
                && best_eval.iou < stage.restart_iou
                && run_moved_picture(stage.restart_gain, &run_start, &best_eval, scene.contacts);
            let trade = !restartable
                && !options.skip_trades
                && !interrupted
                && !traded
                && !robust
                && k + 1 == scene.stages.len()
                && stop != Some(StopReason::TargetReached)
                && best_eval.iou < TRADE_IOU;
            if trade {
                // Moves with trades, then (when one is taken) a run of the stage's
                // population from there.
                (trading, traded, last_stop) = (true, true, stop);
                continue;
            }
            if !restartable {
                break stop;
            }
            restart += 1;
            population = 2 * pop;
            observer.restarted(k, restart, population);
        };
        let polishes = k + 1 == scene.stages.len()
            && !options.skip_polish
            && !interrupted
            && !robust
            && stage.vary.len() > 1
            && best_eval.iou < stage.restart_iou;
        if let Some(template) = one_body.filter(|_| polishes) {
            // Judged without the hints: they say where the design sent each body, and on
            // its own part a hint's pull holds a piece's outline a fraction of a pixel
            // off (see `polish`). The stage's report keeps the weights it ran with.
            let before = best_eval.iou;
            best_eval = problem.evaluate_held(&held, &best_params, &unhinted.weights, &mut ws);
            let (used, seated, moved) = polish(
                problem,
                &pool,
                &held,
                &unhinted,
                template,
                (&mut best_params, &mut best_eval),
                stage_seed(seed, k),
                &mut ws,
                &mut |e: &Evaluation| records.push(sample_record(k, iteration, stage, e)),
            );
            samples += used;
            let ran = if trade_taken { &unhinted } else { given };
            best_eval = problem.evaluate_held(&held, &best_params, &ran.weights, &mut ws);
            best_mask.copy_from(&ws.mask);
            polish_text = Some(format!(
                "; moves taken: {seated}, polished {moved} of {} bodies, IoU {before:.4} to {:.4}",
                stage.vary.len(),
                best_eval.iou
            ));
        }
        // The last stage never leaves a worse picture than it started from: a joint stage
        // can lower its total energy (hints, regularization) while the shadow gets worse.
        let mut stop_text = stop_name(stop, interrupted, false);
        stop_text.push_str(polish_text.as_deref().unwrap_or(""));
        if k + 1 == scene.stages.len()
            && best_eval.iou < start_eval.iou
            && start_eval.outcome.n_contacts <= best_eval.outcome.n_contacts
        {
            best_params.copy_from_slice(&params);
            best_eval = start_eval;
            stop_text.push_str("; kept its start, the better picture");
        }
        params.copy_from_slice(&best_params);
        // A second interrupt during the stage stops the solve: the stage does not count
        // as completed, so that `--resume` runs it again from the best so far.
        let stopped = interrupted && interrupts.load(Ordering::SeqCst) >= 2;
        if stopped {
            stop_text = stop_name(stop, interrupted, stopped);
        }
        reports.push(StageReport {
            name: stage.name.clone(),
            iterations: iteration,
            samples,
            population: lambda,
            restarts: restart,
            best_energy: best_eval.total,
            iou: best_eval.iou,
            stop: stop_text,
            wall_time_s: stage_start.elapsed().as_secs_f64(),
        });
        let wall = prior_time + start.elapsed().as_secs_f64();
        let run = Run {
            seed,
            stages_completed: if stopped { k } else { k + 1 },
            complete: false,
            wall_time_s: wall,
            threads,
        };
        let s = summarize(problem, &params, &reports, &run, None);
        observer.stage_finished(&s, &records);
        if stopped {
            aborted = true;
            break;
        }
    }
    // A stage cut short by a stop is reported but not completed.
    let completed = reports.len()
        - usize::from(
            aborted
                && reports
                    .last()
                    .is_some_and(|r| r.stop.starts_with("stopped")),
        );
    let wall = prior_time + start.elapsed().as_secs_f64();
    let complete = !aborted
        && completed == scene.stages.len()
        && reports.iter().all(|r| !r.stop.starts_with("interrupted"));
    let mut ws = problem.workspace();
    let timing = problem.profile(&params, profile_reps(problem, &params, &mut ws), &mut ws);
    let run = Run {
        seed,
        stages_completed: completed,
        complete,
        wall_time_s: wall,
        threads,
    };
    let s = summarize(problem, &params, &reports, &run, Some(timing));
    (s, records)
}

/// The last stage's picture below which its bodies trade places (`moves::improve` with
/// `trades`), once, after its runs: two or three bodies of different shapes each drawn
/// on the next one's part (a long block end-on on a small block's part, the small one
/// high on a medium one's, the medium one high on the long one's) is a state no move of
/// one or two bodies mends. The trades cost 1.25 and 1.28 times the summed solve time
/// of 14 planted boxes12 and 14 chess problems (`bsa solve` of their designed scenes),
/// paid only where the picture is poor; a picture at 0.985 or more is left alone.
const TRADE_IOU: f64 = 0.985;

/// Moves taken at most by the call of the moves that trades (each pass trades: a trade
/// of two often leaves a third body to trade). Against as many moves as bodies, on 14
/// planted boxes12 and 14 chess problems: 13 % and 18 % less solve time, for IoU 0.9401
/// instead of 0.9473 on chess 10602 (0.9368 with no trades) and 0.9864 instead of
/// 0.9867 on chess 10604, the others the same.
const TRADE_MOVES: usize = 3;

/// The record of one sample of stage `k` (`stage`) at `iteration`.
fn sample_record(k: usize, iteration: usize, stage: &Stage, e: &Evaluation) -> SampleRecord {
    SampleRecord {
        stage: k,
        iteration,
        terms: e.weighted(&stage.weights),
        total: e.total,
    }
}

/// Exchanges of a joint stage's moves that are refined, at most: those whose pictures
/// are best as they stand.
const EXCHANGE_TRIALS: usize = 4;

/// An exchange is refined only when its picture's energy (without contacts) is within
/// this factor of the launch kept: one far worse is a wrong pairing, not two bodies a
/// little off their new parts.
const EXCHANGE_RATIO: f64 = 4.0;

/// The exchanges of a stage draw at most this share of the samples the solve drew before
/// them (a trial starts only while its first round fits): they are a last resort, and on
/// a small solve they would cost more than the solve (the hand-made "to fly" draws
/// 22,000 samples in all, and four trials 15,000 more).
const EXCHANGE_SHARE: f64 = 0.15;

/// Refine the best exchanges that `moved` offers (see [`moves::MoveReport::exchanges`])
/// as two rounds of the sequential strategy would: each of the two bodies alone, one
/// after the other, by a CMA-ES run with the settings of `template` (the scene's last
/// stage of one body), twice; a trial starts only while its first round fits in `budget`
/// samples ([`EXCHANGE_SHARE`]). In the first round the two ignore their contacts with each
/// other: their new flights often cross (each now flies from its own slot to the
/// other's part), and a run that must first get out of that contact moves its body off
/// the picture; the second round counts every contact again. Returns the best refined
/// launch when it ranks better than `kept` (the launch kept, ranked), and the samples
/// drawn.
///
/// Two pieces of a set that each draw the other's shadow (a king and a bishop lying
/// down, each at the other's size) are a local optimum that no single move leaves: the
/// exchange as it stands is a worse picture (each body a few pixels off its new part),
/// and only its refinement shows whether the other pairing is the better one. A joint
/// run of the two bodies refined worse than runs of one body each: on the planted chess
/// problems of seeds 9805 and 9802 it ended above the exchange it started from, where
/// the rounds of one body took the pictures from 0.965 to 0.986 and from 0.961 to 0.972
/// (with four trials; under the budget, the first problem's exchange, the third best
/// picture, is no longer tried).
#[allow(clippy::too_many_arguments)]
fn exchange(
    problem: &Problem,
    pool: &Pool,
    template: &Stage,
    moved: &moves::MoveReport,
    budget: f64,
    kept: f64,
    seed: u64,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (Option<Vec<f64>>, usize) {
    let mut best: Option<(f64, Vec<f64>)> = None;
    let mut samples = 0;
    let trials = moved
        .exchanges
        .iter()
        .filter(|x| x.free < EXCHANGE_RATIO * moved.kept_free)
        .take(EXCHANGE_TRIALS);
    // A trial's first round: two runs of one body at most.
    let round = (2 * template.max_iterations * template.population) as f64;
    for (t, x) in trials.enumerate() {
        if samples as f64 + round > budget {
            break;
        }
        let mut launch = x.launch.clone();
        let mut rank = f64::INFINITY;
        for (g, &body) in x.bodies.iter().cycle().take(4).enumerate() {
            let run = Stage {
                vary: vec![body],
                ..template.clone()
            };
            let seed = stage_seed(seed, 4 * t + g);
            let partner = x.bodies[1 - g % 2];
            let ignore = (g < 2).then_some(partner);
            let (l, r, used) = local_run(problem, pool, &run, &launch, ignore, seed, ws, record);
            (launch, rank) = (l, r);
            samples += used;
            // A first round that draws no better picture than the launch kept, even with
            // the two free to pass through each other, is a wrong pairing.
            if g == 1 && rank >= kept {
                break;
            }
        }
        if rank < kept && best.as_ref().is_none_or(|b| rank < b.0) {
            best = Some((rank, launch));
        }
    }
    (best.map(|b| b.1), samples)
}

/// The trades of pieces that no call of the moves took as seated (`trades`, best picture
/// first), each searched by two rounds of one-piece runs of `template` (a stage of one
/// body) over its pieces, with `stage`'s weights: the first whose search ranks better
/// than `kept` (its launch), and the samples drawn. A seated trade in a cluster of
/// overlapping pieces draws a worse picture than the launch kept until its pieces have
/// found their poses on their new places, which the seats' scans are too coarse to
/// judge: on the planted chess 10903 the trade that mends it is the 28th of 40 by its
/// seated picture.
#[allow(clippy::too_many_arguments)]
fn trade_trials(
    problem: &Problem,
    pool: &Pool,
    stage: &Stage,
    template: &Stage,
    trades: &[moves::Trade],
    kept: f64,
    seed: u64,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (Option<Vec<f64>>, usize) {
    let mut samples = 0;
    for (t, trade) in trades.iter().enumerate() {
        let mut launch = trade.launch.clone();
        let mut rank = f64::INFINITY;
        let rounds = trade.bodies.iter().cycle().take(2 * trade.bodies.len());
        for (g, &body) in rounds.enumerate() {
            let run = Stage {
                vary: vec![body],
                weights: stage.weights,
                ..template.clone()
            };
            let used;
            let seed = stage_seed(seed, 1_000_000 + 16 * t + g);
            (launch, rank, used) = local_run(problem, pool, &run, &launch, None, seed, ws, record);
            samples += used;
        }
        if rank < kept {
            return (Some(launch), samples);
        }
    }
    (None, samples)
}

/// The step of the polish's runs, a share of the one-body stage's step.
const POLISH_STEP_SHARE: f64 = 0.1;

/// The last stage's polish: first the moves with every block seated anew on its own
/// place (`moves::improve` with `seat_blocks`), then each of the stage's bodies in turn,
/// the others held, refined by one CMA-ES run with the settings of `template` (the
/// scene's last stage of one body) but a tenth of its step ([`POLISH_STEP_SHARE`]), from
/// the best launch so far (`best`: the launch and its evaluation under `stage`'s
/// weights). The moves' end and each run's are kept when they rank better and draw no
/// worse a picture; `best` is updated in place. Returns the samples drawn, the moves
/// taken and the bodies the runs moved.
///
/// A joint stage of many bodies stops at its iteration cap still short of a pixel's
/// precision: its step shrinks slowly over 36 dimensions and more (on the planted chess
/// problems, its first step of 0.02 m/s over 1.2 s moves a shadow by about 30 pixels),
/// and its mean, which CMA-ES does not keep at the best, wanders over the picture's
/// staircase of pixels. A run of one body, six dimensions, from a step ten times smaller,
/// mends what is left of its outline. The solver calls it with the stage's weights
/// without the hints: a hint pulls its body toward the pixel the design chose, 0.3 of a
/// wrong pixel per pixel of distance, which holds an outline a fraction of a pixel off
/// its part (on the planted chess 11201, the hints were 434 pixels from their bodies in
/// all at the end, against 132 wrong pixels). Measured in `docs/results.md`, "A polish
/// of one body at a time".
#[allow(clippy::too_many_arguments)]
fn polish(
    problem: &Problem,
    pool: &Pool,
    held: &Held,
    stage: &Stage,
    template: &Stage,
    (params, best): (&mut [f64], &mut Evaluation),
    seed: u64,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (usize, usize, usize) {
    let contacts = problem.scene.contacts;
    let (mut samples, seated) = polish_moves(problem, held, stage, params, best, ws, record);
    let mut moved = 0;
    for (g, &body) in stage.vary.iter().enumerate() {
        let run = Stage {
            vary: vec![body],
            weights: stage.weights,
            step: POLISH_STEP_SHARE * template.step,
            ..template.clone()
        };
        let seed = stage_seed(seed, 2_000_000 + g);
        let (launch, rank, used) = local_run(problem, pool, &run, params, None, seed, ws, record);
        samples += used;
        if rank >= rank_value(best, contacts) {
            continue;
        }
        let e = problem.evaluate_held(held, &launch, &stage.weights, ws);
        if rank_value(&e, contacts) < rank_value(best, contacts) && e.iou >= best.iou {
            params.copy_from_slice(&launch);
            *best = e;
            moved += 1;
        }
    }
    (samples, seated, moved)
}

/// The polish's first step: the moves of `stage`'s bodies from `params` (evaluated as
/// `best`, both updated in place), every block seated anew on its own place in every
/// pass (`seat_blocks`). Returns the samples drawn and the moves taken (none when
/// their end drew a worse picture, which is then not kept).
///
/// A block tilted the other way, or on another face, draws an outline near its part's
/// that no run of small steps leaves (the planted boxes 11204: one block's outline off
/// all round, IoU 0.9916, where its seat draws 0.9997); in a cluster, one block seated
/// anew lets the next find its pose. Run before the runs of one body rather than after
/// them: the runs then refine the seated blocks (on 14 planted block problems, after
/// the runs it gained less: 0.9981 against 0.9997 on boxes 11204).
fn polish_moves(
    problem: &Problem,
    held: &Held,
    stage: &Stage,
    params: &mut [f64],
    best: &mut Evaluation,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (usize, usize) {
    let contacts = problem.scene.contacts;
    let rank = |e: &Evaluation| rank_value(e, contacts);
    let (kept, kept_eval) = (params.to_vec(), *best);
    let seats = moves::improve(
        problem,
        held,
        &stage.vary,
        &stage.weights,
        &rank,
        params,
        best,
        moves::MoveOptions {
            max_moves: stage.vary.len(),
            polish_single: true,
            trades: false,
            seat_blocks: true,
            evolve_fits: true,
        },
        ws,
        record,
    );
    let (samples, mut seated) = (seats.samples, seats.accepted);
    if best.iou < kept_eval.iou {
        params.copy_from_slice(&kept);
        *best = kept_eval;
        seated = 0;
    }
    (samples, seated)
}

/// One CMA-ES run of `run` (its bodies, step, population, iteration cap and stagnation)
/// from `from`, the other bodies held: the best launch (`from` itself when no sample
/// ranks better), its rank, and the samples drawn.
#[allow(clippy::too_many_arguments)]
fn local_run(
    problem: &Problem,
    pool: &Pool,
    run: &Stage,
    from: &[f64],
    ignore: Option<usize>,
    seed: u64,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (Vec<f64>, f64, usize) {
    let contacts = problem.scene.contacts;
    let mut held = problem.hold(from, &run.vary).for_stage(run);
    if let Some(j) = ignore {
        let mut flags = vec![false; problem.scene.occluders.len()];
        flags[j] = true;
        held.ignore_contacts_with(&flags);
    }
    let start = problem.evaluate_held(&held, from, &run.weights, ws);
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

/// The launch values a resumed solve starts from: the saved launch, and with free
/// positions the saved positions as offsets from the scene's.
fn resume_parameters(problem: &Problem, s: &Solution) -> Vec<f64> {
    let mut p = s.parameters();
    let n = problem.scene.occluders.len();
    p.resize(problem.variable_count(), 0.0);
    if problem.plan.free_positions {
        for (i, (o, l)) in problem.scene.occluders.iter().zip(&s.occluders).enumerate() {
            if let Some(pos) = l.position {
                let k = Launch::LEN * n + crate::evaluate::instants::POSITION_LEN * i;
                p[k] = pos[0] - o.position.x;
                p[k + 1] = pos[1] - o.position.y;
            }
        }
    }
    p
}

/// The robust stage's bookkeeping of its best: the iteration's best-ranked candidate,
/// evaluated on the reference draw, replaces `best` if it does better there. Returns its
/// index if it did.
#[allow(clippy::too_many_arguments)]
fn best_on_reference(
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

/// How far a solve got, as [`summarize`] records it.
#[derive(Clone, Copy, Debug)]
pub struct Run {
    pub seed: u64,
    pub stages_completed: usize,
    /// True when every stage ran to its own stop (not cut short by Ctrl-C).
    pub complete: bool,
    pub wall_time_s: f64,
    pub threads: usize,
}

/// Build a [`Solution`] for the launch values `params` after the stages `reports`.
pub fn summarize(
    problem: &Problem,
    params: &[f64],
    reports: &[StageReport],
    run: &Run,
    timing: Option<Vec<(String, f64)>>,
) -> Solution {
    let Run {
        seed,
        stages_completed,
        complete,
        wall_time_s,
        threads,
    } = *run;
    let scene = &problem.scene;
    let mut ws = problem.workspace();
    let all = problem.evaluate(params, &Weights::all_ones(), &mut ws);
    let weights = scene.stages[stages_completed.clamp(1, scene.stages.len()) - 1].weights;
    let weighted = weights.weigh(&all.raw);
    let total: f64 = weighted.iter().sum();
    let energy = Term::ALL
        .iter()
        .map(|&t| {
            let (raw, weighted) = (all.raw[t as usize], weighted[t as usize]);
            (t.key().to_string(), TermValue { raw, weighted })
        })
        .collect();
    let occluders = scene
        .occluders
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let launch = Launch::get(params, i);
            OccluderLaunch {
                name: o.name.clone(),
                launched: o.launched,
                velocity: launch.velocity.to_array(),
                angular_velocity: launch.angular_velocity.to_array(),
                position: (problem.plan.free_positions && o.launched)
                    .then(|| problem.launch_position(params, i).to_array()),
            }
        })
        .collect();
    let mut s = Solution {
        scene: scene.name.clone(),
        scene_file: Some(
            std::path::absolute(&scene.source)
                .unwrap_or_else(|_| scene.source.clone())
                .display()
                .to_string(),
        ),
        seed,
        t: scene.t,
        stages_total: scene.stages.len(),
        stages_completed,
        complete,
        occluders,
        energy,
        total_energy: total,
        iou: all.iou,
        t_sim: all.outcome.t_sim,
        n_contacts: all.outcome.n_contacts,
        samples: reports.iter().map(|r| r.samples).sum(),
        iterations: reports.iter().map(|r| r.iterations).sum(),
        wall_time_s,
        threads,
        time_per_term_us: timing.unwrap_or_default().into_iter().collect(),
        stages: reports.to_vec(),
        frames: Vec::new(),
        shadows_per_sample: None,
        air: None,
        robust: None,
        attempts: Vec::new(),
    };
    describe_plan(problem, params, &mut ws, &mut s);
    s
}

/// What a solution records of a plan beyond one shadow at `t`: the IoU at every frame,
/// the shadows per sample, the air and the launch errors.
fn describe_plan(problem: &Problem, params: &[f64], ws: &mut Workspace, s: &mut Solution) {
    let plan = &problem.plan;
    if !problem.scene.single_instant() {
        s.frames = problem
            .frame_ious(params, ws)
            .into_iter()
            .map(|f| FrameRecord {
                t_s: f.t,
                picture: f.picture,
                iou: f.iou,
            })
            .collect();
    }
    let shadows = plan.shadows_per_sample();
    s.shadows_per_sample = (shadows > 1).then_some(shadows);
    if let Physics::Air { config, .. } = &plan.physics {
        s.air = Some(*config);
    }
    s.robust = plan.robust.map(|r| RobustRecord {
        tolerances: r.tolerances,
        draws: r.draws,
        quantile: r.quantile,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(total: f64, iou: f64, own_contact: f64) -> Evaluation {
        let mut e = Evaluation::diverged();
        e.total = total;
        e.iou = iou;
        e.outcome.own_contact = own_contact;
        e
    }

    #[test]
    fn every_run_of_a_stage_draws_about_the_samples_of_the_first() {
        // 80 iterations of 24, then restarts of 48, 96 and 192 (a population that does
        // not divide the budget rounds the cap up).
        for (population, cap) in [(24, 80), (48, 40), (96, 20), (192, 10), (500, 4)] {
            assert_eq!(run_iterations(80, 24, population), cap);
            assert!(cap * population >= 80 * 24 && (cap - 1) * population < 80 * 24);
        }
        assert_eq!(run_iterations(1, 24, 10_000), 1);
    }

    #[test]
    fn the_first_attempt_keeps_the_seed_and_later_ones_draw_others() {
        assert_eq!(attempt_seed(7, 0), 7);
        let seeds: Vec<u64> = (0..4).map(|a| attempt_seed(7, a)).collect();
        for (k, a) in seeds.iter().enumerate() {
            assert!(!seeds[k + 1..].contains(a), "{seeds:?}");
        }
        // Neighbouring seeds' second attempts are unrelated, not neighbours themselves.
        assert!(attempt_seed(8, 1).abs_diff(attempt_seed(7, 1)) > 1 << 20);
    }

    #[test]
    fn an_attempt_with_a_contact_never_outranks_a_contact_free_one() {
        assert!(picture_rank(0, 0.90) < picture_rank(1, 0.99));
        assert!(picture_rank(0, 0.99) < picture_rank(0, 0.90));
        assert!(picture_rank(2, 0.99) < picture_rank(1, 0.90));
    }

    #[test]
    fn only_a_run_that_moved_the_picture_restarts() {
        let c = Contacts::Constraint;
        let start = eval(1.0, 0.90, 0.0);
        // Lower energy but the same picture: a run that settled.
        assert!(!run_moved_picture(
            0.001,
            &start,
            &eval(0.99, 0.9005, 0.0),
            c
        ));
        // The picture moved by a thousandth or more.
        assert!(run_moved_picture(0.001, &start, &eval(0.9, 0.902, 0.0), c));
        // Nothing better at all.
        assert!(!run_moved_picture(0.0, &start, &start, c));
        // A run that removed its stage's contact restarts whatever the IoU did.
        let stuck = eval(1.0, 0.95, 0.01);
        assert!(run_moved_picture(0.001, &stuck, &eval(2.0, 0.94, 0.0), c));
    }
}
