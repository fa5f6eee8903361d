//! The .blend's view camera: where it looks from, and its two shots.
//!
//! Data flow: [`fit`] places a camera looking along a direction so that a set of points
//! fills a given fraction of the 16:9 frame. [`choose_close_shot`] tries a set of
//! directions and keeps the one whose close shot (the picture, with the bodies at `t` when
//! the picture stays large) shows the picture largest among those from which the bodies
//! at `t` hide little of it (each dark target pixel's line of sight tested against every
//! body's bounding sphere, [`hidden_share`]). [`follow_shot`] frames the bodies of one
//! instant from the same side, lower: the camera follows the flight. [`picture_fraction`]
//! measures the share of the frame's height the picture's bounding box takes.

use glam::{DMat3, DQuat, DVec3};

use crate::scene::Scene;

/// Vertical field of view of the view camera (rad) and its frame's aspect.
pub const FOV_Y: f64 = 40.0 * std::f64::consts::PI / 180.0;
pub const ASPECT: f64 = 16.0 / 9.0;
/// The close shot's picture fills at least this share of the frame's height when the
/// bodies at `t` are framed with it; otherwise the close shot frames the picture alone.
const CLOSE_WITH_BODIES_MIN: f64 = 0.5;
/// Share of the frame (half-extent from the centre) the framed points may fill: in the
/// following shot, the close shot with the bodies, the close shot of the picture alone.
const FOLLOW_FILL: f64 = 0.92;
const CLOSE_FILL: f64 = 0.9;
const PICTURE_FILL: f64 = 0.9;
/// The following shot's elevation above the horizontal (rad): 35 degrees, as the glb's
/// `camera_view`.
const FOLLOW_ELEVATION: f64 = 35.0 * std::f64::consts::PI / 180.0;
/// The bodies at `t` may hide at most this share of the picture from the close shot.
const MAX_HIDDEN: f64 = 0.05;

/// A camera pose: position and orientation (camera -> world; it looks along its local -Z
/// with +Y up, as in Blender and glTF), and the point it aims at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub location: DVec3,
    pub rotation: DQuat,
    /// The point on the line of sight the shot is about (`location - distance * Z`).
    pub aim: DVec3,
}

impl Pose {
    /// The pose `s` of the way (0..1) from `a` to `b`: the orientation by slerp, the aim
    /// point linearly and the distance to it geometrically, so that the shot's subject
    /// stays in frame on the way (blending positions would look away from both).
    pub fn blend(a: &Pose, b: &Pose, s: f64) -> Pose {
        let (da, db) = (a.location.distance(a.aim), b.location.distance(b.aim));
        let d = da.max(1e-9).powf(1.0 - s) * db.max(1e-9).powf(s);
        let rotation = a.rotation.slerp(b.rotation, s).normalize();
        let aim = a.aim.lerp(b.aim, s);
        Pose {
            location: aim + rotation * DVec3::Z * d,
            rotation,
            aim,
        }
    }

    fn axes(&self) -> (DVec3, DVec3, DVec3) {
        (
            self.rotation * DVec3::X,
            self.rotation * DVec3::Y,
            self.rotation * DVec3::Z,
        )
    }

    /// Frame coordinates of a point: (-1..1 left to right, -1..1 bottom to top), and its
    /// depth in front of the camera (m).
    pub fn project(&self, p: DVec3) -> (f64, f64, f64) {
        let (x, y, z) = self.axes();
        let q = p - self.location;
        let depth = -q.dot(z);
        let ty = (FOV_Y / 2.0).tan();
        (
            q.dot(x) / (depth * ty * ASPECT),
            q.dot(y) / (depth * ty),
            depth,
        )
    }
}

/// The unit direction from the scene towards a camera at `azimuth` from the picture's
/// front (`-v`, where the objects start; positive towards `+u`) and `elevation` above
/// the horizontal (world Z up).
pub fn direction(scene: &Scene, azimuth: f64, elevation: f64) -> DVec3 {
    let rc = &scene.receiver;
    let flat = |d: DVec3| (d - DVec3::Z * d.z).try_normalize();
    let front = flat(-rc.v).or_else(|| flat(rc.normal)).unwrap_or(-DVec3::Y);
    let side = DVec3::Z.cross(front).normalize();
    let h = front * azimuth.cos() - side * azimuth.sin();
    (h * elevation.cos() + DVec3::Z * elevation.sin()).normalize()
}

