//! First contact between flying bodies, and between a flying body and the table.
//!
//! Main types: [`Motion`] (a body's pose as a function of time: exact free flight or
//! staying put), [`ContactShape`] (what the distance queries see: an exact ball, or a
//! convex polytope with its sphere cover, built once per scene) and the functions
//! [`pair_contact_time`] and [`table_contact_time`].
//!
//! Contacts are never missed between frames, because time is not sampled in frames:
//! - Ball against ball is solved in closed form (their centres move on parabolas with the
//!   same gravity, so the relative motion is linear and the contact time is the first
//!   root of a quadratic).
//! - Everything else uses conservative advancement: from a lower bound `D` of the
//!   distance and a bound on how fast it can shrink (relative centre-of-mass speed, along
//!   the separating axis when one is known, plus `|w|max * r` for each body, plus the
//!   relative gravity over the step), we step forward by the largest time in which they
//!   cannot touch. Pairs are only searched while their bounding spheres overlap; far apart,
//!   `D` comes from sphere covers, up close from the f64 GJK of [`crate::geometry::gjk`]. The pair
//!   search stops at [`PAIR_CONTACT_DISTANCE`] (0.1 mm), the table search at
//!   [`CONTACT_DISTANCE`] (1 micrometre). See `docs/contacts.md`.
//!
//! Meshes are tested through their convex hulls (exact for convex pieces, conservative
//! for concave ones: a contact may be reported up to the hull's overhang early). parry
//! (f32) only supplies penetration depths, and never raises GJK's certified bound.

use glam::{DQuat, DVec3};

pub use crate::geometry::distance::CONTACT_DISTANCE;
use crate::geometry::distance::{
    cover_gap, signed_distance, signed_distance_warm, table_signed_distance, ContactShape,
    PosedShape,
};
use crate::geometry::gjk::Warm;
use crate::geometry::shape::Table;
use crate::sim::flight::FreeFlight;

/// Tolerance band (m) of the contact search between two bodies other than spheres: a
/// contact (distance 0) is never missed, and the search stops, reporting a contact, at the
/// first step at which the distance is within this band. So a near miss closer than
/// 0.1 mm may count as a contact (whether it does depends on where the steps land), and
/// the reported time lies between the first moment within 0.1 mm and the touch.
/// Conservative advancement never steps over a contact, but a pass that grazes at a
/// distance `d` costs it about `rate / d` queries per second of grazing, and the
/// optimizer is drawn to such passes (neighbouring pieces' shadows want to overlap); the
/// band bounds that work. A near miss within 0.1 mm is a contact for any real launch.
pub const PAIR_CONTACT_DISTANCE: f64 = 1e-4;
/// A body resting on the table at launch may sink this far (m) into it before that
/// counts as a contact (it is launched from touching contact, distance 0).
pub const TABLE_PENETRATION: f64 = 1e-4;
/// A body has left the table once it is this far (m) above it; after that, returning to
/// the surface is a landing.
pub const TABLE_LEAVE: f64 = 1e-4;
/// Cap on conservative-advancement steps per pair; reaching it (a pass that grazes
/// within micrometres for a long time) is reported as a contact, which is the safe side.
const MAX_STEPS: usize = 100_000;

/// Bounding spheres this far apart (m) hold shapes that certainly do not touch: a
/// thousand times the contact distance, far beyond any rounding or GJK's tolerance.
const APART: f64 = 1e-3;

/// Below this lower bound of the distance (m) between two sphere covers, conservative
/// advancement asks parry for the exact distance; above it, the cheap bound drives it.
const COVER_SWITCH: f64 = 1e-3;

/// A body's motion over the flight, as far as contact detection is concerned.
#[derive(Clone, Copy)]
pub enum Motion<'a> {
    /// Exact free flight.
    Flying(&'a FreeFlight),
    /// Staying put at this pose (origin, orientation, centre of mass).
    Fixed {
        origin: DVec3,
        orientation: DQuat,
        com: DVec3,
    },
}

