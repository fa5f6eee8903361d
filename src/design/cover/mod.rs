//! Where each object's shadow goes: a greedy cover of the picture by the objects'
//! magnified top views ([`Cover`]).
//!
//! Largest object first, each object takes the placement (pose, roll, centre, angle,
//! magnification) whose shadow gains the most: +1 per target pixel not yet covered,
//! -1 per background pixel not yet covered (the solver's XOR term, so a shadow that
//! spills is worth less than one that fits), 0 on pixels already covered. Candidate
//! centres are the ridge of the distance transform of the target left uncovered (the
//! centre lines of the strokes still open), angles the local direction of the
//! picture there (so elongated objects go along strokes) and every 30 degrees,
//! magnifications a geometric range between the lowest and highest flight the stage
//! allows. The best few are refined by a pattern search over all their parameters.
//!
//! Two shadows that overlap (or come within [`NEAR_M`] of each other at their
//! height) belong to bodies that would meet at `t` at one height, so a placement that
//! touches an earlier one must fly at a height at least [`separation`] apart from it.

use glam::DVec2;

use super::picture::Picture;
use super::pose::{Family, Outline, Pose};

mod rounds;

/// Sample points per outline in the coarse search and in the refinement.
const COARSE_SAMPLES: usize = 120;
const FINE_SAMPLES: usize = 500;
/// Placements kept from the coarse search for refinement.
const KEEP: usize = 6;
/// The radius (m) of the least ball `auto:sphere` adds.
pub const LEAST_BALL_M: f64 = 0.005;
/// Shadows closer than this (m, at the body's height) count as touching.
pub const NEAR_M: f64 = 0.01;

/// The vertical room two bodies whose shadows touch need between their centres at `t`
/// (m): their half heights, plus as much again, plus a centimetre. The margin leaves
/// room for the last part of the flight, when the two close in from the side at
/// heights still closing in (on THE THINKER's pieces, half the margin costs 0.02 to
/// 0.04 of final IoU: more flights meet and [`super::separate`] must move them).
pub fn separation(e1: f64, e2: f64) -> f64 {
    2.0 * (e1 + e2) + 0.01
}

/// The picture's scale and the flight heights allowed.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Metres per pixel on the receiver.
    pub metres_per_px: f64,
    /// Height of the light above the receiver (m).
    pub light_height: f64,
    /// Lowest and highest magnification (heights between a tenth of the light's and
    /// the ceiling).
    pub m_lo: f64,
    pub m_hi: f64,
}

impl Frame {
    /// The frame of a picture at `metres_per_px` under a light `light_height` above
    /// it, whose highest flight reaches `ceiling` times the light's height (less than 1).
    pub fn new(metres_per_px: f64, light_height: f64, ceiling: f64) -> Frame {
        Frame {
            metres_per_px,
            light_height,
            m_lo: 1.0 / (1.0 - 0.1),
            m_hi: 1.0 / (1.0 - ceiling.clamp(0.2, 0.95)),
        }
    }

    /// Height above the receiver (m) at which a body's shadow is magnified `m` times.
    pub fn height(&self, m: f64) -> f64 {
        self.light_height * (1.0 - 1.0 / m)
    }

    /// The magnification at height `z`.
    pub fn magnification(&self, z: f64) -> f64 {
        self.light_height / (self.light_height - z)
    }
}

/// Where one object's shadow goes.
#[derive(Clone, Debug)]
pub struct Placement {
    /// Index of the object (in the order given to [`Cover`]).
    pub object: usize,
    /// Index of its pose family and the roll within it.
    pub family: usize,
    pub alpha: f64,
    /// Centre of the shadow (pixels).
    pub centre: DVec2,
    /// Direction of the outline's x axis on the picture (rad, counter-clockwise, image up).
    pub theta: f64,
    /// Magnification.
    pub m: f64,
    /// What it gained (pixels: new target minus new background).
    pub gain: f64,
    /// Its shadow's area (pixels).
    pub area: f64,
}

/// The pixel of the outline point `d` (m) of a shadow centred on `c`, turned by
/// `theta`, magnified `m` times, at `metres_per_px`.
pub fn to_pixel(c: DVec2, theta: f64, scale: f64, d: DVec2) -> DVec2 {
    to_pixel_turned(c, theta.sin_cos(), scale, d)
}

