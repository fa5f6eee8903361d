//! What the design reads off a target picture: the Euclidean distance transform of its
//! shadow pixels (how far each is from the nearest background pixel, so twice the
//! value on a stroke's centre line is the stroke's width), the ridge of that transform
//! (the strokes' centre lines: the picture's skeleton, thick by a pixel or so) and the
//! local direction of the picture around a point (the principal axis of its shadow
//! pixels nearby, so the direction of a stroke).

use glam::DVec2;

/// A binary picture, row-major, `true` = shadow (target).
#[derive(Clone, Debug)]
pub struct Picture {
    pub width: usize,
    pub height: usize,
    pub on: Vec<bool>,
}

impl Picture {
    pub fn new(width: usize, height: usize, on: Vec<bool>) -> Picture {
        assert_eq!(on.len(), width * height);
        Picture { width, height, on }
    }

    pub fn get(&self, x: usize, y: usize) -> bool {
        self.on[y * self.width + x]
    }

    pub fn count(&self) -> usize {
        self.on.iter().filter(|&&b| b).count()
    }

    /// Euclidean distance (pixels) from every pixel to the nearest pixel that is off (or
    /// to the image's edge, beyond which everything is off); 0 for pixels that are off.
    /// Exact: the separable lower-envelope method of Felzenszwalb and Huttenlocher.
    pub fn distance(&self) -> Vec<f32> {
        let (w, h) = (self.width, self.height);
        let big = ((w + h) * (w + h)) as f64;
        // Pad by one off pixel on every side so that the edge counts as background.
        let (pw, ph) = (w + 2, h + 2);
        let mut f = vec![0.0f64; pw * ph];
        for y in 0..h {
            for x in 0..w {
                if self.get(x, y) {
                    f[(y + 1) * pw + x + 1] = big;
                }
            }
        }
        let mut line = Vec::new();
        let mut out = Vec::new();
        for x in 0..pw {
            line.clear();
            line.extend((0..ph).map(|y| f[y * pw + x]));
            squared_1d(&line, &mut out);
            for y in 0..ph {
                f[y * pw + x] = out[y];
            }
        }
        for y in 0..ph {
            line.clear();
            line.extend_from_slice(&f[y * pw..(y + 1) * pw]);
            squared_1d(&line, &mut out);
            f[y * pw..(y + 1) * pw].copy_from_slice(&out);
        }
        let mut d = vec![0.0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                d[y * w + x] = f[(y + 1) * pw + x + 1].sqrt() as f32;
            }
        }
        d
    }

    /// The ridge of a distance transform `d` of this picture: pixels that are on and
    /// whose distance is a local maximum along at least one of the four lines through
    /// them (horizontal, vertical, both diagonals), not below either neighbour and above
    /// one. These are the centre lines of the strokes (and the centres of blobs).
    pub fn ridge(&self, d: &[f32]) -> Vec<(usize, usize)> {
        let (w, h) = (self.width, self.height);
        let at = |x: isize, y: isize| -> f32 {
            if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                0.0
            } else {
                d[y as usize * w + x as usize]
            }
        };
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let c = d[y * w + x];
                if c <= 0.0 {
                    continue;
                }
                let (xi, yi) = (x as isize, y as isize);
                let peak = [(1, 0), (0, 1), (1, 1), (1, -1)].iter().any(|&(dx, dy)| {
                    let (a, b) = (at(xi - dx, yi - dy), at(xi + dx, yi + dy));
                    c >= a && c >= b && (c > a || c > b)
                });
                if peak {
                    out.push((x, y));
                }
            }
        }
        out
    }

    /// The direction (radians, world convention: counter-clockwise from image right,
    /// image up positive) of the principal axis of the on pixels within `radius` of
    /// `(x, y)`; 0 when there are fewer than three.
    pub fn direction(&self, x: usize, y: usize, radius: f64) -> f64 {
        let r = radius.ceil() as isize;
        let (mut n, mut sx, mut sy) = (0.0, 0.0, 0.0);
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for dy in -r..=r {
            for dx in -r..=r {
                let (px, py) = (x as isize + dx, y as isize + dy);
                if px < 0 || py < 0 || px >= self.width as isize || py >= self.height as isize {
                    continue;
                }
                if (dx * dx + dy * dy) as f64 > radius * radius
                    || !self.get(px as usize, py as usize)
                {
                    continue;
                }
                // World axes: x right, y up.
                let (u, v) = (dx as f64, -dy as f64);
                n += 1.0;
                sx += u;
                sy += v;
                sxx += u * u;
                sxy += u * v;
                syy += v * v;
            }
        }
        if n < 3.0 {
            return 0.0;
        }
        let (mx, my) = (sx / n, sy / n);
        let (cxx, cxy, cyy) = (sxx / n - mx * mx, sxy / n - mx * my, syy / n - my * my);
        0.5 * (2.0 * cxy).atan2(cxx - cyy)
    }

    /// The share (0 to 1) of the on pixels that no disc of `radius` pixels within the on
    /// pixels covers (the picture less its opening by that disc): its parts thinner than
    /// `2 radius`. `d` is [`Picture::distance`]. The discs' centres are the pixels at
    /// `radius` or more from the background; a pixel is covered when one is within
    /// `radius` of it, which the transform of a picture that is on everywhere but at the
    /// centres tells (padded, so that its edge is farther than `radius`).
    pub fn thin_share(&self, d: &[f32], radius: f64) -> f64 {
        let on = self.count();
        if on == 0 {
            return 0.0;
        }
        let pad = radius.ceil() as usize + 1;
        let (w, h) = (self.width + 2 * pad, self.height + 2 * pad);
        let mut rest = vec![true; w * h];
        for y in 0..self.height {
            for x in 0..self.width {
                if f64::from(d[y * self.width + x]) >= radius {
                    rest[(y + pad) * w + x + pad] = false;
                }
            }
        }
        let near = Picture::new(w, h, rest).distance();
        let thin = (0..self.width * self.height)
            .filter(|&k| {
                let (x, y) = (k % self.width, k / self.width);
                self.on[k] && f64::from(near[(y + pad) * w + x + pad]) > radius
            })
            .count();
        thin as f64 / on as f64
    }

    /// Centroid of the on pixels (pixel coordinates), if any.
    pub fn centroid(&self) -> Option<DVec2> {
        let (mut n, mut s) = (0usize, DVec2::ZERO);
        for y in 0..self.height {
            for x in 0..self.width {
                if self.get(x, y) {
                    n += 1;
                    s += DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                }
            }
        }
        (n > 0).then(|| s / n as f64)
    }
}