impl Motion<'_> {
    fn com(&self, t: f64) -> DVec3 {
        match self {
            Motion::Flying(f) => f.com(t),
            Motion::Fixed { com, .. } => *com,
        }
    }

    fn com_velocity(&self, t: f64) -> DVec3 {
        match self {
            Motion::Flying(f) => f.com_velocity(t),
            Motion::Fixed { .. } => DVec3::ZERO,
        }
    }

    fn pose(&self, t: f64) -> (DVec3, DQuat) {
        match self {
            Motion::Flying(f) => f.pose(t),
            Motion::Fixed {
                origin,
                orientation,
                ..
            } => (*origin, *orientation),
        }
    }

    fn max_angular_speed(&self) -> f64 {
        match self {
            Motion::Flying(f) => f.max_angular_speed(),
            Motion::Fixed { .. } => 0.0,
        }
    }

    fn is_flying(&self) -> bool {
        matches!(self, Motion::Flying(_))
    }

    /// Gravity as the flight sees it (zero for a body that stays put).
    fn gravity(&self) -> DVec3 {
        match self {
            Motion::Flying(f) => match f.drag_accel_bound() {
                None => f.com_velocity(1.0) - f.com_velocity(0.0),
                Some(_) => f.gravity(),
            },
            Motion::Fixed { .. } => DVec3::ZERO,
        }
    }

    /// A bound of the acceleration besides gravity (air drag; 0 on a parabola).
    fn extra_accel(&self) -> f64 {
        match self {
            Motion::Flying(f) => f.drag_accel_bound().unwrap_or(0.0),
            Motion::Fixed { .. } => 0.0,
        }
    }

    /// Whether the centre of mass moves on the exact parabola (no drag).
    fn parabolic(&self) -> bool {
        self.extra_accel() == 0.0
    }
}

/// One participant of a pair query.
#[derive(Clone, Copy)]
pub struct Body<'a> {
    pub motion: Motion<'a>,
    pub shape: &'a ContactShape,
    /// Bounding radius about the centre of mass (m).
    pub radius: f64,
}

/// Largest step `s >= 0` with `a s + b s^2 / 2 <= d` (the time two surfaces `d` apart,
/// approaching at speed at most `a + b s`, certainly need to touch).
fn safe_step(d: f64, a: f64, b: f64) -> f64 {
    if d <= 0.0 {
        return 0.0;
    }
    if b <= 1e-300 {
        return if a > 0.0 { d / a } else { f64::INFINITY };
    }
    // Positive root of b/2 s^2 + a s - d = 0, in the cancellation-free form.
    2.0 * d / (a + (a * a + 2.0 * b * d).sqrt())
}

/// Relative accuracy of the distances conservative advancement asks for (they are lower
/// bounds: 5 % low only shortens its steps by 5 %).
const CA_REL_TOL: f64 = 0.05;

