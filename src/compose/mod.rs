//! Composing a scene from a picture and a box of objects: the design search of
//! `bsa new` ([`Search::run`]), the picture designed under every
//! [`Setting`] (each of [`crate::design::CEILINGS`] in each of [`ORDERS`], once for
//! both orders where they make the same design), each design made contact-free
//! ([`separate`]); the designs that differ from those before them then
//! race ([`race`]) and the best ([`Variant::better_than`]) is kept ([`Found`]). When no
//! design's solve reaches [`REPLACE_BELOW`], a second round designs again under the
//! ceilings of the best designs ([`crate::design::ANEW_CEILINGS`]) with the objects
//! placed anew ([`crate::design::cover::Cover::replace`]), each from the first round's
//! [`crate::design::Draft`] under its ceiling and order, and races those.
//!
//! A start guess's IoU says little of where its solve ends: on 27 held-out pictures the
//! design with the best start was the best solved one for 12. So the designs are
//! solved as `bsa solve` will solve them (the scene's seed and strategy,
//! [`Schedule::TRIAL`]), side by side, in a race whose rungs ([`RUNGS`]) say how far.
//!
//! Each design's scene is written and loaded by the caller ([`Scenes`]: mesh paths are
//! relative to the scene's folder), so that the trial solves the very scene `bsa new`
//! writes and this module touches no file. The caller watches through [`Watch`] and
//! stops the search with the interrupt counter the solver watches too.

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde_json::Value;

use crate::design::launch::{Geometry, Plan};
use crate::design::picture::Picture;
use crate::design::{
    self, separate, DesignError, Order, Request, ANEW_CEILINGS, ORDERS, REPLACE_BELOW,
};
use crate::energy::Weights;
use crate::evaluate::Problem;
use crate::optimize::solver::{self, Schedule, Silent, SolveOptions};
use crate::output::solution::Solution;
use crate::scene::launcher::Tolerances;
use crate::scene::Scene;

pub mod tolerant;

/// Why a design of the search failed.
#[derive(Debug, thiserror::Error)]
pub enum SearchError {
    #[error(transparent)]
    Design(#[from] DesignError),
    /// The caller could not write or load a design's scene ([`Scenes`]).
    #[error(transparent)]
    Scenes(Box<dyn std::error::Error + Send + Sync>),
    /// The interrupt counter was raised before the design began.
    #[error("interrupted")]
    Interrupted,
}

/// What one design is made under.
#[derive(Clone, Copy, Debug)]
pub struct Setting {
    pub order: Order,
    /// The highest flight at `t`, as a share of the light's height ([`crate::design::CEILINGS`]).
    pub ceiling: f64,
    /// Every object placed anew after the exchanges
    /// ([`crate::design::cover::Cover::replace`]).
    pub replace: bool,
}

/// The settings of a round under `ceilings`, orders outermost: the first round's
/// (greedy, exchanged and polished) or, with `replace`, the second's, with every object
/// placed anew too.
fn round_settings(ceilings: &[f64], replace: bool) -> impl Iterator<Item = Setting> + '_ {
    ORDERS.iter().flat_map(move |&order| {
        ceilings.iter().map(move |&ceiling| Setting {
            order,
            ceiling,
            replace,
        })
    })
}

/// The most designs a search under `ceilings` makes (one scene file each).
pub fn most_designs(ceilings: &[f64]) -> usize {
    ORDERS.len() * (ceilings.len() + ANEW_CEILINGS.min(ceilings.len()))
}

/// Where a design's trial solve ended.
#[derive(Clone, Copy, Debug)]
pub struct Solved {
    /// IoU at `t` of the solution.
    pub iou: f64,
    /// No contact before `t`.
    pub clear: bool,
    /// The stages it ran, of all: fewer for a design the race left behind.
    pub stages: (usize, usize),
    /// The highest point of any body's flight up to `t` above the receiver (m).
    pub height: f64,
    /// At the search's launcher, when it has one: `P(IoU >= iou - NEEDS_MARGIN)` and
    /// the largest factor on its errors that keeps that at 90 %.
    pub at_launcher: Option<(f64, f64)>,
}