/// [`to_pixel`] with the turn's sine and cosine `(s, co)` taken once for many points.
fn to_pixel_turned(c: DVec2, (s, co): (f64, f64), scale: f64, d: DVec2) -> DVec2 {
    c + scale * DVec2::new(d.x * co - d.y * s, -(d.x * s + d.y * co))
}

/// The outline point at pixel `p`, the shadow turned by the angle whose sine and
/// cosine are `(s, co)` (taken once for all the pixels of a drawing).
fn from_pixel(c: DVec2, (s, co): (f64, f64), scale: f64, p: DVec2) -> DVec2 {
    let q = (p - c) / scale;
    // Inverse of to_pixel: (qx, -qy) = R(theta) d.
    let (x, y) = (q.x, -q.y);
    DVec2::new(x * co + y * s, -x * s + y * co)
}

/// The state of the cover: what each pixel is worth and who is on it.
#[derive(Clone)]
pub struct Cover<'a> {
    picture: &'a Picture,
    frame: Frame,
    /// +1 target not yet covered, -1 background not yet covered, 0 covered (a byte a
    /// pixel, so that the map stays in cache while the coarse search scores).
    pub(super) value: Vec<i8>,
    /// Bit k: placement k's shadow is on (or near) this pixel.
    owners: Vec<u64>,
    /// Bit k: placement k's shadow is on this pixel (so that one placement can be lifted
    /// off without redrawing the others).
    covers: Vec<u64>,
    /// Height and half height of every placement so far.
    heights: Vec<(f64, f64)>,
    /// The pose family of every placement.
    families: Vec<Family>,
    pub placements: Vec<Placement>,
    /// The whole picture's distance transform and ridge, once ([`Cover::best_disc`]
    /// takes them for every ball).
    whole: std::cell::OnceCell<(Vec<f32>, Ridge)>,
}

/// Ridge pixels of a picture ([`Picture::ridge`]).
type Ridge = Vec<(usize, usize)>;

/// One candidate being scored.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    centre: DVec2,
    theta: f64,
    m: f64,
    alpha: f64,
}

impl<'a> Cover<'a> {
    /// The placement of object `object` at candidate `c` in pose family `family` (whose
    /// pose at `c`'s roll is `pose`), gaining `gain`.
    fn placement(
        &self,
        object: usize,
        family: usize,
        pose: &Pose,
        c: Candidate,
        gain: f64,
    ) -> Placement {
        let scale = c.m / self.frame.metres_per_px;
        Placement {
            object,
            family,
            alpha: c.alpha,
            centre: c.centre,
            theta: c.theta,
            m: c.m,
            gain,
            area: pose.outline.area() * scale * scale,
        }
    }

