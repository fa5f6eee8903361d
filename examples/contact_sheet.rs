//! A contact sheet: PNG pictures tiled in a grid, each scaled to a common width.
//!
//! Run: `cargo run --release --example contact_sheet -- OUT.png COLUMNS WIDTH IN.png...`
//! (`scripts/new-suite.sh` makes `docs/images/new-suite.png` of the overlays with it).

use std::error::Error;

use image::{imageops, RgbaImage};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        return Err("usage: contact_sheet OUT.png COLUMNS WIDTH IN.png...".into());
    }
    let cols: usize = args[1].parse()?;
    let width: u32 = args[2].parse()?;
    let tiles: Vec<RgbaImage> = args[3..]
        .iter()
        .map(|p| -> Result<RgbaImage, Box<dyn Error>> {
            let img = image::open(p).map_err(|e| format!("{p}: {e}"))?.to_rgba8();
            let h = (img.height() as f64 * width as f64 / img.width() as f64).round() as u32;
            Ok(imageops::resize(
                &img,
                width,
                h,
                imageops::FilterType::Triangle,
            ))
        })
        .collect::<Result<_, _>>()?;
    let cols = cols.max(1).min(tiles.len());
    let rows = tiles.len().div_ceil(cols);
    let cell_h = tiles.iter().map(|t| t.height()).max().unwrap_or(1);
    let gap = 8;
    let mut sheet = RgbaImage::from_pixel(
        cols as u32 * (width + gap) + gap,
        rows as u32 * (cell_h + gap) + gap,
        image::Rgba([255, 255, 255, 255]),
    );
    for (k, t) in tiles.iter().enumerate() {
        let (c, r) = ((k % cols) as u32, (k / cols) as u32);
        imageops::overlay(
            &mut sheet,
            t,
            (gap + c * (width + gap)) as i64,
            (gap + r * (cell_h + gap)) as i64,
        );
    }
    sheet.save(&args[0])?;
    println!("wrote {} ({} pictures)", args[0], tiles.len());
    Ok(())
}
