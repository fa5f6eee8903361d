//! The camera: [`ShadowCamera`] (receiver plane, image rectangle, point light) built from
//! an [`ImageRect`], its projection to pixel coordinates, and the homogeneous clipping of
//! triangles against the slab and the image edges (Sutherland–Hodgman).

use crate::shadow::mask::Mask;
use glam::{DVec2, DVec3};

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
    pub(super) n: DVec3,
    /// Height of the light above the receiver (> 0).
    pub(super) h: f64,
    /// World position of pixel coordinate (0, 0) (top-left corner of the image).
    pub(super) origin: DVec3,
    /// World step per unit of pixel x and of pixel y (`dv` points down the image).
    pub(super) du: DVec3,
    pub(super) dv: DVec3,
    /// Homogeneous projection: for `q = p - light`, `(q.ex, q.ey, q.ez)` is
    /// `(px * depth, py * depth, depth)` with `depth = -q.n` the distance of `p` in front of
    /// the light plane. The map is linear in `p`, so clipping can interpolate it directly.
    pub(super) ex: DVec3,
    pub(super) ey: DVec3,
    pub(super) ez: DVec3,
    /// Depth of the near clipping plane, a hair in front of the light.
    pub(super) near: f64,
}

/// The image rectangle on the receiver plane, as [`ShadowCamera::new`] takes it: the
/// camera's public fields other than the light, with the same meanings.
#[derive(Clone, Copy, Debug)]
pub struct ImageRect {
    /// Centre of the rectangle on the receiver plane.
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
}

/// Maximum vertex count of a triangle clipped by six planes (3 + 6), with headroom.
pub(super) const MAX_POLY: usize = 12;

impl ShadowCamera {
    /// Build the camera for the point `light` and the image rectangle `image`. `u` and
    /// `v` must be unit and perpendicular (checked to 1e-6), and the light must be
    /// strictly off the receiver plane.
    pub fn new(light: DVec3, image: ImageRect) -> ShadowCamera {
        let ImageRect {
            center,
            u,
            v,
            width_m,
            height_m,
            width_px,
            height_px,
        } = image;
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

    /// The same camera over a larger rectangle: `margin` more pixels of the same size on
    /// every side, so pixel `(x, y)` of this camera is pixel `(x + margin, y + margin)` of
    /// the widened one.
    pub fn widened(&self, margin: usize) -> ShadowCamera {
        let (wp, hp) = (self.width_px as f64, self.height_px as f64);
        let m = margin as f64;
        ShadowCamera::new(
            self.light,
            ImageRect {
                center: self.center,
                u: self.u,
                v: self.v,
                width_m: self.width_m * (wp + 2.0 * m) / wp,
                height_m: self.height_m * (hp + 2.0 * m) / hp,
                width_px: self.width_px + 2 * margin,
                height_px: self.height_px + 2 * margin,
            },
        )
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

    pub(super) fn check_mask(&self, mask: &Mask) {
        assert!(
            mask.width() == self.width_px && mask.height() == self.height_px,
            "mask is {}x{}, camera is {}x{}",
            mask.width(),
            mask.height(),
            self.width_px,
            self.height_px
        );
    }

    /// Homogeneous image coordinates `(px * depth, py * depth, depth)` of a world point.
    #[inline]
    pub(super) fn homogeneous(&self, p: DVec3) -> DVec3 {
        let q = p - self.light;
        DVec3::new(q.dot(self.ex), q.dot(self.ey), q.dot(self.ez))
    }

    /// Bit set of the clipping planes that the homogeneous point is strictly outside of.
    #[inline]
    pub(super) fn outcode(&self, p: DVec3) -> u8 {
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
    pub(super) fn clip_triangle(
        &self,
        tri: [DVec3; 3],
        planes: u8,
        out: &mut [DVec2; MAX_POLY],
    ) -> usize {
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
