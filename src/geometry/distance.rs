//! Distances between posed convex shapes, in f64.
//!
//! Main types: [`ContactShape`] (what the distance queries see: an exact ball, or a
//! convex polytope with its sphere cover, built once per scene) and the functions
//! [`signed_distance`] (two posed shapes) and [`table_signed_distance`] (a posed shape
//! and the table). Separated shapes get a certified lower bound from the f64 GJK of
//! [`crate::geometry::gjk`]; parry (f32) only supplies penetration depths, and never raises that
//! bound. [`crate::sim::contact`] builds its first-contact search on these queries, and scene
//! validation checks launch poses with them.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use rapier3d::parry::math::Pose;
use rapier3d::parry::query;
use rapier3d::parry::shape::{Ball, ConvexPolyhedron, Cuboid, Shape as ParryShape};

use crate::geometry::gjk::{Polytope, Warm};
use crate::geometry::shape::{Shape, Table};

/// Surfaces closer than this (m) are in contact.
pub const CONTACT_DISTANCE: f64 = 1e-6;

/// The geometry used by the distance queries.
#[derive(Clone)]
pub enum ContactShape {
    /// A sphere of this radius centred on the body origin (closed-form queries).
    Ball(f64),
    /// Any other shape: as parry sees it in the body frame (used for penetration depths
    /// only), its convex hull's vertices in f64 (body frame; distances come from
    /// [`crate::geometry::gjk`]), and a cover of spheres (body frame) whose union contains it.
    Parry(Arc<dyn ParryShape>, SphereCover, Option<Arc<Polytope>>),
}

/// Spheres (centre in the body frame, radius) whose union contains a convex shape. The
/// distance between two covers is a lower bound of the distance between the shapes, and
/// costs a few dozen flops instead of a GJK query: conservative advancement steps on it
/// while the shapes are more than `COVER_SWITCH` (1 mm) apart.
pub type SphereCover = Arc<[(DVec3, f64)]>;

/// Number of slabs (spheres) of a cover.
pub const COVER_SLABS: usize = 6;

/// A sphere cover of the convex polytope with these vertices and edges: the polytope is
/// cut into [`COVER_SLABS`] slabs across its longest axis-aligned extent, and each slab
/// (whose vertices are the polytope's vertices inside it and its edges' crossings of the
/// two planes) gets a bounding sphere. Every point of the polytope lies in some slab, so
/// the union covers it.
pub fn sphere_cover(points: &[DVec3], edges: &[[usize; 2]]) -> SphereCover {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let ext = hi - lo;
    let k = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mut cover = Vec::with_capacity(COVER_SLABS);
    let mut pts: Vec<DVec3> = Vec::new();
    for i in 0..COVER_SLABS {
        let a = lo[k] + ext[k] * i as f64 / COVER_SLABS as f64;
        let b = if i + 1 == COVER_SLABS {
            hi[k]
        } else {
            lo[k] + ext[k] * (i + 1) as f64 / COVER_SLABS as f64
        };
        pts.clear();
        pts.extend(points.iter().filter(|p| p[k] >= a && p[k] <= b));
        for &[u, v] in edges {
            let (p, q) = (points[u], points[v]);
            for plane in [a, b] {
                if (p[k] - plane) * (q[k] - plane) < 0.0 {
                    let s = (plane - p[k]) / (q[k] - p[k]);
                    pts.push(p + (q - p) * s);
                }
            }
        }
        if pts.is_empty() {
            continue;
        }
        let (mut l, mut h) = (pts[0], pts[0]);
        for p in &pts {
            l = l.min(*p);
            h = h.max(*p);
        }
        let c = 0.5 * (l + h);
        let r = pts.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
        // Margin for rounding in the crossings and in parry's f32 geometry.
        cover.push((c, r * (1.0 + 1e-6) + 1e-7));
    }
    cover.into()
}

/// Lower bound of the distance between two posed shapes from their sphere covers
/// (negative when two cover spheres overlap), or `None` if one has no cover.
pub fn cover_gap(
    sa: &ContactShape,
    pa: DVec3,
    qa: DQuat,
    sb: &ContactShape,
    pb: DVec3,
    qb: DQuat,
) -> Option<f64> {
    let (ca, cb) = match (sa, sb) {
        (ContactShape::Parry(_, ca, _), ContactShape::Parry(_, cb, _)) => (ca, cb),
        _ => return None,
    };
    // a's spheres placed once (a cover has at most COVER_SLABS), not once per b's.
    let mut placed = [(DVec3::ZERO, 0.0); COVER_SLABS];
    let place = |&(c, r): &(DVec3, f64)| (pa + qa * c, r);
    let wa: &[(DVec3, f64)] = if ca.len() <= COVER_SLABS {
        for (w, c) in placed.iter_mut().zip(ca.iter()) {
            *w = place(c);
        }
        &placed[..ca.len()]
    } else {
        &ca.iter().map(place).collect::<Vec<_>>()
    };
    let mut best = f64::INFINITY;
    for &(c1, r1) in cb.iter() {
        let w1 = pb + qb * c1;
        for &(w0, r0) in wa {
            best = best.min(w0.distance(w1) - r0 - r1);
        }
    }
    Some(best)
}

