//! The exact shadow of a sphere, in closed form per pixel row: interval arithmetic
//! ([`Iv`]), roots of quadratics, and the conics (cone, ball, Thales sphere) whose row
//! sections bound the shadow.

use super::camera::ShadowCamera;
use super::rows::{centre_span, fill_rows, Iv};
use crate::shadow::mask::Mask;
use glam::DVec3;

/// Sorted real roots of `a s^2 + b s + c` (a != 0), or `None` if there are none. Uses the
/// cancellation-free form, so a tiny `a` yields one accurate root and one huge root.
#[inline]
fn quad_roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    if q == 0.0 {
        // b = 0 and c = 0: a double root at zero.
        return Some((0.0, 0.0));
    }
    let (r1, r2) = (q / a, c / q);
    Some(if r1 <= r2 { (r1, r2) } else { (r2, r1) })
}

/// `{s : a s^2 + b s + c >= 0}` as up to two intervals.
#[inline]
fn quad_nonneg(a: f64, b: f64, c: f64) -> (Iv, Iv) {
    if a == 0.0 {
        let iv = if b > 0.0 {
            Iv::new(-c / b, f64::INFINITY)
        } else if b < 0.0 {
            Iv::new(f64::NEG_INFINITY, -c / b)
        } else if c >= 0.0 {
            Iv::ALL
        } else {
            Iv::EMPTY
        };
        return (iv, Iv::EMPTY);
    }
    match quad_roots(a, b, c) {
        None if a > 0.0 => (Iv::ALL, Iv::EMPTY),
        None => (Iv::EMPTY, Iv::EMPTY),
        Some((r1, r2)) if a > 0.0 => (Iv::new(f64::NEG_INFINITY, r1), Iv::new(r2, f64::INFINITY)),
        Some((r1, r2)) => (Iv::new(r1, r2), Iv::EMPTY),
    }
}

/// `{s : a s^2 + b s + c <= 0}` for `a > 0`: one interval.
#[inline]
fn quad_nonpos_convex(a: f64, b: f64, c: f64) -> Iv {
    match quad_roots(a, b, c) {
        Some((r1, r2)) => Iv::new(r1, r2),
        None => Iv::EMPTY,
    }
}

/// A quadratic in pixel coordinates (s = px, y = py):
/// `a s^2 + b s y + c y^2 + d s + e y + f`.
#[derive(Clone, Copy, Debug)]
struct Conic {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    e: f64,
    f: f64,
}

impl Conic {
    /// The conic `|p0 + s du + y dv|^2 + lin . (p0 + s du + y dv) + k` for in-plane
    /// steps `du`, `dv`.
    fn sq_norm_plus_linear(p0: DVec3, du: DVec3, dv: DVec3, lin: DVec3, k: f64) -> Conic {
        Conic {
            a: du.dot(du),
            b: 2.0 * du.dot(dv),
            c: dv.dot(dv),
            d: 2.0 * p0.dot(du) + lin.dot(du),
            e: 2.0 * p0.dot(dv) + lin.dot(dv),
            f: p0.dot(p0) + lin.dot(p0) + k,
        }
    }

    /// Coefficients `(a2, a1, a0)` of the quadratic in `s` along the row `y`.
    #[inline]
    fn row(&self, y: f64) -> (f64, f64, f64) {
        (
            self.a,
            self.b * y + self.d,
            (self.c * y + self.e) * y + self.f,
        )
    }

    /// The closed `y` range where the row quadratic has real roots, for a conic whose
    /// `a` is negative (an ellipse opening downwards in `s`); `None` if unbounded.
    fn y_range(&self) -> Option<Iv> {
        // Discriminant of the row quadratic as a quadratic in y.
        let qa = self.b * self.b - 4.0 * self.a * self.c;
        let qb = 2.0 * self.b * self.d - 4.0 * self.a * self.e;
        let qc = self.d * self.d - 4.0 * self.a * self.f;
        if qa.is_nan() || qa >= 0.0 {
            return None;
        }
        Some(match quad_roots(qa, qb, qc) {
            Some((y0, y1)) => Iv::new(y0, y1),
            None => Iv::EMPTY,
        })
    }
}

