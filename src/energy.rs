//! The paper's ten energy terms, computed from a shadow mask and the flight outcome.
//!
//! Main types: [`Term`] (the ten terms, in a fixed order), [`Weights`] (one stage's
//! weights), [`TargetData`] (everything about the target picture that never changes:
//! its mask, inner and outer boundary masks, moments) and [`image_terms`], which fills
//! the image terms of a raw energy vector from a shadow mask, through the exact integer
//! sums of [`ImageSums`] (which a held shadow keeps, so that a sample counts again only
//! the rows it drew in).
//!
//! Data flow: `evaluate` rasterizes the shadow at `t` into a [`Mask`], calls
//! [`image_terms`] for the moment, XOR and boundary terms, and adds the physics
//! (contact, regularization) and scene (hints, barrier) terms itself.
//!
//! Deviations from the printed paper, by its text's intent (see `docs/energies.md`):
//! `E_in` counts inner-boundary pixels the shadow fails to cover, `E_out` counts
//! outer-boundary pixels the shadow covers, and `E_XOR` counts pixels that differ.

use std::ops::Range;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::shadow::mask::{Mask, MomentSums, Moments};

/// Number of energy terms.
pub const TERM_COUNT: usize = 10;

/// The energy terms, in the order used by every array of term values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(usize)]
pub enum Term {
    /// |M0(shadow) - M0(target)|, pixels.
    D0 = 0,
    /// Distance between the centroids, pixels.
    D1,
    /// Euclidean distance between (mu20, mu11, mu02) vectors, pixels^2.
    D2,
    /// Pixels where shadow and target differ.
    Xor,
    /// Inner-boundary pixels of the target not covered by the shadow.
    Inner,
    /// Outer-boundary pixels of the target covered by the shadow.
    Outer,
    /// (t - t_sim) * n_contact, seconds.
    Contact,
    /// alpha * sum |v| + (1 - alpha) * sum |w| over launched occluders (alpha = 0.5).
    Reg,
    /// sum of w_h * |P(x_h) - p_h| over hints, pixels.
    Hint,
    /// sum of B(P(C_i)): distance (pixels) of projected centres of mass outside the
    /// circle of half the image height around the image centre.
    Barrier,
}

impl Term {
    pub const ALL: [Term; TERM_COUNT] = [
        Term::D0,
        Term::D1,
        Term::D2,
        Term::Xor,
        Term::Inner,
        Term::Outer,
        Term::Contact,
        Term::Reg,
        Term::Hint,
        Term::Barrier,
    ];

    /// The key used in scene files, CSV headers and JSON.
    pub fn key(self) -> &'static str {
        match self {
            Term::D0 => "d0",
            Term::D1 => "d1",
            Term::D2 => "d2",
            Term::Xor => "xor",
            Term::Inner => "inner",
            Term::Outer => "outer",
            Term::Contact => "contact",
            Term::Reg => "reg",
            Term::Hint => "hint",
            Term::Barrier => "barrier",
        }
    }

    /// A longer name for tables and plots.
    pub fn label(self) -> &'static str {
        match self {
            Term::D0 => "0th moment",
            Term::D1 => "1st moment",
            Term::D2 => "2nd moment",
            Term::Xor => "XOR",
            Term::Inner => "inner boundary",
            Term::Outer => "outer boundary",
            Term::Contact => "contact",
            Term::Reg => "regularization",
            Term::Hint => "hints",
            Term::Barrier => "barrier",
        }
    }

    /// The one name of a term for people: its file key and what it measures, as
    /// "d0 (0th moment)", so that the plots, tables and terminal read the same name the
    /// files use.
    pub fn display_name(self) -> String {
        if self.label().eq_ignore_ascii_case(self.key()) {
            self.key().to_string()
        } else {
            format!("{} ({})", self.key(), self.label())
        }
    }

    /// Parse a scene-file key; a few long aliases are accepted too.
    pub fn from_key(key: &str) -> Option<Term> {
        let t = match key {
            "d0" | "moment0" => Term::D0,
            "d1" | "moment1" => Term::D1,
            "d2" | "moment2" => Term::D2,
            "xor" => Term::Xor,
            "inner" => Term::Inner,
            "outer" => Term::Outer,
            "contact" => Term::Contact,
            "reg" | "regularization" => Term::Reg,
            "hint" | "hints" => Term::Hint,
            "barrier" => Term::Barrier,
            _ => return None,
        };
        Some(t)
    }
}

