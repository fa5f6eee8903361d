//! How an object can be posed at `t`, and what it then shows the light: the design's
//! vocabulary of poses ([`Family`], [`Pose`]) and their top views ([`Outline`]).
//!
//! Every pose starts from a rest pose on the table (how the object lies at launch) and
//! reaches its pose at `t` by one turn at a constant rate. About a principal axis of
//! the body (every family but the pitched box, and the knight's) the spin that produces
//! it is exact; otherwise `design::launch` corrects the spin on the real flight:
//! - a box lies on its largest face with its long axis along the stroke and rolls about
//!   that axis by `alpha` (0 to 90 degrees): its top view is a rectangle of its length by
//!   `B cos(alpha) + C sin(alpha)`, so the roll sets the shadow's width; or it stands on
//!   its end (top view its B x C end) and does not turn; or, rolled, it is also pitched
//!   across the stroke, and its top view is a hexagon ([`Outline::Polygon`]);
//! - a sphere shows a disc;
//! - a mesh stands as its file has it (top view from above), or, when it is tall (a
//!   chess piece), tips over about a horizontal axis to lie along the stroke or lean
//!   part way (top view its side, foreshortened when leaning, seen from two directions
//!   90 degrees apart unless both look the same).
//!
//! Objects are small beside their distance to the light, so a shadow is taken as the
//! top view magnified by `m = H / (H - z)` about the point under the light, `z` being
//! the height of the pose's centre (the middle of its bounding box).

#[cfg(test)]
use std::f64::consts::FRAC_PI_4;
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

use glam::{DQuat, DVec2, DVec3};

use crate::geometry::shape::{box_corners, Shape, TriMesh};

/// A top view, in metres, centred on the pose's centre; x along the stroke.
#[derive(Clone, Debug)]
pub enum Outline {
    /// A rectangle `len` along x by `wid` along y.
    Rect { len: f64, wid: f64 },
    /// A disc of radius `r`.
    Disc { r: f64 },
    /// Any shape, as occupied cells of a grid.
    Grid(Arc<Grid>),
    /// A convex polygon, counter-clockwise (a tilted box's hexagon).
    Polygon(Arc<Vec<DVec2>>),
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        for &q in p.iter() {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 1e-15
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
        if pass == 0 {
            p.reverse();
        }
    }
    hull
}

/// Occupied cells of a square grid (metres).
#[derive(Clone, Debug)]
pub struct Grid {
    cell: f64,
    x0: f64,
    y0: f64,
    nx: usize,
    ny: usize,
    on: Vec<bool>,
}

impl Grid {
    /// The union of the triangles of `points` (their xy), on a grid of about `cells`
    /// cells along its longer side.
    pub fn of_triangles(points: &[DVec3], triangles: &[[u32; 3]], cells: usize) -> Grid {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in points {
            lo = lo.min(p.truncate());
            hi = hi.max(p.truncate());
        }
        let cell = (hi - lo).max_element().max(1e-9) / cells as f64;
        let nx = ((hi.x - lo.x) / cell).ceil() as usize + 1;
        let ny = ((hi.y - lo.y) / cell).ceil() as usize + 1;
        let mut on = vec![false; nx * ny];
        for t in triangles {
            let [a, b, c] = t.map(|i| points[i as usize].truncate());
            let cross = (b - a).perp_dot(c - a);
            if cross.abs() < 1e-18 {
                continue;
            }
            let (tl, th) = (a.min(b).min(c), a.max(b).max(c));
            let i0 = ((tl.x - lo.x) / cell).floor().max(0.0) as usize;
            let j0 = ((tl.y - lo.y) / cell).floor().max(0.0) as usize;
            let i1 = (((th.x - lo.x) / cell).ceil() as usize).min(nx - 1);
            let j1 = (((th.y - lo.y) / cell).ceil() as usize).min(ny - 1);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let p = DVec2::new(
                        lo.x + (i as f64 + 0.5) * cell,
                        lo.y + (j as f64 + 0.5) * cell,
                    );
                    let s = cross.signum();
                    let inside = s * (b - a).perp_dot(p - a) >= 0.0
                        && s * (c - b).perp_dot(p - b) >= 0.0
                        && s * (a - c).perp_dot(p - c) >= 0.0;
                    if inside {
                        on[j * nx + i] = true;
                    }
                }
            }
        }
        Grid {
            cell,
            x0: lo.x,
            y0: lo.y,
            nx,
            ny,
            on,
        }
    }

    fn contains(&self, d: DVec2) -> bool {
        let i = ((d.x - self.x0) / self.cell).floor();
        let j = ((d.y - self.y0) / self.cell).floor();
        i >= 0.0
            && j >= 0.0
            && (i as usize) < self.nx
            && (j as usize) < self.ny
            && self.on[j as usize * self.nx + i as usize]
    }
}

