//! An attempt that runs ahead: while the first attempt runs, the second runs beside it
//! in the idle scheduling class, on a pool of its own ([`Ahead::spawn`], [`Idle`]), its
//! progress queued by a [`Relay`]. If the solve wants that attempt, [`Ahead::replay`]
//! raises its threads back to the normal class and hands its progress to the observer
//! as if it ran then. Where the system refuses (an unprivileged process may not leave
//! the idle class, and on a busy machine the attempt would starve), the attempt is
//! stopped and resumed in the normal class from its last finished stage
//! ([`Ahead::take_over`]). If the solve does not want it, [`Ahead::cancel`] stops it.
//!
//! Why: an attempt's CMA-ES updates and one-body refinements run on one thread, and a
//! population of a few samples keeps two cores busy only in part, so one attempt keeps
//! them about 1.5 times busy. The attempt ahead takes the idle
//! time, so a solve of one attempt is not slowed and one of two takes less time. Each
//! attempt's result is a function of its seed alone, and a resumed attempt ends where
//! it would have, so the solve's result is the same, bit for bit, as when its attempts
//! run one after another.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::{Duration, Instant};

use super::search::Pool;
use super::{attempt, IterationInfo, Observer, SolveOptions};
use crate::evaluate::Problem;
use crate::output::solution::{SampleRecord, Solution};
use crate::scene::Stage;
use crate::shadow::mask::Mask;

/// How often a queued attempt's best shadow is sent for the preview, at most (the
/// observer of `bsa solve` redraws its preview four times a second).
const SHADOW_EVERY: Duration = Duration::from_millis(250);

/// How often the replay looks at the caller's interrupts while it waits for progress.
const POLL: Duration = Duration::from_millis(50);

/// The threads of an attempt run ahead, by their kernel ids: [`Idle::enter`] puts the
/// calling thread in the idle scheduling class (it runs only on what the machine's other
/// threads leave), [`Idle::leave`] raises every thread entered back to the normal one.
/// Elsewhere than on Linux both do nothing and the threads compete evenly.
#[derive(Clone, Default)]
pub(super) struct Idle(Arc<Mutex<Vec<i64>>>);

impl Idle {
    /// Put the calling thread in the idle class, and remember it.
    pub(super) fn enter(&self) {
        #[cfg(target_os = "linux")]
        // SAFETY: gettid and sched_setscheduler take and return plain integers and a
        // parameter that outlives the call; on the calling thread's own id they change
        // only its class (a failure leaves it as it was, which is harmless).
        unsafe {
            let tid = libc::syscall(libc::SYS_gettid);
            let param = libc::sched_param { sched_priority: 0 };
            if libc::sched_setscheduler(tid as libc::pid_t, libc::SCHED_IDLE, &param) == 0 {
                self.0.lock().unwrap_or_else(|e| e.into_inner()).push(tid);
            }
        }
    }

    /// Raise every thread entered back to the normal class; `false` where the system
    /// refuses one (an unprivileged process may not leave the idle class).
    pub(super) fn leave(&self) -> bool {
        let ids = self.0.lock().unwrap_or_else(|e| e.into_inner());
        #[cfg(target_os = "linux")]
        // SAFETY: as in `enter`, on ids of threads of this process that the pool and
        // the attempt's thread keep alive while the attempt runs.
        unsafe {
            let param = libc::sched_param { sched_priority: 0 };
            ids.iter().all(|&tid| {
                libc::sched_setscheduler(tid as libc::pid_t, libc::SCHED_OTHER, &param) == 0
            })
        }
        #[cfg(not(target_os = "linux"))]
        {
            let _ = ids;
            true
        }
    }
}

/// One progress event of an attempt that runs ahead.
enum Event {
    StageStarted(usize),
    Iteration {
        stage_index: usize,
        iteration: usize,
        restart: usize,
        samples: usize,
        best_energy: f64,
        best_iou: f64,
        samples_per_second: f64,
        /// The stage's best shadow, at most every [`SHADOW_EVERY`].
        shadow: Option<Mask>,
    },
    Restarted(usize, usize, usize),
    /// A finished stage's solution, and its records.
    StageFinished(Box<Solution>, Vec<SampleRecord>),
}

