//! Procedural wood textures, drawn here so that the glb needs no image file: maple for
//! the blocks (boxes), boxwood for the chess pieces (meshes). Each is a seamless tile of
//! [`WOOD_TILE_M`] by [`WOOD_TILE_M`] with the grain along the image's x (the meshes'
//! texture `u`): growth rings bent by a few low waves, a darker latewood band at the end of
//! each ring and fine fibres along the grain. Every wave has whole numbers of periods
//! across the tile, so the tile repeats without a seam, and the PNG bytes are the same on
//! every run.

use std::f64::consts::TAU;

/// Side of one texture tile on the object (m): texture coordinates are metres divided by
/// this.
pub const WOOD_TILE_M: f64 = 0.15;
/// Pixels per side of the tile (0.6 mm per pixel).
const TILE_PX: u32 = 256;

/// The two woods of the examples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Wood {
    /// Hard maple, the building blocks: pale with clear, widely spaced rings.
    Maple,
    /// Boxwood, the chess pieces: yellowish, dense, with faint close rings.
    Boxwood,
}

/// A wood's look: sRGB colours of earlywood and latewood, rings per tile, how strongly
/// the latewood shows, and how much the fibres vary the brightness.
struct Look {
    early: [f64; 3],
    late: [f64; 3],
    rings: f64,
    late_strength: f64,
    fibre: f64,
}

impl Wood {
    /// Name of the glTF material (and of its texture and image).
    pub(super) fn name(self) -> &'static str {
        match self {
            Wood::Maple => "maple",
            Wood::Boxwood => "boxwood",
        }
    }

    /// Roughness of the material: planed, unvarnished wood.
    pub(super) fn roughness(self) -> f32 {
        match self {
            Wood::Maple => 0.6,
            Wood::Boxwood => 0.45,
        }
    }

    fn look(self) -> Look {
        match self {
            Wood::Maple => Look {
                early: [226.0, 196.0, 150.0],
                late: [176.0, 128.0, 80.0],
                rings: 22.0,
                late_strength: 0.8,
                fibre: 0.06,
            },
            Wood::Boxwood => Look {
                early: [234.0, 208.0, 146.0],
                late: [206.0, 168.0, 100.0],
                rings: 34.0,
                late_strength: 0.45,
                fibre: 0.04,
            },
        }
    }

    /// The tile's colour at `(x, y)` in tiles (0..1 each; x along the grain).
    fn colour(self, x: f64, y: f64) -> [u8; 3] {
        let l = self.look();
        // Low, gentle waves bend the rings and vary their width; whole periods across
        // the tile keep it seamless.
        let wave = |a: f64, m: f64, n: f64, phase: f64| a * (TAU * (m * x + n * y) + phase).sin();
        let bend = wave(0.010, 1.0, 0.0, 0.3)
            + wave(0.006, 2.0, 1.0, 1.7)
            + wave(0.003, 3.0, -1.0, 4.1)
            + wave(0.012, 0.0, 2.0, 2.2)
            + wave(0.006, 0.0, 3.0, 0.9);
        let ring = (l.rings * (y + bend)).rem_euclid(1.0);
        let late = smoothstep(0.55, 0.85, ring) * (1.0 - smoothstep(0.93, 1.0, ring));
        // Fibres: thin streaks along the grain.
        let fibre = (TAU * (61.0 * y + 2.0 * x)).sin() * (TAU * (37.0 * y - x) + 0.7).sin();
        let shade = 1.0 + l.fibre * fibre;
        let mix = late * l.late_strength;
        std::array::from_fn(|c| {
            let v = (l.early[c] * (1.0 - mix) + l.late[c] * mix) * shade;
            v.round().clamp(0.0, 255.0) as u8
        })
    }

    /// The tile as PNG bytes.
    pub(super) fn png(self) -> Vec<u8> {
        let img = image::RgbImage::from_fn(TILE_PX, TILE_PX, |i, j| {
            let (x, y) = (
                (i as f64 + 0.5) / TILE_PX as f64,
                (j as f64 + 0.5) / TILE_PX as f64,
            );
            image::Rgb(self.colour(x, y))
        });
        let mut bytes = Vec::new();
        // Writing a PNG into memory fails only on an allocation failure.
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .expect("encoding a PNG in memory");
        bytes
    }
}

fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let s = ((x - a) / (b - a)).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tile repeats without a seam: the colour just across each edge matches the
    /// colour at the opposite edge as closely as neighbouring pixels inside do.
    #[test]
    fn wood_tiles_are_seamless_and_look_like_wood() {
        for wood in [Wood::Maple, Wood::Boxwood] {
            let d = |a: [u8; 3], b: [u8; 3]| {
                (0..3)
                    .map(|c| (a[c] as i32 - b[c] as i32).abs())
                    .max()
                    .unwrap()
            };
            let e = 1e-9;
            for k in 0..64 {
                let s = k as f64 / 64.0;
                assert!(
                    d(wood.colour(e, s), wood.colour(1.0 - e, s)) <= 1,
                    "{wood:?} x seam"
                );
                assert!(
                    d(wood.colour(s, e), wood.colour(s, 1.0 - e)) <= 1,
                    "{wood:?} y seam"
                );
            }
            // Rings: colour varies across the grain (y) far more than along it (x).
            let (mut across, mut along) = (0, 0);
            for i in 0..256 {
                let f = i as f64 / 256.0;
                across += d(wood.colour(0.3, f), wood.colour(0.3, f + 1.0 / 256.0));
                along += d(wood.colour(f, 0.3), wood.colour(f + 1.0 / 256.0, 0.3));
            }
            assert!(
                across > 2 * along,
                "{wood:?}: across {across}, along {along}"
            );
            // Wood colours: warm (red > green > blue).
            let c = wood.colour(0.5, 0.5);
            assert!(c[0] > c[1] && c[1] > c[2], "{wood:?}: {c:?}");
            let png = wood.png();
            assert_eq!(&png[1..4], b"PNG");
            assert_eq!(png, wood.png(), "the same bytes every time");
        }
    }
}
