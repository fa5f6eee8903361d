//! The result files' schema: what `solution.json` and `convergence.csv` hold, and the
//! check that a saved solution belongs to a scene.
//!
//! Main types: [`Solution`] (the whole `solution.json`: per occluder an
//! [`OccluderLaunch`], every term as a [`TermValue`], one [`StageReport`] per stage),
//! [`SampleRecord`] (one row of `convergence.csv`) and [`MismatchError`]. The solver
//! produces these values; `export` writes and reads them; `eval`, `export`, `validate`,
//! `video`, `budget` and `--resume` check a loaded one with [`check_solution`] (or
//! [`check_resumable`]) before using it.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::energy::TERM_COUNT;
use crate::scene::{Launch, Scene};
use crate::sim::drag::DragConfig;
use crate::sim::launch_error::Tolerances;

/// One evaluated sample: a row of `convergence.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleRecord {
    pub stage: usize,
    pub iteration: usize,
    /// Weighted value of each term, in [`crate::energy::Term::ALL`] order.
    pub terms: [f64; TERM_COUNT],
    pub total: f64,
}

/// Launch of one occluder, as `solution.json` holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OccluderLaunch {
    pub name: String,
    pub launched: bool,
    /// Centre-of-mass launch velocity (m/s, world). The key carries the unit; files
    /// written before it did are still read.
    #[serde(rename = "velocity_m_s", alias = "velocity")]
    pub velocity: [f64; 3],
    /// Launch angular velocity (rad/s, world).
    #[serde(rename = "angular_velocity_rad_s", alias = "angular_velocity")]
    pub angular_velocity: [f64; 3],
    /// Body origin at launch (m, world), when a solve with free positions moved it from
    /// the scene's; every command that reads the solution launches it from there.
    #[serde(
        rename = "launch_position_m",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub position: Option<[f64; 3]>,
}

/// The IoU at one frame (a picture's instant, or a frame of its hold window).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    pub t_s: f64,
    /// Index of the picture (0 for the first).
    pub picture: usize,
    pub iou: f64,
}

/// The launch errors a robust solve optimised under.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustRecord {
    pub tolerances: Tolerances,
    /// Perturbed launches per sample.
    pub draws: usize,
    /// The quantile of the image energy optimised; none: its mean.
    pub quantile: Option<f64>,
}

/// Value of one energy term.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TermValue {
    pub raw: f64,
    pub weighted: f64,
}

/// Summary of one stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageReport {
    pub name: String,
    pub iterations: usize,
    pub samples: usize,
    /// Population of the stage's first run (restarts double it each time).
    pub population: usize,
    /// Restarts the stage made (IPOP); absent in files written before restarts existed.
    #[serde(default)]
    pub restarts: usize,
    pub best_energy: f64,
    pub iou: f64,
    pub stop: String,
    pub wall_time_s: f64,
}

/// Everything `solution.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Solution {
    pub scene: String,
    /// The scene file the solution was made from; `export`, `validate` and `video` find
    /// the scene through it unless told otherwise. In memory it is a path usable from
    /// the current folder; `solution.json` holds it relative to its own folder (see
    /// `output::files::write_solution`).
    #[serde(default)]
    pub scene_file: Option<String>,
    pub seed: u64,
    /// The instant the shadows form the picture (s).
    #[serde(rename = "t_s", alias = "t")]
    pub t: f64,
    pub stages_total: usize,
    pub stages_completed: usize,
    /// True when the solve ran every stage to its own stop (not cut short by Ctrl-C).
    pub complete: bool,
    pub occluders: Vec<OccluderLaunch>,
    /// Every term at the solution, raw and weighted with the last completed stage's weights.
    pub energy: std::collections::BTreeMap<String, TermValue>,
    pub total_energy: f64,
    pub iou: f64,
    /// The first contact's time, or `t` without contact (s).
    #[serde(rename = "t_sim_s", alias = "t_sim")]
    pub t_sim: f64,
    pub n_contacts: u32,
    pub samples: usize,
    pub iterations: usize,
    pub wall_time_s: f64,
    pub threads: usize,
    /// Mean time per phase of one sample on one core (microseconds).
    pub time_per_term_us: std::collections::BTreeMap<String, f64>,
    pub stages: Vec<StageReport>,
    /// The IoU at every frame the scene asks about (several pictures, or a hold window);
    /// empty for a single picture without hold, whose IoU is `iou`. With frames, `iou`
    /// is the worst of the evaluated instants.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<FrameRecord>,
    /// Shadows scored per sample (instants times launches), when more than one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadows_per_sample: Option<usize>,
    /// The air the solve flew every body through (`bsa solve --air`); none: vacuum.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub air: Option<DragConfig>,
    /// The launch errors of a robust solve (`bsa solve --robust`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust: Option<RobustRecord>,
    /// Every attempt of a solve that ran more than one (`bsa solve --attempts`), in
    /// order; empty after one. The launch, the stages and the energy are those of the
    /// attempt kept; `samples`, `iterations` and `wall_time_s` count every attempt.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub attempts: Vec<AttemptRecord>,
    /// Every pass of the solver's schedule that ran, in order, over every attempt: their
    /// samples add up to `samples`, each a row of `convergence.csv`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub passes: Vec<PassRecord>,
}

