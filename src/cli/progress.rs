//! Progress for people: the observer of a solve (a bar per stage, a line per finished
//! stage, and the files it keeps up to date while the solve runs) and the bars of the
//! budget's long phases. Both draw nothing when `--quiet` is given.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::evaluate::canvas_margin;
use crate::optimize::solver::{IterationInfo, Observer};
use crate::output::files;
use crate::output::solution::{SampleRecord, Solution};
use crate::scene::{Scene, Stage};
use crate::shadow::mask::Mask;

/// A bar that draws nothing when `quiet`, so that callers update it the same way either
/// way.
fn bar(total: u64, template: &'static str, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new(total);
    if quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template(template)
            .expect("static template")
            // Rates read the same in every command: whole samples per second.
            .with_key(
                "rate",
                |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = write!(w, "{:.0} samples/s", state.per_sec());
                },
            )
            .progress_chars("=> "),
    );
    bar
}

/// A bar over `total` steps of plain work (not samples), e.g. the designs of `bsa new`.
pub(super) fn steps(total: u64, prefix: &str) -> ProgressBar {
    let b = bar(total, "{prefix} [{bar:30}] {pos}/{len} {elapsed}", false);
    b.set_prefix(prefix.to_string());
    b
}

/// The observer of `bsa solve`: draws a bar per stage, prints a line per finished stage,
/// refreshes `preview.png`, and after every stage appends its rows to `convergence.csv`
/// and rewrites `solution.json`, so that an interrupted solve can be resumed. The files
/// are written by a [`Writer`] thread, off the optimizer's path; [`SolveProgress::finish`]
/// waits for it and returns the first error.
pub(super) struct SolveProgress {
    writer: Writer,
    /// The stage names, for the convergence plot.
    pub(super) stage_names: Vec<String>,
    /// How many of this run's records were handed to the writer.
    encoded: usize,
    bar: Option<ProgressBar>,
    quiet: bool,
    last_preview: Instant,
    /// When the last stage of any attempt ended, as this observer was told.
    pub(super) last_stage_end: Option<Instant>,
    stages_total: usize,
    /// Iteration cap of one run of the current stage (a restart adds as many again).
    run_length: u64,
    /// The attempt running (0: the first), which later attempts' bars and lines name.
    attempt: usize,
}

impl SolveProgress {
    /// Starts `convergence.csv` in `out` with `prior` (the rows of the stages a resumed
    /// solve skips) and the writer thread.
    pub(super) fn new(
        out: PathBuf,
        scene: &Scene,
        prior: &[SampleRecord],
        quiet: bool,
    ) -> anyhow::Result<SolveProgress> {
        let csv = files::ConvergenceCsv::create(&out, prior)?;
        Ok(SolveProgress {
            writer: Writer::start(
                out,
                scene.target.clone(),
                canvas_margin(scene.target.width(), scene.target.height()),
                csv,
            ),
            stage_names: scene.stages.iter().map(|s| s.name.clone()).collect(),
            encoded: 0,
            run_length: 0,
            bar: None,
            quiet,
            // In the past, so that the first iteration already writes a preview.
            last_preview: Instant::now() - Duration::from_secs(1),
            last_stage_end: None,
            stages_total: scene.stages.len(),
            attempt: 0,
        })
    }

    /// Hands over the rows of `records` (every record of the run) not saved yet, waits
    /// until every file is written, and returns the first error while saving (with the
    /// time spent waiting).
    pub(super) fn finish(&mut self, records: &[SampleRecord]) -> anyhow::Result<Duration> {
        if self.encoded < records.len() {
            self.writer
                .send(Job::Rows(records[self.encoded..].to_vec()));
            self.encoded = records.len();
        }
        let start = Instant::now();
        self.writer.finish()?;
        Ok(start.elapsed())
    }

    /// "attempt N: " during a later attempt, nothing during the first.
    fn attempt_prefix(&self) -> String {
        match self.attempt {
            0 => String::new(),
            a => format!("attempt {}: ", a + 1),
        }
    }
}

impl Observer for SolveProgress {
    fn stage_started(&mut self, index: usize, stage: &Stage) {
        self.run_length = stage.max_iterations as u64;
        let bar = bar(
            stage.max_iterations as u64,
            "{prefix} [{bar:30}] {pos}/{len} it {msg}",
            self.quiet,
        );
        bar.set_prefix(format!(
            "{}stage {}/{} {}",
            self.attempt_prefix(),
            index + 1,
            self.stages_total,
            stage.name
        ));
        self.bar = Some(bar);
    }