impl std::fmt::Debug for ContactShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ContactShape::Ball(r) => write!(f, "Ball({r})"),
            ContactShape::Parry(..) => write!(f, "Parry(..)"),
        }
    }
}

impl ContactShape {
    /// Build the query shape of a scene shape: boxes exactly, meshes by their convex hull.
    pub fn new(shape: &Shape) -> ContactShape {
        match shape {
            Shape::Sphere { radius } => ContactShape::Ball(*radius),
            Shape::Cuboid { half_extents } => {
                let he = *half_extents;
                let corners = crate::geometry::shape::box_corners(he).to_vec();
                let edges: Vec<[usize; 2]> = (0..8usize)
                    .flat_map(|i| [1usize, 2, 4].map(move |b| [i, i | b]))
                    .filter(|[i, j]| i != j)
                    .collect();
                let cover = sphere_cover(&corners, &edges);
                ContactShape::Parry(
                    Arc::new(Cuboid::new(he.as_vec3())),
                    cover,
                    Some(Arc::new(Polytope::new(corners, &edges))),
                )
            }
            Shape::Mesh(mesh) => {
                let pts: Vec<_> = mesh.vertices.iter().map(|v| v.as_vec3()).collect();
                match ConvexPolyhedron::from_convex_hull(&pts) {
                    Some(hull) => {
                        let points: Vec<DVec3> =
                            hull.points().iter().map(|p| p.as_dvec3()).collect();
                        let edges: Vec<[usize; 2]> = hull
                            .edges()
                            .iter()
                            .map(|e| [e.vertices[0] as usize, e.vertices[1] as usize])
                            .collect();
                        let cover = sphere_cover(&points, &edges);
                        let poly = Polytope::new(points, &edges);
                        ContactShape::Parry(Arc::new(hull), cover, Some(Arc::new(poly)))
                    }
                    // A degenerate hull cannot happen for a validated closed mesh with
                    // volume; fall back to the bounding ball about the origin to stay safe.
                    None => ContactShape::Ball(
                        mesh.vertices.iter().map(|v| v.length()).fold(0.0, f64::max),
                    ),
                }
            }
        }
    }

    /// The convex polytope the f64 distance queries use (boxes and meshes).
    pub fn polytope(&self) -> Option<&Polytope> {
        match self {
            ContactShape::Parry(_, _, Some(p)) => Some(p),
            _ => None,
        }
    }

    pub fn parry(&self) -> Option<&dyn ParryShape> {
        match self {
            ContactShape::Ball(_) => None,
            ContactShape::Parry(s, ..) => Some(s.as_ref()),
        }
    }
}

/// Signed distance between two posed shapes (negative: penetration depth).
pub fn signed_distance(
    sa: &ContactShape,
    pa: DVec3,
    qa: DQuat,
    sb: &ContactShape,
    pb: DVec3,
    qb: DQuat,
) -> f64 {
    signed_distance_warm(
        PosedShape {
            shape: sa,
            position: pa,
            orientation: qa,
        },
        PosedShape {
            shape: sb,
            position: pb,
            orientation: qb,
        },
        crate::geometry::gjk::REL_TOL,
        &mut Warm::default(),
    )
}

/// A contact shape at a pose (body -> world: `x -> position + orientation x`), as
/// [`signed_distance_warm`] takes it.
#[derive(Clone, Copy, Debug)]
pub struct PosedShape<'a> {
    /// The shape, in its body frame.
    pub shape: &'a ContactShape,
    /// Body-frame origin (m, world).
    pub position: DVec3,
    /// Body frame -> world.
    pub orientation: DQuat,
}