/// One stage's weights, indexed by [`Term`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Weights(pub [f64; TERM_COUNT]);

impl Weights {
    /// Each raw term times its weight, for reports: a term with weight 0 counts 0, since
    /// a skipped term may hold NaN from a diverged sample. (The optimizer's total is
    /// [`weighted_total`], which instead turns any non-finite sum into
    /// [`DIVERGED_ENERGY`] so that such a sample ranks last.)
    pub fn weigh(&self, raw: &[f64; TERM_COUNT]) -> [f64; TERM_COUNT] {
        let mut out = [0.0; TERM_COUNT];
        for ((o, r), w) in out.iter_mut().zip(raw).zip(&self.0) {
            *o = if *w == 0.0 { 0.0 } else { r * w };
        }
        out
    }

    pub fn get(&self, t: Term) -> f64 {
        self.0[t as usize]
    }

    /// Whether a term contributes at all (zero-weight terms are skipped in the hot loop).
    pub fn uses(&self, t: Term) -> bool {
        self.0[t as usize] != 0.0
    }

    /// Whether any of the moment terms (d0, d1, d2) has a weight.
    pub fn uses_moments(&self) -> bool {
        self.uses(Term::D0) || self.uses(Term::D1) || self.uses(Term::D2)
    }

    /// The weights of a stage whose scene file gives none: every pixel term in units of
    /// the target's area (`target_pixels`), so that a total of 1 is a shadow as wrong as
    /// the target is big, whatever the picture's size:
    /// - XOR 1 and barrier 1 per target area;
    /// - hints 0.3 per target area: a hint pulls a body by 0.3 of what a pixel of the
    ///   picture is worth, enough to draw a body whose shadow is hidden (the picture
    ///   does not change while it moves) and too little to outweigh the picture;
    /// - regularization 0.01 per target area and m/s (or rad/s): a tie-breaker;
    /// - contact 1e5 per target area and second: only used by the penalty mode
    ///   (`"contacts": "penalty"`); the default constraint mode ranks contacts first
    ///   whatever their weight.
    pub fn default_for(target_pixels: f64) -> Weights {
        let unit = 1.0 / target_pixels.max(1.0);
        let mut w = [0.0; TERM_COUNT];
        w[Term::Xor as usize] = unit;
        w[Term::Barrier as usize] = unit;
        w[Term::Hint as usize] = 0.3 * unit;
        w[Term::Reg as usize] = 0.01 * unit;
        w[Term::Contact as usize] = 1e5 * unit;
        Weights(w)
    }

    /// A weight vector with every term on (used by `bsa eval` to compute everything).
    pub fn all_ones() -> Weights {
        Weights([1.0; TERM_COUNT])
    }
}

/// The weighting of linear against angular speed in the regularization (the paper's alpha).
pub const REG_ALPHA: f64 = 0.5;

/// Side of the square structuring element for the boundary images (the paper's 5 x 5).
pub const BOUNDARY_KERNEL: usize = 5;

/// Everything about the target picture that the energies need, computed once per scene.
#[derive(Clone, Debug)]
pub struct TargetData {
    pub mask: Mask,
    /// Target minus its erosion: the band just inside the outline.
    pub inner: Mask,
    /// Dilation minus the target: the band just outside the outline.
    pub outer: Mask,
    pub moments: Moments,
    /// Shadow-free fallbacks: the image diagonal (pixels), used when a centroid is undefined.
    pub diagonal: f64,
    /// Image centre (pixels) and barrier radius (pixels): half the image height, as in
    /// the paper, or the distance from the centre to the farthest target pixel when the
    /// target reaches beyond that circle (a barrier must not push a shadow off the
    /// target's own corners).
    pub center: DVec2,
    pub barrier_radius: f64,
}

