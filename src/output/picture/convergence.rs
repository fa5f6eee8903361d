//! The convergence plot: one log-scale panel per stage, every weighted term and the
//! total against the sample index, as the paper's Figure 7.

use super::*;

// ---------------------------------------------------------------------------
// Convergence plot
// ---------------------------------------------------------------------------

/// Energies recorded during optimisation, for [`convergence_plot`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConvergenceData {
    /// Panel titles, indexed by [`ConvergenceRow::stage`]; missing names are
    /// shown as "stage N".
    pub stage_names: Vec<String>,
    /// Legend names, in the order of [`ConvergenceRow::terms`]; missing names are
    /// shown as "term N".
    pub term_names: Vec<String>,
    /// One row per evaluated sample, in evaluation order.
    pub rows: Vec<ConvergenceRow>,
}

/// One evaluated sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConvergenceRow {
    /// Index of the optimisation stage (panel) the sample belongs to.
    pub stage: usize,
    /// Iteration (generation) within the stage; consecutive rows with the same
    /// value form one generation, whose best sample is joined into a line.
    pub iteration: usize,
    /// Weighted value of each energy term, same order as `term_names`.
    pub terms: Vec<f64>,
    /// Total energy of the sample.
    pub total: f64,
}

/// Colours for the energy terms, in order (then repeated). Red is kept for the
/// total; the rest are the well-separated "tab10" hues without its red.
pub(super) const TERM_COLORS: [Rgb<u8>; 8] = [
    Rgb([31, 119, 180]),  // blue
    Rgb([255, 127, 14]),  // orange
    Rgb([44, 160, 44]),   // green
    Rgb([148, 103, 189]), // purple
    Rgb([23, 190, 207]),  // cyan
    Rgb([140, 86, 75]),   // brown
    Rgb([188, 189, 34]),  // olive
    Rgb([127, 127, 127]), // grey
];
pub(super) const TEXT: Rgb<u8> = Rgb([40, 40, 40]);
pub(super) const GRID: Rgb<u8> = Rgb([226, 226, 226]);
pub(super) const FRAME: Rgb<u8> = Rgb([110, 110, 110]);
/// Opacity of the per-sample dots: faint enough that thousands of them form a
/// density cloud behind the per-generation lines instead of a solid smear.
pub(super) const DOT_ALPHA: f64 = 0.3;
/// The plot never spans more decades than this, so that one stray tiny value
/// (1e-300) does not squash everything else into a sliver.
pub(super) const MAX_DECADES: i32 = 16;

pub(super) fn term_color(term: usize) -> Rgb<u8> {
    TERM_COLORS[term % TERM_COLORS.len()]
}

/// log10 of a value that can be drawn on a log axis; zero, negative and
/// non-finite values are "missing".
pub(super) fn log_value(v: f64) -> Option<f64> {
    (v.is_finite() && v > 0.0)
        .then(|| v.log10())
        .filter(|l| l.is_finite())
}

/// Decade range [lo, hi] (powers of ten) covering every drawable value in the
/// data, shared by all panels so that stages can be compared by eye.
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
        return (-1, 1); // nothing drawable: any axis will do
    }
    let hi = max.ceil() as i32;
    let lo = (min.floor() as i32).max(hi - MAX_DECADES);
    if hi > lo {
        (lo, hi)
    } else {
        (lo, lo + 1)
    }
}

/// Terms worth a legend entry in a stage: those with at least one drawable
/// value (a term that is zero throughout would only be noise in the legend).
pub(super) fn legend_terms(rows: &[&ConvergenceRow], n_terms: usize) -> Vec<usize> {
    (0..n_terms)
        .filter(|&t| {
            rows.iter()
                .any(|r| r.terms.get(t).and_then(|&v| log_value(v)).is_some())
        })
        .collect()
}

/// Smallest "nice" step (1, 2 or 5 times a power of ten) that is at least `min`.
pub(super) fn nice_step(min: f64) -> usize {
    let mut base = 1usize;
    loop {
        for m in [1, 2, 5] {
            if (base * m) as f64 >= min {
                return base * m;
            }
        }
        base *= 10;
    }
}