impl Outline {
    /// Whether the point `d` (metres, outline frame) is inside.
    pub fn contains(&self, d: DVec2) -> bool {
        match self {
            Outline::Rect { len, wid } => d.x.abs() <= 0.5 * len && d.y.abs() <= 0.5 * wid,
            Outline::Disc { r } => d.length_squared() <= r * r,
            Outline::Grid(g) => g.contains(d),
            Outline::Polygon(v) => {
                (0..v.len()).all(|i| (v[(i + 1) % v.len()] - v[i]).perp_dot(d - v[i]) >= 0.0)
            }
        }
    }

    /// Half extents along x and y (metres).
    pub fn half_extents(&self) -> DVec2 {
        match self {
            Outline::Rect { len, wid } => DVec2::new(0.5 * len, 0.5 * wid),
            Outline::Disc { r } => DVec2::splat(*r),
            Outline::Grid(g) => {
                let (mut lo, mut hi) =
                    (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
                for j in 0..g.ny {
                    for i in 0..g.nx {
                        if g.on[j * g.nx + i] {
                            let p = DVec2::new(g.x0 + i as f64 * g.cell, g.y0 + j as f64 * g.cell);
                            lo = lo.min(p);
                            hi = hi.max(p + g.cell);
                        }
                    }
                }
                (hi - lo) * 0.5
            }
            Outline::Polygon(v) => v.iter().fold(DVec2::ZERO, |e, p| e.max(p.abs())),
        }
    }

    /// Area (m^2).
    pub fn area(&self) -> f64 {
        match self {
            Outline::Rect { len, wid } => len * wid,
            Outline::Disc { r } => PI * r * r,
            Outline::Grid(g) => g.on.iter().filter(|&&b| b).count() as f64 * g.cell * g.cell,
            Outline::Polygon(v) => {
                0.5 * (0..v.len())
                    .map(|i| v[i].perp_dot(v[(i + 1) % v.len()]))
                    .sum::<f64>()
            }
        }
    }

    /// Whether `other` (in the same frame) shows nearly the same outline: at least 97 %
    /// of the area of each lies inside the other.
    pub fn matches(&self, other: &Outline) -> bool {
        let inside = |a: &Outline, b: &Outline| {
            let s = a.samples(500);
            let total: f64 = s.iter().map(|(_, w)| w).sum();
            let kept: f64 = s
                .iter()
                .filter(|(d, _)| b.contains(*d))
                .map(|(_, w)| w)
                .sum();
            kept >= 0.97 * total
        };
        inside(self, other) && inside(other, self)
    }

    /// Whether every rotation about the centre shows the same outline.
    pub fn round(&self) -> bool {
        matches!(self, Outline::Disc { .. })
    }

    /// About `n` points spread over the outline, each with the area (m^2) it stands for:
    /// a quadrature of the outline for scoring where it falls on the picture.
    pub fn samples(&self, n: usize) -> Vec<(DVec2, f64)> {
        let n = n.max(4);
        match self {
            Outline::Rect { len, wid } => {
                let nu = ((n as f64 * len / wid).sqrt().round() as usize).clamp(2, n);
                let nv = (n / nu).max(2);
                let w = len * wid / (nu * nv) as f64;
                let mut out = Vec::with_capacity(nu * nv);
                for j in 0..nv {
                    for i in 0..nu {
                        let x = ((i as f64 + 0.5) / nu as f64 - 0.5) * len;
                        let y = ((j as f64 + 0.5) / nv as f64 - 0.5) * wid;
                        out.push((DVec2::new(x, y), w));
                    }
                }
                out
            }
            Outline::Polygon(_) => {
                // Points of a grid over the bounding box that fall inside, each standing
                // for an equal share of the area.
                let e = self.half_extents();
                let area = self.area();
                let cell = (area / n as f64).sqrt().max(1e-9);
                let (nx, ny) = (
                    ((2.0 * e.x / cell).ceil() as usize).max(2),
                    ((2.0 * e.y / cell).ceil() as usize).max(2),
                );
                let mut pts = Vec::new();
                for j in 0..ny {
                    for i in 0..nx {
                        let p = DVec2::new(
                            -e.x + (i as f64 + 0.5) * 2.0 * e.x / nx as f64,
                            -e.y + (j as f64 + 0.5) * 2.0 * e.y / ny as f64,
                        );
                        if self.contains(p) {
                            pts.push(p);
                        }
                    }
                }
                let w = area / pts.len().max(1) as f64;
                pts.into_iter().map(|p| (p, w)).collect()
            }
            Outline::Disc { r } => {
                let k = ((n as f64 * 4.0 / PI).sqrt().ceil() as usize).max(2);
                let step = 2.0 * r / k as f64;
                let mut pts = Vec::new();
                for j in 0..k {
                    for i in 0..k {
                        let p =
                            DVec2::new(-r + (i as f64 + 0.5) * step, -r + (j as f64 + 0.5) * step);
                        if p.length_squared() <= r * r {
                            pts.push(p);
                        }
                    }
                }
                let w = PI * r * r / pts.len().max(1) as f64;
                pts.into_iter().map(|p| (p, w)).collect()
            }
            Outline::Grid(g) => {
                let occupied = g.on.iter().filter(|&&b| b).count().max(1);
                let block = ((occupied as f64 / n as f64).sqrt().floor() as usize).max(1);
                let mut out = Vec::new();
                for bj in (0..g.ny).step_by(block) {
                    for bi in (0..g.nx).step_by(block) {
                        let (mut count, mut sum) = (0usize, DVec2::ZERO);
                        for j in bj..(bj + block).min(g.ny) {
                            for i in bi..(bi + block).min(g.nx) {
                                if g.on[j * g.nx + i] {
                                    count += 1;
                                    sum += DVec2::new(
                                        g.x0 + (i as f64 + 0.5) * g.cell,
                                        g.y0 + (j as f64 + 0.5) * g.cell,
                                    );
                                }
                            }
                        }
                        if count > 0 {
                            out.push((sum / count as f64, count as f64 * g.cell * g.cell));
                        }
                    }
                }
                out
            }
        }
    }
}

/// One pose of an object at `t` and the launch that leads to it.
#[derive(Clone, Debug)]
pub struct Pose {
    /// Body frame -> table frame at launch, before the yaw that turns it to its stroke.
    pub rest: DQuat,
    /// The turn from the rest pose to the pose at `t`: a unit axis in the (unyawed)
    /// table frame (horizontal but for a pitched box), or zero, and the angle (rad).
    pub turn_axis: DVec3,
    pub turn: f64,
    /// Centre of the posed body's bounding box relative to its origin, in the unyawed
    /// frame of the pose at `t`.
    pub centre: DVec3,
    /// Half the posed body's height (m).
    pub half_height: f64,
    /// The top view at `t`, centred on `centre`.
    pub outline: Outline,
    /// Height of the body origin above the table top at rest (m).
    pub lift: f64,
}

impl Pose {
    /// Body frame -> unyawed frame of the pose at `t`.
    pub fn rotation(&self) -> DQuat {
        self.turned(1.0)
    }

