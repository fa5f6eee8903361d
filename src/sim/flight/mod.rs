//! Exact torque-free free flight of one rigid body.
//!
//! [`FreeFlight::reset`] takes the mass properties of [`crate::geometry::shape`] and a launch state
//! (pose, linear and angular velocity, gravity) and prepares an exact torque-free flight;
//! the pose at any time is then a cheap query ([`FreeFlight::pose`],
//! [`FreeFlight::orientation`], [`FreeFlight::com`], ...).
//!
//!
//! Flight is exact in the following sense. The centre of mass follows the parabola
//! `x0 + v t + g t^2 / 2`. The rotation conserves the world angular momentum `L`:
//!
//! * isotropic inertia (sphere, cube): `R(t) = exp(w t) R0`, exact;
//! * axisymmetric inertia (two equal principal moments `I_perp`, symmetry axis `a` in the
//!   body frame, moment `I_a` about it): `R(t) = exp(t L / I_perp) R0 exp(t beta a)` with
//!   `beta = (a . w_body(0)) (1 - I_a / I_perp)`, exact (the derivation is in `docs/flight.md`);
//! * asymmetric inertia: `q' = q (0, w_p) / 2` with `w_p = I^-1 q^* L q` for the
//!   principal-frame quaternion `q`, integrated by RK4 on a uniform grid over
//!   `[0, t_max]` at reset; a query is one partial RK4 step from the grid state just
//!   before `t`, so it costs the same at any time.

use glam::{DQuat, DVec3};

use crate::geometry::shape::MassProperties;
use crate::scene::{Launch, Occluder};
use crate::sim::drag::{BodyDrag, DragTrack};

mod rk4;
use rk4::{renormalize, renormalize_one, rk4_step, rk4_step_one, vec3, Quat, Wide, LANES};

/// Relative tolerance under which two principal moments count as equal, so that the
/// closed-form isotropic or axisymmetric rotation is used. At 1e-9 the closed form's
/// error from treating them as equal is about 1e-9 of the rotation angle, far below the
/// RK4 error it replaces, and meshes with a discrete rotational symmetry of order three
/// or more (a lathed pawn) come out equal to rounding (~1e-15).
pub const EQUAL_MOMENT_RTOL: f64 = 1e-9;

/// Exact maximum of `|w(t)|` over a torque-free motion with three distinct moments,
/// with a small rounding margin.
///
/// The body-frame momentum `L_b` keeps `sum x_i = |L|^2` and `sum x_i / I_i = 2E` with
/// `x_i = L_i^2 >= 0`, while `|w|^2 = sum x_i / I_i^2` is linear in `x`. The two
/// constraints cut a segment out of the octant, the polhode sweeps all of it (each
/// `L_i` that changes sign passes through zero), so the maximum is at an end of the
/// segment, where one `x_k` is zero. This is tighter than `|L| / I_min` by up to the
/// ratio of the moments and lets the RK4 step be as long as the motion allows.
fn asymmetric_max_speed(inertia: DVec3, l_principal: DVec3) -> f64 {
    let x = l_principal * l_principal;
    let inv = inertia.recip();
    let (l2, two_e) = (x.element_sum(), x.dot(inv));
    let mut best = x.dot(inv * inv);
    for k in 0..3 {
        // Solve x_i + x_j = l2, x_i / I_i + x_j / I_j = 2E with x_k = 0.
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let det = inv[j] - inv[i];
        if det == 0.0 {
            continue;
        }
        let xj = (two_e - l2 * inv[i]) / det;
        let xi = l2 - xj;
        if xi >= 0.0 && xj >= 0.0 {
            best = best.max(xi * inv[i] * inv[i] + xj * inv[j] * inv[j]);
        }
    }
    // Cancellation in the 2 x 2 solve can lose a few digits when two moments are close;
    // 1e-9 covers it while keeping the bound tight.
    best.sqrt() * (1.0 + 1e-9)
}

