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

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec2, DVec3};

use crate::energy::Weights;
pub use crate::geometry::shape::Table;
use crate::geometry::shape::{self, MassProperties, Shape};
use crate::shadow::mask::Mask;
use crate::shadow::raster::ShadowCamera;

/// "does not exist", or "cannot be read: <the system's reason>".
fn unreadable(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "does not exist".to_string(),
        _ => format!("cannot be read: {e}"),
    }
}

/// A number as people write limits: plain from 1e-4 up to 1e5 (3600, 0.5), in exponent
/// form beyond (1e6, 1e300, 1e-300), which `{}` would print as three hundred digits.
pub fn short(x: f64) -> String {
    if x == 0.0 || (1e-4..1e5).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

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
    /// A file that a field of the scene names could not be read: both files are named,
    /// and whether the named one is missing or unreadable (with the system's reason).
    #[error("{path}: field `{field}` names {}, which {}", .named.display(), unreadable(.error))]
    Named {
        path: PathBuf,
        field: String,
        named: PathBuf,
        error: std::io::Error,
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
    /// The reason is in the message's first line (not a cause below it), so that the
    /// file, the field and the reason are read together.
    #[error("{path}: field `{field}`: {error}")]
    Obj {
        path: PathBuf,
        field: String,
        error: shape::ObjError,
    },
    /// A launched occluder is thicker, where it is thinnest, than the light is far from
    /// the receiver: it can never pass whole between them.
    #[error("{path}: field `light`: the light is {room:.4} m in front of the receiver, but occluders[{index}] (`{name}`) is {width:.4} m thick where it is thinnest, so it can never pass whole between the light and the receiver; move the light farther from the receiver (or check the units: metres)")]
    NoRoomUnderLight {
        path: PathBuf,
        index: usize,
        name: String,
        room: f64,
        width: f64,
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

mod bounds;
mod launch;
pub mod launcher;
mod pictures;
mod raw;
mod start;
mod validate;

pub use launch::{velocity_reaching, Launch};
pub use raw::at_path;
use raw::RawScene;
pub use start::auto_order;
pub use validate::too_fast_spin;
use validate::Validator;

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
    /// Restarts (IPOP: from the best so far, with the initial step, twice the previous
    /// population and half its iteration cap, so that every run of the stage draws about
    /// as many samples as the first) allowed when the stage stops with its picture below
    /// `restart_iou`, after a run that raised the picture's IoU by `restart_gain`.
    pub restarts: usize,
    /// IoU at `t` from which a stage no longer restarts (0 to 1).
    pub restart_iou: f64,
    /// IoU a run must have gained for the stage to restart after it (0 to 1); a run that
    /// started with a contact of the stage's own need only have ranked better.
    pub restart_gain: f64,
    /// How a hold window's instants add up in this stage (default: `hold.objective`).
    pub objective: Option<HoldObjective>,
}

/// Which strategy produced the stage list (kept for reports).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Strategy {
    Scheduled,
    Sequential { order: Vec<usize> },
}

/// One picture of the scene: a target and the instant the shadows must form it at.
#[derive(Clone, Debug)]
pub struct Picture {
    /// The target picture, one bit per pixel (true = shadow).
    pub target: Mask,
    /// The target's file (for reports).
    pub file: PathBuf,
    /// The instant (s).
    pub t: f64,
    /// Its share of the image energy: the pictures' weights sum to 1.
    pub weight: f64,
    /// The hints aimed at this picture.
    pub hints: Vec<Hint>,
}

/// A picture that must hold over a window of time around its instant, not only at it.
#[derive(Clone, Debug, PartialEq)]
pub struct Hold {
    /// Half-width of the window (s): the picture at `t` must hold from `t - window` to
    /// `t + window`.
    pub window: f64,
    /// How many evenly spaced instants of the window the optimiser evaluates (ends
    /// included); `None`: every frame at `fps`.
    pub instants: Option<usize>,
    /// Frames per second of the window's frames (the reports give the IoU at every one).
    pub fps: f64,
    /// How the instants of a window add up to the picture's image energy.
    pub objective: HoldObjective,
}

/// How the instants of a hold window add up to the picture's image energy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HoldObjective {
    /// Their mean: the weighted sum with equal weights.
    Mean,
    /// The worst instant's: the picture must hold at every frame, the ends of the
    /// window included (the mean favours the middle).
    Worst,
}

