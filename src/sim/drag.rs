//! Quadratic air drag (and optional Magnus lift) on the centre of mass, integrated
//! accurately: the physics model of the error budget (`crate::budget`).
//!
//! Main types: [`DragConfig`] (air density, drag coefficients per shape, Magnus switch,
//! integrator step, with documented defaults and units, in the manner of rapier's
//! `IntegrationParameters`), [`BodyDrag`] (the per-body coefficients derived once from a
//! shape and a mass) and [`fly`] (the centre of mass from a launch state to a time).
//!
//! Model, per body of mass `m` (see `docs/budget.md`):
//!
//! ```text
//! x'' = g - k |v| v + k_L(|v|, w) (w_hat x v),     k = rho Cd A / (2 m)
//! ```
//!
//! * `A` is the reference area: the mean projected area, `S / 4` by Cauchy's formula for
//!   a convex body of surface area `S` (`pi r^2` for a sphere); a mesh uses its convex
//!   hull's `S / 4`, which bounds its mean shadow from above (field notes).
//! * Magnus lift (spheres only, off by default): `F = 1/2 rho C_L A |v| (w_hat x v)` with
//!   the spin parameter `S = r |w| / |v|` and the lift model `C_L = S / (1 + 2 S)`
//!   (`= 1 / (2 + 1/S)`, Sawicki, Hubbard and Stronge's baseball fit, which has the right
//!   limits: `C_L ~ S` for slow spin, 1/2 for fast spin). It needs no division by `|v|`.
//! * No drag torque: the rotation stays the exact torque-free one of
//!   [`crate::sim::flight::FreeFlight`] (a sphere keeps its spin, so the Magnus axis is fixed).
//!
//! The integrator is classical RK4 on a uniform grid of at most
//! [`DragConfig::max_step`] seconds. Measured against the closed forms of vertical
//! flight with quadratic drag and a tiny-step independent reference (tests below and
//! `docs/budget.md`): errors of ~1e-12 m over a 1.2 s flight, far inside the 0.1 mm
//! required.
//!
//! The numeric core does not fail: non-finite input gives non-finite output, which the
//! caller counts as a diverged sample.

use glam::DVec3;
use serde::Serialize;

use crate::geometry::shape::Shape;
use crate::scene::short;

/// Air density at 20 C and sea level (kg/m^3).
pub const AIR_DENSITY: f64 = 1.204;
/// Drag coefficient of a smooth sphere, flat for Reynolds numbers 1e3 to 3e5.
pub const CD_SPHERE: f64 = 0.47;
/// Drag coefficient of a cube/box face-on (0.8 edge-on, about 1.0 tumbling).
pub const CD_BOX: f64 = 1.05;
/// Drag coefficient of a mesh (chess piece, other bluff bodies), tumbling average.
pub const CD_MESH: f64 = 1.0;
/// Default longest RK4 step (s).
pub const DEFAULT_MAX_STEP: f64 = 0.01;
/// Largest accepted drag or lift coefficient (anything above is surely a typo).
pub const MAX_COEFFICIENT: f64 = 10.0;
/// Largest accepted air density (kg/m^3): denser than any gas one launches through.
pub const MAX_DENSITY: f64 = 100.0;

/// Air and integrator settings. Units: SI (kg/m^3, s).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct DragConfig {
    /// Air density (kg/m^3). Default [`AIR_DENSITY`] (1.204, dry air at 20 C, 1 atm).
    /// 0 turns drag off (the vacuum flight, a useful check).
    pub rho: f64,
    /// Drag coefficient of spheres. Default [`CD_SPHERE`] (0.47).
    pub cd_sphere: f64,
    /// Drag coefficient of boxes. Default [`CD_BOX`] (1.05, face-on; tumbling ~1.0).
    pub cd_box: f64,
    /// Drag coefficient of meshes. Default [`CD_MESH`] (1.0).
    pub cd_mesh: f64,
    /// Magnus lift on spinning spheres. Default off.
    pub magnus: bool,
    /// Longest RK4 step (s). Default [`DEFAULT_MAX_STEP`] (10 ms).
    pub max_step: f64,
}

