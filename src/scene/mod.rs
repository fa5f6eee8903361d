//! Scene loading: raw JSON, PNG and OBJ in, one validated [`Scene`] out.
//!
//! This is the only place where user input is checked. [`load`] reads the scene file
//! (see `docs/scene-format.md`), resolves relative paths against the scene's folder,
//! decodes the target PNG into a [`Mask`], loads OBJ meshes, computes mass properties,
//! expands the optimisation strategy into a flat list of [`Stage`]s and checks every
//! number. Everything downstream (flight, rasterizer, energies, optimizer, export)
//! trusts a `Scene` and never fails on it: all attributes are resolved here.
//!
//! Data flow: `scene.json` -> `RawScene` (serde, unknown fields rejected) ->
//! validation with field paths -> [`Scene`]. Errors are [`SceneError`]s that name the
//! file and the field.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DQuat, DVec2, DVec3};
use serde::Deserialize;

use crate::energy::{Term, Weights, TERM_COUNT};
use crate::geometry::distance::{
    signed_distance, table_shape, table_signed_distance, ContactShape,
};
pub use crate::geometry::shape::Table;
use crate::geometry::shape::{self, MassProperties, Shape, TriMesh};
use crate::shadow::mask::Mask;
use crate::shadow::raster::{ImageRect, ShadowCamera};

/// Why a scene could not be loaded. Every variant names the file, and the field when
/// one is at fault, so that the message alone tells the user what to fix.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file (or a file it names) could not be read.
    #[error("cannot read {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The scene file is not valid JSON, has an unknown field, or a value of the wrong type.
    #[error("{path}: {message}")]
    Json { path: PathBuf, message: String },
    /// A field holds a value outside its allowed range (or NaN/infinity).
    #[error("{path}: field `{field}`: {reason}")]
    Field {
        path: PathBuf,
        field: String,
        reason: String,
    },
    /// The target image is not a readable PNG.
    #[error("{path}: the target is not a readable PNG image: {reason}")]
    TargetNotPng { path: PathBuf, reason: String },
    /// The target image has no shadow pixel at all.
    #[error("{path}: the target image has no dark pixel (dark = luminance below half, opaque); there is nothing to match")]
    TargetEmpty { path: PathBuf },
    /// An OBJ mesh could not be used.
    #[error("{path}: field `{field}`: unusable mesh")]
    Obj {
        path: PathBuf,
        field: String,
        #[source]
        source: shape::ObjError,
    },
    /// A line of a hints text file is malformed.
    #[error("{path}:{line}: {reason}")]
    HintLine {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    /// Two occluders overlap at launch, or an occluder starts inside the table.
    #[error("{path}: {what} overlap at launch (penetration {depth:.3e} m); move them apart")]
    Overlap {
        path: PathBuf,
        what: String,
        depth: f64,
    },
}

type Result<T> = std::result::Result<T, SceneError>;

