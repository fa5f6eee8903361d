//! Attempts that run ahead: while one attempt runs, the next runs beside it at the
//! lowest priority, on a pool of its own ([`Ahead::spawn`], `Pool::background`), its
//! progress queued by a [`Relay`]. If the solve wants that
//! attempt, [`Ahead::replay`] hands its progress to the observer as if it ran then;
//! if not, [`Ahead::cancel`] stops it.
//!
//! Why: an attempt's moves, CMA-ES updates and one-body refinements run on one thread,
//! so one attempt keeps two cores about 1.4 times busy. The attempt ahead takes the idle
//! time, so a solve of one attempt is not slowed and one of two takes less time. Each attempt's result is a function of its seed alone, so the solve's
//! result is the same, bit for bit, as when they run one after another.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::{Duration, Instant};

use super::search::{lower_priority, Pool};
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
    StageFinished(Box<Solution>),
}

/// The observer of an attempt that runs ahead: it queues what it is told.
struct Relay {
    events: Sender<Event>,
    shadow_sent: Option<Instant>,
}

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

    fn stage_finished(&mut self, solution: &Solution, _records: &[SampleRecord]) {
        self.send(Event::StageFinished(Box::new(solution.clone())));
    }
}

/// An attempt running ahead on its own thread.
pub(super) struct Ahead<'scope> {
    handle: ScopedJoinHandle<'scope, (Solution, Vec<SampleRecord>)>,
    events: Receiver<Event>,
    /// The attempt's own interrupt counter: the caller's interrupts once it is wanted,
    /// 2 (a stop) when it is cancelled.
    stop: &'scope AtomicUsize,
}

impl<'scope> Ahead<'scope> {
    /// Start attempt `a` (with `seed`, until `deadline`) on a thread of `scope`.
    pub(super) fn spawn<'env>(
        scope: &'scope Scope<'scope, 'env>,
        problem: &'scope Problem,
        options: &'scope SolveOptions,
        pool: &'scope Pool,
        (seed, a, deadline): (u64, usize, Option<Instant>),
        stop: &'scope AtomicUsize,
    ) -> Ahead<'scope> {
        let (tx, events) = mpsc::channel();
        let handle = scope.spawn(move || {
            lower_priority();
            let mut relay = Relay {
                events: tx,
                shadow_sent: None,
            };
            attempt(
                problem,
                options,
                pool,
                (seed, a, deadline),
                &mut relay,
                stop,
            )
        });
        Ahead {
            handle,
            events,
            stop,
        }
    }

    /// Stop the attempt (it is not wanted) and wait for its thread.
    pub(super) fn cancel(self) {
        self.stop.store(2, Ordering::SeqCst);
        drop(self.events);
        let _ = self.handle.join();
    }

    /// Hand the attempt's progress, queued and to come, to `observer` until it ends, the
    /// caller's `interrupts` passed on to it; returns its result.
    pub(super) fn replay(
        self,
        problem: &Problem,
        observer: &mut dyn Observer,
        interrupts: &AtomicUsize,
    ) -> (Solution, Vec<SampleRecord>) {
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
                Event::StageFinished(s) => observer.stage_finished(&s, &[]),
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
        match self.handle.join() {
            Ok(result) => result,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    }
}
