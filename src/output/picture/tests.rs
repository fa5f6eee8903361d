use super::plot::{decade_range, generation_bests, runs};
use super::plot::{ConvergenceData, ConvergenceRow};
use super::*;

#[test]
fn mask_is_black_on_white_with_y_down() {
    let img = mask_image(3, 2, &|x, y| x == 0 && y == 1);
    assert_eq!(img.get_pixel(0, 1)[0], 0);
    assert_eq!(img.get_pixel(0, 0)[0], 255);
    assert_eq!(img.get_pixel(2, 1)[0], 255);
}

#[test]
fn overlay_gives_agreement_misses_and_extras_three_distinct_colours() {
    // Pixel 0: both, 1: target only, 2: shadow only, 3: neither.
    let (img, counts) = overlay_image(4, 1, &|x, _| x <= 1, &|x, _| x == 0 || x == 2);
    assert_eq!(*img.get_pixel(0, 0), AGREE);
    assert_eq!(*img.get_pixel(1, 0), MISSED);
    assert_eq!(*img.get_pixel(2, 0), EXTRA);
    assert_eq!(*img.get_pixel(3, 0), WHITE);
    assert_eq!(
        counts,
        OverlayCounts {
            agree: 1,
            missed: 1,
            extra: 1
        }
    );
    assert!((counts.iou() - 1.0 / 3.0).abs() < 1e-12);
    // The colours differ from each other and from white by far more than a glance needs.
    let colours = [AGREE, MISSED, EXTRA, WHITE];
    for (i, a) in colours.iter().enumerate() {
        for b in &colours[i + 1..] {
            let d: i32 = (0..3)
                .map(|k| (i32::from(a[k]) - i32::from(b[k])).abs())
                .sum();
            assert!(d > 150, "{a:?} and {b:?} are too alike");
        }
    }
}

#[test]
fn overlay_figure_keeps_the_overlay_at_one_to_one_and_adds_a_caption() {
    let (w, h) = (600, 40);
    let fig = overlay_figure(w, h, &|x, _| x < 300, &|x, _| x < 200, "test").unwrap();
    assert_eq!(fig.width(), 600);
    assert!(fig.height() > 40 + 40, "a caption with two lines of text");
    assert_eq!(*fig.get_pixel(100, 10), AGREE);
    assert_eq!(*fig.get_pixel(250, 10), MISSED);
    // The caption holds dark text and the three legend swatches.
    let caption: Vec<_> = (41..fig.height())
        .flat_map(|y| (0..fig.width()).map(move |x| (x, y)))
        .map(|(x, y)| *fig.get_pixel(x, y))
        .collect();
    assert!(caption.iter().any(|p| p[0] < 60 && p[1] < 60 && p[2] < 60));
    for c in [AGREE, MISSED, EXTRA] {
        assert!(caption.contains(&c), "legend swatch {c:?} missing");
    }
}

#[test]
fn narrow_overlay_is_centred_in_a_figure_wide_enough_for_the_legend() {
    let fig = overlay_figure(10, 10, &|_, _| true, &|_, _| true, "t").unwrap();
    assert!(fig.width() > 10);
    let x0 = (fig.width() - 10) / 2;
    assert_eq!(*fig.get_pixel(x0, 0), AGREE);
    assert_eq!(*fig.get_pixel(0, 0), WHITE);
}

#[test]
fn difference_uses_four_colours() {
    let img = difference_image(4, 1, &|x, _| x <= 1, &|x, _| x == 0 || x == 2);
    assert_eq!(*img.get_pixel(0, 0), BLACK);
    assert_eq!(*img.get_pixel(1, 0), RED);
    assert_eq!(*img.get_pixel(2, 0), BLUE);
    assert_eq!(*img.get_pixel(3, 0), WHITE);
}

fn row(stage: usize, iteration: usize, terms: &[f64]) -> ConvergenceRow {
    ConvergenceRow {
        stage,
        iteration,
        terms: terms.to_vec(),
        total: terms.iter().sum(),
    }
}

fn sample_data() -> ConvergenceData {
    let mut rows = Vec::new();
    for stage in 0..2 {
        for it in 0..20 {
            for k in 0..4 {
                let v = 10f64.powf(-(it as f64) / 5.0) * (1.0 + k as f64);
                rows.push(row(stage, it, &[v, v / 10.0, 0.0]));
            }
        }
    }
    ConvergenceData {
        scene: "demo".into(),
        stage_names: vec!["first".into(), "second".into()],
        term_names: vec!["a".into(), "b".into(), "c".into()],
        rows,
    }
}