impl Solved {
    /// Whether its solve ran every stage (it won its way to the race's last rung).
    pub fn finished(&self) -> bool {
        self.stages.0 >= self.stages.1
    }
}

/// One design of the picture under one setting, made contact-free.
#[derive(Clone)]
pub struct Variant {
    pub plan: Plan,
    pub setting: Setting,
    /// Moves [`separate`] took.
    pub moves: usize,
    /// The start guess's IoU and whether it flies without contact before `t`.
    pub iou: f64,
    pub clear: bool,
    /// The trial solve's end (none when the search does not solve).
    pub solved: Option<Solved>,
}

impl Variant {
    /// The solved picture first (contact-free first, then the higher IoU), then the
    /// start guess's (the same order).
    pub fn better_than(&self, other: &Variant) -> bool {
        self.rank() > other.rank()
    }

    fn rank(&self) -> (bool, bool, f64, bool, f64) {
        rank(self.solved, self.clear, self.iou)
    }
}

/// The order of [`Variant::better_than`] as a tuple: a design with a trial solve
/// ranks by it (one that ran every stage before one the race left behind), and by its
/// start guess after that.
fn rank(solved: Option<Solved>, clear: bool, iou: f64) -> (bool, bool, f64, bool, f64) {
    match solved {
        Some(s) => (s.finished(), s.clear, s.iou, clear, iou),
        None => (true, clear, iou, clear, iou),
    }
}

/// What became of one design's trial solve, for [`Found::trials_line`].
#[derive(Clone, Copy, Debug)]
pub enum Trial {
    /// Solved (`None` when the search does not solve).
    Solved(Option<Solved>),
    /// The same scene as a design before it, not solved again.
    Same,
    /// The design failed (its error is reported if no design succeeds).
    Failed,
}

/// How the caller watches the search: phases of counted steps (the CLI draws a
/// progress bar for each). Steps are counted from worker threads.
pub trait Watch: Sync {
    /// A phase of `total` steps begins, described by `what`.
    fn begin(&self, total: u64, what: &str);
    /// One step of the phase is done.
    fn step(&self);
    /// The phase ended.
    fn end(&self);
}

/// Where the designs' scenes are written and loaded from: one scene file per setting
/// of [`round_settings`], in the scene's folder (its mesh paths are relative to it).
pub trait Scenes: Sync {
    /// Write the scene file `json` of setting `k` and load it back.
    fn load(&self, k: usize, json: &Value) -> Result<Scene, SearchError>;
}

/// A search's inputs: the picture, the objects, where the designs' scenes go and what
/// the scene is called.
pub struct Search<'a> {
    pub picture: &'a Picture,
    pub geometry: &'a Geometry,
    pub request: &'a Request,
    pub scenes: &'a dyn Scenes,
    pub name: &'a str,
    /// The target's file name as the scene files name it.
    pub target: &'a str,
    pub seed: u64,
    /// Whether each design is trial-solved (else they rank by their start guesses).
    pub trial: bool,
    /// The highest flights tried, as shares of the light's height ([`crate::design::CEILINGS`] by
    /// default).
    pub ceilings: &'a [f64],
    /// The launcher each trial solve is measured at, if any ([`tolerant`]).
    pub launcher: Option<Tolerances>,
    /// The most rounds of designs: 2 lets a second round place every object anew when
    /// the first reaches too little ([`REPLACE_BELOW`]).
    pub rounds: usize,
}

/// What the search found: the best design, the others, the first error (when no design
/// was made) and every setting's trial, in the order of [`round_settings`].
pub struct Found {
    pub best: Option<Variant>,
    /// Every other design made, in the order of [`round_settings`] (repeats left out).
    pub others: Vec<Variant>,
    pub first_error: Option<SearchError>,
    pub trials: Vec<Trial>,
    /// The ceilings searched.
    pub ceilings: Vec<f64>,
    /// The ceilings of the second round (none when it did not run).
    pub anew_under: Vec<f64>,
}

