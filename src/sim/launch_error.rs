//! The launcher model: 1-sigma launch tolerances ([`Tolerances`]), the actual errors of
//! one body in one sample ([`BodyError`]), their seeded draws ([`draw_errors`]) and the
//! launch a launcher delivers with them ([`BodyError::apply`]).
//! The error budget (`crate::budget`) measures a launch with it; a robust solve
//! (`crate::evaluate`) optimises under it, with the same draws for the same seed.
//!
//! Besides speed, direction, spin rate and timing, a real launcher gets wrong where the
//! body sits on it (position), how it holds it (orientation), and spins it a little
//! even when asked for no spin (the spin floor): a body launched without spin is not
//! immune to spin errors, and the longer it flies the more that floor turns it.

use glam::{DQuat, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

pub use crate::scene::launcher::{ToleranceError, Tolerances, KINDS, PARAMETERS};
use crate::sim::flight::LaunchState;

/// The actual errors of one body in one sample (not tolerances): relative speed error,
/// direction error (rad, two perpendicular components), relative spin error, release
/// delay (s), position offset (m, x and y), orientation error (rad, a rotation vector),
/// spin floor (rad/s, a world vector), relative drag-coefficient error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyError {
    pub speed: f64,
    pub direction: [f64; 2],
    pub spin: f64,
    pub timing: f64,
    pub position: [f64; 2],
    pub orientation: [f64; 3],
    pub spin_floor: [f64; 3],
    pub cd: f64,
}

impl BodyError {
    /// The launch the launcher delivers when asked for `s`: the body sits off by
    /// `position` and turned by `orientation`, the velocity is aimed off by `direction`
    /// and scaled by `1 + speed`, and the spin is scaled by `1 + spin` with `spin_floor`
    /// added. (Timing and drag act on the flight, not on the launch.)
    pub fn apply(&self, s: LaunchState) -> LaunchState {
        let [px, py] = self.position;
        LaunchState {
            origin: s.origin + DVec3::new(px, py, 0.0),
            orientation: DQuat::from_scaled_axis(DVec3::from(self.orientation)) * s.orientation,
            velocity: aim(s.velocity, self.direction) * (1.0 + self.speed),
            angular_velocity: s.angular_velocity * (1.0 + self.spin) + DVec3::from(self.spin_floor),
        }
    }
}

/// Rotate `v` by the direction error `d` (rad) about two axes perpendicular to it: the
/// horizontal one (`v x z`, or `v x x` for a vertical `v`) and the one completing it.
pub fn aim(v: DVec3, d: [f64; 2]) -> DVec3 {
    if d == [0.0, 0.0] {
        return v;
    }
    let u = v.normalize_or_zero();
    if u == DVec3::ZERO {
        return v;
    }
    let mut e1 = u.cross(DVec3::Z);
    if e1.length_squared() < 1e-12 {
        e1 = u.cross(DVec3::X);
    }
    let e1 = e1.normalize();
    let e2 = u.cross(e1);
    DQuat::from_scaled_axis(e1 * d[0] + e2 * d[1]) * v
}

/// SplitMix64 of `(seed, k)`: the seed of sample `k`'s generator.
pub fn sample_seed(seed: u64, k: u64) -> u64 {
    let mut z = seed
        .wrapping_mul(0xD1B5_4A32_D192_ED03)
        .wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k.wrapping_add(1)));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Standard normals drawn per body and sample.
const NORMALS: usize = 14;