    fn attempt_started(&mut self, attempt: usize, attempts: usize, kept: &Solution, seed: u64) {
        self.attempt = attempt;
        println!(
            "attempt {}/{attempts}: the picture kept ends at IoU {:.4}{}, under the last stage's restart IoU; the stages again from the start guess, seed {seed} (the solution saved stays the best)",
            attempt + 1,
            kept.iou,
            if kept.n_contacts > 0 { " with a contact" } else { "" },
        );
    }

    fn attempt_stage_finished(&mut self, s: &Solution, rows: &[SampleRecord]) {
        self.last_stage_end = Some(Instant::now());
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        if let Some(line) = stage_line(s) {
            println!("{}{line}", self.attempt_prefix());
        }
        // The attempt's rows are saved as its stages end (not all at the end of the
        // solve), though its solution is not.
        if !rows.is_empty() {
            self.writer.send(Job::Rows(rows.to_vec()));
            self.encoded += rows.len();
        }
    }

    fn restarted(&mut self, _index: usize, restart: usize, population: usize) {
        if let Some(bar) = &self.bar {
            // Each restart runs up to the stage's iteration cap again.
            bar.set_length(bar.length().unwrap_or(0) + self.run_length);
            let prefix = bar.prefix();
            let base = prefix
                .split(" (restart")
                .next()
                .unwrap_or(&prefix)
                .to_string();
            bar.set_prefix(format!(
                "{base} (restart {restart}, population {population})"
            ));
        }
    }

    fn iteration(&mut self, info: &IterationInfo) {
        if let Some(bar) = &self.bar {
            bar.set_position(info.iteration as u64);
            bar.set_message(format!(
                "| {:.0} samples/s | best {:.4e} | IoU {:.4}",
                info.samples_per_second, info.best_energy, info.best_iou
            ));
        }
        // The preview is refreshed at most four times a second, and only once the writer
        // has saved the last one: encoding a PNG every iteration would cost more than
        // the optimisation itself on small scenes.
        if self.last_preview.elapsed().as_secs_f64() >= 0.25 && !self.writer.preview_pending() {
            self.last_preview = Instant::now();
            self.writer.send(Job::Preview(info.best_shadow.clone()));
        }
    }

    fn stage_finished(&mut self, s: &Solution, rows: &[SampleRecord]) {
        self.last_stage_end = Some(Instant::now());
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        // Stage lines are results, like the summary that follows them: both go to stdout,
        // so that they arrive in order wherever stdout and stderr are sent (the bars
        // stay on stderr).
        if let Some(line) = stage_line(s) {
            println!("{line}");
        }
        self.writer.send(Job::Stage {
            rows: rows.to_vec(),
            solution: Box::new(s.clone()),
        });
        self.encoded += rows.len();
    }
}

/// The line of the last stage of `s`: its iterations, samples, restarts, energy, IoU,
/// time and why it stopped.
fn stage_line(s: &Solution) -> Option<String> {
    let r = s.stages.last()?;
    Some(format!(
        "stage {}/{} `{}`: {} iterations, {} samples{}, best energy {:.4e}, IoU {:.4}, {:.2} s ({})",
        s.stages_completed,
        s.stages_total,
        r.name,
        r.iterations,
        r.samples,
        match r.restarts {
            0 => String::new(),
            1 => ", 1 restart".to_string(),
            n => format!(", {n} restarts"),
        },
        r.best_energy,
        r.iou,
        r.wall_time_s,
        r.stop
    ))
}

/// What the writer thread saves.
enum Job {
    /// A finished stage: its rows, then the solution so far. The rows go first: a stage
    /// counts as completed (in `solution.json`) only once its rows are on disk, so that
    /// a resumed solve finds them.
    Stage {
        rows: Vec<SampleRecord>,
        solution: Box<Solution>,
    },
    /// Rows that no stage has saved.
    Rows(Vec<SampleRecord>),
    /// The overlay of the best shadow so far (`preview.png`).
    Preview(Mask),
}

