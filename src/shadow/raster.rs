//! Exact shadow rasterization of spheres, boxes and triangle meshes under a point light.
//!
//! [`ShadowCamera`] describes the receiver plane, the image rectangle on it and the point
//! light; [`ShadowCamera::new`] precomputes everything the hot loops need. The
//! `rasterize_*` methods OR an object's shadow into a [`Mask`] (they never clear it), and
//! [`RasterScratch`] carries the reusable buffers of the mesh path so that nothing is
//! allocated per call once it has warmed up. Typical use per candidate: `mask.clear()`,
//! then one `rasterize_*` call per object, then the energies read the mask.
//!
//! Pixel convention: pixel coordinates `px` in `[0, width_px]` run from the left edge,
//! `py` in `[0, height_px]` from the top edge. Pixel `(i, j)` is shadow iff its centre
//! `(i + 0.5, j + 0.5)` is in shadow. The point `X` on the receiver plane is in shadow iff
//! the open segment from the light to `X` meets the object's closed solid. Every such
//! segment lies strictly between the receiver plane and the plane through the light
//! parallel to it (the "slab"), so only the part of an object inside the slab casts a
//! shadow: geometry under the receiver or behind the light casts nothing, and a body
//! straddling either plane casts exactly the central projection of its part in the slab.
//!
//! Spheres are solved in closed form per pixel row (no tessellation). Triangles are
//! clipped with Sutherland–Hodgman in homogeneous image coordinates (the slab planes and
//! the four planes through the light and the image edges), then scan-converted per row.

use crate::shadow::mask::Mask;
use glam::{DQuat, DVec2, DVec3};

/// The receiver plane, its image rectangle and the point light. Construct with
/// [`ShadowCamera::new`]; the public fields are for reading (changing them does not update
/// the precomputed values, build a new camera instead).
#[derive(Clone, Debug)]
pub struct ShadowCamera {
    /// Point light (world).
    pub light: DVec3,
    /// Centre of the image rectangle on the receiver plane.
    pub center: DVec3,
    /// Unit in-plane direction of increasing pixel x (image right).
    pub u: DVec3,
    /// Unit in-plane direction perpendicular to `u`: image up (decreasing pixel y).
    pub v: DVec3,
    /// Rectangle size in metres.
    pub width_m: f64,
    pub height_m: f64,
    /// Image size in pixels.
    pub width_px: usize,
    pub height_px: usize,

    /// Unit normal of the receiver on the light's side.
    n: DVec3,
    /// Height of the light above the receiver (> 0).
    h: f64,
    /// World position of pixel coordinate (0, 0) (top-left corner of the image).
    origin: DVec3,
    /// World step per unit of pixel x and of pixel y (`dv` points down the image).
    du: DVec3,
    dv: DVec3,
    /// Homogeneous projection: for `q = p - light`, `(q.ex, q.ey, q.ez)` is
    /// `(px * depth, py * depth, depth)` with `depth = -q.n` the distance of `p` in front of
    /// the light plane. The map is linear in `p`, so clipping can interpolate it directly.
    ex: DVec3,
    ey: DVec3,
    ez: DVec3,
    /// Depth of the near clipping plane, a hair in front of the light.
    near: f64,
}

/// Reusable buffers for [`ShadowCamera::rasterize_triangles`] and
/// [`ShadowCamera::rasterize_box`]. They grow to the largest mesh and image seen, then
/// are reused without allocating.
#[derive(Clone, Debug, Default)]
pub struct RasterScratch {
    /// Homogeneous image coordinates `(px * depth, py * depth, depth)` per vertex.
    hom: Vec<DVec3>,
    /// Pixel coordinates per vertex (meaningful only where `codes` is 0).
    pix: Vec<DVec2>,
    /// Per-vertex bit set of the clipping planes the vertex is outside of.
    codes: Vec<u8>,
    /// Per-row x extent of the polygon being filled.
    row_lo: Vec<f64>,
    row_hi: Vec<f64>,
    /// Silhouette path: which faces face the light, the stamp of the sample that last
    /// projected each vertex, and the row crossings of the silhouette edges.
    facing: Vec<bool>,
    stamp: Vec<u32>,
    sil_pix: Vec<DVec2>,
    current: u32,
    /// Silhouette edges of the current mesh, and their crossings bucketed by row (a
    /// counting sort: `row_start` holds each row's first slot in `crossings`).
    sil_edges: Vec<SilEdge>,
    row_start: Vec<u32>,
    crossings: Vec<(f64, i32)>,
}

/// A silhouette edge in pixel space: its upper end, slope dx/dy, the rows whose centre
/// lines it crosses, and its winding direction.
#[derive(Clone, Copy, Debug)]
struct SilEdge {
    top: DVec2,
    slope: f64,
    j0: u32,
    j1: u32,
    dir: i32,
}

/// What the silhouette path precomputes for a closed, consistently oriented mesh: one
/// plane per triangle and, for every edge, its two faces.
///
/// Why it is exact: seen from a light outside the solid, every segment from the light
/// that meets the solid enters it through a front face, and the front faces project
/// with one orientation. Their projections' winding numbers add up to the number of
/// front faces over a point, so the shadow is where that sum is non-zero; and the sum's
/// boundary is made of the silhouette edges only (an edge between two front faces is
/// crossed once in each direction and cancels). Filling the silhouette polygons with
/// the non-zero rule therefore gives the union of the front faces' projections, which is
/// the exact shadow, from a few dozen edges instead of hundreds of triangles.
#[derive(Clone, Debug)]
pub struct MeshSilhouette {
    /// Per triangle: unnormalised outward normal and its offset (`n . x = d` on the plane).
    planes: Vec<(DVec3, f64)>,
    /// Per edge: vertices `(a, b)`, the face where it runs `a -> b`, and the other face.
    edges: Vec<[u32; 4]>,
    /// Radius of a sphere about the body origin holding every vertex.
    radius: f64,
}

