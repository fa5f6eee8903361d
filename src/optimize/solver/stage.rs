//! One stage of a solve: its [`Schedule`]'s passes run in order on the stage's
//! state ([`StageRun`]), each recorded as a [`PassRecord`].
//!
//! Data flow: the stage starts from the previous stage's best launch; [`Pass::Moves`]
//! jumps, [`Pass::Runs`] runs CMA-ES (IPOP restarts, each after a round of moves),
//! [`Pass::Trades`] and [`Pass::Polish`] mend what the runs leave in the last stage;
//! the stage never ends worse than it started (last stage) and reports to the
//! observer.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use super::refine::polish;
use super::schedule::{Judge, Pass, Schedule, Step, When, TRADE_MOVES};
use super::search::{
    best_on_reference, rank_value, restart_seed, run_iterations, run_moved_picture, stage_seed,
    Pool,
};
use super::{IterationInfo, Observer};
use crate::energy::{Term, Weights};
use crate::evaluate::{Evaluation, Held, Problem, Workspace};
use crate::optimize::cmaes::{Cmaes, CmaesConfig, StopReason};
use crate::optimize::moves::{self, MoveOptions, MoveReport, Purpose};
use crate::output::solution::{MoveRecord, PassRecord, SampleRecord};
use crate::scene::Stage;
use crate::shadow::mask::Mask;

/// What a stage ended with.
pub(super) struct StageEnd {
    pub launch: Vec<f64>,
    pub eval: Evaluation,
    pub samples: usize,
    pub iterations: usize,
    pub population: usize,
    pub restarts: usize,
    pub interrupted: bool,
    /// Whether the solve's time limit ended the stage.
    pub out_of_time: bool,
    pub stop: Option<StopReason>,
    /// What the polish did, for the stage's stop text.
    pub polish: Option<String>,
    /// Whether the stage kept its start, the better picture.
    pub kept_start: bool,
}

/// The state of one stage while its passes run.
pub(super) struct StageRun<'a> {
    pub problem: &'a Problem,
    pub pool: &'a Pool,
    /// The stage's index in the scene.
    pub k: usize,
    /// The attempt's seed.
    pub seed: u64,
    pub given: &'a Stage,
    unhinted: Stage,
    /// The scene's last stage of one body: the settings of the one-body runs.
    pub one_body: Option<&'a Stage>,
    pub last: bool,
    pub robust: bool,
    pub held: Held,
    pub observer: &'a mut dyn Observer,
    pub interrupts: &'a AtomicUsize,
    pub records: &'a mut Vec<SampleRecord>,
    pub passes: &'a mut Vec<PassRecord>,
    pub attempt: usize,
    /// When the solve must stop (`bsa solve --time-limit`).
    pub deadline: Option<Instant>,
    out_of_time: bool,
    interrupts_at_start: usize,
    started: Instant,
    best: Vec<f64>,
    eval: Evaluation,
    start: (Vec<f64>, Evaluation),
    mask: Mask,
    ws: Workspace,
    iteration: usize,
    samples: usize,
    restart: usize,
    lambda: usize,
    population: usize,
    interrupted: bool,
    stop: Option<StopReason>,
    judge: Judge,
    /// The best before the current run's moves: what a restart asks the run to have
    /// improved on.
    run_start: Evaluation,
    /// The last round of moves before a run, and whether it traded.
    moved: Option<(MoveReport, Purpose)>,
    /// The moves taken since the last pass's record.
    taken: Vec<MoveRecord>,
    polish: Option<String>,
}

