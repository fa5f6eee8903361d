use super::*;

#[test]
fn mask_is_black_on_white_with_y_down() {
    // Shadow only in the top-left pixel: checks polarity and that y = 0 is the top.
    let img = mask_image(3, 2, &|x, y| x == 0 && y == 0);
    assert_eq!(img.dimensions(), (3, 2));
    assert_eq!(img.get_pixel(0, 0).0, [0]);
    assert_eq!(img.get_pixel(0, 1).0, [255]);
    assert_eq!(img.get_pixel(2, 1).0, [255]);
}

#[test]
fn overlay_distinguishes_all_four_cases() {
    // Column 0: target only; 1: shadow only; 2: both; 3: neither.
    let target = |x: usize, _: usize| x == 0 || x == 2;
    let shadow = |x: usize, _: usize| x == 1 || x == 2;
    let img = overlay_image(4, 1, &target, &shadow);
    let px: Vec<[u8; 3]> = (0..4).map(|x| img.get_pixel(x, 0).0).collect();
    assert_eq!(px[0], [0, 0, 0], "target only is black");
    assert_eq!(
        px[1],
        [255, 115, 115],
        "shadow only is pink (red over white)"
    );
    assert_eq!(px[2], [140, 0, 0], "overlap is dark red (red over black)");
    assert_eq!(px[3], [255, 255, 255], "neither is white");
}

#[test]
fn difference_uses_four_colours() {
    let a = |x: usize, _: usize| x == 0 || x == 1;
    let b = |x: usize, _: usize| x == 0 || x == 2;
    let img = difference_image(4, 1, &a, &b);
    assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0]);
    assert_eq!(img.get_pixel(1, 0).0, [255, 0, 0]);
    assert_eq!(img.get_pixel(2, 0).0, [0, 0, 255]);
    assert_eq!(img.get_pixel(3, 0).0, [255, 255, 255]);
}

#[test]
fn side_by_side_places_images_with_gap() {
    let a = RgbImage::from_pixel(2, 3, RED);
    let b = RgbImage::from_pixel(4, 1, BLUE);
    let out = side_by_side(&[&a, &b], 5);
    assert_eq!(out.dimensions(), (2 + 5 + 4, 3));
    assert_eq!(*out.get_pixel(1, 2), RED);
    assert_eq!(*out.get_pixel(3, 0), WHITE, "gap is white");
    assert_eq!(*out.get_pixel(7, 0), BLUE);
    assert_eq!(*out.get_pixel(7, 1), WHITE, "short image is padded below");
    assert_eq!(side_by_side(&[], 3).dimensions(), (0, 0));
}

#[test]
fn text_puts_dark_pixels_where_the_glyph_is() {
    let mut img = RgbImage::from_pixel(20, 10, WHITE);
    // '1' is 00100 / 01100 / ... / 01110, drawn at (1, 1).
    draw_text(&mut img, 1, 1, "1", BLACK, 1);
    assert_eq!(*img.get_pixel(1 + 2, 1), BLACK, "top of the stem");
    assert_eq!(*img.get_pixel(1 + 1, 2), BLACK, "the flag");
    assert_eq!(*img.get_pixel(1, 1), WHITE, "left of the stem");
    assert_eq!(*img.get_pixel(1 + 4, 1 + 6), WHITE, "right of the foot");
    assert_eq!(*img.get_pixel(1 + 3, 1 + 6), BLACK, "foot");

    // Scale 2: '-' is row 3 full width, so rows 6..8 are dark over 10 px.
    let mut img = RgbImage::from_pixel(20, 20, WHITE);
    draw_text(&mut img, 0, 0, "-", BLACK, 2);
    for x in 0..10 {
        assert_eq!(*img.get_pixel(x, 6), BLACK);
        assert_eq!(*img.get_pixel(x, 7), BLACK);
        assert_eq!(*img.get_pixel(x, 5), WHITE);
        assert_eq!(*img.get_pixel(x, 8), WHITE);
    }
    assert_eq!(*img.get_pixel(10, 6), WHITE);
    assert_eq!(text_width("-", 2), 10);
    assert_eq!(text_width("ab", 1), 11);
    assert_eq!(text_width("", 3), 0);
}

#[test]
fn text_is_clipped_not_panicking() {
    let mut img = RgbImage::from_pixel(4, 4, WHITE);
    draw_text(&mut img, -3, -3, "Wide text\u{e9}", BLACK, 3);
    draw_text_up(&mut img, 2, 1, "up", BLACK, 2);
}