impl MeshSilhouette {
    /// The silhouette data of a mesh, or `None` unless every directed edge occurs exactly
    /// once and its reverse exactly once (closed, consistently oriented, manifold).
    pub fn new(vertices: &[DVec3], triangles: &[[u32; 3]]) -> Option<MeshSilhouette> {
        use std::collections::HashMap;
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a == b || directed.insert((a, b), f as u32).is_some() {
                    return None;
                }
            }
        }
        let mut edges = Vec::with_capacity(directed.len() / 2);
        for (&(a, b), &f) in &directed {
            let g = *directed.get(&(b, a))?;
            if a < b {
                edges.push([a, b, f, g]);
            }
        }
        // A fixed order keeps the crossings (and so the result) independent of hashing.
        edges.sort_unstable();
        let planes = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                let n = (b - a).cross(c - a);
                (n, n.dot(a))
            })
            .collect();
        let radius = vertices.iter().map(|v| v.length()).fold(0.0, f64::max);
        Some(MeshSilhouette {
            planes,
            edges,
            radius,
        })
    }
}

/// A closed interval `[lo, hi]`; empty when `!(lo <= hi)` (this also catches NaN).
#[derive(Clone, Copy, Debug)]
struct Iv {
    lo: f64,
    hi: f64,
}

impl Iv {
    const EMPTY: Iv = Iv {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
    };
    const ALL: Iv = Iv {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    fn new(lo: f64, hi: f64) -> Iv {
        Iv { lo, hi }
    }

    fn is_empty(self) -> bool {
        // Written with partial_cmp so that NaN bounds count as empty.
        !matches!(
            self.lo.partial_cmp(&self.hi),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        )
    }

    fn meet(self, o: Iv) -> Iv {
        Iv::new(self.lo.max(o.lo), self.hi.min(o.hi))
    }

    /// The smallest interval containing both; used to merge pieces whose union is known
    /// to be an interval (the shadow of a convex body on a line is convex).
    fn hull(self, o: Iv) -> Iv {
        match (self.is_empty(), o.is_empty()) {
            (true, _) => o,
            (_, true) => self,
            _ => Iv::new(self.lo.min(o.lo), self.hi.max(o.hi)),
        }
    }
}

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

/// Pixel indices `i` with centre `i + 0.5` in `iv`, clamped to `0..n`.
#[inline]
fn centre_span(iv: Iv, n: usize) -> Option<(usize, usize)> {
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

/// Outward-wound triangles of a box whose vertex `i` has local signs
/// `(bit 0, bit 1, bit 2)` of `i` for (x, y, z) (bit set = +half extent).
const BOX_TRIANGLES: [[u32; 3]; 12] = [
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

/// Maximum vertex count of a triangle clipped by six planes (3 + 6), with headroom.
const MAX_POLY: usize = 12;

impl ShadowCamera {
    /// Build the camera. `u` and `v` must be unit and perpendicular (checked to 1e-6),
    /// and the light must be strictly off the receiver plane.
    #[allow(clippy::too_many_arguments)] // Mirrors the public fields one to one.
    pub fn new(
        light: DVec3,
        center: DVec3,
        u: DVec3,
        v: DVec3,
        width_m: f64,
        height_m: f64,
        width_px: usize,
        height_px: usize,
    ) -> ShadowCamera {
        assert!(
            (u.length() - 1.0).abs() < 1e-6
                && (v.length() - 1.0).abs() < 1e-6
                && u.dot(v).abs() < 1e-6,
            "u and v must be perpendicular unit vectors"
        );
        assert!(
            width_m > 0.0 && height_m > 0.0,
            "image rectangle must have positive size"
        );
        let mut n = u.cross(v).normalize();
        let mut h = (light - center).dot(n);
        if h < 0.0 {
            n = -n;
            h = -h;
        }
        assert!(h > 0.0, "the light must not lie on the receiver plane");
        let (wp, hp) = (width_px as f64, height_px as f64);
        let sx = wp / width_m; // pixels per metre
        let sy = hp / height_m;
        let du = u * (width_m / wp);
        let dv = -v * (height_m / hp);
        let origin = center - 0.5 * width_m * u + 0.5 * height_m * v;
        // For q = p - light and depth = -q.n: the plane point is light + q * h / depth, so
        // px * depth = (wp/2 + sx * lu) * depth + sx * h * q.u (and likewise for py).
        let lu = (light - center).dot(u);
        let lv = (light - center).dot(v);
        let kx = 0.5 * wp + sx * lu;
        let ky = 0.5 * hp - sy * lv;
        ShadowCamera {
            light,
            center,
            u,
            v,
            width_m,
            height_m,
            width_px,
            height_px,
            n,
            h,
            origin,
            du,
            dv,
            ex: -kx * n + (sx * h) * u,
            ey: -ky * n - (sy * h) * v,
            ez: -n,
            near: 1e-9 * h,
        }
    }

    /// Unit normal of the receiver plane, pointing to the light's side.
    pub fn normal(&self) -> DVec3 {
        self.n
    }

    /// Height of the light above the receiver plane.
    pub fn light_height(&self) -> f64 {
        self.h
    }

    /// Central projection of `p` from the light onto the receiver, in pixel coordinates.
    /// `None` if `p` is at or behind the plane through the light parallel to the receiver
    /// (the line from the light through `p` does not reach the receiver on `p`'s side).
    /// Points beyond the receiver still project.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let q = p - self.light;
        let depth = q.dot(self.ez);
        if depth > 0.0 {
            Some(DVec2::new(q.dot(self.ex), q.dot(self.ey)) / depth)
        } else {
            None
        }
    }

    /// World point of pixel coordinates `(px, py)` on the receiver plane.
    pub fn pixel_to_world(&self, px: f64, py: f64) -> DVec3 {
        self.center
            + (px / self.width_px as f64 - 0.5) * self.width_m * self.u
            + (0.5 - py / self.height_px as f64) * self.height_m * self.v
    }

    fn check_mask(&self, mask: &Mask) {
        assert!(
            mask.width() == self.width_px && mask.height() == self.height_px,
            "mask is {}x{}, camera is {}x{}",
            mask.width(),
            mask.height(),
            self.width_px,
            self.height_px
        );
    }

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

    /// OR the exact shadow of a closed mesh at pose `(p, q)` (body -> world: `x -> p + q x`)
    /// into `mask`, from its silhouette edges (see [`MeshSilhouette`]). Falls back to
    /// [`ShadowCamera::rasterize_triangles`] when the mesh is not entirely inside the slab
    /// or the light is near it; `world_vertices` is the caller's buffer for that.
    #[allow(clippy::too_many_arguments)]
    pub fn rasterize_mesh(
        &self,
        p: DVec3,
        q: DQuat,
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
        sil: &MeshSilhouette,
        world_vertices: &mut Vec<DVec3>,
        mask: &mut Mask,
        scratch: &mut RasterScratch,
    ) {
        self.check_mask(mask);
        if self.width_px == 0 || self.height_px == 0 {
            return;
        }
        let depth = self.h - (p - self.center).dot(self.n);
        let margin = sil.radius * (1.0 + 1e-9) + 1e-9;
        let light_local = q.conjugate() * (self.light - p);
        if !(depth - margin > self.near && depth + margin < self.h)
            || light_local.length() <= margin
        {
            world_vertices.clear();
            world_vertices.extend(vertices.iter().map(|v| p + q * *v));
            self.rasterize_triangles(world_vertices, triangles, true, mask, scratch);
            return;
        }
        let nv = vertices.len();
        scratch.facing.clear();
        scratch
            .facing
            .extend(sil.planes.iter().map(|(n, d)| n.dot(light_local) > *d));
        if scratch.stamp.len() < nv {
            scratch.stamp.resize(nv, 0);
            scratch.sil_pix.resize(nv, DVec2::ZERO);
        }
        scratch.current = scratch.current.wrapping_add(1);
        if scratch.current == 0 {
            scratch.stamp.iter_mut().for_each(|s| *s = 0);
            scratch.current = 1;
        }
        let stamp = scratch.current;
        scratch.sil_edges.clear();
        let hp = self.height_px as f64;
        let (mut row_min, mut row_max) = (u32::MAX, 0u32);
        for &[a, b, f, g] in &sil.edges {
            let (ff, fg) = (scratch.facing[f as usize], scratch.facing[g as usize]);
            if ff == fg {
                continue;
            }
            // Oriented as its front face runs it.
            let (a, b) = if ff { (a, b) } else { (b, a) };
            for v in [a, b] {
                let v = v as usize;
                if scratch.stamp[v] != stamp {
                    scratch.stamp[v] = stamp;
                    let hv = self.homogeneous(p + q * vertices[v]);
                    scratch.sil_pix[v] = DVec2::new(hv.x, hv.y) / hv.z;
                }
            }
            let (pa, pb) = (scratch.sil_pix[a as usize], scratch.sil_pix[b as usize]);
            let (top, bot, dir) = if pa.y < pb.y {
                (pa, pb, 1)
            } else if pb.y < pa.y {
                (pb, pa, -1)
            } else {
                continue; // horizontal (or NaN): no row centre crosses it
            };
            // Rows whose centre line y = j + 0.5 lies in [top.y, bot.y).
            let j0 = (top.y - 0.5).ceil().max(0.0);
            let j1 = ((bot.y - 0.5).ceil() - 1.0).min(hp - 1.0);
            // NaN ends (a degenerate projection) fail this too.
            if j0
                .partial_cmp(&j1)
                .is_none_or(|o| o == std::cmp::Ordering::Greater)
            {
                continue;
            }
            let (j0, j1) = (j0 as u32, j1 as u32);
            row_min = row_min.min(j0);
            row_max = row_max.max(j1);
            scratch.sil_edges.push(SilEdge {
                top,
                slope: (bot.x - top.x) / (bot.y - top.y),
                j0,
                j1,
                dir,
            });
        }
        if scratch.sil_edges.is_empty() {
            return;
        }
        // Counting sort of the crossings by row.
        let (r0, r1) = (row_min as usize, row_max as usize);
        let rows = r1 - r0 + 1;
        scratch.row_start.clear();
        scratch.row_start.resize(rows + 1, 0);
        for e in &scratch.sil_edges {
            for j in e.j0..=e.j1 {
                scratch.row_start[j as usize - r0 + 1] += 1;
            }
        }
        for k in 0..rows {
            scratch.row_start[k + 1] += scratch.row_start[k];
        }
        let total = scratch.row_start[rows] as usize;
        scratch.crossings.clear();
        scratch.crossings.resize(total, (0.0, 0));
        // `row_start[k]` serves as the fill cursor of row k, then is restored.
        for e in &scratch.sil_edges {
            for j in e.j0..=e.j1 {
                let k = j as usize - r0;
                let slot = scratch.row_start[k] as usize;
                scratch.row_start[k] += 1;
                let x = e.top.x + (j as f64 + 0.5 - e.top.y) * e.slope;
                scratch.crossings[slot] = (x, e.dir);
            }
        }
        for k in (1..=rows).rev() {
            scratch.row_start[k] = scratch.row_start[k - 1];
        }
        scratch.row_start[0] = 0;
        let last = (self.width_px - 1) as f64;
        for k in 0..rows {
            let (a, b) = (
                scratch.row_start[k] as usize,
                scratch.row_start[k + 1] as usize,
            );
            let row = &mut scratch.crossings[a..b];
            // Rows hold a handful of crossings: insertion sort by x.
            for i in 1..row.len() {
                let mut j = i;
                while j > 0 && row[j - 1].0 > row[j].0 {
                    row.swap(j - 1, j);
                    j -= 1;
                }
            }
            let mut winding = 0;
            let mut enter = 0.0;
            for &(x, dir) in row.iter() {
                let before = winding;
                winding += dir;
                if before == 0 && winding != 0 {
                    enter = x;
                } else if before != 0 && winding == 0 {
                    let (lo, hi) = ((enter - 0.5).ceil().max(0.0), (x - 0.5).floor().min(last));
                    if lo <= hi {
                        mask.fill_span(r0 + k, lo as usize, hi as usize);
                    }
                }
            }
        }
    }

    /// Homogeneous image coordinates `(px * depth, py * depth, depth)` of a world point.
    #[inline]
    fn homogeneous(&self, p: DVec3) -> DVec3 {
        let q = p - self.light;
        DVec3::new(q.dot(self.ex), q.dot(self.ey), q.dot(self.ez))
    }

    /// Bit set of the clipping planes that the homogeneous point is strictly outside of.
    #[inline]
    fn outcode(&self, p: DVec3) -> u8 {
        let (wp, hp) = (self.width_px as f64, self.height_px as f64);
        let mut c = 0;
        for (bit, value) in self.plane_values(p, wp, hp).into_iter().enumerate() {
            if value < 0.0 {
                c |= 1 << bit;
            }
        }
        c
    }

    /// Signed values of the six clipping planes (>= 0 inside), in bit order: near,
    /// receiver, left, right, top, bottom. All are affine in the homogeneous point.
    #[inline]
    fn plane_values(&self, p: DVec3, wp: f64, hp: f64) -> [f64; 6] {
        [
            p.z - self.near,
            self.h - p.z,
            p.x,
            wp * p.z - p.x,
            p.y,
            hp * p.z - p.y,
        ]
    }

    /// Sutherland–Hodgman clip of a triangle in homogeneous coordinates against the planes
    /// in `planes`; writes the pixel coordinates of the result and returns its length.
    fn clip_triangle(&self, tri: [DVec3; 3], planes: u8, out: &mut [DVec2; MAX_POLY]) -> usize {
        let (wp, hp) = (self.width_px as f64, self.height_px as f64);
        let mut a = [DVec3::ZERO; MAX_POLY];
        let mut b = [DVec3::ZERO; MAX_POLY];
        a[..3].copy_from_slice(&tri);
        let mut n = 3;
        for bit in 0..6 {
            if planes & (1 << bit) == 0 {
                continue;
            }
            let mut m = 0;
            for i in 0..n {
                let (p, q) = (a[i], a[(i + 1) % n]);
                let fp = self.plane_values(p, wp, hp)[bit];
                let fq = self.plane_values(q, wp, hp)[bit];
                if fp >= 0.0 {
                    b[m] = p;
                    m += 1;
                }
                if (fp >= 0.0) != (fq >= 0.0) {
                    b[m] = p + (q - p) * (fp / (fp - fq));
                    m += 1;
                }
            }
            n = m;
            a = b;
            if n < 3 {
                return 0;
            }
        }
        for (o, p) in out.iter_mut().zip(&a[..n]) {
            *o = DVec2::new(p.x, p.y) / p.z;
        }
        n
    }
}

/// Fill rows `j0..=j1`: `span(y)` gives the closed x-interval of row centre line `y`
/// (NaN or `lo > hi` for none), and the pixels whose centres lie in it are set.
///
/// Rows are processed in blocks: a branch-free pass evaluates `span` and rounds to pixel
/// indices for a whole block (the compiler vectorises it, two rows per instruction), then
/// a second pass fills the spans. This halves the cost per row compared with one loop.
#[inline(always)]
fn fill_rows(mask: &mut Mask, j0: usize, j1: usize, span: impl Fn(f64) -> (f64, f64)) {
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
        for j in ja.max(j0)..=jb.min(j1) {
            let x = e.x_at(j as f64 + 0.5);
            lo[j] = lo[j].min(x);
            hi[j] = hi[j].max(x);
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// SplitMix64, so the tests need no dependencies.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
        }
        fn rotation(&mut self) -> DQuat {
            let q = DQuat::from_xyzw(
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
            );
            q.normalize()
        }
    }

    /// The project's reference set-up: light 6 m above the floor, 4 m x 3 m image.
    fn standard_camera(w: usize, h: usize) -> ShadowCamera {
        ShadowCamera::new(
            DVec3::new(0.0, 0.0, 6.0),
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            4.0,
            3.0,
            w,
            h,
        )
    }

    /// A randomly placed and tilted receiver. Returns the camera and the rotation that maps
    /// the camera's local frame (x = u, y = v, z = normal) to the world.
    fn random_camera(rng: &mut Rng, w: usize, h: usize) -> (ShadowCamera, DQuat) {
        let rot = rng.rotation();
        let c = DVec3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let height = rng.uniform(2.0, 8.0);
        let light = c + rot * DVec3::new(rng.uniform(-1.5, 1.5), rng.uniform(-1.0, 1.0), height);
        (
            ShadowCamera::new(light, c, rot * DVec3::X, rot * DVec3::Y, 4.0, 3.0, w, h),
            rot,
        )
    }

    /// Reference: does the segment from the light to `x` meet the ball? (Closest point.)
    fn segment_hits_ball(light: DVec3, x: DVec3, s: DVec3, r: f64) -> bool {
        let d = x - light;
        let t = ((s - light).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        (light + t * d).distance_squared(s) <= r * r
    }

    /// Reference: does the segment from the light to `x` meet the box? (Slab test.)
    fn segment_hits_box(light: DVec3, x: DVec3, c: DVec3, rot: DQuat, he: DVec3) -> bool {
        let inv = rot.conjugate();
        let o = inv * (light - c);
        let d = inv * (x - light);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for i in 0..3 {
            if d[i].abs() < 1e-300 {
                if o[i].abs() > he[i] {
                    return false;
                }
            } else {
                let (a, b) = ((-he[i] - o[i]) / d[i], (he[i] - o[i]) / d[i]);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        t0 <= t1
    }

    /// Compare a mask with a per-pixel reference predicate on world points. A mismatch is
    /// tolerated only if the reference itself changes within 1e-9 m of the pixel centre
    /// (the centre is on the boundary up to rounding). Returns the number tolerated.
    fn compare(cam: &ShadowCamera, mask: &Mask, what: &str, f: impl Fn(DVec3) -> bool) -> usize {
        let eps = 1e-9;
        let mut tolerated = 0;
        for j in 0..cam.height_px {
            for i in 0..cam.width_px {
                let x = cam.pixel_to_world(i as f64 + 0.5, j as f64 + 0.5);
                let want = f(x);
                if mask.get(i, j) == want {
                    continue;
                }
                let near = [cam.u * eps, -cam.u * eps, cam.v * eps, -cam.v * eps];
                assert!(
                    near.iter().any(|&e| f(x + e) != want),
                    "{what}: pixel ({i}, {j}) is {} but the reference says {want}",
                    mask.get(i, j)
                );
                tolerated += 1;
                if std::env::var("DBG").is_ok() {
                    eprintln!("{what}: tolerated ({i},{j}) mask {}", mask.get(i, j));
                }
            }
        }
        tolerated
    }

    /// A closed UV sphere with outward-wound triangles: 16 slices x 16 stacks = 480.
    fn uv_sphere(c: DVec3, r: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let (stacks, slices) = (16u32, 16u32);
        let mut v = vec![c + DVec3::new(0.0, 0.0, r)];
        for i in 1..stacks {
            let th = PI * i as f64 / stacks as f64;
            for k in 0..slices {
                let ph = 2.0 * PI * k as f64 / slices as f64;
                v.push(c + r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
            }
        }
        v.push(c - DVec3::new(0.0, 0.0, r));
        let bottom = v.len() as u32 - 1;
        let ring = |i: u32, k: u32| 1 + i * slices + k % slices;
        let mut t = Vec::new();
        for k in 0..slices {
            t.push([0, ring(0, k), ring(0, k + 1)]);
            t.push([bottom, ring(stacks - 2, k + 1), ring(stacks - 2, k)]);
            for i in 0..stacks - 2 {
                t.push([ring(i, k), ring(i + 1, k), ring(i + 1, k + 1)]);
                t.push([ring(i, k), ring(i + 1, k + 1), ring(i, k + 1)]);
            }
        }
        // Orient every triangle outward (the mesh is convex around c).
        for tri in &mut t {
            let [a, b, cc] = tri.map(|i| v[i as usize]);
            if (b - a).cross(cc - a).dot((a + b + cc) / 3.0 - c) < 0.0 {
                tri.swap(1, 2);
            }
        }
        (v, t)
    }

    #[test]
    fn project_and_pixel_to_world_round_trip() {
        let mut rng = Rng(11);
        for _ in 0..20 {
            let (cam, _) = random_camera(&mut rng, 320, 240);
            for _ in 0..10 {
                let (px, py) = (rng.uniform(-50.0, 400.0), rng.uniform(-50.0, 300.0));
                let x = cam.pixel_to_world(px, py);
                assert!((x - cam.center).dot(cam.normal()).abs() < 1e-12);
                // Any point on the ray from the light through x in front of the light
                // projects to (px, py), including points beyond the receiver.
                for t in [0.1, 0.5, 1.0, 1.7] {
                    let p = cam.project(cam.light + t * (x - cam.light)).unwrap();
                    assert!(p.distance(DVec2::new(px, py)) < 1e-7, "{p} vs ({px}, {py})");
                }
                assert_eq!(cam.project(cam.light - 0.5 * (x - cam.light)), None);
            }
            assert_eq!(cam.project(cam.light), None);
        }
        let cam = standard_camera(640, 480);
        assert_eq!(cam.pixel_to_world(0.0, 0.0), DVec3::new(-2.0, 1.5, 0.0));
        assert_eq!(cam.pixel_to_world(640.0, 480.0), DVec3::new(2.0, -1.5, 0.0));
        assert_eq!(
            cam.project(DVec3::new(0.0, 0.0, 3.0)),
            Some(DVec2::new(320.0, 240.0))
        );
        assert_eq!(cam.light_height(), 6.0);
    }

    /// Area of the ellipse in which the cone from the light around a ball (entirely below
    /// the light plane) meets the receiver. With w = S - L, k = |w|^2 - r^2, h the light
    /// height and w_n = w.n, the cone is (w.d)^2 >= k |d|^2; writing it as the conic
    /// x^T A x + 2 b.x + c <= 0 in plane coordinates gives det A = k (w_n^2 - r^2) and
    /// det of the 3x3 matrix = -k^2 h^2 r^2, hence
    /// area = pi (-det M) / (det A)^(3/2) = pi h^2 r^2 sqrt(k) / (w_n^2 - r^2)^(3/2).
    /// (For a ball straight below the light this is pi h^2 r^2 / k = pi (h tan a)^2.)
    fn analytic_shadow_area(cam: &ShadowCamera, s: DVec3, r: f64) -> f64 {
        let w = s - cam.light;
        let k = w.length_squared() - r * r;
        let wn = w.dot(cam.normal());
        PI * cam.light_height().powi(2) * r * r * k.sqrt() / (wn * wn - r * r).powf(1.5)
    }

    #[test]
    fn sphere_shadow_area_matches_analytic_conic() {
        let cam = standard_camera(640, 480);
        let pixel_area = (4.0 / 640.0) * (3.0 / 480.0);
        let mut mask = Mask::new(640, 480);
        let cases = [
            (DVec3::new(0.0, 0.0, 2.0), 0.5),
            (DVec3::new(0.6, -0.3, 1.2), 0.5),
            (DVec3::new(-0.4, 0.25, 3.5), 0.3),
            (DVec3::new(1.2, 0.2, 0.6), 0.25),
        ];
        for (s, r) in cases {
            mask.clear();
            cam.rasterize_sphere(s, r, &mut mask);
            let area = mask.count() as f64 * pixel_area;
            let want = analytic_shadow_area(&cam, s, r);
            assert!(
                (area / want - 1.0).abs() < 0.005,
                "sphere {s} r {r}: {area} vs {want}"
            );
        }
        // The same on a tilted receiver, where rows are not aligned with anything.
        let rot = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.7);
        let c = DVec3::new(0.2, -0.1, 0.3);
        let cam = ShadowCamera::new(
            c + rot * DVec3::new(0.5, -0.3, 5.0),
            c,
            rot * DVec3::X,
            rot * DVec3::Y,
            4.0,
            3.0,
            640,
            480,
        );
        let s = c + rot * DVec3::new(-0.4, 0.3, 1.5);
        mask.clear();
        cam.rasterize_sphere(s, 0.6, &mut mask);
        let area = mask.count() as f64 * pixel_area;
        let want = analytic_shadow_area(&cam, s, 0.6);
        assert!(
            (area / want - 1.0).abs() < 0.005,
            "tilted: {area} vs {want}"
        );
    }

    #[test]
    fn nothing_behind_the_light_or_under_the_receiver() {
        let cam = standard_camera(320, 240);
        let mut mask = Mask::new(320, 240);
        let mut scratch = RasterScratch::default();
        let rot = DQuat::from_euler(glam::EulerRot::XYZ, 0.4, 0.9, -0.3);
        for c in [
            DVec3::new(0.3, 0.2, 7.0),
            DVec3::new(2.0, -1.0, 6.6),
            DVec3::new(0.1, 0.0, -0.8),
        ] {
            cam.rasterize_sphere(c, 0.5, &mut mask);
            cam.rasterize_box(c, rot, DVec3::new(0.3, 0.2, 0.25), &mut mask, &mut scratch);
            let (v, t) = uv_sphere(c, 0.5);
            cam.rasterize_triangles(&v, &t, false, &mut mask, &mut scratch);
        }
        // Tangent to either plane from outside the slab still casts nothing.
        cam.rasterize_sphere(DVec3::new(0.0, 0.0, -0.5), 0.5, &mut mask);
        cam.rasterize_sphere(DVec3::new(1.0, 0.0, 6.5), 0.5, &mut mask);
        cam.rasterize_box(
            DVec3::new(0.0, 0.0, -0.5),
            DQuat::IDENTITY,
            DVec3::splat(0.5),
            &mut mask,
            &mut scratch,
        );
        assert_eq!(mask.count(), 0);
        // The same objects in front of the light do cast shadows (the test can fail).
        cam.rasterize_sphere(DVec3::new(0.3, 0.2, 3.0), 0.5, &mut mask);
        cam.rasterize_box(
            DVec3::new(0.3, 0.2, 3.0),
            rot,
            DVec3::new(0.3, 0.2, 0.25),
            &mut mask,
            &mut scratch,
        );
        assert!(mask.count() > 1000);
    }

    #[test]
    fn light_inside_sphere_or_box_shadows_everything() {
        let cam = standard_camera(100, 75);
        let mut mask = Mask::new(100, 75);
        cam.rasterize_sphere(DVec3::new(0.1, 0.0, 6.2), 0.5, &mut mask);
        assert_eq!(mask.count(), 100 * 75);
        mask.clear();
        let mut scratch = RasterScratch::default();
        let rot = DQuat::from_rotation_z(0.5);
        cam.rasterize_box(
            DVec3::new(0.1, 0.0, 5.9),
            rot,
            DVec3::splat(0.3),
            &mut mask,
            &mut scratch,
        );
        assert_eq!(mask.count(), 100 * 75);
    }

    #[test]
    fn sphere_straddling_the_receiver_matches_brute_force() {
        let cam = standard_camera(640, 480);
        let mut mask = Mask::new(640, 480);
        for (s, r) in [
            (DVec3::new(0.3, 0.2, 0.2), 0.5),
            (DVec3::new(-0.5, 0.4, -0.4), 0.7),
        ] {
            mask.clear();
            cam.rasterize_sphere(s, r, &mut mask);
            let tol = compare(&cam, &mask, "straddling sphere", |x| {
                segment_hits_ball(cam.light, x, s, r)
            });
            assert!(tol <= 2, "{tol} boundary pixels");
            // With the centre under the receiver, the cone of the whole ball (what a
            // planar projection would draw) is clearly larger than the true shadow.
            let full = analytic_shadow_area(&cam, s, r) / ((4.0 / 640.0) * (3.0 / 480.0));
            if s.z < 0.0 {
                assert!(
                    (mask.count() as f64) < 0.9 * full,
                    "{} vs {full}",
                    mask.count()
                );
            }
        }
    }

    #[test]
    fn random_spheres_match_brute_force() {
        let mut rng = Rng(2024);
        let mut mask = Mask::new(160, 120);
        // Counts of: inside the slab, crossing the receiver, crossing the light plane,
        // outside the slab, light inside.
        let mut kinds = [0; 5];
        let mut nonempty = 0;
        let mut tolerated = 0;
        for case in 0..400 {
            let (cam, rot) = random_camera(&mut rng, 160, 120);
            let h = cam.light_height();
            let r = rng.uniform(0.05, 1.5);
            let local = if case % 4 == 0 {
                // Near the light, to exercise the light-plane crossing.
                DVec3::new(
                    rng.uniform(-2.0, 2.0),
                    rng.uniform(-2.0, 2.0),
                    h + rng.uniform(-r, r),
                )
            } else {
                DVec3::new(
                    rng.uniform(-2.5, 2.5),
                    rng.uniform(-2.0, 2.0),
                    rng.uniform(-1.0, h + 1.0),
                )
            };
            let s = cam.center + rot * local;
            let z = local.z;
            let kind = if s.distance(cam.light) < r {
                4
            } else if z - r >= h || z + r <= 0.0 {
                3
            } else if z + r > h {
                2
            } else if z - r < 0.0 {
                1
            } else {
                0
            };
            kinds[kind] += 1;
            mask.clear();
            cam.rasterize_sphere(s, r, &mut mask);
            nonempty += (mask.count() > 0) as usize;
            tolerated += compare(&cam, &mask, &format!("sphere case {case}"), |x| {
                segment_hits_ball(cam.light, x, s, r)
            });
        }
        assert!(kinds.iter().all(|&k| k >= 5), "categories {kinds:?}");
        assert!(nonempty > 120, "{nonempty}");
        eprintln!("sphere categories {kinds:?}, nonempty {nonempty}, tolerated {tolerated}");
        assert!(tolerated <= 5, "{tolerated}");
    }

    #[test]
    fn random_boxes_match_brute_force() {
        let mut rng = Rng(77);
        let mut mask = Mask::new(160, 120);
        let mut scratch = RasterScratch::default();
        let (mut straddle, mut nonempty, mut tolerated) = (0, 0, 0);
        for case in 0..300 {
            let (cam, frame) = random_camera(&mut rng, 160, 120);
            let h = cam.light_height();
            let he = DVec3::new(
                rng.uniform(0.05, 1.0),
                rng.uniform(0.05, 1.0),
                rng.uniform(0.05, 1.0),
            );
            let z = if case % 4 == 0 {
                h + rng.uniform(-1.0, 1.0)
            } else {
                rng.uniform(-1.0, h + 1.0)
            };
            let local = DVec3::new(rng.uniform(-2.5, 2.5), rng.uniform(-2.0, 2.0), z);
            let c = cam.center + frame * local;
            let rot = rng.rotation();
            let reach = he.length();
            straddle +=
                ((z - reach < 0.0 && z + reach > 0.0) || (z - reach < h && z + reach > h)) as usize;
            mask.clear();
            cam.rasterize_box(c, rot, he, &mut mask, &mut scratch);
            nonempty += (mask.count() > 0) as usize;
            tolerated += compare(&cam, &mask, &format!("box case {case}"), |x| {
                segment_hits_box(cam.light, x, c, rot, he)
            });
        }
        assert!(straddle > 60, "{straddle}");
        assert!(nonempty > 80, "{nonempty}");
        eprintln!("boxes straddling {straddle}, nonempty {nonempty}, tolerated {tolerated}");
        assert!(tolerated <= 5, "{tolerated}");
    }

    #[test]
    fn box_triangles_are_outward() {
        let verts: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    (i & 1) as f64 - 0.5,
                    ((i >> 1) & 1) as f64 - 0.5,
                    ((i >> 2) & 1) as f64 - 0.5,
                )
            })
            .collect();
        let mut volume = 0.0;
        for t in BOX_TRIANGLES {
            let [a, b, c] = t.map(|i| verts[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "triangle {t:?} faces inward");
            volume += a.dot(b.cross(c)) / 6.0;
        }
        assert!((volume - 1.0).abs() < 1e-12);
    }

    #[test]
    fn back_face_culling_is_exact_for_closed_meshes() {
        let mut rng = Rng(5);
        let mut scratch = RasterScratch::default();
        let (mut a, mut b) = (Mask::new(160, 120), Mask::new(160, 120));
        for case in 0..60 {
            let (cam, frame) = random_camera(&mut rng, 160, 120);
            let h = cam.light_height();
            // Inside the slab, straddling the receiver and straddling the light plane.
            let z = [
                rng.uniform(1.0, h - 1.0),
                rng.uniform(-0.3, 0.3),
                h + rng.uniform(-0.3, 0.3),
            ][case % 3];
            let c =
                cam.center + frame * DVec3::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), z);
            if c.distance(cam.light) < 0.8 {
                continue; // The light must be outside the solid.
            }
            let rot = rng.rotation();
            let he = DVec3::new(0.5, 0.3, 0.4);
            let verts: Vec<DVec3> = (0..8)
                .map(|i| {
                    let s = DVec3::new(
                        (i & 1) as f64 * 2.0 - 1.0,
                        ((i >> 1) & 1) as f64 * 2.0 - 1.0,
                        ((i >> 2) & 1) as f64 * 2.0 - 1.0,
                    );
                    c + rot * (s * he)
                })
                .collect();
            a.clear();
            b.clear();
            cam.rasterize_triangles(&verts, &BOX_TRIANGLES, true, &mut a, &mut scratch);
            cam.rasterize_triangles(&verts, &BOX_TRIANGLES, false, &mut b, &mut scratch);
            assert!(a.xor_count(&b) <= 2, "box case {case}: {}", a.xor_count(&b));
            compare(&cam, &a, "culled box", |x| {
                segment_hits_box(cam.light, x, c, rot, he)
            });
            // Culling with the winding reversed keeps only the back faces, which differ
            // from the shadow as soon as the receiver or light plane cuts the box.
            let flipped: Vec<[u32; 3]> = BOX_TRIANGLES.iter().map(|t| [t[0], t[2], t[1]]).collect();
            if case % 3 == 1 && a.count() > 0 {
                b.clear();
                cam.rasterize_triangles(&verts, &flipped, true, &mut b, &mut scratch);
                assert!(
                    a.xor_count(&b) > 0,
                    "case {case}: wrong winding went unnoticed"
                );
            }
            let (v, t) = uv_sphere(c, 0.5);
            a.clear();
            b.clear();
            cam.rasterize_triangles(&v, &t, true, &mut a, &mut scratch);
            cam.rasterize_triangles(&v, &t, false, &mut b, &mut scratch);
            assert!(
                a.xor_count(&b) <= 2,
                "mesh case {case}: {}",
                a.xor_count(&b)
            );
        }
    }