/// The errors of sample `k`: fourteen standard normals per body, always drawn in the
/// same order (so that every tolerance size sees the same draws), scaled by the
/// tolerances.
pub fn draw_errors(seed: u64, k: u64, tol: &Tolerances, out: &mut [BodyError]) {
    let mut rng = ChaCha8Rng::seed_from_u64(sample_seed(seed, k));
    for e in out.iter_mut() {
        let mut z = [0.0f64; NORMALS];
        for zi in &mut z {
            *zi = StandardNormal.sample(&mut rng);
        }
        let deg = |z: f64| (z * tol.orientation_deg).to_radians();
        let floor = |z: f64| z * tol.spin_floor_rad_s;
        *e = BodyError {
            speed: z[0] * tol.speed_pct / 100.0,
            direction: [
                (z[1] * tol.direction_deg).to_radians(),
                (z[2] * tol.direction_deg).to_radians(),
            ],
            spin: z[3] * tol.spin_pct / 100.0,
            timing: z[4] * tol.timing_ms / 1000.0,
            cd: z[5] * tol.cd_pct / 100.0,
            position: [
                z[6] * tol.position_mm / 1000.0,
                z[7] * tol.position_mm / 1000.0,
            ],
            orientation: [deg(z[8]), deg(z[9]), deg(z[10])],
            spin_floor: [floor(z[11]), floor(z[12]), floor(z[13])],
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> LaunchState {
        LaunchState {
            origin: DVec3::new(0.1, -0.4, 0.02),
            orientation: DQuat::from_rotation_z(0.3),
            velocity: DVec3::new(0.2, 0.9, 5.0),
            angular_velocity: DVec3::ZERO,
        }
    }

    #[test]
    fn no_error_delivers_the_asked_launch_bit_for_bit() {
        assert_eq!(BodyError::default().apply(state()), state());
    }

    #[test]
    fn a_body_asked_for_no_spin_still_gets_the_spin_floor() {
        let mut errs = [BodyError::default(); 64];
        let tol = Tolerances {
            spin_floor_rad_s: 0.2,
            ..Tolerances::ZERO
        };
        draw_errors(7, 3, &tol, &mut errs);
        let spins: Vec<f64> = errs
            .iter()
            .map(|e| e.apply(state()).angular_velocity.length())
            .collect();
        assert!(spins.iter().all(|&w| w > 0.0));
        // |w| of three normal components of 0.2 rad/s: mean 0.2 sqrt(8 / pi) = 0.32.
        let mean = spins.iter().sum::<f64>() / spins.len() as f64;
        assert!((0.25..0.4).contains(&mean), "{mean}");
        // The spin floor alone moves nothing else.
        let s = errs[0].apply(state());
        assert_eq!(
            (s.origin, s.orientation, s.velocity),
            (state().origin, state().orientation, state().velocity)
        );
    }

    #[test]
    fn position_and_orientation_errors_move_the_body_on_the_launcher_only() {
        let e = BodyError {
            position: [0.001, -0.002],
            orientation: [0.0, 0.0, 0.01],
            ..Default::default()
        };
        let s = e.apply(state());
        let moved = s.origin - state().origin - DVec3::new(0.001, -0.002, 0.0);
        assert!(moved.length() < 1e-15, "{moved}");
        let turn = s.orientation * state().orientation.inverse();
        assert!((turn.angle_between(DQuat::IDENTITY) - 0.01).abs() < 1e-12);
        assert_eq!(
            (s.velocity, s.angular_velocity),
            (state().velocity, DVec3::ZERO)
        );
    }

    #[test]
    fn each_tolerance_draws_only_its_own_error() {
        for k in 0..KINDS {
            let mut a = [0.0; KINDS];
            a[k] = 1.0;
            let mut errs = [BodyError::default(); 3];
            draw_errors(1, 0, &Tolerances::from_array(a), &mut errs);
            for e in errs {
                let fields = [
                    e.speed != 0.0,
                    e.direction != [0.0; 2],
                    e.spin != 0.0,
                    e.timing != 0.0,
                    e.position != [0.0; 2],
                    e.orientation != [0.0; 3],
                    e.spin_floor != [0.0; 3],
                    e.cd != 0.0,
                ];
                let on: Vec<usize> = (0..KINDS).filter(|&j| fields[j]).collect();
                assert_eq!(on, vec![k], "{}", PARAMETERS[k].0);
            }
        }
    }
}
