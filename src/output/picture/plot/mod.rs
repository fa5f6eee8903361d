//! Plots drawn with `plotters`, each as a PNG image and an SVG document from the same
//! drawing code: the convergence plot (the paper's Figure 7), and the error budget's
//! IoU histogram and tolerance grid, and the frontier of `bsa new --launcher`
//! ([`frontier()`]).
//!
//! Every plot keeps its legend outside the data area, so that no curve hides behind it,
//! and gives each series its own colour (and the terms past the first five a dashed
//! line as well), so that no two series look alike.

use image::RgbImage;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{draw_err, ensure_font, PictureError, BLACK_TEXT};

mod frontier;
pub use frontier::{frontier, FrontierData, FrontierPoint};

/// A plot as both a PNG image and an SVG document.
#[derive(Debug, Clone)]
pub struct Figure {
    pub png: RgbImage,
    pub svg: String,
}

/// Something that draws itself on any plotters backend; [`render`] runs it twice,
/// once on a bitmap and once on an SVG string.
trait Draw {
    /// Size of the figure in pixels.
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError>;
}

fn render(plot: &impl Draw, what: &'static str) -> Result<Figure, PictureError> {
    ensure_font();
    let (w, h) = plot.size();
    let mut buf = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        plot.draw(&root).map_err(|x| draw_err(what, x.0))?;
        root.present().map_err(|x| draw_err(what, x))?;
    }
    let png = RgbImage::from_raw(w, h, buf).expect("buffer has the figure's size");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        plot.draw(&root).map_err(|x| draw_err(what, x.0))?;
        root.present().map_err(|x| draw_err(what, x))?;
    }
    Ok(Figure { png, svg })
}

/// Ten well-separated hues ("tab10"), one per energy term.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];
const GRID: RGBColor = RGBColor(225, 225, 225);
const STAGE_LINE: RGBColor = RGBColor(150, 150, 150);
/// Where a later attempt of a solve starts (`bsa solve --attempts`).
const ATTEMPT_LINE: RGBColor = RGBColor(40, 40, 40);

fn font(size: u32) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", size).into_font()).color(&BLACK_TEXT)
}

/// A plotters error in its debug form (plotters' errors are generic over the backend);
/// [`render`] names the figure.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct DrawError(String);

fn e<E: std::fmt::Debug>(e: E) -> DrawError {
    DrawError(format!("{e:?}"))
}

/// How one series is drawn: colour, width and whether dashed.
#[derive(Clone, Copy)]
struct Pen {
    color: RGBColor,
    width: u32,
    dashed: bool,
}

/// A chart with linear f64 axes, as every plot here draws on.
type Chart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

fn draw_line<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    points: Vec<(f64, f64)>,
    pen: Pen,
) -> Result<(), DrawError> {
    let style = pen.color.stroke_width(pen.width);
    if pen.dashed {
        chart
            .draw_series(DashedLineSeries::new(points, 7, 4, style))
            .map_err(e)?;
    } else {
        chart
            .draw_series(LineSeries::new(points, style))
            .map_err(e)?;
    }
    Ok(())
}

/// A legend drawn in its own area: one row per entry, a line sample then the name.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    top: i32,
    entries: &[(Pen, String)],
) -> Result<(), DrawError> {
    let text = font(14);
    for (i, (pen, name)) in entries.iter().enumerate() {
        let y = top + 22 * i as i32;
        let style = pen.color.stroke_width(pen.width.max(2));
        if pen.dashed {
            for x in [4, 17] {
                area.draw(&PathElement::new([(x, y + 8), (x + 9, y + 8)], style))
                    .map_err(e)?;
            }
        } else {
            area.draw(&PathElement::new([(4, y + 8), (30, y + 8)], style))
                .map_err(e)?;
        }
        area.draw_text(name, &text, (38, y)).map_err(e)?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Convergence
// ---------------------------------------------------------------------------

/// Energies recorded during optimisation, for [`convergence`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConvergenceData {
    /// The scene's name, in the title.
    pub scene: String,
    /// Stage names, indexed by [`ConvergenceRow::stage`]; the plot numbers stages from 1
    /// as the terminal does.
    pub stage_names: Vec<String>,
    /// Legend names, in the order of [`ConvergenceRow::terms`].
    pub term_names: Vec<String>,
    /// One row per evaluated sample, in evaluation order.
    pub rows: Vec<ConvergenceRow>,
}

/// One evaluated sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConvergenceRow {
    /// Index of the optimisation stage (from 0) the sample belongs to.
    pub stage: usize,
    /// Iteration (generation) within the stage; consecutive rows with the same value
    /// form one generation, whose best sample is joined into a line.
    pub iteration: usize,
    /// Weighted value of each energy term, same order as `term_names`.
    pub terms: Vec<f64>,
    /// Total energy of the sample.
    pub total: f64,
}

