//! Launch spins that reach an orientation at `t`: [`spin_reaching`] solves for the
//! spin by Newton's method on the free flight, [`launch_to`] launches a body to a pose
//! from the slowest spin of a few first guesses ([`spin_guesses`]), [`turn_spin`] turns a body
//! about a world axis. Adding `angle / t` to a spin is exact only about a principal
//! axis; a tumbling block needs the solve.

use glam::{DMat3, DQuat, DVec3};

use super::aim;
use crate::evaluate::Problem;
use crate::scene::Launch;
use crate::sim::flight::{FlightConfig, FreeFlight, LaunchState};

/// Set body `i`'s launch spin in `params` so that its orientation at `t`, `now`, turns by
/// `rotation` (a world axis and an angle): by adding `angle / t` about the axis to the
/// spin, which is exact only for a spin about a principal axis, or, when `exact`, by
/// [`spin_reaching`] from there (the added spin where Newton does not converge).
pub(super) fn turn_spin(
    problem: &Problem,
    params: &mut [f64],
    i: usize,
    now: DQuat,
    (axis, angle): (DVec3, f64),
    exact: bool,
    flight: &mut FreeFlight,
) {
    let mut launch = Launch::get(params, i);
    let guess = launch.angular_velocity + axis * (angle / problem.scene.t);
    launch.angular_velocity = if exact {
        let want = DQuat::from_axis_angle(axis, angle) * now;
        spin_reaching(problem, i, want, guess, flight).unwrap_or(guess)
    } else {
        guess
    };
    launch.set(params, i);
}

/// Newton iterations of [`spin_reaching`] on the coarse flight, at most.
pub(super) const NEWTON_STEPS: usize = 12;

/// Iterations of [`spin_reaching`] on the exact flight, at most, after Newton's method
/// on the coarse one.
pub(super) const CHORD_STEPS: usize = 6;

/// Rotation per RK4 step (rad, at the fastest the body's spin may get) of the coarse
/// flight on which [`spin_reaching`] runs Newton's method: about 1e-4 of the turn's error
/// at `t`, where the exact flight's steps of 0.02 rad cost five times as much.
pub(super) const COARSE_ANGLE: f64 = 0.1;

