//! Draws `scenes/mickey/target.png`: the Mickey logo as three discs, in floor metres,
//! rasterised at pixel centres onto the 640 x 480 image that covers x in [-2, 2] m and
//! y in [-1.5, 1.5] m (image up = +y). Run: `cargo run --example mickey_target`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (w, h) = (640u32, 480u32);
    // (centre x, centre y, radius) in metres on the floor.
    let discs = [(0.0, -0.25, 0.75), (-0.78, 0.62, 0.5), (0.78, 0.62, 0.5)];
    let img = image::GrayImage::from_fn(w, h, |i, j| {
        let x = -2.0 + 4.0 * (i as f64 + 0.5) / w as f64;
        let y = 1.5 - 3.0 * (j as f64 + 0.5) / h as f64;
        let inside = discs
            .iter()
            .any(|&(cx, cy, r)| (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r);
        image::Luma([if inside { 0 } else { 255 }])
    });
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mickey/target.png");
    img.save(&out)?;
    println!("wrote {}", out.display());
    Ok(())
}