/// The observer of an attempt that runs ahead: it queues the stages it is told of, and
/// the iterations once the attempt is replayed (`watched`: before, they would only
/// pile up, with a shadow each), and keeps its last finished stage's solution.
struct Relay {
    events: Sender<Event>,
    shadow_sent: Option<Instant>,
    finished: Finished,
    watched: Arc<AtomicBool>,
}

/// The solution of the last stage an attempt finished, as its observer last heard.
type Finished = Arc<Mutex<Option<Box<Solution>>>>;

impl Relay {
    /// Queue `event`; a replay that stopped listening (a cancelled attempt) is no error.
    fn send(&self, event: Event) {
        let _ = self.events.send(event);
    }
}

impl Observer for Relay {
    fn stage_started(&mut self, index: usize, _stage: &Stage) {
        self.send(Event::StageStarted(index));
    }

    fn iteration(&mut self, info: &IterationInfo) {
        if !self.watched.load(Ordering::Relaxed) {
            return;
        }
        let due = self.shadow_sent.is_none_or(|t| t.elapsed() >= SHADOW_EVERY);
        if due {
            self.shadow_sent = Some(Instant::now());
        }
        self.send(Event::Iteration {
            stage_index: info.stage_index,
            iteration: info.iteration,
            restart: info.restart,
            samples: info.samples,
            best_energy: info.best_energy,
            best_iou: info.best_iou,
            samples_per_second: info.samples_per_second,
            shadow: due.then(|| info.best_shadow.clone()),
        });
    }

    fn restarted(&mut self, index: usize, restart: usize, population: usize) {
        self.send(Event::Restarted(index, restart, population));
    }

    fn stage_finished(&mut self, solution: &Solution, rows: &[SampleRecord]) {
        let s = Box::new(solution.clone());
        *self.finished.lock().unwrap_or_else(|e| e.into_inner()) = Some(s.clone());
        self.send(Event::StageFinished(s, rows.to_vec()));
    }
}

/// An attempt running ahead on its own thread.
pub(super) struct Ahead<'scope> {
    handle: ScopedJoinHandle<'scope, (Solution, Vec<SampleRecord>)>,
    events: Receiver<Event>,
    /// The attempt's own interrupt counter: the caller's interrupts once it is wanted,
    /// 2 (a stop) when it is cancelled.
    stop: &'scope AtomicUsize,
    idle: &'scope Idle,
    finished: Finished,
    /// Whether the attempt is being replayed (its iterations are then queued).
    watched: Arc<AtomicBool>,
}

