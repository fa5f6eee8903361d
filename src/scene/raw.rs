//! The scene file as serde reads it. Unknown fields are rejected everywhere so that a
//! misspelt option is an error instead of being silently ignored; [`super::validate`]
//! turns these into the validated types.

use std::collections::HashMap;

use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) name: Option<String>,
    pub(super) target: Option<String>,
    pub(super) t: Option<f64>,
    /// Several pictures at several instants (replaces `target` and `t`).
    pub(super) targets: Option<Vec<RawPicture>>,
    /// A window around every picture's instant over which the picture must hold.
    pub(super) hold: Option<RawHold>,
    /// `"fixed"` (default) or `"free"`: launch positions as optimisation variables.
    pub(super) positions: Option<String>,
    pub(super) timestep: Option<f64>,
    pub(super) gravity: Option<[f64; 3]>,
    pub(super) light: [f64; 3],
    pub(super) receiver: RawReceiver,
    pub(super) table: Option<RawTable>,
    pub(super) occluders: Vec<RawOccluder>,
    #[serde(default)]
    pub(super) hints: Option<RawHints>,
    pub(super) start: Option<RawStart>,
    pub(super) stages: Option<Vec<RawStage>>,
    pub(super) strategy: Option<RawStrategy>,
    pub(super) seed: Option<u64>,
    pub(super) contacts: Option<String>,
    /// The launcher's 1-sigma errors; a field left out keeps its default.
    pub(super) launcher: Option<super::launcher::Tolerances>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawReceiver {
    pub(super) center: [f64; 3],
    pub(super) u: [f64; 3],
    pub(super) v: [f64; 3],
    pub(super) width: f64,
    pub(super) height: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTable {
    pub(super) center: [f64; 3],
    pub(super) size: [f64; 3],
}

/// A shape: an object with exactly one of `sphere`, `box` and `mesh` (read by
/// [`one_shape`]: serde's message for two of them names neither).
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub(super) enum RawShape {
    Sphere { radius: f64 },
    Box { size: [f64; 3] },
    Mesh { obj: String, scale: Option<f64> },
}

/// [`RawShape`], with an object of two kinds refused by name and an error inside the
/// one kind named by its path (`sphere.radius`).
fn one_shape<'de, D: serde::Deserializer<'de>>(d: D) -> Result<RawShape, D::Error> {
    use serde::de::Error;
    let value = serde_json::Value::deserialize(d)?;
    if let Some(map) = value.as_object().filter(|m| m.len() > 1) {
        let keys: Vec<&str> = map.keys().map(String::as_str).collect();
        return Err(D::Error::custom(format!(
            "give one of `sphere`, `box` and `mesh`, got {}",
            keys.join(" and ")
        )));
    }
    serde_path_to_error::deserialize(value).map_err(|e| D::Error::custom(at_path(e)))
}

/// A serde error led by the path of the value at fault (`hints[0].pixel: ...`), or alone
/// at the top level: serde's own errors give a line and column, and for an untagged or
/// tagged enum only say that nothing matched.
pub fn at_path<E: std::fmt::Display>(e: serde_path_to_error::Error<E>) -> String {
    let at = e.path().to_string();
    let message = e.into_inner().to_string();
    if at == "." {
        message
    } else {
        format!("`{at}`: {message}")
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOccluder {
    pub(super) name: String,
    #[serde(deserialize_with = "one_shape")]
    pub(super) shape: RawShape,
    pub(super) position: [f64; 3],
    pub(super) orientation: Option<[f64; 4]>,
    pub(super) mass: Option<f64>,
    pub(super) density: Option<f64>,
    pub(super) launched: Option<bool>,
    pub(super) start_velocity: Option<[f64; 3]>,
    pub(super) start_angular_velocity: Option<[f64; 3]>,
}

/// Hints: a file name, or a list of hints. Read through a JSON value so that a wrong
/// hint's error names its index and field (serde's untagged enums only say that no
/// variant matched).
#[derive(Deserialize)]
#[serde(try_from = "serde_json::Value")]
pub(super) enum RawHints {
    File(String),
    Inline(Vec<RawHint>),
}

/// Why a `hints` value is not hints (serde puts the message into the scene's JSON error,
/// which names the field).
#[derive(Debug, thiserror::Error)]
pub(super) enum HintsError {
    /// A hint of the list is malformed: its index, then the path and serde's message.
    #[error("hint [{index}], {message}")]
    Hint { index: usize, message: String },
    /// Neither a file name nor a list.
    #[error("must be a file name or a list of hints ({{\"occluder\", \"point\": [x, y, z], \"pixel\": [x, y], \"weight\"}}), got {got}")]
    Kind { got: serde_json::Value },
}

impl TryFrom<serde_json::Value> for RawHints {
    type Error = HintsError;

    fn try_from(value: serde_json::Value) -> Result<Self, HintsError> {
        match value {
            serde_json::Value::String(file) => Ok(RawHints::File(file)),
            serde_json::Value::Array(items) => items
                .into_iter()
                .enumerate()
                .map(|(index, item)| {
                    serde_path_to_error::deserialize(item).map_err(|e| HintsError::Hint {
                        index,
                        message: at_path(e),
                    })
                })
                .collect::<Result<_, _>>()
                .map(RawHints::Inline),
            got => Err(HintsError::Kind { got }),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHint {
    pub(super) occluder: String,
    pub(super) point: [f64; 3],
    pub(super) pixel: [f64; 2],
    pub(super) weight: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStart {
    pub(super) rise: Option<f64>,
    pub(super) aim: Option<String>,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStage {
    pub(super) name: Option<String>,
    pub(super) weights: Option<HashMap<String, f64>>,
    pub(super) vary: Option<RawVary>,
    pub(super) step: Option<f64>,
    pub(super) max_iterations: Option<usize>,
    pub(super) population: Option<usize>,
    pub(super) target_energy: Option<f64>,
    pub(super) tol_fun: Option<f64>,
    pub(super) stagnation: Option<usize>,
    pub(super) restarts: Option<usize>,
    pub(super) restart_iou: Option<f64>,
    pub(super) restart_gain: Option<f64>,
    pub(super) objective: Option<String>,
}

#[derive(Deserialize, Clone)]
#[serde(untagged)]
pub(super) enum RawVary {
    All(String),
    Names(Vec<String>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum RawStrategy {
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
pub(super) enum RawOrder {
    Auto(String),
    Names(Vec<String>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPicture {
    pub(super) target: Option<String>,
    pub(super) t: Option<f64>,
    pub(super) weight: Option<f64>,
    pub(super) hints: Option<RawHints>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHold {
    pub(super) window: f64,
    pub(super) instants: Option<usize>,
    pub(super) fps: Option<f64>,
    pub(super) objective: Option<String>,
}
