//! Distance between two convex polytopes in f64 (GJK), returning a certified lower bound.
//!
//! Main function: [`distance_lower_bound`]. Each polytope is the convex hull of its
//! vertices, given in its own frame; the second is placed in the first's frame by a
//! rotation and a translation. The result is never above the true distance: GJK's
//! iterate `v` (a point of the Minkowski difference `A - B`) and the support point `w` in
//! direction `-v` prove `dist >= (v . w) / |v|` by a separating plane, and that bound is
//! what is returned when the iteration stops. This is what conservative advancement
//! needs: a distance that may be a hair low but is never high.
//!
//! Why not parry's GJK: parry works in f32, and on the convex hulls of our chess pieces
//! (surfaces of revolution, many nearly coplanar faces) its `distance` and `contact`
//! were measured to jump by several millimetres between nearby poses, overestimating the
//! distance, which made conservative advancement step over real contacts.
//!
//! The sub-problem (closest point of a simplex of at most four points to the origin) is
//! solved by enumerating the simplex's faces, edges and vertices, which is simple and
//! robust in f64 at the sizes involved.

use glam::{DQuat, DVec3};

/// Largest number of GJK iterations; each adds one support point. Hulls of a few hundred
/// vertices converge in well under 30.
const MAX_ITERATIONS: usize = 64;

/// Relative gap between the upper and lower bounds at which [`distance_lower_bound`]
/// stops. [`distance_lower_bound_warm`] takes its own: conservative advancement only
/// needs a lower bound, a bound 5 % low costs it 5 % shorter steps, and curved hulls
/// need many more iterations for each further digit.
pub const REL_TOL: f64 = 1e-6;

/// Absolute gap (m) at which the iteration stops: far below the contact distance (1 um).
const ABS_TOL: f64 = 1e-9;

/// A convex polytope given by its vertices and the edges of a triangulation of its hull
/// (every true edge of the polytope is among them), for support queries by hill climbing.
#[derive(Clone, Debug)]
pub struct Polytope {
    points: Vec<DVec3>,
    /// Neighbours of vertex `i`: `neighbours[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
    /// Support vertex in each of the [`START_DIRECTIONS`]: a climb starts from the one
    /// closest to the query direction and has only a few steps left.
    starts: Vec<u32>,
    /// Largest distance of a vertex from the frame's origin.
    radius: f64,
}

/// The 26 directions from a cube's centre to its face centres, edges and corners (unit).
const START_DIRECTIONS: [DVec3; 26] = {
    const S2: f64 = std::f64::consts::FRAC_1_SQRT_2;
    const S3: f64 = 0.577_350_269_189_625_8;
    [
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(S2, S2, 0.0),
        DVec3::new(S2, -S2, 0.0),
        DVec3::new(-S2, S2, 0.0),
        DVec3::new(-S2, -S2, 0.0),
        DVec3::new(S2, 0.0, S2),
        DVec3::new(S2, 0.0, -S2),
        DVec3::new(-S2, 0.0, S2),
        DVec3::new(-S2, 0.0, -S2),
        DVec3::new(0.0, S2, S2),
        DVec3::new(0.0, S2, -S2),
        DVec3::new(0.0, -S2, S2),
        DVec3::new(0.0, -S2, -S2),
        DVec3::new(S3, S3, S3),
        DVec3::new(S3, S3, -S3),
        DVec3::new(S3, -S3, S3),
        DVec3::new(S3, -S3, -S3),
        DVec3::new(-S3, S3, S3),
        DVec3::new(-S3, S3, -S3),
        DVec3::new(-S3, -S3, S3),
        DVec3::new(-S3, -S3, -S3),
    ]
};

/// Below this many vertices, support queries scan all of them.
const SCAN_BELOW: usize = 16;