impl Default for DragConfig {
    fn default() -> Self {
        DragConfig {
            rho: AIR_DENSITY,
            cd_sphere: CD_SPHERE,
            cd_box: CD_BOX,
            cd_mesh: CD_MESH,
            magnus: false,
            max_step: DEFAULT_MAX_STEP,
        }
    }
}

/// Why a [`DragConfig`] was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DragError {
    #[error("air density must be between 0 and {MAX_DENSITY} kg/m^3, got {}", short(*.0))]
    Density(f64),
    #[error(
        "the drag coefficient of {shape} must be between 0 and {MAX_COEFFICIENT}, got {}", short(*.value)
    )]
    Coefficient { shape: &'static str, value: f64 },
    #[error("the integrator step must be positive and at most 0.1 s, got {}", short(*.0))]
    Step(f64),
}

impl DragConfig {
    /// The same drag coefficient for every shape.
    pub fn with_cd(mut self, cd: f64) -> Self {
        self.cd_sphere = cd;
        self.cd_box = cd;
        self.cd_mesh = cd;
        self
    }

    /// Check every value (finite, in range).
    pub fn validate(&self) -> Result<(), DragError> {
        if !(self.rho.is_finite() && (0.0..=MAX_DENSITY).contains(&self.rho)) {
            return Err(DragError::Density(self.rho));
        }
        for (shape, value) in [
            ("spheres", self.cd_sphere),
            ("boxes", self.cd_box),
            ("meshes", self.cd_mesh),
        ] {
            if !(value.is_finite() && (0.0..=MAX_COEFFICIENT).contains(&value)) {
                return Err(DragError::Coefficient { shape, value });
            }
        }
        if !(self.max_step.is_finite() && self.max_step > 0.0 && self.max_step <= 0.1) {
            return Err(DragError::Step(self.max_step));
        }
        Ok(())
    }

    /// Drag coefficient of a shape.
    pub fn cd(&self, shape: &Shape) -> f64 {
        match shape {
            Shape::Sphere { .. } => self.cd_sphere,
            Shape::Cuboid { .. } => self.cd_box,
            Shape::Mesh(_) => self.cd_mesh,
        }
    }
}

/// Reference (mean projected) area of a shape (m^2): `S / 4` of the shape, or of its
/// convex hull for a mesh (Cauchy's formula; exact for convex bodies, an upper bound of
/// the mean shadow of a concave one).
pub fn reference_area(shape: &Shape) -> f64 {
    match shape {
        Shape::Sphere { radius } => std::f64::consts::PI * radius * radius,
        Shape::Cuboid { half_extents: h } => {
            // S = 2 (ab + bc + ca) with full sides a = 2 h.x, ...; S / 4 = 2 (h.x h.y + ...).
            2.0 * (h.x * h.y + h.y * h.z + h.z * h.x)
        }
        Shape::Mesh(mesh) => hull_area(mesh) / 4.0,
    }
}

/// Surface area of the convex hull of points (m^2): parry's hull (in f32, about the
/// centroid of the points, so relative precision ~1e-7), its triangle areas summed in f64.
/// Falls back to the mesh's own area if parry finds the hull degenerate.
fn hull_area(mesh: &crate::geometry::shape::TriMesh) -> f64 {
    use rapier3d::parry::transformation::try_convex_hull;
    let points = &mesh.vertices;
    if points.len() < 4 {
        return mesh.surface_area();
    }
    let c = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let pts: Vec<_> = points.iter().map(|p| (*p - c).as_vec3()).collect();
    match try_convex_hull(&pts) {
        Ok((verts, faces)) if !faces.is_empty() => faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| verts[i as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            })
            .sum(),
        _ => mesh.surface_area(),
    }
}