/// Step-size control for the RK4 integration of asymmetric bodies.
///
/// The step is `min(rk4_max_step, rk4_max_angle / w_max)` with `w_max` the bound of
/// [`FreeFlight::max_angular_speed`], and the grid runs to `t_max` or one step past
/// it. RK4's global orientation error scales with `rk4_max_angle^4`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightConfig {
    /// Longest step in seconds (default 0.05 s: the angle sets the step of every spin
    /// above 1 rad/s; at 0.01 s this limit set the step of every block the examples
    /// launch, at 1 to 2 rad/s, and cost fly a fifth of its time for no change of its
    /// picture).
    pub rk4_max_step: f64,
    /// Largest rotation per step in radians (default 0.05 rad: for a tumbling brick at
    /// ~20 rad/s, measured orientation error 2.9e-5 rad and relative energy drift 4.6e-8
    /// after 2 s; both scale as the fourth power of this value, the cost inversely; see
    /// `docs/flight.md` for the table). At 2.9e-5 rad a corner 0.15 m from the centre
    /// moves 4 um, a few hundredths of the examples' smallest pixel (1.5 mm) and 300
    /// times less than a launcher's orientation error (0.5 deg); 0.02 rad made the error
    /// 40 times smaller still for 2.5 times the steps, a fifth of fly's solve.
    pub rk4_max_angle: f64,
}

impl Default for FlightConfig {
    fn default() -> Self {
        Self {
            rk4_max_step: 0.05,
            rk4_max_angle: 0.05,
        }
    }
}

/// The state of a body at launch (`t = 0`), as [`FreeFlight::reset`] takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaunchState {
    /// Body-frame origin (m, world).
    pub origin: DVec3,
    /// Body frame -> world.
    pub orientation: DQuat,
    /// Centre-of-mass velocity (m/s, world).
    pub velocity: DVec3,
    /// Angular velocity (rad/s, world).
    pub angular_velocity: DVec3,
}

impl LaunchState {
    /// Occluder `o` launched from its scene pose with the velocities `launch`.
    pub fn of(o: &Occluder, launch: Launch) -> LaunchState {
        LaunchState {
            origin: o.position,
            orientation: o.orientation,
            velocity: launch.velocity,
            angular_velocity: launch.angular_velocity,
        }
    }
}

/// Which rotation law [`FreeFlight`] uses, chosen from the principal moments at reset
/// with the relative tolerance [`EQUAL_MOMENT_RTOL`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RotationKind {
    /// All three moments equal: constant angular velocity (closed form).
    Isotropic,
    /// Two moments equal: regular precession (closed form).
    Axisymmetric,
    /// Three distinct moments: RK4 on a precomputed grid.
    Asymmetric,
}

impl RotationKind {
    /// The law of a body with principal moments `inertia` (positive), and the principal
    /// axis of an axisymmetric body's distinct moment.
    fn of_moments(inertia: DVec3) -> (RotationKind, Option<usize>) {
        let [i0, i1, i2] = inertia.to_array();
        let tol = EQUAL_MOMENT_RTOL * inertia.max_element();
        if inertia.max_element() - inertia.min_element() <= tol {
            return (RotationKind::Isotropic, None);
        }
        let axis = if (i0 - i1).abs() <= tol {
            2
        } else if (i1 - i2).abs() <= tol {
            0
        } else if (i2 - i0).abs() <= tol {
            1
        } else {
            return (RotationKind::Asymmetric, None);
        };
        (RotationKind::Axisymmetric, Some(axis))
    }

    /// The law [`FreeFlight::reset`] takes for a body of mass properties `mp`.
    pub fn of(mp: &MassProperties) -> RotationKind {
        RotationKind::of_moments(mp.principal_inertia).0
    }
}