    pub fn new(picture: &'a Picture, frame: Frame) -> Cover<'a> {
        Cover {
            picture,
            frame,
            value: picture.on.iter().map(|&b| worth(b)).collect(),
            owners: vec![0; picture.on.len()],
            covers: vec![0; picture.on.len()],
            heights: Vec::new(),
            families: Vec::new(),
            placements: Vec::new(),
            whole: std::cell::OnceCell::new(),
        }
    }

    /// Target pixels.
    pub fn target(&self) -> usize {
        self.picture.count()
    }

    /// Target pixels not yet covered.
    pub fn open(&self) -> usize {
        self.value.iter().filter(|&&v| v > 0).count()
    }

    /// Pixels of the target or of a shadow: the union of the design's IoU.
    pub fn union(&self) -> usize {
        let covered_background = self
            .value
            .iter()
            .zip(&self.picture.on)
            .filter(|&(&v, &on)| v == 0 && !on)
            .count();
        self.picture.count() + covered_background
    }

    /// The uncovered target as a picture.
    fn open_picture(&self) -> Picture {
        Picture::new(
            self.picture.width,
            self.picture.height,
            self.value.iter().map(|&v| v > 0).collect(),
        )
    }

    /// Score of a shadow with these samples: the gain, or `None` if it touches an
    /// earlier shadow without the height separation.
    fn score(&self, samples: &[(DVec2, f64)], c: &Candidate, half_height: f64) -> Option<f64> {
        self.score_above(samples, None, c, c.theta.sin_cos(), half_height)
    }

    /// [`Cover::score`], given up (`None`) as soon as the gain cannot exceed `floor.1`
    /// any more, even if every sample left fell on uncovered target: `floor.0[i]` is the
    /// sum of the weights of the samples from `i` on ([`tails`]). The coarse search
    /// only keeps candidates above its sixth best, so most of them stop early, and
    /// those it keeps are scored exactly as [`Cover::score`] scores them.
    /// `turn` is the sine and cosine of `c.theta` (the coarse search takes them once for
    /// all its magnifications).
    fn score_above(
        &self,
        samples: &[(DVec2, f64)],
        floor: Option<(&[f64], f64)>,
        c: &Candidate,
        turn: (f64, f64),
        half_height: f64,
    ) -> Option<f64> {
        let (w, h) = (self.picture.width, self.picture.height);
        let scale = c.m / self.frame.metres_per_px;
        let px_area = scale * scale;
        let (mut gain, mut touch) = (0.0f64, 0u64);
        // Eight samples at a time, so that the floor's test costs little beside the sum.
        for (i, eight) in samples.chunks(8).enumerate() {
            if let Some((tail, floor)) = floor {
                if gain + tail[8 * i] * px_area < floor {
                    return None;
                }
            }
            for (d, a) in eight {
                let p = to_pixel_turned(c.centre, turn, scale, *d);
                let v = if p.x >= 0.0 && p.y >= 0.0 && p.x < w as f64 && p.y < h as f64 {
                    // SAFETY: 0 <= p.x < w and 0 <= p.y < h (so neither is NaN), so both
                    // truncate to indices of the picture, as `as usize` would, without
                    // its saturation.
                    let (x, y): (i64, i64) =
                        unsafe { (p.x.to_int_unchecked(), p.y.to_int_unchecked()) };
                    let k = y as usize * w + x as usize;
                    touch |= self.owners[k];
                    f64::from(self.value[k])
                } else {
                    -1.0
                };
                gain += v * a * px_area;
            }
        }
        let z = self.frame.height(c.m);
        while touch != 0 {
            let j = touch.trailing_zeros() as usize;
            touch &= touch - 1;
            let (zj, ej) = self.heights[j];
            if (z - zj).abs() < separation(half_height, ej) {
                return None;
            }
        }
        Some(gain)
    }

    /// Place object `object` (index for the record) with the pose families `families`:
    /// the best placement found, not yet committed.
    pub fn best(&self, object: usize, families: &[Family]) -> Option<Placement> {
        let open = self.open_picture();
        let source = if open.count() > 0 {
            &open
        } else {
            self.picture
        };
        let dist = source.distance();
        let mut ridge = source.ridge(&dist);
        thin(
            &mut ridge,
            &dist,
            source.width,
            (source.width.max(source.height) / 120).max(2),
        );
        let dirs: Vec<f64> = ridge
            .iter()
            .map(|&(x, y)| {
                let r = (2.5 * dist[y * source.width + x] as f64).max(6.0);
                self.picture.direction(x, y, r)
            })
            .collect();
        let scales: Vec<f64> = (0..10)
            .map(|k| self.frame.m_lo * (self.frame.m_hi / self.frame.m_lo).powf(k as f64 / 9.0))
            .collect();
        let mut kept: Vec<(f64, usize, Candidate)> = Vec::new();
        for (fi, fam) in families.iter().enumerate() {
            for alpha in fam.alphas() {
                let pose = fam.pose(alpha);
                let samples = pose.outline.samples(COARSE_SAMPLES);
                let tail = tails(&samples);
                for (k, &(x, y)) in ridge.iter().enumerate() {
                    let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let thetas: Vec<(f64, (f64, f64))> = if pose.outline.round() {
                        vec![(0.0, 0.0f64.sin_cos())]
                    } else {
                        let d = dirs[k];
                        let mut t = vec![d, d + 0.26, d - 0.26];
                        t.extend((0..6).map(|i| i as f64 * std::f64::consts::PI / 6.0));
                        t.into_iter().map(|a| (a, a.sin_cos())).collect()
                    };
                    for &m in &scales {
                        for &(theta, turn) in &thetas {
                            let c = Candidate {
                                centre,
                                theta,
                                m,
                                alpha,
                            };
                            let floor = (kept.len() == KEEP).then(|| {
                                let f = kept[KEEP - 1].0;
                                // Below the sixth best by more than rounding: `keep`
                                // would refuse it.
                                (tail.as_slice(), f - 1e-9 * f.abs().max(1.0))
                            });
                            if let Some(s) =
                                self.score_above(&samples, floor, &c, turn, pose.half_height)
                            {
                                keep(&mut kept, (s, fi, c));
                            }
                        }
                    }
                }
            }
        }
        let mut best: Option<(f64, usize, Candidate)> = None;
        for (_, fi, c) in kept {
            let (s, c) = self.refine(&families[fi], c);
            if best.as_ref().is_none_or(|b| s > b.0) {
                best = Some((s, fi, c));
            }
        }
        let (gain, family, c) = best?;
        let pose = families[family].pose(c.alpha);
        Some(self.placement(object, family, &pose, c, gain))
    }

    /// The sphere that gains most, for `auto:sphere`: centred on the ridge of the target
    /// (or of what is left of it), as large as the target allows there, flying at the
    /// magnification nearest 2 (half the light's height) that the height rule allows.
    /// Returns the placement and the sphere's radius (m, whole millimetres).
    pub fn best_disc(&self, object: usize) -> Option<(Placement, f64)> {
        let w = self.picture.width;
        let (full, ridge) = self.whole.get_or_init(|| {
            let full = self.picture.distance();
            let ridge = self.picture.ridge(&full);
            (full, ridge)
        });
        let open = self.open_picture();
        let mut cands = ridge.clone();
        cands.extend(open.ridge(&open.distance()));
        thin(
            &mut cands,
            full,
            w,
            (w.max(self.picture.height) / 120).max(2),
        );
        let mut prefs: Vec<f64> = (0..10)
            .map(|k| self.frame.m_lo * (self.frame.m_hi / self.frame.m_lo).powf(k as f64 / 9.0))
            .collect();
        prefs.sort_by(|a, b| (a / 2.0).ln().abs().total_cmp(&(b / 2.0).ln().abs()));
        let p = self.frame.metres_per_px;
        let mut best: Option<(f64, Candidate, f64)> = None;
        for (x, y) in cands {
            let r_px = full[y * w + x] as f64 + 0.5;
            if r_px < 3.0 {
                continue;
            }
            let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            for &m in &prefs {
                let r = (r_px * p / m * 1000.0).round() / 1000.0;
                if r < LEAST_BALL_M {
                    continue;
                }
                let samples = Outline::Disc { r }.samples(COARSE_SAMPLES);
                let c = Candidate {
                    centre,
                    theta: 0.0,
                    m,
                    alpha: 0.0,
                };
                if let Some(g) = self.score(&samples, &c, r) {
                    if best.as_ref().is_none_or(|b| g > b.0) {
                        best = Some((g, c, r));
                    }
                    break;
                }
            }
        }
        let (gain, c, r) = best?;
        let scale = c.m / p;
        Some((
            Placement {
                object,
                family: 0,
                alpha: 0.0,
                centre: c.centre,
                theta: 0.0,
                m: c.m,
                gain,
                area: Outline::Disc { r }.area() * scale * scale,
            },
            r,
        ))
    }

    /// Pattern search from `c` over centre, angle, magnification (and roll).
    fn refine(&self, fam: &Family, mut c: Candidate) -> (f64, Candidate) {
        let mut pose = fam.pose(c.alpha);
        let mut samples = pose.outline.samples(FINE_SAMPLES);
        let eval = |pose: &Pose, samples: &[(DVec2, f64)], c: &Candidate| -> f64 {
            if c.m < self.frame.m_lo || c.m > self.frame.m_hi {
                return f64::NEG_INFINITY;
            }
            self.score(samples, c, pose.half_height)
                .unwrap_or(f64::NEG_INFINITY)
        };
        let mut best = eval(&pose, &samples, &c);
        let round = pose.outline.round();
        let mut step = [4.0, 4.0, 0.12, 0.06, 0.2];
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..40 {
            let mut improved = false;
            for (p, s) in step.iter().enumerate() {
                if (p == 2 && round) || (p == 4 && !fam.rolls()) {
                    continue;
                }
                for sign in [-1.0, 1.0] {
                    let mut n = c;
                    match p {
                        0 => n.centre.x += sign * s,
                        1 => n.centre.y += sign * s,
                        2 => n.theta += sign * s,
                        3 => n.m *= (sign * s).exp(),
                        _ => n.alpha = (n.alpha + sign * s).clamp(0.0, std::f64::consts::FRAC_PI_2),
                    }
                    if p == 3 {
                        // Also grow or shrink from either end (on a plateau of the
                        // samples, length and centre only improve together).
                        let half = pose.outline.half_extents().x / self.frame.metres_per_px;
                        let shift = half * (n.m - c.m);
                        let dir = DVec2::new(c.theta.cos(), -c.theta.sin());
                        for end in [-1.0, 1.0] {
                            let mut g = n;
                            g.centre += end * shift * dir;
                            let v = eval(&pose, &samples, &g);
                            if v > best + 1e-9 {
                                best = v;
                                c = g;
                                improved = true;
                            }
                        }
                    }
                    let (np, ns);
                    let (pp, ss) = if p == 4 {
                        np = fam.pose(n.alpha);
                        ns = np.outline.samples(FINE_SAMPLES);
                        (&np, &ns[..])
                    } else {
                        (&pose, &samples[..])
                    };
                    let v = eval(pp, ss, &n);
                    if v > best + 1e-9 {
                        best = v;
                        c = n;
                        if p == 4 {
                            pose = pp.clone();
                            samples = ss.to_vec();
                        }
                        improved = true;
                    }
                }
            }
            // Moves of all parameters at once (random directions, scaled by the
            // steps): the shadow's length, width and centre often only improve
            // together.
            for _ in 0..16 {
                let mut r = [0.0f64; 5];
                for x in r.iter_mut() {
                    rng ^= rng << 13;
                    rng ^= rng >> 7;
                    rng ^= rng << 17;
                    *x = (rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                }
                let mut n = c;
                n.centre += DVec2::new(r[0] * step[0], r[1] * step[1]);
                if !round {
                    n.theta += r[2] * step[2];
                }
                n.m *= (r[3] * step[3]).exp();
                let rolled;
                let (pp, ss) = if fam.rolls() {
                    n.alpha = (n.alpha + r[4] * step[4]).clamp(0.0, std::f64::consts::FRAC_PI_2);
                    let q = fam.pose(n.alpha);
                    rolled = (q.outline.samples(FINE_SAMPLES), q);
                    (&rolled.1, &rolled.0[..])
                } else {
                    (&pose, &samples[..])
                };
                let v = eval(pp, ss, &n);
                if v > best + 1e-9 {
                    best = v;
                    c = n;
                    if fam.rolls() {
                        pose = pp.clone();
                        samples = ss.to_vec();
                    }
                    improved = true;
                }
            }
            if !improved {
                for s in step.iter_mut() {
                    *s *= 0.5;
                }
                if step[0] < 0.25 {
                    break;
                }
            }
        }
        (best, c)
    }

    /// Commit a placement: its pixels are covered, and it owns them and those near it.
    pub fn commit(&mut self, p: Placement, family: Family) {
        let pose = family.pose(p.alpha);
        self.draw(self.placements.len(), &p, &pose);
        self.heights
            .push((self.frame.height(p.m), pose.half_height));
        self.families.push(family);
        self.placements.push(p);
    }

    /// Redraw the value and owner maps from every placement but `skip`.
    fn redraw(&mut self, skip: Option<usize>) {
        self.redraw_but(&skip.into_iter().collect::<Vec<_>>());
    }

    /// Redraw the value and owner maps from every placement but those in `skip`.
    fn redraw_but(&mut self, skip: &[usize]) {
        self.value = self.picture.on.iter().map(|&b| worth(b)).collect();
        self.owners.iter_mut().for_each(|o| *o = 0);
        self.covers.iter_mut().for_each(|o| *o = 0);
        for k in 0..self.placements.len() {
            if !skip.contains(&k) {
                let p = self.placements[k].clone();
                let pose = self.families[k].pose(p.alpha);
                self.draw(k, &p, &pose);
            }
        }
    }

    /// Take placements `ks` out of the height rule (a placement looking for its place is
    /// no obstacle to itself); their heights are returned for [`Cover::put_back`].
    fn lift_heights(&mut self, ks: &[usize]) -> Vec<(usize, (f64, f64))> {
        ks.iter()
            .map(|&k| (k, std::mem::replace(&mut self.heights[k], (f64::NAN, 0.0))))
            .collect()
    }

    /// Put back heights that [`Cover::lift_heights`] took out.
    fn put_back(&mut self, lifted: Vec<(usize, (f64, f64))>) {
        for (k, h) in lifted {
            self.heights[k] = h;
        }
    }

    /// The pixels (x0..x1, y0..y1) a placement's shadow, or the ring near it, may reach;
    /// and that ring's offsets (outline units).
    fn reach(&self, p: &Placement, pose: &Pose) -> ((usize, usize, usize, usize), Vec<DVec2>) {
        let (w, h) = (self.picture.width, self.picture.height);
        let scale = p.m / self.frame.metres_per_px;
        let near = (NEAR_M * scale).ceil();
        let e = pose.outline.half_extents();
        let reach = scale * e.length() + near + 1.0;
        let (x0, x1) = (
            (p.centre.x - reach).floor().max(0.0) as usize,
            ((p.centre.x + reach).ceil() as usize).min(w),
        );
        let (y0, y1) = (
            (p.centre.y - reach).floor().max(0.0) as usize,
            ((p.centre.y + reach).ceil() as usize).min(h),
        );
        let rings: Vec<DVec2> = (0..8)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_4;
                DVec2::new(a.cos(), a.sin()) * (near / scale)
            })
            .collect();
        ((x0, x1, y0, y1), rings)
    }