impl Hold {
    /// The frames of the window as offsets from the picture's instant (s): `k / fps` for
    /// every integer `k` with `|k / fps| <= window`, in order (0 among them).
    pub fn frame_offsets(&self) -> Vec<f64> {
        let k = (self.window * self.fps + 1e-9).floor() as i64;
        (-k..=k).map(|i| i as f64 / self.fps).collect()
    }

    /// The offsets (s) from the picture's instant that the optimiser evaluates: the
    /// frames, or `instants` evenly spaced from `-window` to `window`.
    pub fn offsets(&self) -> Vec<f64> {
        match self.instants {
            None => self.frame_offsets(),
            Some(n) => (0..n)
                .map(|i| self.window * (2.0 * i as f64 / (n - 1) as f64 - 1.0))
                .collect(),
        }
    }
}

/// Where the launched bodies start from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaunchPositions {
    /// From their positions in the scene file.
    Fixed,
    /// Their positions on the table (x and y; height and orientation kept) are
    /// optimised with their launch, bounded to the table's top and contact-free at
    /// launch.
    Free,
}

/// A fully validated scene. Every field is resolved and in range.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The scene file this was loaded from.
    pub source: PathBuf,
    /// The target picture, one bit per pixel (true = shadow): the last picture's.
    pub target: Mask,
    /// The instant at which the shadow must match (s): the last picture's. The solver's
    /// model runs to it (to the end of its hold window with `hold`).
    pub t: f64,
    /// Every picture, by instant (one in the single-target form).
    pub pictures: Vec<Picture>,
    /// The window over which each picture must hold, if any.
    pub hold: Option<Hold>,
    /// Fixed (the default) or free launch positions.
    pub positions: LaunchPositions,
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
    /// How the optimizer treats a contact before `t`.
    pub contacts: Contacts,
    /// The launcher the scene is made for (its `"launcher"`, else the defaults).
    pub launcher: launcher::Tolerances,
}

/// How the optimizer treats a sample with a contact before `t` (a landing included).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contacts {
    /// A constraint: a sample with a contact never ranks above one without, and among
    /// samples with contacts less contact time (`(t - t_sim) n`) ranks first; the
    /// contact weight does not matter.
    Constraint,
    /// The paper's weighted penalty: the contact term is one more term of the energy.
    /// The default, for now: on the four examples the constraint gives a slightly lower
    /// median IoU (docs/results.md).
    Penalty,
}

impl Scene {
    /// Number of optimisation variables for all occluders (6 each: v and w).
    pub fn variable_count(&self) -> usize {
        Launch::LEN * self.occluders.len()
    }

    /// The initial guess: every occluder's start velocities, laid out as
    /// `[v.x, v.y, v.z, w.x, w.y, w.z]` per occluder.
    pub fn start_parameters(&self) -> Vec<f64> {
        let mut p = Vec::with_capacity(self.variable_count());
        for o in &self.occluders {
            let launch = if o.launched {
                Launch {
                    velocity: o.start_velocity,
                    angular_velocity: o.start_angular_velocity,
                }
            } else {
                Launch::default()
            };
            p.extend_from_slice(&launch.to_array());
        }
        p
    }

    /// Index of the occluder with this name.
    pub fn occluder_index(&self, name: &str) -> Option<usize> {
        self.occluders.iter().position(|o| o.name == name)
    }

    /// The last instant the solver's model runs to: `t`, or the end of the last
    /// picture's hold window.
    pub fn horizon(&self) -> f64 {
        self.t + self.hold.as_ref().map_or(0.0, |h| h.window)
    }