/// [`signed_distance`] for a sequence of nearby poses of one pair: `warm` carries GJK's
/// state from one query to the next (see [`crate::geometry::gjk::Warm`]).
pub fn signed_distance_warm(
    a: PosedShape<'_>,
    b: PosedShape<'_>,
    rel_tol: f64,
    warm: &mut Warm,
) -> f64 {
    let PosedShape {
        shape: sa,
        position: pa,
        orientation: qa,
    } = a;
    let PosedShape {
        shape: sb,
        position: pb,
        orientation: qb,
    } = b;
    match (sa, sb) {
        (ContactShape::Ball(ra), ContactShape::Ball(rb)) => pa.distance(pb) - ra - rb,
        _ => {
            // Express b in a's frame in f64, then hand parry small f32 coordinates.
            let qa_inv = qa.inverse();
            let rel_p = qa_inv * (pb - pa);
            let rel_q = (qa_inv * qb).normalize();
            let pose_a = Pose::IDENTITY;
            let pose_b = Pose::from_parts(rel_p.as_vec3(), rel_q.as_quat());
            let ball_a;
            let ball_b;
            let ga: &dyn ParryShape = match sa.parry() {
                Some(s) => s,
                None => {
                    ball_a = Ball::new(ball_radius(sa) as f32);
                    &ball_a
                }
            };
            let gb: &dyn ParryShape = match sb.parry() {
                Some(s) => s,
                None => {
                    ball_b = Ball::new(ball_radius(sb) as f32);
                    &ball_b
                }
            };
            // Separated shapes: the f64 GJK of `crate::geometry::gjk` on the hull vertices (a
            // ball is its centre, its radius subtracted). Only a penetration depth,
            // needed for bodies that touch at launch, comes from parry.
            let (va, vb) = (hull_points(sa), hull_points(sb));
            let certified = match (va, vb) {
                (Some(va), Some(vb)) => {
                    let d = crate::geometry::gjk::distance_lower_bound_warm(
                        va, vb, rel_q, rel_p, rel_tol, warm,
                    ) - ball_radius(sa)
                        - ball_radius(sb);
                    if d > CONTACT_DISTANCE {
                        return d;
                    }
                    Some(d)
                }
                _ => None,
            };
            // Touching or overlapping: parry gives the penetration depth. It is never
            // trusted to raise the certified bound: on curved hulls its f32 GJK was seen to
            // report millimetres of clearance for overlapping poses (docs/contacts.md).
            let parry = match query::contact(&pose_a, ga, &pose_b, gb, f32::MAX) {
                Ok(Some(c)) => Some(c.dist as f64),
                _ => None,
            };
            match (certified, parry) {
                (Some(d), Some(p)) => p.min(d),
                (Some(d), None) => d.min(0.0),
                (None, Some(p)) => p,
                // Not reachable for the supported shape pairs; treat as far apart.
                (None, None) => f64::INFINITY,
            }
        }
    }
}

/// The points whose convex hull is the shape, for [`crate::geometry::gjk`]: the hull's vertices,
/// or a ball's centre (its radius is subtracted from the distance).
pub fn hull_points(s: &ContactShape) -> Option<&Polytope> {
    // Built once: a ball's centre in its own frame.
    static CENTRE: std::sync::LazyLock<Polytope> =
        std::sync::LazyLock::new(|| Polytope::point(DVec3::ZERO));
    match s {
        ContactShape::Parry(_, _, Some(p)) => Some(p),
        ContactShape::Ball(_) => Some(&CENTRE),
        _ => None,
    }
}

pub fn ball_radius(s: &ContactShape) -> f64 {
    match s {
        ContactShape::Ball(r) => *r,
        ContactShape::Parry(..) => 0.0,
    }
}

/// Signed distance from a posed shape to the table box (negative: penetration).
pub fn table_signed_distance(
    shape: &ContactShape,
    p: DVec3,
    q: DQuat,
    table: &Table,
    table_shape: &ContactShape,
) -> f64 {
    match shape {
        ContactShape::Ball(r) => {
            // Closed form: distance from the centre to the box, minus the radius.
            let local = p - table.center;
            let h = table.half_extents;
            let outside = (local.abs() - h).max(DVec3::ZERO);
            let inside = (local.abs() - h).max_element().min(0.0);
            outside.length() + inside - r
        }
        ContactShape::Parry(_, _, Some(poly)) => {
            // Over the top face, away from its edges, the closest part of the table is
            // the top plane: the distance is the height of the lowest vertex, exactly.
            let r = poly.radius();
            let local = p - table.center;
            let h = table.half_extents;
            if local.x.abs() + r <= h.x && local.y.abs() + r <= h.y {
                let low = p + q * poly.support_point(q.inverse() * DVec3::NEG_Z);
                low.z - table.top()
            } else {
                signed_distance(shape, p, q, table_shape, table.center, DQuat::IDENTITY)
            }
        }
        _ => signed_distance(shape, p, q, table_shape, table.center, DQuat::IDENTITY),
    }
}

/// The table as a query shape.
pub fn table_shape(table: &Table) -> ContactShape {
    // The table's queries never use a cover (see `sphere_clear_of_top`).
    let he = table.half_extents;
    let corners = crate::geometry::shape::box_corners(he).to_vec();
    ContactShape::Parry(
        Arc::new(Cuboid::new(he.as_vec3())),
        Arc::new([]),
        Some(Arc::new(Polytope::new(corners, &[]))),
    )
}