/// One pass of the solver's schedule that ran (see
/// [`Schedule`](crate::optimize::solver::Schedule)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassRecord {
    /// The attempt it ran in (0: the first).
    pub attempt: usize,
    /// The index of its stage.
    pub stage: usize,
    /// `moves`, `runs`, `trades` or `polish`.
    pub pass: String,
    pub iou_before: f64,
    pub iou_after: f64,
    pub samples: usize,
    pub wall_time_s: f64,
    /// The moves the pass took, in order (a pass of moves, trades or polish).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moves: Vec<MoveRecord>,
}

/// A move a pass took (see `optimize::moves`): `swap`, `fill`, `fit`, `reorient`,
/// `seat`, `seat pair`, `split`, `trade` or `pose fit`, and the IoU before and after it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveRecord {
    #[serde(rename = "move")]
    pub name: String,
    pub iou_before: f64,
    pub iou_after: f64,
}

/// One attempt of a solve (its stages from the start guess, with its own seed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AttemptRecord {
    pub seed: u64,
    pub iou: f64,
    pub n_contacts: u32,
    pub samples: usize,
    pub wall_time_s: f64,
    /// Whether its launch is the solution's.
    pub kept: bool,
}

impl AttemptRecord {
    /// "seed N IoU 0.xxxx", and " with a contact" when it had one: how the summary line
    /// of `bsa solve` and the report page name an attempt.
    pub fn describe(&self) -> String {
        let contact = if self.n_contacts > 0 {
            " with a contact"
        } else {
            ""
        };
        format!("seed {} IoU {:.4}{contact}", self.seed, self.iou)
    }
}

impl Solution {
    /// The launch values as the solver's parameter vector (6 per occluder).
    pub fn parameters(&self) -> Vec<f64> {
        self.occluders
            .iter()
            .flat_map(|o| o.velocity.iter().chain(o.angular_velocity.iter()).copied())
            .collect()
    }

    /// The scene as this solution launches it: every occluder at its saved launch
    /// position (free positions), and the positions fixed from then on.
    pub fn place(&self, scene: &mut Scene) {
        for (o, l) in scene.occluders.iter_mut().zip(&self.occluders) {
            if let Some(p) = l.position {
                o.position = glam::DVec3::from_array(p);
            }
        }
        scene.positions = crate::scene::LaunchPositions::Fixed;
    }
}

/// Why a solution does not belong to a scene.
#[derive(Debug, thiserror::Error)]
pub enum MismatchError {
    #[error("the solution is for scene `{found}`, not `{expected}`")]
    Scene { expected: String, found: String },
    #[error("the solution has {found} occluders, the scene has {expected}")]
    Count { expected: usize, found: usize },
    #[error("occluder {index} is `{found}` in the solution but `{expected}` in the scene")]
    Name {
        index: usize,
        expected: String,
        found: String,
    },
    #[error("it has {found} stages, the scene has {expected}")]
    Stages { expected: usize, found: usize },
    #[error("the solution is for t = {found} s but the scene has t = {expected} s: the scene was edited after the solve")]
    Time { expected: f64, found: f64 },
    #[error("the solution holds a non-finite launch value for `{name}`")]
    NotFinite { name: String },
    /// A launch beyond the limits of the scene files ([`Scene::launch_beyond_limits`]).
    #[error("occluder `{name}`: `{field}` {message}")]
    TooFast {
        name: String,
        field: &'static str,
        message: String,
    },
}