/// First time in `[0, horizon]` at which the two bodies touch, if any. At least one of
/// them is flying. Bodies may start touching (validation allows up to 0.1 mm of overlap):
/// then, as for the table, sinking [`TABLE_PENETRATION`] deeper before they have separated,
/// or touching again after separating, is the contact.
pub fn pair_contact_time(a: &Body, b: &Body, horizon: f64) -> Option<f64> {
    debug_assert!(a.motion.is_flying() || b.motion.is_flying());
    if let (Some(ba), Some(bb)) = (BallStart::of(a), BallStart::of(b)) {
        return match ball_pair_contact_time(&ba, &bb, horizon) {
            Ok(time) => time,
            Err(d0) => touching_pair_contact_time(a, b, d0, horizon),
        };
    }
    if let Some(d0) = launch_distance(a, b).filter(|&d| d <= CONTACT_DISTANCE) {
        return touching_pair_contact_time(a, b, d0, horizon);
    }
    let both_fly = a.motion.is_flying() && b.motion.is_flying();
    let reach = a.radius + b.radius;
    // The end of the search: the horizon, or the moment the bounding spheres part for
    // good (two flying bodies only; then no contact is possible afterwards).
    let mut end = horizon;
    // 1. Bounding spheres about the centres of mass.
    let extra = a.motion.extra_accel() + b.motion.extra_accel();
    let s0 = if both_fly && extra == 0.0 {
        // Gravity cancels: d(s) = d0 + dv s exactly.
        let d0 = b.motion.com(0.0) - a.motion.com(0.0);
        let dv = b.motion.com_velocity(0.0) - a.motion.com_velocity(0.0);
        let (s_in, s_out) = linear_overlap_interval(d0, dv, reach, horizon)?;
        end = s_out;
        s_in
    } else {
        // One body flies (relative gravity) or drag bends the paths (relative
        // acceleration at most the drag bounds): conservative advancement.
        let g = if both_fly {
            DVec3::ZERO
        } else if a.motion.is_flying() {
            a.motion.gravity()
        } else {
            b.motion.gravity()
        };
        let gn = g.length() + extra;
        let mut s = 0.0;
        let mut steps = 0;
        loop {
            let d = b.motion.com(s) - a.motion.com(s);
            let gap = d.length() - reach;
            if gap <= CONTACT_DISTANCE {
                break s;
            }
            let rel_v = (b.motion.com_velocity(s) - a.motion.com_velocity(s)).length();
            s += safe_step(gap, rel_v, gn);
            steps += 1;
            if s > horizon {
                return None;
            }
            if steps > MAX_STEPS {
                break s;
            }
        }
    };
    if s0 > horizon {
        return None;
    }
    // 2. Balls are their bounding spheres: the answer is exact already.
    if let (ContactShape::Ball(_), ContactShape::Ball(_)) = (a.shape, b.shape) {
        return Some(s0);
    }
    // 3. Conservative advancement on the true shapes.
    let g_rel = b.motion.gravity() - a.motion.gravity();
    let gn = g_rel.length() + extra;
    let spin = a.motion.max_angular_speed() * a.radius + b.motion.max_angular_speed() * b.radius;
    let mut s = s0;
    let mut warm = Warm::default();
    for _ in 0..MAX_STEPS {
        let (pa, qa) = a.motion.pose(s);
        let (pb, qb) = b.motion.pose(s);
        // The covers' gap bounds the distance from below, which is all that
        // conservative advancement needs; the exact query is only needed up close.
        let (d, axis) = match cover_gap(a.shape, pa, qa, b.shape, pb, qb) {
            Some(lb) if lb > COVER_SWITCH => (lb, None),
            _ => {
                let d = signed_distance_warm(
                    PosedShape {
                        shape: a.shape,
                        position: pa,
                        orientation: qa,
                    },
                    PosedShape {
                        shape: b.shape,
                        position: pb,
                        orientation: qb,
                    },
                    CA_REL_TOL,
                    &mut warm,
                );
                (d.max(0.0), warm.axis().map(|n| qa * n))
            }
        };
        if d <= PAIR_CONTACT_DISTANCE {
            return Some(s);
        }
        let dv = b.motion.com_velocity(s) - a.motion.com_velocity(s);
        let approach = match axis {
            // The bound is the width of the slab between the shapes across the fixed
            // axis `n` (from b to a): it shrinks no faster than the centres approach
            // along `n` plus the spin terms (a rotating body's support moves at most
            // w r), which for a grazing pass is far slower than |dv|.
            Some(n) => (spin + n.dot(dv)).max(0.0),
            None => dv.length() + spin,
        };
        if approach == 0.0 && gn == 0.0 {
            // Both fly (no relative gravity) and the slab can only widen: never again.
            return None;
        }
        s += safe_step(d, approach, gn);
        if s > end {
            return None;
        }
    }
    Some(s)
}

/// The distance of two bodies at launch, where they may touch then: not where their
/// bounding spheres (about the centres of mass) are [`APART`], which hold shapes that
/// cannot, and which no distance query then asks (a ball, which can stand in for a
/// degenerate mesh about its origin instead, is always asked).
fn launch_distance(a: &Body, b: &Body) -> Option<f64> {
    let balls =
        matches!(a.shape, ContactShape::Ball(_)) || matches!(b.shape, ContactShape::Ball(_));
    let gap = a.motion.com(0.0).distance(b.motion.com(0.0)) - a.radius - b.radius;
    if !balls && gap > APART {
        return None;
    }
    let (pa, qa) = a.motion.pose(0.0);
    let (pb, qb) = b.motion.pose(0.0);
    Some(signed_distance(a.shape, pa, qa, b.shape, pb, qb))
}