/// The drag coefficients of one body, derived once.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BodyDrag {
    /// Drag coefficient used.
    pub cd: f64,
    /// Reference area (m^2).
    pub area: f64,
    /// Mass (kg).
    pub mass: f64,
    /// `rho A / (2 m)` (1/m): the drag deceleration is `cd * half_rho_a_over_m * |v|^2`.
    pub half_rho_a_over_m: f64,
    /// Radius for the Magnus spin parameter; `None` when Magnus lift is off or the body
    /// is not a sphere.
    pub magnus_radius: Option<f64>,
}

impl BodyDrag {
    pub fn new(shape: &Shape, mass: f64, cfg: &DragConfig) -> BodyDrag {
        let area = reference_area(shape);
        BodyDrag {
            cd: cfg.cd(shape),
            area,
            mass,
            half_rho_a_over_m: cfg.rho * area / (2.0 * mass),
            magnus_radius: match shape {
                Shape::Sphere { radius } if cfg.magnus => Some(*radius),
                _ => None,
            },
        }
    }

    /// The same body with its drag coefficient multiplied by `factor` (clamped at 0).
    pub fn with_cd_factor(&self, factor: f64) -> BodyDrag {
        BodyDrag {
            cd: self.cd * factor.max(0.0),
            ..*self
        }
    }

    /// The drag constant `k = rho Cd A / (2 m)` (1/m).
    pub fn k(&self) -> f64 {
        self.cd * self.half_rho_a_over_m
    }

    /// Terminal speed `sqrt(g / k)` (m/s) for gravity `g`.
    pub fn terminal_speed(&self, g: f64) -> f64 {
        (g / self.k()).sqrt()
    }

    /// Acceleration at velocity `v` with angular velocity `w`.
    #[inline]
    fn accel(&self, v: DVec3, g: DVec3, k: f64, lift: Option<(f64, DVec3)>) -> DVec3 {
        let s = v.length();
        let mut a = g - v * (k * s);
        if let Some((rw, w_hat)) = lift {
            // 1/2 rho A C_L |v| / m with C_L = S / (1 + 2 S), S = r|w| / |v|:
            // |v| C_L = r|w| |v| / (|v| + 2 r|w|).
            let denom = s + 2.0 * rw;
            if denom > 0.0 {
                a += w_hat.cross(v) * (self.half_rho_a_over_m * rw * s / denom);
            }
        }
        a
    }
}

/// The centre of mass after `duration` seconds of flight with drag from position `x0`,
/// velocity `v0` (m/s), angular velocity `w` (rad/s, constant for a sphere; used only
/// for Magnus lift) and gravity `g`: `(position, velocity)`. Classical RK4 with
/// `ceil(|duration| / max_step)` equal steps; a negative duration integrates backwards.
pub fn fly(
    body: &BodyDrag,
    x0: DVec3,
    v0: DVec3,
    w: DVec3,
    g: DVec3,
    duration: f64,
    max_step: f64,
) -> (DVec3, DVec3) {
    if !duration.is_finite() || !max_step.is_finite() || max_step <= 0.0 {
        return (DVec3::NAN, DVec3::NAN);
    }
    if duration == 0.0 {
        return (x0, v0);
    }
    let n = (duration.abs() / max_step).ceil().clamp(1.0, 1e8) as usize;
    let h = duration / n as f64;
    let k = body.k();
    let lift = body.magnus_radius.and_then(|r| {
        let wl = w.length();
        (wl > 0.0).then(|| (r * wl, w / wl))
    });
    let (mut x, mut v) = (x0, v0);
    for _ in 0..n {
        (x, v) = rk4_step(body, x, v, g, k, lift, h);
    }
    (x, v)
}

