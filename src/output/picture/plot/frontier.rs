//! The frontier of `bsa new --launcher` ([`FrontierData`]): P at the launcher against
//! IoU and against the height of the flights, and the launcher factor against IoU.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{draw_legend, e, font, render, Draw, DrawError, Figure, Pen, GRID, PALETTE};
use crate::output::picture::PictureError;

/// The designs `bsa new --launcher` tried, as points in named groups, and the kept one.
#[derive(Debug, Clone, PartialEq)]
pub struct FrontierData {
    pub title: String,
    pub groups: Vec<(String, Vec<FrontierPoint>)>,
    pub kept: Option<FrontierPoint>,
}

/// One design of a [`FrontierData`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontierPoint {
    pub iou: f64,
    /// P(IoU >= IoU - 0.05) at the launcher.
    pub p: f64,
    /// The highest flight (m).
    pub height: f64,
    /// The largest factor on the launcher's errors that keeps P at 90 %.
    pub factor: f64,
}

/// A panel of the frontier: x and y of a point, the axes' names, y's range and labels.
type FrontierPanel = (
    fn(&FrontierPoint) -> f64,
    fn(&FrontierPoint) -> f64,
    &'static str,
    &'static str,
);

impl FrontierData {
    /// The span of `f` over every point, padded by 5 %.
    fn span(&self, f: fn(&FrontierPoint) -> f64) -> std::ops::Range<f64> {
        let (lo, hi) = self
            .groups
            .iter()
            .flat_map(|(_, p)| p.iter().map(f))
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        if lo < hi {
            let pad = 0.05 * (hi - lo);
            (lo - pad)..(hi + pad)
        } else if lo.is_finite() {
            (lo - 0.5)..(lo + 0.5)
        } else {
            0.0..1.0
        }
    }
}

impl Draw for FrontierData {
    fn size(&self) -> (u32, u32) {
        (1400, 460)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE).map_err(e)?;
        let (top, body) = root.split_vertically(40);
        top.draw_text(&self.title, &font(19), (12, 10)).map_err(e)?;
        let (w, _) = self.size();
        let (panels, legend_area) = body.split_horizontally(w - 250);
        let p_label = "P(IoU >= IoU - 0.05) at the launcher";
        let factor_label = "launcher factor keeping P at 90 % (log10)";
        let specs: [FrontierPanel; 3] = [
            (|p| p.iou, |p| p.p, "IoU of the trial solve", p_label),
            (|p| p.height, |p| p.p, "highest flight (m)", p_label),
            (
                |p| p.iou,
                |p| p.factor.max(1e-3).log10(),
                "IoU of the trial solve",
                factor_label,
            ),
        ];
        for (k, (area, (x_of, y_of, x_label, y_label))) in
            panels.split_evenly((1, 3)).iter().zip(specs).enumerate()
        {
            let y_range = if k < 2 { -0.02..1.02 } else { self.span(y_of) };
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(44)
                .y_label_area_size(56)
                .build_cartesian_2d(self.span(x_of), y_range)
                .map_err(e)?;
            chart
                .configure_mesh()
                .light_line_style(WHITE)
                .bold_line_style(GRID)
                .x_desc(x_label)
                .y_desc(y_label)
                .x_labels(5)
                .label_style(font(12))
                .axis_desc_style(font(13))
                .draw()
                .map_err(e)?;
            for (g, (_, points)) in self.groups.iter().enumerate() {
                let color = PALETTE[g % PALETTE.len()];
                chart
                    .draw_series(
                        points
                            .iter()
                            .map(|p| Circle::new((x_of(p), y_of(p)), 5, color.filled())),
                    )
                    .map_err(e)?;
            }
            if let Some(p) = &self.kept {
                let ring = Circle::new((x_of(p), y_of(p)), 10, BLACK.stroke_width(2));
                chart.draw_series(std::iter::once(ring)).map_err(e)?;
            }
        }
        let mut legend: Vec<(Pen, String)> = self
            .groups
            .iter()
            .enumerate()
            .map(|(k, (name, _))| {
                let pen = Pen {
                    color: PALETTE[k % PALETTE.len()],
                    width: 8,
                    dashed: false,
                };
                (pen, name.clone())
            })
            .collect();
        if self.kept.is_some() {
            let pen = Pen {
                color: RGBColor(0, 0, 0),
                width: 2,
                dashed: false,
            };
            legend.push((pen, "kept (ringed)".to_string()));
        }
        draw_legend(&legend_area, 30, &legend)
    }
}

/// The frontier of `bsa new --launcher`: P at the launcher against IoU and against
/// the height of the flights, and the launcher factor against IoU.
pub fn frontier(data: &FrontierData) -> Result<Figure, PictureError> {
    render(data, "the frontier")
}
