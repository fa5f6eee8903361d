//! The launcher's errors on the command line ([`LauncherArgs`]), shared by `bsa budget`
//! and `bsa solve --robust`: the scene's `"launcher"` (else the defaults), then a
//! `--launcher FILE` over it, then each flag over that.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

use crate::scene::launcher::{Tolerances, KINDS, PARAMETERS};
use crate::scene::Scene;

/// The launcher's 1-sigma errors, each over the scene's own.
#[derive(Args, Clone, Debug, Default)]
pub(super) struct LauncherArgs {
    /// The builder's launcher: a JSON object of 1-sigma errors, any of "speed_pct",
    /// "direction_deg", "spin_pct", "timing_ms", "position_mm", "orientation_deg",
    /// "spin_floor_rad_s" and "cd_pct"; each one left out keeps the scene's "launcher"
    /// (else its default below).
    #[arg(long, value_name = "FILE.json")]
    launcher: Option<PathBuf>,
    /// Launch speed error, 1 sigma (% of the speed) [default: 0.5].
    #[arg(long, allow_negative_numbers = true)]
    speed_tol: Option<f64>,
    /// Launch direction error, 1 sigma per perpendicular component (deg) [default: 0.25].
    #[arg(long, allow_negative_numbers = true)]
    direction_tol: Option<f64>,
    /// Spin rate error, 1 sigma (% of the angular speed) [default: 2].
    #[arg(long, allow_negative_numbers = true)]
    spin_tol: Option<f64>,
    /// Release timing error, 1 sigma (ms) [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    timing_tol: Option<f64>,
    /// Where the body sits on the launcher, 1 sigma per horizontal component (mm)
    /// [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    position_tol: Option<f64>,
    /// How the launcher holds the body, 1 sigma of a turn about each axis (deg)
    /// [default: 0.5].
    #[arg(long, allow_negative_numbers = true)]
    orientation_tol: Option<f64>,
    /// Spin the launcher gives whatever spin is asked, 1 sigma per component (rad/s)
    /// [default: 0.2].
    #[arg(long, allow_negative_numbers = true)]
    spin_floor_tol: Option<f64>,
    /// Drag coefficient error, 1 sigma (% of Cd): the drag model's, used in air
    /// [default: 5].
    #[arg(long, allow_negative_numbers = true)]
    cd_tol: Option<f64>,
}

/// The flags of the errors, in the order of [`Tolerances::to_array`].
pub(super) const FLAGS: [&str; KINDS] = [
    "--speed-tol",
    "--direction-tol",
    "--spin-tol",
    "--timing-tol",
    "--position-tol",
    "--orientation-tol",
    "--spin-floor-tol",
    "--cd-tol",
];

impl LauncherArgs {
    /// The flags' values, in the order of [`FLAGS`].
    fn values(&self) -> [Option<f64>; KINDS] {
        [
            self.speed_tol,
            self.direction_tol,
            self.spin_tol,
            self.timing_tol,
            self.position_tol,
            self.orientation_tol,
            self.spin_floor_tol,
            self.cd_tol,
        ]
    }

    /// The first option given, if any (to refuse them where they do nothing).
    pub(super) fn first_given(&self) -> Option<&'static str> {
        if self.launcher.is_some() {
            return Some("--launcher");
        }
        FLAGS
            .iter()
            .zip(self.values())
            .find(|(_, v)| v.is_some())
            .map(|(f, _)| *f)
    }

    /// Whether `--cd-tol` was given.
    pub(super) fn cd_given(&self) -> bool {
        self.cd_tol.is_some()
    }

    /// The launcher for `scene`: its own, the file's fields over it, the flags over
    /// that; checked against the scene's `t`, an error naming the flag or file to change.
    pub(super) fn resolve(&self, scene: &Scene) -> Result<Tolerances> {
        let mut tol = scene.launcher;
        if let Some(file) = &self.launcher {
            tol = read_over(file, tol)?;
        }
        let mut a = tol.to_array();
        for (k, v) in self.values().into_iter().enumerate() {
            if let Some(v) = v {
                a[k] = v;
            }
        }
        let tol = Tolerances::from_array(a);
        if let Err(e) = tol.validate(scene.t) {
            let k = PARAMETERS
                .iter()
                .position(|p| p.0 == e.name)
                .unwrap_or(KINDS - 1);
            let from = match (self.values()[k], &self.launcher) {
                (Some(_), _) => FLAGS[k].to_string(),
                (None, Some(file)) => file.display().to_string(),
                (None, None) => format!("{}: \"launcher\"", scene.source.display()),
            };
            bail!("{from}: {e}");
        }
        Ok(tol)
    }
}

/// The launcher of the file `file` (its fields over the defaults), checked against `t`.
pub(super) fn read(file: &Path, t: f64) -> Result<Tolerances> {
    let tol = read_over(file, Tolerances::default())?;
    tol.validate(t)
        .with_context(|| format!("{}", file.display()))?;
    Ok(tol)
}

/// The launcher file `file`'s fields over `base`.
fn read_over(file: &Path, base: Tolerances) -> Result<Tolerances> {
    let text = std::fs::read_to_string(file)
        .with_context(|| format!("cannot read the launcher file {}", file.display()))?;
    let given: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", file.display()))?;
    let Some(fields) = given.as_object() else {
        bail!(
            "{}: a launcher is a JSON object of 1-sigma errors, such as {{\"direction_deg\": 0.1}}",
            file.display()
        );
    };
    let mut merged = serde_json::to_value(base)?;
    for (k, v) in fields {
        merged[k] = v.clone();
    }
    serde_json::from_value(merged).with_context(|| format!("{}", file.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_flag_names_its_tolerance_in_order() {
        for (flag, (name, _, _)) in FLAGS.iter().zip(PARAMETERS) {
            assert_eq!(flag[2..].trim_end_matches("-tol"), name.replace('_', "-"));
        }
    }

    #[test]
    fn a_launcher_file_overrides_only_the_fields_it_names() {
        let dir = std::env::temp_dir().join(format!("bsa-launcher-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("l.json");
        std::fs::write(&f, r#"{"direction_deg": 0.1}"#).unwrap();
        let base = Tolerances {
            speed_pct: 0.3,
            ..Tolerances::default()
        };
        let t = read_over(&f, base).unwrap();
        assert_eq!(t.direction_deg, 0.1);
        assert_eq!(t.speed_pct, 0.3);
        std::fs::write(&f, r#"{"direction": 0.1}"#).unwrap();
        let e = format!("{:#}", read_over(&f, base).unwrap_err());
        assert!(
            e.contains("l.json") && e.contains("unknown field `direction`"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
