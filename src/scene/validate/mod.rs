//! Validation: the raw scene in, a [`Scene`] out, with every field checked and every
//! error naming the file and the field ([`SceneError`]).
//!
//! [`Validator`] holds the scene's file and folder; its checks are split by what they
//! validate: the scene as a whole, its receiver and target here; the occluders
//! (`occluder`), the hints (`hints`) and the stages of the strategy (`strategy`) beside
//! it; the pictures in `super::pictures` and the number checks in `super::bounds`.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::raw::*;
use super::start::{raw_start_overrides, Aim};
use super::*;
use crate::energy::Weights;
use crate::shadow::mask::Mask;
use crate::shadow::raster::{ImageRect, ShadowCamera};

mod hints;
mod occluder;
mod strategy;

pub use occluder::too_fast_spin;

/// What validation knows besides the raw scene: the scene file (every error names it)
/// and its folder (relative paths are resolved against it).
pub(super) struct Validator<'a> {
    pub(super) file: &'a Path,
    pub(super) dir: &'a Path,
}

impl Validator<'_> {
    /// An error of field `field` (a path such as `occluders[1].shape`) of the scene file.
    pub(super) fn field_err(
        &self,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> SceneError {
        SceneError::Field {
            path: self.file.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// A path the scene names: absolute as given, relative to the scene's folder.
    pub(super) fn resolve(&self, rel: &str) -> PathBuf {
        let p = Path::new(rel);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.dir.join(p)
        }
    }

    /// The whole scene, checked in the order its fields depend on each other: pictures,
    /// timing, gravity, light and receiver, table, occluders, hints, start guess,
    /// stages and contacts.
    pub(super) fn scene(&self, raw: RawScene, default_name: String) -> Result<Scene> {
        let name = self.name(&raw, default_name)?;
        let specs = self.pictures(&raw)?;
        let t = specs.last().expect("at least one picture").t;
        let Timing { dt, hold, horizon } = self.timing(&raw, specs[0].t, t)?;
        let gravity = self.gravity(&raw)?;
        let light = self.vec3("light", raw.light)?;
        let receiver = self.receiver(&raw.receiver, light)?;
        let target = specs.last().expect("at least one picture").target.clone();
        let camera = camera(light, &receiver, &target);
        let table = self.table(&raw)?;
        let rise = self.within(
            "start.rise",
            raw.start
                .as_ref()
                .and_then(|s| s.rise)
                .unwrap_or(DEFAULT_START_RISE),
            MAX_COORDINATE,
        )?;
        let mut occluders = self.occluders(&raw.occluders, (t, horizon), gravity, rise)?;
        self.check_overlaps(&occluders, table.as_ref())?;
        self.check_room_under_light(&occluders, &receiver, light)?;
        let pictures = self.with_hints(specs, &occluders)?;
        let hints: Vec<Hint> = pictures.iter().flat_map(|p| p.hints.clone()).collect();
        let positions = self.positions(raw.positions.as_deref(), table.is_some())?;
        let free_on = table
            .as_ref()
            .filter(|_| positions == LaunchPositions::Free);
        let aim = |t| Aim {
            camera: &camera,
            receiver: &receiver,
            t,
            gravity,
            rise,
            free_on,
        };
        self.aim_start(&raw, &pictures, &mut occluders, aim)?;
        self.check_start_guess(&occluders)?;
        let defaults = Weights::default_for(target.count() as f64);
        let (stages, strategy) = self.stages(&raw, &occluders, defaults)?;
        let contacts = self.contacts(&raw)?;
        if stages.len() > MAX_STAGES {
            return Err(self.field_err(
                "strategy",
                format!(
                    "expands to {} stages, more than the {MAX_STAGES} supported",
                    stages.len()
                ),
            ));
        }
        let launcher = raw.launcher.unwrap_or_default();
        launcher
            .validate(t)
            .map_err(|e| self.field_err("launcher", e.to_string()))?;
        Ok(Scene {
            name,
            source: self.file.to_path_buf(),
            target,
            t,
            pictures,
            hold,
            positions,
            dt,
            gravity,
            light,
            receiver,
            camera,
            table,
            occluders,
            hints,
            stages,
            strategy,
            seed: raw.seed.unwrap_or(1),
            contacts,
            launcher,
        })
    }

    /// The scene's name: `name`, or the folder's (`default_name`); a name without path
    /// separators, since the output folder is named after it.
    fn name(&self, raw: &RawScene, default_name: String) -> Result<String> {
        let name = raw.name.clone().unwrap_or(default_name);
        if name.is_empty() || name == "." || name == ".." || name.contains(['/', '\\']) {
            return Err(self.field_err("name", "must be a non-empty name without path separators"));
        }
        Ok(name)
    }

    /// The timestep and the hold window, for pictures from `first_t` to `t`: the flight
    /// within [`MAX_T`] and its keys within [`MAX_KEYS`].
    fn timing(&self, raw: &RawScene, first_t: f64, t: f64) -> Result<Timing> {
        let dt = self.positive("timestep", raw.timestep.unwrap_or(DEFAULT_TIMESTEP))?;
        let hold = match &raw.hold {
            Some(h) => Some(self.hold(h, first_t, dt)?),
            None => None,
        };
        let horizon = t + hold.as_ref().map_or(0.0, |h| h.window);
        if horizon > MAX_T {
            return Err(self.field_err(
                "hold.window",
                format!("ends at {horizon} s, after the longest flight allowed ({MAX_T} s)"),
            ));
        }
        if dt > t {
            return Err(self.field_err(
                "timestep",
                format!("must not exceed t = {} s, got {}", short(t), short(dt)),
            ));
        }
        // Every key from launch to t is stored (trajectory, export, continuation), so
        // their count bounds memory.
        if horizon / dt > MAX_KEYS {
            return Err(self.field_err(
                "timestep",
                format!(
                    "gives {:.0} keys up to t = {t} s, more than the {MAX_KEYS:e} allowed; use a timestep of at least {:e} s",
                    (horizon / dt).ceil(),
                    horizon / MAX_KEYS
                ),
            ));
        }
        Ok(Timing { dt, hold, horizon })
    }

    /// Gravity: within [`MAX_GRAVITY`], and pulling down.
    fn gravity(&self, raw: &RawScene) -> Result<DVec3> {
        let gravity = self.vec3_len_within(
            "gravity",
            raw.gravity.unwrap_or(DEFAULT_GRAVITY),
            MAX_GRAVITY,
        )?;
        // The objects are launched upwards from the table's top and come down: every
        // start guess and design counts on it (z is up).
        if gravity.z.is_nan() || gravity.z >= 0.0 {
            return Err(self.field_err(
                "gravity",
                format!(
                    "must pull down (a negative z, z is up), got {:?}",
                    gravity.to_array()
                ),
            ));
        }
        Ok(gravity)
    }

    /// The table, if the scene has one: a centre and a positive size.
    fn table(&self, raw: &RawScene) -> Result<Option<Table>> {
        let Some(tb) = &raw.table else {
            return Ok(None);
        };
        let center = self.vec3("table.center", tb.center)?;
        let mut half = DVec3::ZERO;
        for i in 0..3 {
            half[i] =
                self.positive_within(&format!("table.size[{i}]"), tb.size[i], MAX_COORDINATE)?
                    / 2.0;
        }
        Ok(Some(Table {
            center,
            half_extents: half,
        }))
    }

    /// Aim the start guess as `start.aim` says: at the hints (`aim` gives the aim of a
    /// picture's instant), or straight up.
    fn aim_start<'a>(
        &self,
        raw: &RawScene,
        pictures: &[Picture],
        occluders: &mut [Occluder],
        aim: impl Fn(f64) -> Aim<'a>,
    ) -> Result<()> {
        let setting = raw
            .start
            .as_ref()
            .and_then(|s| s.aim.clone())
            .unwrap_or_else(|| "hints".to_string());
        match setting.as_str() {
            // The earliest picture an occluder has hints in aims it (later ones first,
            // so that earlier ones overwrite them).
            "hints" => {
                let explicit = raw_start_overrides(raw);
                for p in pictures.iter().rev() {
                    aim(p.t).apply(occluders, &p.hints, &explicit);
                }
                if let [a, b, ..] = pictures {
                    aim(a.t).apply_between(b.t, &b.hints, occluders, &a.hints, &explicit);
                }
                Ok(())
            }
            "up" => Ok(()),
            other => Err(self.field_err(
                "start.aim",
                format!("must be \"hints\" or \"up\", got \"{other}\""),
            )),
        }
    }

    /// How the optimizer treats contacts: `"constraint"` (the default) or `"penalty"`.
    fn contacts(&self, raw: &RawScene) -> Result<Contacts> {
        match raw.contacts.as_deref() {
            None | Some("constraint") => Ok(Contacts::Constraint),
            Some("penalty") => Ok(Contacts::Penalty),
            Some(other) => Err(self.field_err(
                "contacts",
                format!("must be \"constraint\" or \"penalty\", got \"{other}\""),
            )),
        }
    }

    fn receiver(&self, r: &RawReceiver, light: DVec3) -> Result<Receiver> {
        let center = self.vec3("receiver.center", r.center)?;
        let u = self.unit("receiver.u", r.u)?;
        let v = self.unit("receiver.v", r.v)?;
        if u.dot(v).abs() > 1e-6 {
            return Err(self.field_err("receiver.v", "must be perpendicular to receiver.u"));
        }
        let width = self.positive_within("receiver.width", r.width, 2.0 * MAX_COORDINATE)?;
        let height = self.positive_within("receiver.height", r.height, 2.0 * MAX_COORDINATE)?;
        let normal = u.cross(v).normalize();
        let h = (light - center).dot(normal);
        // The image is seen from the light's side with u to the right and v up, so the
        // light must be strictly in front of the receiver (on the side of u x v).
        if h <= 1e-9 {
            return Err(self.field_err(
                "light",
                format!(
                    "the light is on or behind the receiver plane (its height above the plane along u x v is {h:.4} m); it must be in front"
                ),
            ));
        }
        Ok(Receiver {
            center,
            u,
            v,
            normal,
            width,
            height,
        })
    }

    pub(super) fn target(&self, field: &str, rel: &str) -> Result<Mask> {
        let path = self.resolve(rel);
        let bytes = super::read_input(&path).map_err(|error| SceneError::Named {
            path: self.file.to_path_buf(),
            field: field.to_string(),
            named: path.clone(),
            error,
        })?;
        let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
            .map_err(|e| SceneError::TargetNotPng {
                path: path.clone(),
                reason: e.to_string(),
            })?
            .to_rgba8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
            return Err(SceneError::TargetNotPng {
                path,
                reason: format!("{w} x {h} pixels is larger than the {MAX_IMAGE_SIDE} x {MAX_IMAGE_SIDE} supported"),
            });
        }
        let mask = Mask::from_fn(w, h, |x, y| {
            let p = img.get_pixel(x as u32, y as u32).0;
            // Rec. 709 luma of the 8-bit values; dark means below half luminance, and a
            // (mostly) transparent pixel is never shadow.
            let luma = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            p[3] >= 128 && luma < 127.5
        });
        if mask.count() == 0 {
            return Err(SceneError::TargetEmpty { path });
        }
        Ok(mask)
    }
}

/// The scene's timing: the timestep, the hold window and the horizon, the last instant
/// the solver's model runs to (s).
struct Timing {
    dt: f64,
    hold: Option<Hold>,
    horizon: f64,
}

/// The shadow camera of the picture: the light, and the receiver's rectangle covered by
/// the target's pixels.
fn camera(light: DVec3, receiver: &Receiver, target: &Mask) -> ShadowCamera {
    ShadowCamera::new(
        light,
        ImageRect {
            center: receiver.center,
            u: receiver.u,
            v: receiver.v,
            width_m: receiver.width,
            height_m: receiver.height,
            width_px: target.width(),
            height_px: target.height(),
        },
    )
}
