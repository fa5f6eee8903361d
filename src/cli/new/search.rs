//! `bsa new`'s design search as the CLI runs it: its scene files ([`DesignFiles`]), its
//! progress bars ([`Bars`]), the standard or the launcher's search ([`run`]) and the
//! launcher's frontier beside the scene ([`write_frontier`]).

use std::path::{Path, PathBuf};

use anyhow::Result;
use serde_json::Value;

use super::INTERRUPTS;
use crate::cli::progress;
use crate::compose::{tolerant, Scenes, Search, SearchError, Variant, Watch};
use crate::output::files;
use crate::scene::launcher::Tolerances;
use crate::scene::Scene;

/// The search's outcome: the design kept (or the first error, if any), the launcher's
/// frontier, and the standard search's trials line.
type Outcome = (
    Result<Variant, Option<SearchError>>,
    Option<tolerant::Frontier>,
    Option<String>,
);

/// Run the standard search, or with a launcher the launcher's.
pub(super) fn run(search: &Search, launcher: Option<Tolerances>) -> Outcome {
    match launcher {
        None => {
            let mut found = search.run(&Bars::default(), &INTERRUPTS);
            let trials = found.best.as_ref().map(|v| found.trials_line(v.setting));
            let kept = found.best.take().ok_or_else(|| found.first_error.take());
            (kept, None, trials)
        }
        Some(tol) => {
            let (frontier, kept) = tolerant::run(search, tol, &Bars::default(), &INTERRUPTS);
            (kept.map_err(Some), Some(frontier), None)
        }
    }
}

/// The design search's scene files, one per setting, beside the scene.
pub(super) struct DesignFiles<'a>(pub(super) &'a [PathBuf]);

impl Scenes for DesignFiles<'_> {
    fn load(&self, k: usize, json: &Value) -> Result<Scene, SearchError> {
        let text = serde_json::to_string_pretty(json).expect("a JSON value serialises");
        files::write_atomic(&self.0[k], text.as_bytes())
            .map_err(|e| SearchError::Scenes(Box::new(e)))?;
        crate::scene::load(&self.0[k]).map_err(|e| SearchError::Scenes(Box::new(e)))
    }
}

/// The search's phases as progress bars, one at a time.
#[derive(Default)]
struct Bars(std::sync::Mutex<Option<indicatif::ProgressBar>>);

impl Watch for Bars {
    fn begin(&self, total: u64, what: &str) {
        *self.0.lock().expect("no panic holds the bar") = Some(progress::steps(total, what));
    }
    fn step(&self) {
        if let Some(bar) = &*self.0.lock().expect("no panic holds the bar") {
            bar.inc(1);
        }
    }
    fn end(&self) {
        if let Some(bar) = self.0.lock().expect("no panic holds the bar").take() {
            bar.finish_and_clear();
        }
    }
}

/// The frontier of `bsa new --launcher` beside the scene in `dir`: `frontier.md`,
/// `frontier.csv` and its plot; and a line of what was kept against the standard design.
pub(super) fn write_frontier(dir: &Path, name: &str, f: &tolerant::Frontier) -> Result<()> {
    let md = format!("# The launcher's frontier\n\n{}", f.markdown());
    files::write_atomic(&dir.join("frontier.md"), md.as_bytes())?;
    files::write_csv(&dir.join("frontier.csv"), &f.points)?;
    let figure = crate::output::picture::plot::frontier(&tolerant::plot_data(name, f))?;
    files::save_figure(dir, "frontier", &figure)?;
    let standard = f.points.iter().filter(|p| !p.posed).max_by(|a, b| {
        (a.clear, a.iou)
            .partial_cmp(&(b.clear, b.iou))
            .expect("numbers")
    });
    if let (Some(k), Some(s)) = (f.chosen, standard) {
        let p = &f.points[k];
        println!(
            "{name}: for the launcher, kept the design at t = {} s{} under ceiling {}: IoU {:.4}, P(IoU >= IoU - 0.05) {:.0} % at the launcher, P at 90 % with its errors times {:.3}, flights up to {:.2} m (the standard design: IoU {:.4}, {:.0} %, times {:.3}, {:.2} m); every design tried: {}",
            p.t,
            if p.posed { ", launched in its pose" } else { "" },
            p.ceiling,
            p.iou,
            100.0 * p.p_launcher,
            p.launcher_scale,
            p.height,
            s.iou,
            100.0 * s.p_launcher,
            s.launcher_scale,
            s.height,
            dir.join("frontier.md").display()
        );
    }
    Ok(())
}