impl<'a> StageRun<'a> {
    /// A stage from `params` (every body's launch), `held` computed for it.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        problem: &'a Problem,
        pool: &'a Pool,
        k: usize,
        seed: u64,
        one_body: Option<&'a Stage>,
        held: Held,
        params: &[f64],
        observer: &'a mut dyn Observer,
        interrupts: &'a AtomicUsize,
        records: &'a mut Vec<SampleRecord>,
        passes: &'a mut Vec<PassRecord>,
    ) -> StageRun<'a> {
        let scene = &problem.scene;
        let given = &scene.stages[k];
        let mut unhinted = given.clone();
        unhinted.weights.0[Term::Hint as usize] = 0.0;
        let mut ws = problem.workspace();
        let eval = problem.evaluate_held(&held, params, &given.weights, &mut ws);
        StageRun {
            problem,
            pool,
            k,
            seed,
            given,
            unhinted,
            one_body,
            last: k + 1 == scene.stages.len(),
            robust: problem.plan.robust.is_some(),
            held,
            observer,
            interrupts,
            records,
            passes,
            attempt: 0,
            deadline: None,
            out_of_time: false,
            interrupts_at_start: interrupts.load(Ordering::SeqCst),
            started: Instant::now(),
            best: params.to_vec(),
            eval,
            start: (params.to_vec(), eval),
            mask: ws.mask.clone(),
            ws,
            iteration: 0,
            samples: 0,
            restart: 0,
            lambda: 0,
            population: given.population,
            interrupted: false,
            stop: None,
            judge: Judge::Stage,
            run_start: eval,
            moved: None,
            taken: Vec::new(),
            polish: None,
        }
    }

    /// Run `schedule`'s passes whose guards hold, then end the stage.
    pub fn run(mut self, schedule: &Schedule) -> StageEnd {
        for step in schedule.stage {
            if self.wanted(step) {
                let (before, samples, clock) = (self.eval.iou, self.samples, Instant::now());
                self.judge = step.judge;
                match step.pass {
                    Pass::Moves => self.moves(),
                    Pass::Runs => self.runs(),
                    Pass::Trades => self.trades(),
                    Pass::Polish => self.polish(),
                }
                self.passes.push(PassRecord {
                    attempt: self.attempt,
                    stage: self.k,
                    pass: step.pass.name().to_string(),
                    iou_before: before,
                    iou_after: self.eval.iou,
                    samples: self.samples - samples,
                    wall_time_s: clock.elapsed().as_secs_f64(),
                    moves: std::mem::take(&mut self.taken),
                });
            }
        }
        self.end()
    }

    /// Whether `step` runs now.
    fn wanted(&mut self, step: &Step) -> bool {
        if self.interrupted || self.timed_out() {
            return false;
        }
        let searches = !self.robust || matches!(step.pass, Pass::Moves | Pass::Runs);
        searches
            && match step.when {
                When::Always => true,
                When::LastStageBelow(t) => {
                    self.last
                        && self.stop != Some(StopReason::TargetReached)
                        && self.eval.iou < t.value
                }
                When::LastJointStageBelowRestartIou => {
                    self.last
                        && self.given.vary.len() > 1
                        && self.one_body.is_some()
                        && self.eval.iou < self.given.restart_iou
                }
            }
    }

    /// Whether the solve's time limit has passed (and from then on, that it had).
    fn timed_out(&mut self) -> bool {
        self.out_of_time |= self.deadline.is_some_and(|d| Instant::now() >= d);
        self.out_of_time
    }

    /// The stage as the current judge weighs it.
    fn judged(&self) -> &Stage {
        match self.judge {
            Judge::Stage => self.given,
            Judge::NoHints => &self.unhinted,
        }
    }

    fn weights(&self) -> Weights {
        self.judged().weights
    }

    /// Evaluate the best launch under `weights` into `self.eval` (and the workspace).
    fn rejudge(&mut self, weights: &Weights) {
        self.eval = self
            .problem
            .evaluate_held(&self.held, &self.best, weights, &mut self.ws);
    }

    /// A round of moves from the best (see [`moves::improve`]), at most `max_moves`,
    /// for `purpose`; remembered for the next run's start.
    fn round_of_moves(&mut self, max_moves: usize, purpose: Purpose) {
        let (problem, k, iteration) = (self.problem, self.k, self.iteration);
        let contacts = problem.scene.contacts;
        let weights = self.weights();
        let records = &mut *self.records;
        let moved = moves::improve(
            problem,
            &self.held,
            &self.given.vary,
            &weights,
            &|e: &Evaluation| rank_value(e, contacts),
            &mut self.best,
            &mut self.eval,
            MoveOptions {
                max_moves,
                settled: self.restart > 0 || self.given.vary.len() > 1,
                purpose,
            },
            self.pool.rayon(),
            &mut self.ws,
            &mut |e: &Evaluation| records.push(sample_record(k, iteration, &weights, e)),
        );
        self.samples += moved.samples;
        if !moved.taken.is_empty() {
            self.mask.copy_from(&self.ws.mask);
        }
        self.taken.extend_from_slice(&moved.taken);
        self.moved = Some((moved, purpose));
    }

    /// [`Pass::Moves`]: a round of moves of as many moves as the stage has bodies.
    fn moves(&mut self) {
        self.run_start = self.eval;
        self.round_of_moves(self.given.vary.len(), Purpose::Stage);
    }

    /// [`Pass::Runs`]: CMA-ES runs from the best, each after the moves before it (the
    /// first after the last round of moves, if any); another run (IPOP) while the last
    /// one moved the picture, the IoU is below `restart_iou` and restarts are left.
    fn runs(&mut self) {
        let stage = self.given;
        loop {
            let start_from = match self.moved.take() {
                Some((moved, purpose)) => moved
                    .promising
                    .filter(|_| moved.taken.is_empty() || purpose == Purpose::Trade),
                None => {
                    self.moves();
                    let (moved, _) = self.moved.take().expect("the moves just ran");
                    moved.promising.filter(|_| moved.taken.is_empty())
                }
            };
            self.stop = self.cmaes(start_from);
            let contacts = self.problem.scene.contacts;
            let restartable = !self.interrupted
                && !self.out_of_time
                && self.stop != Some(StopReason::TargetReached)
                && self.restart < stage.restarts
                && self.eval.iou < stage.restart_iou
                && run_moved_picture(stage.restart_gain, &self.run_start, &self.eval, contacts);
            if !restartable {
                return;
            }
            self.restart += 1;
            self.population *= 2;
            self.observer
                .restarted(self.k, self.restart, self.population);
        }
    }

    /// One CMA-ES run of the stage from `from` (the best when `None`), with the stage's
    /// population and seed of this restart. Returns why it stopped (`None`: an
    /// interrupt).
    fn cmaes(&mut self, from: Option<Vec<f64>>) -> Option<StopReason> {
        let problem = self.problem;
        let contacts = problem.scene.contacts;
        let stage = self.judged().clone();
        let n = problem.stage_variable_count(&stage.vary);
        let mut x0 = vec![0.0; n];
        problem.stage_start(from.as_deref().unwrap_or(&self.best), &stage.vary, &mut x0);
        let config = CmaesConfig {
            population: Some(self.population),
            max_generations: run_iterations(
                stage.max_iterations,
                stage.population,
                self.population,
            ),
            f_target: stage.target_energy,
            tol_fun: stage.tol_fun,
            stagnation_window: stage.stagnation,
            ..CmaesConfig::default()
        };
        let seed = restart_seed(self.seed, self.k, self.restart);
        let mut cma = Cmaes::new(&x0, stage.step, config, seed);
        if self.restart == 0 {
            self.lambda = cma.population();
        }
        let pop = cma.population();
        self.population = pop;
        let mut evals = vec![Evaluation::diverged(); pop];
        let mut fitness = vec![0.0; pop];
        let mut candidates = vec![0.0; pop * n];
        let mut scratch = vec![0.0; self.best.len()];
        // The launch values the candidates expand on: the stage's start (a candidate
        // sets every value the stage varies).
        let base = self.start.0.clone();
        loop {
            if self.interrupts.load(Ordering::SeqCst) > self.interrupts_at_start {
                self.interrupted = true;
                return None;
            }
            if self.timed_out() {
                return None;
            }
            candidates.copy_from_slice(cma.ask());
            // Common random numbers: one draw of launch errors per iteration.
            let draw = stage_seed(stage_seed(self.seed, self.k), self.iteration);
            self.pool.evaluate(
                problem,
                &self.held,
                &stage,
                &candidates,
                n,
                draw,
                &mut evals,
            );
            let mut improved = None;
            for (j, e) in evals.iter().enumerate() {
                fitness[j] = rank_value(e, contacts);
                self.records
                    .push(sample_record(self.k, self.iteration, &stage.weights, e));
                if !self.robust && fitness[j] < rank_value(&self.eval, contacts) {
                    self.eval = *e;
                    improved = Some(j);
                }
            }
            if self.robust {
                // Energies of different iterations met different errors: the
                // iteration's best is compared with the stage's best on the reference
                // draw.
                improved = best_on_reference(
                    problem,
                    &self.held,
                    &stage,
                    &base,
                    &candidates,
                    &fitness,
                    &mut self.eval,
                    &mut scratch,
                    &mut self.ws,
                );
            }
            if let Some(j) = improved {
                problem.expand(
                    &base,
                    &stage.vary,
                    &candidates[j * n..(j + 1) * n],
                    &mut scratch,
                );
                self.best.copy_from_slice(&scratch);
                problem.evaluate_held(&self.held, &self.best, &stage.weights, &mut self.ws);
                self.mask.copy_from(&self.ws.mask);
            }
            cma.tell(&fitness);
            self.iteration += 1;
            self.samples += pop;
            let elapsed = self.started.elapsed().as_secs_f64();
            self.observer.iteration(&IterationInfo {
                stage_index: self.k,
                stage: &stage,
                iteration: self.iteration,
                restart: self.restart,
                samples: self.samples,
                best_energy: self.eval.total,
                best_iou: self.eval.iou,
                samples_per_second: self.samples as f64 / elapsed.max(1e-9),
                best_shadow: &self.mask,
            });
            if let Some(s) = cma.stop() {
                return Some(s);
            }
        }
    }

    /// [`Pass::Trades`]: moves that trade places among bodies (at most
    /// [`TRADE_MOVES`]); after a trade taken, runs again. A stage where no trade draws a
    /// better picture ends as its runs did, judged as before.
    fn trades(&mut self) {
        let run_start = self.eval;
        self.rejudge(&self.weights());
        self.round_of_moves(TRADE_MOVES.value as usize, Purpose::Trade);
        let (moved, _) = self.moved.as_ref().expect("the moves just ran");
        if !moved.taken.is_empty() {
            self.run_start = run_start;
            return self.runs();
        }
        self.moved = None;
        // No trade drew a better picture: the stage ends as its last run did, judged as
        // it ran.
        self.judge = Judge::Stage;
        let given = self.given.weights;
        self.rejudge(&given);
    }

    /// [`Pass::Polish`]: see [`polish`]; the stage's picture judged afterwards as its
    /// runs judged it.
    fn polish(&mut self) {
        let Some(template) = self.one_body else {
            return;
        };
        let before = self.eval.iou;
        let unhinted = self.unhinted.weights;
        self.rejudge(&unhinted);
        let (k, iteration, weights) = (self.k, self.iteration, self.given.weights);
        let records = &mut *self.records;
        let (used, taken, moved) = polish(
            self.problem,
            self.pool,
            &self.held,
            &self.unhinted,
            template,
            (&mut self.best, &mut self.eval),
            stage_seed(self.seed, k),
            &mut self.ws,
            &mut |e: &Evaluation| records.push(sample_record(k, iteration, &weights, e)),
        );
        self.samples += used;
        let seated = taken.len();
        self.taken.extend(taken);
        self.rejudge(&self.given.weights);
        self.mask.copy_from(&self.ws.mask);
        self.polish = Some(format!(
            "; moves taken: {seated}, polished {moved} of {} bodies, IoU {before:.4} to {:.4}",
            self.given.vary.len(),
            self.eval.iou
        ));
    }

    /// The stage's end: the last stage never leaves a worse picture than it started
    /// from (a joint stage can lower its total energy, hints and regularization, while
    /// the shadow gets worse).
    fn end(mut self) -> StageEnd {
        let (start, start_eval) = &self.start;
        let kept_start = self.last
            && self.eval.iou < start_eval.iou
            && start_eval.outcome.n_contacts <= self.eval.outcome.n_contacts;
        if kept_start {
            self.best.copy_from_slice(start);
            self.eval = *start_eval;
        }
        StageEnd {
            launch: self.best,
            eval: self.eval,
            samples: self.samples,
            iterations: self.iteration,
            population: self.lambda,
            restarts: self.restart,
            interrupted: self.interrupted,
            out_of_time: self.out_of_time,
            stop: self.stop,
            polish: self.polish,
            kept_start,
        }
    }
}

/// The record of one sample of stage `k` at `iteration`, its terms weighed by `weights`.
fn sample_record(k: usize, iteration: usize, weights: &Weights, e: &Evaluation) -> SampleRecord {
    SampleRecord {
        stage: k,
        iteration,
        terms: e.weighted(weights),
        total: e.total,
    }
}
