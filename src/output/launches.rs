//! Launch values from the files people hold: a solve's `solution.json`, the builders'
//! `launch.csv`, or a minimal launch file (occluder name -> velocity and angular
//! velocity). [`read_launches`] turns any of them into the solver's parameter vector
//! (six values per occluder, [`crate::scene::Launch`]) once, checked against the scene;
//! its [`LaunchFileError`]s name the file and the row or field at fault.
//!
//! The minimal launch file is JSON:
//!
//! ```text
//! { "head": { "velocity": [0.0, 1.5, 6.35], "angular_velocity": [0.2, 0.5, 0.2] },
//!   "left_ear": { "velocity": [1.46, -0.39, 7.06] } }
//! ```
//!
//! in m/s and rad/s, world frame; `angular_velocity` defaults to zero. Every launched
//! occluder needs an entry; occluders that are not launched stay put and need none.
//!
//! A solve with free launch positions moved its bodies: a `solution.json` carries their
//! positions exactly, a `launch.csv` to the micrometre (its centre-of-mass columns);
//! [`read_launches`] moves the scene's bodies there. A `solution.json` of a solve with air
//! in the loop also carries its air.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Deserialize;

use crate::output::solution::{check_solution, MismatchError, Solution};
use crate::scene::{Launch, LaunchPositions, Scene};
use crate::sim::drag::DragConfig;

/// What a launch file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Launches {
    /// Six values per occluder ([`Launch`]).
    pub params: Vec<f64>,
    /// The air the launch is meant for (a `solution.json` of `bsa solve --air`).
    pub air: Option<DragConfig>,
}

/// A launch table's centre of mass farther than this (m) from the scene's moves the body:
/// the table keeps positions to the micrometre.
const MOVED: f64 = 2e-6;

/// Why a launch file cannot be used for a scene.
#[derive(Debug, thiserror::Error)]
pub enum LaunchFileError {
    /// The file cannot be read.
    #[error("cannot read {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is neither a solution, a minimal launch file nor a launch table.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    /// A launch table lacks a column.
    #[error("{path}: no column `{column}` (a launch.csv from `bsa solve` or `bsa export` has it)")]
    Column { path: PathBuf, column: &'static str },
    /// An entry names no occluder of the scene.
    #[error("{path}: {place}: the scene has no occluder `{name}`")]
    Unknown {
        path: PathBuf,
        place: String,
        name: String,
    },
    /// An entry names an occluder that the scene does not launch.
    #[error("{path}: {place}: occluder `{name}` is not launched in the scene (it stays put)")]
    NotLaunched {
        path: PathBuf,
        place: String,
        name: String,
    },
    /// Two entries name the same occluder.
    #[error("{path}: {place}: occluder `{name}` is given twice")]
    Duplicate {
        path: PathBuf,
        place: String,
        name: String,
    },
    /// A launched occluder has no entry.
    #[error("{path}: no launch for occluder `{name}`")]
    Missing { path: PathBuf, name: String },
    /// A value is not a finite number.
    #[error("{path}: {place}: `{field}` must be a finite number, got {value}")]
    NotFinite {
        path: PathBuf,
        place: String,
        field: String,
        value: String,
    },
    /// A launch beyond the limits of the scene files
    /// ([`Scene::launch_beyond_limits`]): too fast, or spinning its body too many turns.
    #[error("{path}: {place}: `{field}` {message}")]
    TooFast {
        path: PathBuf,
        place: String,
        field: &'static str,
        message: String,
    },
    /// A `solution.json` made for another scene.
    #[error("{path} cannot be used with this scene")]
    Mismatch {
        path: PathBuf,
        #[source]
        source: MismatchError,
    },
}

type Result<T> = std::result::Result<T, LaunchFileError>;

/// One entry of a minimal launch file.
#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "an entry {\"velocity\": [x, y, z], \"angular_velocity\": [x, y, z]}"
)]
struct Entry {
    velocity: [f64; 3],
    #[serde(default)]
    angular_velocity: [f64; 3],
}

/// The launch values in `path` for `scene`: a `.csv` file is read as a launch table, a
/// JSON file as a `solution.json` (checked with [`check_solution`]) when it has the
/// solution's fields, else as a minimal launch file. The scene's bodies are moved to the
/// file's launch positions where it gives others (free positions).
pub fn read_launches(path: &Path, scene: &mut Scene) -> Result<Launches> {
    let text = crate::scene::read_input_text(path).map_err(|source| LaunchFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let format = |message: String| LaunchFileError::Format {
        path: path.to_path_buf(),
        message,
    };
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    {
        let params = from_table(path, &text, scene)?;
        return Ok(Launches { params, air: None });
    }
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format(format!("not JSON: {e}")))?;
    if value.get("occluders").is_some_and(|o| o.is_array()) && value.get("scene").is_some() {
        let solution: Solution = serde_json::from_value(value)
            .map_err(|e| format(format!("not a readable solution.json: {e}")))?;
        check_solution(scene, &solution).map_err(|source| LaunchFileError::Mismatch {
            path: path.to_path_buf(),
            source,
        })?;
        solution.place(scene);
        return Ok(Launches {
            params: solution.parameters(),
            air: solution.air,
        });
    }
    let entries: HashMap<String, Entry> = serde_path_to_error::deserialize(value).map_err(|e| {
        format(format!(
            "neither a solution.json nor a launch file ({{\"<occluder>\": {{\"velocity\": [x, y, z], \"angular_velocity\": [x, y, z]}}}}): {}",
            crate::scene::at_path(e)
        ))
    })?;
    let mut launches = Vec::new();
    let mut names: Vec<&String> = entries.keys().collect();
    names.sort();
    for name in names {
        let e = &entries[name];
        launches.push((
            name.clone(),
            format!("`{name}`"),
            e.velocity,
            e.angular_velocity,
        ));
    }
    let params = assemble(path, scene, launches)?;
    Ok(Launches { params, air: None })
}