/// The launch spin that turns body `i` to the orientation `want` at `t` in free flight,
/// from `guess`; `None` when it does not converge to 1e-6 rad. Adding `angle / t` about
/// an axis to the spin is exact only for a spin about a principal axis; a tumbling block
/// needs this to turn where a move asks.
///
/// Newton's method (a finite-difference Jacobian, halved steps where a full one does not
/// get closer) runs on a coarse flight: RK4 on a fixed number of steps set by the guess
/// ([`COARSE_ANGLE`]), so that the miss is smooth in the spin (the exact flight's step
/// count follows the spin, and a finite difference across a change of it is noise).
/// Chord steps with the last Jacobian then bring the exact flight's miss under 1e-6 rad.
/// For a body with two equal moments both flights are the exact closed form.
pub fn spin_reaching(
    problem: &Problem,
    i: usize,
    want: DQuat,
    guess: DVec3,
    flight: &mut FreeFlight,
) -> Option<DVec3> {
    let scene = &problem.scene;
    let o = &scene.occluders[i];
    let t = scene.t;
    let limit = crate::evaluate::MAX_TURN / t;
    if !guess.is_finite() || guess.length() > limit {
        return None;
    }
    let k = o.mass.principal_inertia;
    // The spin's greatest speed in flight is at most |w| I_max / I_min.
    let turn = guess.length() * k.max_element() / k.min_element() * t;
    let steps = (turn / COARSE_ANGLE).ceil().max(1.0);
    let coarse = FlightConfig {
        rk4_max_step: t / steps,
        rk4_max_angle: f64::INFINITY,
    };
    let mut miss = |w: DVec3, cfg: &FlightConfig| -> DVec3 {
        let launch = LaunchState {
            origin: o.position,
            orientation: o.orientation,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        };
        flight.reset(&o.mass, launch, scene.gravity, t, cfg);
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
        if r.length() < 1e-6 && jacobian.is_some() {
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
        if r.length() < 1e-6 {
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
        let r = miss(w, &problem.flight);
        if !r.is_finite() || w.length() > limit {
            return None;
        }
        if r.length() < 1e-6 {
            return Some(w);
        }
        w -= inverse * r;
    }
    None
}

/// Launch body `i` in `candidate` so that at `t` its centre of mass is at `com` and its
/// orientation `q`: its spin the slowest that [`spin_reaching`] converges to from
/// `guesses` (a faster tumble makes every later flight of the body dearer: its RK4
/// steps are bounded by angle), its velocity by [`aim`]; `false`, and `candidate`
/// unchanged, when no guess converges.
pub(super) fn launch_to(
    problem: &Problem,
    i: usize,
    (com, q): (DVec3, DQuat),
    guesses: &[DVec3],
    candidate: &mut [f64],
    flight: &mut FreeFlight,
) -> bool {
    let slowest = guesses
        .iter()
        .filter_map(|&guess| spin_reaching(problem, i, q, guess, flight))
        .min_by(|a, b| a.length().total_cmp(&b.length()));
    let Some(w) = slowest else { return false };
    let mut launch = Launch::get(candidate, i);
    launch.angular_velocity = w;
    launch.set(candidate, i);
    aim(problem, candidate, i, com);
    true
}

/// The turn (a scaled axis, rad) from orientation `from` to `to`, the short way.
pub(super) fn turn_between(from: DQuat, to: DQuat) -> DVec3 {
    let d = to * from.conjugate();
    if d.w < 0.0 { -d } else { d }.to_scaled_axis()
}

/// The first guesses of the launch spin of body `i` (spin now `spin`, orientation at
/// `t` now `now`) that turns it to `q` at `t`: the turn added to its spin (exact for a
/// spin about a principal axis), and the turn from its launch orientation alone (a
/// seat is often far from `now`, and Newton's method on a tumbling flight strays from
/// a guess a whole turn away).
pub(super) fn spin_guesses(
    problem: &Problem,
    i: usize,
    spin: DVec3,
    now: DQuat,
    q: DQuat,
) -> [DVec3; 2] {
    let t = problem.scene.t;
    let o = &problem.scene.occluders[i];
    [
        spin + turn_between(now, q) / t,
        turn_between(o.orientation, q) / t,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turn_between_takes_the_short_way_round() {
        let from = DQuat::from_rotation_y(0.4);
        for w in [
            DVec3::new(0.3, -0.2, 0.1),
            DVec3::new(0.0, 2.5, 1.0),
            DVec3::ZERO,
        ] {
            let to = DQuat::from_scaled_axis(w) * from;
            let got = turn_between(from, to);
            assert!((got - w).length() < 1e-9, "{got} != {w}");
            // The same orientation given by the opposite quaternion gives the same turn.
            assert!((turn_between(from, -to) - w).length() < 1e-9);
        }
        // A turn past a half turn comes back as the shorter one the other way.
        let to = DQuat::from_rotation_z(4.0) * from;
        let got = turn_between(from, to);
        assert!(
            (got - DVec3::Z * (4.0 - std::f64::consts::TAU)).length() < 1e-9,
            "{got}"
        );
    }

    #[test]
    fn spin_reaching_finds_the_spin_of_a_tumbling_block() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fly");
        let p = Problem::new(crate::scene::load(&dir).unwrap());
        let mut flight = FreeFlight::default();
        let o = &p.scene.occluders[0];
        let t = p.scene.t;
        // A tumble about no principal axis, several turns long.
        let w0 = DVec3::new(4.0, -7.0, 11.0);
        let launch = LaunchState {
            origin: o.position,
            orientation: o.orientation,
            velocity: DVec3::ZERO,
            angular_velocity: w0,
        };
        flight.reset(&o.mass, launch, p.scene.gravity, t, &p.flight);
        let want = flight.orientation(t);
        // Where the naive guess (the spin plus a turn over t) lands, Newton corrects it.
        let guess = w0 + DVec3::new(0.3, 0.2, -0.25);
        let w = spin_reaching(&p, 0, want, guess, &mut flight).expect("converges");
        let launch = LaunchState {
            angular_velocity: w,
            ..launch
        };
        flight.reset(&o.mass, launch, p.scene.gravity, t, &p.flight);
        let d = want.conjugate() * flight.orientation(t);
        assert!(d.xyz().length() < 1e-6, "{w} misses by {d}");
    }
}
