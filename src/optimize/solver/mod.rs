//! The optimisation driver: a [`Schedule`] of passes over the scene's stages.
//!
//! Main types: [`SolveOptions`], [`Schedule`] (the passes of every stage and their
//! guards, as data, with the table of thresholds), [`Observer`] (how the caller
//! watches and saves: the CLI draws progress bars, writes previews and saves after
//! every stage; this module touches no file), [`Solution`] (what `solution.json`
//! holds, with a [`PassRecord`] for every pass that ran) and [`SampleRecord`] (one row
//! of `convergence.csv`).
//!
//! Data flow of [`solve`]: attempts ([`Schedule::attempts`]) of [`attempt`], the second
//! run ahead in the idle scheduling class while the first runs (`ahead`); an
//! attempt runs each stage (a scheduled stage, or one occluder of the sequential
//! strategy, then the final joint stage) from the best launch of the previous one,
//! the others held fixed, through the schedule's passes (`stage`): moves, CMA-ES runs
//! whose populations are evaluated in parallel on a rayon pool with one [`Workspace`]
//! per thread (`search`), and the one-body runs of the last stage's polish
//! (`refine`).
//!
//! Determinism: candidates come from one seeded RNG per stage in `ask`, and each
//! sample's energy is a pure function of its launch values, so the result is
//! bit-identical for a seed whatever the number of threads.
//!
//! Interrupts: the caller passes a counter that a Ctrl-C handler increments. One
//! interrupt ends the current stage (the next one starts from its best); a second one
//! stops the solve, which still returns the best so far.

mod ahead;
pub mod cost;
mod refine;
pub mod schedule;
mod search;
mod stage;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use ahead::{Ahead, Idle};
pub use schedule::Schedule;
use search::{stop_name, Pool};
use stage::{StageEnd, StageRun};

use crate::energy::{Term, Weights};
use crate::evaluate::{Held, Physics, Problem, Workspace};
use crate::output::solution::{
    AttemptRecord, FrameRecord, OccluderLaunch, PassRecord, RobustRecord, SampleRecord, Solution,
    StageReport, TermValue,
};
use crate::scene::{Launch, Stage};
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
    /// The passes and attempts: [`Schedule::DEFAULT`] for `bsa solve`,
    /// [`Schedule::TRIAL`] for `bsa new`'s trial solves.
    pub schedule: Schedule,
    /// Stop at this wall time from the start of the solve, with the best picture so far
    /// as a complete result: the run under way ends, and the passes and stages left
    /// are skipped (each skipped stage reported as such).
    pub time_limit: Option<std::time::Duration>,
    /// Run the stages before this index only (the solution then has that many stages
    /// completed, and a later solve may resume it): the budget of a design's trial in
    /// `bsa new`'s race. `None`: every stage.
    pub until_stage: Option<usize>,
}

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
    /// Called after each stage with the solution so far (save it: nothing is lost) and
    /// the records the stage added (every sample since the attempt's last stage).
    fn stage_finished(&mut self, _solution: &Solution, _rows: &[SampleRecord]) {}
    /// A later attempt `attempt` (counted from 0) of at most `attempts` starts from the
    /// start guess with `seed`, the solution kept so far being `kept`.
    fn attempt_started(&mut self, _attempt: usize, _attempts: usize, _kept: &Solution, _seed: u64) {
    }
    /// A stage of a later attempt ended, with that attempt's solution so far (not to be
    /// saved: the solution kept is the one saved) and the records the stage added (the
    /// solve's records hold them after those of the attempts before).
    fn attempt_stage_finished(&mut self, _solution: &Solution, _rows: &[SampleRecord]) {}
}

