//! The two plots of `bsa budget`, drawn from a [`BudgetReport`] with
//! [`crate::output::picture::plot`]: the histogram of the Monte Carlo IoUs
//! (`budget_hist.{png,svg}`) and, when the tolerance search ran, a grid of one panel per
//! launch error with IoU and success probability against the error's size
//! (`budget_tolerances.{png,svg}`). Nothing here touches the filesystem: the caller
//! saves the figures.

use super::{short, BudgetReport, CurvePoint};
use crate::output::picture::plot::{self, Figure, GridData, HistogramData, Panel};
use crate::output::picture::PictureError;

/// The histogram of the Monte Carlo IoUs, with the IoU threshold marked.
pub fn histogram(r: &BudgetReport) -> Result<Figure, PictureError> {
    let h = &r.histogram;
    plot::histogram(&HistogramData {
        title: format!(
            "{}: IoU at t over {} launches with errors",
            r.scene, r.monte_carlo.samples
        ),
        x_label: "IoU at t".to_string(),
        lo: h.lo,
        hi: h.hi,
        counts: h.counts.clone(),
        marker: Some((
            r.iou_threshold,
            format!(
                "threshold {} (P = {:.1} %)",
                short(r.iou_threshold),
                100.0 * r.monte_carlo.p_iou_at_least_threshold
            ),
        )),
    })
}

/// The tolerance curves in a grid, one panel per launch error, each with its largest
/// tolerance marked; `None` when the report has no tolerance search.
pub fn tolerances(r: &BudgetReport) -> Option<Result<Figure, PictureError>> {
    let search = r.search.as_ref()?;
    let threshold = short(r.iou_threshold);
    let panels = search
        .single
        .iter()
        .map(|p| {
            let pts =
                |f: &dyn Fn(&CurvePoint) -> f64| p.curve.iter().map(|c| (c.size, f(c))).collect();
            Panel {
                title: format!("{} error alone", p.parameter),
                x_label: format!("1 sigma ({})", p.unit),
                curves: vec![
                    ("mean IoU".to_string(), pts(&|c| c.mean)),
                    ("5th percentile IoU".to_string(), pts(&|c| c.p5)),
                    (
                        format!("P(IoU >= {threshold})"),
                        pts(&|c| c.p_iou_at_least_threshold),
                    ),
                ],
                marker: p.largest,
            }
        })
        .collect();
    Some(plot::tolerance_grid(&GridData {
        title: format!(
            "{}: IoU against the size of each launch error alone",
            r.scene
        ),
        panels,
        y_label: "IoU / probability".to_string(),
        marker_name: format!(
            "largest tolerance (P(IoU >= {threshold}) >= {:.0} %)",
            100.0 * super::PROBABILITY_TARGET
        ),
    }))
}
