//! Linear-axis plots for the error budget: a histogram and line plots with ticks, labels
//! and a legend.

use super::*;

// ---------------------------------------------------------------------------
// Linear-axis plots: histogram and line plot (error budget)
// ---------------------------------------------------------------------------

/// One curve of a [`line_plot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub color: Rgb<u8>,
    /// (x, y) points, drawn joined in the given order; non-finite points are skipped.
    pub points: Vec<(f64, f64)>,
}

/// Tick values of a linear axis from `lo` to `hi`: about `n` "nice" steps.
pub(super) fn linear_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return vec![lo];
    }
    let raw = span / n.max(1) as f64;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p);
    let first = (lo / step).ceil();
    let mut out = Vec::new();
    let mut k = first;
    while k * step <= hi + 1e-9 * span {
        out.push(k * step);
        k += 1.0;
    }
    out
}

pub(super) fn tick_label(v: f64, step: f64) -> String {
    let digits = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil().clamp(0.0, 6.0) as usize
    };
    format!("{v:.digits$}")
}

/// Linear axes in a `width` x `height` panel with a title and axis labels; returns the
/// picture and a mapping from data to pixels.
pub(super) struct LinearAxes {
    left: i32,
    top: i32,
    right: i32,
    bottom: i32,
    x: (f64, f64),
    y: (f64, f64),
}

impl LinearAxes {
    fn px(&self, x: f64) -> i32 {
        let f = (x - self.x.0) / (self.x.1 - self.x.0);
        self.left + (f * f64::from(self.right - self.left)).round() as i32
    }
    fn py(&self, y: f64) -> i32 {
        let f = (y - self.y.0) / (self.y.1 - self.y.0);
        self.bottom - (f * f64::from(self.bottom - self.top)).round() as i32
    }
}

pub(super) fn linear_frame(chart: &Chart, x: (f64, f64), y: (f64, f64)) -> (RgbImage, LinearAxes) {
    let Chart {
        title,
        x_label,
        y_label,
        width,
        height,
    } = *chart;
    let mut img = RgbImage::from_pixel(width, height, WHITE);
    let s = (width.min(height * 4 / 3) / 230).clamp(1, 4);
    let si = s as i32;
    let th = text_height(s) as i32;
    let cap = (CAP_H * s) as i32;
    let yt = linear_ticks(y.0, y.1, 5);
    let ystep = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
    let tick_w = yt
        .iter()
        .map(|v| text_width(&tick_label(*v, ystep), s))
        .max()
        .unwrap_or(0) as i32;
    let ax = LinearAxes {
        left: 4 * si + th + 6 * si + tick_w + 5 * si,
        top: 6 * si + text_height(s + 1) as i32 + 6 * si,
        right: width as i32 - 16 * si,
        bottom: height as i32 - (4 * si + th + 5 * si + th + 6 * si),
        x,
        y,
    };
    let tw = text_width(title, s + 1) as i32;
    draw_text(
        &mut img,
        (ax.left + ax.right - tw) / 2,
        6 * si,
        title,
        TEXT,
        s + 1,
    );
    if ax.right - ax.left < 10 || ax.bottom - ax.top < 10 {
        return (img, ax);
    }
    for v in &yt {
        let py = ax.py(*v);
        fill_rect(&mut img, ax.left, py, ax.right - ax.left, 1, GRID);
        fill_rect(&mut img, ax.left - 3 * si, py, 3 * si, 1, FRAME);
        let label = tick_label(*v, ystep);
        let w = text_width(&label, s) as i32;
        draw_text(
            &mut img,
            ax.left - 5 * si - w,
            py - cap / 2,
            &label,
            TEXT,
            s,
        );
    }
    let xt = linear_ticks(x.0, x.1, 5);
    let xstep = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
    for v in &xt {
        let px = ax.px(*v);
        fill_rect(&mut img, px, ax.top, 1, ax.bottom - ax.top, GRID);
        fill_rect(&mut img, px, ax.bottom, 1, 3 * si, FRAME);
        let label = tick_label(*v, xstep);
        let w = text_width(&label, s) as i32;
        draw_text(&mut img, px - w / 2, ax.bottom + 5 * si, &label, TEXT, s);
    }
    let xl_w = text_width(x_label, s) as i32;
    draw_text(
        &mut img,
        (ax.left + ax.right - xl_w) / 2,
        height as i32 - 4 * si - th,
        x_label,
        TEXT,
        s,
    );
    let yl_w = text_width(y_label, s) as i32;
    draw_text_up(
        &mut img,
        4 * si,
        (ax.top + ax.bottom + yl_w) / 2,
        y_label,
        TEXT,
        s,
    );
    (img, ax)
}

