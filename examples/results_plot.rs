//! The planted suites from the results ledger as a picture: each class's median IoU
//! (a line) and lowest IoU (a cross) over the draws of `results/planted.csv`, in ledger
//! order, with the acceptance's bars (median 0.995, every problem 0.97).
//!
//! `cargo run --release --example results_plot` writes `docs/images/results-planted.png`.

use std::collections::BTreeMap;
use std::error::Error;

use plotters::prelude::*;

const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
const OUT: &str = "docs/images/results-planted.png";
const SIZE: (u32, u32) = (900, 480);

/// The first five hues of "tab10", as the solver's plots use, one per class.
const PALETTE: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
];

/// The draws the plot shows, the last of the ledger (as the page's table).
const LAST_DRAWS: usize = 4;

/// One draw of the planted suite: its commit, first seed and route.
type Draw = (String, String, String);

/// A class's median and lowest IoU in one draw.
#[derive(Default, Clone, Copy)]
struct Class {
    median: Option<f64>,
    lowest: Option<f64>,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// The planted ledger: its last draws in ledger order, its classes, and per draw (by index)
/// and class the IoU.
struct Planted {
    draws: Vec<Draw>,
    classes: Vec<String>,
    ious: BTreeMap<(usize, String), Class>,
}

/// The draws in ledger order, and per draw each class's IoU. A draw's rows are one per
/// problem (item `<class> <seed>`) or the summary (`<class> median`, `<class> lowest`).
fn read_ledger() -> Result<Planted, Box<dyn Error>> {
    let mut reader = csv::Reader::from_path("results/planted.csv")?;
    let mut draws: Vec<Draw> = Vec::new();
    let mut classes: Vec<String> = Vec::new();
    let mut problems: BTreeMap<(usize, String), Vec<f64>> = BTreeMap::new();
    let mut out: BTreeMap<(usize, String), Class> = BTreeMap::new();
    for record in reader.records() {
        let r = record?;
        let draw = (r[0].to_string(), r[4].to_string(), r[6].to_string());
        let d = draws.iter().position(|x| *x == draw).unwrap_or_else(|| {
            draws.push(draw);
            draws.len() - 1
        });
        let (class, what) = r[5].split_once(' ').unwrap_or((&r[5], ""));
        if !classes.iter().any(|c| c == class) {
            classes.push(class.to_string());
        }
        let Ok(iou) = r[7].parse::<f64>() else {
            continue;
        };
        let key = (d, class.to_string());
        match what {
            "median" => out.entry(key).or_default().median = Some(iou),
            "lowest" => out.entry(key).or_default().lowest = Some(iou),
            _ => problems.entry(key).or_default().push(iou),
        }
    }
    for (key, ious) in problems {
        let lowest = ious.iter().copied().reduce(f64::min);
        out.insert(
            key,
            Class {
                median: median(ious),
                lowest,
            },
        );
    }
    // The last draws only, as docs/results.md's table shows them.
    let first = draws.len().saturating_sub(LAST_DRAWS);
    draws.drain(..first);
    let out = out
        .into_iter()
        .filter(|((d, _), _)| *d >= first)
        .map(|((d, class), c)| ((d - first, class), c))
        .collect();
    Ok(Planted {
        draws,
        classes,
        ious: out,
    })
}

fn main() -> Result<(), Box<dyn Error>> {
    for style in [FontStyle::Normal, FontStyle::Bold] {
        plotters::style::register_font("sans-serif", style, FONT)
            .map_err(|_| "the embedded DejaVu Sans font does not parse")?;
    }
    let Planted {
        draws,
        classes,
        ious,
    } = read_ledger()?;
    let n = draws.len() as i32;
    let low = ious
        .values()
        .flat_map(|c| [c.median, c.lowest])
        .flatten()
        .fold(0.97_f64, f64::min);
    let y0 = ((low - 0.005) * 100.0).floor() / 100.0;

    let mut buf = vec![255u8; SIZE.0 as usize * SIZE.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        let (plot, legend) = root.split_horizontally(SIZE.0 - 170);
        let mut chart = ChartBuilder::on(&plot)
            .caption(
                "Planted problems: median (line) and lowest (x) IoU per class",
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(60)
            .build_cartesian_2d((0..n - 1).into_segmented(), y0..1.0005)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(RGBColor(235, 235, 235))
            .x_desc("draw: first seed, route, commit (results/planted.csv)")
            .y_desc("IoU at t")
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => draws
                    .get(*i as usize)
                    .map(|(commit, seed, route)| format!("{seed} {route} {commit}"))
                    .unwrap_or_default(),
                _ => String::new(),
            })
            .label_style(("sans-serif", 13))
            .draw()?;
        for (bar, label) in [(0.995, "median bar 0.995"), (0.97, "every problem 0.97")] {
            chart.draw_series(LineSeries::new(
                [(SegmentValue::Exact(0), bar), (SegmentValue::Last, bar)],
                ShapeStyle::from(RGBColor(120, 120, 120)).stroke_width(1),
            ))?;
            chart.draw_series([Text::new(
                label,
                (SegmentValue::Exact(0), bar + 0.0007),
                ("sans-serif", 12).into_font().color(&RGBColor(90, 90, 90)),
            )])?;
        }
        for (k, class) in classes.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            let at = |d: i32| {
                ious.get(&(d as usize, class.clone()))
                    .copied()
                    .unwrap_or_default()
            };
            let medians: Vec<_> = (0..n)
                .filter_map(|d| at(d).median.map(|m| (SegmentValue::CenterOf(d), m)))
                .collect();
            chart.draw_series(LineSeries::new(
                medians.clone(),
                ShapeStyle::from(colour).stroke_width(2),
            ))?;
            chart.draw_series(
                medians
                    .into_iter()
                    .map(|p| Circle::new(p, 4, ShapeStyle::from(colour).filled())),
            )?;
            chart.draw_series((0..n).filter_map(|d| {
                at(d).lowest.map(|l| {
                    Cross::new(
                        (SegmentValue::CenterOf(d), l),
                        5,
                        ShapeStyle::from(colour).stroke_width(2),
                    )
                })
            }))?;
        }
        for (k, class) in classes.iter().enumerate() {
            let y = 60 + 26 * k as i32;
            let colour = PALETTE[k % PALETTE.len()];
            legend.draw(&PathElement::new(
                [(10, y), (40, y)],
                ShapeStyle::from(colour).stroke_width(2),
            ))?;
            legend.draw(&Text::new(
                class.clone(),
                (48, y - 8),
                ("sans-serif", 15).into_font(),
            ))?;
        }
        root.present()?;
    }
    image::RgbImage::from_raw(SIZE.0, SIZE.1, buf)
        .ok_or("the buffer has not the picture's size")?
        .save(OUT)?;
    println!("wrote {OUT}");
    Ok(())
}
