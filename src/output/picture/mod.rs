//! Pictures for the user, built in memory (the caller decides where to save them).
//!
//! - [`mask_image`]: a shadow mask as black-on-white.
//! - [`overlay_figure`]: target and shadow at 1:1 in three distinct colours (agreement
//!   grey, missed target blue, extra shadow red) above a caption with the IoU and a
//!   legend, so that the picture reads without the README.
//! - [`difference_image`]: four-colour comparison of two masks.
//! - [`plot`]: the convergence plot (the paper's Figure 7) and the error budget's
//!   histogram and tolerance grid, drawn with `plotters` as PNG and SVG.
//! - [`sheet`]: the contact sheet of a film (`bsa video`): its stills in a grid, labelled.
//!
//! Text is drawn with DejaVu Sans, embedded in the binary, so that no system font
//! library is needed at build or run time. Nothing here touches the filesystem.

use image::{GrayImage, Luma, Rgb, RgbImage};
use plotters::prelude::*;

pub mod plot;
pub mod sheet;

/// Why a picture could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    #[error("cannot draw {what}: {message}")]
    Draw { what: &'static str, message: String },
}

/// Background colour of every picture.
pub const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
/// "Both" in [`difference_image`].
pub const BLACK: Rgb<u8> = Rgb([0, 0, 0]);
/// "Only a" in [`difference_image`].
pub const RED: Rgb<u8> = Rgb([255, 0, 0]);
/// "Only b" in [`difference_image`].
pub const BLUE: Rgb<u8> = Rgb([0, 0, 255]);

/// Overlay colour where shadow and target agree: a mid grey, so that the two error
/// colours stand out against it.
pub const AGREE: Rgb<u8> = Rgb([120, 120, 120]);
/// Overlay colour of target pixels the shadow misses.
pub const MISSED: Rgb<u8> = Rgb([31, 119, 220]);
/// Overlay colour of shadow pixels outside the target.
pub const EXTRA: Rgb<u8> = Rgb([220, 40, 40]);

/// The embedded font (DejaVu Sans; its licence is in assets/fonts/).
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// Register the embedded font as plotters' "sans-serif" once per process. Every
/// drawing function calls this first, because plotters' `ab_glyph` backend knows no
/// font until one is registered.
pub(crate) fn ensure_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            // The font is a fixed, valid file compiled into the binary, so a failure
            // here is a build mistake that every picture test would catch.
            if plotters::style::register_font("sans-serif", style, FONT).is_err() {
                panic!("the embedded DejaVu Sans font does not parse");
            }
        }
    });
}

/// A plotters error as a [`PictureError`] naming what was being drawn.
pub(crate) fn draw_err(what: &'static str, e: impl std::fmt::Debug) -> PictureError {
    PictureError::Draw {
        what,
        message: format!("{e:?}"),
    }
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).expect("picture dimension does not fit in u32")
}

/// Shadow mask: black (0) where `shadow(x, y)`, white (255) elsewhere; y = 0 is the
/// top row.
pub fn mask_image(width: usize, height: usize, shadow: &dyn Fn(usize, usize) -> bool) -> GrayImage {
    GrayImage::from_fn(to_u32(width), to_u32(height), |x, y| {
        Luma([if shadow(x as usize, y as usize) {
            0
        } else {
            255
        }])
    })
}

/// Pixel counts of an overlay: where target and shadow agree and where they differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OverlayCounts {
    pub agree: usize,
    pub missed: usize,
    pub extra: usize,
}

impl OverlayCounts {
    /// Intersection over union of target and shadow (1 when both are empty).
    pub fn iou(&self) -> f64 {
        let union = self.agree + self.missed + self.extra;
        if union == 0 {
            1.0
        } else {
            self.agree as f64 / union as f64
        }
    }
}

/// Target and shadow pixel by pixel: agreement [`AGREE`], target only [`MISSED`],
/// shadow only [`EXTRA`], neither white; with the counts of each.
pub fn overlay_image(
    width: usize,
    height: usize,
    target: &dyn Fn(usize, usize) -> bool,
    shadow: &dyn Fn(usize, usize) -> bool,
) -> (RgbImage, OverlayCounts) {
    let mut counts = OverlayCounts::default();
    let img = RgbImage::from_fn(to_u32(width), to_u32(height), |x, y| {
        let (x, y) = (x as usize, y as usize);
        match (target(x, y), shadow(x, y)) {
            (true, true) => {
                counts.agree += 1;
                AGREE
            }
            (true, false) => {
                counts.missed += 1;
                MISSED
            }
            (false, true) => {
                counts.extra += 1;
                EXTRA
            }
            (false, false) => WHITE,
        }
    });
    (img, counts)
}

