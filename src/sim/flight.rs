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
/// [`FreeFlight::max_angular_speed`], shrunk so that a whole number of steps spans
/// `[0, t_max]`. RK4's global orientation error scales with `rk4_max_angle^4`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightConfig {
    /// Longest step in seconds (default 0.01 s, only binding for slow spins).
    pub rk4_max_step: f64,
    /// Largest rotation per step in radians (default 0.02 rad: for a tumbling brick at
    /// ~20 rad/s, measured orientation error 7e-7 rad and relative energy drift 1.1e-9
    /// after 2 s; both scale as the fourth power of this value, the cost inversely; see
    /// `docs/flight.md` for the table).
    pub rk4_max_angle: f64,
}

impl Default for FlightConfig {
    fn default() -> Self {
        Self {
            rk4_max_step: 0.01,
            rk4_max_angle: 0.02,
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
        }
    }
}

/// Time derivative of the principal-to-world quaternion: `q' = q (0, w_p) / 2` with the
/// principal-frame angular velocity `w_p = I^-1 (q^* L q)`. Both products are polynomial
/// in `q`, so the field is smooth off the unit sphere and RK4 keeps its fourth order even
/// though the stage values are not normalised.
#[inline(always)]
fn quat_rate(q: DQuat, l_world: DVec3, half_inv_inertia: DVec3) -> DQuat {
    // Written out in scalars: the RK4 stages form one long dependency chain, and this
    // form has a shorter critical path than composing glam's generic products.
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    let (lx, ly, lz) = (l_world.x, l_world.y, l_world.z);
    // v = q^* L q = (w^2 - b^2) L + 2 (b . L) b - 2 w (b x L), with b = (x, y, z).
    let s = w * w - (x * x + y * y + z * z);
    let d = 2.0 * (x * lx + y * ly + z * lz);
    let w2 = 2.0 * w;
    let vx = s * lx + d * x - w2 * (y * lz - z * ly);
    let vy = s * ly + d * y - w2 * (z * lx - x * lz);
    let vz = s * lz + d * z - w2 * (x * ly - y * lx);
    // Half the principal angular velocity, then q (0, w_p / 2).
    let (ax, ay, az) = (
        vx * half_inv_inertia.x,
        vy * half_inv_inertia.y,
        vz * half_inv_inertia.z,
    );
    DQuat::from_xyzw(
        w * ax + y * az - z * ay,
        w * ay + z * ax - x * az,
        w * az + x * ay - y * ax,
        -(x * ax + y * ay + z * az),
    )
}

/// Pulls a nearly unit quaternion back to unit length with one Newton step for
/// `1 / sqrt(|q|^2)`: RK4 changes the norm by far less than 1e-9 per step, so the
/// residual (~ the square of that) is below rounding, and the step avoids the square
/// root and division that would lengthen the serial chain of the integration.
#[inline(always)]
fn renormalize(q: DQuat) -> DQuat {
    q * (1.5 - 0.5 * q.length_squared())
}

/// One classical RK4 step of length `h` for [`quat_rate`] (result not normalised).
#[inline(always)]
fn rk4_step(q: DQuat, h: f64, l_world: DVec3, half_inv_inertia: DVec3) -> DQuat {
    let k1 = quat_rate(q, l_world, half_inv_inertia);
    let k2 = quat_rate(q + k1 * (0.5 * h), l_world, half_inv_inertia);
    let k3 = quat_rate(q + k2 * (0.5 * h), l_world, half_inv_inertia);
    let k4 = quat_rate(q + k3 * h, l_world, half_inv_inertia);
    q + (k1 + (k2 + k3) * 2.0 + k4) * (h / 6.0)
}

