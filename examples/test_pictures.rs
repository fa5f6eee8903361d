//! The held-out test pictures of `bsa new`: letters and digits of DejaVu Sans (the font
//! in `assets/fonts/`, emboldened by a dilation so that strokes are about as wide as a
//! wooden block's shadow), simple drawn shapes and silhouettes of the font's symbols,
//! 640 x 480, black on white, each with the objects it is to be made of, stated before
//! any solve.
//!
//! The sets are data: `tools/test-pictures/set-NN/manifest.json` lists each picture's
//! name, how it is drawn (`"glyph"` a character and `"dilate"` pixels, `"drawn"` the
//! name of a shape of [`DRAWN`], or `"parts"` a silhouette as a list of [`Part`]s), its objects as `bsa new --objects` takes them, and any
//! extra `bsa new` options; its `"about"` says when the set was drawn and how its
//! objects were stated. `scripts/new-suite.sh` reads the same manifests.
//!
//! Run: `cargo run --release --example test_pictures [-- SET [DIR]]` (SET the number
//! of a folder `tools/test-pictures/set-NN`, or `all`, default `all`; DIR default that
//! folder, only with one SET): reads the set's manifest and writes `DIR/<name>.png`.
//! The output depends only on the font file, the manifests and this code.

use std::error::Error;
use std::path::{Path, PathBuf};

use ab_glyph::{Font, FontRef, PxScale};
use serde::Deserialize;

const W: usize = 640;
const H: usize = 480;
/// The shape's bounding box fills at most this share of the frame's height and width.
const FILL_H: f64 = 0.7;
const FILL_W: f64 = 0.8;
/// Supersampling of the drawn shapes (per axis).
const SS: usize = 4;

/// One picture of a set's `manifest.json`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Picture {
    /// The file name without `.png`.
    name: String,
    /// A character of the font: itself, or `U+XXXX`.
    glyph: Option<String>,
    /// The glyph's dilation in pixels.
    #[serde(default)]
    dilate: usize,
    /// The name of a drawn shape of [`DRAWN`].
    drawn: Option<String>,
    /// A silhouette made of parts, drawn in order.
    parts: Option<Vec<Part>>,
    /// The objects, as `bsa new --objects` takes them.
    objects: String,
    /// Extra `bsa new` options.
    #[serde(default)]
    options: String,
}

/// A set's `manifest.json`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    set: u32,
    /// When and how the set was drawn, and how its objects were stated.
    #[allow(dead_code)]
    about: String,
    pictures: Vec<Picture>,
}

/// A part of a silhouette, in pixels, centred on the frame with y up: each part adds
/// its points to the silhouette drawn so far, or with `cut` takes them away (a cup's
/// handle: a ring, then the body over it).
#[derive(Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
enum Part {
    /// An ellipse: centre, semi-axes along x and y, turned by `turn` degrees.
    Ellipse {
        centre: [f64; 2],
        radii: [f64; 2],
        #[serde(default)]
        turn: f64,
    },
    /// A polyline of `width` with round joins and ends.
    Stroke { points: Vec<[f64; 2]>, width: f64 },
    /// A polygon (even-odd rule).
    Polygon { points: Vec<[f64; 2]> },
    /// The points of the part taken away.
    Cut(Box<Part>),
}

impl Part {
    /// Whether the part holds (x, y); for a `cut`, whether its own part does.
    fn holds(&self, x: f64, y: f64) -> bool {
        match self {
            Part::Ellipse {
                centre,
                radii,
                turn,
            } => {
                let (s, c) = turn.to_radians().sin_cos();
                let (dx, dy) = (x - centre[0], y - centre[1]);
                let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
                (u / radii[0]).powi(2) + (v / radii[1]).powi(2) <= 1.0
            }
            Part::Stroke { points, width } => {
                points.windows(2).any(|w| {
                    let ([ax, ay], [bx, by]) = (w[0], w[1]);
                    let (dx, dy) = (bx - ax, by - ay);
                    let len2 = (dx * dx + dy * dy).max(f64::MIN_POSITIVE);
                    let s = (((x - ax) * dx + (y - ay) * dy) / len2).clamp(0.0, 1.0);
                    (x - ax - s * dx).hypot(y - ay - s * dy) <= width / 2.0
                }) || (points.len() == 1
                    && (x - points[0][0]).hypot(y - points[0][1]) <= width / 2.0)
            }
            Part::Polygon { points } => {
                let mut inside = false;
                for k in 0..points.len() {
                    let (a, b) = (points[k], points[(k + 1) % points.len()]);
                    if (a[1] > y) != (b[1] > y)
                        && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
                    {
                        inside = !inside;
                    }
                }
                inside
            }
            Part::Cut(p) => p.holds(x, y),
        }
    }
}

