//! Scan conversion in pixel space and the triangle path: [`RasterScratch`], row filling,
//! polygon edges, triangles and convex polygons, the convex hull of a box's corners, and
//! [`ShadowCamera::rasterize_box`] / [`ShadowCamera::rasterize_triangles`].

use super::camera::{ShadowCamera, MAX_POLY};
use super::rows::{centre_span, fill_rows, Iv, RasterScratch};

use crate::shadow::mask::Mask;
use glam::{DQuat, DVec2, DVec3};

/// Outward-wound triangles of a box whose vertex `i` has local signs
/// `(bit 0, bit 1, bit 2)` of `i` for (x, y, z) (bit set = +half extent).
pub(super) const BOX_TRIANGLES: [[u32; 3]; 12] = [
    [4, 5, 7],
    [4, 7, 6], // +z
    [0, 2, 3],
    [0, 3, 1], // -z
    [1, 3, 7],
    [1, 7, 5], // +x
    [0, 4, 6],
    [0, 6, 2], // -x
    [2, 6, 7],
    [2, 7, 3], // +y
    [0, 1, 5],
    [0, 5, 4], // -y
];

impl ShadowCamera {
    /// OR the exact shadow of a solid box (centre, orientation, positive half extents)
    /// into `mask`. A light inside the box shadows every pixel.
    pub fn rasterize_box(
        &self,
        center: DVec3,
        rotation: DQuat,
        half_extents: DVec3,
        mask: &mut Mask,
        scratch: &mut RasterScratch,
    ) {
        self.check_mask(mask);
        if self.width_px == 0 || self.height_px == 0 {
            return;
        }
        let he = half_extents.abs();
        let local_light = rotation.conjugate() * (self.light - center);
        if local_light.abs().cmplt(he).all() {
            // Back-face culling below assumes the light is outside the solid.
            mask.fill_all();
            return;
        }
        let mut verts = [DVec3::ZERO; 8];
        let mut pix = [DVec2::ZERO; 8];
        let mut inside = true;
        for ((p, px), c) in verts
            .iter_mut()
            .zip(&mut pix)
            .zip(crate::geometry::shape::box_corners(he))
        {
            *p = center + rotation * c;
            let hv = self.homogeneous(*p);
            inside &= self.outcode(hv) == 0;
            *px = DVec2::new(hv.x, hv.y) / hv.z;
        }
        if inside {
            // The whole box is inside the slab and projects into the image: its shadow
            // is the convex hull of the projected corners, filled in one pass.
            let mut hull = [DVec2::ZERO; MAX_POLY];
            let n = convex_hull8(&mut pix, &mut hull);
            if n >= 3 {
                if scratch.row_lo.len() < self.height_px {
                    scratch.row_lo.resize(self.height_px, 0.0);
                    scratch.row_hi.resize(self.height_px, 0.0);
                }
                let hp = self.height_px as f64;
                fill_convex(
                    &hull[..n],
                    mask,
                    &mut scratch.row_lo,
                    &mut scratch.row_hi,
                    hp,
                );
            }
            return;
        }
        self.rasterize_triangles(&verts, &BOX_TRIANGLES, true, mask, scratch);
    }