/// Distance (pixels) from `(cx, cy)` to the farthest corner of any set pixel of `mask`.
fn farthest_pixel(mask: &Mask, cx: f64, cy: f64) -> f64 {
    let mut far: f64 = 0.0;
    for y in 0..mask.height() {
        for x in 0..mask.width() {
            if mask.get(x, y) {
                let dx = (x as f64 + 0.5 - cx).abs() + 0.5;
                let dy = (y as f64 + 0.5 - cy).abs() + 0.5;
                far = far.max((dx * dx + dy * dy).sqrt());
            }
        }
    }
    far
}

impl TargetData {
    /// The target data of a picture drawn on a canvas of its own size.
    pub fn new(mask: &Mask) -> TargetData {
        TargetData::on_canvas(mask, 0)
    }

    /// The target data of `picture` on the solver's canvas, `margin` pixels larger on
    /// every side (see [`crate::evaluate::Problem`]): the masks and moments are the
    /// padded ones, in canvas pixels, so that shadow beyond the picture counts as shadow
    /// where the target has none. The barrier and hint geometry (`center`,
    /// `barrier_radius`, `diagonal`) stay in the picture's own pixels, where hints are
    /// projected.
    pub fn on_canvas(picture: &Mask, margin: usize) -> TargetData {
        let (w, h) = (picture.width() as f64, picture.height() as f64);
        let mask = picture.padded(margin);
        let inner = mask.and_not(&mask.erode(BOUNDARY_KERNEL));
        let outer = mask.dilate(BOUNDARY_KERNEL).and_not(&mask);
        TargetData {
            moments: mask.moments(),
            mask,
            inner,
            outer,
            diagonal: (w * w + h * h).sqrt(),
            center: DVec2::new(w / 2.0, h / 2.0),
            barrier_radius: (h / 2.0).max(farthest_pixel(picture, w / 2.0, h / 2.0)),
        }
    }

    /// The barrier B(x) of one projected point (pixels); `None` (no projection: the
    /// point is at or behind the light) costs ten image diagonals.
    pub fn barrier(&self, p: Option<DVec2>) -> f64 {
        match p {
            Some(p) if p.is_finite() => {
                let d = p.distance(self.center);
                if d < self.barrier_radius {
                    0.0
                } else {
                    d
                }
            }
            _ => 10.0 * self.diagonal,
        }
    }

    /// Distance (pixels) of a projected hint point from its target pixel, with the same
    /// fallback as [`TargetData::barrier`] when the point does not project.
    pub fn hint_distance(&self, p: Option<DVec2>, target: DVec2) -> f64 {
        match p {
            Some(p) if p.is_finite() => p.distance(target),
            _ => 10.0 * self.diagonal,
        }
    }
}

/// Pixel counts that [`image_terms`] found on its way, for [`iou_of`] to reuse.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    /// Shadow pixels, when the moments were computed.
    pub shadow: Option<u64>,
    /// Pixels where shadow and target differ, when the XOR term was computed.
    pub xor: Option<u64>,
}

/// Fill the image terms (d0, d1, d2, XOR, inner, outer) of `raw` from the shadow mask.
/// Terms whose weight is zero are skipped (left at 0) to save time; pass
/// [`Weights::all_ones`] to compute them all.
pub fn image_terms(
    target: &TargetData,
    shadow: &Mask,
    weights: &Weights,
    raw: &mut [f64; TERM_COUNT],
) -> Counts {
    let sums = ImageSums::of(target, shadow, 0..usize::MAX, weights, false);
    image_terms_of(target, &sums, weights, raw)
}