/// Whether the silhouette of `parts` holds (x, y).
fn in_parts(parts: &[Part], x: f64, y: f64) -> bool {
    parts.iter().fold(false, |inside, p| match p {
        Part::Cut(_) => inside && !p.holds(x, y),
        _ => inside || p.holds(x, y),
    })
}

/// The drawn shapes a manifest names: point-sets drawn by supersampling, true inside,
/// in coordinates centred on the frame with y up (pixels).
type ShapeFn = fn(f64, f64) -> bool;

const DRAWN: &[(&str, ShapeFn)] = &[
    ("arrow", arrow),
    ("bars", bars),
    ("bridge", bridge),
    ("caterpillar", caterpillar),
    ("chevron", chevron),
    ("crescent", crescent),
    ("cross", cross),
    ("dice", dice),
    ("disc_arc", disc_arc),
    ("disc_cross", disc_cross),
    ("disc_ell", disc_ell),
    ("disc_ring", disc_ring),
    ("disc_spiral", disc_spiral),
    ("disc_square", disc_square),
    ("disc_triangle", disc_triangle),
    ("disc_v", disc_v),
    ("disc_wave", disc_wave),
    ("disc_zigzag", disc_zigzag),
    ("dots", dots),
    ("frame", frame),
    ("grapes", grapes),
    ("hexagon", hexagon),
    ("hexagon_ring", hexagon_ring),
    ("house", house),
    ("ladder", ladder),
    ("lights", lights),
    ("pyramid", pyramid),
    ("ring", ring),
    ("snowman", snowman),
    ("star", star),
    ("steps", steps),
    ("triangle", triangle),
    ("trio", trio),
    ("two_discs", two_discs),
    ("window", window),
    ("zigzag", zigzag),
];

fn ring(x: f64, y: f64) -> bool {
    let r = x.hypot(y);
    (100.0..=160.0).contains(&r)
}

fn arrow(x: f64, y: f64) -> bool {
    // A shaft 200 x 60 and a head 150 wide at its base, pointing right.
    let shaft = (-220.0..=20.0).contains(&x) && y.abs() <= 30.0;
    let head = (20.0..=170.0).contains(&x) && y.abs() <= 75.0 * (170.0 - x) / 150.0;
    shaft || head
}

fn crescent(x: f64, y: f64) -> bool {
    x.hypot(y) <= 160.0 && (x - 70.0).hypot(y - 30.0) > 130.0
}

fn cross(x: f64, y: f64) -> bool {
    (x.abs() <= 35.0 && y.abs() <= 160.0) || (y.abs() <= 35.0 && x.abs() <= 160.0)
}

/// A regular triangle pointing up, centred on the origin, whose sides are `r` from the
/// centre.
fn in_triangle(x: f64, y: f64, r: f64) -> bool {
    [-90.0f64, 30.0, 150.0].iter().all(|a| {
        let (s, c) = a.to_radians().sin_cos();
        x * c + y * s <= r
    })
}

fn triangle(x: f64, y: f64) -> bool {
    in_triangle(x, y + 30.0, 100.0) && !in_triangle(x, y + 30.0, 60.0)
}

fn frame(x: f64, y: f64) -> bool {
    let d = x.abs().max(y.abs());
    (110.0..=150.0).contains(&d)
}