/// The camera looking along `-dir` (level horizon) that fits every `(point, radius)`
/// within `fill` of the frame's half-extents, as close as it can.
pub fn fit(points: &[(DVec3, f64)], dir: DVec3, fill: f64) -> Pose {
    let z = dir.normalize();
    let x = DVec3::Z.cross(z).try_normalize().unwrap_or(DVec3::X);
    let y = z.cross(x);
    let rotation = DQuat::from_mat3(&DMat3::from_cols(x, y, z));
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), (p, r)| (lo.min(*p - *r), hi.max(*p + *r)),
    );
    let mut aim = (lo + hi) / 2.0;
    let size = (hi - lo).length().max(1e-3);
    let ty = (FOV_Y / 2.0).tan();
    let tx = ty * ASPECT;
    // How much of the frame the points take from distance d (> 1 does not fit; a point
    // behind the camera never fits), and the centre of their extent in frame units.
    let extent = |aim: DVec3, d: f64| {
        let c = aim + z * d;
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (p, r) in points {
            let q = *p - c;
            let depth = -q.dot(z) - r;
            if depth <= 1e-6 {
                return (f64::INFINITY, 0.0, 0.0);
            }
            let (px, py) = (q.dot(x), q.dot(y));
            x0 = x0.min((px - r) / (depth * tx));
            x1 = x1.max((px + r) / (depth * tx));
            y0 = y0.min((py - r) / (depth * ty));
            y1 = y1.max((py + r) / (depth * ty));
        }
        let e = ((x1 - x0) / 2.0).max((y1 - y0) / 2.0);
        (e, (x0 + x1) / 2.0, (y0 + y1) / 2.0)
    };
    let mut d = size;
    for _ in 0..4 {
        // The smallest distance at which the points fit (bisection; the extent shrinks
        // as the camera backs away).
        let (mut near, mut far) = (0.0, 1000.0 * size);
        for _ in 0..100 {
            let mid = 0.5 * (near + far);
            if extent(aim, mid).0 <= fill {
                far = mid;
            } else {
                near = mid;
            }
        }
        d = far;
        // Centre the points' extent in the frame.
        let (_, cx, cy) = extent(aim, d);
        aim += x * (cx * d * tx) + y * (cy * d * ty);
    }
    Pose {
        location: aim + z * d,
        rotation,
        aim,
    }
}

/// The share of the frame's height that the bounding box of `corners` takes.
pub fn picture_fraction(pose: &Pose, corners: &[DVec3]) -> f64 {
    let ys: Vec<f64> = corners.iter().map(|p| pose.project(*p).1).collect();
    let lo = ys.iter().copied().fold(f64::INFINITY, f64::min).max(-1.0);
    let hi = ys
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max)
        .min(1.0);
    ((hi - lo) / 2.0).max(0.0)
}

/// The share of `picture` (points on the receiver) hidden by the spheres `bodies` seen
/// from far along `dir`.
pub fn hidden_share(picture: &[DVec3], bodies: &[(DVec3, f64)], dir: DVec3) -> f64 {
    if picture.is_empty() {
        return 0.0;
    }
    let hidden = picture
        .iter()
        .filter(|p| {
            bodies.iter().any(|(c, r)| {
                let q = *c - **p;
                let along = q.dot(dir);
                along > 0.0 && (q - dir * along).length() < *r
            })
        })
        .count();
    hidden as f64 / picture.len() as f64
}

/// The close shot: of the candidate directions (elevations 30 to 70 degrees, azimuths
/// up to 90 degrees either side of the front) from which the bodies at `t` hide at most
/// 5 % of the picture (`dark`, points of the picture), the most frontal (a picture reads
/// best upright), and of those the one whose [`close_shot`] shows the picture largest;
/// if none, the one that hides the least. Returns the direction, the pose and the hidden
/// share.
pub fn choose_close_shot(
    scene: &Scene,
    corners: &[DVec3],
    dark: &[DVec3],
    bodies: &[(DVec3, f64)],
) -> (DVec3, Pose, f64) {
    let deg = std::f64::consts::PI / 180.0;
    // Ranks, lowest best: [1 if hidden too much, then hidden share and |azimuth|; else 0,
    // |azimuth| and minus the picture's fraction (within 0.001 counts as equal)].
    let mut best: Option<([f64; 3], Candidate)> = None;
    for elevation in [70.0, 60.0, 50.0, 40.0, 30.0] {
        for azimuth in [0.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0f64] {
            let dir = direction(scene, azimuth * deg, elevation * deg);
            let hidden = hidden_share(dark, bodies, dir);
            let pose = close_shot(dir, corners, bodies);
            let fraction = picture_fraction(&pose, corners);
            let rank = if hidden <= MAX_HIDDEN {
                [0.0, azimuth.abs(), -fraction]
            } else {
                [1.0, hidden, azimuth.abs()]
            };
            let better = best.as_ref().is_none_or(|(b, _)| {
                let margin = [0.0, 0.0, 1e-3];
                (0..3)
                    .map(|k| (rank[k] + margin[k]).partial_cmp(&b[k]))
                    .find(|o| *o != Some(std::cmp::Ordering::Equal))
                    .is_some_and(|o| o == Some(std::cmp::Ordering::Less))
            });
            if better {
                best = Some((rank, Candidate { dir, pose, hidden }));
            }
        }
    }
    let c = best.expect("at least one candidate").1;
    (c.dir, c.pose, c.hidden)
}