/// The centre of mass of one body flown with drag, stored on a step grid so that any
/// instant costs one partial RK4 step: the drag flight that [`crate::sim::flight::FreeFlight`]
/// follows when a solve has air in the loop. The grid is [`fly`]'s: a query at the end
/// of the grid gives the bits of `fly` over the whole span.
#[derive(Clone, Debug, Default)]
pub struct DragTrack {
    body: Option<BodyDrag>,
    g: DVec3,
    k: f64,
    lift: Option<(f64, DVec3)>,
    h: f64,
    inv_h: f64,
    /// (position, velocity) at `k h`, `k = 0..=n`.
    nodes: Vec<(DVec3, DVec3)>,
    /// An upper bound of the drag (and lift) acceleration's magnitude over the grid.
    accel_bound: f64,
}

impl DragTrack {
    /// Fly `body` from `x0` with velocity `v0` (spin `w`, for Magnus lift) under gravity
    /// `g` over `[0, t_max]` with steps of at most `max_step`. Reuses the grid buffer.
    #[allow(clippy::too_many_arguments)]
    pub fn reset(
        &mut self,
        body: &BodyDrag,
        x0: DVec3,
        v0: DVec3,
        w: DVec3,
        g: DVec3,
        t_max: f64,
        max_step: f64,
    ) {
        self.body = Some(*body);
        self.g = g;
        self.k = body.k();
        self.lift = body.magnus_radius.and_then(|r| {
            let wl = w.length();
            (wl > 0.0).then(|| (r * wl, w / wl))
        });
        self.nodes.clear();
        self.nodes.push((x0, v0));
        let n = if t_max.is_finite() && t_max > 0.0 && max_step > 0.0 {
            (t_max / max_step).ceil().clamp(1.0, 1e7) as usize
        } else {
            0
        };
        self.h = if n > 0 { t_max / n as f64 } else { max_step };
        self.inv_h = 1.0 / self.h;
        let (mut x, mut v) = (x0, v0);
        let mut bound: f64 = 0.0;
        for _ in 0..n {
            bound = bound.max((body.accel(v, g, self.k, self.lift) - g).length());
            (x, v) = rk4_step(body, x, v, g, self.k, self.lift, self.h);
            self.nodes.push((x, v));
        }
        bound = bound.max((body.accel(v, g, self.k, self.lift) - g).length());
        // Between two nodes the speed changes by at most |a| h (2 % for 10 ms at a few
        // m/s), the drag by about twice that: a 25 % margin covers it.
        self.accel_bound = 1.25 * bound + 1e-12;
    }

    /// Centre of mass and its velocity at `t`: one partial RK4 step from the grid node
    /// at or before `t`; outside the grid, full steps from its nearer end.
    pub fn state(&self, t: f64) -> (DVec3, DVec3) {
        let Some(body) = &self.body else {
            return (DVec3::NAN, DVec3::NAN);
        };
        let n = self.nodes.len() - 1;
        let s = t * self.inv_h;
        let step =
            |(x, v): (DVec3, DVec3), h: f64| rk4_step(body, x, v, self.g, self.k, self.lift, h);
        if (0.0..=n as f64).contains(&s) {
            let k = (s as usize).min(n);
            let tau = t - k as f64 * self.h;
            if tau == 0.0 {
                return self.nodes[k];
            }
            return step(self.nodes[k], tau);
        }
        if !t.is_finite() {
            return (DVec3::NAN, DVec3::NAN);
        }
        let (mut xv, mut remaining, h) = if t > 0.0 {
            (self.nodes[n], t - n as f64 * self.h, self.h)
        } else {
            (self.nodes[0], t, -self.h)
        };
        while remaining.abs() > self.h {
            xv = step(xv, h);
            remaining -= h;
        }
        step(xv, remaining)
    }

    /// An upper bound of the magnitude of the acceleration besides gravity (drag and
    /// lift), for conservative advancement.
    pub fn accel_bound(&self) -> f64 {
        self.accel_bound
    }
}