    fn turned(&self, fraction: f64) -> DQuat {
        if self.turn_axis == DVec3::ZERO {
            self.rest
        } else {
            DQuat::from_axis_angle(self.turn_axis, self.turn * fraction) * self.rest
        }
    }

    /// Whether the top view is long enough to be aimed by both ends (two hints).
    pub fn elongated(&self) -> bool {
        let e = self.outline.half_extents();
        e.x >= 1.6 * e.y
    }
}

/// A family of poses of one object; boxes lying along a stroke form a family in their
/// roll angle.
#[derive(Clone, Debug)]
pub enum Family {
    Sphere {
        radius: f64,
    },
    /// A box on its largest face, rolled about its long axis by `alpha`.
    BoxLying {
        half: DVec3,
        rest: DQuat,
    },
    /// A box on its largest face, rolled about its long axis by `alpha`, then pitched
    /// about the horizontal axis across it by `pitch`: its top view is a hexagon, its
    /// end face showing beside its top.
    BoxTilted {
        half: DVec3,
        rest: DQuat,
        pitch: f64,
    },
    /// A box standing on its smallest face.
    BoxUpright {
        half: DVec3,
        rest: DQuat,
    },
    /// A mesh as its file stands (`tip` None), or tipped over by `lean` radians (up to
    /// 90 degrees: lying) after a yaw of `tip` radians.
    Mesh {
        mesh: Arc<TriMesh>,
        tip: Option<f64>,
        lean: f64,
        outline: Outline,
    },
}

/// Roll angles tried for a lying box (the search refines them).
const ROLLS: [f64; 7] = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0];