/// log10 of a value that can be drawn on a log axis; zero, negative and non-finite
/// values are "missing".
fn log_value(v: f64) -> Option<f64> {
    (v.is_finite() && v > 0.0)
        .then(|| v.log10())
        .filter(|l| l.is_finite())
}

/// The plot never spans more decades than this, so that one stray tiny value (1e-300)
/// does not squash everything else into a sliver.
const MAX_DECADES: i32 = 16;

/// Decade range [lo, hi] covering every drawable value.
pub(super) fn decade_range(data: &ConvergenceData) -> (i32, i32) {
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for row in &data.rows {
        for l in row
            .terms
            .iter()
            .chain(std::iter::once(&row.total))
            .filter_map(|&v| log_value(v))
        {
            min = min.min(l);
            max = max.max(l);
        }
    }
    if min > max {
        return (-1, 1);
    }
    let hi = max.ceil() as i32;
    let lo = (min.floor() as i32).max(hi - MAX_DECADES);
    if hi > lo {
        (lo, hi)
    } else {
        (lo, lo + 1)
    }
}

/// One generation's best sample and where it sits on the x axis.
pub(super) struct GenerationBest<'a> {
    pub(super) x: f64,
    pub(super) stage: usize,
    pub(super) row: &'a ConvergenceRow,
}

/// The best sample (lowest total; non-finite totals rank last) of each generation, at
/// the index of its generation's last sample.
pub(super) fn generation_bests(rows: &[ConvergenceRow]) -> Vec<GenerationBest<'_>> {
    let mut out: Vec<GenerationBest> = Vec::new();
    let rank = |r: &ConvergenceRow| {
        if r.total.is_finite() {
            r.total
        } else {
            f64::INFINITY
        }
    };
    for (i, r) in rows.iter().enumerate() {
        match out.last_mut() {
            Some(g) if g.stage == r.stage && g.row.iteration == r.iteration => {
                g.x = i as f64;
                if rank(r) < rank(g.row) {
                    g.row = r;
                }
            }
            _ => out.push(GenerationBest {
                x: i as f64,
                stage: r.stage,
                row: r,
            }),
        }
    }
    out
}

/// Runs of drawable points of one series, split at stage boundaries and at missing
/// values, so that no line joins two stages (whose weights differ).
pub(super) fn runs(
    bests: &[GenerationBest],
    value: impl Fn(&ConvergenceRow) -> f64,
) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut prev_stage = None;
    for g in bests {
        let l = log_value(value(g.row));
        if prev_stage != Some(g.stage) || l.is_none() {
            out.push(Vec::new());
        }
        prev_stage = Some(g.stage);
        if let Some(l) = l {
            out.last_mut().expect("a run was pushed").push((g.x, l));
        }
    }
    out.retain(|r| !r.is_empty());
    out
}

/// Width of the legend column right of the convergence plot's data.
const LEGEND_WIDTH: u32 = 270;

struct ConvergencePlot<'a> {
    data: &'a ConvergenceData,
}

/// How term `t` is drawn: its own colour; the terms past the first five dashed too.
fn term_pen(t: usize) -> Pen {
    Pen {
        color: PALETTE[t % PALETTE.len()],
        width: 2,
        dashed: t >= 5,
    }
}

const TOTAL_PEN: Pen = Pen {
    color: RGBColor(0, 0, 0),
    width: 5,
    dashed: false,
};
const BEST_PEN: Pen = Pen {
    color: RGBColor(0, 0, 0),
    width: 1,
    dashed: true,
};

/// The convergence plot's axes: decades `lo..hi` of the log energy axis and `n` samples
/// along x (at least 2, so that the range is not empty).
#[derive(Clone, Copy)]
struct Axes {
    lo: i32,
    hi: i32,
    n: f64,
}