/// One classical RK4 step of length `h` of the drag flight.
#[inline(always)]
fn rk4_step(
    body: &BodyDrag,
    x: DVec3,
    v: DVec3,
    g: DVec3,
    k: f64,
    lift: Option<(f64, DVec3)>,
    h: f64,
) -> (DVec3, DVec3) {
    let a1 = body.accel(v, g, k, lift);
    let v2 = v + a1 * (0.5 * h);
    let a2 = body.accel(v2, g, k, lift);
    let v3 = v + a2 * (0.5 * h);
    let a3 = body.accel(v3, g, k, lift);
    let v4 = v + a3 * h;
    let a4 = body.accel(v4, g, k, lift);
    (
        x + (v + (v2 + v3) * 2.0 + v4) * (h / 6.0),
        v + (a1 + (a2 + a3) * 2.0 + a4) * (h / 6.0),
    )
}

/// One flight of [`fly_each`]: the body and its launch state and duration.
#[derive(Clone, Copy, Debug)]
pub struct Flight {
    pub body: BodyDrag,
    pub x0: DVec3,
    pub v0: DVec3,
    pub w: DVec3,
    pub duration: f64,
}

/// [`fly`] of several flights under the same gravity and step bound: each result is the
/// same, bit for bit, as its own `fly`. The flights are integrated four abreast, because
/// one flight is a chain of dependent square roots that leaves the processor waiting;
/// four independent chains keep it busy.
pub fn fly_each(flights: &[Flight], g: DVec3, max_step: f64, out: &mut [(DVec3, DVec3)]) {
    assert_eq!(flights.len(), out.len());
    for (chunk, res) in flights.chunks(4).zip(out.chunks_mut(4)) {
        if chunk.len() < 4
            || !max_step.is_finite()
            || max_step <= 0.0
            || chunk
                .iter()
                .any(|f| !f.duration.is_finite() || f.duration == 0.0)
        {
            for (f, r) in chunk.iter().zip(res.iter_mut()) {
                *r = fly(&f.body, f.x0, f.v0, f.w, g, f.duration, max_step);
            }
            continue;
        }
        let n = chunk.map_lanes(|f| (f.duration.abs() / max_step).ceil().clamp(1.0, 1e8) as usize);
        let h = [0, 1, 2, 3].map(|l| chunk[l].duration / n[l] as f64);
        let k = chunk.map_lanes(|f| f.body.k());
        let lift = chunk.map_lanes(|f| {
            f.body.magnus_radius.and_then(|r| {
                let wl = f.w.length();
                (wl > 0.0).then(|| (r * wl, f.w / wl))
            })
        });
        let mut x = chunk.map_lanes(|f| f.x0);
        let mut v = chunk.map_lanes(|f| f.v0);
        let common = *n.iter().min().expect("four lanes");
        for _ in 0..common {
            for l in 0..4 {
                let (body, kl, ll, hl) = (&chunk[l].body, k[l], lift[l], h[l]);
                (x[l], v[l]) = rk4_step(body, x[l], v[l], g, kl, ll, hl);
            }
        }
        for l in 0..4 {
            let (body, kl, ll, hl) = (&chunk[l].body, k[l], lift[l], h[l]);
            for _ in common..n[l] {
                (x[l], v[l]) = rk4_step(body, x[l], v[l], g, kl, ll, hl);
            }
            res[l] = (x[l], v[l]);
        }
    }
}

/// A value per lane of a chunk of four flights.
trait Lanes {
    fn map_lanes<T>(&self, f: impl Fn(&Flight) -> T) -> [T; 4];
}