impl Search<'_> {
    /// Design under every setting of the first round and race the designs; when no
    /// trial reaches [`REPLACE_BELOW`], a second round under the ceilings of the best
    /// designs ([`ANEW_CEILINGS`]); keep the best of all. After an interrupt the designs not
    /// begun fail with [`SearchError::Interrupted`].
    pub fn run(&self, watch: &dyn Watch, interrupts: &AtomicUsize) -> Found {
        let mut settings: Vec<Setting> = round_settings(self.ceilings, false).collect();
        let first_round = settings.len();
        let mut made = Made::default();
        self.round(&settings, 0..first_round, &mut made, watch, interrupts);
        let best_trial = made
            .designed
            .iter()
            .filter_map(|v| v.as_ref().ok()?.solved)
            .filter(|s| s.clear && s.finished())
            .map(|s| s.iou)
            .fold(f64::NEG_INFINITY, f64::max);
        let second = self.may_place_anew() && best_trial < REPLACE_BELOW;
        let mut anew_under: Vec<f64> = Vec::new();
        if second && interrupts.load(Ordering::SeqCst) == 0 {
            // The ceilings of the best designs, best first.
            let mut ranked: Vec<&Variant> = made.designed.iter().flatten().collect();
            ranked.sort_by(|a, b| b.rank().partial_cmp(&a.rank()).expect("IoUs are numbers"));
            for v in ranked {
                if anew_under.len() < ANEW_CEILINGS && !anew_under.contains(&v.setting.ceiling) {
                    anew_under.push(v.setting.ceiling);
                }
            }
            settings.extend(round_settings(&anew_under, true));
            // Only the drafts of the ceilings placed anew are wanted (a few MB each).
            let wanted = |c: u64| anew_under.iter().any(|a| a.to_bits() == c);
            let drafts = made.drafts.get_mut().unwrap_or_else(|e| e.into_inner());
            drafts.retain(|((c, _), _)| wanted(*c));
            let ks = first_round..settings.len();
            self.round(&settings, ks, &mut made, watch, interrupts);
        }
        let mut found = Found {
            best: None,
            others: Vec::new(),
            first_error: None,
            trials: Vec::new(),
            ceilings: self.ceilings.to_vec(),
            anew_under,
        };
        for (v, same) in made.designed.into_iter().zip(made.same_as) {
            match v {
                Ok(v) => {
                    found.trials.push(match same {
                        Some(_) => Trial::Same,
                        None => Trial::Solved(v.solved),
                    });
                    if found.best.as_ref().is_none_or(|b| v.better_than(b)) {
                        if let Some(b) = found.best.replace(v) {
                            found.others.push(b);
                        }
                    } else if same.is_none() {
                        found.others.push(v);
                    }
                }
                Err(e) => {
                    found.trials.push(Trial::Failed);
                    found.first_error.get_or_insert(e);
                }
            }
        }
        found
    }

    /// Design under the settings `ks` (in parallel, each made contact-free), append
    /// them to `made.designed`, and to `made.same_as` the earlier design each repeats
    /// (one that another order or round made too); with `trial`, race those that repeat
    /// none.
    fn round<'s>(
        &'s self,
        settings: &[Setting],
        ks: Range<usize>,
        made: &mut Made<'s>,
        watch: &dyn Watch,
        interrupts: &AtomicUsize,
    ) {
        let drafts = &made.drafts;
        let replace = ks.clone().any(|k| settings[k].replace);
        watch.begin(
            ks.len() as u64,
            &format!(
                "{}: designing{} under {} ceilings and {} orders{}",
                self.name,
                match self.launcher {
                    Some(_) => format!(" for t = {} s", self.geometry.t),
                    None => String::new(),
                },
                self.ceilings.len(),
                ORDERS.len(),
                if replace { ", objects placed anew" } else { "" }
            ),
        );
        // Where the orders make the same design, each is made once: a setting's twin is
        // the first before it under the same ceiling and replace.
        let one = self.request.one_order();
        let twin: Vec<Option<usize>> = ks
            .clone()
            .map(|k| {
                let s = settings[k];
                (ks.start..k).find(|&j| {
                    one && settings[j].ceiling == s.ceiling && settings[j].replace == s.replace
                })
            })
            .collect();
        let mut now: Vec<Option<Result<Variant, SearchError>>> = ks
            .clone()
            .into_par_iter()
            .map(|k| {
                twin[k - ks.start].is_none().then(|| {
                    let variant =
                        unless_interrupted(interrupts, || self.design(settings[k], k, drafts));
                    watch.step();
                    variant
                })
            })
            .collect();
        for k in ks.clone() {
            if let Some(j) = twin[k - ks.start] {
                let v = match &now[j - ks.start] {
                    Some(Ok(v)) => Ok(Variant {
                        setting: settings[k],
                        ..v.clone()
                    }),
                    // The twin's error, made again (errors do not clone).
                    _ => unless_interrupted(interrupts, || self.design(settings[k], k, drafts)),
                };
                now[k - ks.start] = Some(v);
                watch.step();
            }
        }
        watch.end();
        let (designed, same_as) = (&mut made.designed, &mut made.same_as);
        designed.extend(now.into_iter().map(|v| v.expect("every setting designed")));
        let scenes: Vec<Option<String>> = designed
            .iter()
            .map(|v| {
                v.as_ref()
                    .ok()
                    .map(|v| self.scene_json(&v.plan).to_string())
            })
            .collect();
        for k in ks.clone() {
            same_as.push((0..k).find(|&j| scenes[k].is_some() && scenes[j] == scenes[k]));
        }
        if !self.trial {
            return;
        }
        let todo: Vec<usize> = ks
            .filter(|&k| designed[k].is_ok() && same_as[k].is_none())
            .collect();
        let loaded: Vec<(usize, Result<Problem, SearchError>)> = todo
            .par_iter()
            .map(|&k| {
                let v = designed[k].as_ref().expect("a design to solve");
                let p = unless_interrupted(interrupts, || self.problem(&v.plan, k));
                (k, p)
            })
            .collect();
        let mut entrants = Vec::new();
        for (k, p) in loaded {
            match p {
                Ok(p) => entrants.push((k, p)),
                Err(e) => designed[k] = Err(e),
            }
        }
        // A solve begun stops at once on an interrupt: its solver watches the counter.
        let launcher = self.launcher.as_ref();
        for (k, s) in race(entrants, self.name, launcher, watch, interrupts) {
            designed[k].as_mut().expect("a raced design").solved = Some(s);
        }
    }

    /// Whether a second round may place the objects anew ([`Search::run`]).
    fn may_place_anew(&self) -> bool {
        self.rounds >= 2 && self.trial
    }

    /// The scene file's JSON of `plan`.
    fn scene_json(&self, plan: &Plan) -> Value {
        plan.scene_json(self.name, self.target, self.seed)
    }

    /// The scene of `plan` as setting `k`'s scene file loads it.
    fn problem(&self, plan: &Plan, k: usize) -> Result<Problem, SearchError> {
        Ok(Problem::new(self.scenes.load(k, &self.scene_json(plan))?))
    }

    /// Design under `setting` (the `k`-th), make its start guess contact-free and
    /// evaluate it. A first round's draft is kept in `drafts` when a second round may
    /// place its objects anew; that round's design starts from it (the same bits as
    /// making it again).
    fn design<'s>(
        &'s self,
        setting: Setting,
        k: usize,
        drafts: &Drafts<'s>,
    ) -> Result<Variant, SearchError> {
        let key = (setting.ceiling.to_bits(), setting.order);
        let list = || drafts.lock().unwrap_or_else(|e| e.into_inner());
        let kept = match setting.replace {
            true => {
                let mut list = list();
                let i = list.iter().position(|(k, _)| *k == key);
                i.map(|i| list.swap_remove(i).1)
            }
            false => None,
        };
        let draft = match kept {
            Some(d) => d,
            None => {
                let geometry = Geometry {
                    ceiling: setting.ceiling,
                    ..self.geometry.clone()
                };
                design::draft(self.picture, geometry, self.request, setting.order)?
            }
        };
        if !setting.replace && self.may_place_anew() {
            list().push((key, draft.clone()));
        }
        let mut plan = draft.finish(setting.replace);
        let mut problem = self.problem(&plan, k)?;
        let n = plan.objects.len();
        let sep = separate::separate(&mut plan, &mut problem, 4 * n + 10);
        let params = separate::apply(&plan, &mut problem);
        let mut ws = problem.workspace();
        let start = problem.evaluate(&params, &Weights::default(), &mut ws);
        Ok(Variant {
            plan,
            setting,
            moves: sep.moves,
            iou: start.iou,
            clear: start.outcome.n_contacts == 0,
            solved: None,
        })
    }
}

