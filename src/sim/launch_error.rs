//! The launch-error model: 1-sigma launch tolerances ([`Tolerances`]), the actual errors
//! of one body in one sample ([`BodyError`]) and their seeded draws ([`draw_errors`]).
//! The error budget (`crate::budget`) measures a launch with it; a robust solve
//! (`crate::evaluate`) optimises under it, with the same draws for the same seed.

use glam::{DQuat, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;

/// Launch errors, each the standard deviation of a normal error (1 sigma), independent
/// per body.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Tolerances {
    /// Launch speed (% of the speed). Default 0.5 %.
    pub speed_pct: f64,
    /// Launch direction (deg), each of two perpendicular components. Default 0.25 deg.
    pub direction_deg: f64,
    /// Spin rate (% of the angular speed; the axis is kept). Default 2 %.
    pub spin_pct: f64,
    /// Release time (ms): a body released `dt` late has at `t` its pose at `t - dt`.
    /// Default 1 ms.
    pub timing_ms: f64,
    /// Drag coefficient (% of Cd): the model error. Default 5 %.
    pub cd_pct: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            speed_pct: 0.5,
            direction_deg: 0.25,
            spin_pct: 2.0,
            timing_ms: 1.0,
            cd_pct: 5.0,
        }
    }
}

/// The five error kinds: key, unit, largest accepted tolerance.
pub const PARAMETERS: [(&str, &str, f64); 5] = [
    ("speed", "%", 50.0),
    ("direction", "deg", 45.0),
    ("spin", "%", 100.0),
    ("timing", "ms", 100.0),
    ("cd", "%", 50.0),
];

impl Tolerances {
    pub fn to_array(&self) -> [f64; 5] {
        [
            self.speed_pct,
            self.direction_deg,
            self.spin_pct,
            self.timing_ms,
            self.cd_pct,
        ]
    }

    pub fn from_array(a: [f64; 5]) -> Tolerances {
        Tolerances {
            speed_pct: a[0],
            direction_deg: a[1],
            spin_pct: a[2],
            timing_ms: a[3],
            cd_pct: a[4],
        }
    }
}

/// The actual errors of one body in one sample (not tolerances): relative speed error,
/// direction error (rad, two perpendicular components), relative spin error, release
/// delay (s), relative drag-coefficient error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyError {
    pub speed: f64,
    pub direction: [f64; 2],
    pub spin: f64,
    pub timing: f64,
    pub cd: f64,
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

/// The errors of sample `k`: six standard normals per body, always drawn in the same
/// order (so that every tolerance size sees the same draws), scaled by the tolerances.
pub fn draw_errors(seed: u64, k: u64, tol: &Tolerances, out: &mut [BodyError]) {
    let mut rng = ChaCha8Rng::seed_from_u64(sample_seed(seed, k));
    for e in out.iter_mut() {
        let mut z = [0.0f64; 6];
        for zi in &mut z {
            *zi = StandardNormal.sample(&mut rng);
        }
        *e = BodyError {
            speed: z[0] * tol.speed_pct / 100.0,
            direction: [
                (z[1] * tol.direction_deg).to_radians(),
                (z[2] * tol.direction_deg).to_radians(),
            ],
            spin: z[3] * tol.spin_pct / 100.0,
            timing: z[4] * tol.timing_ms / 1000.0,
            cd: z[5] * tol.cd_pct / 100.0,
        };
    }
}