/// A chart's title, axis labels and size in pixels.
#[derive(Clone, Copy, Debug)]
pub struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub width: u32,
    pub height: u32,
}

/// Histogram of `counts` over equal bins from `lo` to `hi`, with an optional vertical
/// marker (e.g. the IoU threshold) in red.
pub fn histogram_plot(
    chart: &Chart,
    (lo, hi): (f64, f64),
    counts: &[usize],
    marker: Option<f64>,
) -> RgbImage {
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let (mut img, ax) = linear_frame(chart, (lo, hi), (0.0, top * 1.05));
    let n = counts.len().max(1);
    for (k, &c) in counts.iter().enumerate() {
        let x0 = ax.px(lo + (hi - lo) * k as f64 / n as f64);
        let x1 = ax.px(lo + (hi - lo) * (k + 1) as f64 / n as f64);
        let y = ax.py(c as f64);
        if c > 0 {
            fill_rect(
                &mut img,
                x0,
                y,
                (x1 - x0).max(1),
                ax.bottom - y + 1,
                TERM_COLORS[0],
            );
            rect_outline(
                &mut img,
                x0,
                y,
                (x1 - x0).max(1) + 1,
                ax.bottom - y + 1,
                WHITE,
            );
        }
    }
    if let Some(m) = marker.filter(|m| (lo..=hi).contains(m)) {
        let px = ax.px(m);
        line(&mut img, (px, ax.top), (px, ax.bottom), RED, 2);
    }
    rect_outline(
        &mut img,
        ax.left,
        ax.top,
        ax.right - ax.left + 1,
        ax.bottom - ax.top + 1,
        FRAME,
    );
    img
}

/// Line plot of `series` on linear axes (`x` range from the data, `y` range given),
/// with a legend in the lower left and an optional vertical marker in grey.
pub fn line_plot(chart: &Chart, series: &[Series], y: (f64, f64), marker: Option<f64>) -> RgbImage {
    let xs = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .filter(|x| x.is_finite());
    let (xmin, xmax) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let x = if xmin < xmax {
        (xmin, xmax)
    } else if xmin.is_finite() {
        (xmin, xmin + 1.0)
    } else {
        (0.0, 1.0)
    };
    let (mut img, ax) = linear_frame(chart, x, y);
    if let Some(m) = marker.filter(|m| m.is_finite() && *m >= x.0 && *m <= x.1) {
        let px = ax.px(m);
        line(&mut img, (px, ax.top), (px, ax.bottom), FRAME, 1);
    }
    for s in series {
        let mut prev: Option<(i32, i32)> = None;
        for &(px, py) in &s.points {
            if !(px.is_finite() && py.is_finite()) {
                prev = None;
                continue;
            }
            let p = (ax.px(px), ax.py(py.clamp(y.0, y.1)));
            line(&mut img, prev.unwrap_or(p), p, s.color, 2);
            fill_rect(&mut img, p.0 - 2, p.1 - 2, 5, 5, s.color);
            prev = Some(p);
        }
    }
    rect_outline(
        &mut img,
        ax.left,
        ax.top,
        ax.right - ax.left + 1,
        ax.bottom - ax.top + 1,
        FRAME,
    );
    // Legend in the lower-left corner.
    let sc = (chart.width.min(chart.height * 4 / 3) / 230).clamp(1, 4);
    let si = sc as i32;
    let th = text_height(sc) as i32;
    let line_h = th + 2 * si;
    let lw = 4 * si
        + 12 * si
        + 2 * si
        + series
            .iter()
            .map(|s| text_width(&s.name, sc))
            .max()
            .unwrap_or(0) as i32
        + 4 * si;
    let lh = 8 * si + series.len() as i32 * line_h - 2 * si;
    let (lx, ly) = (ax.left + 5 * si, ax.bottom - 5 * si - lh);
    if !series.is_empty() {
        fill_rect(&mut img, lx, ly, lw, lh, WHITE);
        rect_outline(&mut img, lx, ly, lw, lh, FRAME);
        for (k, s) in series.iter().enumerate() {
            let y0 = ly + 4 * si + k as i32 * line_h;
            fill_rect(
                &mut img,
                lx + 4 * si,
                y0 + th / 2 - si,
                12 * si,
                2 * si,
                s.color,
            );
            draw_text(&mut img, lx + 18 * si, y0, &s.name, TEXT, sc);
        }
    }
    img
}