/// The first round's drafts, by ceiling (its bits) and order, for the second
/// ([`Search::design`]).
type Drafts<'a> = std::sync::Mutex<Vec<((u64, Order), design::Draft<'a>)>>;

/// The designs of a search so far ([`Search::round`]): each setting's, the earlier
/// setting each repeats, and the first round's drafts.
#[derive(Default)]
struct Made<'a> {
    designed: Vec<Result<Variant, SearchError>>,
    same_as: Vec<Option<usize>>,
    drafts: Drafts<'a>,
}

/// `work()`, unless the interrupt counter was raised: after it nothing is written, so
/// the designs and trial solves not yet begun are skipped.
fn unless_interrupted<T>(
    interrupts: &AtomicUsize,
    work: impl FnOnce() -> Result<T, SearchError>,
) -> Result<T, SearchError> {
    if interrupts.load(Ordering::SeqCst) > 0 {
        return Err(SearchError::Interrupted);
    }
    work()
}

/// The share of its stages each rung of the race solves a design to, the better half
/// going on to the next rung (successive halving). One rung, every design to its end:
/// rungs of a quarter and a half of the stages dropped the design that ends best in 6
/// of the 35 planted problems of seeds 12000 to 12006 through `bsa new` and raised none
/// (median 0.9968 to 0.9961), for a quarter less of `bsa new`'s time. A sequential
/// solve places its bodies one by one, so its picture part way through says little of
/// where it ends.
pub const RUNGS: [f64; 1] = [1.0];

