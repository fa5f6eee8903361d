//! Where each object goes in a user's picture: [`cover_hints`] places one hint per
//! object, largest first, where a square the size of its shadow covers the most of the
//! target not yet covered by the objects placed before it. The shadow's size is the
//! object's bounding radius magnified as at a third of the light's height (the middle of
//! the heights the start guess uses). `bsa new` writes these hints; the scene's start
//! guess then aims every object at its hint.

use glam::DVec2;

use crate::evaluate::Problem;
use crate::shadow::mask::Mask;

/// Fraction of the light's height at which an object's shadow size is judged.
const HEIGHT_FRACTION: f64 = 1.0 / 3.0;

/// One hint pixel per launched occluder (occluder index, pixel), largest object first.
pub fn cover_hints(problem: &Problem, target: &Mask) -> Vec<(usize, DVec2)> {
    let scene = &problem.scene;
    let (w, h) = (target.width(), target.height());
    let metres_per_px = scene.receiver.width / w as f64;
    let magnification = 1.0 / (1.0 - HEIGHT_FRACTION);
    let mut open: Vec<u32> = (0..w * h)
        .map(|k| u32::from(target.get(k % w, k / w)))
        .collect();
    let occ = &scene.occluders;
    let mut order: Vec<usize> = (0..occ.len()).filter(|&i| occ[i].launched).collect();
    order.sort_by(|&a, &b| {
        occ[b]
            .bounding_radius
            .total_cmp(&occ[a].bounding_radius)
            .then(a.cmp(&b))
    });
    let mut sums = vec![0u32; (w + 1) * (h + 1)];
    let mut out = Vec::new();
    for i in order {
        let r = occ[i].bounding_radius * magnification / metres_per_px;
        // A square of the disc's area.
        let half = ((0.5 * r * std::f64::consts::PI.sqrt()).round() as usize).max(1);
        integrate(&open, w, h, &mut sums);
        let window = |x: usize, y: usize| -> u32 {
            let (x0, y0) = (x.saturating_sub(half), y.saturating_sub(half));
            let (x1, y1) = ((x + half + 1).min(w), (y + half + 1).min(h));
            let at = |x: usize, y: usize| sums[y * (w + 1) + x];
            at(x1, y1) + at(x0, y0) - at(x0, y1) - at(x1, y0)
        };
        let (mut best, mut at) = (0u32, (w / 2, h / 2));
        for y in 0..h {
            for x in 0..w {
                let s = window(x, y);
                if s > best {
                    best = s;
                    at = (x, y);
                }
            }
        }
        if best == 0 {
            // Everything is covered: the target's densest point.
            at = densest(target, half).unwrap_or(at);
        }
        let c = DVec2::new(at.0 as f64 + 0.5, at.1 as f64 + 0.5);
        for y in at.1.saturating_sub(half)..(at.1 + half + 1).min(h) {
            for x in at.0.saturating_sub(half)..(at.0 + half + 1).min(w) {
                open[y * w + x] = 0;
            }
        }
        out.push((i, c));
    }
    out.sort_by_key(|h| h.0);
    out
}

/// Summed-area table of `values` (`w x h`) into `sums` (`(w + 1) x (h + 1)`).
fn integrate(values: &[u32], w: usize, h: usize, sums: &mut [u32]) {
    for y in 0..h {
        let mut row = 0;
        for x in 0..w {
            row += values[y * w + x];
            sums[(y + 1) * (w + 1) + x + 1] = sums[y * (w + 1) + x + 1] + row;
        }
    }
}

/// The pixel whose square of half-side `half` holds the most target.
fn densest(target: &Mask, half: usize) -> Option<(usize, usize)> {
    let (w, h) = (target.width(), target.height());
    let all: Vec<u32> = (0..w * h)
        .map(|k| u32::from(target.get(k % w, k / w)))
        .collect();
    let mut sums = vec![0u32; (w + 1) * (h + 1)];
    integrate(&all, w, h, &mut sums);
    let at = |x: usize, y: usize| sums[y * (w + 1) + x];
    (0..w * h).map(|k| (k % w, k / w)).max_by_key(|&(x, y)| {
        let (x0, y0) = (x.saturating_sub(half), y.saturating_sub(half));
        let (x1, y1) = ((x + half + 1).min(w), (y + half + 1).min(h));
        at(x1, y1) + at(x0, y0) - at(x0, y1) - at(x1, y0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summed_area_table_counts_a_rectangle() {
        let (w, h) = (5, 4);
        let v: Vec<u32> = (0..w * h).map(|k| (k % 3 == 0) as u32).collect();
        let mut s = vec![0u32; (w + 1) * (h + 1)];
        integrate(&v, w, h, &mut s);
        let direct: u32 = (1..3)
            .flat_map(|y| (2..5).map(move |x| (x, y)))
            .map(|(x, y)| v[y * w + x])
            .sum();
        let at = |x: usize, y: usize| s[y * (w + 1) + x];
        assert_eq!(at(5, 3) + at(2, 1) - at(2, 3) - at(5, 1), direct);
    }
}