    /// Why occluder `i`'s launch is beyond the limits of the scene files, as the field
    /// at fault (`velocity` or `angular_velocity`) and the reason: a speed above
    /// [`MAX_SPEED`], or a spin that turns a launched body more than [`MAX_TURN`] by the
    /// horizon (the solver's model does not fly it, and its shadow would be missing).
    pub fn launch_beyond_limits(
        &self,
        i: usize,
        launch: &Launch,
    ) -> Option<(&'static str, String)> {
        if !self.occluders[i].launched {
            return None;
        }
        // The length, or the largest component where the length overflows (1e300).
        let size = |v: DVec3| {
            Some(v.length())
                .filter(|l| l.is_finite())
                .unwrap_or(v.abs().max_element())
        };
        let (speed, spin) = (size(launch.velocity), size(launch.angular_velocity));
        if speed.is_nan() || speed > MAX_SPEED {
            return Some((
                "velocity",
                format!("has magnitude {speed:e} m/s, more than the {MAX_SPEED:e} allowed"),
            ));
        }
        if spin.is_nan() || spin * self.horizon() > MAX_TURN {
            return Some(("angular_velocity", too_fast_spin(spin, self.horizon())));
        }
        None
    }

    /// Whether the scene asks for one shadow at `t` only (one picture, no hold).
    pub fn single_instant(&self) -> bool {
        self.pictures.len() == 1 && self.hold.is_none()
    }
}

/// Node names the glTF export uses for what is not an occluder; occluders may not take
/// them (checked here, so that the export cannot fail on a loaded scene).
pub const RESERVED_NAMES: [&str; 5] =
    ["receiver", "table", "light", "camera_shadow", "camera_view"];

/// Largest target image side (pixels).
pub const MAX_IMAGE_SIDE: usize = 16384;
/// Largest CMA-ES population a stage may ask for: more gains CMA-ES nothing on the few
/// hundred parameters a scene has, and every sample is a row of `convergence.csv`.
pub const MAX_POPULATION: usize = 10_000;

/// Largest magnitude (m) of any coordinate or length in a scene: positions, the light,
/// the receiver, the table, hint points, shape sizes and mesh vertices after scaling.
/// Products of these (squared distances, volumes, moments of inertia) then stay far
/// from overflow, and no real launch needs more than a thousand kilometres.
pub const MAX_COORDINATE: f64 = 1e6;
/// Longest flight time `t` (s), and longest hold window: a minute. (A launch that
/// reaches its picture after a minute has risen 4.4 km, at 300 m/s; a longer one needs
/// more than [`MAX_SPEED`] or never comes down in the solver's model.)
pub const MAX_T: f64 = 60.0;
/// Shortest flight time `t` (s): a hundredth of a second, a frame of a fast camera.
pub const MIN_T: f64 = 0.01;
/// Most timesteps (keys) from launch to `t`, `t / timestep`; the trajectory, the
/// animated export and the continuation store one pose per key and body.
pub const MAX_KEYS: f64 = 1_000_000.0;
/// Largest gravity magnitude (m/s^2), a hundred times the Earth's.
pub const MAX_GRAVITY: f64 = 1000.0;
/// Largest start speed (m/s) and start angular speed (rad/s) of any occluder, and
/// largest launch speed of a launch file.
pub const MAX_SPEED: f64 = 1e4;
/// Largest total rotation (rad) of a launched body by the horizon (`t`, or the end of
/// the hold window) that a launch may ask for (over 300 turns): no real launch does, and
/// the asymmetric-body integrator's step grid grows with the turn. The solver treats a
/// sample beyond it as diverged; a start guess or a launch file beyond it is refused.
pub const MAX_TURN: f64 = 2000.0;
/// Largest input file (bytes) read whole: a scene, a target picture, a launch file.
/// (OBJ files have their own limit, [`MAX_OBJ_BYTES`].) A larger file, or an endless one
/// such as a device, is refused instead of filling the memory.
pub const MAX_INPUT_BYTES: u64 = 256 * 1024 * 1024;
/// Largest mass (kg) and density (kg/m^3) of an occluder.
pub const MAX_MASS: f64 = 1e9;
/// Largest hint pixel coordinate magnitude and largest weight of any term or hint.
pub const MAX_PIXEL: f64 = 1e6;
/// Largest weight of an energy term or a hint.
pub const MAX_WEIGHT: f64 = 1e12;
/// Largest CMA-ES step size of a stage (in the optimizer's scaled units).
pub const MAX_STEP: f64 = 1e3;
/// Most occluders a scene may hold. The solver keeps per-pair contact data (pairs grow
/// as the square of the count); a solve of 1000 small spheres was measured at 0.8 GB
/// (10,000 asked for 28.8 GB and aborted).
pub const MAX_OCCLUDERS: usize = 1000;
/// Most CMA-ES iterations of a stage, and the largest stagnation window.
pub const MAX_ITERATIONS: usize = 1_000_000;
/// Largest stagnation window (iterations) of a stage; the solver keeps a history this
/// long.
pub const MAX_STAGNATION: usize = 100_000;
/// Restarts a stage may make when its file does not say (see [`Stage::restarts`]).
pub const DEFAULT_RESTARTS: usize = 2;
/// Most restarts of one stage: the population doubles at each, so 10 is a thousand
/// times the first population.
pub const MAX_RESTARTS: usize = 10;
/// IoU from which a stage no longer restarts when its file does not say.
pub const DEFAULT_RESTART_IOU: f64 = 0.995;
/// IoU a run must gain for its stage to restart, when the file does not say: a run that
/// left the picture as it was (by a thousandth of its IoU) has settled where a wider run
/// from the same best rarely finds more.
pub const DEFAULT_RESTART_GAIN: f64 = 0.001;
/// Most stages a scene may expand to (scheduled list, or rounds times the order).
pub const MAX_STAGES: usize = 10_000;
/// Most pictures of a scene (`targets`).
pub const MAX_PICTURES: usize = 100;
/// Most instants the optimiser evaluates per sample (pictures times hold instants).
pub const MAX_INSTANTS: usize = 1000;