impl FreeFlight {
    /// Prepares the flight of a body with mass properties `mp` launched at `t = 0`.
    ///
    /// `origin`, `orientation`: pose of the body frame at launch (world); `v`: centre-of-
    /// mass velocity (m/s, world); `w`: angular velocity (rad/s, world); `g`: gravity
    /// (m/s^2). `t_max` is the latest time that will be queried: the asymmetric case
    /// integrates up to it now, so that every later query is O(1). Queries outside
    /// `[0, t_max]` stay correct but integrate from the nearest end of the grid at query
    /// time (cost proportional to the distance). Allocates only if the grid needs more
    /// states than any earlier reset.
    ///
    /// Panics if a principal moment is not positive and finite.
    #[allow(clippy::too_many_arguments)]
    pub fn reset(
        &mut self,
        mp: &MassProperties,
        origin: DVec3,
        orientation: DQuat,
        v: DVec3,
        w: DVec3,
        g: DVec3,
        t_max: f64,
        cfg: &FlightConfig,
    ) {
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

        let [i0, i1, i2] = inertia.to_array();
        let tol = EQUAL_MOMENT_RTOL * inertia.max_element();
        // The closed forms keep |w| constant, so |w0| itself bounds it; the margin
        // covers rounding in the queries.
        let closed_form_bound = w.length() * (1.0 + 1e-12);
        if inertia.max_element() - inertia.min_element() <= tol {
            self.kind = RotationKind::Isotropic;
            self.precession = w;
            self.w_max = closed_form_bound;
            return;
        }
        let symmetric_axis = if (i0 - i1).abs() <= tol {
            Some(2)
        } else if (i1 - i2).abs() <= tol {
            Some(0)
        } else if (i2 - i0).abs() <= tol {
            Some(1)
        } else {
            None
        };
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
        let n = if t_max > 0.0 && t_max.is_finite() {
            (t_max / h_target).ceil().max(1.0) as usize
        } else {
            0
        };
        self.h = if n > 0 { t_max / n as f64 } else { h_target };
        self.inv_h = 1.0 / self.h;
        self.states.reserve(n + 1);
        let mut q = qp0;
        self.states.push(q);
        for _ in 0..n {
            q = renormalize(rk4_step(q, self.h, l_world, self.half_inv_inertia));
            self.states.push(q);
        }
    }

    /// Centre of mass at time `t` (world): `x0 + v t + g t^2 / 2`.
    #[inline]
    pub fn com(&self, t: f64) -> DVec3 {
        self.com0 + self.v0 * t + self.g * (0.5 * t * t)
    }