fn star(x: f64, y: f64) -> bool {
    // Ten vertices, outer radius 175, inner 75, a point up; even-odd ray casting.
    let v: Vec<(f64, f64)> = (0..10)
        .map(|k| {
            let r = if k % 2 == 0 { 175.0 } else { 75.0 };
            let a = 90.0f64.to_radians() + k as f64 * 36.0f64.to_radians();
            (r * a.cos(), r * a.sin() - 15.0)
        })
        .collect();
    let mut inside = false;
    for k in 0..10 {
        let (a, b) = (v[k], v[(k + 1) % 10]);
        if (a.1 > y) != (b.1 > y) && x < a.0 + (y - a.1) * (b.0 - a.0) / (b.1 - a.1) {
            inside = !inside;
        }
    }
    inside
}

fn snowman(x: f64, y: f64) -> bool {
    x.hypot(y + 100.0) <= 90.0 || x.hypot(y - 40.0) <= 65.0 || x.hypot(y - 140.0) <= 45.0
}

fn chevron(x: f64, y: f64) -> bool {
    // A band 60 thick bent to a point down: |x| rises with y along each arm.
    let d = (y + 120.0 - 0.9 * x.abs()) / 0.9f64.hypot(1.0);
    x.abs() <= 170.0 && (0.0..=60.0).contains(&d)
}

fn hexagon(x: f64, y: f64) -> bool {
    // A hexagonal outline, flat top and bottom, 40 thick.
    let d = (0..6)
        .map(|k| {
            let a = (30.0 + 60.0 * k as f64).to_radians();
            x * a.cos() + y * a.sin()
        })
        .fold(f64::NEG_INFINITY, f64::max);
    (110.0..=150.0).contains(&d)
}

fn house(x: f64, y: f64) -> bool {
    // A filled square with a triangular roof.
    let body = x.abs() <= 110.0 && (-160.0..=30.0).contains(&y);
    let roof = y > 30.0 && y <= 30.0 + 130.0 * (1.0 - x.abs() / 150.0);
    body || roof
}

fn dots(x: f64, y: f64) -> bool {
    // Three discs of falling size along a slant.
    (x + 150.0).hypot(y + 60.0) <= 80.0
        || (x - 10.0).hypot(y - 20.0) <= 60.0
        || (x - 140.0).hypot(y - 90.0) <= 45.0
}

fn bars(x: f64, y: f64) -> bool {
    // A bar chart: three bars 50 wide, 120, 200 and 280 tall, on one baseline.
    [(-110.0, 120.0), (0.0, 200.0), (110.0, 280.0)]
        .iter()
        .any(|&(cx, h)| (x - cx).abs() <= 25.0 && (-140.0..=-140.0 + h).contains(&y))
}

fn grapes(x: f64, y: f64) -> bool {
    // Four discs in a diamond, the upper two larger, just apart.
    (x + 75.0).hypot(y - 60.0) <= 70.0
        || (x - 75.0).hypot(y - 60.0) <= 70.0
        || x.hypot(y + 45.0) <= 55.0
        || x.hypot(y + 150.0) <= 45.0
}

fn ladder(x: f64, y: f64) -> bool {
    // Two rails 40 wide and 340 tall, 180 apart, and three rungs 36 tall between them.
    let rails = [-90.0, 90.0]
        .iter()
        .any(|&cx: &f64| (x - cx).abs() <= 20.0 && y.abs() <= 170.0);
    let rungs = x.abs() <= 90.0
        && [-90.0, 0.0, 90.0]
            .iter()
            .any(|&cy: &f64| (y - cy).abs() <= 18.0);
    rails || rungs
}

fn lights(x: f64, y: f64) -> bool {
    // Three discs of falling size in a column, apart.
    x.hypot(y - 120.0) <= 55.0 || x.hypot(y) <= 50.0 || x.hypot(y + 115.0) <= 45.0
}