/// Height of the caption under an overlay, in pixels.
const CAPTION_HEIGHT: u32 = 78;
/// Narrowest overlay figure: wide enough for the legend on one line.
const MIN_FIGURE_WIDTH: u32 = 560;

/// [`overlay_image`] at 1:1 with a caption below it: `title` and the IoU on the first
/// line, the three colours with their pixel counts on the second. The overlay is
/// centred when it is narrower than the legend.
pub fn overlay_figure(
    width: usize,
    height: usize,
    target: &dyn Fn(usize, usize) -> bool,
    shadow: &dyn Fn(usize, usize) -> bool,
    title: &str,
) -> Result<RgbImage, PictureError> {
    ensure_font();
    let (overlay, counts) = overlay_image(width, height, target, shadow);
    let fig_w = overlay.width().max(MIN_FIGURE_WIDTH);
    let fig_h = overlay.height() + CAPTION_HEIGHT;
    let mut out = RgbImage::from_pixel(fig_w, fig_h, WHITE);
    let x0 = (fig_w - overlay.width()) / 2;
    image::imageops::replace(&mut out, &overlay, i64::from(x0), 0);
    {
        let err = |e: DrawingAreaErrorKind<_>| draw_err("the overlay caption", e);
        let mut buf = out.into_raw();
        {
            let root = BitMapBackend::with_buffer(&mut buf, (fig_w, fig_h)).into_drawing_area();
            let caption = root.split_vertically(overlay.height()).1;
            // A thin rule shows where the picture ends, which white alone would hide.
            caption
                .draw(&PathElement::new(
                    [(0, 0), (fig_w as i32, 0)],
                    RGBColor(200, 200, 200),
                ))
                .map_err(&err)?;
            let text = TextStyle::from(("sans-serif", 17).into_font()).color(&BLACK_TEXT);
            caption
                .draw_text(
                    &format!("{title}   IoU {:.4}", counts.iou()),
                    &text,
                    (10, 10),
                )
                .map_err(&err)?;
            let small = TextStyle::from(("sans-serif", 15).into_font()).color(&BLACK_TEXT);
            let mut x = 10;
            for (color, name, n) in [
                (AGREE, "shadow on target", counts.agree),
                (MISSED, "target missed", counts.missed),
                (EXTRA, "extra shadow", counts.extra),
            ] {
                let c = RGBColor(color[0], color[1], color[2]);
                caption
                    .draw(&Rectangle::new([(x, 44), (x + 16, 60)], c.filled()))
                    .map_err(&err)?;
                let label = format!("{name} ({n} px)");
                caption
                    .draw_text(&label, &small, (x + 22, 44))
                    .map_err(&err)?;
                let (w, _) = caption.estimate_text_size(&label, &small).map_err(&err)?;
                x += 22 + w as i32 + 18;
            }
            root.present().map_err(&err)?;
        }
        out = RgbImage::from_raw(fig_w, fig_h, buf).expect("buffer keeps its size");
    }
    Ok(out)
}

/// The colour of text in every picture: near black.
pub(crate) const BLACK_TEXT: RGBColor = RGBColor(30, 30, 30);

/// Compares two masks: both = black, only `a` = red, only `b` = blue, neither = white.
pub fn difference_image(
    width: usize,
    height: usize,
    a: &dyn Fn(usize, usize) -> bool,
    b: &dyn Fn(usize, usize) -> bool,
) -> RgbImage {
    RgbImage::from_fn(to_u32(width), to_u32(height), |x, y| {
        let (x, y) = (x as usize, y as usize);
        match (a(x, y), b(x, y)) {
            (true, true) => BLACK,
            (true, false) => RED,
            (false, true) => BLUE,
            (false, false) => WHITE,
        }
    })
}

#[cfg(test)]
mod tests;