/// [`image_terms`] from the sums of a whole shadow.
pub fn image_terms_of(
    target: &TargetData,
    sums: &ImageSums,
    weights: &Weights,
    raw: &mut [f64; TERM_COUNT],
) -> Counts {
    if weights.uses_moments() {
        let m = Moments::from_sums(sums.moments);
        let tm = &target.moments;
        raw[Term::D0 as usize] = (m.count - tm.count).abs();
        match (m.centroid(), tm.centroid()) {
            (Some(a), Some(b)) => raw[Term::D1 as usize] = a.distance(b),
            _ => raw[Term::D1 as usize] = target.diagonal,
        }
        match (m.central_second(), tm.central_second()) {
            (Some(a), Some(b)) => {
                let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
                raw[Term::D2 as usize] = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            }
            (None, Some(b)) => {
                raw[Term::D2 as usize] = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt()
            }
            _ => raw[Term::D2 as usize] = 0.0,
        }
    }
    if let (true, Some(x)) = (weights.uses(Term::Xor), sums.xor) {
        raw[Term::Xor as usize] = x as f64;
    }
    if weights.uses(Term::Inner) {
        raw[Term::Inner as usize] = sums.inner as f64;
    }
    if weights.uses(Term::Outer) {
        raw[Term::Outer as usize] = sums.outer as f64;
    }
    Counts {
        shadow: sums.count,
        xor: sums.xor,
    }
}

/// The exact integer sums the image terms of a shadow are made of, over some of its rows:
/// its moments, its pixels, and its pixels counted against the target's masks. Sums of
/// disjoint rows add up to the sums of their union, so a held shadow's sums, with the
/// rows a sample drew over replaced ([`ImageSums::replaced`]), are the sample's own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImageSums {
    /// The moment sums (zero unless the weights use d0, d1 or d2).
    moments: MomentSums,
    /// The shadow's pixels and the pixels where it differs from the target, when counted.
    count: Option<u64>,
    xor: Option<u64>,
    /// Inner-band pixels the shadow leaves bare (zero unless the weights use the term).
    inner: u64,
    /// Outer-band pixels the shadow covers (zero unless the weights use the term).
    outer: u64,
}

impl ImageSums {
    /// The sums of `shadow` over `rows` that `weights` need, and with `iou` the pixel
    /// and XOR counts whatever the weights (the IoU takes them).
    pub fn of(
        target: &TargetData,
        shadow: &Mask,
        rows: Range<usize>,
        weights: &Weights,
        iou: bool,
    ) -> ImageSums {
        let moments = match weights.uses_moments() {
            true => shadow.moment_sums(rows.clone()),
            false => MomentSums::default(),
        };
        ImageSums {
            moments,
            count: match (weights.uses_moments(), iou) {
                (true, _) => Some(moments.0[0] as u64),
                (false, true) => Some(shadow.count_in(rows.clone())),
                (false, false) => None,
            },
            xor: (weights.uses(Term::Xor) || iou)
                .then(|| shadow.xor_count_in(&target.mask, rows.clone())),
            inner: match weights.uses(Term::Inner) {
                true => target.inner.and_not_count_in(shadow, rows.clone()),
                false => 0,
            },
            outer: match weights.uses(Term::Outer) {
                true => target.outer.and_count_in(shadow, rows),
                false => 0,
            },
        }
    }

    /// `self` with the sums `b` of some rows taken out and `c` put in their place (`b` a
    /// part of `self`; a count that either lacks is left out).
    pub fn replaced(&self, b: &ImageSums, c: &ImageSums) -> ImageSums {
        let swap = |a: Option<u64>, b: Option<u64>, c: Option<u64>| Some(a? - b? + c?);
        ImageSums {
            moments: self.moments.replaced(b.moments, c.moments),
            count: swap(self.count, b.count, c.count),
            xor: swap(self.xor, b.xor, c.xor),
            inner: self.inner - b.inner + c.inner,
            outer: self.outer - b.outer + c.outer,
        }
    }
}

