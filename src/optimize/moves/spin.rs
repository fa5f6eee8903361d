//! Launch spins that reach an orientation at `t`: [`spin_reaching`] solves for the
//! spin ([`crate::sim::aim`]'s Newton's method on the free flight), [`launch_to`] launches a body to a pose
//! from the slowest spin of a few first guesses ([`spin_guesses`]), [`turn_spin`] turns a body
//! about a world axis. Adding `angle / t` to a spin is exact only about a principal
//! axis; a tumbling block needs the solve.

use glam::{DQuat, DVec3};

use super::aim;
use crate::evaluate::Problem;
use crate::scene::Launch;
use crate::sim::aim::Spin;
use crate::sim::flight::FreeFlight;

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

/// The miss (rad) under which a move's spin reaches its pose: far below a pixel's turn
/// for any body a picture shows (a 10 cm body turned 1e-6 rad moves its end 0.1 um).
pub const MOVE_TOLERANCE: f64 = 1e-6;

/// The launch spin that turns body `i` to the orientation `want` at `t` in free flight,
/// from `guess` ([`Spin::reaching`] on the solver's flight, to [`MOVE_TOLERANCE`]);
/// `None` when it does not converge.
pub fn spin_reaching(
    problem: &Problem,
    i: usize,
    want: DQuat,
    guess: DVec3,
    flight: &mut FreeFlight,
) -> Option<DVec3> {
    let o = &problem.scene.occluders[i];
    let spin = Spin {
        mass: &o.mass,
        from: o.orientation,
        t: problem.scene.t,
        flight: &problem.flight,
        tolerance: MOVE_TOLERANCE,
    };
    spin.reaching(want, guess, flight)
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
}