/// A ball flying without drag, as [`ball_pair_contact_time`] takes it: what the search
/// of a pair needs of its flight, read once (a picture of 64 balls searches 63 pairs
/// of each body at every sample).
#[derive(Clone, Copy, Debug)]
pub struct BallStart {
    /// Its origin and its centre of mass at launch (the same point unless the ball
    /// stands in for a degenerate mesh about its origin).
    origin: DVec3,
    com: DVec3,
    /// Its centre of mass's launch velocity.
    velocity: DVec3,
    /// The ball's radius, and the body's bounding radius about its centre of mass.
    ball: f64,
    radius: f64,
}

impl BallStart {
    /// `body`'s launch, if it is a ball flying without drag.
    pub fn of(body: &Body) -> Option<BallStart> {
        match (body.shape, body.motion) {
            (ContactShape::Ball(r), Motion::Flying(f)) if f.drag_accel_bound().is_none() => {
                Some(BallStart {
                    origin: f.origin(0.0),
                    com: f.com(0.0),
                    velocity: f.com_velocity(0.0),
                    ball: *r,
                    radius: body.radius,
                })
            }
            _ => None,
        }
    }
}

/// [`pair_contact_time`] of two balls flying without drag, in closed form (gravity
/// cancels, so their centres part or meet along a line): `Err` with their distance
/// when they touch at launch, which takes the search of [`pair_contact_time`].
pub fn ball_pair_contact_time(
    a: &BallStart,
    b: &BallStart,
    horizon: f64,
) -> Result<Option<f64>, f64> {
    let d0 = a.origin.distance(b.origin) - a.ball - b.ball;
    if d0 <= CONTACT_DISTANCE {
        return Err(d0);
    }
    let reach = a.radius + b.radius;
    let overlap = linear_overlap_interval(b.com - a.com, b.velocity - a.velocity, reach, horizon);
    Ok(overlap.map(|(s_in, _)| s_in))
}

/// The times in `[0, horizon]` at which `|d0 + dv s| <= reach`: an interval
/// `(s_in, s_out)` (the set is convex, `|d0 + dv s|` being convex in `s`), or `None` if
/// there are none. `s_out` is at most `horizon`.
fn linear_overlap_interval(d0: DVec3, dv: DVec3, reach: f64, horizon: f64) -> Option<(f64, f64)> {
    let c = d0.length_squared() - reach * reach;
    let a = dv.length_squared();
    let b = d0.dot(dv);
    if a == 0.0 {
        return (c <= 0.0).then_some((0.0, horizon));
    }
    // Roots of a s^2 + 2 b s + c = 0; the set is between them.
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    // Cancellation-free pair of roots.
    let qv = -(b + b.signum() * sq);
    let (r1, r2) = if qv != 0.0 {
        (qv / a, c / qv)
    } else {
        (0.0, 0.0)
    };
    let (lo, hi) = (r1.min(r2), r1.max(r2));
    // A small relative margin keeps rounding in the roots on the safe side.
    let margin = 1e-12 * (1.0 + hi.abs());
    let (lo, hi) = (lo.max(0.0), (hi + margin).min(horizon));
    (lo <= hi).then_some((lo, hi))
}