/// [`iou`] of `shadow` and the target, bit for bit, with the counts [`image_terms`]
/// found: a sample whose terms counted the shadow and the XOR pays nothing more for
/// its IoU, and one that counted either pays one pass over the rows instead of two.
pub fn iou_of(target: &TargetData, shadow: &Mask, counts: Counts) -> f64 {
    let s = counts.shadow.unwrap_or_else(|| shadow.count());
    let x = counts.xor.unwrap_or_else(|| shadow.xor_count(&target.mask));
    // |S & T| = (|S| + |T| - |S ^ T|) / 2, exactly, in integers.
    let inter = (s + target.moments.count as u64 - x) / 2;
    let union = inter + x;
    if union == 0 {
        1.0
    } else {
        inter as f64 / union as f64
    }
}

/// Intersection over union of two masks (1 when both are empty).
pub fn iou(a: &Mask, b: &Mask) -> f64 {
    // The union is the intersection plus the pixels in exactly one: two vectorised
    // passes over the rows either mask uses, rather than a count of the whole of each.
    let inter = a.and_count(b) as f64;
    let union = inter + a.xor_count(b) as f64;
    if union == 0.0 {
        1.0
    } else {
        inter / union
    }
}

/// Weighted total of raw term values. A non-finite total (a diverged sample) becomes a
/// huge finite energy so that the optimizer ranks it last instead of failing.
pub fn weighted_total(raw: &[f64; TERM_COUNT], weights: &Weights) -> f64 {
    let total: f64 = raw.iter().zip(weights.0.iter()).map(|(r, w)| r * w).sum();
    if total.is_finite() {
        total
    } else {
        DIVERGED_ENERGY
    }
}

