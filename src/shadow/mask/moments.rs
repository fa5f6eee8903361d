//! The moments of a mask's set pixels: [`Moments`] from the exact integer sums
//! [`MomentSums`] that [`Mask::moment_sums`] accumulates row by row.

use std::ops::Range;

use glam::DVec2;

use super::Mask;

/// Raw image moments of a mask in pixel units (pixel centres at `i + 0.5`, `j + 0.5`).
///
/// The sums are exact: they are accumulated in integers and converted at the end.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    /// M00: number of set pixels.
    pub count: f64,
    /// M10 = sum of x.
    pub sum_x: f64,
    /// M01 = sum of y.
    pub sum_y: f64,
    /// M20 = sum of x^2.
    pub sum_xx: f64,
    /// M11 = sum of x*y.
    pub sum_xy: f64,
    /// M02 = sum of y^2.
    pub sum_yy: f64,
}

/// The exact integer sums behind [`Moments`] ([`Mask::moment_sums`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MomentSums(pub [u128; 6]);

impl MomentSums {
    /// `self - b + c`: the sums of a mask whose rows of `b` were replaced by those of `c`.
    pub fn replaced(self, b: MomentSums, c: MomentSums) -> MomentSums {
        MomentSums(std::array::from_fn(|k| self.0[k] - b.0[k] + c.0[k]))
    }
}

impl Moments {
    /// The moments of the sums `t` (in doubled coordinates, see [`Mask::moment_sums`]).
    pub fn from_sums(MomentSums(t): MomentSums) -> Moments {
        Moments {
            count: t[0] as f64,
            sum_x: t[1] as f64 / 2.0,
            sum_y: t[2] as f64 / 2.0,
            sum_xx: t[3] as f64 / 4.0,
            sum_xy: t[4] as f64 / 4.0,
            sum_yy: t[5] as f64 / 4.0,
        }
    }

    /// The centroid (xbar, ybar) in pixels, or `None` for an empty mask.
    pub fn centroid(&self) -> Option<DVec2> {
        if self.count > 0.0 {
            Some(DVec2::new(self.sum_x / self.count, self.sum_y / self.count))
        } else {
            None
        }
    }

    /// Normalised central second moments `[mu20, mu11, mu02]` (pixels squared), where
    /// `mu_pq = sum (x - xbar)^p (y - ybar)^q / M00`, or `None` for an empty mask.
    pub fn central_second(&self) -> Option<[f64; 3]> {
        let c = self.centroid()?;
        let m = self.count;
        Some([
            self.sum_xx / m - c.x * c.x,
            self.sum_xy / m - c.x * c.y,
            self.sum_yy / m - c.y * c.y,
        ])
    }
}

/// Sums over the set pixels of one row, in doubled x coordinates: (count, sum of 2x, sum
/// of 4x^2), or `None` for an empty row.
///
/// A run of pixels m0..m1 contributes F(m1) - F(m0) with F(m) = (m, m^2, G(m)), the
/// sums over pixels 0..m, so only the run boundaries matter. A boundary is a bit that
/// differs from the pixel to its left: a start where the pixel is set, an end where it
/// is clear. Words inside a run or inside a gap have no boundary bits and cost almost
/// nothing; boundary bits are visited with `trailing_zeros`. The sums are accumulated as
/// (sum over ends) - (sum over starts) in wrapping u64, which is exact because the true
/// totals are non-negative and fit. As G(m) = (4 m^3 - m) / 3, the row's G term is
/// (4 (sum of m^3) - (sum of m)) / 3 over the signed boundaries: one division a row.
#[inline(always)]
fn row_sums(row: &[u64]) -> Option<(u64, u64, u64)> {
    let (mut rn, mut rx2, mut rx3) = (0u64, 0u64, 0u64);
    let mut carry = 0u64; // the pixel left of the current word (0 outside)
    for (w, &word) in row.iter().enumerate() {
        let mut edges = word ^ ((word << 1) | carry);
        carry = word >> 63;
        let base = 64 * w as u64;
        while edges != 0 {
            let p = edges.trailing_zeros();
            edges &= edges - 1;
            let m = base + p as u64;
            // All ones at a start (negate), zero at an end; branch-free so the sums stay
            // in registers.
            let neg = ((word >> p) & 1).wrapping_neg();
            let signed = |v: u64| (v ^ neg).wrapping_sub(neg);
            let m2 = m.wrapping_mul(m);
            rn = rn.wrapping_add(signed(m));
            rx2 = rx2.wrapping_add(signed(m2));
            rx3 = rx3.wrapping_add(signed(m2.wrapping_mul(m)));
        }
    }
    if carry == 1 {
        // A run reaching the end of the last word (width a multiple of 64).
        let m = 64 * row.len() as u64;
        rn = rn.wrapping_add(m);
        rx2 = rx2.wrapping_add(m * m);
        rx3 = rx3.wrapping_add(m * m * m);
    }
    (rn != 0).then(|| (rn, rx2, 4u64.wrapping_mul(rx3).wrapping_sub(rn) / 3))
}

impl Mask {
    /// Raw moments of the set pixels (pixel centres at `i + 0.5`, `j + 0.5`).
    ///
    /// Each word is decomposed into runs of consecutive set bits with `trailing_zeros`;
    /// a run of pixels `a..b` contributes closed-form sums, so the cost depends on the
    /// number of runs, not of pixels. Sums are kept in doubled coordinates as integers
    /// (exact) and halved once at the end.
    pub fn moments(&self) -> Moments {
        Moments::from_sums(self.moment_sums(self.rows.clone()))
    }

    /// The integer sums of [`Mask::moments`] over `rows`, in
    /// doubled coordinates: sum 1, sum 2x, sum 2y, sum 4x^2, sum 4xy, sum 4y^2. Sums of
    /// disjoint rows add up to the sums of their union, exactly.
    pub fn moment_sums(&self, rows: Range<usize>) -> MomentSums {
        let rows = rows.start.max(self.rows.start)..rows.end.min(self.rows.end);
        // Each sum is below 4 W^3 H, 2 W^2 H^2 or 4 W H^3, so u64 holds them when both
        // sides are at most 2^15 pixels; u128 multiplications cost a third of the time here.
        let t = if self.width <= 1 << 15 && self.height <= 1 << 15 {
            let mut t = [0u64; 6];
            for j in rows {
                if let Some((rn, rx2, rxx4)) = row_sums(self.row(j)) {
                    let yy = 2 * j as u64 + 1;
                    let s = [rn, rx2, rn * yy, rxx4, rx2 * yy, rn * yy * yy];
                    for (t, s) in t.iter_mut().zip(s) {
                        *t += s;
                    }
                }
            }
            t.map(|v| v as u128)
        } else {
            let mut t = [0u128; 6];
            for j in rows {
                if let Some((rn, rx2, rxx4)) = row_sums(self.row(j)) {
                    let (rn, rx2, yy) = (rn as u128, rx2 as u128, 2 * j as u128 + 1);
                    let s = [rn, rx2, rn * yy, rxx4 as u128, rx2 * yy, rn * yy * yy];
                    for (t, s) in t.iter_mut().zip(s) {
                        *t += s;
                    }
                }
            }
            t
        };
        MomentSums(t)
    }
}
