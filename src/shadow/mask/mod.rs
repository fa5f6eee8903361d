//! Bit-packed binary images and the pixel statistics the energies need.
//!
//! [`Mask`] stores a `width` x `height` binary image as rows of `u64` words: bit `k` of
//! word `w` in row `j` is pixel `x = 64 * w + k`, `y = j`. Bits past `width` in the last
//! word of a row (the padding) are always zero, so whole-word operations such as
//! `count_ones` never see garbage. Every mask also keeps a conservative range of rows that
//! may hold set bits; rows outside it are guaranteed zero, which lets [`Mask::clear`] and
//! the counting functions skip the empty part of a sparse shadow image.
//!
//! Data flow in the project: the rasterizer ([`crate::shadow::raster`]) fills a cleared mask with
//! [`Mask::fill_span`]; the energies then compare it with the target through
//! [`Mask::xor_count`], [`Mask::and_count`], [`Mask::and_not_count`] and
//! [`Mask::moments`] (which returns [`Moments`]). The morphological operations
//! [`Mask::erode`] and [`Mask::dilate`] run once per scene to build the target's
//! boundary bands.
//!
//! Pixel convention for moments: pixel `(i, j)` is the unit square `[i, i+1] x [j, j+1]`
//! and contributes at its centre `(i + 0.5, j + 0.5)`, in pixel units with `y` pointing
//! down the image.

use glam::DVec2;
use std::fmt;
use std::ops::Range;

mod moments;

/// Every row, as the row ranges of the counts take it.
const ALL: Range<usize> = 0..usize::MAX;
pub use moments::{MomentSums, Moments};

/// A binary image with bit-packed rows. See the module documentation for the layout.
#[derive(Clone)]
pub struct Mask {
    width: usize,
    height: usize,
    words_per_row: usize,
    words: Vec<u64>,
    /// Rows `rows.start..rows.end` may hold set bits; all other rows are zero. The range
    /// is conservative (it may include empty rows) and is `0..0` when nothing was set.
    rows: Range<usize>,
}

/// Word `w` of `row` shifted so that bit `x` of the result is bit `x + d` of the row
/// (zero where `x + d` falls outside the row's words).
#[inline]
fn shifted_word(row: &[u64], w: usize, d: isize) -> u64 {
    let q = d.div_euclid(64);
    let s = d.rem_euclid(64) as u32;
    let get = |i: isize| -> u64 {
        if i >= 0 && (i as usize) < row.len() {
            row[i as usize]
        } else {
            0
        }
    };
    let base = w as isize + q;
    let lo = get(base) >> s;
    if s == 0 {
        lo
    } else {
        lo | (get(base + 1) << (64 - s))
    }
}

/// The 4-neighbours of pixel `(x, y)` inside a `w` x `h` image.
fn neighbours(x: usize, y: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    [
        (x.wrapping_sub(1), y),
        (x + 1, y),
        (x, y.wrapping_sub(1)),
        (x, y + 1),
    ]
    .into_iter()
    .filter(move |&(nx, ny)| nx < w && ny < h)
}

impl Mask {
    /// An all-zero mask of `width` x `height` pixels.
    pub fn new(width: usize, height: usize) -> Mask {
        let words_per_row = width.div_ceil(64);
        Mask {
            width,
            height,
            words_per_row,
            words: vec![0; words_per_row * height],
            rows: 0..0,
        }
    }

    /// The 4-connected components of the set pixels, in scan order of their first pixel:
    /// (pixel count, centroid in pixel coordinates, pixel centres at `+0.5`, first pixel).
    pub fn blobs(&self) -> Vec<(usize, DVec2, (usize, usize))> {
        let (w, h) = (self.width, self.height);
        let mut label = vec![false; w * h];
        let mut out = Vec::new();
        let mut stack = Vec::new();
        for y0 in 0..h {
            for x0 in 0..w {
                if !self.get(x0, y0) || label[y0 * w + x0] {
                    continue;
                }
                let (mut count, mut sum) = (0usize, DVec2::ZERO);
                label[y0 * w + x0] = true;
                stack.push((x0, y0));
                while let Some((x, y)) = stack.pop() {
                    count += 1;
                    sum += DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    for (nx, ny) in neighbours(x, y, w, h) {
                        if self.get(nx, ny) && !label[ny * w + nx] {
                            label[ny * w + nx] = true;
                            stack.push((nx, ny));
                        }
                    }
                }
                out.push((count, sum / count as f64, (x0, y0)));
            }
        }
        out
    }

