//! The launcher a scene is made for: the 1-sigma errors of its launches ([`Tolerances`]),
//! with their defaults, units and limits ([`PARAMETERS`]). A scene file may state it as
//! `"launcher"`; `crate::sim::launch_error` draws the errors and applies them.

use serde::Serialize;

/// Launch errors, each the standard deviation of a normal error (1 sigma), independent
/// per body: the launcher model. A builder states their own launcher as a JSON object
/// of these fields (a scene's `"launcher"`, or `--launcher FILE`); a field left out keeps
/// its default.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    /// Where the body sits on the launcher (mm), each of two horizontal components.
    /// Default 1 mm.
    pub position_mm: f64,
    /// How the launcher holds the body (deg), a turn about each of three axes.
    /// Default 0.5 deg.
    pub orientation_deg: f64,
    /// Spin the launcher gives whatever spin is asked (rad/s), each of three
    /// components. Default 0.2 rad/s.
    pub spin_floor_rad_s: f64,
    /// Drag coefficient (% of Cd): the model error, not the launcher's. Default 5 %.
    pub cd_pct: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            speed_pct: 0.5,
            direction_deg: 0.25,
            spin_pct: 2.0,
            timing_ms: 1.0,
            position_mm: 1.0,
            orientation_deg: 0.5,
            spin_floor_rad_s: 0.2,
            cd_pct: 5.0,
        }
    }
}

/// How many error kinds there are: the launcher's seven, then the drag model's.
pub const KINDS: usize = 8;

/// The error kinds, in the order of [`Tolerances::to_array`]: key, unit, largest
/// accepted tolerance. The drag coefficient's is last, so that `[..KINDS - 1]` are the
/// launcher's own.
pub const PARAMETERS: [(&str, &str, f64); KINDS] = [
    ("speed", "%", 50.0),
    ("direction", "deg", 45.0),
    ("spin", "%", 100.0),
    ("timing", "ms", 100.0),
    ("position", "mm", 100.0),
    ("orientation", "deg", 45.0),
    ("spin_floor", "rad/s", 50.0),
    ("cd", "%", 50.0),
];

impl Tolerances {
    /// No error at all.
    pub const ZERO: Tolerances = Tolerances {
        speed_pct: 0.0,
        direction_deg: 0.0,
        spin_pct: 0.0,
        timing_ms: 0.0,
        position_mm: 0.0,
        orientation_deg: 0.0,
        spin_floor_rad_s: 0.0,
        cd_pct: 0.0,
    };

    pub fn to_array(&self) -> [f64; KINDS] {
        [
            self.speed_pct,
            self.direction_deg,
            self.spin_pct,
            self.timing_ms,
            self.position_mm,
            self.orientation_deg,
            self.spin_floor_rad_s,
            self.cd_pct,
        ]
    }

    pub fn from_array(a: [f64; KINDS]) -> Tolerances {
        Tolerances {
            speed_pct: a[0],
            direction_deg: a[1],
            spin_pct: a[2],
            timing_ms: a[3],
            position_mm: a[4],
            orientation_deg: a[5],
            spin_floor_rad_s: a[6],
            cd_pct: a[7],
        }
    }

    /// Whether every error is zero (every draw is then the nominal launch).
    pub fn is_zero(&self) -> bool {
        self.to_array() == [0.0; KINDS]
    }
}

/// A tolerance out of its range.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("the {} tolerance must be between 0 and {} {unit}, got {}", .name.replace('_', " "), super::short(*.max), super::short(*.value))]
pub struct ToleranceError {
    pub name: &'static str,
    pub unit: &'static str,
    pub value: f64,
    pub max: f64,
}

/// The largest tolerance of each kind accepted for a picture at `t`, in the order of
/// [`Tolerances::to_array`]: [`PARAMETERS`]' limits, the timing's also a third of `t`.
pub fn limits(t: f64) -> [f64; KINDS] {
    PARAMETERS.map(|(name, _, max)| match name {
        "timing" => max.min(t * 1000.0 / 3.0),
        _ => max,
    })
}

impl Tolerances {
    /// Every tolerance finite and within its [`limits`].
    pub fn validate(&self, t: f64) -> Result<(), ToleranceError> {
        let values = self.to_array().into_iter().zip(limits(t));
        for ((value, max), (name, unit, _)) in values.zip(PARAMETERS) {
            if !(value.is_finite() && (0.0..=max).contains(&value)) {
                return Err(ToleranceError {
                    name,
                    unit,
                    value,
                    max,
                });
            }
        }
        Ok(())
    }
}