#[test]
fn convergence_plot_draws_png_and_svg_with_names_and_legend() {
    let fig = plot::convergence(&sample_data()).unwrap();
    assert!(fig.png.width() >= 1000 && fig.png.height() >= 500);
    // Black total line and coloured term lines are both present.
    let pixels: Vec<_> = fig.png.pixels().copied().collect();
    assert!(pixels.iter().any(|p| p[0] < 20 && p[1] < 20 && p[2] < 20));
    assert!(pixels.contains(&Rgb([31, 119, 180])));
    for text in [
        "demo",
        "stage 1: first",
        "stage 2: second",
        "best total so far",
    ] {
        assert!(fig.svg.contains(text), "{text} missing from the SVG");
    }
    // The term that is zero throughout has no legend entry.
    assert!(!fig.svg.contains(">c<"));
}

#[test]
fn a_later_attempt_of_a_solve_is_marked_where_its_stages_start_again() {
    let mut data = sample_data();
    assert!(!plot::convergence(&data).unwrap().svg.contains("attempt 2"));
    // The same two stages again: a second attempt.
    let again: Vec<ConvergenceRow> = data.rows.clone();
    data.rows.extend(again);
    let fig = plot::convergence(&data).unwrap();
    assert!(
        fig.svg.contains("attempt 2"),
        "no marker of the second attempt"
    );
    assert!(!fig.svg.contains("attempt 3"));
}

#[test]
fn convergence_plot_survives_non_finite_and_empty_data() {
    let mut data = sample_data();
    data.rows[3].total = f64::NAN;
    data.rows[5].terms[0] = f64::INFINITY;
    data.rows[7].terms[1] = -1.0;
    plot::convergence(&data).unwrap();
    plot::convergence(&ConvergenceData::default()).unwrap();
}

#[test]
fn generation_bests_and_runs_split_at_stages_and_missing_values() {
    let rows = vec![
        row(0, 0, &[3.0]),
        row(0, 0, &[1.0]),
        row(0, 1, &[0.0]),
        row(1, 0, &[2.0]),
    ];
    let bests = generation_bests(&rows);
    assert_eq!(bests.len(), 3);
    assert_eq!(bests[0].row.total, 1.0);
    assert_eq!(bests[0].x, 1.0);
    let r = runs(&bests, |r| r.total);
    assert_eq!(
        r.len(),
        2,
        "the zero breaks the line and the stage starts a new one"
    );
}

#[test]
fn decade_range_follows_the_data_within_sixteen_decades() {
    let mut data = sample_data();
    assert_eq!(decade_range(&data), (-5, 1));
    data.rows[0].terms[0] = 1e-300;
    let (lo, hi) = decade_range(&data);
    assert_eq!(hi - lo, 16);
}

#[test]
fn budget_plots_draw_png_and_svg() {
    let h = plot::histogram(&plot::HistogramData {
        title: "h".into(),
        x_label: "IoU".into(),
        lo: 0.5,
        hi: 1.0,
        counts: vec![1, 5, 3, 0, 9],
        marker: Some((0.8, "threshold".into())),
    })
    .unwrap();
    assert!(h.svg.contains("threshold"));
    let panel = plot::Panel {
        title: "p".into(),
        x_label: "mm/s".into(),
        curves: vec![("mean IoU".into(), vec![(0.0, 0.9), (1.0, 0.5)])],
        marker: 0.5,
    };
    let g = plot::tolerance_grid(&plot::GridData {
        title: "g".into(),
        panels: vec![panel; 5],
        y_label: "IoU".into(),
        marker_name: "largest tolerance".into(),
    })
    .unwrap();
    // Five panels make a grid of three columns and two rows, not a strip.
    assert!(g.png.width() < 2 * g.png.height());
    assert!(g.svg.contains("largest tolerance"));
}

#[test]
fn stage_labels_shrink_to_their_number_or_vanish_when_stages_are_narrow() {
    let mut data = sample_data();
    // One wide stage, then 60 narrow ones of a single generation each.
    for stage in 2..62 {
        data.rows.push(row(stage, 0, &[1.0, 0.1, 0.0]));
        data.stage_names
            .push(format!("narrow stage with a long name {stage}"));
    }
    let fig = plot::convergence(&data).unwrap();
    assert!(fig.svg.contains("stage 1: first"));
    assert!(!fig.svg.contains("narrow stage with a long name"));
}
