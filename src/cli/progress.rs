//! Progress for people: the observer of a solve (a bar per stage, a line per finished
//! stage, and the files it keeps up to date while the solve runs) and the bars of the
//! budget's long phases. Both draw nothing when `--quiet` is given.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::optimize::solver::{IterationInfo, Observer};
use crate::output::files;
use crate::output::solution::{SampleRecord, Solution};
use crate::scene::{Scene, Stage};

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
            .progress_chars("=> "),
    );
    bar
}

/// The observer of `bsa solve`: draws a bar per stage, prints a line per finished stage,
/// refreshes `preview.png` and rewrites `solution.json` and `convergence.csv` after every
/// stage, so that an interrupted solve can be resumed. Errors while writing are kept in
/// [`SolveProgress::error`] because the solver's callbacks cannot fail.
pub(super) struct SolveProgress {
    out: PathBuf,
    target: crate::shadow::mask::Mask,
    /// The stage names, for the convergence table.
    pub(super) stage_names: Vec<String>,
    /// `convergence.csv` so far (a resumed solve's skipped stages included).
    pub(super) csv: files::ConvergenceCsv,
    /// How many of this run's records `csv` holds.
    pub(super) encoded: usize,
    bar: Option<ProgressBar>,
    quiet: bool,
    last_preview: Instant,
    stages_total: usize,
    /// The first error while saving progress.
    pub(super) error: Option<anyhow::Error>,
}

impl SolveProgress {
    pub(super) fn new(
        out: PathBuf,
        scene: &Scene,
        prior: &[SampleRecord],
        quiet: bool,
    ) -> anyhow::Result<SolveProgress> {
        let mut csv = files::ConvergenceCsv::new(&out);
        csv.extend(prior)?;
        Ok(SolveProgress {
            out,
            target: scene.target.clone(),
            stage_names: scene.stages.iter().map(|s| s.name.clone()).collect(),
            csv,
            encoded: 0,
            bar: None,
            quiet,
            // In the past, so that the first iteration already writes a preview.
            last_preview: Instant::now() - Duration::from_secs(1),
            stages_total: scene.stages.len(),
            error: None,
        })
    }
}

impl Observer for SolveProgress {
    fn stage_started(&mut self, index: usize, stage: &Stage) {
        let bar = bar(
            stage.max_iterations as u64,
            "{prefix} [{bar:30}] {pos}/{len} it {msg}",
            self.quiet,
        );
        bar.set_prefix(format!(
            "stage {}/{} {}",
            index + 1,
            self.stages_total,
            stage.name
        ));
        self.bar = Some(bar);
    }

    fn iteration(&mut self, info: &IterationInfo) {
        if let Some(bar) = &self.bar {
            bar.set_position(info.iteration as u64);
            bar.set_message(format!(
                "| {:.0} samples/s | best {:.4e} | IoU {:.4}",
                info.samples_per_second, info.best_energy, info.best_iou
            ));
        }
        // The preview is refreshed at most ten times a second: encoding a PNG every
        // iteration would cost more than the optimisation itself on small scenes.
        if self.last_preview.elapsed().as_secs_f64() >= 0.1 {
            self.last_preview = Instant::now();
            if let Err(e) = files::write_preview(&self.out, &self.target, info.best_shadow) {
                self.error.get_or_insert(e.into());
            }
        }
    }

    fn stage_finished(&mut self, s: &Solution, records: &[SampleRecord]) {
        // `records` is every record of this run so far: only the new ones are encoded.
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        if let Some(r) = s.stages.last() {
            eprintln!(
                "stage {}/{} `{}`: {} iterations, {} samples, best energy {:.4e}, IoU {:.4}, {:.2} s ({})",
                s.stages_completed, s.stages_total, r.name, r.iterations, r.samples, r.best_energy, r.iou, r.wall_time_s, r.stop
            );
        }
        let res = files::write_solution(&self.out, s)
            .and_then(|_| self.csv.extend(&records[self.encoded..]))
            .and_then(|_| self.csv.write());
        self.encoded = records.len();
        if let Err(e) = res {
            self.error.get_or_insert(e.into());
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
            "{prefix} [{bar:30}] {pos}/{len} {per_sec} eta {eta}",
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