    fn draw(&mut self, index: usize, p: &Placement, pose: &Pose) {
        let w = self.picture.width;
        let scale = p.m / self.frame.metres_per_px;
        let ((x0, x1, y0, y1), rings) = self.reach(p, pose);
        let bit = 1u64 << (index % 64);
        let turn = p.theta.sin_cos();
        for y in y0..y1 {
            for x in x0..x1 {
                let d = from_pixel(
                    p.centre,
                    turn,
                    scale,
                    DVec2::new(x as f64 + 0.5, y as f64 + 0.5),
                );
                let k = y * w + x;
                if pose.outline.contains(d) {
                    self.value[k] = 0;
                    self.owners[k] |= bit;
                    self.covers[k] |= bit;
                } else if rings.iter().any(|r| pose.outline.contains(d + *r)) {
                    self.owners[k] |= bit;
                }
            }
        }
    }

    /// Lift placement `index` (drawn as `p` in `pose`) off the maps: they become what
    /// [`Cover::redraw_but`] would draw without it.
    fn undraw(&mut self, index: usize, p: &Placement, pose: &Pose) {
        let w = self.picture.width;
        let ((x0, x1, y0, y1), _) = self.reach(p, pose);
        let bit = 1u64 << (index % 64);
        for y in y0..y1 {
            for x in x0..x1 {
                let k = y * w + x;
                self.owners[k] &= !bit;
                if self.covers[k] & bit != 0 {
                    self.covers[k] &= !bit;
                    if self.covers[k] == 0 {
                        self.value[k] = worth(self.picture.on[k]);
                    }
                }
            }
        }
    }