/// Pitches (degrees) of the tilted box families: a box thrown with a spin is seldom
/// flat or on edge at `t`, and its shadow is then a hexagon.
const PITCHES: [f64; 2] = [25.0, 50.0];

/// Roll angles tried for a tilted box: fewer than for a lying one, since a pitched box
/// barely rolled or rolled onto its edge shows a rectangle, as a lying one does (the
/// search refines the roll from these).
const TILTED_ROLLS: [f64; 3] = [22.5, 45.0, 67.5];

/// Angles (degrees) a tall mesh leans by besides lying (90): part way, its top view is
/// its side foreshortened toward the base (a piece thrown with a spin is seldom exactly
/// upright or lying at `t`).
const LEANS: [f64; 3] = [67.5, 45.0, 22.5];

/// Every family of poses of `shape`.
pub fn families(shape: &Shape) -> Vec<Family> {
    match shape {
        Shape::Sphere { radius } => vec![Family::Sphere { radius: *radius }],
        Shape::Cuboid { half_extents } => {
            let h = half_extents.to_array();
            let mut idx = [0usize, 1, 2];
            idx.sort_by(|&a, &b| h[b].total_cmp(&h[a]).then(a.cmp(&b)));
            let axis = |k: usize| DVec3::AXES[k];
            let lying = frame_to(axis(idx[0]), axis(idx[1]));
            let upright = frame_to(axis(idx[1]), axis(idx[2]));
            let mut out = vec![Family::BoxLying {
                half: *half_extents,
                rest: lying,
            }];
            out.push(Family::BoxUpright {
                half: *half_extents,
                rest: upright,
            });
            out.extend(PITCHES.iter().map(|p| Family::BoxTilted {
                half: *half_extents,
                rest: lying,
                pitch: p.to_radians(),
            }));
            out
        }
        Shape::Mesh(mesh) => {
            let mut out = vec![Family::of_mesh(mesh, None, 0.0)];
            let (lo, hi) = mesh.bounding_box();
            let e = hi - lo;
            if e.z >= 1.3 * e.x.max(e.y) {
                // Lying, seen from two yaws 90 degrees apart; a body of revolution shows
                // the same side from every yaw, so one does (the search turns outlines
                // in the picture's plane), and half as many families halve the search.
                // A knight needs both.
                let lying = [0.0, FRAC_PI_2].map(|yaw| Family::of_mesh(mesh, Some(yaw), FRAC_PI_2));
                let [Family::Mesh { outline: a, .. }, Family::Mesh { outline: b, .. }] = &lying
                else {
                    unreachable!("of_mesh makes mesh families")
                };
                let yaws: &[f64] = if a.matches(b) {
                    &[0.0]
                } else {
                    &[0.0, FRAC_PI_2]
                };
                out.extend(lying.into_iter().take(yaws.len()));
                for lean in LEANS {
                    for &yaw in yaws {
                        out.push(Family::of_mesh(mesh, Some(yaw), lean.to_radians()));
                    }
                }
            }
            out
        }
    }
}