/// A thread that writes a solve's files in the order they are sent, so that encoding
/// and syncing them never holds up the optimizer. After an error it writes nothing more
/// (a later checkpoint must not pass over a missing one) and keeps the first error.
struct Writer {
    jobs: Option<mpsc::Sender<Job>>,
    thread: Option<std::thread::JoinHandle<anyhow::Result<()>>>,
    preview_pending: Arc<AtomicBool>,
}

impl Writer {
    /// `margin`: the canvas's margin around the picture in the previews' masks.
    fn start(out: PathBuf, target: Mask, margin: usize, csv: files::ConvergenceCsv) -> Writer {
        let (jobs, queue) = mpsc::channel::<Job>();
        let preview_pending = Arc::new(AtomicBool::new(false));
        let pending = Arc::clone(&preview_pending);
        let thread = std::thread::spawn(move || {
            let mut first_error = None;
            for job in queue {
                let result = match (&first_error, job) {
                    (Some(_), Job::Preview(_)) => {
                        pending.store(false, Ordering::SeqCst);
                        continue;
                    }
                    (Some(_), _) => continue,
                    (None, Job::Stage { rows, solution }) => csv
                        .append(&rows)
                        .and_then(|_| files::write_solution(&out, &solution)),
                    (None, Job::Rows(rows)) => csv.append(&rows),
                    (None, Job::Preview(mask)) => {
                        let r = files::write_preview(&out, &target, &mask.cropped(margin));
                        pending.store(false, Ordering::SeqCst);
                        r
                    }
                };
                if let Err(e) = result {
                    first_error = Some(e);
                }
            }
            first_error.map_or(Ok(()), |e| Err(e.into()))
        });
        Writer {
            jobs: Some(jobs),
            thread: Some(thread),
            preview_pending,
        }
    }

    fn preview_pending(&self) -> bool {
        self.preview_pending.load(Ordering::SeqCst)
    }

    fn send(&self, job: Job) {
        if matches!(job, Job::Preview(_)) {
            self.preview_pending.store(true, Ordering::SeqCst);
        }
        if let Some(jobs) = &self.jobs {
            // The thread only stops once the sender is dropped, so sending cannot fail
            // before `finish`; a panic in it is reported by `finish`.
            let _ = jobs.send(job);
        }
    }

    /// Closes the queue and waits for the thread.
    fn finish(&mut self) -> anyhow::Result<()> {
        self.jobs = None;
        match self.thread.take().map(|t| t.join()) {
            Some(Ok(result)) => result,
            Some(Err(_)) => anyhow::bail!("the thread writing the solve's files panicked"),
            None => Ok(()),
        }
    }
}

/// Progress bars of the budget's long phases. The budget reports from its worker
/// threads, hence the mutex.
pub(super) struct BudgetProgress {
    bar: Mutex<Option<ProgressBar>>,
    quiet: bool,
}

impl BudgetProgress {
    pub(super) fn new(quiet: bool) -> BudgetProgress {
        BudgetProgress {
            bar: Mutex::new(None),
            quiet,
        }
    }
}

impl crate::budget::Progress for BudgetProgress {
    fn start(&self, phase: &str, total: u64) {
        let bar = bar(
            total,
            "{prefix} [{bar:30}] {pos}/{len} {rate} eta {eta}",
            self.quiet,
        );
        bar.set_prefix(phase.to_string());
        // A poisoned lock only means a worker panicked while drawing; the bar itself
        // is still usable.
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }
    fn advance(&self, n: u64) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}

/// What a solve of `problem` with `schedule` will cost, in one line: its time on the
/// machine's (or `threads`) threads, its samples and its memory (the scene as loaded,
/// read from the process, plus what the solve adds).
pub(super) fn cost_line(
    problem: &crate::evaluate::Problem,
    schedule: &crate::optimize::solver::Schedule,
    threads: Option<usize>,
) -> String {
    use crate::optimize::solver::cost;
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let c = cost::estimate(problem, schedule, threads);
    format!(
        "a solve takes about {} to {} on {threads} threads, {} samples at most, about {} of memory",
        cost::duration(c.seconds.0),
        cost::duration(c.seconds.1),
        c.samples,
        cost::bytes(resident_bytes() + c.bytes)
    )
}

/// The memory this process holds now (bytes; 0 where the system does not say).
fn resident_bytes() -> usize {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<usize>().ok())
        .map_or(0, |pages| pages * 4096)
}