    /// [`Cover::draw`] or [`Cover::undraw`] placement `k` as it stands.
    fn show(&mut self, k: usize, on: bool) {
        let p = self.placements[k].clone();
        let pose = self.families[k].pose(p.alpha);
        if on {
            self.draw(k, &p, &pose);
        } else {
            self.undraw(k, &p, &pose);
        }
    }
}

/// What an uncovered pixel is worth: +1 on the target, -1 off it.
fn worth(on: bool) -> i8 {
    if on {
        1
    } else {
        -1
    }
}

/// `tails[i]`: the sum of the weights of `samples[i..]` (the last entry is 0).
fn tails(samples: &[(DVec2, f64)]) -> Vec<f64> {
    let mut out = vec![0.0; samples.len() + 1];
    for i in (0..samples.len()).rev() {
        out[i] = out[i + 1] + samples[i].1.abs();
    }
    out
}

/// Keep the best [`KEEP`] candidates, at most one per nearby centre.
fn keep(kept: &mut Vec<(f64, usize, Candidate)>, c: (f64, usize, Candidate)) {
    if kept.len() == KEEP && c.0 <= kept[KEEP - 1].0 {
        return;
    }
    if let Some(k) = kept
        .iter()
        .position(|k| k.1 == c.1 && k.2.centre.distance(c.2.centre) < 8.0)
    {
        if kept[k].0 >= c.0 {
            return;
        }
        kept.remove(k);
    }
    let at = kept.iter().position(|k| k.0 < c.0).unwrap_or(kept.len());
    kept.insert(at, c);
    kept.truncate(KEEP);
}