impl Draw for ConvergencePlot<'_> {
    fn size(&self) -> (u32, u32) {
        (1200, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        let data = self.data;
        root.fill(&WHITE).map_err(e)?;
        let (w, _) = self.size();
        let (plot_area, legend_area) = root.split_horizontally(w - LEGEND_WIDTH);
        let (lo, hi) = decade_range(data);
        let n = data.rows.len().max(2) as f64;
        let axes = Axes { lo, hi, n };
        let mut chart = self.chart(&plot_area, axes)?;
        self.draw_stages(&mut chart, &plot_area, axes)?;
        let legend = self.draw_energies(&mut chart)?;
        legend_area
            .draw_text("terms (weighted)", &font(15), (4, 40))
            .map_err(e)?;
        draw_legend(&legend_area, 66, &legend)
    }
}

impl ConvergencePlot<'_> {
    /// The chart on `plot_area` with its caption, grid and labelled axes drawn.
    fn chart<'a, DB: DrawingBackend>(
        &self,
        plot_area: &'a DrawingArea<DB, Shift>,
        axes: Axes,
    ) -> Result<Chart<'a, DB>, DrawError> {
        let Axes { lo, hi, n } = axes;
        let mut chart = ChartBuilder::on(plot_area)
            .caption(
                format!(
                    "{}: weighted energy per generation, by stage",
                    self.data.scene
                ),
                font(20),
            )
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..n - 1.0, f64::from(lo)..f64::from(hi))
            .map_err(e)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .bold_line_style(GRID)
            .y_labels((hi - lo + 1) as usize)
            .y_label_formatter(&|v| format!("1e{}", v.round() as i64))
            .x_label_formatter(&|v| format!("{}", v.round() as i64))
            .x_desc("sample (all stages in order)")
            .y_desc("weighted energy (log scale)")
            .label_style(font(13))
            .axis_desc_style(font(15))
            .draw()
            .map_err(e)?;
        Ok(chart)
    }

    /// Stage boundaries: a grey line where each stage after the first starts, and
    /// every stage's number and name at the top of its span.
    fn draw_stages<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        plot_area: &DrawingArea<DB, Shift>,
        axes: Axes,
    ) -> Result<(), DrawError> {
        let data = self.data;
        let Axes { lo, hi, n } = axes;
        let pixel_width = f64::from(chart.plotting_area().dim_in_pixel().0);
        let mut starts: Vec<(usize, usize)> = Vec::new();
        for (i, r) in data.rows.iter().enumerate() {
            if starts.last().is_none_or(|&(s, _)| s != r.stage) {
                starts.push((r.stage, i));
            }
        }
        // A solve of several attempts runs the stages again from the first: a stage
        // number lower than the one before starts an attempt, drawn dark and named.
        let mut attempt = 1;
        for (k, &(stage, i)) in starts.iter().enumerate() {
            let x = i as f64;
            let again = k > 0 && stage < starts[k - 1].0;
            if k > 0 {
                let (colour, width) = if again {
                    (ATTEMPT_LINE, 3)
                } else {
                    (STAGE_LINE, 1)
                };
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        [(x, f64::from(lo)), (x, f64::from(hi))],
                        colour.stroke_width(width),
                    )))
                    .map_err(e)?;
            }
            if again {
                attempt += 1;
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("attempt {attempt}"),
                        (x + n * 0.004, f64::from(lo) + 0.05 * f64::from(hi - lo)),
                        font(15),
                    )))
                    .map_err(e)?;
            }
            // Each stage is labelled with the longest label that fits in its span: its
            // number and name, its number alone, or nothing (THE THINKER has 33 stages).
            let end = starts.get(k + 1).map_or(data.rows.len(), |&(_, j)| j);
            let span_px = pixel_width * (end - i) as f64 / n;
            let full = match data.stage_names.get(stage) {
                Some(name) => format!("stage {}: {name}", stage + 1),
                None => format!("stage {}", stage + 1),
            };
            let short = format!("{}", stage + 1);
            let label = [full, short].into_iter().find(|l| {
                plot_area
                    .estimate_text_size(l, &font(13))
                    .is_ok_and(|(w, _)| f64::from(w) + 8.0 <= span_px)
            });
            if let Some(label) = label {
                chart
                    .draw_series(std::iter::once(Text::new(
                        label,
                        (x + n * 0.004, f64::from(hi) - 0.05 * f64::from(hi - lo)),
                        font(13),
                    )))
                    .map_err(e)?;
            }
        }
        Ok(())
    }

    /// The energy lines: the total and every non-zero term of each generation's best
    /// sample, then the best total so far; returns their legend entries in that order.
    fn draw_energies<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
    ) -> Result<Vec<(Pen, String)>, DrawError> {
        let data = self.data;
        let bests = generation_bests(&data.rows);
        // The total first and wide, so that a term equal to it (XOR late in a solve)
        // stays visible as a coloured line inside the black one.
        for run in runs(&bests, |r| r.total) {
            draw_line(chart, run, TOTAL_PEN)?;
        }
        let n_terms = data.rows.iter().map(|r| r.terms.len()).max().unwrap_or(0);
        let mut legend = Vec::new();
        for t in 0..n_terms {
            let pen = term_pen(t);
            let series = runs(&bests, |r| r.terms.get(t).copied().unwrap_or(0.0));
            if series.is_empty() {
                continue; // zero throughout: only noise in the legend
            }
            for run in series {
                draw_line(chart, run, pen)?;
            }
            let name = data
                .term_names
                .get(t)
                .cloned()
                .unwrap_or_else(|| format!("term {t}"));
            legend.push((pen, name));
        }
        legend.push((TOTAL_PEN, "total (best of generation)".to_string()));
        for run in best_so_far_runs(&data.rows)
            .into_iter()
            .filter(|r| r.len() > 1)
        {
            draw_line(chart, run, BEST_PEN)?;
        }
        legend.push((BEST_PEN, "best total so far".to_string()));
        Ok(legend)
    }
}