    #[test]
    fn inscribed_mesh_shadow_is_inside_the_sphere_shadow() {
        let cam = standard_camera(640, 480);
        let mut scratch = RasterScratch::default();
        let (mut mesh, mut ball) = (Mask::new(640, 480), Mask::new(640, 480));
        for c in [DVec3::new(0.4, -0.2, 1.5), DVec3::new(-0.3, 0.1, 0.2)] {
            mesh.clear();
            ball.clear();
            let (v, t) = uv_sphere(c, 0.5);
            cam.rasterize_triangles(&v, &t, true, &mut mesh, &mut scratch);
            cam.rasterize_sphere(c, 0.5, &mut ball);
            assert_eq!(mesh.and_not_count(&ball), 0);
            assert!(mesh.count() as f64 > 0.95 * ball.count() as f64);
        }
    }

    #[test]
    fn triangle_fill_has_no_cracks_and_clips_huge_coordinates() {
        let cam = standard_camera(160, 120);
        let mut scratch = RasterScratch::default();
        let mut mask = Mask::new(160, 120);
        // A quad lying in a plane parallel to the receiver, split along a diagonal that
        // passes exactly through pixel centres (its projection covers the whole image
        // twice over): every pixel must be set.
        let z = 3.0; // projection scale 2
        let q = [
            DVec3::new(-1.5, -1.0, z),
            DVec3::new(1.5, -1.0, z),
            DVec3::new(1.5, 1.0, z),
            DVec3::new(-1.5, 1.0, z),
        ];
        cam.rasterize_triangles(&q, &[[0, 1, 2], [0, 2, 3]], false, &mut mask, &mut scratch);
        assert_eq!(mask.count(), 160 * 120);
        // A triangle reaching almost to the light plane projects to enormous coordinates
        // yet fills exactly the brute-force set.
        mask.clear();
        let t = [
            DVec3::new(-0.5, -0.3, 1.0),
            DVec3::new(0.7, -0.2, 2.0),
            DVec3::new(0.1, 0.4, 6.0 - 1e-7),
        ];
        cam.rasterize_triangles(&t, &[[0, 1, 2]], false, &mut mask, &mut scratch);
        assert!(mask.count() > 0);
        let hits = |x: DVec3| {
            // Segment-triangle test (Moller-Trumbore) as the reference.
            let (o, d) = (cam.light, x - cam.light);
            let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
            let p = d.cross(e2);
            let det = e1.dot(p);
            let s = o - t[0];
            let a = s.dot(p) / det;
            let qv = s.cross(e1);
            let b = d.dot(qv) / det;
            let tt = e2.dot(qv) / det;
            a >= 0.0 && b >= 0.0 && a + b <= 1.0 && tt > 0.0 && tt < 1.0
        };
        compare(&cam, &mask, "thin triangle", hits);
    }