/// An observer that ignores everything (tests, benchmarks).
pub struct Silent;
impl Observer for Silent {}

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
    let deadline = options.time_limit.map(|limit| started + limit);
    let threads = options
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let attempts = options.schedule.attempts.max(1);
    // The second attempt runs ahead of the first where a core is spare for it and it
    // could be wanted (a robust solve's never is).
    let ahead = threads > 1 && attempts > 1 && problem.plan.robust.is_none();
    let pool = Pool::new(problem, threads.max(1));
    let idle = Idle::default();
    let pool_ahead = ahead.then(|| {
        let idle = idle.clone();
        Pool::with_start(problem, threads, move || idle.enter())
    });
    let stop_ahead = AtomicUsize::new(0);
    let later = SolveOptions {
        resume: None,
        ..options.clone()
    };
    // Attempt `a` from the start, or resumed from a solution of its finished stages.
    let run_later = |a: usize, from: Option<Solution>, observer: &mut dyn Observer| {
        let resumed;
        let options = match from {
            Some(s) => {
                resumed = SolveOptions {
                    resume: Some(s),
                    ..later.clone()
                };
                &resumed
            }
            None => &later,
        };
        let at = (attempt_seed(seed, a), a, deadline);
        attempt(problem, options, &pool, at, observer, interrupts)
    };
    std::thread::scope(|scope| {
        let mut next = pool_ahead.as_ref().map(|pool_ahead| {
            let at = (attempt_seed(seed, 1), 1, deadline);
            Ahead::spawn(scope, problem, &later, (pool_ahead, &idle), at, &stop_ahead)
        });
        let (mut kept, mut records) = attempt(
            problem,
            options,
            &pool,
            (seed, 0, deadline),
            observer,
            interrupts,
        );
        let target = scene.stages.last().map_or(1.0, |s| s.restart_iou);
        let mut tried = vec![attempt_record(&kept, true)];
        let mut iterations = kept.iterations;
        let mut passes = kept.passes.clone();
        for a in 1..attempts {
            let wanted = kept.complete
                && kept.iou < target
                && problem.plan.robust.is_none()
                && interrupts.load(Ordering::SeqCst) == 0
                && deadline.is_none_or(|d| Instant::now() < d);
            if !wanted {
                break;
            }
            let seed_a = attempt_seed(seed, a);
            observer.attempt_started(a, attempts, &kept, seed_a);
            let mut later_observer = LaterAttempt(&mut *observer);
            let (s, more) = match next.take() {
                Some(running) => {
                    let resume = |from, o: &mut dyn Observer| run_later(a, from, o);
                    running.replay(problem, &mut later_observer, interrupts, &resume)
                }
                None => run_later(a, None, &mut later_observer),
            };
            records.extend(more);
            passes.extend(s.passes.iter().cloned());
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
        if let Some(running) = next {
            running.cancel();
        }
        if tried.len() > 1 {
            kept.samples = tried.iter().map(|t| t.samples).sum();
            kept.iterations = iterations;
            kept.wall_time_s = options.resume.as_ref().map_or(0.0, |s| s.wall_time_s)
                + started.elapsed().as_secs_f64();
            kept.attempts = tried;
            kept.passes = passes;
        }
        (kept, records)
    })
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
    fn stage_finished(&mut self, solution: &Solution, rows: &[SampleRecord]) {
        self.0.attempt_stage_finished(solution, rows);
    }
}

/// Where an attempt begins: the start guess, or a saved solution's launch and the
/// records of its completed stages (a stage that a stop cut short runs again, from the
/// saved best).
struct Begun {
    params: Vec<f64>,
    first_stage: usize,
    reports: Vec<StageReport>,
    passes: Vec<PassRecord>,
    prior_time: f64,
}

impl Begun {
    fn of(problem: &Problem, resume: Option<&Solution>) -> Begun {
        match resume {
            Some(s) => {
                let done = s.stages_completed.min(s.stages.len());
                Begun {
                    params: resume_parameters(problem, s),
                    first_stage: s.stages_completed,
                    reports: s.stages[..done].to_vec(),
                    passes: s
                        .passes
                        .iter()
                        .filter(|p| p.stage < done)
                        .cloned()
                        .collect(),
                    prior_time: s.wall_time_s,
                }
            }
            None => Begun {
                params: problem.start_parameters(),
                first_stage: 0,
                reports: Vec::new(),
                passes: Vec::new(),
                prior_time: 0.0,
            },
        }
    }
}

/// What `stage` holds fixed, computed once (a sample only pays for what varies) from
/// `params`. Bodies no stage has moved yet (`unplaced`, updated) are still at their
/// start guess: the bodies being placed need not go around them (they will move), only
/// around those placed.
fn held_for(problem: &Problem, params: &[f64], stage: &Stage, unplaced: &mut [bool]) -> Held {
    let mut held = problem.hold(params, &stage.vary).for_stage(stage);
    held.ignore_contacts_with(unplaced);
    for &i in &stage.vary {
        unplaced[i] = false;
    }
    held
}

/// The report of `stage`, begun at `started`, as it ended (`stopped`: by a second
/// interrupt).
fn stage_report(stage: &Stage, end: &StageEnd, stopped: bool, started: Instant) -> StageReport {
    let stop = if stopped {
        stop_name(end.stop, end.interrupted, true)
    } else {
        let mut text = match end.out_of_time {
            true => "time limit".to_string(),
            false => stop_name(end.stop, end.interrupted, false),
        };
        text.push_str(end.polish.as_deref().unwrap_or(""));
        if end.kept_start {
            text.push_str("; kept its start, the better picture");
        }
        text
    };
    StageReport {
        name: stage.name.clone(),
        iterations: end.iterations,
        samples: end.samples,
        population: end.population,
        restarts: end.restarts,
        best_energy: end.eval.total,
        iou: end.eval.iou,
        stop,
        wall_time_s: started.elapsed().as_secs_f64(),
    }
}

