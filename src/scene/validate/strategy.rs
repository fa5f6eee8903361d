//! Validation of the optimisation strategy: the scheduled list of `stages`, or the
//! sequential strategy's `order`, `rounds`, `stage` and `final`, expanded into the flat
//! list of [`Stage`]s the solver runs.

use super::Validator;
use crate::energy::{Term, Weights, TERM_COUNT};
use crate::scene::raw::{RawOrder, RawScene, RawStage, RawStrategy, RawVary};
use crate::scene::start::auto_order;
use crate::scene::{
    Launch, Occluder, Result, Stage, Strategy, DEFAULT_RESTARTS, DEFAULT_RESTART_GAIN,
    DEFAULT_RESTART_IOU, MAX_ITERATIONS, MAX_POPULATION, MAX_RESTARTS, MAX_STAGNATION, MAX_STEP,
};

impl Validator<'_> {
    /// One stage of the list, `field` naming it in errors: its weights, the occluders it
    /// varies (`default_vary` unless it says), and CMA-ES's settings.
    fn stage(
        &self,
        field: &str,
        rs: &RawStage,
        default_name: String,
        default_vary: &[usize],
        occ: &[Occluder],
        defaults: StageDefaults,
    ) -> Result<Stage> {
        let w = self.stage_weights(field, rs, defaults)?;
        let vary = self.stage_vary(field, rs, default_vary, occ)?;
        let n = Launch::LEN * vary.len();
        let step =
            self.positive_within(&format!("{field}.step"), rs.step.unwrap_or(0.3), MAX_STEP)?;
        let max_iterations = rs.max_iterations.unwrap_or(150);
        if !(1..=MAX_ITERATIONS).contains(&max_iterations) {
            return Err(self.field_err(
                format!("{field}.max_iterations"),
                format!("must be between 1 and {MAX_ITERATIONS}, got {max_iterations}"),
            ));
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
        if !(1..=MAX_STAGNATION).contains(&stagnation) {
            return Err(self.field_err(
                format!("{field}.stagnation"),
                format!("must be between 1 and {MAX_STAGNATION} iterations, got {stagnation}"),
            ));
        }
        let restarts = rs.restarts.unwrap_or(defaults.restarts);
        if restarts > MAX_RESTARTS {
            return Err(self.field_err(
                format!("{field}.restarts"),
                format!("must be between 0 and {MAX_RESTARTS}, got {restarts}"),
            ));
        }
        let restart_iou = rs.restart_iou.unwrap_or(DEFAULT_RESTART_IOU);
        if !(0.0..=1.0).contains(&restart_iou) {
            return Err(self.field_err(
                format!("{field}.restart_iou"),
                format!("must be an IoU between 0 and 1, got {restart_iou}"),
            ));
        }
        let restart_gain = rs.restart_gain.unwrap_or(DEFAULT_RESTART_GAIN);
        if !(0.0..=1.0).contains(&restart_gain) {
            return Err(self.field_err(
                format!("{field}.restart_gain"),
                format!("must be an IoU gain between 0 and 1, got {restart_gain}"),
            ));
        }
        let objective = self.objective(&format!("{field}.objective"), rs.objective.as_deref())?;
        Ok(Stage {
            objective,
            name: rs.name.clone().unwrap_or(default_name),
            weights: w,
            vary,
            step,
            max_iterations,
            population,
            target_energy,
            tol_fun,
            stagnation,
            restarts,
            restart_iou,
            restart_gain,
        })
    }

    /// A stage's weights: the defaults, or the terms it names (the others 0), not all 0.
    fn stage_weights(
        &self,
        field: &str,
        rs: &RawStage,
        defaults: StageDefaults,
    ) -> Result<Weights> {
        let mut w = [0.0; TERM_COUNT];
        if rs.weights.is_none() {
            w = defaults.weights.0;
        }
        for (key, value) in rs.weights.iter().flatten() {
            let term = Term::from_key(key).ok_or_else(|| {
                self.field_err(
                    format!("{field}.weights.{key}"),
                    format!(
                        "unknown energy term; use one of {}",
                        Term::ALL.map(|t| t.key()).join(", ")
                    ),
                )
            })?;
            w[term as usize] = self.weight(&format!("{field}.weights.{key}"), *value)?;
        }
        if w.iter().all(|&x| x == 0.0) {
            return Err(self.field_err(
                format!("{field}.weights"),
                "gives every term a weight of 0, so the stage has nothing to optimise; leave `weights` out for the defaults",
            ));
        }
        Ok(Weights(w))
    }

    /// The occluders a stage varies: `default_vary`, every launched one (`"all"`), or
    /// the launched ones it names; never none.
    fn stage_vary(
        &self,
        field: &str,
        rs: &RawStage,
        default_vary: &[usize],
        occ: &[Occluder],
    ) -> Result<Vec<usize>> {
        let vary = match &rs.vary {
            None => default_vary.to_vec(),
            Some(RawVary::All(s)) if s == "all" => launched(occ),
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
        Ok(vary)
    }

    /// The stages the scene's strategy expands to, and the strategy (for reports).
    pub(super) fn stages(
        &self,
        raw: &RawScene,
        occ: &[Occluder],
        defaults: Weights,
    ) -> Result<(Vec<Stage>, Strategy)> {
        let launched = launched(occ);
        match (&raw.strategy, &raw.stages) {
            (None | Some(RawStrategy::Scheduled), Some(list)) => {
                if list.is_empty() {
                    return Err(self.field_err("stages", "needs at least one stage"));
                }
                let stages = list
                    .iter()
                    .enumerate()
                    .map(|(i, s)| {
                        let d = StageDefaults::of(defaults, i + 1 == list.len());
                        self.stage(&format!("stages[{i}]"), s, format!("stage {}", i + 1), &launched, occ, d)
                    })
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
                let order = self.order(order.as_ref(), occ)?;
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
                        let d = StageDefaults::of(defaults, false);
                        let s = self.stage("strategy.stage", stage, name, &[i], occ, d)?;
                        stages.push(s);
                    }
                }
                if let Some(fs) = final_stage {
                    let d = StageDefaults::of(defaults, true);
                    stages.push(self.stage("strategy.final", fs, "final".to_string(), &launched, occ, d)?);
                }
                Ok((stages, Strategy::Sequential { order }))
            }
        }
    }

    /// The sequential strategy's order: automatic ([`auto_order`]), or the launched
    /// occluders it names, each once.
    fn order(&self, order: Option<&RawOrder>, occ: &[Occluder]) -> Result<Vec<usize>> {
        Ok(match order {
            None => auto_order(occ),
            Some(RawOrder::Auto(s)) if s == "auto" => auto_order(occ),
            Some(RawOrder::Auto(s)) => {
                return Err(self.field_err(
                    "strategy.order",
                    format!("must be \"auto\" or a list of occluder names, got \"{s}\""),
                ))
            }
            Some(RawOrder::Names(names)) => {
                let mut out = Vec::new();
                for n in names {
                    let i = occ.iter().position(|o| &o.name == n).ok_or_else(|| {
                        self.field_err(
                            "strategy.order",
                            format!("names occluder `{n}`, which does not exist"),
                        )
                    })?;
                    if !occ[i].launched {
                        return Err(self.field_err(
                            "strategy.order",
                            format!("occluder `{n}` is not launched"),
                        ));
                    }
                    if out.contains(&i) {
                        return Err(self.field_err(
                            "strategy.order",
                            format!("occluder `{n}` is listed twice"),
                        ));
                    }
                    out.push(i);
                }
                out
            }
        })
    }
}

/// The indices of the launched occluders, in order.
fn launched(occ: &[Occluder]) -> Vec<usize> {
    occ.iter()
        .enumerate()
        .filter(|(_, o)| o.launched)
        .map(|(i, _)| i)
        .collect()
}

/// What a stage gets for the fields its file leaves out, beyond the fixed defaults.
#[derive(Clone, Copy)]
struct StageDefaults {
    weights: Weights,
    restarts: usize,
}

impl StageDefaults {
    /// The defaults of a stage: the scene's default weights, and
    /// [`DEFAULT_RESTARTS`] for the last stage (the one that leaves the result), one
    /// restart for the others.
    fn of(weights: Weights, last: bool) -> StageDefaults {
        StageDefaults {
            weights,
            restarts: if last { DEFAULT_RESTARTS } else { 1 },
        }
    }
}