// ---------------------------------------------------------------------------------
// Raw JSON types. Unknown fields are rejected everywhere so that a misspelt option is
// an error instead of being silently ignored.
// ---------------------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<String>,
    target: String,
    t: f64,
    timestep: Option<f64>,
    gravity: Option<[f64; 3]>,
    light: [f64; 3],
    receiver: RawReceiver,
    table: Option<RawTable>,
    occluders: Vec<RawOccluder>,
    #[serde(default)]
    hints: Option<RawHints>,
    start: Option<RawStart>,
    stages: Option<Vec<RawStage>>,
    strategy: Option<RawStrategy>,
    seed: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawReceiver {
    center: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    width: f64,
    height: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTable {
    center: [f64; 3],
    size: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
enum RawShape {
    Sphere { radius: f64 },
    Box { size: [f64; 3] },
    Mesh { obj: String, scale: Option<f64> },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOccluder {
    name: String,
    shape: RawShape,
    position: [f64; 3],
    orientation: Option<[f64; 4]>,
    mass: Option<f64>,
    density: Option<f64>,
    launched: Option<bool>,
    start_velocity: Option<[f64; 3]>,
    start_angular_velocity: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawHints {
    File(String),
    Inline(Vec<RawHint>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHint {
    occluder: String,
    point: [f64; 3],
    pixel: [f64; 2],
    weight: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStart {
    rise: Option<f64>,
    aim: Option<String>,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
struct RawStage {
    name: Option<String>,
    weights: HashMap<String, f64>,
    vary: Option<RawVary>,
    step: Option<f64>,
    max_iterations: Option<usize>,
    population: Option<usize>,
    target_energy: Option<f64>,
    tol_fun: Option<f64>,
    stagnation: Option<usize>,
}

#[derive(Deserialize, Clone)]
#[serde(untagged)]
enum RawVary {
    All(String),
    Names(Vec<String>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum RawStrategy {
    Scheduled,
    Sequential {
        order: Option<RawOrder>,
        rounds: Option<u32>,
        stage: Box<RawStage>,
        #[serde(rename = "final")]
        final_stage: Option<Box<RawStage>>,
    },
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawOrder {
    Auto(String),
    Names(Vec<String>),
}

// ---------------------------------------------------------------------------------
// Validated types.
// ---------------------------------------------------------------------------------

/// The planar receiver and the rectangle on it that the target image covers.
#[derive(Clone, Debug)]
pub struct Receiver {
    /// Centre of the image rectangle (m).
    pub center: DVec3,
    /// Unit in-plane axis along image x (left to right).
    pub u: DVec3,
    /// Unit in-plane axis along image up (bottom to top), perpendicular to `u`.
    pub v: DVec3,
    /// Unit normal `u x v`, pointing to the light's side.
    pub normal: DVec3,
    /// Rectangle width along `u` (m).
    pub width: f64,
    /// Rectangle height along `v` (m).
    pub height: f64,
}

/// One occluder, resolved: shape, mass properties and launch pose.
#[derive(Clone, Debug)]
pub struct Occluder {
    pub name: String,
    pub shape: Shape,
    pub mass: MassProperties,
    /// Position of the body frame's origin at launch (m, world).
    pub position: DVec3,
    /// Orientation of the body frame at launch (body -> world).
    pub orientation: DQuat,
    /// Whether the optimizer launches it; a non-launched occluder stays put.
    pub launched: bool,
    /// Initial guess of the centre-of-mass launch velocity (m/s).
    pub start_velocity: DVec3,
    /// Initial guess of the launch angular velocity (rad/s, world).
    pub start_angular_velocity: DVec3,
    /// Radius of the smallest sphere about the centre of mass that holds the body (m).
    pub bounding_radius: f64,
}

impl Occluder {
    /// Centre of mass at launch (world).
    pub fn launch_com(&self) -> DVec3 {
        self.position + self.orientation * self.mass.local_com
    }
}

/// A user hint: a point on an occluder that should land on a target pixel at `t`.
#[derive(Clone, Debug)]
pub struct Hint {
    pub occluder: usize,
    /// The point in the occluder's body frame (m).
    pub point: DVec3,
    /// Target position in pixel coordinates (x right, y down, pixel centres at +0.5).
    pub pixel: DVec2,
    /// Per-hint weight (multiplies the stage's hint weight).
    pub weight: f64,
}

/// One optimisation stage: which energy terms count, which occluders vary, and when
/// CMA-ES stops.
#[derive(Clone, Debug)]
pub struct Stage {
    pub name: String,
    pub weights: Weights,
    /// Indices of the occluders whose launch velocities vary (all launched ones by default).
    pub vary: Vec<usize>,
    /// Initial CMA-ES step (m/s for linear, rad/s for angular velocities).
    pub step: f64,
    pub max_iterations: usize,
    /// CMA-ES population (samples per iteration).
    pub population: usize,
    /// Stop the stage when the best total energy is at or below this.
    pub target_energy: Option<f64>,
    /// Stop when the recent best energies vary by less than this.
    pub tol_fun: f64,
    /// Stop after this many iterations without improvement.
    pub stagnation: usize,
}

/// Which strategy produced the stage list (kept for reports).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Strategy {
    Scheduled,
    Sequential { order: Vec<usize> },
}

/// A fully validated scene. Every field is resolved and in range.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The scene file this was loaded from.
    pub source: PathBuf,
    /// The target picture, one bit per pixel (true = shadow).
    pub target: Mask,
    /// The instant at which the shadow must match (s).
    pub t: f64,
    /// Simulation and animation timestep (s).
    pub dt: f64,
    pub gravity: DVec3,
    pub light: DVec3,
    pub receiver: Receiver,
    pub camera: ShadowCamera,
    pub table: Option<Table>,
    pub occluders: Vec<Occluder>,
    pub hints: Vec<Hint>,
    pub stages: Vec<Stage>,
    pub strategy: Strategy,
    pub seed: u64,
}

impl Scene {
    /// Number of optimisation variables for all occluders (6 each: v and w).
    pub fn variable_count(&self) -> usize {
        6 * self.occluders.len()
    }

    /// The initial guess: every occluder's start velocities, laid out as
    /// `[v.x, v.y, v.z, w.x, w.y, w.z]` per occluder.
    pub fn start_parameters(&self) -> Vec<f64> {
        let mut p = Vec::with_capacity(self.variable_count());
        for o in &self.occluders {
            let (v, w) = if o.launched {
                (o.start_velocity, o.start_angular_velocity)
            } else {
                (DVec3::ZERO, DVec3::ZERO)
            };
            p.extend_from_slice(&[v.x, v.y, v.z, w.x, w.y, w.z]);
        }
        p
    }

    /// Index of the occluder with this name.
    pub fn occluder_index(&self, name: &str) -> Option<usize> {
        self.occluders.iter().position(|o| o.name == name)
    }
}

/// Node names the glTF export uses for what is not an occluder; occluders may not take
/// them (checked here, so that the export cannot fail on a loaded scene).
pub const RESERVED_NAMES: [&str; 5] =
    ["receiver", "table", "light", "camera_shadow", "camera_view"];

/// Largest target image side (pixels).
pub const MAX_IMAGE_SIDE: usize = 16384;
/// Largest CMA-ES population a stage may ask for.
pub const MAX_POPULATION: usize = 100_000;

/// Default simulation timestep (s), as in the paper.
pub const DEFAULT_TIMESTEP: f64 = 1.0 / 60.0;
/// Default gravity (m/s^2), Z up.
pub const DEFAULT_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];
/// Default height (m) the start guess lifts every launched body's centre of mass by at `t`.
pub const DEFAULT_START_RISE: f64 = 1.5;

/// Load and validate a scene. `path` is the scene JSON file or a folder holding `scene.json`.
pub fn load(path: &Path) -> Result<Scene> {
    let file = if path.is_dir() {
        path.join("scene.json")
    } else {
        path.to_path_buf()
    };
    let text = std::fs::read_to_string(&file).map_err(|source| SceneError::Io {
        path: file.clone(),
        source,
    })?;
    let raw: RawScene = serde_json::from_str(&text).map_err(|e| SceneError::Json {
        path: file.clone(),
        message: e.to_string(),
    })?;
    let dir = file
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let default_name = if path.is_dir() {
        path.file_name()
    } else {
        dir.file_name()
    }
    .and_then(|s| s.to_str())
    .unwrap_or("scene")
    .to_string();
    Validator {
        file: &file,
        dir: &dir,
    }
    .scene(raw, default_name)
}

struct Validator<'a> {
    file: &'a Path,
    dir: &'a Path,
}

impl Validator<'_> {
    fn field_err(&self, field: impl Into<String>, reason: impl Into<String>) -> SceneError {
        SceneError::Field {
            path: self.file.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    fn finite(&self, field: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.field_err(field, format!("must be a finite number, got {x}")))
        }
    }

    fn positive(&self, field: &str, x: f64) -> Result<f64> {
        let x = self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.field_err(field, format!("must be positive, got {x}")))
        }
    }

    fn non_negative(&self, field: &str, x: f64) -> Result<f64> {
        let x = self.finite(field, x)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.field_err(field, format!("must not be negative, got {x}")))
        }
    }

    fn vec3(&self, field: &str, a: [f64; 3]) -> Result<DVec3> {
        for (i, x) in a.iter().enumerate() {
            self.finite(&format!("{field}[{i}]"), *x)?;
        }
        Ok(DVec3::from_array(a))
    }

    fn unit(&self, field: &str, a: [f64; 3]) -> Result<DVec3> {
        let v = self.vec3(field, a)?;
        let len = v.length();
        if len < 1e-12 {
            return Err(self.field_err(field, "must be a non-zero vector"));
        }
        Ok(v / len)
    }

    fn resolve(&self, rel: &str) -> PathBuf {
        let p = Path::new(rel);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.dir.join(p)
        }
    }

    fn scene(&self, raw: RawScene, default_name: String) -> Result<Scene> {
        let name = raw.name.clone().unwrap_or(default_name);
        if name.is_empty() || name == "." || name == ".." || name.contains(['/', '\\']) {
            return Err(self.field_err("name", "must be a non-empty name without path separators"));
        }
        let t = self.positive("t", raw.t)?;
        let dt = self.positive("timestep", raw.timestep.unwrap_or(DEFAULT_TIMESTEP))?;
        if dt > t {
            return Err(self.field_err("timestep", format!("must not exceed t = {t} s, got {dt}")));
        }
        let gravity = self.vec3("gravity", raw.gravity.unwrap_or(DEFAULT_GRAVITY))?;
        let light = self.vec3("light", raw.light)?;
        let receiver = self.receiver(&raw.receiver, light)?;
        let target = self.target(&raw.target)?;
        let camera = ShadowCamera::new(
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
        );
        let table = match &raw.table {
            None => None,
            Some(tb) => {
                let center = self.vec3("table.center", tb.center)?;
                let mut half = DVec3::ZERO;
                for i in 0..3 {
                    half[i] = self.positive(&format!("table.size[{i}]"), tb.size[i])? / 2.0;
                }
                Some(Table {
                    center,
                    half_extents: half,
                })
            }
        };
        let rise = self.finite(
            "start.rise",
            raw.start
                .as_ref()
                .and_then(|s| s.rise)
                .unwrap_or(DEFAULT_START_RISE),
        )?;
        let mut occluders = Vec::with_capacity(raw.occluders.len());
        if raw.occluders.is_empty() {
            return Err(self.field_err("occluders", "needs at least one occluder"));
        }
        for (i, ro) in raw.occluders.iter().enumerate() {
            let o = self.occluder(i, ro, t, gravity, rise)?;
            if RESERVED_NAMES.contains(&o.name.as_str()) {
                return Err(self.field_err(
                    format!("occluders[{i}].name"),
                    format!(
                        "`{}` is the name of a node of the glTF export; occluders may not use {}",
                        o.name,
                        RESERVED_NAMES.map(|n| format!("`{n}`")).join(", ")
                    ),
                ));
            }
            if occluders.iter().any(|p: &Occluder| p.name == o.name) {
                return Err(self.field_err(
                    format!("occluders[{i}].name"),
                    format!(
                        "`{}` is used by two occluders; names must be unique",
                        o.name
                    ),
                ));
            }
            occluders.push(o);
        }
        if !occluders.iter().any(|o| o.launched) {
            return Err(self.field_err(
                "occluders",
                "no occluder is launched; there is nothing to optimise",
            ));
        }
        self.check_overlaps(&occluders, table.as_ref())?;
        let hints = match &raw.hints {
            None => Vec::new(),
            Some(RawHints::Inline(list)) => list
                .iter()
                .enumerate()
                .map(|(i, h)| self.hint(&format!("hints[{i}]"), h, &occluders))
                .collect::<Result<_>>()?,
            Some(RawHints::File(rel)) => self.hints_file(&self.resolve(rel), &occluders)?,
        };
        let aim = raw
            .start
            .as_ref()
            .and_then(|s| s.aim.clone())
            .unwrap_or_else(|| "hints".to_string());
        match aim.as_str() {
            "hints" => aim_at_hints(
                &mut occluders,
                &hints,
                &raw_start_overrides(&raw),
                &camera,
                &receiver,
                t,
                gravity,
                rise,
            ),
            "up" => {}
            other => {
                return Err(self.field_err(
                    "start.aim",
                    format!("must be \"hints\" or \"up\", got \"{other}\""),
                ))
            }
        }
        let (stages, strategy) = self.stages(&raw, &occluders)?;
        Ok(Scene {
            name,
            source: self.file.to_path_buf(),
            target,
            t,
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
        })
    }

    fn receiver(&self, r: &RawReceiver, light: DVec3) -> Result<Receiver> {
        let center = self.vec3("receiver.center", r.center)?;
        let u = self.unit("receiver.u", r.u)?;
        let v = self.unit("receiver.v", r.v)?;
        if u.dot(v).abs() > 1e-6 {
            return Err(self.field_err("receiver.v", "must be perpendicular to receiver.u"));
        }
        let width = self.positive("receiver.width", r.width)?;
        let height = self.positive("receiver.height", r.height)?;
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

    fn target(&self, rel: &str) -> Result<Mask> {
        let path = self.resolve(rel);
        let bytes = std::fs::read(&path).map_err(|source| SceneError::Io {
            path: path.clone(),
            source,
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

    fn occluder(
        &self,
        i: usize,
        ro: &RawOccluder,
        t: f64,
        gravity: DVec3,
        rise: f64,
    ) -> Result<Occluder> {
        let f = |s: &str| format!("occluders[{i}].{s}");
        if ro.name.trim().is_empty() {
            return Err(self.field_err(f("name"), "must not be empty"));
        }
        let shape = match &ro.shape {
            RawShape::Sphere { radius } => Shape::Sphere {
                radius: self.positive(&f("shape.sphere.radius"), *radius)?,
            },
            RawShape::Box { size } => {
                let mut half = DVec3::ZERO;
                for k in 0..3 {
                    half[k] = self.positive(&f(&format!("shape.box.size[{k}]")), size[k])? / 2.0;
                }
                Shape::Cuboid { half_extents: half }
            }
            RawShape::Mesh { obj, scale } => {
                let scale = self.positive(&f("shape.mesh.scale"), scale.unwrap_or(1.0))?;
                let path = self.resolve(obj);
                let mesh: TriMesh =
                    shape::load_obj(&path, scale).map_err(|source| SceneError::Obj {
                        path: path.clone(),
                        field: f("shape.mesh.obj"),
                        source,
                    })?;
                Shape::Mesh(Arc::new(mesh))
            }
        };
        let position = self.vec3(&f("position"), ro.position)?;
        let orientation = match ro.orientation {
            None => DQuat::IDENTITY,
            Some(q) => {
                for (k, x) in q.iter().enumerate() {
                    self.finite(&f(&format!("orientation[{k}]")), *x)?;
                }
                let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
                if q.length() < 1e-9 {
                    return Err(self.field_err(
                        f("orientation"),
                        "must be a non-zero quaternion [x, y, z, w]",
                    ));
                }
                q.normalize()
            }
        };
        let volume = shape.volume();
        let density = match (ro.mass, ro.density) {
            (Some(m), None) => self.positive(&f("mass"), m)? / volume,
            (None, Some(d)) => self.positive(&f("density"), d)?,
            (None, None) => {
                return Err(
                    self.field_err(f("mass"), "give either `mass` (kg) or `density` (kg/m^3)")
                )
            }
            (Some(_), Some(_)) => {
                return Err(
                    self.field_err(f("density"), "give either `mass` or `density`, not both")
                )
            }
        };
        let mass = shape.mass_properties_checked(density).ok_or_else(|| {
            self.field_err(
                f("shape"),
                "is too small or too large to give a finite, positive mass and inertia",
            )
        })?;
        let launched = ro.launched.unwrap_or(true);
        // The default start guess launches straight up so that the centre of mass is
        // `rise` metres higher at t: a neutral, collision-free, in-view starting point.
        let g_up = -gravity.z;
        let default_v = DVec3::new(0.0, 0.0, (rise + 0.5 * g_up * t * t) / t);
        let start_velocity = match ro.start_velocity {
            Some(v) => self.vec3(&f("start_velocity"), v)?,
            None => default_v,
        };
        let start_angular_velocity = match ro.start_angular_velocity {
            Some(w) => self.vec3(&f("start_angular_velocity"), w)?,
            None => DVec3::ZERO,
        };
        let bounding_radius = shape.bounding_radius(mass.local_com);
        Ok(Occluder {
            name: ro.name.clone(),
            shape,
            mass,
            position,
            orientation,
            launched,
            start_velocity,
            start_angular_velocity,
            bounding_radius,
        })
    }

    fn check_overlaps(&self, occ: &[Occluder], table: Option<&Table>) -> Result<()> {
        // Tolerance for resting contact: bodies may touch (a ball on the floor) but not
        // interpenetrate by more than a tenth of a millimetre.
        const TOL: f64 = 1e-4;
        for i in 0..occ.len() {
            for j in (i + 1)..occ.len() {
                let (a, b) = (&occ[i], &occ[j]);
                let (sa, sb) = (ContactShape::new(&a.shape), ContactShape::new(&b.shape));
                let d = signed_distance(
                    &sa,
                    a.position,
                    a.orientation,
                    &sb,
                    b.position,
                    b.orientation,
                );
                if d < -TOL {
                    return Err(SceneError::Overlap {
                        path: self.file.to_path_buf(),
                        what: format!("occluders `{}` and `{}`", occ[i].name, occ[j].name),
                        depth: -d,
                    });
                }
            }
            if let Some(tb) = table {
                let o = &occ[i];
                let s = ContactShape::new(&o.shape);
                let d = table_signed_distance(&s, o.position, o.orientation, tb, &table_shape(tb));
                if d < -TOL {
                    return Err(SceneError::Overlap {
                        path: self.file.to_path_buf(),
                        what: format!("occluder `{}` and the table", occ[i].name),
                        depth: -d,
                    });
                }
            }
        }
        Ok(())
    }

    fn hint(&self, field: &str, h: &RawHint, occ: &[Occluder]) -> Result<Hint> {
        let occluder = occ
            .iter()
            .position(|o| o.name == h.occluder)
            .ok_or_else(|| {
                self.field_err(
                    format!("{field}.occluder"),
                    format!("names occluder `{}`, which does not exist", h.occluder),
                )
            })?;
        let point = self.vec3(&format!("{field}.point"), h.point)?;
        let px = self.finite(&format!("{field}.pixel[0]"), h.pixel[0])?;
        let py = self.finite(&format!("{field}.pixel[1]"), h.pixel[1])?;
        let weight = self.non_negative(&format!("{field}.weight"), h.weight.unwrap_or(1.0))?;
        Ok(Hint {
            occluder,
            point,
            pixel: DVec2::new(px, py),
            weight,
        })
    }

    /// Hints in a text file, one per line: `occluder x y z px py [weight]`; `#` starts a
    /// comment. This is the paper's "hints stored separately in a text file".
    fn hints_file(&self, path: &Path, occ: &[Occluder]) -> Result<Vec<Hint>> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut out = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let err = |reason: String| SceneError::HintLine {
                path: path.to_path_buf(),
                line: k + 1,
                reason,
            };
            let parts: Vec<&str> = line.split_whitespace().collect();
            if parts.len() != 6 && parts.len() != 7 {
                return Err(err(format!(
                    "expected `occluder x y z px py [weight]`, got {} fields",
                    parts.len()
                )));
            }
            let mut nums = [0.0f64; 6];
            for (n, s) in parts[1..].iter().enumerate() {
                let x: f64 = s
                    .parse()
                    .map_err(|_| err(format!("`{s}` is not a number")))?;
                if !x.is_finite() {
                    return Err(err(format!("`{s}` is not a finite number")));
                }
                nums[n] = x;
            }
            let raw = RawHint {
                occluder: parts[0].to_string(),
                point: [nums[0], nums[1], nums[2]],
                pixel: [nums[3], nums[4]],
                weight: if parts.len() == 7 {
                    Some(nums[5])
                } else {
                    None
                },
            };
            let h = self
                .hint(&format!("hints (line {})", k + 1), &raw, occ)
                .map_err(|e| err(e.to_string()))?;
            out.push(h);
        }
        Ok(out)
    }

    fn stage(
        &self,
        field: &str,
        rs: &RawStage,
        default_name: String,
        default_vary: &[usize],
        occ: &[Occluder],
    ) -> Result<Stage> {
        let mut w = [0.0; TERM_COUNT];
        for (key, value) in &rs.weights {
            let term = Term::from_key(key).ok_or_else(|| {
                self.field_err(
                    format!("{field}.weights.{key}"),
                    format!(
                        "unknown energy term; use one of {}",
                        Term::ALL.map(|t| t.key()).join(", ")
                    ),
                )
            })?;
            w[term as usize] = self.non_negative(&format!("{field}.weights.{key}"), *value)?;
        }
        let vary = match &rs.vary {
            None => default_vary.to_vec(),
            Some(RawVary::All(s)) if s == "all" => occ
                .iter()
                .enumerate()
                .filter(|(_, o)| o.launched)
                .map(|(i, _)| i)
                .collect(),
            Some(RawVary::All(s)) => {
                return Err(self.field_err(
                    format!("{field}.vary"),
                    format!("must be \"all\" or a list of occluder names, got \"{s}\""),
                ))
            }
            Some(RawVary::Names(names)) => {
                let mut out = Vec::new();
                for n in names {
                    let i = occ.iter().position(|o| &o.name == n).ok_or_else(|| {
                        self.field_err(
                            format!("{field}.vary"),
                            format!("names occluder `{n}`, which does not exist"),
                        )
                    })?;
                    if !occ[i].launched {
                        return Err(self.field_err(
                            format!("{field}.vary"),
                            format!("occluder `{n}` is not launched and cannot vary"),
                        ));
                    }
                    if !out.contains(&i) {
                        out.push(i);
                    }
                }
                out
            }
        };
        if vary.is_empty() {
            return Err(self.field_err(format!("{field}.vary"), "no occluder varies in this stage"));
        }
        let n = 6 * vary.len();
        let step = self.positive(&format!("{field}.step"), rs.step.unwrap_or(0.3))?;
        let max_iterations = rs.max_iterations.unwrap_or(150);
        if max_iterations == 0 {
            return Err(self.field_err(format!("{field}.max_iterations"), "must be at least 1"));
        }
        let population = rs
            .population
            .unwrap_or(4 + (3.0 * (n as f64).ln()).floor() as usize);
        if !(4..=MAX_POPULATION).contains(&population) {
            return Err(self.field_err(
                format!("{field}.population"),
                format!("must be between 4 and {MAX_POPULATION}"),
            ));
        }
        let target_energy = match rs.target_energy {
            Some(x) => Some(self.finite(&format!("{field}.target_energy"), x)?),
            None => None,
        };
        let tol_fun = self.non_negative(&format!("{field}.tol_fun"), rs.tol_fun.unwrap_or(1e-9))?;
        let stagnation = rs.stagnation.unwrap_or(60);
        if stagnation == 0 {
            return Err(self.field_err(
                format!("{field}.stagnation"),
                "must be at least 1 iteration",
            ));
        }
        Ok(Stage {
            name: rs.name.clone().unwrap_or(default_name),
            weights: Weights(w),
            vary,
            step,
            max_iterations,
            population,
            target_energy,
            tol_fun,
            stagnation,
        })
    }

    fn stages(&self, raw: &RawScene, occ: &[Occluder]) -> Result<(Vec<Stage>, Strategy)> {
        let launched: Vec<usize> = occ
            .iter()
            .enumerate()
            .filter(|(_, o)| o.launched)
            .map(|(i, _)| i)
            .collect();
        match (&raw.strategy, &raw.stages) {
            (None | Some(RawStrategy::Scheduled), Some(list)) => {
                if list.is_empty() {
                    return Err(self.field_err("stages", "needs at least one stage"));
                }
                let stages = list
                    .iter()
                    .enumerate()
                    .map(|(i, s)| self.stage(&format!("stages[{i}]"), s, format!("stage {}", i + 1), &launched, occ))
                    .collect::<Result<Vec<_>>>()?;
                Ok((stages, Strategy::Scheduled))
            }
            (None | Some(RawStrategy::Scheduled), None) => Err(self.field_err(
                "stages",
                "is required with the scheduled strategy (or give `strategy` of kind \"sequential\")",
            )),
            (Some(RawStrategy::Sequential { .. }), Some(_)) => Err(self.field_err(
                "stages",
                "the sequential strategy builds its own stages from `strategy.stage` and `strategy.final`; remove `stages`",
            )),
            (Some(RawStrategy::Sequential { order, rounds, stage, final_stage }), None) => {
                let rounds = match rounds.as_ref() {
                    None => 1,
                    Some(&r) if (1..=100).contains(&r) => r as usize,
                    Some(r) => {
                        return Err(self.field_err("strategy.rounds", format!("must be 1 to 100, got {r}")))
                    }
                };
                let order: Vec<usize> = match order {
                    None => auto_order(occ),
                    Some(RawOrder::Auto(s)) if s == "auto" => auto_order(occ),
                    Some(RawOrder::Auto(s)) => {
                        return Err(self.field_err("strategy.order", format!("must be \"auto\" or a list of occluder names, got \"{s}\"")))
                    }
                    Some(RawOrder::Names(names)) => {
                        let mut out = Vec::new();
                        for n in names {
                            let i = occ.iter().position(|o| &o.name == n).ok_or_else(|| {
                                self.field_err("strategy.order", format!("names occluder `{n}`, which does not exist"))
                            })?;
                            if !occ[i].launched {
                                return Err(self.field_err("strategy.order", format!("occluder `{n}` is not launched")));
                            }
                            if out.contains(&i) {
                                return Err(self.field_err("strategy.order", format!("occluder `{n}` is listed twice")));
                            }
                            out.push(i);
                        }
                        out
                    }
                };
                if stage.vary.is_some() {
                    return Err(self.field_err("strategy.stage.vary", "is set by the sequential strategy (one occluder per stage); remove it"));
                }
                let mut stages = Vec::new();
                for round in 1..=rounds {
                    for &i in &order {
                        // Later rounds are told apart in progress and reports.
                        let name = if round == 1 {
                            occ[i].name.clone()
                        } else {
                            format!("{} ({round})", occ[i].name)
                        };
                        let s = self.stage("strategy.stage", stage, name, &[i], occ)?;
                        stages.push(s);
                    }
                }
                if let Some(fs) = final_stage {
                    stages.push(self.stage("strategy.final", fs, "final".to_string(), &launched, occ)?);
                }
                Ok((stages, Strategy::Sequential { order }))
            }
        }
    }
}

/// Which occluders have an explicit `start_velocity` (those are never re-aimed).
fn raw_start_overrides(raw: &RawScene) -> Vec<bool> {
    raw.occluders
        .iter()
        .map(|o| o.start_velocity.is_some())
        .collect()
}

/// Aim the initial guess of every launched occluder that has hints (and no explicit
/// `start_velocity`): its centre of mass is sent to the point where its hints' light
/// rays are `rise` higher above the receiver than it starts, so the search starts with
/// the hints met, in flight and clear of the table. Launching straight up instead puts
/// the shadows far outside the picture, and the first iterations then find that
/// lowering a body shrinks its distance to the picture fastest: it lands, and a landed
/// body's shadow no longer depends on its vertical launch speed (a plateau that CMA-ES
/// cannot cross; see docs/energies.md).
#[allow(clippy::too_many_arguments)]
fn aim_at_hints(
    occ: &mut [Occluder],
    hints: &[Hint],
    explicit: &[bool],
    camera: &ShadowCamera,
    receiver: &Receiver,
    t: f64,
    gravity: DVec3,
    rise: f64,
) {
    let n = receiver.normal;
    let light_height = (camera.light - receiver.center).dot(n);
    for (i, o) in occ.iter_mut().enumerate() {
        if !o.launched || explicit[i] {
            continue;
        }
        let mine: Vec<&Hint> = hints
            .iter()
            .filter(|h| h.occluder == i && h.weight > 0.0)
            .collect();
        if mine.is_empty() {
            continue;
        }
        let wsum: f64 = mine.iter().map(|h| h.weight).sum();
        let pixel = mine.iter().map(|h| h.pixel * h.weight).sum::<DVec2>() / wsum;
        let point = mine.iter().map(|h| h.point * h.weight).sum::<DVec3>() / wsum;
        let com0 = o.launch_com();
        // Offset from the centre of mass to the (mean) hint point, in the launch orientation.
        let offset = o.orientation * (point - o.mass.local_com);
        let on_plane = camera.pixel_to_world(pixel.x, pixel.y);
        // Height of the hint point above the receiver at t: the start height plus `rise`,
        // kept strictly between the receiver and the light.
        let h0 = (com0 + offset - receiver.center).dot(n);
        let h = (h0 + rise).clamp(0.05 * light_height, 0.9 * light_height);
        // The point on the ray light -> on_plane at height h: X + s (L - X) with s = h / H.
        let s = h / light_height;
        let hint_at_t = on_plane + s * (camera.light - on_plane);
        let com_t = hint_at_t - offset;
        let v = (com_t - com0 - 0.5 * gravity * t * t) / t;
        // Absurd hint values can overflow; keep the straight-up start then.
        if v.is_finite() {
            o.start_velocity = v;
        }
    }
}

/// The automatic sequential order: largest occluders first, since they fix most of the
/// picture and the small ones then fill in details around them. Ties keep file order.
fn auto_order(occ: &[Occluder]) -> Vec<usize> {
    let mut idx: Vec<usize> = occ
        .iter()
        .enumerate()
        .filter(|(_, o)| o.launched)
        .map(|(i, _)| i)
        .collect();
    idx.sort_by(|&a, &b| {
        occ[b]
            .shape
            .volume()
            .total_cmp(&occ[a].shape.volume())
            .then(a.cmp(&b))
    });
    idx
}