/// Contact time of two bodies that touch at launch (signed distance `d0` <= 1 um).
fn touching_pair_contact_time(a: &Body, b: &Body, d0: f64, horizon: f64) -> Option<f64> {
    let g_rel = b.motion.gravity() - a.motion.gravity();
    let gn = g_rel.length() + a.motion.extra_accel() + b.motion.extra_accel();
    let spin = a.motion.max_angular_speed() * a.radius + b.motion.max_angular_speed() * b.radius;
    let sink_floor = d0.min(0.0) - TABLE_PENETRATION;
    let mut left = false;
    let mut s = 0.0;
    let mut warm = Warm::default();
    for _ in 0..MAX_STEPS {
        let (pa, qa) = a.motion.pose(s);
        let (pb, qb) = b.motion.pose(s);
        let d = signed_distance_warm(
            PosedShape {
                shape: a.shape,
                position: pa,
                orientation: qa,
            },
            PosedShape {
                shape: b.shape,
                position: pb,
                orientation: qb,
            },
            CA_REL_TOL,
            &mut warm,
        );
        if !left && d > TABLE_LEAVE {
            left = true;
        }
        let floor = if left { CONTACT_DISTANCE } else { sink_floor };
        if d <= floor {
            return Some(s);
        }
        let rel_v = (b.motion.com_velocity(s) - a.motion.com_velocity(s)).length();
        s += safe_step(d - floor, rel_v + spin, gn).max(1e-9);
        if s > horizon {
            return None;
        }
    }
    Some(s)
}
/// First time in `(0, horizon]` at which a flying body, launched from rest on (or above)
/// the table, hits it: by sinking more than [`TABLE_PENETRATION`] before it has left the
/// surface, or by coming back to the surface after it has left.
pub fn table_contact_time(
    body: &Body,
    table: &Table,
    table_shape: &ContactShape,
    horizon: f64,
) -> Option<f64> {
    table_contact(body, table, table_shape, horizon).map(|c| c.time)
}

/// A contact of a flying body with the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableContact {
    pub time: f64,
    /// True for a landing (the body had left the table and came back down onto it);
    /// false when it sank into the table before leaving it (launched downward, sliding,
    /// or tipping a corner into it), which costs a contact but is no landing.
    pub landed: bool,
}

/// As [`table_contact_time`], telling a landing from a sinking start.
pub fn table_contact(
    body: &Body,
    table: &Table,
    table_shape: &ContactShape,
    horizon: f64,
) -> Option<TableContact> {
    let flight = match body.motion {
        Motion::Flying(f) => f,
        Motion::Fixed { .. } => return None,
    };
    let parabolic = body.motion.parabolic();
    if let (ContactShape::Ball(r), true) = (body.shape, parabolic) {
        if let Some(answer) = ball_table_closed_form(flight, *r, table, horizon) {
            return answer;
        }
    }
    let g = body.motion.gravity().length() + body.motion.extra_accel();
    let spin = flight.max_angular_speed() * body.radius;
    let mut left = false;
    let mut s = 0.0;
    for _ in 0..MAX_STEPS {
        let (p, q) = body.motion.pose(s);
        let d = table_signed_distance(body.shape, p, q, table, table_shape);
        if !left && d > TABLE_LEAVE {
            left = true;
        }
        let floor = if left {
            CONTACT_DISTANCE
        } else {
            -TABLE_PENETRATION
        };
        if d <= floor {
            // A landing is a body coming back down; a spinning body that clips the table
            // while still rising is a contact, but no landing.
            let landed = left && flight.com_velocity(s).z < 0.0;
            return Some(TableContact { time: s, landed });
        }
        if left && parabolic {
            // While the bounding sphere is above the top face, nothing can touch the
            // table: jump to when its lowest point could come back down to the top.
            if let Some(next) = sphere_clear_of_top(flight, body.radius, table, s, horizon) {
                match next {
                    Some(s_next) if s_next > s => {
                        s = s_next;
                        continue;
                    }
                    Some(_) => {}
                    None => return None,
                }
            }
        }
        let v = flight.com_velocity(s).length();
        let step = safe_step(d - floor, v + spin, g).max(1e-9);
        s += step;
        if s > horizon {
            return None;
        }
    }
    Some(TableContact {
        time: s,
        landed: left && flight.com_velocity(s).z < 0.0,
    })
}