/// Best so far within each stage: the running minimum of every sample's total, one run
/// of (sample, log10) points per stage.
fn best_so_far_runs(rows: &[ConvergenceRow]) -> Vec<Vec<(f64, f64)>> {
    let mut best_runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut best = f64::INFINITY;
    let mut prev_stage = None;
    for (i, r) in rows.iter().enumerate() {
        if prev_stage != Some(r.stage) {
            best = f64::INFINITY;
            best_runs.push(Vec::new());
        }
        prev_stage = Some(r.stage);
        if r.total.is_finite() && r.total < best {
            best = r.total;
        }
        if let (Some(l), Some(run)) = (log_value(best), best_runs.last_mut()) {
            run.push((i as f64, l));
        }
    }
    best_runs
}

/// The convergence plot: every weighted term and the total of each generation's best
/// sample on a log axis against the sample index, stage boundaries marked, the best
/// total so far dashed; legend to the right of the data.
pub fn convergence(data: &ConvergenceData) -> Result<Figure, PictureError> {
    render(&ConvergencePlot { data }, "the convergence plot")
}

// ---------------------------------------------------------------------------
// Error budget
// ---------------------------------------------------------------------------

/// A histogram of values in `[lo, hi]` with equal bins and an optional marked value.
#[derive(Debug, Clone, PartialEq)]
pub struct HistogramData {
    pub title: String,
    pub x_label: String,
    pub lo: f64,
    pub hi: f64,
    pub counts: Vec<usize>,
    /// A value marked by a red vertical line, with its legend name.
    pub marker: Option<(f64, String)>,
}

impl Draw for HistogramData {
    fn size(&self) -> (u32, u32) {
        (900, 480)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE).map_err(e)?;
        let (w, _) = self.size();
        let (plot_area, legend_area) = root.split_horizontally(w - 230);
        let top = self.counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.08;
        let (lo, hi) = if self.hi > self.lo {
            (self.lo, self.hi)
        } else {
            (self.lo, self.lo + 1.0)
        };
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(&self.title, font(19))
            .margin(12)
            .x_label_area_size(46)
            .y_label_area_size(66)
            .build_cartesian_2d(lo..hi, 0.0..top)
            .map_err(e)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .bold_line_style(GRID)
            .x_desc(&self.x_label)
            .y_desc("samples")
            .y_label_formatter(&|v| format!("{}", v.round() as i64))
            .label_style(font(13))
            .axis_desc_style(font(15))
            .draw()
            .map_err(e)?;
        let bins = self.counts.len().max(1) as f64;
        let width = (hi - lo) / bins;
        let bar = PALETTE[0];
        chart
            .draw_series(self.counts.iter().enumerate().map(|(i, &c)| {
                let x0 = lo + i as f64 * width;
                Rectangle::new([(x0, 0.0), (x0 + width, c as f64)], bar.filled())
            }))
            .map_err(e)?;
        let mut legend = vec![(
            Pen {
                color: bar,
                width: 8,
                dashed: false,
            },
            "samples per bin".to_string(),
        )];
        if let Some((m, name)) = &self.marker {
            let pen = Pen {
                color: PALETTE[3],
                width: 2,
                dashed: false,
            };
            draw_line(&mut chart, vec![(*m, 0.0), (*m, top)], pen)?;
            legend.push((pen, name.clone()));
        }
        draw_legend(&legend_area, 60, &legend)
    }
}