impl ShadowCamera {
    /// OR the exact shadow of a solid sphere into `mask`.
    ///
    /// Along the centre line of each row, `X(s) = origin + s du + y dv`, the segment
    /// `light + t d` (`d = X - light`, `t` in (0, 1)) meets the ball iff
    /// `t^2 |d|^2 - 2 t (w.d) + |w|^2 - r^2 <= 0` (`w = S - light`) for some such `t`.
    /// With the light outside the ball, this is: the cone condition
    /// `(w.d)^2 >= (|w|^2 - r^2) |d|^2` with `w.d > 0` (the ray hits), and the entry point
    /// lies before `X`: either `X` is inside the ball, or the chord midpoint is before `X`,
    /// `w.d < |d|^2`. Each condition is a quadratic or linear inequality in `s`, solved in
    /// closed form; the result is one interval per row because the shadow is convex.
    pub fn rasterize_sphere(&self, center: DVec3, radius: f64, mask: &mut Mask) {
        self.check_mask(mask);
        if radius.is_nan() || radius <= 0.0 || self.width_px == 0 || self.height_px == 0 {
            return;
        }
        let w = center - self.light;
        let z = self.h + w.dot(self.n); // height of the centre above the receiver
        if z - radius >= self.h || z + radius <= 0.0 {
            // Entirely behind the light plane or under the receiver (touching included:
            // the open segments never reach a tangent plane).
            return;
        }
        let k = w.length_squared() - radius * radius;
        if k < 0.0 {
            // The light is inside the ball: every segment starts inside it.
            mask.fill_all();
            return;
        }
        // The cone condition (w.d)^2 - k |d|^2 >= 0 as a conic in pixel coordinates, with
        // d = p0 + s du + y dv.
        let p0 = self.origin - self.light;
        let (g0, gu, gv) = (w.dot(p0), w.dot(self.du), w.dot(self.dv));
        let cone = Conic {
            a: gu * gu - k * self.du.length_squared(),
            b: 2.0 * (gu * gv - k * self.du.dot(self.dv)),
            c: gv * gv - k * self.dv.length_squared(),
            d: 2.0 * (g0 * gu - k * p0.dot(self.du)),
            e: 2.0 * (g0 * gv - k * p0.dot(self.dv)),
            f: g0 * g0 - k * p0.length_squared(),
        };
        let (wp, hp) = (self.width_px, self.height_px);
        let below_light_plane = z + radius < self.h;
        let above_receiver = z - radius > 0.0;
        // When the ball is below the light plane every ray into it descends, so the cone
        // meets the receiver in a bounded ellipse that bounds the rows to visit.
        let rows = if below_light_plane {
            cone.y_range()
        } else {
            None
        };
        let rows = match rows {
            Some(iv) => match centre_span(iv, hp) {
                Some(r) => r,
                None => return,
            },
            None => (0, hp - 1),
        };

        if below_light_plane && above_receiver && cone.a < 0.0 {
            // Common case, the ball strictly inside the slab: the shadow is the ellipse
            // itself (every descending ray that enters the ball does so above the
            // receiver), one square root per row.
            let inv = 0.5 / cone.a;
            let half_scale = inv.abs();
            fill_rows(mask, rows.0, rows.1, |y| {
                let (a, b, c) = cone.row(y);
                // A negative discriminant (the row misses the ellipse) gives NaN, which
                // `fill_rows` rejects.
                let mid = -b * inv;
                let half = (b * b - 4.0 * a * c).sqrt() * half_scale;
                (mid - half, mid + half)
            });
            return;
        }

        // General case: the ball crosses the receiver and/or the light plane.
        // |X - S|^2 - r^2 <= 0: the pixel centre is inside the ball.
        let ball = Conic::sq_norm_plus_linear(
            self.origin - center,
            self.du,
            self.dv,
            DVec3::ZERO,
            -radius * radius,
        );
        // |d|^2 - w.d <= 0: the chord midpoint is at or beyond X (Thales sphere on L, S).
        let thales = Conic::sq_norm_plus_linear(p0, self.du, self.dv, -w, 0.0);
        // Points slightly outside the image are irrelevant; clamping infinite ends here
        // keeps the interval arithmetic finite.
        let domain = Iv::new(-1.0, wp as f64 + 1.0);
        fill_rows(mask, rows.0, rows.1, |y| {
            // Cone and forward half-space w.d > 0 (the nappe the rays travel in).
            let (a, b, c) = cone.row(y);
            let (c1, c2) = quad_nonneg(a, b, c);
            let (b0, b1) = (g0 + gv * y, gu);
            let forward = if b1 > 0.0 {
                Iv::new(-b0 / b1, f64::INFINITY)
            } else if b1 < 0.0 {
                Iv::new(f64::NEG_INFINITY, -b0 / b1)
            } else if b0 > 0.0 {
                Iv::ALL
            } else {
                Iv::EMPTY
            };
            let fwd = forward.meet(domain);
            let hit = c1.meet(fwd).hull(c2.meet(fwd));
            if hit.is_empty() {
                return (hit.lo, hit.hi);
            }
            let shadow = if above_receiver {
                // The chord lies above the receiver, so it always starts before X.
                hit
            } else {
                let (a, b, c) = ball.row(y);
                let inside = quad_nonpos_convex(a, b, c);
                let (a, b, c) = thales.row(y);
                let late = quad_nonpos_convex(a, b, c);
                if late.is_empty() {
                    hit
                } else {
                    hit.meet(inside)
                        .hull(hit.meet(Iv::new(f64::NEG_INFINITY, late.lo)))
                        .hull(hit.meet(Iv::new(late.hi, f64::INFINITY)))
                }
            };
            (shadow.lo, shadow.hi)
        });
    }
}