/// The energy given to a sample whose evaluation produced NaN or infinity.
pub const DIVERGED_ENERGY: f64 = 1e30;

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(w: usize, h: usize, cx: f64, cy: f64, r: f64) -> Mask {
        Mask::from_fn(w, h, |x, y| {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            dx * dx + dy * dy <= r * r
        })
    }

    fn terms(target: &Mask, shadow: &Mask) -> [f64; TERM_COUNT] {
        let td = TargetData::new(target);
        let mut raw = [0.0; TERM_COUNT];
        image_terms(&td, shadow, &Weights::all_ones(), &mut raw);
        raw
    }

    #[test]
    fn identical_masks_cost_nothing() {
        let t = disc(128, 96, 60.0, 40.0, 20.0);
        let raw = terms(&t, &t);
        for term in [
            Term::D0,
            Term::D1,
            Term::D2,
            Term::Xor,
            Term::Inner,
            Term::Outer,
        ] {
            assert_eq!(raw[term as usize], 0.0, "{term:?}");
        }
    }

    #[test]
    fn shifted_disc_moments_and_xor() {
        let t = disc(128, 96, 60.0, 40.0, 20.0);
        let s = disc(128, 96, 63.0, 44.0, 20.0);
        let raw = terms(&t, &s);
        // Same area (up to pixelisation at integer offsets: exactly the same pixel set shifted).
        assert_eq!(raw[Term::D0 as usize], 0.0);
        assert!(
            (raw[Term::D1 as usize] - 5.0).abs() < 1e-9,
            "{}",
            raw[Term::D1 as usize]
        );
        assert!(raw[Term::D2 as usize] < 1e-9);
        // XOR = 2 * (area - overlap); compare with a per-pixel count.
        let brute = (0..96)
            .flat_map(|y| (0..128).map(move |x| (x, y)))
            .filter(|&(x, y)| t.get(x, y) != s.get(x, y))
            .count();
        assert_eq!(raw[Term::Xor as usize], brute as f64);
    }

    #[test]
    fn boundary_terms_follow_the_texts_intent() {
        // A 20x20 square target in a 64x64 image. Inner band = outline pixels 2 deep
        // inside; outer band = 2 deep outside.
        let target = Mask::from_fn(64, 64, |x, y| {
            (20..40).contains(&x) && (20..40).contains(&y)
        });
        let td = TargetData::new(&target);
        assert_eq!(td.inner.count(), 20 * 20 - 16 * 16);
        assert_eq!(td.outer.count(), 24 * 24 - 20 * 20);
        // A shadow equal to the target: no inner pixel left uncovered, no outer pixel covered.
        let raw = terms(&target, &target);
        assert_eq!(raw[Term::Inner as usize], 0.0);
        assert_eq!(raw[Term::Outer as usize], 0.0);
        // An empty shadow leaves the whole inner band uncovered and covers nothing outside.
        let empty = Mask::new(64, 64);
        let raw = terms(&target, &empty);
        assert_eq!(raw[Term::Inner as usize], td.inner.count() as f64);
        assert_eq!(raw[Term::Outer as usize], 0.0);
        // A shadow one pixel larger on every side covers one ring of the outer band.
        let big = Mask::from_fn(64, 64, |x, y| {
            (19..41).contains(&x) && (19..41).contains(&y)
        });
        let raw = terms(&target, &big);
        assert_eq!(raw[Term::Inner as usize], 0.0);
        assert_eq!(raw[Term::Outer as usize], (22 * 22 - 20 * 20) as f64);
    }

    #[test]
    fn empty_shadow_gets_finite_fallbacks() {
        let t = disc(64, 48, 30.0, 20.0, 10.0);
        let raw = terms(&t, &Mask::new(64, 48));
        assert_eq!(raw[Term::D0 as usize], t.count() as f64);
        assert!((raw[Term::D1 as usize] - (64f64.hypot(48.0))).abs() < 1e-12);
        assert!(raw[Term::D2 as usize] > 0.0 && raw[Term::D2 as usize].is_finite());
    }

    #[test]
    fn barrier_and_hint_fallbacks() {
        let td = TargetData::new(&disc(640, 480, 320.0, 240.0, 50.0));
        assert_eq!(td.barrier(Some(DVec2::new(320.0, 240.0 + 239.0))), 0.0);
        assert!((td.barrier(Some(DVec2::new(320.0, 240.0 + 300.0))) - 300.0).abs() < 1e-12);
        assert_eq!(td.barrier(None), 8000.0);
        assert_eq!(
            td.hint_distance(Some(DVec2::new(3.0, 4.0)), DVec2::ZERO),
            5.0
        );
        assert_eq!(
            td.hint_distance(Some(DVec2::new(f64::NAN, 4.0)), DVec2::ZERO),
            8000.0
        );
    }

    #[test]
    fn weighted_total_never_returns_nan() {
        let mut raw = [1.0; TERM_COUNT];
        let w = Weights::all_ones();
        assert_eq!(weighted_total(&raw, &w), 10.0);
        raw[3] = f64::NAN;
        assert_eq!(weighted_total(&raw, &w), DIVERGED_ENERGY);
    }

    #[test]
    fn iou_basics() {
        let a = Mask::from_fn(64, 1, |x, _| x < 32);
        let b = Mask::from_fn(64, 1, |x, _| x >= 16);
        assert!((iou(&a, &b) - 16.0 / 64.0).abs() < 1e-12);
        assert_eq!(iou(&Mask::new(8, 8), &Mask::new(8, 8)), 1.0);
    }

    #[test]
    fn iou_of_the_terms_counts_is_iou_bit_for_bit() {
        let target = disc(200, 150, 90.0, 70.0, 40.0);
        let td = TargetData::on_canvas(&target, 50);
        let shadows = [
            disc(300, 250, 150.0, 120.0, 35.0),
            disc(300, 250, 20.0, 20.0, 60.0),
            Mask::new(300, 250),
            td.mask.clone(),
        ];
        let only = |t: Term| {
            let mut w = Weights::default();
            w.0[t as usize] = 1.0;
            w
        };
        for shadow in &shadows {
            let want = iou(shadow, &td.mask);
            for w in [
                Weights::default(),
                only(Term::D0),
                only(Term::Xor),
                Weights::all_ones(),
            ] {
                let mut raw = [0.0; TERM_COUNT];
                let counts = image_terms(&td, shadow, &w, &mut raw);
                assert_eq!(iou_of(&td, shadow, counts).to_bits(), want.to_bits());
            }
        }
    }
}