/// The rotation that takes body axis `a` to table x and body axis `b` to table y.
fn frame_to(a: DVec3, b: DVec3) -> DQuat {
    let c = a.cross(b);
    // Rows of the matrix are the body axes that land on x, y and z.
    let m = glam::DMat3::from_cols(a, b, c).transpose();
    DQuat::from_mat3(&m)
}

impl Family {
    /// The mesh family of `tip` and `lean` (see [`Family::Mesh`]) with its top view.
    fn of_mesh(mesh: &Arc<TriMesh>, tip: Option<f64>, lean: f64) -> Family {
        let placeholder = Family::Mesh {
            mesh: mesh.clone(),
            tip,
            lean,
            outline: Outline::Disc { r: 0.0 },
        };
        Family::Mesh {
            mesh: mesh.clone(),
            tip,
            lean,
            outline: placeholder.pose(0.0).outline,
        }
    }

    /// Roll angles (rad) to try; one value for the families that have no roll.
    pub fn alphas(&self) -> Vec<f64> {
        match self {
            Family::BoxLying { .. } => ROLLS.iter().map(|d| d.to_radians()).collect(),
            Family::BoxTilted { .. } => TILTED_ROLLS.iter().map(|d| d.to_radians()).collect(),
            _ => vec![0.0],
        }
    }

    /// Whether the roll angle is a continuous parameter.
    pub fn rolls(&self) -> bool {
        matches!(self, Family::BoxLying { .. } | Family::BoxTilted { .. })
    }

