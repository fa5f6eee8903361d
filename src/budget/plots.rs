//! The two plots of `bsa budget`, drawn from a [`BudgetReport`] with
//! [`crate::output::picture`]: the histogram of the Monte Carlo IoUs
//! (`budget_hist.png`) and, when the tolerance search ran, one panel per launch error
//! with IoU and success probability against the error's size (`budget_tolerances.png`).
//! Nothing here touches the filesystem: the caller saves the images.

use image::{Rgb, RgbImage};

use super::{BudgetReport, CurvePoint, SingleTolerance};
use crate::output::picture::{self, Chart, Series};

/// Size of the histogram, in pixels.
const HISTOGRAM_SIZE: (u32, u32) = (640, 400);
/// Size of each panel of the tolerance plot, in pixels.
const PANEL_SIZE: (u32, u32) = (380, 300);
/// Colour of the 5th-percentile curve: a green that stays apart from the blue mean and
/// the red probability.
const GREEN: Rgb<u8> = Rgb([44, 160, 44]);

/// The histogram of the Monte Carlo IoUs, with the IoU threshold marked in red.
pub fn histogram(r: &BudgetReport) -> RgbImage {
    let h = &r.histogram;
    let title = format!("{}: IoU at t, {} samples", r.scene, r.monte_carlo.samples);
    let x_label = format!(
        "IoU (red: {}; P(IoU >= {}) = {:.1} %)",
        r.iou_threshold,
        r.iou_threshold,
        100.0 * r.monte_carlo.p_iou_at_least_threshold
    );
    let chart = Chart {
        title: &title,
        x_label: &x_label,
        y_label: "samples",
        width: HISTOGRAM_SIZE.0,
        height: HISTOGRAM_SIZE.1,
    };
    picture::histogram_plot(&chart, (h.lo, h.hi), &h.counts, Some(r.iou_threshold))
}

/// The tolerance curves side by side, one panel per launch error, each with its
/// largest tolerance marked; `None` when the report has no tolerance search.
pub fn tolerances(r: &BudgetReport) -> Option<RgbImage> {
    let search = r.search.as_ref()?;
    let panels: Vec<RgbImage> = search
        .single
        .iter()
        .map(|p| tolerance_panel(p, r.iou_threshold))
        .collect();
    let refs: Vec<&RgbImage> = panels.iter().collect();
    Some(picture::side_by_side(&refs, 0))
}

/// Mean IoU, 5th-percentile IoU and `P(IoU >= threshold)` against the size of one error
/// alone.
fn tolerance_panel(p: &SingleTolerance, threshold: f64) -> RgbImage {
    let pts = |f: &dyn Fn(&CurvePoint) -> f64| p.curve.iter().map(|c| (c.size, f(c))).collect();
    let title = format!("{} error alone", p.parameter);
    let x_label = format!("1 sigma ({})", p.unit);
    let chart = Chart {
        title: &title,
        x_label: &x_label,
        y_label: "IoU / probability",
        width: PANEL_SIZE.0,
        height: PANEL_SIZE.1,
    };
    picture::line_plot(
        &chart,
        &[
            Series {
                name: "mean IoU".into(),
                color: picture::BLUE,
                points: pts(&|c| c.mean),
            },
            Series {
                name: "5th pct IoU".into(),
                color: GREEN,
                points: pts(&|c| c.p5),
            },
            Series {
                name: format!("P(IoU>={threshold})"),
                color: picture::RED,
                points: pts(&|c| c.p_iou_at_least_threshold),
            },
        ],
        (0.0, 1.0),
        Some(p.largest),
    )
}