fn zigzag(x: f64, y: f64) -> bool {
    // Three strokes 44 wide through (-240, -100), (-80, 100), (80, -100), (240, 100).
    let pts = [
        (-240.0, -100.0),
        (-80.0, 100.0),
        (80.0, -100.0),
        (240.0, 100.0),
    ];
    pts.windows(2).any(|w| {
        let ((ax, ay), (bx, by)): ((f64, f64), (f64, f64)) = (w[0], w[1]);
        let (dx, dy) = (bx - ax, by - ay);
        let s = (((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        (x - ax - s * dx).hypot(y - ay - s * dy) <= 22.0
    })
}

fn two_discs(x: f64, y: f64) -> bool {
    // A large disc and a smaller one beside it, apart.
    (x + 70.0).hypot(y) <= 90.0 || (x - 110.0).hypot(y + 20.0) <= 60.0
}

fn steps(x: f64, y: f64) -> bool {
    // A staircase of three treads 40 thick, each 120 long, rising to the right, joined
    // by risers 40 wide.
    let tread = |x0: f64, y0: f64| (x0..=x0 + 120.0).contains(&x) && (y0..=y0 + 40.0).contains(&y);
    let riser = |x0: f64, y0: f64| (x0..=x0 + 40.0).contains(&x) && (y0..=y0 + 120.0).contains(&y);
    tread(-200.0, -140.0)
        || riser(-120.0, -140.0)
        || tread(-120.0, -60.0)
        || riser(-40.0, -60.0)
        || tread(-40.0, 20.0)
        || riser(40.0, 20.0)
        || tread(40.0, 100.0)
}

fn trio(x: f64, y: f64) -> bool {
    // Three discs in a row, the middle one largest, apart.
    (x + 150.0).hypot(y) <= 55.0 || x.hypot(y) <= 75.0 || (x - 150.0).hypot(y) <= 55.0
}

fn window(x: f64, y: f64) -> bool {
    // A square frame 220 wide with bars 36 wide, and a cross of two bars 36 wide
    // through its middle.
    let (ax, ay) = (x.abs(), y.abs());
    ax <= 110.0 && ay <= 110.0 && (ax >= 74.0 || ay >= 74.0 || ax <= 18.0 || ay <= 18.0)
}

fn caterpillar(x: f64, y: f64) -> bool {
    // Five discs of radius 34 along an arch, apart.
    (0..5).any(|k| {
        let a = std::f64::consts::PI * (0.15 + 0.175 * k as f64);
        let (cx, cy) = (-190.0 * a.cos(), 110.0 * a.sin() - 50.0);
        (x - cx).hypot(y - cy) <= 34.0
    })
}

fn pyramid(x: f64, y: f64) -> bool {
    // Six discs of radius 36 stacked three, two, one, apart.
    let rows = [(3, -90.0), (2, 0.0), (1, 90.0)];
    rows.iter().any(|&(n, cy)| {
        (0..n).any(|k| {
            let cx = (k as f64 - (n - 1) as f64 / 2.0) * 100.0;
            (x - cx).hypot(y - cy) <= 36.0
        })
    })
}

fn dice(x: f64, y: f64) -> bool {
    // The five of a die: four discs of radius 38 at the corners of a square and one in
    // its middle, apart.
    let spots = [
        (-110.0, -110.0),
        (110.0, -110.0),
        (0.0, 0.0),
        (-110.0, 110.0),
        (110.0, 110.0),
    ];
    spots.iter().any(|&(cx, cy)| (x - cx).hypot(y - cy) <= 38.0)
}

fn bridge(x: f64, y: f64) -> bool {
    // A deck 400 x 40 px on two pillars 40 x 200 px.
    let deck = x.abs() <= 200.0 && (60.0..=100.0).contains(&y);
    let pillar = (120.0..=160.0).contains(&x.abs()) && (-140.0..=60.0).contains(&y);
    deck || pillar
}

fn hexagon_ring(x: f64, y: f64) -> bool {
    // Six discs of radius 36 on a circle of radius 150, evenly spaced.
    (0..6).any(|k| {
        let a = k as f64 * std::f64::consts::PI / 3.0;
        (x - 150.0 * a.cos()).hypot(y - 150.0 * a.sin()) <= 36.0
    })
}

fn disc_arc(x: f64, y: f64) -> bool {
    // Five discs of radius 34 on an arc of radius 220 about a centre below the frame,
    // from 50 to 130 degrees.
    (0..5).any(|k| {
        let a = (50.0 + 20.0 * k as f64).to_radians();
        (x - 220.0 * a.cos()).hypot(y + 120.0 - 220.0 * a.sin()) <= 34.0
    })
}

fn disc_zigzag(x: f64, y: f64) -> bool {
    // Six discs of radius 30 on a zigzag across the frame, alternately 70 pixels above
    // and below its middle line.
    (0..6).any(|k| {
        let cx = -225.0 + 90.0 * k as f64;
        let cy = if k % 2 == 0 { -70.0 } else { 70.0 };
        (x - cx).hypot(y - cy) <= 30.0
    })
}

fn disc_cross(x: f64, y: f64) -> bool {
    // Five discs of radius 30 in a plus sign: one in the middle and one 100 pixels from it
    // on each side, above and below.
    [
        (0.0, 0.0),
        (-100.0, 0.0),
        (100.0, 0.0),
        (0.0, -100.0),
        (0.0, 100.0),
    ]
    .iter()
    .any(|&(cx, cy)| (x - cx).hypot(y - cy) <= 30.0)
}

fn disc_ell(x: f64, y: f64) -> bool {
    // Six discs of radius 28 in an L (y up): four down a column 62 pixels apart, two
    // more to the right of the lowest.
    let centres = [
        (-60.0, 130.0),
        (-60.0, 68.0),
        (-60.0, 6.0),
        (-60.0, -56.0),
        (2.0, -56.0),
        (64.0, -56.0),
    ];
    centres
        .iter()
        .any(|&(cx, cy)| (x - cx).hypot(y - cy) <= 28.0)
}

fn disc_spiral(x: f64, y: f64) -> bool {
    // Seven discs of radius 28 on a spiral about the centre: the k-th at 40 + 25 k
    // pixels from it, turned 1.1 k radians.
    (0..7).any(|k| {
        let (r, a) = (40.0 + 25.0 * k as f64, 1.1 * k as f64);
        (x - r * a.cos()).hypot(y - r * a.sin()) <= 28.0
    })
}

fn disc_wave(x: f64, y: f64) -> bool {
    // Seven discs of radius 30 on a wave, 65 pixels apart across, 70 pixels up and down
    // a sine of period 260 pixels.
    (0..7).any(|k| {
        let cx = 65.0 * (k as f64 - 3.0);
        let cy = 70.0 * (std::f64::consts::TAU * cx / 260.0).sin();
        (x - cx).hypot(y - cy) <= 30.0
    })
}

fn disc_ring(x: f64, y: f64) -> bool {
    // Eight discs of radius 30 on a circle of radius 140, an eighth of a turn apart.
    (0..8).any(|k| {
        let a = std::f64::consts::FRAC_PI_4 * k as f64;
        (x - 140.0 * a.cos()).hypot(y - 140.0 * a.sin()) <= 30.0
    })
}

fn disc_v(x: f64, y: f64) -> bool {
    // Seven discs of radius 30 on a V: one at its point, 130 pixels below the middle,
    // and three up each arm, 75 pixels apart across and 85 up.
    (0..7).any(|k| {
        let step = k as f64 - 3.0;
        let cx = 75.0 * step;
        let cy = -130.0 + 85.0 * step.abs();
        (x - cx).hypot(y - cy) <= 30.0
    })
}

fn disc_square(x: f64, y: f64) -> bool {
    // Eight discs of radius 30 on a square outline: one at each corner, 130 pixels from
    // its middle along both axes, and one halfway along each side.
    (0..9)
        .filter(|&k| k != 4)
        .map(|k| {
            (
                130.0 * (k % 3) as f64 - 130.0,
                130.0 * (k / 3) as f64 - 130.0,
            )
        })
        .any(|(cx, cy)| (x - cx).hypot(y - cy) <= 30.0)
}

fn disc_triangle(x: f64, y: f64) -> bool {
    // Six discs of radius 30 on a triangle: one at each corner, 150 pixels from its
    // middle, and one halfway along each side.
    let corner = |k: usize| {
        let a = (90.0 + 120.0 * k as f64).to_radians();
        (150.0 * a.cos(), 150.0 * a.sin())
    };
    (0..3)
        .flat_map(|k| {
            let (a, b) = (corner(k), corner((k + 1) % 3));
            [a, (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1))]
        })
        .any(|(cx, cy)| (x - cx).hypot(y - cy) <= 30.0)
}

/// Coverage of a glyph at `scale`, drawn with its top-left at `at` into a `W x H` grid.
fn draw_glyph(
    font: &FontRef,
    c: char,
    scale: f32,
    at: (f32, f32),
) -> Result<Vec<f32>, Box<dyn Error>> {
    let id = font.glyph_id(c);
    if id.0 == 0 {
        return Err(format!("the font has no glyph for {c:?}").into());
    }
    let glyph = id.with_scale_and_position(PxScale::from(scale), ab_glyph::point(at.0, at.1));
    let outline = font.outline_glyph(glyph).ok_or("glyph without outline")?;
    let b = outline.px_bounds();
    let mut cov = vec![0.0f32; W * H];
    outline.draw(|x, y, v| {
        let (px, py) = (b.min.x as i64 + x as i64, b.min.y as i64 + y as i64);
        if px >= 0 && py >= 0 && (px as usize) < W && (py as usize) < H {
            cov[py as usize * W + px as usize] = v;
        }
    });
    Ok(cov)
}

fn bounds(on: &[bool]) -> Option<(usize, usize, usize, usize)> {
    let (mut x0, mut y0, mut x1, mut y1) = (W, H, 0, 0);
    for (k, _) in on.iter().enumerate().filter(|(_, &b)| b) {
        let (x, y) = (k % W, k / W);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
    }
    (x1 > x0).then_some((x0, y0, x1, y1))
}

fn glyph(font: &FontRef, c: char, dilate: usize) -> Result<Vec<bool>, Box<dyn Error>> {
    // Measure at a trial size, then scale the ink box to the frame and centre it.
    let trial = 200.0f32;
    let at = (200.0, 300.0);
    let on: Vec<bool> = draw_glyph(font, c, trial, at)?
        .iter()
        .map(|&v| v >= 0.5)
        .collect();
    let (x0, y0, x1, y1) = bounds(&on).ok_or("empty glyph")?;
    let (bw, bh) = ((x1 - x0) as f64, (y1 - y0) as f64);
    let grow = 2.0 * dilate as f64;
    let f = ((FILL_H * H as f64 - grow) / bh).min((FILL_W * W as f64 - grow) / bw);
    let scale = trial * f as f32;
    // The ink box's centre moves with the scale about the pen position.
    let cx = at.0 as f64 + ((x0 + x1) as f64 / 2.0 - at.0 as f64) * f;
    let cy = at.1 as f64 + ((y0 + y1) as f64 / 2.0 - at.1 as f64) * f;
    let pen = (
        (at.0 as f64 + W as f64 / 2.0 - cx) as f32,
        (at.1 as f64 + H as f64 / 2.0 - cy) as f32,
    );
    let on: Vec<bool> = draw_glyph(font, c, scale, pen)?
        .iter()
        .map(|&v| v >= 0.5)
        .collect();
    Ok(dilated(&on, dilate))
}

/// Dilation by a disc of radius `r` pixels.
fn dilated(on: &[bool], r: usize) -> Vec<bool> {
    if r == 0 {
        return on.to_vec();
    }
    let ri = r as i64;
    let mut out = vec![false; W * H];
    for (k, _) in on.iter().enumerate().filter(|(_, &b)| b) {
        let (x, y) = ((k % W) as i64, (k / W) as i64);
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                let (px, py) = (x + dx, y + dy);
                if dx * dx + dy * dy <= ri * ri
                    && px >= 0
                    && py >= 0
                    && px < W as i64
                    && py < H as i64
                {
                    out[py as usize * W + px as usize] = true;
                }
            }
        }
    }
    out
}