/// Exact torque-free flight of one rigid body launched at `t = 0` (see the module docs).
///
/// Create once with [`Default`] and [`reset`](FreeFlight::reset) for every launch: the
/// RK4 grid buffer is reused, so resets allocate only when `t_max` grows past what an
/// earlier reset needed.
#[derive(Clone, Debug)]
pub struct FreeFlight {
    /// Centre of mass at launch (world).
    com0: DVec3,
    v0: DVec3,
    g: DVec3,
    local_com: DVec3,
    /// Body-to-world rotation at launch.
    q0: DQuat,
    /// Principal-to-body rotation.
    principal_frame: DQuat,
    inv_inertia: DVec3,
    /// Half of `inv_inertia`, as the quaternion rate uses it.
    half_inv_inertia: DVec3,
    /// World angular momentum, constant during flight.
    l_world: DVec3,
    kind: RotationKind,
    /// World angular velocity of the closed forms' left factor: `w0` (isotropic) or
    /// `L / I_perp` (axisymmetric).
    precession: DVec3,
    /// Body-frame angular velocity of the right factor, `beta a` (axisymmetric only).
    spin_body: DVec3,
    w_max: f64,
    t_max: f64,
    /// Grid step and its inverse (asymmetric only).
    h: f64,
    inv_h: f64,
    /// Principal-to-world quaternions at `k h`, `k = 0..=n` (asymmetric only).
    states: Vec<DQuat>,
    /// Steps the grid takes to reach `t_max` (asymmetric only).
    grid_steps: usize,
    /// The centre of mass flown with drag, when `drag_on` (see [`FreeFlight::set_drag`]).
    drag: DragTrack,
    drag_on: bool,
}

impl Default for FreeFlight {
    /// A body at rest at the origin, unit isotropic inertia, no gravity.
    fn default() -> Self {
        Self {
            com0: DVec3::ZERO,
            v0: DVec3::ZERO,
            g: DVec3::ZERO,
            local_com: DVec3::ZERO,
            q0: DQuat::IDENTITY,
            principal_frame: DQuat::IDENTITY,
            inv_inertia: DVec3::ONE,
            half_inv_inertia: DVec3::splat(0.5),
            l_world: DVec3::ZERO,
            kind: RotationKind::Isotropic,
            precession: DVec3::ZERO,
            spin_body: DVec3::ZERO,
            w_max: 0.0,
            t_max: 0.0,
            h: 0.0,
            inv_h: 0.0,
            states: Vec::new(),
            grid_steps: 0,
            drag: DragTrack::default(),
            drag_on: false,
        }
    }
}

impl FreeFlight {
    /// Prepares the flight of a body with mass properties `mp` launched at `t = 0`.
    ///
    /// `launch`: pose and velocities of the body at launch (see [`LaunchState`]); `g`:
    /// gravity (m/s^2). `t_max` is the latest time that will be queried: the asymmetric case
    /// integrates up to it now, so that every later query is O(1). Queries outside
    /// `[0, t_max]` stay correct but integrate from the nearest end of the grid at query
    /// time (cost proportional to the distance). Allocates only if the grid needs more
    /// states than any earlier reset.
    ///
    /// Panics if a principal moment is not positive and finite.
    pub fn reset(
        &mut self,
        mp: &MassProperties,
        launch: LaunchState,
        g: DVec3,
        t_max: f64,
        cfg: &FlightConfig,
    ) {
        self.reset_without_grid(mp, launch, g, t_max, cfg);
        integrate_grids([self]);
    }