    /// OR the shadow of a triangle mesh into `mask`: the union of the central projections
    /// of its triangles clipped to the slab. For a closed mesh this is the exact shadow of
    /// the solid it bounds, provided the light is outside that solid.
    ///
    /// With `closed_outward` (closed, consistently wound mesh with outward normals,
    /// counter-clockwise seen from outside) triangles facing away from the light are
    /// skipped: every segment from a light outside the solid that meets it enters it
    /// through a front face inside the slab, so the result is unchanged.
    pub fn rasterize_triangles(
        &self,
        world_vertices: &[DVec3],
        triangles: &[[u32; 3]],
        closed_outward: bool,
        mask: &mut Mask,
        scratch: &mut RasterScratch,
    ) {
        self.check_mask(mask);
        if self.width_px == 0 || self.height_px == 0 {
            return;
        }
        let hp = self.height_px as f64;
        let nv = world_vertices.len();
        scratch.hom.resize(nv, DVec3::ZERO);
        scratch.pix.resize(nv, DVec2::ZERO);
        scratch.codes.resize(nv, 0);
        if scratch.row_lo.len() < self.height_px {
            scratch.row_lo.resize(self.height_px, 0.0);
            scratch.row_hi.resize(self.height_px, 0.0);
        }
        // Transform every vertex once: homogeneous image coordinates and outcodes.
        for (i, p) in world_vertices.iter().enumerate() {
            let hv = self.homogeneous(*p);
            let code = self.outcode(hv);
            scratch.hom[i] = hv;
            scratch.codes[i] = code;
            if code == 0 {
                scratch.pix[i] = DVec2::new(hv.x, hv.y) / hv.z;
            }
        }
        let mut poly = [DVec2::ZERO; MAX_POLY];
        for tri in triangles {
            let [a, b, c] = tri.map(|i| i as usize);
            let (ca, cb, cc) = (scratch.codes[a], scratch.codes[b], scratch.codes[c]);
            if ca & cb & cc != 0 {
                // All three vertices outside one plane.
                continue;
            }
            let (ha, hb, hc) = (scratch.hom[a], scratch.hom[b], scratch.hom[c]);
            if ha.z >= self.h && hb.z >= self.h && hc.z >= self.h {
                // On or under the receiver: the open segments never reach it.
                continue;
            }
            if closed_outward {
                let (pa, pb, pc) = (world_vertices[a], world_vertices[b], world_vertices[c]);
                if (pb - pa).cross(pc - pa).dot(self.light - pa) <= 0.0 {
                    continue;
                }
            }
            if ca | cb | cc == 0 {
                fill_triangle([scratch.pix[a], scratch.pix[b], scratch.pix[c]], mask, hp);
                continue;
            }
            let count = self.clip_triangle([ha, hb, hc], ca | cb | cc, &mut poly);
            if count >= 3 {
                fill_convex(
                    &poly[..count],
                    mask,
                    &mut scratch.row_lo,
                    &mut scratch.row_hi,
                    hp,
                );
            }
        }
    }
}

/// A non-horizontal polygon edge, oriented from its lower-y end (ties broken by x) so
/// that every polygon sharing the edge computes bit-identical crossings: with closed
/// intervals, a pixel centre exactly on an edge shared by two triangles is then filled
/// by both, and meshes have no cracks.
#[derive(Clone, Copy)]
struct Edge {
    p: DVec2,
    slope: f64,
}

impl Edge {
    /// The edge between `a` and `b`, or `None` if it is horizontal (a horizontal edge
    /// adds nothing: its ends are crossings of the neighbouring edges).
    #[inline]
    fn new(a: DVec2, b: DVec2) -> Option<Edge> {
        let (p, q) = if (b.y, b.x) < (a.y, a.x) {
            (b, a)
        } else {
            (a, b)
        };
        if q.y > p.y {
            Some(Edge {
                p,
                slope: (q.x - p.x) / (q.y - p.y),
            })
        } else {
            None
        }
    }

    /// The x where the edge's line crosses the row centre line `y`.
    #[inline]
    fn x_at(&self, y: f64) -> f64 {
        self.p.x + (y - self.p.y) * self.slope
    }
}

