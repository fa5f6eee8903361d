//! The contact sheet of a film: its stills (launch, mid-flight, `t`, after) in a grid,
//! each above its label, under a title line; built in memory.

use image::imageops::FilterType;
use image::RgbImage;
use plotters::prelude::*;

use super::{draw_err, ensure_font, PictureError, BLACK_TEXT, WHITE};

/// Height of the title line and of each tile's label (pixels).
const TITLE_HEIGHT: u32 = 40;
const LABEL_HEIGHT: u32 = 30;
/// White space between tiles and around them (pixels).
const GAP: u32 = 8;

/// The stills in a grid of two columns (one row for up to two stills), each scaled to
/// fit `max_width` for the whole sheet and labelled below, under `title`. Stills of
/// different sizes are scaled to the first one's size.
pub fn contact_sheet(
    stills: &[(RgbImage, String)],
    title: &str,
    max_width: u32,
) -> Result<RgbImage, PictureError> {
    let Some((first, _)) = stills.first() else {
        return Err(PictureError::Draw {
            what: "the contact sheet",
            message: "no still".into(),
        });
    };
    ensure_font();
    let cols = stills.len().min(2) as u32;
    let rows = (stills.len() as u32).div_ceil(cols);
    let tw = first
        .width()
        .min((max_width.saturating_sub(GAP * (cols + 1)) / cols).max(16));
    let th = ((first.height() as f64 * tw as f64 / first.width() as f64).round() as u32).max(1);
    let (w, h) = (
        GAP + cols * (tw + GAP),
        TITLE_HEIGHT + rows * (th + LABEL_HEIGHT + GAP),
    );
    let mut out = RgbImage::from_pixel(w, h, WHITE);
    let origin = |k: u32| {
        (
            GAP + (k % cols) * (tw + GAP),
            TITLE_HEIGHT + (k / cols) * (th + LABEL_HEIGHT + GAP),
        )
    };
    for (k, (img, _)) in stills.iter().enumerate() {
        let tile = if img.dimensions() == (tw, th) {
            img.clone()
        } else {
            image::imageops::resize(img, tw, th, FilterType::Triangle)
        };
        let (x, y) = origin(k as u32);
        image::imageops::replace(&mut out, &tile, i64::from(x), i64::from(y));
    }
    let err = |e: DrawingAreaErrorKind<_>| draw_err("the contact sheet's labels", e);
    let mut buf = out.into_raw();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let big = TextStyle::from(("sans-serif", 20).into_font()).color(&BLACK_TEXT);
        root.draw_text(title, &big, (GAP as i32, 10))
            .map_err(&err)?;
        let small = TextStyle::from(("sans-serif", 16).into_font()).color(&BLACK_TEXT);
        for (k, (_, label)) in stills.iter().enumerate() {
            let (x, y) = origin(k as u32);
            root.draw_text(label, &small, (x as i32 + 2, (y + th + 6) as i32))
                .map_err(&err)?;
        }
        root.present().map_err(&err)?;
    }
    Ok(RgbImage::from_raw(w, h, buf).expect("buffer keeps its size"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_stills_make_a_two_by_two_sheet_with_labels() {
        let colours = [[200, 30, 30], [30, 200, 30], [30, 30, 200], [200, 200, 30]];
        let stills: Vec<(RgbImage, String)> = colours
            .iter()
            .enumerate()
            .map(|(k, c)| {
                (
                    RgbImage::from_pixel(640, 360, image::Rgb(*c)),
                    format!("still {k}"),
                )
            })
            .collect();
        let sheet = contact_sheet(&stills, "a film", 1000).unwrap();
        let tw = (1000 - 3 * GAP) / 2;
        let th = (360.0 * tw as f64 / 640.0).round() as u32;
        assert_eq!(sheet.width(), GAP + 2 * (tw + GAP));
        assert_eq!(sheet.height(), TITLE_HEIGHT + 2 * (th + LABEL_HEIGHT + GAP));
        // Each tile's centre shows its still, in reading order.
        for (k, c) in colours.iter().enumerate() {
            let k = k as u32;
            let x = GAP + (k % 2) * (tw + GAP) + tw / 2;
            let y = TITLE_HEIGHT + (k / 2) * (th + LABEL_HEIGHT + GAP) + th / 2;
            assert_eq!(sheet.get_pixel(x, y).0, *c, "tile {k}");
        }
        // Labels and title are drawn: dark pixels below the first tile and at the top.
        let dark = |x0: u32, y0: u32, w: u32, h: u32| {
            (y0..y0 + h)
                .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
                .filter(|&(x, y)| sheet.get_pixel(x, y).0[0] < 100)
                .count()
        };
        assert!(dark(GAP, TITLE_HEIGHT + th, tw, LABEL_HEIGHT) > 20);
        assert!(dark(0, 0, 300, TITLE_HEIGHT) > 20);
        assert!(contact_sheet(&[], "none", 100).is_err());
    }
}