    /// [`FreeFlight::reset`] except the asymmetric case's grid, which
    /// [`integrate_grids`] then integrates beside other flights' grids. Until it has,
    /// a query is still exact but marches from the launch state (the same steps, so the
    /// same bits, at the cost of the steps up to its time).
    pub fn reset_without_grid(
        &mut self,
        mp: &MassProperties,
        launch: LaunchState,
        g: DVec3,
        t_max: f64,
        cfg: &FlightConfig,
    ) {
        let LaunchState {
            origin,
            orientation,
            velocity: v,
            angular_velocity: w,
        } = launch;
        let inertia = mp.principal_inertia;
        assert!(
            inertia.is_finite() && inertia.min_element() > 0.0,
            "principal moments must be positive and finite: {inertia}"
        );
        let q0 = orientation.normalize();
        let p = mp.principal_frame.normalize();
        let qp0 = q0 * p;
        let w_principal = qp0.conjugate() * w;
        let l_principal = inertia * w_principal;
        let l_world = qp0 * l_principal;

        self.com0 = origin + q0 * mp.local_com;
        self.v0 = v;
        self.g = g;
        self.local_com = mp.local_com;
        self.q0 = q0;
        self.principal_frame = p;
        self.inv_inertia = inertia.recip();
        self.half_inv_inertia = 0.5 * self.inv_inertia;
        self.l_world = l_world;
        self.t_max = t_max;
        self.precession = DVec3::ZERO;
        self.spin_body = DVec3::ZERO;
        self.states.clear();
        self.grid_steps = 0;
        self.drag_on = false;

        // The closed forms keep |w| constant, so |w0| itself bounds it; the margin
        // covers rounding in the queries.
        let closed_form_bound = w.length() * (1.0 + 1e-12);
        let (kind, symmetric_axis) = RotationKind::of_moments(inertia);
        if kind == RotationKind::Isotropic {
            self.kind = RotationKind::Isotropic;
            self.precession = w;
            self.w_max = closed_form_bound;
            return;
        }
        if let Some(k) = symmetric_axis {
            // Regular precession. With n(t) the world symmetry axis, w = L / I_perp +
            // beta n solves Euler's equations: it makes I(t) w = L, and n rotates about L
            // so that n . L = I_a w_a stays constant. See docs/flight.md for the derivation.
            let i_perp = 0.5 * (inertia.element_sum() - inertia[k]);
            let beta = w_principal[k] * (1.0 - inertia[k] / i_perp);
            let mut e = DVec3::ZERO;
            e[k] = 1.0;
            self.kind = RotationKind::Axisymmetric;
            self.precession = l_world / i_perp;
            self.spin_body = p * e * beta;
            self.w_max = closed_form_bound;
            return;
        }

        self.kind = RotationKind::Asymmetric;
        self.w_max = asymmetric_max_speed(inertia, l_principal);
        let h_target = if self.w_max > 0.0 {
            cfg.rk4_max_step.min(cfg.rk4_max_angle / self.w_max)
        } else {
            cfg.rk4_max_step
        };
        assert!(
            h_target > 0.0 && h_target.is_finite(),
            "invalid flight config {cfg:?}"
        );
        // The step is `h_target` itself, and the grid reaches `t_max` or just past it:
        // a step shrunk to span `[0, t_max]` exactly would jump whenever the step count
        // does, and so would the pose at `t` (by the integration error), where the step
        // as it stands makes the pose a continuous function of the launch (a whole step
        // from the grid state before equals a partial step of the same length).
        let n = if t_max > 0.0 && t_max.is_finite() {
            (t_max / h_target).ceil().max(1.0) as usize
        } else {
            0
        };
        self.h = h_target;
        self.inv_h = 1.0 / self.h;
        self.grid_steps = n;
        self.states.reserve(n + 1);
        self.states.push(qp0);
    }

    /// The grid's steps left, as one flight.
    fn integrate_alone(&mut self) {
        let mut q = self.states[self.states.len() - 1];
        for _ in 0..self.steps_left() {
            q = renormalize_one(rk4_step_one(q, self.h, self.l_world, self.half_inv_inertia));
            self.states.push(q);
        }
    }

    /// Steps of the asymmetric grid that [`integrate_grids`] has still to take.
    fn steps_left(&self) -> usize {
        match self.kind {
            RotationKind::Asymmetric => self.grid_steps + 1 - self.states.len(),
            _ => 0,
        }
    }

    /// From now on (until the next reset) the centre of mass flies through air: quadratic
    /// drag of `body` (and Magnus lift if its model has it, with the launch spin), RK4
    /// on a grid of at most `max_step` over `[0, t_max]` ([`DragTrack`]). The rotation
    /// stays the torque-free one (the drag model has no torque).
    pub fn set_drag(&mut self, body: &BodyDrag, max_step: f64) {
        let w0 = self.angular_velocity(0.0);
        self.drag
            .reset(body, self.com0, self.v0, w0, self.g, self.t_max, max_step);
        self.drag_on = true;
    }