fn drawn(f: impl Fn(f64, f64) -> bool) -> Vec<bool> {
    (0..W * H)
        .map(|k| {
            let (x, y) = ((k % W) as f64, (k / W) as f64);
            let mut n = 0;
            for j in 0..SS {
                for i in 0..SS {
                    let px = x + (i as f64 + 0.5) / SS as f64 - W as f64 / 2.0;
                    let py = H as f64 / 2.0 - (y + (j as f64 + 0.5) / SS as f64);
                    n += usize::from(f(px, py));
                }
            }
            2 * n >= SS * SS
        })
        .collect()
}

/// The folder of set `set`.
fn set_dir(set: u32) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tools/test-pictures/set-{set:02}"))
}

/// The character a manifest's `"glyph"` names.
fn parse_char(g: &str) -> Result<char, Box<dyn Error>> {
    if let Some(hex) = g.strip_prefix("U+") {
        let code = u32::from_str_radix(hex, 16)?;
        return char::from_u32(code).ok_or_else(|| format!("no character {g}").into());
    }
    let mut chars = g.chars();
    match (chars.next(), chars.next()) {
        (Some(c), None) => Ok(c),
        _ => Err(format!("glyph {g:?} is not one character or U+XXXX").into()),
    }
}

/// The picture's pixels, true for shadow.
fn draw(font: &FontRef, p: &Picture) -> Result<Vec<bool>, Box<dyn Error>> {
    match (&p.glyph, &p.drawn, &p.parts) {
        (Some(g), None, None) => glyph(font, parse_char(g)?, p.dilate),
        (None, None, Some(parts)) => Ok(drawn(|x, y| in_parts(parts, x, y))),
        (None, Some(d), None) => {
            let f = DRAWN
                .iter()
                .find(|(n, _)| n == d)
                .ok_or_else(|| format!("{}: no drawn shape {d:?}", p.name))?
                .1;
            Ok(drawn(f))
        }
        _ => Err(format!("{}: give one of \"glyph\", \"drawn\" and \"parts\"", p.name).into()),
    }
}