    /// The set pixels of `self` 4-connected (within `self`) to a pixel set in both
    /// `self` and `seed` (same size): the parts of `self` that `seed` touches.
    pub fn connected_to(&self, seed: &Mask) -> Mask {
        assert!(
            self.width == seed.width && self.height == seed.height,
            "mask sizes differ"
        );
        let (w, h) = (self.width, self.height);
        let mut out = Mask::new(w, h);
        let mut stack = Vec::new();
        for y in seed.rows.clone() {
            for (k, (&a, &b)) in self.row(y).iter().zip(seed.row(y)).enumerate() {
                let mut both = a & b;
                while both != 0 {
                    let x = 64 * k + both.trailing_zeros() as usize;
                    both &= both - 1;
                    if !out.get(x, y) {
                        out.set(x, y);
                        stack.push((x, y));
                    }
                }
            }
        }
        while let Some((x, y)) = stack.pop() {
            for (nx, ny) in neighbours(x, y, w, h) {
                if self.get(nx, ny) && !out.get(nx, ny) {
                    out.set(nx, ny);
                    stack.push((nx, ny));
                }
            }
        }
        out
    }

    /// A mask with pixel `(x, y)` set iff `f(x, y)`.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> bool) -> Mask {
        let mut m = Mask::new(width, height);
        for y in 0..height {
            for x in 0..width {
                if f(x, y) {
                    m.set(x, y);
                }
            }
        }
        m
    }

    /// This mask with `margin` empty pixels added on every side: the picture on the
    /// solver's canvas ([`crate::evaluate::Problem`] draws shadows there, so that a shadow
    /// beyond the picture's edge still counts).
    pub fn padded(&self, margin: usize) -> Mask {
        let mut out = Mask::new(self.width + 2 * margin, self.height + 2 * margin);
        for y in self.rows.clone() {
            for x in 0..self.width {
                if self.get(x, y) {
                    out.set(x + margin, y + margin);
                }
            }
        }
        out
    }

    /// The inside of this mask without `margin` pixels on every side: the inverse of
    /// [`Mask::padded`], the picture cut out of the canvas.
    pub fn cropped(&self, margin: usize) -> Mask {
        assert!(
            2 * margin <= self.width && 2 * margin <= self.height,
            "a margin of {margin} pixels does not fit a {}x{} mask",
            self.width,
            self.height
        );
        let (w, h) = (self.width - 2 * margin, self.height - 2 * margin);
        let mut out = Mask::new(w, h);
        for y in self.rows.clone() {
            if y < margin || y >= margin + h {
                continue;
            }
            for x in 0..w {
                if self.get(x + margin, y) {
                    out.set(x, y - margin);
                }
            }
        }
        out
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn words_per_row(&self) -> usize {
        self.words_per_row
    }

    /// The rows that may hold set bits (all rows outside are zero). Conservative.
    pub fn row_range(&self) -> Range<usize> {
        self.rows.clone()
    }

    /// The words of row `j` (bit `k` of word `w` is pixel `64 * w + k`).
    #[inline]
    pub fn row(&self, j: usize) -> &[u64] {
        &self.words[j * self.words_per_row..(j + 1) * self.words_per_row]
    }

    /// Mask with the valid (non-padding) bits of the last word of a row.
    #[inline]
    fn last_word_mask(&self) -> u64 {
        match self.width % 64 {
            0 => !0,
            r => (1u64 << r) - 1,
        }
    }

    /// Record that row `y` may now hold set bits.
    #[inline(always)]
    fn touch_row(&mut self, y: usize) {
        if self.rows.start >= self.rows.end {
            self.rows = y..y + 1;
        } else {
            self.rows.start = self.rows.start.min(y);
            self.rows.end = self.rows.end.max(y + 1);
        }
    }

    pub fn get(&self, x: usize, y: usize) -> bool {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the mask"
        );
        (self.words[y * self.words_per_row + x / 64] >> (x % 64)) & 1 == 1
    }

    pub fn set(&mut self, x: usize, y: usize) {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the mask"
        );
        self.words[y * self.words_per_row + x / 64] |= 1u64 << (x % 64);
        self.touch_row(y);
    }

    /// Clear every pixel. Only the rows in the tracked range are written.
    pub fn clear(&mut self) {
        let r = self.rows.clone();
        self.words[r.start * self.words_per_row..r.end * self.words_per_row].fill(0);
        self.rows = 0..0;
    }

    /// Make this mask a copy of `other` (same size) without allocating: only the rows
    /// either may have set bits in are written.
    pub fn copy_from(&mut self, other: &Mask) {
        assert!(
            self.width == other.width && self.height == other.height,
            "mask sizes differ"
        );
        self.clear();
        let r = other.rows.clone();
        let wr = r.start * self.words_per_row..r.end * self.words_per_row;
        self.words[wr.clone()].copy_from_slice(&other.words[wr]);
        self.rows = r;
    }

    /// [`Mask::copy_from`] for a mask that differs from `other` only in `rows`: only
    /// those rows are written.
    pub fn restore_rows(&mut self, other: &Mask, rows: Range<usize>) {
        assert!(
            self.width == other.width && self.height == other.height,
            "mask sizes differ"
        );
        let wr = rows.start * self.words_per_row..rows.end * self.words_per_row;
        self.words[wr.clone()].copy_from_slice(&other.words[wr]);
        self.rows = other.rows.clone();
    }

    /// Set every pixel (padding bits stay zero).
    pub fn fill_all(&mut self) {
        if self.width == 0 || self.height == 0 {
            return;
        }
        self.words.fill(!0);
        let last = self.last_word_mask();
        let wpr = self.words_per_row;
        for row in self.words.chunks_exact_mut(wpr) {
            row[wpr - 1] = last;
        }
        self.rows = 0..self.height;
    }

    /// Set pixels `x0..=x1` of row `y` using whole-word masks. Empty if `x0 > x1`.
    /// The caller clamps: `x1 < width` and `y < height` are required.
    #[inline(always)]
    pub fn fill_span(&mut self, y: usize, x0: usize, x1: usize) {
        if x0 > x1 {
            return;
        }
        assert!(x1 < self.width && y < self.height, "span outside the mask");
        let base = y * self.words_per_row;
        let (w0, w1) = (x0 / 64, x1 / 64);
        let m0 = !0u64 << (x0 % 64);
        let m1 = !0u64 >> (63 - x1 % 64);
        let row = &mut self.words[base..base + self.words_per_row];
        if w0 == w1 {
            row[w0] |= m0 & m1;
        } else if w1 == w0 + 1 {
            row[w0] |= m0;
            row[w1] |= m1;
        } else {
            // Spans are short, so OR-ing a per-word mask beats a `fill` of the middle
            // words, which compiles to a call to `memset`.
            for (k, word) in row[w0..=w1].iter_mut().enumerate() {
                let mut m = !0u64;
                if k == 0 {
                    m &= m0;
                }
                if k == w1 - w0 {
                    m &= m1;
                }
                *word |= m;
            }
        }
        self.touch_row(y);
    }

    /// Number of set pixels.
    pub fn count(&self) -> u64 {
        let r = &self.rows;
        self.words[r.start * self.words_per_row..r.end * self.words_per_row]
            .iter()
            .map(|w| w.count_ones() as u64)
            .sum()
    }

    /// Union of the two masks' row ranges (checking that the masks are the same size).
    fn union_rows(&self, other: &Mask) -> Range<usize> {
        assert!(
            self.width == other.width && self.height == other.height,
            "mask sizes differ: {}x{} vs {}x{}",
            self.width,
            self.height,
            other.width,
            other.height
        );
        let (a, b) = (&self.rows, &other.rows);
        if a.start >= a.end {
            b.clone()
        } else if b.start >= b.end {
            a.clone()
        } else {
            a.start.min(b.start)..a.end.max(b.end)
        }
    }

    /// The rows where both masks may hold set bits (an AND is zero elsewhere); empty or
    /// reversed when there are none.
    fn common_rows(&self, other: &Mask) -> Range<usize> {
        // The size check, as for every pair of masks.
        self.union_rows(other);
        let (a, b) = (&self.rows, &other.rows);
        a.start.max(b.start)..a.end.min(b.end)
    }

    /// Popcount of `op(a, b)` over the word range `r` of both masks, with four
    /// independent accumulators so the popcounts of consecutive words can overlap in the
    /// pipeline.
    #[inline(always)]
    fn pair_count_in(
        &self,
        other: &Mask,
        r: Range<usize>,
        op: impl Fn(u64, u64) -> u64 + Copy,
    ) -> u64 {
        let a = &self.words[r.clone()];
        let b = &other.words[r];
        #[cfg(target_arch = "x86_64")]
        {
            // With AVX2, LLVM vectorises the popcount (a nibble lookup with vpshufb), about
            // twice as fast as scalar POPCNT. The check is cached by std and costs a load.
            if std::arch::is_x86_feature_detected!("avx512vpopcntdq") {
                // SAFETY: the CPU supports AVX-512F and VPOPCNTDQ, checked just above.
                return unsafe { pair_count_avx512(a, b, op) };
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above.
                return unsafe { pair_count_avx2(a, b, op) };
            }
        }
        pair_count_words(a, b, op)
    }

    /// The words of the rows in both `a` and `b`.
    fn words_within(&self, a: Range<usize>, b: Range<usize>) -> Range<usize> {
        let (start, end) = (a.start.max(b.start), a.end.min(b.end));
        if start >= end {
            return 0..0;
        }
        start * self.words_per_row..end * self.words_per_row
    }

    /// Number of set pixels in `rows`.
    pub fn count_in(&self, rows: Range<usize>) -> u64 {
        let r = self.words_within(rows, self.rows.clone());
        self.words[r].iter().map(|w| w.count_ones() as u64).sum()
    }

    /// [`Mask::xor_count`] over `rows` only.
    pub fn xor_count_in(&self, other: &Mask, rows: Range<usize>) -> u64 {
        let r = self.words_within(rows, self.union_rows(other));
        self.pair_count_in(other, r, |a, b| a ^ b)
    }

    /// [`Mask::and_count`] over `rows` only.
    pub fn and_count_in(&self, other: &Mask, rows: Range<usize>) -> u64 {
        let r = self.words_within(rows, self.common_rows(other));
        self.pair_count_in(other, r, |a, b| a & b)
    }

    /// [`Mask::and_not_count`] over `rows` only.
    pub fn and_not_count_in(&self, other: &Mask, rows: Range<usize>) -> u64 {
        self.union_rows(other);
        let r = self.words_within(rows, self.rows.clone());
        self.pair_count_in(other, r, |a, b| a & !b)
    }

    /// Runs `draw` on this mask and returns the rows it set pixels in (`0..0` for none;
    /// conservative, as the mask's own range is): the rows where the mask may now differ
    /// from before.
    pub fn drawn_rows(&mut self, draw: impl FnOnce(&mut Mask)) -> Range<usize> {
        let before = std::mem::replace(&mut self.rows, 0..0);
        draw(self);
        let drawn = std::mem::replace(&mut self.rows, before);
        if drawn.start < drawn.end {
            self.touch_row(drawn.start);
            self.touch_row(drawn.end - 1);
        }
        drawn
    }

    /// Number of pixels set in exactly one of the masks.
    pub fn xor_count(&self, other: &Mask) -> u64 {
        self.xor_count_in(other, ALL)
    }

    /// Number of pixels set in both masks.
    pub fn and_count(&self, other: &Mask) -> u64 {
        self.and_count_in(other, ALL)
    }

    /// Number of pixels set in `self` but not in `other` (popcount of `self & !other`).
    pub fn and_not_count(&self, other: &Mask) -> u64 {
        self.and_not_count_in(other, ALL)
    }

    /// `self & !other` as a new mask.
    pub fn and_not(&self, other: &Mask) -> Mask {
        self.combined(other, |a, b| a & !b)
    }

    /// `self & other` as a new mask.
    pub fn and(&self, other: &Mask) -> Mask {
        self.combined(other, |a, b| a & b)
    }

    /// A new mask of `f` applied word by word to `self` and `other` (same size); `f`
    /// must keep every pixel clear where `self` is clear (its row range is kept).
    fn combined(&self, other: &Mask, f: impl Fn(u64, u64) -> u64) -> Mask {
        assert!(
            self.width == other.width && self.height == other.height,
            "mask sizes differ"
        );
        let mut out = self.clone();
        for (o, b) in out.words.iter_mut().zip(&other.words) {
            *o = f(*o, *b);
        }
        out
    }

    /// `self |= other`.
    pub fn or_assign(&mut self, other: &Mask) {
        assert!(
            self.width == other.width && self.height == other.height,
            "mask sizes differ"
        );
        let r = other.rows.clone();
        if r.start >= r.end {
            return;
        }
        let wr = r.start * self.words_per_row..r.end * self.words_per_row;
        for (o, b) in self.words[wr.clone()].iter_mut().zip(&other.words[wr]) {
            *o |= b;
        }
        self.touch_row(r.start);
        self.touch_row(r.end - 1);
    }

    /// Binary dilation with a `k` x `k` all-ones kernel centred on each pixel (`k` odd):
    /// a pixel is set iff some pixel within Chebyshev distance `k / 2` is set. Pixels
    /// outside the image count as 0.
    pub fn dilate(&self, k: usize) -> Mask {
        self.morph(k, false)
    }

    /// Binary erosion with a `k` x `k` all-ones kernel centred on each pixel (`k` odd):
    /// a pixel stays set iff every pixel within Chebyshev distance `k / 2` is set.
    /// Pixels outside the image count as 0, so everything within `k / 2` of the border
    /// is cleared.
    pub fn erode(&self, k: usize) -> Mask {
        self.morph(k, true)
    }

    /// Separable morphology: a horizontal pass of word shifts, then a vertical pass over
    /// whole rows. `erode` selects AND (erosion) instead of OR (dilation).
    fn morph(&self, k: usize, erode: bool) -> Mask {
        assert!(k % 2 == 1, "morphology kernel size must be odd, got {k}");
        let r = k / 2;
        let wpr = self.words_per_row;
        let last = self.last_word_mask();
        let combine = |a: u64, b: u64| if erode { a & b } else { a | b };

        // Horizontal pass: row j of `horiz` combines the row shifted by -r..=r pixels.
        // Zeros shifted in from beyond either edge (and the zero padding) implement
        // "outside counts as 0".
        let mut horiz = Mask::new(self.width, self.height);
        horiz.rows = self.rows.clone();
        for j in self.rows.clone() {
            let src = self.row(j);
            let dst = &mut horiz.words[j * wpr..(j + 1) * wpr];
            for (w, out) in dst.iter_mut().enumerate() {
                let mut acc = shifted_word(src, w, -(r as isize));
                for d in -(r as isize) + 1..=r as isize {
                    acc = combine(acc, shifted_word(src, w, d));
                }
                *out = acc;
            }
            if wpr > 0 {
                dst[wpr - 1] &= last;
            }
        }

        // Vertical pass: row j combines rows j-r..=j+r of `horiz`. For erosion rows
        // outside the image are 0, so rows within r of the top or bottom become empty.
        let mut out = Mask::new(self.width, self.height);
        if self.rows.start >= self.rows.end {
            return out;
        }
        let (lo, hi) = if erode {
            (
                self.rows.start.max(r),
                self.rows.end.min(self.height.saturating_sub(r)),
            )
        } else {
            (
                self.rows.start.saturating_sub(r),
                (self.rows.end + r).min(self.height),
            )
        };
        if lo >= hi {
            return out;
        }
        for j in lo..hi {
            let (a, b) = (j.saturating_sub(r), (j + r).min(self.height - 1));
            let dst = &mut out.words[j * wpr..(j + 1) * wpr];
            dst.copy_from_slice(horiz.row(a));
            for jj in a + 1..=b {
                for (o, &s) in dst.iter_mut().zip(horiz.row(jj)) {
                    *o = combine(*o, s);
                }
            }
        }
        out.rows = lo..hi;
        out
    }
}