    /// With drag on ([`FreeFlight::set_drag`]), an upper bound of the magnitude of the
    /// acceleration besides gravity; `None` for the exact parabola.
    pub fn drag_accel_bound(&self) -> Option<f64> {
        self.drag_on.then(|| self.drag.accel_bound())
    }

    /// Centre of mass at time `t` (world): `x0 + v t + g t^2 / 2` (with drag: the drag
    /// flight's).
    #[inline]
    pub fn com(&self, t: f64) -> DVec3 {
        if self.drag_on {
            return self.drag.state(t).0;
        }
        self.com0 + self.v0 * t + self.g * (0.5 * t * t)
    }

    /// Centre-of-mass velocity at time `t` (world).
    #[inline]
    pub fn com_velocity(&self, t: f64) -> DVec3 {
        if self.drag_on {
            return self.drag.state(t).1;
        }
        self.v0 + self.g * t
    }

    /// Rotation from the body frame to the world at time `t`.
    pub fn orientation(&self, t: f64) -> DQuat {
        match self.kind {
            RotationKind::Isotropic => {
                (DQuat::from_scaled_axis(self.precession * t) * self.q0).normalize()
            }
            RotationKind::Axisymmetric => (DQuat::from_scaled_axis(self.precession * t)
                * self.q0
                * DQuat::from_scaled_axis(self.spin_body * t))
            .normalize(),
            RotationKind::Asymmetric => {
                (self.principal_orientation(t) * self.principal_frame.conjugate()).normalize()
            }
        }
    }

    /// Body origin at time `t` (world): `com(t) - R(t) local_com`; the centre of mass
    /// itself, without the orientation, where the two coincide (a ball).
    #[inline]
    pub fn origin(&self, t: f64) -> DVec3 {
        if self.local_com == DVec3::ZERO {
            return self.com(t);
        }
        self.com(t) - self.orientation(t) * self.local_com
    }

    /// Body origin and orientation at time `t`, sharing one orientation evaluation.
    #[inline]
    pub fn pose(&self, t: f64) -> (DVec3, DQuat) {
        let r = self.orientation(t);
        (self.com(t) - r * self.local_com, r)
    }

    /// Angular velocity at time `t` (world), `R I^-1 R^T L`.
    pub fn angular_velocity(&self, t: f64) -> DVec3 {
        match self.kind {
            RotationKind::Isotropic => self.precession,
            RotationKind::Axisymmetric => self.precession + self.orientation(t) * self.spin_body,
            RotationKind::Asymmetric => {
                let q = self.principal_orientation(t).normalize();
                q * (self.inv_inertia * (q.conjugate() * self.l_world))
            }
        }
    }

    /// An upper bound of `|w(t)|` over all `t`, for conservative advancement: `|w0|`
    /// (with a 1e-12 rounding margin) in the closed-form cases, where it is constant, and
    /// the exact maximum over the polhode (with a 1e-9 margin) for asymmetric bodies.
    #[inline]
    pub fn max_angular_speed(&self) -> f64 {
        self.w_max
    }

    /// Gravity (m/s^2).
    #[inline]
    pub fn gravity(&self) -> DVec3 {
        self.g
    }

    /// World angular momentum about the centre of mass (constant).
    #[inline]
    pub fn angular_momentum(&self) -> DVec3 {
        self.l_world
    }

    /// The rotation law chosen at reset.
    #[inline]
    pub fn rotation_kind(&self) -> RotationKind {
        self.kind
    }

    /// Number of RK4 steps taken at reset (0 for the closed forms).
    #[inline]
    pub fn rk4_steps(&self) -> usize {
        self.states.len().saturating_sub(1)
    }