/// Convergence plot in the style of the paper's Figure 7: one panel per stage,
/// side by side (so the picture is `stages * panel_width` by `panel_height`).
///
/// In each panel the x axis is the sample index within the stage and the y axis
/// is log10 energy with a gridline per decade. Every sample is a faint dot (so
/// the spread of a generation is visible) and the best sample of each
/// generation is joined by a solid line (one vertex per pixel column: the
/// median of the generation bests there): total in red, each term in its own
/// colour. Values that are zero, negative or non-finite are not drawn; terms
/// that are zero throughout a stage are left out of its legend.
pub fn convergence_plot(data: &ConvergenceData, panel_width: u32, panel_height: u32) -> RgbImage {
    let n_panels = data
        .rows
        .iter()
        .map(|r| r.stage + 1)
        .max()
        .unwrap_or(0)
        .max(data.stage_names.len())
        .max(1);
    let n_terms = data
        .rows
        .iter()
        .map(|r| r.terms.len())
        .max()
        .unwrap_or(0)
        .max(data.term_names.len());
    let term_names: Vec<String> = (0..n_terms)
        .map(|t| {
            data.term_names
                .get(t)
                .cloned()
                .unwrap_or_else(|| format!("term {t}"))
        })
        .collect();
    let range = decade_range(data);
    let panels: Vec<RgbImage> = (0..n_panels)
        .map(|stage| {
            let rows: Vec<&ConvergenceRow> =
                data.rows.iter().filter(|r| r.stage == stage).collect();
            let title = data
                .stage_names
                .get(stage)
                .cloned()
                .unwrap_or_else(|| format!("stage {stage}"));
            draw_panel(panel_width, panel_height, &title, &term_names, &rows, range)
        })
        .collect();
    let refs: Vec<&RgbImage> = panels.iter().collect();
    side_by_side(&refs, 0)
}

/// Where data goes inside a panel, and how values map to pixels.
pub(super) struct Axes {
    left: i32,
    top: i32,
    right: i32,
    bottom: i32,
    n_samples: usize,
    lo: i32,
    hi: i32,
}

impl Axes {
    /// Pixel column of (possibly fractional) sample index `i`. The data area is
    /// inset a few pixels from the frame so that dots on the edge stay visible.
    fn x(&self, i: f64) -> i32 {
        let span = (self.n_samples.max(2) - 1) as f64;
        let (l, r) = (self.left + 3, self.right - 3);
        l + ((i / span) * f64::from(r - l)).round() as i32
    }

    /// Pixel row of log10 value `l`, or None if it is outside the axis range.
    fn y_log(&self, l: f64) -> Option<i32> {
        let f = (f64::from(self.hi) - l) / f64::from(self.hi - self.lo);
        (-1e-9..=1.0 + 1e-9)
            .contains(&f)
            .then(|| self.top + (f * f64::from(self.bottom - self.top)).round() as i32)
    }

    fn y(&self, v: f64) -> Option<i32> {
        log_value(v).and_then(|l| self.y_log(l))
    }
}

