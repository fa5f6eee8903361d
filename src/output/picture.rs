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

// ---------------------------------------------------------------------------
// Pixel helpers. All take signed coordinates and silently clip, so callers can
// draw shapes that hang over an edge without checks of their own.
// ---------------------------------------------------------------------------

fn put(img: &mut RgbImage, x: i32, y: i32, c: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, c);
    }
}

fn put_blend(img: &mut RgbImage, x: i32, y: i32, c: Rgb<u8>, alpha: f64) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        let p = img.get_pixel_mut(x as u32, y as u32);
        *p = blend(*p, c, alpha);
    }
}

fn fill_rect(img: &mut RgbImage, x: i32, y: i32, w: i32, h: i32, c: Rgb<u8>) {
    for yy in y..y + h {
        for xx in x..x + w {
            put(img, xx, yy, c);
        }
    }
}

fn rect_outline(img: &mut RgbImage, x: i32, y: i32, w: i32, h: i32, c: Rgb<u8>) {
    fill_rect(img, x, y, w, 1, c);
    fill_rect(img, x, y + h - 1, w, 1, c);
    fill_rect(img, x, y, 1, h, c);
    fill_rect(img, x + w - 1, y, 1, h, c);
}

/// Line from (x0, y0) to (x1, y1) (Bresenham), each point stamped as a
/// `thickness` x `thickness` square.
fn line(
    img: &mut RgbImage,
    (x0, y0): (i32, i32),
    (x1, y1): (i32, i32),
    c: Rgb<u8>,
    thickness: i32,
) {
    let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
    let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
    let (mut x, mut y, mut err) = (x0, y0, dx + dy);
    let off = (thickness - 1) / 2;
    loop {
        fill_rect(img, x - off, y - off, thickness, thickness, c);
        if x == x1 && y == y1 {
            break;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

// ---------------------------------------------------------------------------
// Bitmap font: printable ASCII (32..=126), 5 columns x 7 rows above the baseline
// plus 2 descender rows (g, j, p, q, y, comma), bit 4 = leftmost column. Glyphs
// follow the classic HD44780 LCD character set, which is legible at 1x and
// scales cleanly by integer factors.
// ---------------------------------------------------------------------------

const GLYPH_W: u32 = 5;
/// Height of capitals and digits above the baseline, in unscaled pixels.
const CAP_H: u32 = 7;
/// Full cell height including the 2 rows below the baseline for descenders.
const CELL_H: u32 = 9;
/// Horizontal distance between glyph origins, in unscaled pixels (1 px spacing).
const ADVANCE: u32 = 6;

#[rustfmt::skip]
const FONT: [[u8; 9]; 95] = [
    [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000], // ' '
    [0b00100, 0b00100, 0b00100, 0b00100, 0b00000, 0b00000, 0b00100, 0b00000, 0b00000], // '!'
    [0b01010, 0b01010, 0b01010, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000], // '"'
    [0b01010, 0b01010, 0b11111, 0b01010, 0b11111, 0b01010, 0b01010, 0b00000, 0b00000], // '#'
    [0b00100, 0b01111, 0b10100, 0b01110, 0b00101, 0b11110, 0b00100, 0b00000, 0b00000], // '$'
    [0b11000, 0b11001, 0b00010, 0b00100, 0b01000, 0b10011, 0b00011, 0b00000, 0b00000], // '%'
    [0b01100, 0b10010, 0b10100, 0b01000, 0b10101, 0b10010, 0b01101, 0b00000, 0b00000], // '&'
    [0b01100, 0b00100, 0b01000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000], // '''
    [0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010, 0b00000, 0b00000], // '('
    [0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000, 0b00000, 0b00000], // ')'
    [0b00000, 0b00100, 0b10101, 0b01110, 0b10101, 0b00100, 0b00000, 0b00000, 0b00000], // '*'
    [0b00000, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0b00000, 0b00000, 0b00000], // '+'
    [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100, 0b00100, 0b01000], // ','
    [0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000], // '-'
    [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100, 0b00000, 0b00000], // '.'
    [0b00000, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b00000, 0b00000, 0b00000], // '/'
    [0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110, 0b00000, 0b00000], // '0'
    [0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110, 0b00000, 0b00000], // '1'
    [0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111, 0b00000, 0b00000], // '2'
    [0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110, 0b00000, 0b00000], // '3'
    [0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010, 0b00000, 0b00000], // '4'
    [0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110, 0b00000, 0b00000], // '5'
    [0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110, 0b00000, 0b00000], // '6'
    [0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00000, 0b00000], // '7'
    [0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110, 0b00000, 0b00000], // '8'
    [0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100, 0b00000, 0b00000], // '9'
    [0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000, 0b00000, 0b00000], // ':'
    [0b00000, 0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00100, 0b01000], // ';'
    [0b00010, 0b00100, 0b01000, 0b10000, 0b01000, 0b00100, 0b00010, 0b00000, 0b00000], // '<'
    [0b00000, 0b00000, 0b11111, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000, 0b00000], // '='
    [0b01000, 0b00100, 0b00010, 0b00001, 0b00010, 0b00100, 0b01000, 0b00000, 0b00000], // '>'
    [0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b00000, 0b00100, 0b00000, 0b00000], // '?'
    [0b01110, 0b10001, 0b00001, 0b01101, 0b10101, 0b10101, 0b01110, 0b00000, 0b00000], // '@'
    [0b01110, 0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b00000, 0b00000], // 'A'
    [0b11110, 0b10001, 0b10001, 0b11110, 0b10001, 0b10001, 0b11110, 0b00000, 0b00000], // 'B'
    [0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110, 0b00000, 0b00000], // 'C'
    [0b11100, 0b10010, 0b10001, 0b10001, 0b10001, 0b10010, 0b11100, 0b00000, 0b00000], // 'D'
    [0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111, 0b00000, 0b00000], // 'E'
    [0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000, 0b00000, 0b00000], // 'F'
    [0b01110, 0b10001, 0b10000, 0b10111, 0b10001, 0b10001, 0b01111, 0b00000, 0b00000], // 'G'
    [0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001, 0b00000, 0b00000], // 'H'
    [0b01110, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110, 0b00000, 0b00000], // 'I'
    [0b00111, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100, 0b00000, 0b00000], // 'J'
    [0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001, 0b00000, 0b00000], // 'K'
    [0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111, 0b00000, 0b00000], // 'L'
    [0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001, 0b00000, 0b00000], // 'M'
    [0b10001, 0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001, 0b00000, 0b00000], // 'N'
    [0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110, 0b00000, 0b00000], // 'O'
    [0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000, 0b00000, 0b00000], // 'P'
    [0b01110, 0b10001, 0b10001, 0b10001, 0b10101, 0b10010, 0b01101, 0b00000, 0b00000], // 'Q'
    [0b11110, 0b10001, 0b10001, 0b11110, 0b10100, 0b10010, 0b10001, 0b00000, 0b00000], // 'R'
    [0b01111, 0b10000, 0b10000, 0b01110, 0b00001, 0b00001, 0b11110, 0b00000, 0b00000], // 'S'
    [0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00000, 0b00000], // 'T'
    [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110, 0b00000, 0b00000], // 'U'
    [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100, 0b00000, 0b00000], // 'V'
    [0b10001, 0b10001, 0b10001, 0b10101, 0b10101, 0b10101, 0b01010, 0b00000, 0b00000], // 'W'
    [0b10001, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b10001, 0b00000, 0b00000], // 'X'
    [0b10001, 0b10001, 0b10001, 0b01010, 0b00100, 0b00100, 0b00100, 0b00000, 0b00000], // 'Y'
    [0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b11111, 0b00000, 0b00000], // 'Z'
    [0b01110, 0b01000, 0b01000, 0b01000, 0b01000, 0b01000, 0b01110, 0b00000, 0b00000], // '['
    [0b00000, 0b10000, 0b01000, 0b00100, 0b00010, 0b00001, 0b00000, 0b00000, 0b00000], // '\'
    [0b01110, 0b00010, 0b00010, 0b00010, 0b00010, 0b00010, 0b01110, 0b00000, 0b00000], // ']'
    [0b00100, 0b01010, 0b10001, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000], // '^'
    [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000], // '_'
    [0b01000, 0b00100, 0b00010, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000], // '`'
    [0b00000, 0b00000, 0b01110, 0b00001, 0b01111, 0b10001, 0b01111, 0b00000, 0b00000], // 'a'
    [0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b11110, 0b00000, 0b00000], // 'b'
    [0b00000, 0b00000, 0b01110, 0b10000, 0b10000, 0b10001, 0b01110, 0b00000, 0b00000], // 'c'
    [0b00001, 0b00001, 0b01101, 0b10011, 0b10001, 0b10001, 0b01111, 0b00000, 0b00000], // 'd'
    [0b00000, 0b00000, 0b01110, 0b10001, 0b11111, 0b10000, 0b01110, 0b00000, 0b00000], // 'e'
    [0b00110, 0b01001, 0b01000, 0b11100, 0b01000, 0b01000, 0b01000, 0b00000, 0b00000], // 'f'
    [0b00000, 0b00000, 0b01111, 0b10001, 0b10001, 0b10011, 0b01101, 0b00001, 0b01110], // 'g'
    [0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001, 0b00000, 0b00000], // 'h'
    [0b00100, 0b00000, 0b01100, 0b00100, 0b00100, 0b00100, 0b01110, 0b00000, 0b00000], // 'i'
    [0b00010, 0b00000, 0b00110, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100], // 'j'
    [0b10000, 0b10000, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b00000, 0b00000], // 'k'
    [0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110, 0b00000, 0b00000], // 'l'
    [0b00000, 0b00000, 0b11010, 0b10101, 0b10101, 0b10001, 0b10001, 0b00000, 0b00000], // 'm'
    [0b00000, 0b00000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001, 0b00000, 0b00000], // 'n'
    [0b00000, 0b00000, 0b01110, 0b10001, 0b10001, 0b10001, 0b01110, 0b00000, 0b00000], // 'o'
    [0b00000, 0b00000, 0b10110, 0b11001, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000], // 'p'
    [0b00000, 0b00000, 0b01101, 0b10011, 0b10001, 0b10001, 0b01111, 0b00001, 0b00001], // 'q'
    [0b00000, 0b00000, 0b10110, 0b11001, 0b10000, 0b10000, 0b10000, 0b00000, 0b00000], // 'r'
    [0b00000, 0b00000, 0b01110, 0b10000, 0b01110, 0b00001, 0b11110, 0b00000, 0b00000], // 's'
    [0b01000, 0b01000, 0b11100, 0b01000, 0b01000, 0b01001, 0b00110, 0b00000, 0b00000], // 't'
    [0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b10011, 0b01101, 0b00000, 0b00000], // 'u'
    [0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100, 0b00000, 0b00000], // 'v'
    [0b00000, 0b00000, 0b10001, 0b10001, 0b10101, 0b10101, 0b01010, 0b00000, 0b00000], // 'w'
    [0b00000, 0b00000, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b00000, 0b00000], // 'x'
    [0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b10011, 0b01101, 0b00001, 0b01110], // 'y'
    [0b00000, 0b00000, 0b11111, 0b00010, 0b00100, 0b01000, 0b11111, 0b00000, 0b00000], // 'z'
    [0b00010, 0b00100, 0b00100, 0b01000, 0b00100, 0b00100, 0b00010, 0b00000, 0b00000], // '{'
    [0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00000, 0b00000], // '|'
    [0b01000, 0b00100, 0b00100, 0b00010, 0b00100, 0b00100, 0b01000, 0b00000, 0b00000], // '}'
    [0b00000, 0b00000, 0b01000, 0b10101, 0b00010, 0b00000, 0b00000, 0b00000, 0b00000], // '~'
];

/// Glyph rows for `c`; characters outside printable ASCII are drawn as '?' so
/// that a stray name still shows that something is there.
fn glyph(c: char) -> &'static [u8; 9] {
    let i = c as usize;
    if (32..=126).contains(&i) {
        &FONT[i - 32]
    } else {
        &FONT[usize::from(b'?') - 32]
    }
}

/// Width in pixels of `text` drawn by [`draw_text`] at `scale` (no trailing gap).
pub fn text_width(text: &str, scale: u32) -> u32 {
    let n = text.chars().count() as u32;
    (n * ADVANCE).saturating_sub(ADVANCE - GLYPH_W) * scale.max(1)
}

/// Height in pixels of a line of text at `scale`, descenders included.
pub fn text_height(scale: u32) -> u32 {
    CELL_H * scale
}

/// Draws one line of `text` with its top-left corner at (x, y), each font pixel
/// a `scale` x `scale` square. Whatever falls outside `img` is clipped.
pub fn draw_text(img: &mut RgbImage, x: i32, y: i32, text: &str, color: Rgb<u8>, scale: u32) {
    let s = scale.max(1) as i32;
    for (i, c) in text.chars().enumerate() {
        let gx0 = x + i as i32 * ADVANCE as i32 * s;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..GLYPH_W {
                if bits & (1 << (GLYPH_W - 1 - col)) != 0 {
                    fill_rect(img, gx0 + col as i32 * s, y + row as i32 * s, s, s, color);
                }
            }
        }
    }
}

/// Like [`draw_text`] but rotated a quarter turn anticlockwise (reading bottom to
/// top, as a y-axis label); (x, y) is the bottom-left corner of the rotated text.
fn draw_text_up(img: &mut RgbImage, x: i32, y: i32, text: &str, color: Rgb<u8>, scale: u32) {
    let s = scale.max(1) as i32;
    for (i, c) in text.chars().enumerate() {
        let along = i as i32 * ADVANCE as i32 * s;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..GLYPH_W as i32 {
                if bits & (1 << (GLYPH_W as i32 - 1 - col)) != 0 {
                    // Glyph x runs up the picture, glyph y runs right.
                    let px = x + row as i32 * s;
                    let py = y - along - (col + 1) * s;
                    fill_rect(img, px, py, s, s, color);
                }
            }
        }
    }
}

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
const TERM_COLORS: [Rgb<u8>; 8] = [
    Rgb([31, 119, 180]),  // blue
    Rgb([255, 127, 14]),  // orange
    Rgb([44, 160, 44]),   // green
    Rgb([148, 103, 189]), // purple
    Rgb([23, 190, 207]),  // cyan
    Rgb([140, 86, 75]),   // brown
    Rgb([188, 189, 34]),  // olive
    Rgb([127, 127, 127]), // grey
];
const TEXT: Rgb<u8> = Rgb([40, 40, 40]);
const GRID: Rgb<u8> = Rgb([226, 226, 226]);
const FRAME: Rgb<u8> = Rgb([110, 110, 110]);
/// Opacity of the per-sample dots: faint enough that thousands of them form a
/// density cloud behind the per-generation lines instead of a solid smear.
const DOT_ALPHA: f64 = 0.3;
/// The plot never spans more decades than this, so that one stray tiny value
/// (1e-300) does not squash everything else into a sliver.
const MAX_DECADES: i32 = 16;