    /// The `t_max` given at reset.
    #[inline]
    pub fn t_max(&self) -> f64 {
        self.t_max
    }

    /// Principal-to-world rotation at time `t` (asymmetric case), not normalised.
    fn principal_orientation(&self, t: f64) -> DQuat {
        let n = self.states.len() - 1;
        let s = t * self.inv_h;
        if (0.0..=n as f64).contains(&s) {
            // Within the grid: one partial step from the state at or just before t.
            let k = (s as usize).min(n);
            let tau = t - k as f64 * self.h;
            return rk4_step_one(self.states[k], tau, self.l_world, self.half_inv_inertia);
        }
        // Outside the grid: march from the nearer end with full steps, then one partial
        // step. A NaN t falls through to a NaN quaternion without looping.
        let (mut q, mut remaining, h) = if t > 0.0 {
            (self.states[n], t - n as f64 * self.h, self.h)
        } else {
            (self.states[0], t, -self.h)
        };
        while remaining.abs() > self.h {
            q = renormalize_one(rk4_step_one(q, h, self.l_world, self.half_inv_inertia));
            remaining -= h;
        }
        rk4_step_one(q, remaining, self.l_world, self.half_inv_inertia)
    }
}

/// Integrates the grids that [`FreeFlight::reset_without_grid`] left to do, [`LANES`]
/// flights at a time in the lanes of one [`Wide`] integration (see [`rk4`]): the same
/// bits as each alone, for a fraction of the time.
pub fn integrate_grids<'a>(flights: impl IntoIterator<Item = &'a mut FreeFlight>) {
    let mut lanes: [Option<&mut FreeFlight>; LANES] = Default::default();
    let mut used = 0;
    for f in flights {
        if f.steps_left() > 0 {
            lanes[used] = Some(f);
            used += 1;
            if used == LANES {
                integrate_lanes(&mut lanes);
                used = 0;
            }
        }
    }
    match &mut lanes[..used] {
        [] => {}
        [Some(f)] => f.integrate_alone(),
        some => integrate_lanes(some),
    }
}

/// The grids of `lanes`, side by side; empties them. A lane left unused steps on an idle
/// state (the identity, no momentum), and one whose grid is done steps on; their results
/// are dropped.
fn integrate_lanes(lanes: &mut [Option<&mut FreeFlight>]) {
    // Lane by lane: the quaternion, the step, the momentum and the half inverse moments.
    let mut q = [[0.0; LANES], [0.0; LANES], [0.0; LANES], [1.0; LANES]];
    let (mut h, mut l, mut half_inv) = ([0.0; LANES], [[0.0; LANES]; 3], [[0.0; LANES]; 3]);
    let mut left = [0; LANES];
    for (j, f) in lanes.iter().enumerate() {
        let f = f.as_deref().expect("a flight in every lane used");
        let last = f.states[f.states.len() - 1].to_array();
        let (lw, hi) = (vec3(f.l_world), vec3(f.half_inv_inertia));
        (0..4).for_each(|c| q[c][j] = last[c]);
        (0..3).for_each(|c| (l[c][j], half_inv[c][j]) = (lw[c], hi[c]));
        (h[j], left[j]) = (f.h, f.steps_left());
    }
    let (h, l, half_inv) = (
        Wide::from_lanes(h),
        l.map(Wide::from_lanes),
        half_inv.map(Wide::from_lanes),
    );
    let mut wide = Quat(q.map(Wide::from_lanes));
    let most = left.iter().copied().max().unwrap_or(0);
    for step in 0..most {
        wide = renormalize(rk4_step(wide, h, l, half_inv));
        let q = wide.0.map(Wide::lanes);
        for (j, f) in lanes.iter_mut().enumerate() {
            if step < left[j] {
                let f = f.as_deref_mut().expect("a flight in every lane used");
                f.states.push(DQuat::from_array(q.map(|c| c[j])));
            }
        }
    }
    lanes.iter_mut().for_each(|f| *f = None);
}

#[cfg(test)]
mod tests;