impl Polytope {
    /// A polytope from its hull's vertices and edges (pairs of vertex indices).
    pub fn new(points: Vec<DVec3>, edges: &[[usize; 2]]) -> Polytope {
        let n = points.len();
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n];
        for &[u, v] in edges {
            if u != v && u < n && v < n {
                lists[u].push(v as u32);
                lists[v].push(u as u32);
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut neighbours = Vec::new();
        offsets.push(0);
        for mut l in lists {
            l.sort_unstable();
            l.dedup();
            neighbours.extend(l);
            offsets.push(neighbours.len() as u32);
        }
        let radius = points.iter().map(|v| v.length()).fold(0.0, f64::max);
        let mut p = Polytope {
            points,
            offsets,
            neighbours,
            starts: Vec::new(),
            radius,
        };
        p.starts = START_DIRECTIONS.iter().map(|d| p.scan(*d) as u32).collect();
        p
    }

    /// Index of a vertex maximising `v . d`, by scanning all vertices.
    fn scan(&self, d: DVec3) -> usize {
        let mut best = 0;
        let mut best_dot = f64::NEG_INFINITY;
        for (i, v) in self.points.iter().enumerate() {
            let s = v.dot(d);
            if s > best_dot {
                best_dot = s;
                best = i;
            }
        }
        best
    }

    /// A good vertex to start a climb in direction `d` from: the support vertex of the
    /// precomputed direction closest to `d`.
    pub fn start_for(&self, d: DVec3) -> usize {
        let mut best = 0;
        let mut best_dot = f64::NEG_INFINITY;
        for (k, s) in START_DIRECTIONS.iter().enumerate() {
            let v = s.dot(d);
            if v > best_dot {
                best_dot = v;
                best = k;
            }
        }
        self.starts.get(best).map_or(0, |&i| i as usize)
    }

    /// A single point (a ball's centre).
    pub fn point(p: DVec3) -> Polytope {
        Polytope {
            points: vec![p],
            offsets: vec![0, 0],
            neighbours: Vec::new(),
            starts: Vec::new(),
            radius: p.length(),
        }
    }

    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Largest distance of a vertex from the frame's origin.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Support point in direction `d` (a vertex maximising `v . d`).
    pub fn support_point(&self, d: DVec3) -> DVec3 {
        self.points[self.support(d, self.start_for(d))]
    }

    /// Index of a vertex maximising `v . d`, climbing from `start`. A vertex of a convex
    /// polytope with no better neighbour along the hull's edges maximises a linear
    /// function (as in the simplex method), so the climb ends at a true support point.
    #[inline]
    fn support(&self, d: DVec3, start: usize) -> usize {
        if self.points.len() < SCAN_BELOW {
            return self.scan(d);
        }
        let mut cur = start.min(self.points.len() - 1);
        let mut cur_dot = self.points[cur].dot(d);
        loop {
            let mut next = cur;
            let (a, b) = (self.offsets[cur] as usize, self.offsets[cur + 1] as usize);
            for &j in &self.neighbours[a..b] {
                let s = self.points[j as usize].dot(d);
                if s > cur_dot {
                    cur_dot = s;
                    next = j as usize;
                }
            }
            if next == cur {
                return cur;
            }
            cur = next;
        }
    }
}

/// Closest point to the origin of the convex hull of `pts` (1 to 4 points), and the
/// subset (bit mask) whose relative interior holds it.
fn closest_on_simplex(pts: &[DVec3]) -> (DVec3, u8) {
    let n = pts.len();
    let mut best = (pts[0], 1u8);
    let mut best_len = f64::INFINITY;
    for mask in 1u8..(1 << n) {
        let mut idx = [0usize; 4];
        let mut m = 0;
        for (i, slot) in (0..n).filter(|i| mask & (1 << i) != 0).zip(0..) {
            idx[slot] = i;
            m += 1;
        }
        let cand = match m {
            1 => Some(pts[idx[0]]),
            2 => {
                let (a, b) = (pts[idx[0]], pts[idx[1]]);
                let ab = b - a;
                let den = ab.length_squared();
                if den <= 0.0 {
                    None
                } else {
                    let t = -a.dot(ab) / den;
                    (t > 0.0 && t < 1.0).then(|| a + ab * t)
                }
            }
            3 => {
                let (a, b, c) = (pts[idx[0]], pts[idx[1]], pts[idx[2]]);
                barycentric_triangle(a, b, c)
            }
            _ => {
                let (a, b, c, d) = (pts[idx[0]], pts[idx[1]], pts[idx[2]], pts[idx[3]]);
                origin_in_tetrahedron(a, b, c, d).then_some(DVec3::ZERO)
            }
        };
        if let Some(p) = cand {
            let l = p.length_squared();
            if l < best_len {
                best_len = l;
                best = (p, mask);
            }
        }
    }
    best
}

/// The origin's projection on the plane of triangle `abc`, if it falls strictly inside.
fn barycentric_triangle(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    let (ab, ac) = (b - a, c - a);
    let (d00, d01, d11) = (ab.dot(ab), ab.dot(ac), ac.dot(ac));
    let (d20, d21) = (-a.dot(ab), -a.dot(ac));
    let den = d00 * d11 - d01 * d01;
    if den <= 1e-300 || den <= 1e-14 * d00 * d11 {
        return None; // degenerate (collinear)
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    let u = 1.0 - v - w;
    (u > 0.0 && v > 0.0 && w > 0.0).then(|| a * u + b * v + c * w)
}

fn origin_in_tetrahedron(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
    let vol = (b - a).cross(c - a).dot(d - a);
    if vol.abs() <= 1e-300 {
        return false;
    }
    // The origin is inside iff it is on the same side of every face as the opposite vertex.
    let side = |p: DVec3, q: DVec3, r: DVec3, opp: DVec3| {
        let n = (q - p).cross(r - p);
        n.dot(-p) * n.dot(opp - p) > 0.0
    };
    side(a, b, c, d) && side(a, b, d, c) && side(a, c, d, b) && side(b, c, d, a)
}

/// A lower bound of the distance between `a` and `b`, `b` being given in its own frame
/// and placed in `a`'s frame by `x -> rot * x + pos`. Returns 0 when they intersect (or
/// touch within rounding). Within [`REL_TOL`] (or 1 nm) of the true distance when it converges,
/// and never above it.
pub fn distance_lower_bound(a: &Polytope, b: &Polytope, rot: DQuat, pos: DVec3) -> f64 {
    distance_lower_bound_warm(a, b, rot, pos, REL_TOL, &mut Warm::default())
}

/// What one query leaves for the next query of the same pair at a nearby pose: the last
/// closest point of `A - B` (in `a`'s frame) and the last support vertices. Starting
/// there, a query of a pose that changed a little converges in one or two iterations.
#[derive(Clone, Copy, Debug, Default)]
pub struct Warm {
    v: Option<DVec3>,
    ids: (usize, usize),
    /// Unit axis (in `a`'s frame, pointing from `b` to `a`) along which the last query's
    /// bound holds: the slab between the two shapes across it is that wide.
    axis: Option<DVec3>,
}

impl Warm {
    /// The separating axis of the last query's bound (see the field), if it was positive.
    pub fn axis(&self) -> Option<DVec3> {
        self.axis
    }
}

/// [`distance_lower_bound`], starting from (and updating) `warm`, and stopping once the
/// bound is within `rel_tol` (relative) of the true distance.
pub fn distance_lower_bound_warm(
    a: &Polytope,
    b: &Polytope,
    rot: DQuat,
    pos: DVec3,
    rel_tol: f64,
    warm: &mut Warm,
) -> f64 {
    let inv = rot.inverse();
    let (d0, start) = match warm.v {
        Some(v) if v.length_squared() > 0.0 => (-v, warm.ids),
        _ => (
            DVec3::X,
            (a.start_for(DVec3::X), b.start_for(inv * -DVec3::X)),
        ),
    };
    // Support of the Minkowski difference A - B in direction d, climbing from the last
    // support points (GJK's directions change little from one iteration to the next).
    let mut last = start;
    let mut sup = |d: DVec3| -> (DVec3, (usize, usize)) {
        let ia = a.support(d, last.0);
        let ib = b.support(inv * -d, last.1);
        last = (ia, ib);
        (a.points[ia] - (rot * b.points[ib] + pos), (ia, ib))
    };
    let (w0, id0) = sup(d0);
    // The simplex lives in fixed arrays: no allocation per query.
    let mut simplex = [DVec3::ZERO; 4];
    let mut ids = [(usize::MAX, usize::MAX); 4];
    simplex[0] = w0;
    ids[0] = id0;
    let mut n = 1;
    let mut v = w0;
    let mut lower: f64 = 0.0;
    let mut axis = None;
    let mut result = None;
    for _ in 0..MAX_ITERATIONS {
        let vl2 = v.length_squared();
        if vl2 <= ABS_TOL * ABS_TOL {
            result = Some(0.0);
            break;
        }
        let vl = vl2.sqrt();
        let (w, id) = sup(-v);
        // Separating-plane bound: every point x of A - B has v . x >= v . w.
        let bound = v.dot(w) / vl;
        if bound > lower {
            lower = bound;
            axis = Some(v / vl);
        }
        if vl - lower <= ABS_TOL.max(rel_tol * vl) || ids[..n].contains(&id) || n == 4 {
            break;
        }
        simplex[n] = w;
        ids[n] = id;
        n += 1;
        let (p, mask) = closest_on_simplex(&simplex[..n]);
        let mut k = 0;
        for i in 0..n {
            if mask & (1 << i) != 0 {
                simplex[k] = simplex[i];
                ids[k] = ids[i];
                k += 1;
            }
        }
        n = k;
        if p.length_squared() >= vl2 {
            // No progress (rounding): the bound found so far stands.
            break;
        }
        v = p;
        if n == 4 {
            // The closest point of a full tetrahedron is the origin itself (inside).
            result = Some(0.0);
            break;
        }
    }
    warm.v = Some(v);
    warm.ids = ids[0];
    warm.axis = if result.is_none() { axis } else { None };
    result.unwrap_or(lower.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn box_polytope(he: DVec3) -> Polytope {
        Polytope::new(crate::geometry::shape::box_corners(he).to_vec(), &[])
    }

    /// Tiny deterministic generator for the tests.
    fn rng(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64)
    }

    #[test]
    fn axis_aligned_boxes_match_the_closed_form() {
        let a = box_polytope(DVec3::new(0.1, 0.05, 0.02));
        let b = box_polytope(DVec3::new(0.03, 0.2, 0.04));
        let mut s = 7u64;
        for _ in 0..500 {
            let pos = DVec3::new(rng(&mut s) - 0.5, rng(&mut s) - 0.5, rng(&mut s) - 0.5);
            let gap = (pos.abs() - DVec3::new(0.13, 0.25, 0.06)).max(DVec3::ZERO);
            let exact = gap.length();
            let got = distance_lower_bound(&a, &b, DQuat::IDENTITY, pos);
            assert!(
                got <= exact + 1e-12,
                "bound {got} above the distance {exact}"
            );
            assert!(
                exact - got <= 1e-9 + 1e-6 * exact,
                "bound {got} far below {exact}"
            );
        }
    }

    #[test]
    fn rotated_point_sets_agree_with_a_point_to_hull_reference() {
        // B is a single point: the distance to conv(A) for a box A is the distance to the
        // box, in closed form in A's frame.
        let he = DVec3::new(0.07, 0.035, 0.0175);
        let a = box_polytope(he);
        let b = Polytope::point(DVec3::new(0.01, -0.02, 0.03));
        let mut s = 3u64;
        for _ in 0..500 {
            let rot = DQuat::from_scaled_axis(DVec3::new(
                rng(&mut s) * 6.0,
                rng(&mut s) * 6.0,
                rng(&mut s) * 6.0,
            ));
            let pos = DVec3::new(rng(&mut s) - 0.5, rng(&mut s) - 0.5, rng(&mut s) - 0.5) * 0.4;
            let p = rot * b.points()[0] + pos;
            let exact = (p.abs() - he).max(DVec3::ZERO).length();
            let got = distance_lower_bound(&a, &b, rot, pos);
            assert!(got <= exact + 1e-12, "{got} above {exact}");
            assert!(
                exact - got <= 1e-9 + 1e-6 * exact,
                "{got} far below {exact}"
            );
        }
    }

    #[test]
    fn overlapping_sets_give_zero() {
        let a = box_polytope(DVec3::splat(0.1));
        let b = box_polytope(DVec3::splat(0.05));
        let rot = DQuat::from_rotation_z(0.3);
        assert_eq!(
            distance_lower_bound(&a, &b, rot, DVec3::new(0.1, 0.0, 0.0)),
            0.0
        );
    }
}