    /// Centre-of-mass velocity at time `t` (world).
    #[inline]
    pub fn com_velocity(&self, t: f64) -> DVec3 {
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

    /// Body origin at time `t` (world): `com(t) - R(t) local_com`.
    #[inline]
    pub fn origin(&self, t: f64) -> DVec3 {
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
            return rk4_step(self.states[k], tau, self.l_world, self.half_inv_inertia);
        }
        // Outside the grid: march from the nearer end with full steps, then one partial
        // step. A NaN t falls through to a NaN quaternion without looping.
        let (mut q, mut remaining, h) = if t > 0.0 {
            (self.states[n], t - n as f64 * self.h, self.h)
        } else {
            (self.states[0], t, -self.h)
        };
        while remaining.abs() > self.h {
            q = renormalize(rk4_step(q, h, self.l_world, self.half_inv_inertia));
            remaining -= h;
        }
        rk4_step(q, remaining, self.l_world, self.half_inv_inertia)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shape::tests::*;
    use crate::geometry::shape::Shape;
    use glam::DMat3;
    use std::sync::Arc;

    // ---------------------------------------------------------------- flight

    /// Independent reference: Euler's equations for the principal-frame angular velocity
    /// together with the body quaternion, by classical RK4 with a fixed small step.
    fn reference_rotation(
        mp: &MassProperties,
        q0: DQuat,
        w0: DVec3,
        t: f64,
        steps: usize,
    ) -> DQuat {
        let inertia = mp.principal_inertia.to_array();
        let p = mp.principal_frame;
        let wp0 = (q0 * p).conjugate() * w0;
        // State: [w1, w2, w3, qx, qy, qz, qw], q = body -> world.
        let f = |s: &[f64; 7]| -> [f64; 7] {
            let [i1, i2, i3] = inertia;
            let (w1, w2, w3) = (s[0], s[1], s[2]);
            let dw = [
                (i2 - i3) * w2 * w3 / i1,
                (i3 - i1) * w3 * w1 / i2,
                (i1 - i2) * w1 * w2 / i3,
            ];
            // Body-frame angular velocity; q' = q (0, w_body) / 2.
            let wb = p * DVec3::new(w1, w2, w3);
            let q = DQuat::from_xyzw(s[3], s[4], s[5], s[6]);
            let dq = q * DQuat::from_xyzw(wb.x, wb.y, wb.z, 0.0) * 0.5;
            [dw[0], dw[1], dw[2], dq.x, dq.y, dq.z, dq.w]
        };
        let mut s = [wp0.x, wp0.y, wp0.z, q0.x, q0.y, q0.z, q0.w];
        let h = t / steps as f64;
        let add = |a: &[f64; 7], b: &[f64; 7], c: f64| -> [f64; 7] {
            std::array::from_fn(|i| a[i] + c * b[i])
        };
        for _ in 0..steps {
            let k1 = f(&s);
            let k2 = f(&add(&s, &k1, h / 2.0));
            let k3 = f(&add(&s, &k2, h / 2.0));
            let k4 = f(&add(&s, &k3, h));
            s = std::array::from_fn(|i| {
                s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
        DQuat::from_xyzw(s[3], s[4], s[5], s[6]).normalize()
    }

    fn world_inertia(mp: &MassProperties, r: DQuat) -> DMat3 {
        let m = DMat3::from_quat(r);
        m * mp.inertia_tensor() * m.transpose()
    }

    /// Checks that L = I(t) w(t) stays the launch value and returns the largest relative
    /// deviations of L and of the kinetic energy 1/2 w . L over `times`.
    fn conservation(f: &FreeFlight, mp: &MassProperties, times: &[f64]) -> (f64, f64) {
        let l0 = f.angular_momentum();
        let e0 = 0.5 * f.angular_velocity(0.0).dot(l0);
        let (mut dl, mut de) = (0.0f64, 0.0f64);
        for &t in times {
            let r = f.orientation(t);
            let w = f.angular_velocity(t);
            let l = world_inertia(mp, r) * w;
            dl = dl.max((l - l0).length() / l0.length());
            de = de.max(rel(0.5 * w.dot(l), e0));
        }
        (dl, de)
    }

    fn brick() -> MassProperties {
        Shape::Cuboid {
            half_extents: DVec3::new(0.05, 0.025, 0.0125),
        }
        .mass_properties(600.0)
    }

    fn grid(t_end: f64, n: usize) -> Vec<f64> {
        // Irregular sample times so that queries fall between grid points.
        (0..=n)
            .map(|i| t_end * (i as f64 / n as f64).powf(1.1))
            .collect()
    }

    #[test]
    fn isotropic_body_spins_about_fixed_axis() {
        let mp = Shape::Sphere { radius: 0.02 }.mass_properties(1000.0);
        let q0 = DQuat::from_axis_angle(DVec3::Y, 0.3);
        let w = DVec3::new(1.0, -4.0, 9.0);
        let mut f = FreeFlight::default();
        f.reset(
            &mp,
            DVec3::ONE,
            q0,
            DVec3::X,
            w,
            DVec3::NEG_Z * 9.81,
            1.5,
            &FlightConfig::default(),
        );
        assert_eq!(f.rotation_kind(), RotationKind::Isotropic);
        let r = f.orientation(1.5);
        let want = reference_rotation(&mp, q0, w, 1.5, 20_000);
        assert!(angle_between(r, want) < 1e-10);
        assert!(angle_between(r, DQuat::from_scaled_axis(w * 1.5) * q0) < 1e-14);
        assert!((f.max_angular_speed() - w.length()).abs() < 1e-10);
    }

    #[test]
    fn torque_free_symmetric_top_matches_closed_form_precession() {
        // A symmetric top (I1 = I2 != I3) whose principal frame is rotated against the body
        // frame, launched in a tilted pose: the closed form must agree with an
        // independent fine RK4 of Euler's equations to 1e-9 rad after 1.5 s.
        for (i_perp, i3) in [(2.0e-5, 0.8e-5), (1.0e-5, 1.7e-5)] {
            let mp = MassProperties {
                mass: 0.03,
                local_com: DVec3::new(0.0, 0.0, 0.01),
                principal_inertia: DVec3::new(i_perp, i_perp, i3),
                principal_frame: DQuat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 0.2),
            };
            let q0 = DQuat::from_axis_angle(DVec3::new(0.3, 1.0, -0.2).normalize(), 1.2);
            let w = DVec3::new(6.0, -14.0, 9.0);
            let mut f = FreeFlight::default();
            f.reset(
                &mp,
                DVec3::ZERO,
                q0,
                DVec3::ZERO,
                w,
                DVec3::ZERO,
                1.5,
                &FlightConfig::default(),
            );
            assert_eq!(f.rotation_kind(), RotationKind::Axisymmetric);
            let reference = reference_rotation(&mp, q0, w, 1.5, 150_000);
            let err = angle_between(f.orientation(1.5), reference);
            assert!(err < 1e-9, "closed form vs reference: {err}");
            // The naive constant-w rotation is far off, so the comparison has teeth.
            assert!(angle_between(DQuat::from_scaled_axis(w * 1.5) * q0, reference) > 0.1);
            let (dl, de) = conservation(&f, &mp, &grid(1.5, 37));
            assert!(dl < 1e-13 && de < 1e-13, "{dl} {de}");
            let max_w = (0..=30)
                .map(|i| f.angular_velocity(i as f64 * 0.05).length())
                .fold(0.0, f64::max);
            assert!(max_w <= f.max_angular_speed());
        }
    }

    #[test]
    fn asymmetric_brick_conserves_l_and_energy_and_converges() {
        let mp = brick();
        let q0 = DQuat::from_axis_angle(DVec3::new(1.0, -0.5, 0.3).normalize(), 0.8);
        let w = DVec3::new(11.0, -13.0, 9.0); // |w| ~ 19.3 rad/s
        let cfg = FlightConfig::default();
        let mut f = FreeFlight::default();
        f.reset(&mp, DVec3::ZERO, q0, DVec3::ZERO, w, DVec3::ZERO, 2.0, &cfg);
        assert_eq!(f.rotation_kind(), RotationKind::Asymmetric);
        let times = grid(2.0, 101);
        let (dl, de) = conservation(&f, &mp, &times);
        assert!(dl < 1e-12, "L drift {dl}");
        // Measured 1.1e-9 with the default 0.02 rad per step (error ~ angle^4).
        assert!(de < 2e-9, "energy drift {de}");
        // 10x finer steps: measured difference 7.1e-7 rad after 2 s; require 2e-6.
        let fine_cfg = FlightConfig {
            rk4_max_step: cfg.rk4_max_step / 10.0,
            rk4_max_angle: cfg.rk4_max_angle / 10.0,
        };
        let mut fine = FreeFlight::default();
        fine.reset(
            &mp,
            DVec3::ZERO,
            q0,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            2.0,
            &fine_cfg,
        );
        let ratio = fine.rk4_steps() as f64 / f.rk4_steps() as f64;
        assert!((ratio - 10.0).abs() < 0.01, "{ratio}");
        let err = times
            .iter()
            .map(|&t| angle_between(f.orientation(t), fine.orientation(t)))
            .fold(0.0, f64::max);
        assert!(err < 2e-6, "vs 10x finer: {err}");
        // Independent Euler-equation reference.
        let reference = reference_rotation(&mp, q0, w, 2.0, 200_000);
        let err = angle_between(f.orientation(2.0), reference);
        assert!(err < 2e-6, "vs Euler reference: {err}");
        // The gyroscopic motion matters: constant-w rotation is far off.
        assert!(angle_between(DQuat::from_scaled_axis(w * 2.0) * q0, reference) > 0.1);
        // The speed bound holds and is tight (the exact polhode maximum): 2 s covers
        // more than one polhode period here.
        let max_w = times
            .iter()
            .map(|&t| f.angular_velocity(t).length())
            .fold(0.0, f64::max);
        assert!(max_w <= f.max_angular_speed());
        assert!(
            f.max_angular_speed() < 1.001 * max_w,
            "{} {max_w}",
            f.max_angular_speed()
        );
    }

    #[test]
    fn intermediate_axis_flips_and_still_conserves() {
        // Tennis-racket theorem: spin about the middle axis (y for this brick) with a tiny
        // perturbation flips over repeatedly.
        let mp = brick();
        let w = DVec3::new(0.05, 20.0, 0.0);
        let mut f = FreeFlight::default();
        f.reset(
            &mp,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            2.0,
            &FlightConfig::default(),
        );
        let times = grid(2.0, 400);
        let body_wy: Vec<f64> = times
            .iter()
            .map(|&t| (f.orientation(t).conjugate() * f.angular_velocity(t)).y)
            .collect();
        assert!(body_wy.iter().any(|&y| y < -19.0), "the body never flipped");
        let (dl, de) = conservation(&f, &mp, &times);
        assert!(dl < 1e-12 && de < 2e-9, "{dl} {de}");
    }

    #[test]
    fn angular_velocity_is_the_derivative_of_orientation() {
        // Central differences inside one grid step, so the partial-step interpolant and
        // the angular velocity must agree.
        let mp = brick();
        let mut f = FreeFlight::default();
        let w = DVec3::new(-7.0, 15.0, 10.0);
        f.reset(
            &mp,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            1.0,
            &FlightConfig::default(),
        );
        let h = 1.0 / f.rk4_steps() as f64;
        for k in [3usize, 100, 700] {
            let t = (k as f64 + 0.5) * h;
            let d = 1e-3 * h;
            let dq = f.orientation(t + d) * f.orientation(t - d).conjugate();
            let w_fd = dq.to_scaled_axis() / (2.0 * d);
            let w_an = f.angular_velocity(t);
            assert!(
                (w_fd - w_an).length() < 1e-6 * w_an.length(),
                "{w_fd} {w_an}"
            );
        }
    }

    #[test]
    fn queries_beyond_t_max_extend_the_integration() {
        let mp = brick();
        let w = DVec3::new(5.0, 8.0, -12.0);
        let cfg = FlightConfig::default();
        let (mut short, mut long) = (FreeFlight::default(), FreeFlight::default());
        short.reset(
            &mp,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            0.5,
            &cfg,
        );
        long.reset(
            &mp,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            1.5,
            &cfg,
        );
        for t in [0.7, 1.3] {
            let err = angle_between(short.orientation(t), long.orientation(t));
            assert!(err < 1e-8, "t = {t}: {err}");
        }
        // Negative times integrate backwards: relaunching from the pose and angular
        // velocity at -0.4 s must come back to the launch pose 0.4 s later.
        let (q, wq) = (short.orientation(-0.4), short.angular_velocity(-0.4));
        let mut back = FreeFlight::default();
        back.reset(&mp, DVec3::ZERO, q, DVec3::ZERO, wq, DVec3::ZERO, 0.5, &cfg);
        let err = angle_between(back.orientation(0.4), DQuat::IDENTITY);
        assert!(err < 1e-8, "{err}");
        assert!(angle_between(q, DQuat::IDENTITY) > 0.5);
    }

    #[test]
    fn origin_and_com_stay_consistent_for_off_centre_mesh() {
        let mesh = box_mesh(DVec3::new(0.01, -0.02, 0.0), DVec3::new(0.05, 0.0, 0.01));
        let mp = Shape::Mesh(Arc::new(mesh)).mass_properties(700.0);
        assert!(mp.local_com.length() > 0.01);
        let origin = DVec3::new(0.1, 0.2, 0.8);
        let q0 = DQuat::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), 0.6);
        let (v, w, g) = (
            DVec3::new(1.0, 0.5, 4.0),
            DVec3::new(9.0, -5.0, 14.0),
            DVec3::new(0.0, 0.0, -9.81),
        );
        let mut f = FreeFlight::default();
        f.reset(&mp, origin, q0, v, w, g, 1.5, &FlightConfig::default());
        assert_eq!(f.rotation_kind(), RotationKind::Asymmetric);
        assert!((f.origin(0.0) - origin).length() < 1e-15);
        assert!(angle_between(f.orientation(0.0), q0) < 1e-15);
        let com0 = origin + q0 * mp.local_com;
        for t in [0.0, 0.31, 0.9, 1.5] {
            let (o, r) = f.pose(t);
            assert!((o + r * mp.local_com - f.com(t)).length() < 1e-14);
            assert!((o - f.origin(t)).length() < 1e-15);
            let want = com0 + v * t + 0.5 * g * t * t;
            assert!((f.com(t) - want).length() < 1e-14);
            assert!((f.com_velocity(t) - (v + g * t)).length() < 1e-14);
        }
        // t = 1.5 s under gravity: the COM is 11.04 m below the no-gravity line.
        assert!((f.com(1.5).z - (com0.z + 6.0 - 11.03625)).abs() < 1e-12);
    }

    #[test]
    fn reset_reuses_its_buffer() {
        let mp = brick();
        let cfg = FlightConfig::default();
        let mut f = FreeFlight::default();
        let w = DVec3::new(3.0, 20.0, 1.0);
        f.reset(
            &mp,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            1.5,
            &cfg,
        );
        let (ptr, cap) = (f.states.as_ptr(), f.states.capacity());
        f.reset(
            &mp,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w * 0.9,
            DVec3::ZERO,
            1.5,
            &cfg,
        );
        assert_eq!((ptr, cap), (f.states.as_ptr(), f.states.capacity()));
        // A closed-form reset leaves the buffer alone as well.
        let ball = Shape::Sphere { radius: 0.01 }.mass_properties(1.0);
        f.reset(
            &ball,
            DVec3::ZERO,
            DQuat::IDENTITY,
            DVec3::ZERO,
            w,
            DVec3::ZERO,
            1.5,
            &cfg,
        );
        assert_eq!(f.rk4_steps(), 0);
        assert_eq!(cap, f.states.capacity());
    }

    // ---------------------------------------------------------------- shapes
}