    /// The pose of this family at roll `alpha` (ignored by the families that do not roll).
    pub fn pose(&self, alpha: f64) -> Pose {
        match self {
            Family::Sphere { radius } => Pose {
                rest: DQuat::IDENTITY,
                turn_axis: DVec3::ZERO,
                turn: 0.0,
                centre: DVec3::ZERO,
                half_height: *radius,
                outline: Outline::Disc { r: *radius },
                lift: *radius,
            },
            Family::BoxLying { half, rest } => {
                let e = (*rest * *half).abs();
                let (l, b, c) = (2.0 * e.x, 2.0 * e.y, 2.0 * e.z);
                let a = alpha.clamp(0.0, FRAC_PI_2);
                Pose {
                    rest: *rest,
                    turn_axis: DVec3::X,
                    turn: a,
                    centre: DVec3::ZERO,
                    half_height: 0.5 * (b * a.sin() + c * a.cos()),
                    outline: Outline::Rect {
                        len: l,
                        wid: b * a.cos() + c * a.sin(),
                    },
                    lift: 0.5 * c,
                }
            }
            Family::BoxTilted { half, rest, pitch } => {
                let a = alpha.clamp(0.0, FRAC_PI_2);
                let turn = DQuat::from_rotation_y(*pitch) * DQuat::from_rotation_x(a);
                let (axis, angle) = turn.to_axis_angle();
                let q = turn * *rest;
                let corners: Vec<DVec3> = box_corners(*half).iter().map(|c| q * *c).collect();
                let top: Vec<DVec2> = corners.iter().map(|c| c.truncate()).collect();
                let half_height = corners.iter().map(|c| c.z).fold(0.0, f64::max);
                Pose {
                    rest: *rest,
                    turn_axis: if angle == 0.0 { DVec3::ZERO } else { axis },
                    turn: angle,
                    centre: DVec3::ZERO,
                    half_height,
                    outline: Outline::Polygon(Arc::new(convex_hull(&top))),
                    lift: (*rest * *half).abs().z,
                }
            }
            Family::BoxUpright { half, rest } => {
                // `rest` lays the middle axis along x and the short one along y, so the
                // long axis stands along z.
                let e = (*rest * *half).abs();
                Pose {
                    rest: *rest,
                    turn_axis: DVec3::ZERO,
                    turn: 0.0,
                    centre: DVec3::ZERO,
                    half_height: e.z,
                    outline: Outline::Rect {
                        len: 2.0 * e.x,
                        wid: 2.0 * e.y,
                    },
                    lift: e.z,
                }
            }
            Family::Mesh {
                mesh,
                tip,
                lean,
                outline,
            } => {
                let rest = DQuat::from_rotation_z(tip.unwrap_or(0.0));
                let (turn_axis, turn) = match tip {
                    Some(_) => (DVec3::Y, *lean),
                    None => (DVec3::ZERO, 0.0),
                };
                let mut pose = Pose {
                    rest,
                    turn_axis,
                    turn,
                    centre: DVec3::ZERO,
                    half_height: 0.0,
                    outline: outline.clone(),
                    lift: -mesh
                        .vertices
                        .iter()
                        .map(|v| (rest * *v).z)
                        .fold(f64::INFINITY, f64::min),
                };
                let q = pose.rotation();
                let posed: Vec<DVec3> = mesh.vertices.iter().map(|v| q * *v).collect();
                let (mut lo, mut hi) =
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                for p in &posed {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
                pose.centre = 0.5 * (lo + hi);
                pose.half_height = 0.5 * (hi.z - lo.z);
                if matches!(outline, Outline::Disc { r } if *r == 0.0) {
                    let centred: Vec<DVec3> = posed.iter().map(|p| *p - pose.centre).collect();
                    pose.outline =
                        Outline::Grid(Arc::new(Grid::of_triangles(&centred, &mesh.triangles, 96)));
                }
                pose
            }
        }
    }
}

/// Largest horizontal distance from the body origin to a point of the body in its rest
/// pose (m): the room it takes on the table, whatever its yaw.
pub fn rest_radius(shape: &Shape, rest: DQuat) -> f64 {
    match shape {
        Shape::Sphere { radius } => *radius,
        _ => hull_points(shape)
            .iter()
            .map(|p| (rest * *p).truncate().length())
            .fold(0.0, f64::max),
    }
}

/// Height of the body origin above the table when the body stands on it turned by `q`
/// (the launcher holds it so): the depth of its lowest point below the origin (m).
pub fn lift_at(shape: &Shape, q: DQuat) -> f64 {
    match shape {
        Shape::Sphere { radius } => *radius,
        _ => hull_points(shape)
            .iter()
            .map(|p| -(q * *p).z)
            .fold(f64::NEG_INFINITY, f64::max),
    }
}

/// The points whose hull is the body (not for a sphere).
fn hull_points(shape: &Shape) -> Vec<DVec3> {
    match shape {
        Shape::Sphere { .. } => Vec::new(),
        Shape::Cuboid { half_extents } => box_corners(*half_extents).to_vec(),
        Shape::Mesh(m) => m.vertices.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rolled_box_shows_the_width_of_its_rolled_section() {
        // A 0.14 x 0.07 x 0.035 block given as 0.07 x 0.035 x 0.14 (long axis z in the body).
        let shape = Shape::Cuboid {
            half_extents: DVec3::new(0.035, 0.0175, 0.07),
        };
        let fams = families(&shape);
        let lying = &fams[0];
        for deg in [0.0f64, 30.0, 90.0] {
            let a = deg.to_radians();
            let pose = lying.pose(a);
            // The posed corners' extents agree with the outline and half height.
            let q = pose.rotation();
            let (mut lo, mut hi) = (DVec3::splat(9.0), DVec3::splat(-9.0));
            for c in box_corners(DVec3::new(0.035, 0.0175, 0.07)) {
                lo = lo.min(q * c);
                hi = hi.max(q * c);
            }
            let e = pose.outline.half_extents();
            assert!((hi.x - lo.x - 2.0 * e.x).abs() < 1e-12, "{deg}");
            assert!((hi.y - lo.y - 2.0 * e.y).abs() < 1e-12, "{deg}");
            assert!(
                (hi.z - lo.z - 2.0 * pose.half_height).abs() < 1e-12,
                "{deg}"
            );
            assert!((2.0 * e.y - (0.07 * a.cos() + 0.035 * a.sin())).abs() < 1e-12);
            // It rests on its largest face.
            assert!((pose.lift - 0.0175).abs() < 1e-12);
        }
        let up = fams[1].pose(0.0);
        assert!((up.half_height - 0.07).abs() < 1e-12);
        assert!(!up.elongated() || up.outline.half_extents().x >= 0.035);
    }

    #[test]
    fn a_tall_mesh_can_tip_over_and_its_outline_is_its_side() {
        // A square prism 0.02 x 0.02 x 0.1, base on z = 0.
        let mut v = Vec::new();
        for z in [0.0, 0.1] {
            for (x, y) in [(-0.01, -0.01), (0.01, -0.01), (0.01, 0.01), (-0.01, 0.01)] {
                v.push(DVec3::new(x, y, z));
            }
        }
        let t: Vec<[u32; 3]> = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        let shape = Shape::Mesh(Arc::new(TriMesh::new(v, t)));
        let fams = families(&shape);
        // Standing, and tipped by each lean at one yaw: its side is the same from both.
        assert_eq!(fams.len(), 2 + LEANS.len());
        let up = fams[0].pose(0.0);
        assert!((up.half_height - 0.05).abs() < 1e-9 && up.lift.abs() < 1e-12);
        let tipped = fams[1].pose(0.0);
        let e = tipped.outline.half_extents();
        assert!(
            (e.x - 0.05).abs() < 0.002 && (e.y - 0.01).abs() < 0.002,
            "{e}"
        );
        assert!((tipped.half_height - 0.01).abs() < 1e-9);
        assert!(tipped.elongated() && !up.elongated());
        // The outline's area is the side's, 0.1 x 0.02.
        assert!((tipped.outline.area() - 0.002).abs() < 2e-4);
        let total: f64 = tipped.outline.samples(200).iter().map(|s| s.1).sum();
        assert!((total - tipped.outline.area()).abs() < 1e-12);
    }

    #[test]
    fn a_leaning_piece_shows_its_side_foreshortened() {
        // A king-like solid of revolution 6 cm tall on a base 2.5 cm across.
        let profile = [
            (0.0, 0.0),
            (0.0125, 0.0),
            (0.0125, 0.004),
            (0.006, 0.012),
            (0.005, 0.045),
            (0.009, 0.05),
            (0.006, 0.058),
            (0.0, 0.060),
        ];
        let king = Arc::new(crate::geometry::shape::tests::lathe(&profile, 48));
        let fams = families(&Shape::Mesh(king.clone()));
        assert_eq!(
            fams.len(),
            2 + LEANS.len(),
            "a body of revolution needs one yaw"
        );
        let side = |lean: f64| {
            fams.iter()
                .find(|f| matches!(f, Family::Mesh { tip: Some(_), lean: l, .. } if (l - lean.to_radians()).abs() < 1e-12))
                .expect("a family per lean")
                .pose(0.0)
        };
        // Lying, its length along x is the piece's height (6 cm). Leaning 45 degrees,
        // its top view spans the posed vertices' (the height foreshortened by sin 45,
        // the base's far side by cos 45), to the outline grid's cells (96 along it).
        let lying = side(90.0).outline.half_extents();
        assert!((2.0 * lying.x - 0.060).abs() < 0.0015, "{lying}");
        let leaning = side(45.0);
        let e = leaning.outline.half_extents();
        let q = leaning.rotation();
        let xs: Vec<f64> = king.vertices.iter().map(|v| (q * *v).x).collect();
        let span = xs.iter().cloned().fold(f64::MIN, f64::max)
            - xs.iter().cloned().fold(f64::MAX, f64::min);
        // The head's rim (radius 6 mm at 5.8 cm) reaches farthest; the foot's edge
        // on the other side.
        let head = 0.058 * FRAC_PI_4.sin() + 0.006 * FRAC_PI_4.cos();
        let foot = 0.0125 * FRAC_PI_4.cos();
        assert!((span - (head + foot)).abs() < 1e-9, "{span}");
        assert!(
            (2.0 * e.x - span).abs() < 4.0 * span / 96.0,
            "{e} vs {span}"
        );
        assert!(2.0 * e.x < 2.0 * lying.x - 0.005);
        // The pose turns the piece by its lean about a horizontal axis.
        let up = leaning.rotation() * DVec3::Z;
        assert!((up.z - FRAC_PI_4.cos()).abs() < 1e-12, "{up}");
        // A piece that is not round (a flat slab standing on edge) keeps both yaws.
        let slab = Shape::Cuboid {
            half_extents: DVec3::new(0.02, 0.005, 0.05),
        };
        let Shape::Cuboid { half_extents } = slab else {
            unreachable!()
        };
        let corners = box_corners(half_extents);
        let v: Vec<DVec3> = corners.iter().map(|c| *c + DVec3::Z * 0.05).collect();
        let faces: Vec<[u32; 3]> = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        let fams = families(&Shape::Mesh(Arc::new(TriMesh::new(v, faces))));
        assert_eq!(fams.len(), 1 + 2 * (1 + LEANS.len()));
    }

    #[test]
    fn a_tilted_box_shows_a_hexagon() {
        let half = DVec3::new(0.07, 0.035, 0.0175);
        let fams = families(&Shape::Cuboid { half_extents: half });
        let tilted: Vec<&Family> = fams
            .iter()
            .filter(|f| matches!(f, Family::BoxTilted { .. }))
            .collect();
        assert_eq!(tilted.len(), PITCHES.len());
        for f in tilted {
            for deg in [0.0f64, 30.0, 60.0] {
                let pose = f.pose(deg.to_radians());
                let Outline::Polygon(hull) = &pose.outline else {
                    panic!("a tilted box's top view is a polygon");
                };
                // Rolled, a pitched box shows three faces: a hexagon.
                assert_eq!(hull.len(), if deg == 0.0 { 4 } else { 6 }, "{deg}");
                // The outline is the posed corners' top view: each corner is inside (or
                // on) it, and a point just beyond the farthest corner is not.
                let q = pose.rotation();
                let corners: Vec<DVec3> = box_corners(half).iter().map(|c| q * *c).collect();
                for c in &corners {
                    assert!(pose.outline.contains(c.truncate() * (1.0 - 1e-9)));
                }
                let far = corners.iter().max_by(|a, b| a.x.total_cmp(&b.x)).unwrap();
                assert!(!pose.outline.contains(far.truncate() + DVec2::X * 1e-6));
                let top = corners.iter().map(|c| c.z).fold(f64::MIN, f64::max);
                assert!((top - pose.half_height).abs() < 1e-12);
                // Its samples cover its area.
                let s = pose.outline.samples(150);
                let total: f64 = s.iter().map(|p| p.1).sum();
                assert!((total - pose.outline.area()).abs() < 1e-12);
                assert!(s.len() >= 100 && s.len() <= 220, "{}", s.len());
            }
        }
    }

    #[test]
    fn samples_cover_the_area() {
        for o in [
            Outline::Rect {
                len: 0.3,
                wid: 0.05,
            },
            Outline::Disc { r: 0.2 },
        ] {
            let s = o.samples(150);
            assert!(s.len() >= 100 && s.len() <= 220, "{}", s.len());
            let total: f64 = s.iter().map(|p| p.1).sum();
            assert!((total - o.area()).abs() < 1e-9 * o.area().max(1.0));
            assert!(s.iter().all(|p| o.contains(p.0)));
        }
    }
}