/// Check that a solution was made for this scene: the scene's name, the occluders'
/// count and names, the instant `t`, and finite launch values. Every command that reads
/// a solution checks it here.
pub fn check_solution(scene: &Scene, s: &Solution) -> Result<(), MismatchError> {
    if s.scene != scene.name {
        return Err(MismatchError::Scene {
            expected: scene.name.clone(),
            found: s.scene.clone(),
        });
    }
    if s.occluders.len() != scene.occluders.len() {
        return Err(MismatchError::Count {
            expected: scene.occluders.len(),
            found: s.occluders.len(),
        });
    }
    for (i, (a, b)) in scene.occluders.iter().zip(&s.occluders).enumerate() {
        if a.name != b.name {
            return Err(MismatchError::Name {
                index: i,
                expected: a.name.clone(),
                found: b.name.clone(),
            });
        }
        if b.velocity
            .iter()
            .chain(&b.angular_velocity)
            .any(|x| !x.is_finite())
        {
            return Err(MismatchError::NotFinite {
                name: b.name.clone(),
            });
        }
        let launch = Launch {
            velocity: DVec3::from_array(b.velocity),
            angular_velocity: DVec3::from_array(b.angular_velocity),
        };
        if let Some((field, message)) = scene.launch_beyond_limits(i, &launch) {
            return Err(MismatchError::TooFast {
                name: b.name.clone(),
                field,
                message,
            });
        }
    }
    if s.t != scene.t {
        return Err(MismatchError::Time {
            expected: scene.t,
            found: s.t,
        });
    }
    Ok(())
}

/// [`check_solution`], and that the solution's stages are the scene's, so that a solve
/// can resume after its completed stages.
pub fn check_resumable(scene: &Scene, s: &Solution) -> Result<(), MismatchError> {
    check_solution(scene, s)?;
    if s.stages_total != scene.stages.len() {
        return Err(MismatchError::Stages {
            expected: scene.stages.len(),
            found: s.stages_total,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_older_solution_file_reads_and_is_written_with_units_in_its_keys() {
        // solution.json as written before its keys carried units.
        let old = serde_json::json!({
            "scene": "demo", "scene_file": null, "seed": 1, "t": 1.2,
            "stages_total": 1, "stages_completed": 1, "complete": true,
            "occluders": [{"name": "ball", "launched": true,
                "velocity": [1.0, 2.0, 3.0], "angular_velocity": [0.1, 0.2, 0.3]}],
            "energy": {}, "total_energy": 1.0, "iou": 0.99, "t_sim": 1.1,
            "n_contacts": 1, "samples": 10, "iterations": 2, "wall_time_s": 0.1,
            "threads": 2, "time_per_term_us": {}, "stages": []
        });
        let s: Solution = serde_json::from_value(old).unwrap();
        assert_eq!((s.t, s.t_sim), (1.2, 1.1));
        assert_eq!(s.occluders[0].velocity, [1.0, 2.0, 3.0]);
        let new = serde_json::to_value(&s).unwrap();
        for key in ["t_s", "t_sim_s"] {
            assert!(new.get(key).is_some(), "{key} missing");
        }
        assert!(new["occluders"][0].get("velocity_m_s").is_some());
        assert_eq!(serde_json::from_value::<Solution>(new).unwrap(), s);
    }

    #[test]
    fn launch_keys_carry_units_and_old_files_still_read() {
        let o = OccluderLaunch {
            name: "a".into(),
            launched: true,
            velocity: [1.0, 2.0, 3.0],
            angular_velocity: [4.0, 5.0, 6.0],
            position: None,
        };
        let text = serde_json::to_string(&o).unwrap();
        assert!(text.contains("\"velocity_m_s\"") && text.contains("\"angular_velocity_rad_s\""));
        let old = r#"{"name":"a","launched":true,"velocity":[1,2,3],"angular_velocity":[4,5,6]}"#;
        assert_eq!(serde_json::from_str::<OccluderLaunch>(old).unwrap(), o);
    }
}