#[test]
fn rotated_text_reads_bottom_to_top() {
    // '-' rotated: a vertical bar at glyph row 3, spanning 5 px upwards.
    let mut img = RgbImage::from_pixel(10, 10, WHITE);
    draw_text_up(&mut img, 0, 9, "-", BLACK, 1);
    for y in 4..9 {
        assert_eq!(*img.get_pixel(3, y), BLACK, "y = {y}");
    }
    assert_eq!(*img.get_pixel(3, 9), WHITE);
    assert_eq!(*img.get_pixel(3, 3), WHITE);
    assert_eq!(*img.get_pixel(2, 6), WHITE);
}

fn row(stage: usize, iteration: usize, terms: &[f64]) -> ConvergenceRow {
    ConvergenceRow {
        stage,
        iteration,
        terms: terms.to_vec(),
        total: terms.iter().sum(),
    }
}

#[test]
fn plot_has_one_panel_per_stage_and_a_red_total() {
    let mut rows = Vec::new();
    for i in 0..200 {
        let e = 100.0 * (-(i as f64) / 50.0).exp();
        rows.push(row(0, i / 10, &[e, 0.0, e * 0.1]));
        rows.push(row(1, i / 10, &[e * 0.01, 0.5, 0.0]));
    }
    let data = ConvergenceData {
        stage_names: vec!["coarse".into(), "fine".into()],
        term_names: vec!["a".into(), "b".into(), "c".into()],
        rows,
    };
    let img = convergence_plot(&data, 400, 300);
    assert_eq!(img.dimensions(), (800, 300));
    for panel in 0..2 {
        let reds = (panel * 400..(panel + 1) * 400)
            .flat_map(|x| (0..300).map(move |y| (x, y)))
            .filter(|&(x, y)| *img.get_pixel(x, y) == RED)
            .count();
        // The legend swatch alone is ~24 px; the curve adds hundreds.
        assert!(reds > 200, "panel {panel} has only {reds} red pixels");
    }
}

#[test]
fn plot_survives_non_finite_and_missing_values() {
    let data = ConvergenceData {
        stage_names: vec![],
        term_names: vec!["only".into()],
        rows: vec![
            row(0, 0, &[f64::NAN, 1.0]),
            ConvergenceRow {
                stage: 0,
                iteration: 0,
                terms: vec![],
                total: f64::INFINITY,
            },
            ConvergenceRow {
                stage: 0,
                iteration: 1,
                terms: vec![-1.0],
                total: f64::NAN,
            },
            ConvergenceRow {
                stage: 2,
                iteration: 0,
                terms: vec![0.0; 4],
                total: 0.0,
            },
            ConvergenceRow {
                stage: 2,
                iteration: 1,
                terms: vec![1e-300],
                total: 1e300,
            },
        ],
    };
    let img = convergence_plot(&data, 200, 150);
    assert_eq!(
        img.dimensions(),
        (600, 150),
        "stage 1 has no rows but still a panel"
    );
    let empty = convergence_plot(&ConvergenceData::default(), 200, 150);
    assert_eq!(empty.dimensions(), (200, 150));
    let tiny = convergence_plot(&data, 5, 5);
    assert_eq!(tiny.dimensions(), (15, 5));
}

#[test]
fn axis_range_and_legend_follow_the_data() {
    let data = ConvergenceData {
        rows: vec![
            row(0, 0, &[0.02, 0.0, 300.0]),
            row(0, 1, &[f64::NAN, -4.0, 0.5]),
        ],
        ..Default::default()
    };
    assert_eq!(decade_range(&data), (-2, 3));
    let rows: Vec<&ConvergenceRow> = data.rows.iter().collect();
    assert_eq!(
        legend_terms(&rows, 4),
        vec![0, 2],
        "zero/negative/absent terms are left out"
    );
    let flat = ConvergenceData {
        rows: vec![row(0, 0, &[1.0])],
        ..Default::default()
    };
    assert_eq!(decade_range(&flat), (0, 1));
    let wide = ConvergenceData {
        rows: vec![row(0, 0, &[1e-300, 1e5])],
        ..Default::default()
    };
    assert_eq!(decade_range(&wide), (5 - MAX_DECADES, 5));
}

#[test]
fn nice_steps() {
    assert_eq!(nice_step(0.0), 1);
    assert_eq!(nice_step(1.5), 2);
    assert_eq!(nice_step(3.0), 5);
    assert_eq!(nice_step(1234.0), 2000);
}