impl PartialEq for Mask {
    /// Pixel-wise equality; the tracked row ranges do not matter.
    fn eq(&self, other: &Mask) -> bool {
        self.width == other.width && self.height == other.height && self.words == other.words
    }
}

impl Eq for Mask {}

impl fmt::Debug for Mask {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Mask")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("rows", &self.rows)
            .field("count", &self.count())
            .finish()
    }
}

/// Popcount of `op(a[i], b[i])` summed over the words, with four accumulators so the
/// adds do not form one long dependency chain.
#[inline(always)]
fn pair_count_words(a: &[u64], b: &[u64], op: impl Fn(u64, u64) -> u64) -> u64 {
    let mut acc = [0u64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for k in 0..4 {
            acc[k] += op(x[k], y[k]).count_ones() as u64;
        }
    }
    let tail: u64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(&x, &y)| op(x, y).count_ones() as u64)
        .sum();
    acc.iter().sum::<u64>() + tail
}

/// The same count compiled for AVX-512 with the vector popcount instruction (VPOPCNTQ).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vpopcntdq")]
unsafe fn pair_count_avx512(a: &[u64], b: &[u64], op: impl Fn(u64, u64) -> u64) -> u64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| op(x, y).count_ones() as u64)
        .sum()
}

/// The same count compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn pair_count_avx2(a: &[u64], b: &[u64], op: impl Fn(u64, u64) -> u64) -> u64 {
    // A plain iterator sum: LLVM turns it into vector popcounts, which the manual
    // four-accumulator unroll of the scalar version would prevent.
    a.iter()
        .zip(b)
        .map(|(&x, &y)| op(x, y).count_ones() as u64)
        .sum()
}

#[cfg(test)]
mod tests;