/// A direction tried by [`choose_close_shot`].
struct Candidate {
    dir: DVec3,
    pose: Pose,
    hidden: f64,
}

/// The direction of the following shot: from the close shot's side (its azimuth) at
/// 35 degrees above the horizontal.
pub fn follow_direction(close_dir: DVec3) -> DVec3 {
    let flat = (close_dir - DVec3::Z * close_dir.z)
        .try_normalize()
        .unwrap_or(-DVec3::Y);
    flat * FOLLOW_ELEVATION.cos() + DVec3::Z * FOLLOW_ELEVATION.sin()
}

/// The following shot of one instant: the bodies then (centres and bounding radii) in
/// frame, seen along `dir`, and no closer than a sphere of `min_radius` about their
/// centre would allow (so that one body or a tight cluster does not fill the frame).
pub fn follow_shot(dir: DVec3, bodies: &[(DVec3, f64)], min_radius: f64) -> Pose {
    let centre = bodies.iter().map(|(p, _)| *p).sum::<DVec3>() / bodies.len().max(1) as f64;
    let mut pts: Vec<(DVec3, f64)> = bodies.to_vec();
    pts.push((centre, min_radius));
    fit(&pts, dir, FOLLOW_FILL)
}

/// The close shot along `dir`: the picture's bounding box and the bodies at `t` when the
/// picture then still takes [`CLOSE_WITH_BODIES_MIN`] of the frame's height, else the
/// picture alone, filling 90 % of the frame.
pub fn close_shot(dir: DVec3, corners: &[DVec3], bodies: &[(DVec3, f64)]) -> Pose {
    let mut pts: Vec<(DVec3, f64)> = corners.iter().map(|p| (*p, 0.0)).collect();
    pts.extend_from_slice(bodies);
    let with = fit(&pts, dir, CLOSE_FILL);
    if picture_fraction(&with, corners) >= CLOSE_WITH_BODIES_MIN {
        return with;
    }
    let alone: Vec<(DVec3, f64)> = corners.iter().map(|p| (*p, 0.0)).collect();
    fit(&alone, dir, PICTURE_FILL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fitted_points_fill_the_frame_and_stay_inside() {
        let pts: Vec<(DVec3, f64)> = [
            DVec3::new(-2.0, -1.5, 0.0),
            DVec3::new(2.0, -1.5, 0.0),
            DVec3::new(2.0, 1.5, 0.0),
            DVec3::new(-2.0, 1.5, 0.0),
            DVec3::new(0.3, 0.2, 2.5),
        ]
        .map(|p| (p, 0.0))
        .to_vec();
        let dir = DVec3::new(0.2, -1.0, 1.2).normalize();
        let pose = fit(&pts, dir, 0.8);
        let mut worst: f64 = 0.0;
        for (p, _) in &pts {
            let (x, y, depth) = pose.project(*p);
            assert!(depth > 0.0);
            worst = worst.max(x.abs()).max(y.abs());
        }
        // As close as it can: one point touches the 0.8 border (centred extent).
        assert!((worst - 0.8).abs() < 0.02, "{worst}");
        // Halfway to another shot, the aim point stays in the middle of the frame.
        let other = fit(&pts[..2], DVec3::new(-0.5, -1.0, 0.4).normalize(), 0.5);
        let mid = Pose::blend(&pose, &other, 0.5);
        let (x, y, depth) = mid.project(mid.aim);
        assert!(x.abs() < 1e-9 && y.abs() < 1e-9 && depth > 0.0);
        assert!(
            Pose::blend(&pose, &other, 0.0)
                .location
                .distance(pose.location)
                < 1e-9
        );
        // Looking along -dir with a level horizon: camera x is horizontal.
        let (x, _, z) = pose.axes();
        assert!(x.z.abs() < 1e-12 && z.distance(dir) < 1e-12);
    }
}