pub(super) fn draw_panel(
    width: u32,
    height: u32,
    title: &str,
    term_names: &[String],
    rows: &[&ConvergenceRow],
    (lo, hi): (i32, i32),
) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height, WHITE);
    // Text grows with the panel so labels stay legible on large plots.
    let s = (width.min(height * 4 / 3) / 230).clamp(1, 4);
    let si = s as i32;
    let th = text_height(s) as i32;
    let cap = (CAP_H * s) as i32;

    let tick_labels: Vec<(i32, String)> = (lo..=hi).map(|d| (d, format!("1e{d}"))).collect();
    let tick_w = tick_labels
        .iter()
        .map(|(_, t)| text_width(t, s))
        .max()
        .unwrap_or(0) as i32;
    let axes = Axes {
        left: 4 * si + th + 6 * si + tick_w + 5 * si,
        top: 6 * si + text_height(s + 1) as i32 + 6 * si,
        right: width as i32 - 8 * si,
        bottom: height as i32 - (4 * si + th + 5 * si + th + 6 * si),
        n_samples: rows.len(),
        lo,
        hi,
    };
    let Axes {
        left,
        top,
        right,
        bottom,
        ..
    } = axes;

    // Title, centred over the plot area.
    let tw = text_width(title, s + 1) as i32;
    draw_text(
        &mut img,
        (left + right - tw) / 2,
        6 * si,
        title,
        TEXT,
        s + 1,
    );
    if right - left < 10 || bottom - top < 10 {
        return img; // too small for axes; the title alone is all that fits
    }

    // y axis: a gridline per decade, labels on as many decades as fit.
    let px_per_decade = f64::from(bottom - top) / f64::from(hi - lo);
    let label_every = nice_step(f64::from(2 * th) / px_per_decade).max(1) as i32;
    for (d, label) in &tick_labels {
        let Some(y) = axes.y_log(f64::from(*d)) else {
            continue;
        };
        if px_per_decade >= 4.0 {
            fill_rect(&mut img, left, y, right - left, 1, GRID);
        }
        if (d - lo) % label_every == 0 {
            fill_rect(&mut img, left - 3 * si, y, 3 * si, 1, FRAME);
            let w = text_width(label, s) as i32;
            draw_text(&mut img, left - 5 * si - w, y - cap / 2, label, TEXT, s);
        }
    }
    let y_label = "energy (log10)";
    let yl_w = text_width(y_label, s) as i32;
    draw_text_up(
        &mut img,
        4 * si,
        (top + bottom + yl_w) / 2,
        y_label,
        TEXT,
        s,
    );

    // x axis: nice steps of sample index, as many as fit without labels touching.
    if rows.len() > 1 {
        let widest = text_width(&(rows.len() - 1).to_string(), s) as f64 + f64::from(8 * si);
        let px_per_sample = f64::from(right - left - 6) / (rows.len() - 1) as f64;
        let step = nice_step((widest / px_per_sample).max((rows.len() - 1) as f64 / 8.0));
        for i in (0..rows.len()).step_by(step) {
            let x = axes.x(i as f64);
            fill_rect(&mut img, x, top, 1, bottom - top, GRID);
            fill_rect(&mut img, x, bottom, 1, 3 * si, FRAME);
            let label = i.to_string();
            let w = text_width(&label, s) as i32;
            draw_text(&mut img, x - w / 2, bottom + 5 * si, &label, TEXT, s);
        }
    }
    let x_label = "sample";
    let xl_w = text_width(x_label, s) as i32;
    draw_text(
        &mut img,
        (left + right - xl_w) / 2,
        height as i32 - 4 * si - th,
        x_label,
        TEXT,
        s,
    );

    if rows.is_empty() {
        let msg = "no samples";
        let w = text_width(msg, s) as i32;
        draw_text(
            &mut img,
            (left + right - w) / 2,
            (top + bottom - th) / 2,
            msg,
            FRAME,
            s,
        );
        rect_outline(
            &mut img,
            left,
            top,
            right - left + 1,
            bottom - top + 1,
            FRAME,
        );
        return img;
    }

    // Series: terms first, total last so that it stays on top.
    let n_terms = term_names.len();
    let value = |row: &ConvergenceRow, series: usize| -> f64 {
        if series < n_terms {
            row.terms.get(series).copied().unwrap_or(0.0)
        } else {
            row.total
        }
    };
    let color = |series: usize| {
        if series < n_terms {
            term_color(series)
        } else {
            RED
        }
    };

    // Faint dot per sample.
    for series in 0..=n_terms {
        for (i, row) in rows.iter().enumerate() {
            if let Some(y) = axes.y(value(row, series)) {
                put_blend(&mut img, axes.x(i as f64), y, color(series), DOT_ALPHA);
            }
        }
    }

    // Best sample (lowest finite total) of each generation, placed at the
    // middle of the generation's run of samples.
    let mut best: Vec<(f64, &ConvergenceRow)> = Vec::new();
    let mut start = 0;
    while start < rows.len() {
        let mut end = start + 1;
        while end < rows.len() && rows[end].iteration == rows[start].iteration {
            end += 1;
        }
        let winner = rows[start..end]
            .iter()
            .filter(|r| r.total.is_finite())
            .min_by(|a, b| a.total.total_cmp(&b.total));
        if let Some(w) = winner {
            best.push(((start + end - 1) as f64 / 2.0, w));
        }
        start = end;
    }
    // Many generations per pixel column would make the line a solid band of
    // noise; one vertex per column (the median of its generation bests) shows
    // the trend, while the dots still show the spread.
    let mut vertices: Vec<(i32, &ConvergenceRow)> = Vec::new();
    let mut k = 0;
    while k < best.len() {
        let px = axes.x(best[k].0);
        let mut e = k + 1;
        while e < best.len() && axes.x(best[e].0) == px {
            e += 1;
        }
        let mut column: Vec<&ConvergenceRow> = best[k..e].iter().map(|b| b.1).collect();
        column.sort_by(|a, b| a.total.total_cmp(&b.total));
        vertices.push((px, column[column.len() / 2]));
        k = e;
    }
    for series in 0..=n_terms {
        let mut prev: Option<(i32, i32)> = None;
        for &(x, row) in &vertices {
            // A missing value breaks the line: log scale has no place for 0.
            let p = axes.y(value(row, series)).map(|y| (x, y));
            if let Some(p) = p {
                line(&mut img, prev.unwrap_or(p), p, color(series), 2);
            }
            prev = p;
        }
    }
    rect_outline(
        &mut img,
        left,
        top,
        right - left + 1,
        bottom - top + 1,
        FRAME,
    );

    // Legend, in whichever corner of the plot has the least data under it.
    let mut entries: Vec<(String, Rgb<u8>)> = vec![("total".to_string(), RED)];
    for t in legend_terms(rows, n_terms) {
        entries.push((term_names[t].clone(), term_color(t)));
    }
    let swatch = 12 * si;
    let pad = 4 * si;
    let line_h = th + 2 * si;
    let max_chars =
        ((right - left - swatch - 4 * pad - 2 * si) / (ADVANCE as i32 * si)).max(1) as usize;
    for (name, _) in &mut entries {
        if name.chars().count() > max_chars {
            *name = name.chars().take(max_chars).collect();
        }
    }
    let name_w = entries
        .iter()
        .map(|(n, _)| text_width(n, s))
        .max()
        .unwrap_or(0) as i32;
    let lw = pad + swatch + 2 * si + name_w + pad;
    let lh = pad + entries.len() as i32 * line_h - 2 * si + pad;
    let m = 5 * si;
    let corners = [
        (right - m - lw, top + m),
        (right - m - lw, bottom - m - lh),
        (left + m, top + m),
        (left + m, bottom - m - lh),
    ];
    let ink = |img: &RgbImage, (cx, cy): (i32, i32)| -> usize {
        let mut n = 0;
        for y in cy.max(0)..(cy + lh).min(img.height() as i32) {
            for x in cx.max(0)..(cx + lw).min(img.width() as i32) {
                let p = img.get_pixel(x as u32, y as u32);
                if *p != WHITE && *p != GRID {
                    n += 1;
                }
            }
        }
        n
    };
    let (lx, ly) = corners
        .iter()
        .copied()
        .min_by_key(|&c| ink(&img, c))
        .unwrap_or(corners[0]);
    fill_rect(&mut img, lx, ly, lw, lh, WHITE);
    rect_outline(&mut img, lx, ly, lw, lh, FRAME);
    for (k, (name, c)) in entries.iter().enumerate() {
        let y = ly + pad + k as i32 * line_h;
        fill_rect(
            &mut img,
            lx + pad,
            y + cap / 2 - si / 2 - 1,
            swatch,
            2 + si / 2 * 2,
            *c,
        );
        draw_text(&mut img, lx + pad + swatch + 2 * si, y, name, TEXT, s);
    }
    img
}
