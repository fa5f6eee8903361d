//! Aiming: the launch that brings a body to a pose at `t` in free flight, for both the
//! designs of `bsa new` and the solver's moves. [`velocity_reaching`] puts the centre of
//! mass at a point (exact: the parabola); [`Spin::reaching`] finds the launch spin that
//! turns a body to an orientation, by Newton's method on the flight.
//!
//! Adding `angle / t` about an axis to a spin is exact only about a principal axis (a
//! box rolled about its long axis, a body of revolution tipped over); a tumbling block or
//! a knight wobbles off that axis, and needs the solve.

use glam::{DMat3, DQuat, DVec3};

use crate::geometry::shape::MassProperties;
use crate::scene::MAX_TURN;
use crate::sim::flight::{FlightConfig, FreeFlight, LaunchState};

pub use crate::scene::velocity_reaching;

/// Newton iterations of [`Spin::reaching`] on the coarse flight, at most.
pub const NEWTON_STEPS: usize = 12;

/// Iterations of [`Spin::reaching`] on the flight itself, at most, after Newton's method
/// on the coarse one.
pub const CHORD_STEPS: usize = 6;

/// Rotation per RK4 step (rad, at the fastest the body's spin may get) of the coarse
/// flight on which [`Spin::reaching`] runs Newton's method: about 1e-4 of the turn's
/// error at `t`, at half the cost of the flight's own steps of 0.05 rad (a fifth when
/// those were 0.02 rad).
pub const COARSE_ANGLE: f64 = 0.1;

/// A body's turn in free flight: from `from` at launch, over `t` seconds of `flight`.
#[derive(Clone, Copy, Debug)]
pub struct Spin<'a> {
    pub mass: &'a MassProperties,
    /// The orientation at launch (body to world).
    pub from: DQuat,
    /// Seconds of flight to the pose.
    pub t: f64,
    /// The flight the body flies (the solver's [`FlightConfig`]).
    pub flight: &'a FlightConfig,
    /// The miss (rad) under which a spin reaches the pose.
    pub tolerance: f64,
}

impl Spin<'_> {
    /// The launch spin that turns the body to `want` at `t`, from `guess`; `None` when
    /// it does not converge, when the spin would turn more than [`MAX_TURN`], or when
    /// the Jacobian is singular.
    ///
    /// Newton's method (a finite-difference Jacobian, halved steps where a full one does
    /// not get closer) runs on a coarse flight: RK4 on a fixed number of steps set by the
    /// guess ([`COARSE_ANGLE`]), so that the miss is smooth in the spin. Chord steps with
    /// the last Jacobian then bring the flight's own miss under the tolerance. For a
    /// body with two equal moments both flights are the exact closed form.
    pub fn reaching(&self, want: DQuat, guess: DVec3, flight: &mut FreeFlight) -> Option<DVec3> {
        let t = self.t;
        let limit = MAX_TURN / t;
        if !guess.is_finite() || guess.length() > limit {
            return None;
        }
        let k = self.mass.principal_inertia;
        // The spin's greatest speed in flight is at most |w| I_max / I_min.
        let turn = guess.length() * k.max_element() / k.min_element() * t;
        let steps = (turn / COARSE_ANGLE).ceil().max(1.0);
        let coarse = FlightConfig {
            rk4_max_step: t / steps,
            rk4_max_angle: f64::INFINITY,
        };
        let mut miss = |w: DVec3, cfg: &FlightConfig| -> DVec3 {
            let launch = LaunchState {
                origin: DVec3::ZERO,
                orientation: self.from,
                velocity: DVec3::ZERO,
                angular_velocity: w,
            };
            flight.reset(self.mass, launch, DVec3::ZERO, t, cfg);
            let d = want.conjugate() * flight.orientation(t);
            if d.w < 0.0 { -d } else { d }.to_scaled_axis()
        };
        let mut w = guess;
        let mut r = miss(w, &coarse);
        let mut jacobian = None;
        for _ in 0..NEWTON_STEPS {
            if !r.is_finite() || w.length() > limit {
                return None;
            }
            // The chord steps need a Jacobian, so a guess that already meets the coarse
            // flight still gets one below.
            if r.length() < self.tolerance && jacobian.is_some() {
                break;
            }
            let h = 1e-6 * (1.0 + w.length());
            let j = DMat3::from_cols(
                (miss(w + DVec3::X * h, &coarse) - r) / h,
                (miss(w + DVec3::Y * h, &coarse) - r) / h,
                (miss(w + DVec3::Z * h, &coarse) - r) / h,
            );
            let det = j.determinant();
            if det.is_nan() || det.abs() <= 1e-12 {
                return None;
            }
            let inverse = j.inverse();
            jacobian = Some(inverse);
            if r.length() < self.tolerance {
                break;
            }
            let step = -(inverse * r);
            let mut lambda = 1.0;
            loop {
                let next = w + step * lambda;
                let rn = miss(next, &coarse);
                if rn.length() < r.length() {
                    (w, r) = (next, rn);
                    break;
                }
                lambda *= 0.5;
                if lambda < 1.0 / 64.0 {
                    return None;
                }
            }
        }
        let inverse = jacobian?;
        for _ in 0..=CHORD_STEPS {
            let r = miss(w, self.flight);
            if !r.is_finite() || w.length() > limit {
                return None;
            }
            if r.length() < self.tolerance {
                return Some(w);
            }
            w -= inverse * r;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shape::Shape;

    fn brick() -> MassProperties {
        Shape::Cuboid {
            half_extents: DVec3::new(0.07, 0.035, 0.0175),
        }
        .mass_properties(705.0)
    }

    #[test]
    fn the_spin_of_a_tumbling_block_is_found_to_the_tolerance() {
        let mass = brick();
        let cfg = FlightConfig::default();
        let from = DQuat::from_rotation_x(0.4);
        let t = 1.2;
        // A tumble about no principal axis, several turns long.
        let w0 = DVec3::new(4.0, -7.0, 11.0);
        let mut flight = FreeFlight::default();
        let launch = LaunchState {
            origin: DVec3::ZERO,
            orientation: from,
            velocity: DVec3::ZERO,
            angular_velocity: w0,
        };
        flight.reset(&mass, launch, DVec3::ZERO, t, &cfg);
        let want = flight.orientation(t);
        for tolerance in [1e-6, 1e-9] {
            let spin = Spin {
                mass: &mass,
                from,
                t,
                flight: &cfg,
                tolerance,
            };
            // Where the naive guess (the spin plus a turn over t) lands, Newton corrects it.
            let guess = w0 + DVec3::new(0.3, 0.2, -0.25);
            let w = spin.reaching(want, guess, &mut flight).expect("converges");
            flight.reset(
                &mass,
                LaunchState {
                    angular_velocity: w,
                    ..launch
                },
                DVec3::ZERO,
                t,
                &cfg,
            );
            let d = want.conjugate() * flight.orientation(t);
            assert!(d.xyz().length() < tolerance, "{w} misses by {d}");
        }
    }

    #[test]
    fn a_spin_past_the_largest_turn_is_refused() {
        let mass = brick();
        let cfg = FlightConfig::default();
        let spin = Spin {
            mass: &mass,
            from: DQuat::IDENTITY,
            t: 1.0,
            flight: &cfg,
            tolerance: 1e-6,
        };
        let mut flight = FreeFlight::default();
        let too_fast = DVec3::X * (2.0 * MAX_TURN);
        assert_eq!(spin.reaching(DQuat::IDENTITY, too_fast, &mut flight), None);
    }
}