/// Scan-convert a triangle given in pixel coordinates (the unclipped fast path of
/// [`fill_convex`], with the same crossings): per row whose centre line meets it, fill
/// the pixels whose centres lie in the closed x-interval between the edge crossings.
fn fill_triangle(v: [DVec2; 3], mask: &mut Mask, hp: f64) {
    let mut v = v;
    // Sort by (y, x) so that a -> b -> c runs down the image.
    let key = |p: DVec2| (p.y, p.x);
    if key(v[1]) < key(v[0]) {
        v.swap(0, 1);
    }
    if key(v[2]) < key(v[1]) {
        v.swap(1, 2);
        if key(v[1]) < key(v[0]) {
            v.swap(0, 1);
        }
    }
    let [a, b, c] = v;
    let Some(long) = Edge::new(a, c) else {
        return; // Zero height: no area.
    };
    let Some((j0, j1)) = centre_span(Iv::new(a.y, c.y), hp as usize) else {
        return;
    };
    // A horizontal short edge never supplies a crossing; NaN drops out of min and max.
    let nan = Edge {
        p: DVec2::NAN,
        slope: f64::NAN,
    };
    let upper = Edge::new(a, b).unwrap_or(nan);
    let lower = Edge::new(b, c).unwrap_or(nan);
    fill_rows(mask, j0, j1, |y| {
        let x = long.x_at(y);
        let xu = if y <= b.y { upper.x_at(y) } else { f64::NAN };
        let xl = if y >= b.y { lower.x_at(y) } else { f64::NAN };
        (x.min(xu).min(xl), x.max(xu).max(xl))
    });
}

/// Scan-convert a convex polygon given in pixel coordinates: for each row whose centre
/// line crosses it, fill the pixels whose centres lie in the closed x-interval between the
/// edge crossings. `lo` and `hi` are per-row scratch of at least `hp` entries.
fn fill_convex(poly: &[DVec2], mask: &mut Mask, lo: &mut [f64], hi: &mut [f64], hp: f64) {
    let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in poly {
        ymin = ymin.min(p.y);
        ymax = ymax.max(p.y);
    }
    let Some((j0, j1)) = centre_span(Iv::new(ymin, ymax), hp as usize) else {
        return;
    };
    lo[j0..=j1].fill(f64::INFINITY);
    hi[j0..=j1].fill(f64::NEG_INFINITY);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let Some(e) = Edge::new(a, b) else {
            continue;
        };
        let Some((ja, jb)) = centre_span(Iv::new(a.y.min(b.y), a.y.max(b.y)), hp as usize) else {
            continue;
        };
        let (a, b) = (ja.max(j0), jb.min(j1));
        if a > b {
            continue;
        }
        // Slices rather than indices: no bounds check per row, and the loop vectorises.
        for ((l, h), j) in lo[a..=b].iter_mut().zip(&mut hi[a..=b]).zip(a..) {
            let x = e.x_at(j as f64 + 0.5);
            *l = l.min(x);
            *h = h.max(x);
        }
    }
    fill_rows(mask, j0, j1, |y| {
        let j = y as usize;
        (lo[j], hi[j])
    });
}

/// Convex hull (Andrew's monotone chain) of at most eight points, written to `out`;
/// returns the hull's length. Collinear points are dropped.
fn convex_hull8(pts: &mut [DVec2; 8], out: &mut [DVec2; MAX_POLY]) -> usize {
    // Insertion sort by (x, y): eight elements, no allocation.
    for i in 1..8 {
        let mut k = i;
        while k > 0 && (pts[k].x, pts[k].y) < (pts[k - 1].x, pts[k - 1].y) {
            pts.swap(k, k - 1);
            k -= 1;
        }
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    // out[..n] holds the chain under construction; a hull of 8 points has at most 8
    // vertices plus the repeated start, within MAX_POLY.
    let mut n = 0;
    for &p in pts.iter() {
        while n >= 2 && cross(out[n - 2], out[n - 1], p) <= 0.0 {
            n -= 1;
        }
        out[n] = p;
        n += 1;
    }
    let lower = n + 1;
    for &p in pts.iter().rev().skip(1) {
        while n >= lower && cross(out[n - 2], out[n - 1], p) <= 0.0 {
            n -= 1;
        }
        out[n] = p;
        n += 1;
    }
    n - 1 // The last point repeats the first.
}