/// Race the designs `entrants` (each with its index): each rung of [`RUNGS`] solves
/// every design left to its share of the stages, resuming where the last rung left it,
/// and keeps the better half (contact-free first, then the higher IoU) for the next.
/// The solves leave out the last stage's trades and polish ([`Schedule::TRIAL`]: they
/// compare designs, not rescues or refinements) and run on one thread each, the
/// designs side by side (a solve's result does not depend on its thread count).
/// Returns where each design's solve ended.
pub fn race(
    mut entrants: Vec<(usize, Problem)>,
    name: &str,
    launcher: Option<&Tolerances>,
    watch: &dyn Watch,
    interrupts: &AtomicUsize,
) -> Vec<(usize, Solved)> {
    let mut ended = Vec::new();
    let mut reached: Vec<Option<Solution>> = entrants.iter().map(|_| None).collect();
    for (r, share) in RUNGS.into_iter().enumerate() {
        let what = match share < 1.0 {
            true => format!("racing {} designs ({share} of the stages)", entrants.len()),
            false => format!("solving {} designs", entrants.len()),
        };
        watch.begin(entrants.len() as u64, &format!("{name}: {what}"));
        let solved: Vec<(Solution, Option<(f64, f64)>)> = entrants
            .par_iter()
            .zip(reached.par_iter_mut())
            .map(|((_, problem), from)| {
                let stages = problem.scene.stages.len();
                let options = SolveOptions {
                    threads: Some(1),
                    schedule: Schedule::TRIAL,
                    resume: from.take(),
                    until_stage: Some(((share * stages as f64).ceil() as usize).clamp(1, stages)),
                    ..SolveOptions::default()
                };
                let (s, _) = solver::solve(problem, &options, &mut Silent, interrupts);
                let p = launcher.map(|tol| tolerant::measure(problem, &s, tol));
                watch.step();
                (s, p)
            })
            .collect();
        let (solved, at_launcher): (Vec<Solution>, Vec<Option<(f64, f64)>>) =
            solved.into_iter().unzip();
        watch.end();
        let mut order: Vec<usize> = (0..entrants.len()).collect();
        let key = |s: &Solution| (s.n_contacts == 0, s.iou);
        order.sort_by(|&a, &b| {
            key(&solved[b])
                .partial_cmp(&key(&solved[a]))
                .expect("IoUs are numbers")
        });
        let keep = if r + 1 == RUNGS.len() {
            order.len()
        } else {
            order.len().div_ceil(2)
        };
        let mut next = Vec::new();
        let mut next_reached = Vec::new();
        let mut slots: Vec<Option<(usize, Problem)>> = entrants.into_iter().map(Some).collect();
        for (place, &j) in order.iter().enumerate() {
            let (k, problem) = slots[j].take().expect("each design once");
            let s = &solved[j];
            if place < keep && s.stages_completed < s.stages_total {
                next.push((k, problem));
                next_reached.push(Some(s.clone()));
            } else {
                ended.push((
                    k,
                    Solved {
                        iou: s.iou,
                        clear: s.n_contacts == 0,
                        stages: (s.stages_completed, s.stages_total),
                        height: tolerant::highest_flight(&problem, &s.parameters()),
                        at_launcher: at_launcher[j],
                    },
                ));
            }
        }
        entrants = next;
        reached = next_reached;
        if entrants.is_empty() || interrupts.load(Ordering::SeqCst) > 0 {
            break;
        }
    }
    ended
}