/// The 1-D squared distance transform of `f` (0 on sites, large elsewhere) into `out`:
/// `out[q] = min_p (q - p)^2 + f[p]`, by the lower envelope of parabolas.
fn squared_1d(f: &[f64], out: &mut Vec<f64>) {
    let n = f.len();
    out.clear();
    out.resize(n, 0.0);
    let mut v = vec![0usize; n];
    let mut z = vec![0.0f64; n + 1];
    let mut k = 0usize;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let parabola =
            |p: usize| ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q - p) as f64);
        let mut s = parabola(v[k]);
        // z[0] is minus infinity, so this stops at k = 0 at the latest.
        while s <= z[k] {
            k -= 1;
            s = parabola(v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    let mut k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *o = (q as f64 - p as f64).powi(2) + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_share_is_the_share_outside_the_opening_by_a_disc() {
        // A 40 x 40 square with a leg 6 px wide and 60 long below it.
        let (w, h) = (80, 120);
        let on: Vec<bool> = (0..w * h)
            .map(|k| {
                let (x, y) = (k % w, k / w);
                (20..60).contains(&x) && (10..50).contains(&y)
                    || (37..43).contains(&x) && (50..110).contains(&y)
            })
            .collect();
        let pic = Picture::new(w, h, on.clone());
        let d = pic.distance();
        let total = pic.count() as f64;
        // Discs 6 px across fit in the leg: nothing is thin.
        assert_eq!(pic.thin_share(&d, 3.0), 0.0);
        // Discs 8 px across fit only in the square: the leg (but for the top, where
        // discs in the square reach) is thin, and so are the square's corners.
        let thin = pic.thin_share(&d, 4.0);
        let leg = 6.0 * 60.0 / total;
        assert!(
            thin > 0.9 * leg && thin < leg + 8.0 / total,
            "{thin} against {leg}"
        );
        // Brute force: a pixel is covered when a centre (d >= r) lies within r of it.
        let r = 4.0f64;
        let centres: Vec<(f64, f64)> = (0..w * h)
            .filter(|&k| f64::from(d[k]) >= r)
            .map(|k| ((k % w) as f64, (k / w) as f64))
            .collect();
        let brute = (0..w * h)
            .filter(|&k| {
                let (x, y) = ((k % w) as f64, (k / w) as f64);
                on[k] && !centres.iter().any(|c| (c.0 - x).hypot(c.1 - y) <= r)
            })
            .count() as f64
            / total;
        assert!((thin - brute).abs() < 1e-12, "{thin} against {brute}");
        // Wider than the square: all of it is thin.
        assert_eq!(pic.thin_share(&d, 21.0), 1.0);
    }

    fn bar(w: usize, h: usize, x0: usize, x1: usize, y0: usize, y1: usize) -> Picture {
        let on = (0..w * h)
            .map(|k| (x0..x1).contains(&(k % w)) && (y0..y1).contains(&(k / w)))
            .collect();
        Picture::new(w, h, on)
    }

    #[test]
    fn distance_matches_brute_force() {
        // An L shape and a dot, against the minimum over every off pixel and the edge.
        let (w, h) = (23, 17);
        let on: Vec<bool> = (0..w * h)
            .map(|k| {
                let (x, y) = (k % w, k / w);
                (3..9).contains(&x) && (2..15).contains(&y)
                    || (3..20).contains(&x) && (10..15).contains(&y)
                    || (x, y) == (18, 3)
            })
            .collect();
        let p = Picture::new(w, h, on.clone());
        let d = p.distance();
        for y in 0..h {
            for x in 0..w {
                let mut best = f64::INFINITY;
                for yy in -1..=h as isize {
                    for xx in -1..=w as isize {
                        let inside = xx >= 0 && yy >= 0 && xx < w as isize && yy < h as isize;
                        if inside && on[yy as usize * w + xx as usize] {
                            continue;
                        }
                        let dd = ((xx - x as isize).pow(2) + (yy - y as isize).pow(2)) as f64;
                        best = best.min(dd.sqrt());
                    }
                }
                let want = if on[y * w + x] { best } else { 0.0 };
                assert!((d[y * w + x] as f64 - want).abs() < 1e-5, "({x}, {y})");
            }
        }
    }

    #[test]
    fn ridge_of_a_bar_is_its_centre_line_and_direction_follows_it() {
        // A horizontal bar 40 x 9 px: its ridge is the middle row (y = 14) away from
        // the ends, and the direction there is horizontal.
        let p = bar(60, 30, 10, 50, 10, 19);
        let d = p.distance();
        assert_eq!(d[14 * 60 + 30], 5.0);
        let ridge = p.ridge(&d);
        for x in 16..44 {
            assert!(ridge.contains(&(x, 14)), "x = {x}");
            assert!(!ridge.contains(&(x, 11)), "x = {x}");
        }
        assert!(p.direction(30, 14, 12.0).abs() < 1e-9);
        // The same bar upright points along the image's y axis (+-pi/2).
        let q = bar(30, 60, 10, 19, 10, 50);
        assert!((q.direction(14, 30, 12.0).abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    }

    #[test]
    fn direction_of_a_diagonal_stroke() {
        // Pixels on the line y = -x in image coordinates go up-right in world terms: 45 deg.
        let w = 40;
        let on = (0..w * w)
            .map(|k| {
                let (x, y) = ((k % w) as isize, (k / w) as isize);
                (x + y - 39).abs() <= 2
            })
            .collect();
        let p = Picture::new(w, w, on);
        let a = p.direction(20, 19, 10.0);
        assert!((a - std::f64::consts::FRAC_PI_4).abs() < 1e-6, "{a}");
    }
}