/// A histogram plot (the error budget's IoUs).
pub fn histogram(data: &HistogramData) -> Result<Figure, PictureError> {
    render(data, "the histogram")
}

/// One panel of a [`tolerance_grid`]: curves against one error's size.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    /// (name, points) per curve; every panel has the same curves in the same order.
    pub curves: Vec<(String, Vec<(f64, f64)>)>,
    /// The x marked by a vertical line (the largest tolerance).
    pub marker: f64,
}

/// Panels sharing one legend, for [`tolerance_grid`].
#[derive(Debug, Clone, PartialEq)]
pub struct GridData {
    pub title: String,
    pub panels: Vec<Panel>,
    pub y_label: String,
    /// The legend name of each panel's marker line.
    pub marker_name: String,
}

const GRID_COLUMNS: usize = 3;
const PANEL: (u32, u32) = (440, 320);
const GRID_HEADER: u32 = 110;

impl Draw for GridData {
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(GRID_COLUMNS).max(1) as u32;
        let cols = self.panels.len().clamp(1, GRID_COLUMNS) as u32;
        (cols * PANEL.0, GRID_HEADER + rows * PANEL.1)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE).map_err(e)?;
        let (header, body) = root.split_vertically(GRID_HEADER);
        header
            .draw_text(&self.title, &font(19), (12, 8))
            .map_err(e)?;
        let pens: Vec<Pen> = (0..3)
            .map(|i| Pen {
                color: [PALETTE[0], PALETTE[2], PALETTE[3]][i],
                width: 2,
                dashed: i == 1,
            })
            .chain(std::iter::repeat(Pen {
                color: PALETTE[7],
                width: 2,
                dashed: false,
            }))
            .take(self.panels.first().map_or(0, |p| p.curves.len()))
            .collect();
        let marker_pen = Pen {
            color: RGBColor(0, 0, 0),
            width: 1,
            dashed: true,
        };
        let mut legend: Vec<(Pen, String)> = self
            .panels
            .first()
            .map(|p| {
                p.curves
                    .iter()
                    .zip(&pens)
                    .map(|((name, _), pen)| (*pen, name.clone()))
                    .collect()
            })
            .unwrap_or_default();
        legend.push((marker_pen, self.marker_name.clone()));
        // The legend in two columns under the title, outside every panel.
        let half = legend.len().div_ceil(2);
        draw_legend(&header.margin(0, 0, 12, 0), 40, &legend[..half])?;
        let (w, _) = self.size();
        draw_legend(&header.split_horizontally(w / 2).1, 40, &legend[half..])?;

        let rows = self.panels.len().div_ceil(GRID_COLUMNS).max(1);
        let cols = self.panels.len().clamp(1, GRID_COLUMNS);
        for (panel, area) in self.panels.iter().zip(body.split_evenly((rows, cols))) {
            let x_max = panel
                .curves
                .iter()
                .flat_map(|(_, p)| p.iter().map(|q| q.0))
                .chain(std::iter::once(panel.marker))
                .filter(|x| x.is_finite())
                .fold(0.0f64, f64::max);
            let x_max = if x_max > 0.0 { x_max * 1.02 } else { 1.0 };
            let mut chart = ChartBuilder::on(&area)
                .caption(&panel.title, font(16))
                .margin(10)
                .x_label_area_size(44)
                .y_label_area_size(52)
                .build_cartesian_2d(0.0..x_max, 0.0..1.0)
                .map_err(e)?;
            chart
                .configure_mesh()
                .light_line_style(WHITE)
                .bold_line_style(GRID)
                .x_labels(5)
                .y_labels(6)
                .x_desc(&panel.x_label)
                .y_desc(&self.y_label)
                .label_style(font(12))
                .axis_desc_style(font(13))
                .draw()
                .map_err(e)?;
            for ((_, points), pen) in panel.curves.iter().zip(&pens) {
                let pts: Vec<(f64, f64)> = points
                    .iter()
                    .copied()
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .collect();
                draw_line(&mut chart, pts, *pen)?;
            }
            if panel.marker.is_finite() {
                draw_line(
                    &mut chart,
                    vec![(panel.marker, 0.0), (panel.marker, 1.0)],
                    marker_pen,
                )?;
            }
        }
        Ok(())
    }
}

/// Panels in a grid of up to three columns under one title and one legend (the error
/// budget's tolerance curves).
pub fn tolerance_grid(data: &GridData) -> Result<Figure, PictureError> {
    render(data, "the tolerance grid")
}