fn write_set(font: &FontRef, set: u32, dir: &Path) -> Result<(), Box<dyn Error>> {
    let path = set_dir(set).join("manifest.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let manifest: Manifest =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    if manifest.set != set {
        return Err(format!("{} says set {}", path.display(), manifest.set).into());
    }
    std::fs::create_dir_all(dir)?;
    for p in &manifest.pictures {
        let on = draw(font, p)?;
        let img = image::GrayImage::from_fn(W as u32, H as u32, |x, y| {
            image::Luma([if on[y as usize * W + x as usize] {
                0
            } else {
                255
            }])
        });
        img.save(dir.join(format!("{}.png", p.name)))?;
        println!(
            "set {set} {}: {} shadow pixels ({}{})",
            p.name,
            on.iter().filter(|&&b| b).count(),
            p.objects,
            if p.options.is_empty() {
                String::new()
            } else {
                format!("; {}", p.options)
            }
        );
    }
    println!("wrote {}", dir.display());
    Ok(())
}

/// The sets there are: the folders `tools/test-pictures/set-NN` with a manifest.
fn all_sets() -> Result<Vec<u32>, Box<dyn Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tools/test-pictures");
    let mut sets = Vec::new();
    for entry in std::fs::read_dir(&root)? {
        let name = entry?.file_name().to_string_lossy().into_owned();
        if let Some(n) = name.strip_prefix("set-").and_then(|n| n.parse().ok()) {
            sets.push(n);
        }
    }
    sets.sort_unstable();
    Ok(sets)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let font = FontRef::try_from_slice(include_bytes!("../assets/fonts/DejaVuSans.ttf"))?;
    match args.first().map_or("all", String::as_str) {
        "all" => {
            if args.len() > 1 {
                return Err("DIR goes with one SET, not all".into());
            }
            for set in all_sets()? {
                write_set(&font, set, &set_dir(set))?;
            }
        }
        one => {
            let set: u32 = one
                .parse()
                .map_err(|_| format!("SET must be a number or all, got {one:?}"))?;
            let dir = args.get(1).map_or_else(|| set_dir(set), PathBuf::from);
            write_set(&font, set, &dir)?;
        }
    }
    Ok(())
}