/// Most triangles of one OBJ mesh after triangulation; larger meshes are refused with a
/// clear error (decimate them first), which keeps loading and hull building to seconds.
pub const MAX_MESH_TRIANGLES: usize = 200_000;
/// Largest OBJ file (bytes) read at all; larger files are refused before parsing.
pub const MAX_OBJ_BYTES: u64 = 200 * 1024 * 1024;

/// Default simulation timestep (s), as in the paper.
pub const DEFAULT_TIMESTEP: f64 = 1.0 / 60.0;
/// Default gravity (m/s^2), Z up.
pub const DEFAULT_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];
/// Default height (m) the start guess lifts every launched body's centre of mass by at `t`.
pub const DEFAULT_START_RISE: f64 = 1.5;

/// The bytes of an input file, at most [`MAX_INPUT_BYTES`] of them: a longer file (or
/// an endless one, a device) is an `InvalidData` error that says so.
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("longer than the {} MiB read at most", MAX_INPUT_BYTES >> 20),
        ));
    }
    Ok(bytes)
}

/// [`read_input`] as UTF-8 text.
pub fn read_input_text(path: &Path) -> std::io::Result<String> {
    String::from_utf8(read_input(path)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

/// What a path names, for a check made before the file is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// A file (or anything else that is not a folder).
    File,
    /// A folder.
    Folder,
}

/// What `path` names, or why it cannot be looked at (the OS reason): the look the object
/// lists of `bsa new` and `bsa plant` take at their mesh files, passed to
/// [`crate::design::inventory::parse`] by the command line, so that `design` itself
/// touches no file.
pub fn path_kind(path: &Path) -> std::io::Result<PathKind> {
    Ok(if std::fs::metadata(path)?.is_dir() {
        PathKind::Folder
    } else {
        PathKind::File
    })
}

/// Load and validate a scene. `path` is the scene JSON file or a folder holding `scene.json`.
pub fn load(path: &Path) -> Result<Scene> {
    let file = if path.is_dir() {
        path.join("scene.json")
    } else {
        path.to_path_buf()
    };
    let text = read_input_text(&file).map_err(|source| SceneError::Io {
        path: file.clone(),
        source,
    })?;
    let raw: RawScene = serde_path_to_error::deserialize(&mut serde_json::Deserializer::from_str(
        &text,
    ))
    .map_err(|e| SceneError::Json {
        path: file.clone(),
        message: raw::at_path(e),
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