impl<'scope> Ahead<'scope> {
    /// Start attempt `a` (with `seed`, until `deadline`) on a thread of `scope` in the
    /// idle class, on `pool`, whose workers entered `idle`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spawn<'env>(
        scope: &'scope Scope<'scope, 'env>,
        problem: &'scope Problem,
        options: &'scope SolveOptions,
        (pool, idle): (&'scope Pool, &'scope Idle),
        at: (u64, usize, Option<Instant>),
        stop: &'scope AtomicUsize,
    ) -> Ahead<'scope> {
        Self::spawn_observed(scope, problem, options, (pool, idle), at, stop, |r| r)
    }

    /// [`Ahead::spawn`], the attempt observed by `observe(relay)` (tests stop it at a
    /// chosen point through an observer around the relay).
    #[allow(clippy::too_many_arguments)]
    fn spawn_observed<'env, O: Observer + Send + 'scope>(
        scope: &'scope Scope<'scope, 'env>,
        problem: &'scope Problem,
        options: &'scope SolveOptions,
        (pool, idle): (&'scope Pool, &'scope Idle),
        (seed, a, deadline): (u64, usize, Option<Instant>),
        stop: &'scope AtomicUsize,
        observe: impl FnOnce(Relay) -> O + Send + 'scope,
    ) -> Ahead<'scope> {
        let (tx, events) = mpsc::channel();
        let finished = Finished::default();
        let heard = finished.clone();
        let watched = Arc::new(AtomicBool::new(false));
        let seen = watched.clone();
        let handle = scope.spawn(move || {
            idle.enter();
            let mut observer = observe(Relay {
                events: tx,
                shadow_sent: None,
                finished: heard,
                watched: seen,
            });
            attempt(
                problem,
                options,
                pool,
                (seed, a, deadline),
                &mut observer,
                stop,
            )
        });
        Ahead {
            handle,
            events,
            stop,
            idle,
            finished,
            watched,
        }
    }

    /// Stop the attempt (it is not wanted) and wait for its thread.
    pub(super) fn cancel(self) {
        self.stop.store(2, Ordering::SeqCst);
        drop(self.events);
        let _ = self.handle.join();
    }

    /// Raise the attempt to the normal class and hand its progress, queued and to come,
    /// to `observer` until it ends, the caller's `interrupts` passed on to it; returns
    /// its result. Where it cannot be raised, [`Ahead::take_over`] with `resume`.
    pub(super) fn replay(
        self,
        problem: &Problem,
        observer: &mut dyn Observer,
        interrupts: &AtomicUsize,
        resume: Resume<'_>,
    ) -> (Solution, Vec<SampleRecord>) {
        if !self.idle.leave() {
            return self.take_over(problem, observer, resume);
        }
        self.watched.store(true, Ordering::Relaxed);
        let stages = &problem.scene.stages;
        let mut shadow: Option<Mask> = None;
        loop {
            self.stop
                .fetch_max(interrupts.load(Ordering::SeqCst), Ordering::SeqCst);
            let event = match self.events.recv_timeout(POLL) {
                Ok(event) => event,
                Err(RecvTimeoutError::Timeout) => continue,
                Err(RecvTimeoutError::Disconnected) => break,
            };
            match event {
                Event::StageStarted(k) => observer.stage_started(k, &stages[k]),
                Event::Restarted(k, restart, population) => {
                    observer.restarted(k, restart, population)
                }
                Event::StageFinished(s, rows) => observer.stage_finished(&s, &rows),
                Event::Iteration {
                    stage_index,
                    iteration,
                    restart,
                    samples,
                    best_energy,
                    best_iou,
                    samples_per_second,
                    shadow: sent,
                } => {
                    if sent.is_some() {
                        shadow = sent;
                    }
                    if let Some(best_shadow) = &shadow {
                        observer.iteration(&IterationInfo {
                            stage_index,
                            stage: &stages[stage_index],
                            iteration,
                            restart,
                            samples,
                            best_energy,
                            best_iou,
                            samples_per_second,
                            best_shadow,
                        });
                    }
                }
            }
        }
        join(self.handle)
    }

    /// Stop the attempt, hand the observer its stages, and run it on from its last
    /// finished stage by `resume` (from the start if it finished none): a resumed attempt
    /// ends where the attempt would have. Its records are those of its finished stages,
    /// then the resumed run's.
    pub(super) fn take_over(
        self,
        problem: &Problem,
        observer: &mut dyn Observer,
        resume: Resume<'_>,
    ) -> (Solution, Vec<SampleRecord>) {
        self.stop.store(2, Ordering::SeqCst);
        let stages = &problem.scene.stages;
        let mut completed = 0;
        for event in self.events.iter() {
            match event {
                Event::StageStarted(k) => observer.stage_started(k, &stages[k]),
                Event::StageFinished(s, rows) => {
                    // The rows of the stages it finished only: the stage the stop cut
                    // short runs again, and its rows are dropped below.
                    let finished = s.stages_completed > completed;
                    completed = s.stages_completed;
                    observer.stage_finished(&s, if finished { &rows } else { &[] });
                }
                Event::Iteration { .. } | Event::Restarted(..) => {}
            }
        }
        let (ended, mut records) = join(self.handle);
        if ended.complete {
            // It ended on its own before the stop.
            return (ended, records);
        }
        let finished = self
            .finished
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take();
        let from = finished.filter(|s| s.stages_completed > 0);
        let kept: usize = from.as_ref().map_or(0, |s| {
            s.stages[..s.stages_completed]
                .iter()
                .map(|r| r.samples)
                .sum()
        });
        records.truncate(kept);
        let (s, more) = resume(from.map(|s| *s), observer);
        records.extend(more);
        (s, records)
    }
}

/// How a solve runs an attempt on in the normal class: from a solution of its finished
/// stages (or from the start), with an observer.
pub(super) type Resume<'a> =
    &'a dyn Fn(Option<Solution>, &mut dyn Observer) -> (Solution, Vec<SampleRecord>);