/// If the bounding sphere (about the centre of mass, radius `r`) is entirely above the
/// table's top face at time `s`, the first later time at which it could touch the top
/// again: `Some(Some(time))`, or `Some(None)` if not before `horizon`. `None` when the
/// sphere is not clear of the top at `s` (use conservative advancement).
///
/// While the sphere's lowest point is above the top plane and its centre stays over the
/// top face shrunk by `r`, the body cannot touch the table: the centre moves on a line
/// horizontally (a convex region contains the whole segment if it contains both ends),
/// and the lowest point's height is a quadratic in time.
fn sphere_clear_of_top(
    f: &FreeFlight,
    r: f64,
    table: &Table,
    s: f64,
    horizon: f64,
) -> Option<Option<f64>> {
    let top = table.top();
    let inside = |c: DVec3| {
        let d = (c - table.center).abs();
        d.x + r <= table.half_extents.x && d.y + r <= table.half_extents.y
    };
    let c = f.com(s);
    let h0 = c.z - r - top;
    // Written so that a NaN height also declines.
    if h0.partial_cmp(&CONTACT_DISTANCE) != Some(std::cmp::Ordering::Greater) || !inside(c) {
        return None;
    }
    // h(s + u) = h0 + b u + a u^2 / 2; first u > 0 with h = 0 (a < 0 under gravity).
    let b = f.com_velocity(s).z;
    let a = f.com_velocity(s + 1.0).z - b;
    let u = if a < 0.0 {
        // Positive root of a/2 u^2 + b u + h0 = 0, cancellation-free.
        let disc = b * b - 2.0 * a * h0;
        let sq = disc.max(0.0).sqrt();
        if b >= 0.0 {
            (b + sq) / (-a)
        } else {
            2.0 * h0 / (sq - b)
        }
    } else if b < 0.0 {
        // No downward gravity: a linear (or slower) descent.
        h0 / (-b)
    } else {
        f64::INFINITY
    };
    // A hair early, so that rounding can never skip past a contact.
    let next = s + u * (1.0 - 1e-9);
    if next > horizon {
        return Some(None);
    }
    if !inside(f.com(next)) {
        return None;
    }
    Some(Some(next))
}

/// Closed-form table contact of a ball that starts over the table's top face: its lowest
/// point's height above the top is a quadratic in time, and while it is above the top
/// plane the ball can touch nothing but the top face. Returns `None` (use conservative
/// advancement) when the ball does not start over the top face, or when it comes down
/// beyond the top face's edges.
fn ball_table_closed_form(
    f: &FreeFlight,
    r: f64,
    table: &Table,
    horizon: f64,
) -> Option<Option<TableContact>> {
    let over_top = |c: DVec3| {
        let d = (c - table.center).abs();
        d.x <= table.half_extents.x && d.y <= table.half_extents.y
    };
    let c0 = f.com(0.0);
    if !over_top(c0) {
        return None;
    }
    let top = table.top();
    // h(s) = h0 + b s + a s^2 / 2: height of the ball's lowest point above the top.
    let h0 = c0.z - r - top;
    let b = f.com_velocity(0.0).z;
    let a = f.com_velocity(1.0).z - b;
    if h0 < -TABLE_PENETRATION {
        return None; // starts sunk in (validation forbids it); let the general path decide
    }
    // First time the height falls to `level` from above, after `from`.
    let first_down = |level: f64, from: f64| -> Option<f64> {
        // Roots of a/2 s^2 + b s + (h0 - level) = 0.
        let (qa, qb, qc) = (0.5 * a, b, h0 - level);
        let roots = if qa.abs() < 1e-300 {
            if qb == 0.0 {
                return None;
            }
            [-qc / qb, f64::NAN]
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc < 0.0 {
                return None;
            }
            let sq = disc.sqrt();
            // Cancellation-free pair of roots.
            let q = -0.5 * (qb + qb.signum() * sq);
            let (r1, r2) = if q == 0.0 {
                (0.0, 0.0)
            } else {
                (q / qa, qc / q)
            };
            [r1.min(r2), r1.max(r2)]
        };
        roots
            .into_iter()
            .filter(|x| x.is_finite() && *x >= from)
            // Going down through `level`: h'(s) = b + a s < 0 (or touching at the apex).
            .find(|&x| b + a * x <= 0.0)
    };
    let sinks = h0 <= TABLE_LEAVE && b <= 0.0 && a <= 0.0;
    let answer = if sinks {
        // Resting and not launched upward: it sinks at once.
        first_down(-TABLE_PENETRATION, 0.0)
    } else {
        first_down(CONTACT_DISTANCE, 1e-12)
    };
    match answer {
        Some(s) if s > horizon => Some(None),
        Some(s) if over_top(f.com(s)) => Some(Some(TableContact {
            time: s,
            landed: !sinks,
        })),
        Some(_) => None, // comes down past an edge of the top face
        None => Some(None),
    }
}

#[cfg(test)]
mod tests;