/// Keep one ridge pixel (the one farthest inside) per `cell` x `cell` block.
fn thin(ridge: &mut Vec<(usize, usize)>, dist: &[f32], width: usize, cell: usize) {
    let mut best: std::collections::HashMap<(usize, usize), (usize, usize)> = Default::default();
    for &(x, y) in ridge.iter() {
        let key = (x / cell, y / cell);
        let e = best.entry(key).or_insert((x, y));
        if dist[y * width + x] > dist[e.1 * width + e.0] {
            *e = (x, y);
        }
    }
    let mut out: Vec<(usize, usize)> = best.into_values().collect();
    out.sort_unstable();
    *ridge = out;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::pose::families;
    use crate::geometry::shape::Shape;
    use glam::DVec3;

    /// A picture of axis-aligned rectangles (x0, y0, x1, y1) in pixels.
    fn picture(w: usize, h: usize, rects: &[(usize, usize, usize, usize)]) -> Picture {
        let on = (0..w * h)
            .map(|k| {
                let (x, y) = (k % w, k / w);
                rects
                    .iter()
                    .any(|r| (r.0..r.2).contains(&x) && (r.1..r.3).contains(&y))
            })
            .collect();
        Picture::new(w, h, on)
    }

    fn block() -> Vec<Family> {
        families(&Shape::Cuboid {
            half_extents: DVec3::new(0.07, 0.035, 0.0175),
        })
    }

    #[test]
    fn a_block_goes_along_a_bar_at_the_magnification_of_its_length() {
        // A vertical bar 60 x 200 px at 2.5 mm per pixel under a light 6 m up: a
        // 0.14 m block covers its length at m = 200 * 0.0025 / 0.14 = 3.57.
        let pic = picture(320, 240, &[(130, 20, 190, 220)]);
        let cover = Cover::new(&pic, Frame::new(0.0025, 6.0, 0.8));
        let p = cover.best(0, &block()).unwrap();
        let along = (p.theta.rem_euclid(std::f64::consts::PI) - std::f64::consts::FRAC_PI_2).abs();
        assert!(along < 0.05, "theta {}", p.theta);
        // Within the sample quadrature's reach (a few pixels at each end).
        assert!((p.m - 3.57).abs() < 0.3, "m {}", p.m);
        // On the bar's centre line, both ends within the bar.
        let half = 0.07 * p.m / 0.0025;
        assert!((p.centre.x - 160.0).abs() < 2.0, "{}", p.centre);
        assert!(
            p.centre.y - half > 17.0 && p.centre.y + half < 223.0,
            "{}",
            p.centre
        );
        assert!(p.gain > 0.9 * 12000.0, "gain {}", p.gain);
    }

    /// The block's families that lie flat or stand (no pitch).
    fn flat_block() -> Vec<Family> {
        let mut f = block();
        f.retain(|f| !matches!(f, Family::BoxTilted { .. }));
        f
    }

    #[test]
    fn touching_shadows_fly_apart_in_height() {
        // A cross of two bars: two blocks, one per bar, their heights at least the
        // separation apart; and polishing keeps that. Flat blocks only: a pitched block
        // covers the first bar's length at its width better, and flies so much taller
        // that the second bar is left at a smaller magnification.
        let pic = picture(320, 240, &[(40, 100, 280, 140), (140, 10, 180, 230)]);
        let frame = Frame::new(0.0025, 6.0, 0.8);
        let mut cover = Cover::new(&pic, frame);
        for k in 0..2 {
            let fams = flat_block();
            let p = cover.best(k, &fams).unwrap();
            let f = fams[p.family].clone();
            cover.commit(p, f);
        }
        cover.polish(1);
        let [a, b] = [&cover.placements[0], &cover.placements[1]];
        let pose = |p: &Placement| flat_block()[p.family].pose(p.alpha);
        let need = separation(pose(a).half_height, pose(b).half_height);
        assert!((frame.height(a.m) - frame.height(b.m)).abs() >= need - 1e-9);
        // One bar each: their angles differ by a right angle.
        let d = (a.theta - b.theta).rem_euclid(std::f64::consts::PI);
        assert!(
            (d - std::f64::consts::FRAC_PI_2).abs() < 0.1,
            "{} {}",
            a.theta,
            b.theta
        );
        assert!(cover.open() < 2000, "{} target pixels left", cover.open());
    }

    /// Commit object `k` in the first of its pose `families` at `centre` (pixels),
    /// unturned, at magnification `m`, on a cover of 5 mm per pixel.
    fn commit_flat(cover: &mut Cover, k: usize, families: &[Family], centre: DVec2, m: f64) {
        let pose = families[0].pose(0.0);
        let scale = m / 0.005;
        let p = Placement {
            object: k,
            family: 0,
            alpha: 0.0,
            centre,
            theta: 0.0,
            m,
            gain: 0.0,
            area: pose.outline.area() * scale * scale,
        };
        cover.commit(p, families[0].clone());
    }

    #[test]
    fn objects_on_each_others_places_are_exchanged() {
        // A square of 100 px and a bar of 150 x 50 px at 5 mm per pixel; a block of
        // 0.3 x 0.1 x 0.05 m placed on the square and a cube of 0.1 m on the bar (as the
        // greedy pass leaves chess pieces of similar sizes when the largest takes the
        // place it covers most). Exchanged, the block lies along the bar and the cube
        // fills the square.
        let pic = picture(320, 240, &[(40, 70, 140, 170), (170, 95, 320, 145)]);
        let frame = Frame::new(0.005, 6.0, 0.8);
        let big = families(&Shape::Cuboid {
            half_extents: DVec3::new(0.15, 0.05, 0.025),
        });
        let cube = families(&Shape::Cuboid {
            half_extents: DVec3::splat(0.05),
        });
        let mut cover = Cover::new(&pic, frame);
        for (k, fams, centre, m) in [
            (0, &big, DVec2::new(90.0, 120.0), 1.7),
            (1, &cube, DVec2::new(245.0, 120.0), 2.5),
        ] {
            commit_flat(&mut cover, k, fams, centre, m);
        }
        let on_square = |p: &Placement| p.centre.x < 155.0;
        let before = cover.open();
        let made = cover.exchange(&[big.clone(), cube.clone()], &|_, _| false);
        assert_eq!(made, 1);
        assert!(!on_square(&cover.placements[0]) && on_square(&cover.placements[1]));
        // The objects keep their indices, and the cover gained.
        assert_eq!(
            (cover.placements[0].object, cover.placements[1].object),
            (0, 1)
        );
        assert!(
            cover.open() + 5000 < before,
            "{} open after, {before} before",
            cover.open()
        );
        // Objects of the same shape are never exchanged, and a second round finds
        // nothing more.
        assert_eq!(
            cover.exchange(&[big.clone(), cube.clone()], &|_, _| true),
            0
        );
        assert_eq!(cover.exchange(&[big, cube], &|_, _| false), 0);
    }

    #[test]
    fn a_cube_sharing_a_square_with_another_is_placed_anew_on_a_bare_one() {
        // Two squares of 100 px at 5 mm per pixel and two cubes of 0.1 m, both on the
        // left square at heights apart (as the greedy can leave two small blocks on a
        // medium block's part): the right square is bare. Identical objects are never
        // exchanged; placed anew, one of them takes the bare square.
        let pic = picture(320, 240, &[(20, 70, 120, 170), (200, 70, 300, 170)]);
        let frame = Frame::new(0.005, 6.0, 0.8);
        let cube = families(&Shape::Cuboid {
            half_extents: DVec3::splat(0.05),
        });
        let mut cover = Cover::new(&pic, frame);
        for (k, m) in [(0, 5.0), (1, 3.0)] {
            commit_flat(&mut cover, k, &cube, DVec2::new(70.0, 120.0), m);
        }
        let before = cover.open();
        assert!(before >= 10_000, "{before}");
        let made = cover.replace(&[cube.clone(), cube.clone()]);
        assert!(made >= 1, "{made}");
        let on_right = |p: &Placement| p.centre.x > 160.0;
        assert_eq!(
            cover.placements.iter().filter(|p| on_right(p)).count(),
            1,
            "{:?}",
            cover.placements
        );
        assert_eq!(
            (cover.placements[0].object, cover.placements[1].object),
            (0, 1)
        );
        assert!(
            cover.open() < 1_000,
            "{} open after, {before} before",
            cover.open()
        );
        // Each placement is then where it gains most: a second pass moves none.
        assert_eq!(cover.replace(&[cube.clone(), cube]), 0);
    }

    #[test]
    fn pixels_and_outline_coordinates_are_inverse() {
        let c = DVec2::new(100.0, 50.0);
        for theta in [0.0, 0.4, 2.0] {
            let d = DVec2::new(0.03, -0.01);
            let p = to_pixel(c, theta, 400.0, d);
            assert!(from_pixel(c, theta.sin_cos(), 400.0, p).distance(d) < 1e-12);
        }
        // Outline x at theta = 90 degrees points up the image (decreasing pixel y).
        let p = to_pixel(c, std::f64::consts::FRAC_PI_2, 100.0, DVec2::new(0.1, 0.0));
        assert!(p.distance(DVec2::new(100.0, 40.0)) < 1e-9);
    }
}
