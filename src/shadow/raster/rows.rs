//! What the rasterizers share, below all of them: the interval type of the closed-form
//! row spans, row filling, and the reusable scratch buffers of the mesh paths.

use glam::{DVec2, DVec3};

use crate::shadow::mask::Mask;

/// A closed interval `[lo, hi]`; empty when `!(lo <= hi)` (this also catches NaN).
#[derive(Clone, Copy, Debug)]
pub(super) struct Iv {
    pub(super) lo: f64,
    pub(super) hi: f64,
}

impl Iv {
    pub(super) const EMPTY: Iv = Iv {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
    };
    pub(super) const ALL: Iv = Iv {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    #[inline]
    pub(super) fn new(lo: f64, hi: f64) -> Iv {
        Iv { lo, hi }
    }

    #[inline]
    pub(super) fn is_empty(self) -> bool {
        // Written with partial_cmp so that NaN bounds count as empty.
        !matches!(
            self.lo.partial_cmp(&self.hi),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        )
    }

    #[inline]
    pub(super) fn meet(self, o: Iv) -> Iv {
        Iv::new(self.lo.max(o.lo), self.hi.min(o.hi))
    }

    /// The smallest interval containing both; used to merge pieces whose union is known
    /// to be an interval (the shadow of a convex body on a line is convex).
    #[inline]
    pub(super) fn hull(self, o: Iv) -> Iv {
        match (self.is_empty(), o.is_empty()) {
            (true, _) => o,
            (_, true) => self,
            _ => Iv::new(self.lo.min(o.lo), self.hi.max(o.hi)),
        }
    }
}

/// Pixel indices `i` with centre `i + 0.5` in `iv`, clamped to `0..n`.
#[inline]
pub(super) fn centre_span(iv: Iv, n: usize) -> Option<(usize, usize)> {
    if iv.is_empty() || n == 0 {
        return None;
    }
    let a = (iv.lo - 0.5).ceil().max(0.0);
    let b = (iv.hi - 0.5).floor().min((n - 1) as f64);
    if a <= b {
        // Both are clamped to 0..n, so the cheaper signed conversion is exact.
        Some((a as i64 as usize, b as i64 as usize))
    } else {
        None
    }
}

/// Fill rows `j0..=j1`: `span(y)` gives the closed x-interval of row centre line `y`
/// (NaN or `lo > hi` for none), and the pixels whose centres lie in it are set.
///
/// Rows are processed in blocks: a branch-free pass evaluates `span` and rounds to pixel
/// indices for a whole block (the compiler vectorises it, two rows per instruction), then
/// a second pass fills the spans. This halves the cost per row compared with one loop.
#[inline(always)]
pub(super) fn fill_rows(mask: &mut Mask, j0: usize, j1: usize, span: impl Fn(f64) -> (f64, f64)) {
    const BLOCK: usize = 16;
    let last = (mask.width() - 1) as f64;
    let mut first_px = [0.0f64; BLOCK];
    let mut last_px = [0.0f64; BLOCK];
    let mut j = j0;
    while j <= j1 {
        let n = BLOCK.min(j1 + 1 - j);
        for (k, (fp, lp)) in first_px[..n].iter_mut().zip(&mut last_px[..n]).enumerate() {
            let (lo, hi) = span((j + k) as f64 + 0.5);
            *fp = (lo - 0.5).ceil();
            *lp = (hi - 0.5).floor();
        }
        for k in 0..n {
            let (a, b) = (first_px[k], last_px[k]);
            // Reject NaN before clamping (`max` and `min` would swallow it).
            if a <= b {
                let (a, b) = (a.max(0.0), b.min(last));
                if a <= b {
                    // Both are clamped to the row, so the cheaper signed conversion is exact.
                    mask.fill_span(j + k, a as i64 as usize, b as i64 as usize);
                }
            }
        }
        j += n;
    }
}

/// A silhouette edge in pixel space: its upper end, slope dx/dy, the rows whose centre
/// lines it crosses, and its winding direction.
#[derive(Clone, Copy, Debug)]
pub(super) struct SilEdge {
    pub(super) top: DVec2,
    pub(super) slope: f64,
    pub(super) j0: u32,
    pub(super) j1: u32,
    pub(super) dir: i32,
}

/// Reusable buffers for [`rasterize_triangles`] and [`rasterize_box`]. They grow to the
/// largest mesh and image seen, then are reused without allocating.
///
/// [`rasterize_triangles`]: super::camera::ShadowCamera::rasterize_triangles
/// [`rasterize_box`]: super::camera::ShadowCamera::rasterize_box
#[derive(Clone, Debug, Default)]
pub struct RasterScratch {
    /// Homogeneous image coordinates `(px * depth, py * depth, depth)` per vertex.
    pub(super) hom: Vec<DVec3>,
    /// Pixel coordinates per vertex (meaningful only where `codes` is 0).
    pub(super) pix: Vec<DVec2>,
    /// Per-vertex bit set of the clipping planes the vertex is outside of.
    pub(super) codes: Vec<u8>,
    /// Per-row x extent of the polygon being filled.
    pub(super) row_lo: Vec<f64>,
    pub(super) row_hi: Vec<f64>,
    /// Silhouette path: which faces face the light, the stamp of the sample that last
    /// projected each vertex, and the row crossings of the silhouette edges.
    pub(super) facing: Vec<bool>,
    pub(super) stamp: Vec<u32>,
    pub(super) sil_pix: Vec<DVec2>,
    pub(super) current: u32,
    /// Silhouette edges of the current mesh, and their crossings bucketed by row (a
    /// counting sort: `row_ends` holds each row's end in `crossings`).
    pub(super) sil_edges: Vec<SilEdge>,
    pub(super) row_ends: Vec<u32>,
    pub(super) crossings: Vec<(f64, i32)>,
}