    /// Timing report; run with
    /// `cargo test --release raster::tests::timing -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timing() {
        use std::hint::black_box;
        use std::time::Instant;
        let cam = standard_camera(640, 480);
        let mut mask = Mask::new(640, 480);
        let mut scratch = RasterScratch::default();
        // The machine's speed drifts, so report the best and the median of 30 batches.
        let time = |name: &str, n: usize, f: &mut dyn FnMut()| {
            let mut per_call: Vec<f64> = (0..30)
                .map(|_| {
                    let t = Instant::now();
                    for _ in 0..n / 30 {
                        f();
                    }
                    t.elapsed().as_secs_f64() / (n / 30) as f64 * 1e6
                })
                .collect();
            per_call.sort_by(f64::total_cmp);
            println!(
                "{name:<44} best {:8.3} us   median {:8.3} us",
                per_call[0], per_call[15]
            );
        };
        let spheres = [
            (DVec3::new(-1.0, 0.5, 1.0), 0.5),
            (DVec3::new(0.8, -0.3, 1.5), 0.5),
            (DVec3::new(0.2, 0.6, 0.7), 0.5),
        ];
        time("clear + 3 spheres r=0.5 (in slab)", 20_000, &mut || {
            mask.clear();
            for (c, r) in spheres {
                cam.rasterize_sphere(black_box(c), r, &mut mask);
            }
        });
        println!("  (shadow pixels: {})", mask.count());
        time(
            "clear + 3 spheres straddling the receiver",
            20_000,
            &mut || {
                mask.clear();
                for (c, r) in spheres {
                    cam.rasterize_sphere(
                        black_box(c * DVec3::new(1.0, 1.0, 0.0) + DVec3::Z * 0.2),
                        r,
                        &mut mask,
                    );
                }
            },
        );
        time("clear + 3 boxes 0.8 m (rotated)", 20_000, &mut || {
            mask.clear();
            for (i, (c, _)) in spheres.iter().enumerate() {
                let rot = DQuat::from_euler(glam::EulerRot::XYZ, 0.3 * i as f64, 0.5, 0.2);
                cam.rasterize_box(
                    black_box(*c),
                    rot,
                    DVec3::splat(0.4),
                    &mut mask,
                    &mut scratch,
                );
            }
        });
        let (v, t) = uv_sphere(DVec3::new(0.2, -0.1, 1.2), 0.5);
        time(
            &format!("clear + {}-triangle closed mesh (culled)", t.len()),
            5_000,
            &mut || {
                mask.clear();
                cam.rasterize_triangles(black_box(&v), &t, true, &mut mask, &mut scratch);
            },
        );
        time(
            &format!("clear + {}-triangle mesh (no culling)", t.len()),
            5_000,
            &mut || {
                mask.clear();
                cam.rasterize_triangles(black_box(&v), &t, false, &mut mask, &mut scratch);
            },
        );
        mask.clear();
        for (c, r) in spheres {
            cam.rasterize_sphere(c, r, &mut mask);
        }
        let mut other = Mask::new(640, 480);
        cam.rasterize_sphere(DVec3::new(0.0, 0.0, 2.0), 1.0, &mut other);
        let mut sink = 0u64;
        time("xor_count (shadow vs target)", 50_000, &mut || {
            sink += black_box(&mask).xor_count(black_box(&other))
        });
        time("moments (3-sphere shadow)", 50_000, &mut || {
            sink += black_box(&mask).moments().count as u64
        });
        println!("  (checksum {sink})");
    }

    /// The silhouette path must give the same pixels as filling every front face, for
    /// the chess pieces (curved, many near-silhouette faces) at random poses, including
    /// poses that straddle the receiver or the light plane (where it falls back).
    #[test]
    fn silhouette_fill_matches_the_triangle_fill_on_chess_pieces() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/thinker/pieces");
        let cam = ShadowCamera::new(
            DVec3::new(0.0, 0.0, 3.0),
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            0.96,
            0.72,
            640,
            480,
        );
        let mut rng = Rng(11);
        let mut scratch = RasterScratch::default();
        let mut world = Vec::new();
        let (mut a, mut b) = (Mask::new(640, 480), Mask::new(640, 480));
        let mut compared = 0u64;
        for piece in ["pawn", "rook", "knight", "bishop", "queen", "king"] {
            let mesh = crate::geometry::shape::load_obj(&dir.join(format!("{piece}.obj")), 1.0)
                .expect("piece");
            let sil =
                MeshSilhouette::new(&mesh.vertices, &mesh.triangles).expect("closed, oriented");
            for k in 0..40 {
                // Mostly inside the slab, some across the receiver (z near 0) or the light.
                let z = match k % 8 {
                    0 => rng.uniform(-0.05, 0.05),
                    1 => rng.uniform(2.95, 3.05),
                    _ => rng.uniform(0.3, 2.6),
                };
                let p = DVec3::new(rng.uniform(-0.3, 0.3), rng.uniform(-0.25, 0.25), z);
                let q = rng.rotation();
                a.clear();
                b.clear();
                cam.rasterize_mesh(
                    p,
                    q,
                    &mesh.vertices,
                    &mesh.triangles,
                    &sil,
                    &mut world,
                    &mut a,
                    &mut scratch,
                );
                world.clear();
                world.extend(mesh.vertices.iter().map(|v| p + q * *v));
                cam.rasterize_triangles(&world, &mesh.triangles, true, &mut b, &mut scratch);
                assert_eq!(
                    a.xor_count(&b),
                    0,
                    "{piece} at {p} {q}: {} vs {} pixels",
                    a.count(),
                    b.count()
                );
                compared += b.count();
            }
        }
        assert!(
            compared > 100_000,
            "the poses must cast real shadows ({compared} px)"
        );
    }
}
