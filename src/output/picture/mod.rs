//! Pictures for the user, built in memory (the caller decides where to save them).
//!
//! - [`mask_image`]: a shadow mask as black-on-white.
//! - [`overlay_image`]: target in black with the shadow as translucent red on top
//!   (like the paper's Figure 3, bottom row).
//! - [`difference_image`]: four-colour comparison of two masks.
//! - [`convergence_plot`]: energy per sample on a log10 axis, one panel per
//!   optimisation stage (like the paper's Figure 7), from a [`ConvergenceData`].
//! - [`histogram_plot`] and [`line_plot`]: linear-axis plots (the error budget's IoU
//!   histogram and IoU against each tolerance).
//! - [`side_by_side`]: stitches pictures into a strip.
//! - [`draw_text`] / [`text_width`]: labels with the embedded 5x7 bitmap font, so
//!   no font file or font crate is needed.
//!
//! Nothing here touches the filesystem.

use image::{GrayImage, Luma, Rgb, RgbImage};

mod chart;
mod convergence;
mod draw;

pub use chart::*;
pub use convergence::*;
pub use draw::*;

/// Background colour of every picture.
pub const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
/// Colour of the target in [`overlay_image`] and of "both" in [`difference_image`].
pub const BLACK: Rgb<u8> = Rgb([0, 0, 0]);
/// Shadow colour in [`overlay_image`], "only a" in [`difference_image`] and the
/// total-energy curve in [`convergence_plot`].
pub const RED: Rgb<u8> = Rgb([255, 0, 0]);
/// "Only b" in [`difference_image`].
pub const BLUE: Rgb<u8> = Rgb([0, 0, 255]);
/// Opacity of the shadow in [`overlay_image`]: high enough that the shadow reads as
/// red, low enough that the target below it stays visible (red over black is a
/// dark red, red over white a pink).
pub const SHADOW_ALPHA: f64 = 0.55;

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

/// `over` composited onto `under` with opacity `alpha` (0 = invisible, 1 = opaque).
fn blend(under: Rgb<u8>, over: Rgb<u8>, alpha: f64) -> Rgb<u8> {
    let mix = |u: u8, o: u8| (f64::from(o) * alpha + f64::from(u) * (1.0 - alpha)).round() as u8;
    Rgb([
        mix(under[0], over[0]),
        mix(under[1], over[1]),
        mix(under[2], over[2]),
    ])
}

/// Target and shadow in one picture: white background, target black, shadow
/// translucent red on top, so that target only (black), shadow only (pink) and
/// overlap (dark red) are told apart at a glance.
pub fn overlay_image(
    width: usize,
    height: usize,
    target: &dyn Fn(usize, usize) -> bool,
    shadow: &dyn Fn(usize, usize) -> bool,
) -> RgbImage {
    RgbImage::from_fn(to_u32(width), to_u32(height), |x, y| {
        let (x, y) = (x as usize, y as usize);
        let base = if target(x, y) { BLACK } else { WHITE };
        if shadow(x, y) {
            blend(base, RED, SHADOW_ALPHA)
        } else {
            base
        }
    })
}

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

/// Pictures left to right, `gap` white pixels apart, top-aligned on a white
/// background as tall as the tallest. No pictures give a 0x0 picture.
pub fn side_by_side(images: &[&RgbImage], gap: u32) -> RgbImage {
    let width = images.iter().map(|i| i.width()).sum::<u32>()
        + gap * (images.len() as u32).saturating_sub(1);
    let height = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(width, height, WHITE);
    let mut x0 = 0;
    for img in images {
        for (x, y, p) in img.enumerate_pixels() {
            out.put_pixel(x0 + x, y, *p);
        }
        x0 += img.width() + gap;
    }
    out
}

#[cfg(test)]
mod tests;