/// The result of an attempt's thread (its panic passed on).
fn join(
    handle: ScopedJoinHandle<'_, (Solution, Vec<SampleRecord>)>,
) -> (Solution, Vec<SampleRecord>) {
    match handle.join() {
        Ok(result) => result,
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::solver::{attempt_seed, Schedule, Silent};

    /// The relay of an attempt run ahead, which stops the attempt (as a take-over
    /// would) at its `at`-th iteration after stage `stage` starts: where the take-over
    /// lands does not hang on how the test's thread and the attempt's are scheduled.
    struct StopAt<'a> {
        relay: Relay,
        stop: &'a AtomicUsize,
        stage: usize,
        at: usize,
        /// Iterations since stage `stage` started, once it has.
        seen: Option<usize>,
    }

    impl Observer for StopAt<'_> {
        fn stage_started(&mut self, index: usize, stage: &Stage) {
            if index == self.stage {
                self.seen = Some(0);
            }
            self.relay.stage_started(index, stage);
        }
        fn iteration(&mut self, info: &IterationInfo) {
            if let Some(seen) = self.seen.as_mut() {
                *seen += 1;
                if *seen == self.at {
                    self.stop.store(2, Ordering::SeqCst);
                }
            }
            self.relay.iteration(info);
        }
        fn restarted(&mut self, index: usize, restart: usize, population: usize) {
            self.relay.restarted(index, restart, population);
        }
        fn stage_finished(&mut self, solution: &Solution, rows: &[SampleRecord]) {
            self.relay.stage_finished(solution, rows);
        }
    }

    #[test]
    fn an_attempt_taken_over_part_way_ends_where_it_would_have_alone() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mickey");
        let mut scene = crate::scene::load(&dir).unwrap();
        for s in &mut scene.stages {
            s.max_iterations = 8;
            s.population = 16;
        }
        let last = scene.stages.len() - 1;
        assert!(last > 0, "the take-over must land after a finished stage");
        let problem = Problem::new(scene);
        let options = SolveOptions {
            threads: Some(1),
            seed: Some(5),
            schedule: Schedule::DEFAULT.with_attempts(2),
            ..SolveOptions::default()
        };
        let pool = Pool::new(&problem, 1);
        let none = AtomicUsize::new(0);
        let at = (attempt_seed(5, 1), 1, None);
        let (alone, alone_records) = attempt(&problem, &options, &pool, at, &mut Silent, &none);
        let (stop, idle) = (AtomicUsize::new(0), Idle::default());
        let resumed = std::cell::Cell::new(false);
        let mut told = Told::default();
        let (taken, records) = std::thread::scope(|scope| {
            // Stopped in the middle of its last stage.
            let stop_at = |relay| StopAt {
                relay,
                stop: &stop,
                stage: last,
                at: 3,
                seen: None,
            };
            let ahead = Ahead::spawn_observed(
                scope,
                &problem,
                &options,
                (&pool, &idle),
                at,
                &stop,
                stop_at,
            );
            // The take-over comes once the attempt has been stopped where chosen.
            while stop.load(Ordering::SeqCst) == 0 {
                std::thread::sleep(Duration::from_millis(1));
            }
            let resume = |from: Option<Solution>, o: &mut dyn Observer| {
                assert!(from.as_ref().is_some_and(|s| s.stages_completed == last));
                resumed.set(true);
                let options = SolveOptions {
                    resume: from,
                    ..options.clone()
                };
                attempt(&problem, &options, &pool, at, o, &none)
            };
            ahead.take_over(&problem, &mut told, &resume)
        });
        assert!(resumed.get(), "the attempt ended before the take-over");
        assert_eq!(taken.parameters(), alone.parameters());
        assert_eq!(taken.iou.to_bits(), alone.iou.to_bits());
        assert_eq!(taken.samples, alone.samples);
        assert_eq!(records, alone_records);
        // The observer was told every row of the records once, in order, with the
        // stages that drew them (the cut-short stage's rows once, from the resumed run).
        assert_eq!(told.0, records);
    }

    /// The rows an observer is told with the finished stages.
    #[derive(Default)]
    struct Told(Vec<SampleRecord>);

    impl Observer for Told {
        fn stage_finished(&mut self, _solution: &Solution, rows: &[SampleRecord]) {
            self.0.extend_from_slice(rows);
        }
    }
}