impl Lanes for [Flight] {
    fn map_lanes<T>(&self, f: impl Fn(&Flight) -> T) -> [T; 4] {
        [0, 1, 2, 3].map(|l| f(&self[l]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball(k: f64) -> BodyDrag {
        BodyDrag {
            cd: 1.0,
            area: 1.0,
            mass: 1.0,
            half_rho_a_over_m: k,
            magnus_radius: None,
        }
    }

    #[test]
    fn flights_four_abreast_give_the_bits_of_one_at_a_time() {
        let g = DVec3::new(0.0, 0.0, -9.81);
        let mut b = ball(0.07);
        for count in [1, 3, 4, 5, 8, 9] {
            let flights: Vec<Flight> = (0..count)
                .map(|i| {
                    let f = i as f64;
                    // Some with Magnus lift, durations that give different step counts.
                    b.magnus_radius = (i % 3 == 0).then_some(0.1);
                    Flight {
                        body: b,
                        x0: DVec3::new(f, -f, 0.5),
                        v0: DVec3::new(0.3 * f, 1.0, 6.0 + f),
                        w: DVec3::new(0.0, f, 2.0),
                        duration: 1.2 + 0.004 * f - if i == 2 { 2.5 } else { 0.0 },
                    }
                })
                .collect();
            let mut out = vec![(DVec3::ZERO, DVec3::ZERO); count];
            fly_each(&flights, g, 0.01, &mut out);
            for (f, got) in flights.iter().zip(&out) {
                let want = fly(&f.body, f.x0, f.v0, f.w, g, f.duration, 0.01);
                let bits = |(x, v): (DVec3, DVec3)| {
                    [x.to_array(), v.to_array()].map(|a| a.map(f64::to_bits))
                };
                assert_eq!(bits(*got), bits(want), "{count} flights");
            }
        }
    }

    /// Vertical fall from rest: v(t) = v_T tanh(g t / v_T), drop = v_T^2 / g ln cosh(g t / v_T).
    #[test]
    fn vertical_fall_matches_the_tanh_closed_form() {
        let g = 9.81;
        // A wooden-cube-like k (v_T ~ 12 m/s) and a heavy-drag one (v_T ~ 3 m/s).
        for k in [0.07, 1.0] {
            let b = ball(k);
            let vt = b.terminal_speed(g);
            let mut worst: f64 = 0.0;
            for i in 1..=15 {
                let t = 0.1 * i as f64;
                let (x, v) = fly(
                    &b,
                    DVec3::ZERO,
                    DVec3::ZERO,
                    DVec3::ZERO,
                    DVec3::new(0.0, 0.0, -g),
                    t,
                    DEFAULT_MAX_STEP,
                );
                let v_ref = -vt * (g * t / vt).tanh();
                let x_ref = -vt * vt / g * (g * t / vt).cosh().ln();
                worst = worst.max((x.z - x_ref).abs());
                assert!(
                    (v.z - v_ref).abs() < 1e-7,
                    "k {k} t {t}: v {} vs {v_ref}",
                    v.z
                );
                assert!(x.x == 0.0 && x.y == 0.0);
            }
            eprintln!("tanh fall, k = {k} 1/m, v_T = {vt:.3} m/s: max position error {worst:.3e} m over 1.5 s");
            assert!(worst < 1e-7, "k {k}: {worst}"); // 0.1 um, far below the 0.1 mm required
        }
    }

    /// Vertical throw up to the apex: v(t) = v_T tan(atan(v0 / v_T) - g t / v_T),
    /// height = v_T^2 / g ln(cos(atan(v0/v_T) - g t/v_T) / cos(atan(v0/v_T))).
    #[test]
    fn vertical_rise_matches_the_tan_closed_form() {
        let g = 9.81;
        let b = ball(0.05);
        let vt = b.terminal_speed(g);
        let v0 = 7.0;
        let a0 = (v0 / vt).atan();
        let t_apex = a0 * vt / g;
        let mut worst: f64 = 0.0;
        for i in 1..=10 {
            let t = t_apex * i as f64 / 10.0;
            let (x, v) = fly(
                &b,
                DVec3::ZERO,
                DVec3::new(0.0, 0.0, v0),
                DVec3::ZERO,
                DVec3::new(0.0, 0.0, -g),
                t,
                DEFAULT_MAX_STEP,
            );
            let ph = a0 - g * t / vt;
            let v_ref = vt * ph.tan();
            let z_ref = vt * vt / g * (ph.cos() / a0.cos()).ln();
            worst = worst.max((x.z - z_ref).abs());
            assert!((v.z - v_ref).abs() < 1e-7, "t {t}: {} vs {v_ref}", v.z);
        }
        eprintln!("tan rise to the apex ({t_apex:.3} s): max position error {worst:.3e} m");
        assert!(worst < 1e-7, "{worst}");
    }

    /// An independent tiny-step reference for a 3-D throw with drag and Magnus lift:
    /// explicit midpoint (second order, a different method) with 1e-5 s steps.
    fn midpoint_reference(b: &BodyDrag, v0: DVec3, w: DVec3, g: DVec3, t: f64, n: usize) -> DVec3 {
        let h = t / n as f64;
        let acc = |v: DVec3| -> DVec3 {
            let s = v.length();
            let mut a = g - b.k() * s * v;
            if let Some(r) = b.magnus_radius {
                let wl = w.length();
                let spin = r * wl / s; // spin parameter S
                let cl = spin / (1.0 + 2.0 * spin);
                // F / m = 1/2 rho C_L A |v| (w_hat x v) / m
                a += b.half_rho_a_over_m * cl * s * (w / wl).cross(v);
            }
            a
        };
        let (mut x, mut v) = (DVec3::ZERO, v0);
        for _ in 0..n {
            let vm = v + 0.5 * h * acc(v);
            x += h * vm;
            v += h * acc(vm);
        }
        x
    }

    #[test]
    fn three_d_throw_matches_a_tiny_step_reference() {
        let g = DVec3::new(0.0, 0.0, -9.81);
        let cfg = DragConfig {
            magnus: true,
            ..DragConfig::default()
        };
        // A table-tennis ball (2.7 g, r 20 mm) and a tennis ball (57 g, r 33 mm), spinning.
        for (r, m, w) in [
            (0.02, 0.0027, DVec3::new(30.0, -80.0, 20.0)),
            (0.033, 0.057, DVec3::new(0.0, 50.0, 0.0)),
        ] {
            let b = BodyDrag::new(&Shape::Sphere { radius: r }, m, &cfg);
            let v0 = DVec3::new(3.0, 1.5, 6.5);
            let t = 1.5;
            let x_ref = midpoint_reference(&b, v0, w, g, t, 300_000);
            for step in [0.001, 0.002, 0.005, 0.01, 0.02] {
                let (x, _) = fly(&b, DVec3::ZERO, v0, w, g, t, step);
                eprintln!(
                    "  RK4 step {step} s: {:.3e} m from the reference",
                    x.distance(x_ref)
                );
            }
            let (x, _) = fly(&b, DVec3::ZERO, v0, w, g, t, DEFAULT_MAX_STEP);
            let vacuum = v0 * t + 0.5 * g * t * t;
            let err = x.distance(x_ref);
            eprintln!(
                "3-D throw r {r} m, m {m} kg: drag+Magnus moves it {:.3} m; RK4 (default step) vs midpoint (5 us): {err:.3e} m",
                x.distance(vacuum)
            );
            assert!(x.distance(vacuum) > 0.1, "drag too weak to test anything");
            assert!(err < 1e-4, "{err}"); // 0.1 mm
            assert!(err < 1e-7, "{err}"); // what it really achieves
        }
    }

    #[test]
    fn a_drag_track_is_fly_at_its_end_and_close_to_it_between() {
        let g = DVec3::new(0.0, 0.0, -9.81);
        let b = BodyDrag::new(
            &Shape::Sphere { radius: 0.033 },
            0.057,
            &DragConfig::default(),
        );
        let (x0, v0) = (DVec3::new(0.1, -1.0, 0.5), DVec3::new(1.0, 2.0, 7.0));
        let mut track = DragTrack::default();
        track.reset(&b, x0, v0, DVec3::ZERO, g, 1.2, DEFAULT_MAX_STEP);
        let bits =
            |(x, v): (DVec3, DVec3)| [x.to_array(), v.to_array()].map(|a| a.map(f64::to_bits));
        let end = fly(&b, x0, v0, DVec3::ZERO, g, 1.2, DEFAULT_MAX_STEP);
        assert_eq!(bits(track.state(1.2)), bits(end));
        let mut worst: f64 = 0.0;
        for k in 0..=37 {
            let t = 1.3 * k as f64 / 37.0; // past the grid too
            let (x, _) = track.state(t);
            let (y, _) = fly(&b, x0, v0, DVec3::ZERO, g, t, 1e-4);
            worst = worst.max(x.distance(y));
        }
        assert!(worst < 1e-7, "{worst}");
        // The bound holds over the flight (the drag at the launch speed is the largest).
        let k = b.k();
        assert!(track.accel_bound() >= k * v0.length_squared());
        assert!(track.accel_bound() < 2.0 * k * v0.length_squared());
    }

    #[test]
    fn no_air_is_the_vacuum_parabola() {
        let cfg = DragConfig {
            rho: 0.0,
            ..DragConfig::default()
        };
        let b = BodyDrag::new(&Shape::Sphere { radius: 0.1 }, 1.0, &cfg);
        let g = DVec3::new(0.0, 0.0, -9.81);
        let v0 = DVec3::new(1.0, 2.0, 7.0);
        let (x, v) = fly(&b, DVec3::ONE, v0, DVec3::ZERO, g, 1.2, DEFAULT_MAX_STEP);
        assert!(x.distance(DVec3::ONE + v0 * 1.2 + 0.5 * g * 1.44) < 1e-12);
        assert!(v.distance(v0 + g * 1.2) < 1e-12);
    }

    #[test]
    fn reference_areas_are_a_quarter_of_the_surface() {
        let s = Shape::Sphere { radius: 0.5 };
        assert!((reference_area(&s) - std::f64::consts::PI * 0.25).abs() < 1e-15);
        let b = Shape::Cuboid {
            half_extents: DVec3::new(0.05, 0.025, 0.0125),
        };
        let (x, y, z) = (0.1, 0.05, 0.025);
        assert!((reference_area(&b) - 2.0 * (x * y + y * z + z * x) / 4.0).abs() < 1e-15);
        // A box as a mesh: its hull is itself.
        let h = DVec3::new(0.05, 0.025, 0.0125);
        let mut v = Vec::new();
        for i in 0..8 {
            v.push(DVec3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { -h.y } else { h.y },
                if i & 4 == 0 { -h.z } else { h.z },
            ));
        }
        let mesh = crate::geometry::shape::TriMesh::new(v, Vec::new());
        let a = reference_area(&Shape::Mesh(std::sync::Arc::new(mesh)));
        // parry's hull is in f32: relative precision ~1e-7.
        assert!((a / reference_area(&b) - 1.0).abs() < 1e-6, "{a}");
    }

    #[test]
    fn bad_config_is_refused() {
        let ok = DragConfig::default();
        assert!(ok.validate().is_ok());
        let e = DragConfig { rho: -1.0, ..ok }.validate().unwrap_err();
        assert_eq!(e, DragError::Density(-1.0));
        assert!(e.to_string().contains("air density"));
        let e = ok.with_cd(-0.5).validate().unwrap_err();
        assert!(matches!(e, DragError::Coefficient { value, .. } if value == -0.5));
        let e = DragConfig {
            cd_box: f64::NAN,
            ..ok
        }
        .validate()
        .unwrap_err();
        assert!(matches!(e, DragError::Coefficient { shape: "boxes", .. }));
        assert!(DragConfig {
            max_step: 0.0,
            ..ok
        }
        .validate()
        .is_err());
    }
}