/// The rows of a launch table: `name`, `vx_m_s`.. `vz_m_s`, `wx_rad_s`.. `wz_rad_s`, and
/// where given the centre of mass at launch (`com_x_m`.. `com_z_m`).
fn from_table(path: &Path, text: &str, scene: &mut Scene) -> Result<Vec<f64>> {
    let format = |message: String| LaunchFileError::Format {
        path: path.to_path_buf(),
        message,
    };
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| format(format!("not a CSV table: {e}")))?
        .clone();
    const COLUMNS: [&str; 7] = [
        "name", "vx_m_s", "vy_m_s", "vz_m_s", "wx_rad_s", "wy_rad_s", "wz_rad_s",
    ];
    let mut at = [0usize; 7];
    for (k, column) in COLUMNS.iter().enumerate() {
        at[k] = headers
            .iter()
            .position(|h| h == *column)
            .ok_or(LaunchFileError::Column {
                path: path.to_path_buf(),
                column,
            })?;
    }
    let com_at: Option<Vec<usize>> = ["com_x_m", "com_y_m", "com_z_m"]
        .iter()
        .map(|c| headers.iter().position(|h| h == *c))
        .collect();
    let mut launches = Vec::new();
    for (r, row) in reader.records().enumerate() {
        let place = format!("row {}", r + 2);
        let row = row.map_err(|e| format(format!("{place}: {e}")))?;
        let name = row.get(at[0]).unwrap_or("").to_string();
        if let (Some(cols), Some(i)) = (&com_at, scene.occluder_index(&name)) {
            let com: Option<Vec<f64>> = cols
                .iter()
                .map(|&c| row.get(c).and_then(|f| f.trim().parse::<f64>().ok()))
                .collect();
            if let Some(c) = com.filter(|c| c.iter().all(|x| x.is_finite())) {
                let o = &mut scene.occluders[i];
                let c = DVec3::from_array([c[0], c[1], c[2]]);
                if o.launched && c.distance(o.launch_com()) > MOVED {
                    o.position = c - o.orientation * o.mass.local_com;
                    scene.positions = LaunchPositions::Fixed;
                }
            }
        }
        let mut x = [0.0; 6];
        for k in 0..6 {
            let field = row.get(at[k + 1]).unwrap_or("");
            x[k] = field
                .trim()
                .parse::<f64>()
                .map_err(|_| LaunchFileError::NotFinite {
                    path: path.to_path_buf(),
                    place: place.clone(),
                    field: COLUMNS[k + 1].to_string(),
                    value: format!("`{field}`"),
                })?;
        }
        launches.push((name, place, [x[0], x[1], x[2]], [x[3], x[4], x[5]]));
    }
    // A table lists every occluder; those that stay put carry zeros and are skipped.
    launches.retain(|(name, ..)| {
        scene
            .occluder_index(name)
            .is_none_or(|i| scene.occluders[i].launched)
    });
    assemble(path, scene, launches)
}

/// The parameter vector from (occluder name, where it was given, v, w) entries.
fn assemble(
    path: &Path,
    scene: &Scene,
    launches: Vec<(String, String, [f64; 3], [f64; 3])>,
) -> Result<Vec<f64>> {
    let mut params = vec![0.0; scene.variable_count()];
    let mut given = vec![false; scene.occluders.len()];
    for (name, place, v, w) in launches {
        let Some(i) = scene.occluder_index(&name) else {
            return Err(LaunchFileError::Unknown {
                path: path.to_path_buf(),
                place,
                name,
            });
        };
        if !scene.occluders[i].launched {
            return Err(LaunchFileError::NotLaunched {
                path: path.to_path_buf(),
                place,
                name,
            });
        }
        if given[i] {
            return Err(LaunchFileError::Duplicate {
                path: path.to_path_buf(),
                place,
                name,
            });
        }
        for (field, value) in ["velocity", "angular_velocity"].iter().zip([v, w]) {
            if let Some(x) = value.iter().find(|x| !x.is_finite()) {
                return Err(LaunchFileError::NotFinite {
                    path: path.to_path_buf(),
                    place,
                    field: field.to_string(),
                    value: x.to_string(),
                });
            }
        }
        given[i] = true;
        Launch {
            velocity: DVec3::from_array(v),
            angular_velocity: DVec3::from_array(w),
        }
        .set(&mut params, i);
        if let Some((field, message)) = scene.launch_beyond_limits(i, &Launch::get(&params, i)) {
            return Err(LaunchFileError::TooFast {
                path: path.to_path_buf(),
                place,
                field,
                message,
            });
        }
    }
    if let Some(o) = scene
        .occluders
        .iter()
        .zip(&given)
        .find(|(o, g)| o.launched && !**g)
    {
        return Err(LaunchFileError::Missing {
            path: path.to_path_buf(),
            name: o.0.name.clone(),
        });
    }
    Ok(params)
}