fn term_color(term: usize) -> Rgb<u8> {
    TERM_COLORS[term % TERM_COLORS.len()]
}

/// log10 of a value that can be drawn on a log axis; zero, negative and
/// non-finite values are "missing".
fn log_value(v: f64) -> Option<f64> {
    (v.is_finite() && v > 0.0)
        .then(|| v.log10())
        .filter(|l| l.is_finite())
}

/// Decade range [lo, hi] (powers of ten) covering every drawable value in the
/// data, shared by all panels so that stages can be compared by eye.
fn decade_range(data: &ConvergenceData) -> (i32, i32) {
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
fn legend_terms(rows: &[&ConvergenceRow], n_terms: usize) -> Vec<usize> {
    (0..n_terms)
        .filter(|&t| {
            rows.iter()
                .any(|r| r.terms.get(t).and_then(|&v| log_value(v)).is_some())
        })
        .collect()
}

/// Smallest "nice" step (1, 2 or 5 times a power of ten) that is at least `min`.
fn nice_step(min: f64) -> usize {
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
struct Axes {
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

fn draw_panel(
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
fn linear_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
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

fn tick_label(v: f64, step: f64) -> String {
    let digits = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil().clamp(0.0, 6.0) as usize
    };
    format!("{v:.digits$}")
}

/// Linear axes in a `width` x `height` panel with a title and axis labels; returns the
/// picture and a mapping from data to pixels.
struct LinearAxes {
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

fn linear_frame(
    width: u32,
    height: u32,
    title: &str,
    x_label: &str,
    y_label: &str,
    x: (f64, f64),
    y: (f64, f64),
) -> (RgbImage, LinearAxes) {
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

/// Histogram of `counts` over equal bins from `lo` to `hi`, with an optional vertical
/// marker (e.g. the IoU threshold) in red.
#[allow(clippy::too_many_arguments)]
pub fn histogram_plot(
    title: &str,
    x_label: &str,
    lo: f64,
    hi: f64,
    counts: &[usize],
    marker: Option<f64>,
    width: u32,
    height: u32,
) -> RgbImage {
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let (mut img, ax) = linear_frame(
        width,
        height,
        title,
        x_label,
        "samples",
        (lo, hi),
        (0.0, top * 1.05),
    );
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
#[allow(clippy::too_many_arguments)]
pub fn line_plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    y: (f64, f64),
    marker: Option<f64>,
    width: u32,
    height: u32,
) -> RgbImage {
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
    let (mut img, ax) = linear_frame(width, height, title, x_label, y_label, x, y);
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
    let sc = (width.min(height * 4 / 3) / 230).clamp(1, 4);
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

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(cx: f64, cy: f64, r: f64) -> impl Fn(usize, usize) -> bool {
        move |x, y| (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= r * r
    }

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

    /// Tiny deterministic generator for synthetic demo data (no rand crate needed).
    struct Lcg(u64);
    impl Lcg {
        fn uniform(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Writes sample pictures to the temp directory for a person to look at:
    /// `cargo test picture -- --ignored`.
    #[test]
    #[ignore]
    fn demo_pictures_to_tmp() {
        let dir = std::env::temp_dir().join("picture_demo");
        std::fs::create_dir_all(&dir).unwrap();
        let (w, h) = (160, 120);
        let target = |x: usize, y: usize| circle(70.0, 60.0, 40.0)(x, y) || (y > 95 && x > 20);
        let shadow = circle(90.0, 55.0, 38.0);
        let mask = mask_image(w, h, &shadow);
        mask.save(dir.join("mask.png")).unwrap();
        let overlay = overlay_image(w, h, &target, &shadow);
        overlay.save(dir.join("overlay.png")).unwrap();
        let diff = difference_image(w, h, &target, &shadow);
        diff.save(dir.join("difference.png")).unwrap();
        let as_rgb = |m: &dyn Fn(usize, usize) -> bool| {
            RgbImage::from_fn(w as u32, h as u32, |x, y| {
                if m(x as usize, y as usize) {
                    BLACK
                } else {
                    WHITE
                }
            })
        };
        let (t, s) = (as_rgb(&target), as_rgb(&shadow));
        let mut strip = side_by_side(&[&t, &s, &overlay, &diff], 8);
        draw_text(&mut strip, 2, 2, "target", RED, 1);
        strip.save(dir.join("strip.png")).unwrap();

        let mut font = RgbImage::from_pixel(620, 110, WHITE);
        draw_text(
            &mut font,
            4,
            4,
            " !\"#$%&'()*+,-./0123456789:;<=>?@",
            BLACK,
            2,
        );
        draw_text(
            &mut font,
            4,
            26,
            "ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_`",
            BLACK,
            2,
        );
        draw_text(&mut font, 4, 48, "abcdefghijklmnopqrstuvwxyz{|}~", BLACK, 2);
        draw_text(
            &mut font,
            4,
            74,
            "energy (log10) 1e-2 1e0 1e+2 silhouette_term: 3/4",
            BLACK,
            1,
        );
        draw_text_up(&mut font, 600, 100, "up text", BLUE, 1);
        font.save(dir.join("font.png")).unwrap();

        // Two stages of ~5,000 samples: 6 terms decaying at different rates with
        // multiplicative noise; one term zero throughout stage 0, another zero in
        // stage 1, and a few non-finite totals.
        let mut rng = Lcg(7);
        let names = [
            "silhouette",
            "coverage",
            "smoothness",
            "collision",
            "speed",
            "ground",
        ];
        let mut rows = Vec::new();
        for stage in 0..2 {
            let pop = 24;
            for it in 0..(5000 / pop) {
                let p = it as f64 / (5000 / pop) as f64;
                for _ in 0..pop {
                    let mut noise = || 10f64.powf(1.2 * (rng.uniform() - 0.3));
                    let mut terms = vec![
                        200.0 * (-6.0 * p).exp() * noise(),
                        30.0 * (-3.0 * p).exp() * noise(),
                        0.5 * noise(),
                        if stage == 0 {
                            0.0
                        } else {
                            0.05 * (-4.0 * p).exp() * noise()
                        },
                        if stage == 1 {
                            0.0
                        } else {
                            2.0 * (1.0 - p) * noise()
                        },
                        0.001 * noise(),
                    ];
                    if stage == 1 {
                        terms[0] *= 0.01;
                        terms[1] *= 0.05;
                    }
                    let mut r = row(stage, it, &terms);
                    if rng.uniform() < 0.001 {
                        r.total = f64::NAN;
                    }
                    rows.push(r);
                }
            }
        }
        let data = ConvergenceData {
            stage_names: vec!["stage 1: coarse".into(), "stage 2: fine".into()],
            term_names: names.iter().map(|s| s.to_string()).collect(),
            rows,
        };
        convergence_plot(&data, 600, 450)
            .save(dir.join("convergence.png"))
            .unwrap();
        convergence_plot(&data, 360, 260)
            .save(dir.join("convergence_small.png"))
            .unwrap();

        // Three long stages (20,000 samples, population 16), three terms.
        let mut rows = Vec::new();
        for stage in 0..3 {
            for i in 0..20_000 {
                let p = i as f64 / 20_000.0;
                let scale = 10f64.powi(-2 * stage as i32);
                let mut noise = || 10f64.powf(0.8 * (rng.uniform() - 0.2));
                let terms = [
                    50.0 * scale * (-5.0 * p).exp() * noise(),
                    if stage == 2 {
                        0.0
                    } else {
                        3.0 * scale * noise()
                    },
                    1e-4 * noise(),
                ];
                rows.push(row(stage, i / 16, &terms));
            }
        }
        let data = ConvergenceData {
            stage_names: vec!["s1".into(), "s2".into(), "s3 long name".into()],
            term_names: vec!["image".into(), "drag".into(), "tiny".into()],
            rows,
        };
        convergence_plot(&data, 500, 380)
            .save(dir.join("convergence_3stages.png"))
            .unwrap();
    }
}