/// One attempt (`a`, counted from 0): the stages from the start guess (or from a
/// resumed solution) with `seed`, each through the schedule's passes, until the
/// `deadline` if any.
fn attempt(
    problem: &Problem,
    options: &SolveOptions,
    pool: &Pool,
    (seed, a, deadline): (u64, usize, Option<Instant>),
    observer: &mut dyn Observer,
    interrupts: &AtomicUsize,
) -> (Solution, Vec<SampleRecord>) {
    let scene = &problem.scene;
    let threads = pool.threads();
    let start = Instant::now();
    let mut records = Vec::new();
    // The records already handed to the observer with a finished stage.
    let mut reported = 0;
    let Begun {
        mut params,
        first_stage,
        mut reports,
        mut passes,
        prior_time,
    } = Begun::of(problem, options.resume.as_ref());
    let mut aborted = false;
    // Occluders that no stage has varied yet (a resumed solve has varied those of its
    // completed stages).
    let mut unplaced = vec![true; scene.occluders.len()];
    for stage in &scene.stages[..first_stage.min(scene.stages.len())] {
        for &i in &stage.vary {
            unplaced[i] = false;
        }
    }
    // The scene's last stage of one body: the settings of the one-body runs of the last
    // stage's polish.
    let one_body = scene.stages.iter().rev().find(|s| s.vary.len() == 1);
    let until = options.until_stage.unwrap_or(usize::MAX);
    for (k, stage) in scene
        .stages
        .iter()
        .enumerate()
        .skip(first_stage)
        .take_while(|(k, _)| *k < until)
    {
        if interrupts.load(Ordering::SeqCst) >= 2 {
            aborted = true;
            break;
        }
        observer.stage_started(k, stage);
        let stage_start = Instant::now();
        let held = held_for(problem, &params, stage, &mut unplaced);
        let mut run = StageRun::new(
            problem,
            pool,
            k,
            seed,
            one_body,
            held,
            &params,
            observer,
            interrupts,
            &mut records,
            &mut passes,
        );
        run.attempt = a;
        run.deadline = deadline;
        let end = run.run(&options.schedule);
        params.copy_from_slice(&end.launch);
        // A second interrupt during the stage stops the solve: the stage does not count
        // as completed, so that `--resume` runs it again from the best so far.
        let stopped = end.interrupted && interrupts.load(Ordering::SeqCst) >= 2;
        reports.push(stage_report(stage, &end, stopped, stage_start));
        let run = Run {
            seed,
            stages_completed: if stopped { k } else { k + 1 },
            complete: false,
            wall_time_s: prior_time + start.elapsed().as_secs_f64(),
            threads,
        };
        let mut s = summarize(problem, &params, &reports, &run, None);
        s.passes = passes.clone();
        observer.stage_finished(&s, &records[reported..]);
        reported = records.len();
        if stopped {
            aborted = true;
            break;
        }
        if end.out_of_time {
            // The stages left are skipped: the solve is complete at its time limit.
            reports.extend(scene.stages[k + 1..].iter().map(|skipped| StageReport {
                name: skipped.name.clone(),
                iterations: 0,
                samples: 0,
                population: 0,
                restarts: 0,
                best_energy: end.eval.total,
                iou: end.eval.iou,
                stop: "skipped (time limit)".into(),
                wall_time_s: 0.0,
            }));
            break;
        }
    }
    let run = Run {
        seed,
        stages_completed: 0,
        complete: false,
        wall_time_s: prior_time + start.elapsed().as_secs_f64(),
        threads,
    };
    (
        finish(problem, &params, &reports, passes, aborted, run),
        records,
    )
}

/// The solution of an attempt that ran `reports` (`aborted` by a stop) to `params`,
/// with its per-phase profile: a stage cut short by a stop is reported but not
/// completed, and an attempt is complete when every stage ran to its own stop.
fn finish(
    problem: &Problem,
    params: &[f64],
    reports: &[StageReport],
    passes: Vec<PassRecord>,
    aborted: bool,
    mut run: Run,
) -> Solution {
    let cut = aborted
        && reports
            .last()
            .is_some_and(|r| r.stop.starts_with("stopped"));
    run.stages_completed = reports.len() - usize::from(cut);
    run.complete = !aborted
        && run.stages_completed == problem.scene.stages.len()
        && reports.iter().all(|r| !r.stop.starts_with("interrupted"));
    let mut ws = problem.workspace();
    let timing = problem.profile(params, profile_reps(problem, params, &mut ws), &mut ws);
    let mut s = summarize(problem, params, reports, &run, Some(timing));
    s.passes = passes;
    s
}

/// Repetitions of the per-phase profile in `solution.json`: as many as fit in about
/// 10 ms (a profile repetition costs about two samples), from 5 to 100.
fn profile_reps(problem: &Problem, params: &[f64], ws: &mut Workspace) -> usize {
    let start = Instant::now();
    problem.evaluate(params, &Weights::all_ones(), ws);
    let sample = start.elapsed().as_secs_f64().max(1e-9);
    ((0.01 / (2.0 * sample)) as usize).clamp(5, 100)
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
        passes: Vec::new(),
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
    use super::search::{run_iterations, run_moved_picture};
    use super::*;
    use crate::evaluate::Evaluation;
    use crate::scene::Contacts;

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