impl Found {
    /// "trial solves under ceilings 0.8 / 0.7 / 0.6 / 0.5 of the light's height: IoU a
    /// / b / c / d (largest object first), e / same / f / g (best fit first)[; placed
    /// anew under 0.6 / 0.8: h / i (largest object first), same / j (best fit
    /// first)]; kept the design under c, best fit first[, placed anew]": what the
    /// choice was made on (a trial that ended with a contact says so; "same" is a
    /// design that an earlier one made too). The second round only when it ran.
    pub fn trials_line(&self, kept: Setting) -> String {
        let ceilings: Vec<String> = self.ceilings.iter().map(|c| format!("{c}")).collect();
        let (first, second) = self.trials.split_at(ORDERS.len() * self.ceilings.len());
        let per_order = |trials: &[Trial], per: usize| -> String {
            let texts: Vec<String> = ORDERS
                .iter()
                .zip(trials.chunks(per))
                .map(|(order, trials)| {
                    let ious: Vec<String> = trials.iter().map(trial_text).collect();
                    format!("{} ({})", ious.join(" / "), order.label())
                })
                .collect();
            texts.join(", ")
        };
        let anew = match self.anew_under.as_slice() {
            [] => String::new(),
            under => {
                let under: Vec<String> = under.iter().map(|c| format!("{c}")).collect();
                let ious = per_order(second, under.len());
                format!("; placed anew under {}: {ious}", under.join(" / "))
            }
        };
        format!(
            "trial solves under ceilings {} of the light's height: IoU {}{anew}; kept the design under {}, {}{}",
            ceilings.join(" / "),
            per_order(first, self.ceilings.len()),
            kept.ceiling,
            kept.order.label(),
            if kept.replace { ", placed anew" } else { "" }
        )
    }
}

/// One trial as [`Found::trials_line`] writes it.
fn trial_text(trial: &Trial) -> String {
    match trial {
        Trial::Solved(Some(s)) => format!(
            "{:.4}{}{}",
            s.iou,
            if s.clear { "" } else { " (contact)" },
            if s.finished() {
                String::new()
            } else {
                format!(" (raced out after {} of {} stages)", s.stages.0, s.stages.1)
            }
        ),
        Trial::Solved(None) | Trial::Failed => "-".to_string(),
        Trial::Same => "same".to_string(),
    }
}
