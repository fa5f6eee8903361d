//! Several shadows per sample: a sample's image energy is a weighted sum over a set of
//! evaluations, each an (instant, target, launch perturbation, physics) tuple.
//!
//! Main types: [`Plan`] (the evaluation set of a [`Problem`]: its [`Instant`]s, the
//! [`Physics`], the [`Robust`] launch errors and whether launch positions are free),
//! [`FrameIou`] (the IoU at one frame, for reports) and the per-worker [`Scratch`].
//!
//! The set is built from the scene and the solve's options:
//! - **instants**: every picture at its `t` (`targets` in the scene), and with `hold`
//!   the instants of the window around it; each picture's weight is split evenly over
//!   its instants, and the weights sum to 1;
//! - **physics**: the exact vacuum flight, or the centre of mass flown through air
//!   ([`crate::sim::drag`]; `bsa solve --air`), for every flight, contacts included;
//! - **launch perturbations**: the nominal launch, and with [`Robust`] `draws` launches
//!   perturbed by the budget's error model ([`crate::sim::launch_error`]), drawn from a
//!   seed the optimiser gives per iteration (common random numbers: every candidate of an
//!   iteration meets the same errors, so their ranking is not noise).
//!
//! Data flow of one sample ([`Problem::evaluate_plan`]): the nominal launch is flown to
//! the horizon (the last instant) and its first contact found, so contacts are forbidden
//! before the last instant; the shadow at every instant is scored against its picture
//! (image terms, hints, barrier) and summed with the instants' weights; with `Robust`, the
//! image and scene terms are instead the mean (or a quantile) over the perturbed
//! launches, each flown freely (as the budget's Monte Carlo does). The contact and
//! regularization terms are the nominal launch's. The reported IoU is the worst
//! instant's of the nominal launch.
//!
//! A scene with one picture, no hold, vacuum, no errors and fixed positions never comes
//! here: [`Plan::simple`] keeps the plain path, bit for bit.

use glam::{DQuat, DVec3};

use super::{Evaluation, Held, HeldMask, Problem, Workspace};
use crate::energy::{self, Term, Weights, TERM_COUNT};
use crate::geometry::distance::{signed_distance, table_signed_distance};
use crate::scene::{Hint, HoldObjective, Launch, LaunchPositions, Scene, Stage};
use crate::sim::drag::{BodyDrag, DragConfig};
use crate::sim::flight::{integrate_grids, FreeFlight, LaunchState};
use crate::sim::launch_error::{draw_errors, BodyError, Tolerances};

/// Position values per occluder in the parameter vector when launch positions are free:
/// the offset `(dx, dy)` (m) of its launch position on the table from the scene's.
pub const POSITION_LEN: usize = 2;

/// The draw seed [`Problem::evaluate`] uses: a fixed set of perturbed launches, against
/// which samples from different iterations compare.
pub const REFERENCE_DRAW: u64 = 0x005E_ED0F_BE57;

/// Depth (m) below which two bodies' launch poses count as overlapping (the scene
/// validation's tolerance for resting contact).
const LAUNCH_OVERLAP: f64 = 1e-4;

/// The energy of a launch that breaks the rules of free positions, per broken rule, and
/// per 10 cm of overlap or of overhang past the table's edge: far above any real energy,
/// so that such a sample ranks after every valid one, and the least broken first.
const LAUNCH_PENALTY: f64 = 1e9;

/// One shadow a sample is scored on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instant {
    /// When (s after the launch).
    pub t: f64,
    /// Which picture (index into `Scene::pictures`).
    pub picture: usize,
    /// Its share of the image energy (the weights of a plan sum to 1).
    pub weight: f64,
}

/// The physics every flight of a sample follows.
#[derive(Clone, Debug, PartialEq)]
pub enum Physics {
    /// Exact free flight in a vacuum.
    Vacuum,
    /// The centre of mass flown through air (the budget's drag model); `bodies` holds
    /// each occluder's drag coefficients.
    Air {
        config: DragConfig,
        bodies: Vec<BodyDrag>,
    },
}

/// Optimise under the launcher's errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Robust {
    /// 1-sigma launch errors, as `bsa budget` takes them.
    pub tolerances: Tolerances,
    /// Perturbed launches per sample.
    pub draws: usize,
    /// Perturbed launches of the reference set ([`REFERENCE_DRAW`]), on which samples of
    /// different iterations are compared: larger than `draws`, so that the best kept is
    /// not the one that was lucky with a small set.
    pub reference_draws: usize,
    /// `None`: the mean image energy over the draws; `Some(q)`: its `q`-quantile.
    pub quantile: Option<f64>,
}

/// The evaluation set of a problem.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// In evaluation order: the instant at the scene's `t` last.
    pub instants: Vec<Instant>,
    /// The last instant (s): flights, contacts and landings run to it.
    pub horizon: f64,
    pub physics: Physics,
    pub robust: Option<Robust>,
    /// Launch positions are optimised too ([`POSITION_LEN`] values per occluder after
    /// the launch values).
    pub free_positions: bool,
    /// A picture's image energy is its worst instant's (`hold.objective` "worst"), not
    /// the weighted sum.
    pub worst: bool,
}

impl Plan {
    /// The plan a scene asks for: its pictures (and hold window), in a vacuum, with
    /// exact launches.
    pub fn of(scene: &Scene) -> Plan {
        let mut instants = Vec::new();
        let last = scene.pictures.len() - 1;
        for (p, pic) in scene.pictures.iter().enumerate() {
            let offsets = scene.hold.as_ref().map_or(vec![0.0], |h| h.offsets());
            let w = pic.weight / offsets.len() as f64;
            for dt in offsets {
                instants.push(Instant {
                    t: pic.t + dt,
                    picture: p,
                    weight: w,
                });
            }
        }
        // The scene's own instant last, so that a workspace ends with its shadow.
        if let Some(k) = instants
            .iter()
            .position(|i| i.picture == last && i.t == scene.t)
        {
            let own = instants.remove(k);
            instants.push(own);
        }
        Plan {
            horizon: scene.horizon(),
            instants,
            physics: Physics::Vacuum,
            robust: None,
            free_positions: scene.positions == LaunchPositions::Free,
            worst: scene
                .hold
                .as_ref()
                .is_some_and(|h| h.objective == HoldObjective::Worst),
        }
    }

    /// Whether a sample is the plain one: one shadow at `t`, vacuum, exact launch, fixed
    /// positions.
    pub fn simple(&self) -> bool {
        self.instants.len() == 1
            && self.physics == Physics::Vacuum
            && self.robust.is_none()
            && !self.free_positions
    }

    /// Evaluations (shadows) per sample.
    pub fn shadows_per_sample(&self) -> usize {
        self.instants.len() * (1 + self.robust.map_or(0, |r| r.draws))
    }
}

/// The IoU at one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameIou {
    pub t: f64,
    pub picture: usize,
    pub iou: f64,
}

/// Per-worker buffers of the multi-evaluation.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    flights: Vec<FreeFlight>,
    errors: Vec<BodyError>,
    totals: Vec<f64>,
    /// The image energy of every instant of one launch (plan order).
    energies: Vec<f64>,
}

impl Scratch {
    pub(super) fn new(n: usize, plan: &Plan) -> Scratch {
        let draws = plan.robust.map_or(0, |r| r.draws.max(r.reference_draws));
        Scratch {
            flights: (0..if draws > 0 { n } else { 0 })
                .map(|_| FreeFlight::default())
                .collect(),
            errors: vec![BodyError::default(); n],
            totals: Vec::with_capacity(draws),
            energies: vec![0.0; plan.instants.len()],
        }
    }
}

impl Held {
    /// The held part of a stage, scored with the stage's hold objective (when it gives
    /// one; else the scene's).
    pub fn for_stage(mut self, stage: &Stage) -> Held {
        if let Some(o) = stage.objective {
            self.worst = o == HoldObjective::Worst;
        }
        self
    }
}

/// What a stage holds fixed at one instant: the held occluders' poses and shadow.
pub struct HeldInstant {
    poses: Vec<(DVec3, DQuat)>,
    mask: HeldMask,
}

/// The image and scene terms (those summed over instants).
const IMAGE_AND_SCENE: [Term; 8] = [
    Term::D0,
    Term::D1,
    Term::D2,
    Term::Xor,
    Term::Inner,
    Term::Outer,
    Term::Hint,
    Term::Barrier,
];

impl Problem {
    /// Number of values in a full parameter vector: six launch values per occluder, and
    /// with free positions [`POSITION_LEN`] more per occluder after them.
    pub fn variable_count(&self) -> usize {
        let n = self.scene.occluders.len();
        Launch::LEN * n
            + if self.plan.free_positions {
                POSITION_LEN * n
            } else {
                0
            }
    }

    /// Number of values CMA-ES searches in a stage varying the occluders `vary`.
    pub fn stage_variable_count(&self, vary: &[usize]) -> usize {
        let per = Launch::LEN
            + if self.plan.free_positions {
                POSITION_LEN
            } else {
                0
            };
        per * vary.len()
    }

    /// The stage's search vector for the full vector `params`: the varying occluders'
    /// launch values, then their position offsets (free positions).
    pub fn stage_start(&self, params: &[f64], vary: &[usize], x: &mut [f64]) {
        for (k, &i) in vary.iter().enumerate() {
            Launch::copy(params, i, x, k);
        }
        if self.plan.free_positions {
            let (n, m) = (self.scene.occluders.len(), vary.len());
            for (k, &i) in vary.iter().enumerate() {
                let (src, dst) = (position_slot(n, i), position_slot(m, k));
                x[dst.clone()].copy_from_slice(&params[src]);
            }
        }
    }

    /// The start of the search: the scene's start guess, at the scene's positions.
    pub fn start_parameters(&self) -> Vec<f64> {
        let mut p = self.scene.start_parameters();
        p.resize(self.variable_count(), 0.0);
        p
    }

    /// Occluder `i`'s launch state for the parameters `params` (its position moved by its
    /// offset when positions are free).
    pub fn launch_state(&self, params: &[f64], i: usize) -> LaunchState {
        let o = &self.scene.occluders[i];
        let mut s = LaunchState::of(o, Launch::get(params, i));
        if self.plan.free_positions {
            s.origin = self.launch_position(params, i);
        }
        s
    }

    /// Occluder `i`'s body origin at launch.
    pub fn launch_position(&self, params: &[f64], i: usize) -> DVec3 {
        let o = &self.scene.occluders[i];
        if !self.plan.free_positions || !o.launched {
            return o.position;
        }
        let d = &params[position_slot(self.scene.occluders.len(), i)];
        o.position + DVec3::new(d[0], d[1], 0.0)
    }

    /// The position part of [`Problem::expand`]: the varying occluders' offsets from `x`.
    pub(super) fn expand_positions(&self, vary: &[usize], x: &[f64], out: &mut [f64]) {
        if !self.plan.free_positions {
            return;
        }
        let (n, m) = (self.scene.occluders.len(), vary.len());
        for (k, &i) in vary.iter().enumerate() {
            out[position_slot(n, i)].copy_from_slice(&x[position_slot(m, k)]);
        }
    }

    /// Air in the loop: every flight's centre of mass flies through air with `config`.
    pub fn set_air(&mut self, config: DragConfig) {
        let bodies = self
            .scene
            .occluders
            .iter()
            .map(|o| BodyDrag::new(&o.shape, o.mass.mass, &config))
            .collect();
        self.plan.physics = Physics::Air { config, bodies };
    }

    /// Optimise under launch errors.
    pub fn set_robust(&mut self, robust: Robust) {
        self.plan.robust = Some(robust);
    }

    /// Start occluder `i`'s flight in `flight` for launch `state` with the plan's physics
    /// (drag coefficient off by `1 + cd_error`), up to `t_max`. The caller integrates the
    /// grids of the flights it started with [`integrate_grids`], side by side.
    pub(super) fn start_flight(
        &self,
        flight: &mut FreeFlight,
        i: usize,
        state: LaunchState,
        cd_error: f64,
        t_max: f64,
    ) {
        let o = &self.scene.occluders[i];
        flight.reset_without_grid(&o.mass, state, self.scene.gravity, t_max, &self.flight);
        if let Physics::Air { config, bodies } = &self.plan.physics {
            let body = if cd_error != 0.0 {
                bodies[i].with_cd_factor(1.0 + cd_error)
            } else {
                bodies[i]
            };
            flight.set_drag(&body, config.max_step);
        }
    }

    /// The per-instant part of [`Problem::hold`]: the held occluders' poses and shadow at
    /// every instant of the plan (after `hold` has flown them into `ws`).
    pub(super) fn hold_instants(&self, kept: &[bool], ws: &mut Workspace) -> Vec<HeldInstant> {
        if self.plan.simple() {
            return Vec::new();
        }
        let mut out = Vec::with_capacity(self.plan.instants.len());
        for inst in &self.plan.instants {
            for (i, _) in kept.iter().enumerate().filter(|(_, k)| **k) {
                ws.poses[i] = self.state_at(ws, i, inst.t).0;
            }
            self.shadow_only(kept, ws);
            out.push(HeldInstant {
                poses: ws.poses.clone(),
                mask: HeldMask::new(ws.mask.clone()),
            });
        }
        out
    }

    /// [`Problem::evaluate_held`] with the perturbed launches of a robust plan drawn from
    /// `draw` (the optimiser's per-iteration seed); other plans ignore it.
    pub fn evaluate_held_draw(
        &self,
        held: &Held,
        params: &[f64],
        weights: &Weights,
        draw: u64,
        ws: &mut Workspace,
    ) -> Evaluation {
        self.evaluate_sample(Some(held), params, weights, draw, ws)
    }

    /// One sample under the plan (see the module docs); `draw` seeds the perturbed
    /// launches.
    pub(super) fn evaluate_plan(
        &self,
        held: Option<&Held>,
        params: &[f64],
        weights: &Weights,
        draw: u64,
        ws: &mut Workspace,
    ) -> Evaluation {
        let n = self.scene.occluders.len();
        let outcome = self.land(held, ws);
        let (bad, depth) = if self.plan.free_positions {
            self.launch_violations(held, params)
        } else {
            (0, 0.0)
        };
        let launch_penalty = LAUNCH_PENALTY * (bad as f64 + 10.0 * depth);
        let worst_objective = held.map_or(self.plan.worst, |h| h.worst);
        let mut raw = [0.0; TERM_COUNT];
        let mut image_total = None;
        if let Some(robust) = self.plan.robust {
            let run = (&robust, worst_objective, draw);
            image_total = Some(self.robust_terms(run, params, weights, ws, &mut raw));
        }
        let mut worst = f64::INFINITY;
        let mut own = [0.0; TERM_COUNT];
        let mut energies = std::mem::take(&mut ws.multi.energies);
        for (k, inst) in self.plan.instants.iter().enumerate() {
            for i in 0..n {
                ws.poses[i] = match held {
                    Some(h) if !h.varying[i] => h.instants[k].poses[i],
                    _ => self.state_at(ws, i, inst.t).0,
                };
            }
            self.shadow_with(
                held.map(|h| &h.instants[k].mask),
                held.map(|h| &h.varying[..]),
                ws,
            );
            let (iou, e) = self.score_instant(inst, weights, ws, &mut own);
            energies[k] = e;
            worst = worst.min(iou);
        }
        if image_total.is_none() {
            for t in IMAGE_AND_SCENE {
                raw[t as usize] = own[t as usize];
            }
            if worst_objective {
                image_total = Some(self.image_energy(&energies));
            }
        }
        ws.multi.energies = energies;
        self.physics_terms(params, &outcome, &mut raw, None);
        // The image energy of the `worst` objective or of launch errors replaces the
        // weighted sum of the instants.
        let total = match image_total {
            None => energy::weighted_total(&raw, weights),
            Some(image) => {
                let mut physics = [0.0; TERM_COUNT];
                physics[Term::Contact as usize] = raw[Term::Contact as usize];
                physics[Term::Reg as usize] = raw[Term::Reg as usize];
                image + energy::weighted_total(&physics, weights)
            }
        } + launch_penalty;
        let total = if total.is_finite() {
            total.min(energy::DIVERGED_ENERGY)
        } else {
            energy::DIVERGED_ENERGY
        };
        Evaluation {
            raw,
            total,
            outcome,
            iou: worst,
        }
    }

    /// The image and scene terms of the shadow in `ws.mask` (poses in `ws.poses`) at
    /// `inst`, times its weight, added to `raw`; returns its IoU and its own weighted
    /// image and scene energy.
    fn score_instant(
        &self,
        inst: &Instant,
        weights: &Weights,
        ws: &Workspace,
        raw: &mut [f64; TERM_COUNT],
    ) -> (f64, f64) {
        let target = &self.pictures[inst.picture];
        let mut r = [0.0; TERM_COUNT];
        energy::image_terms(target, &ws.mask, weights, &mut r);
        let hints = &self.scene.pictures[inst.picture].hints;
        self.hint_and_barrier(hints, target, ws, &mut r, None);
        for t in IMAGE_AND_SCENE {
            raw[t as usize] += inst.weight * r[t as usize];
        }
        (
            energy::iou(&ws.mask, &target.mask),
            energy::weighted_total(&r, weights),
        )
    }

    /// The image energy of a launch whose instants have the energies `e` (plan order)
    /// under the `worst` objective: every picture's worst instant, weighted by the
    /// picture.
    fn image_energy(&self, e: &[f64]) -> f64 {
        let mut total = 0.0;
        for p in 0..self.scene.pictures.len() {
            let (mut worst, mut weight) = (f64::NEG_INFINITY, 0.0);
            for (inst, &ek) in self.plan.instants.iter().zip(e) {
                if inst.picture == p {
                    worst = worst.max(ek);
                    weight += inst.weight;
                }
            }
            if weight > 0.0 {
                total += weight * worst;
            }
        }
        total
    }

    /// The robust image and scene terms: their mean over `robust.draws` perturbed
    /// launches (drawn from `draw`) into `raw`; returns the weighted image energy the
    /// sample is ranked by (the mean, or the quantile; each launch's energy under the
    /// `worst` hold objective if asked).
    fn robust_terms(
        &self,
        (robust, worst, draw): (&Robust, bool, u64),
        params: &[f64],
        weights: &Weights,
        ws: &mut Workspace,
        raw: &mut [f64; TERM_COUNT],
    ) -> f64 {
        let draws = if draw == REFERENCE_DRAW {
            robust.reference_draws
        } else {
            robust.draws
        };
        let scale = 1.0 / draws as f64;
        let mut scratch = std::mem::take(&mut ws.multi);
        scratch.totals.clear();
        for s in 0..draws {
            draw_errors(draw, s as u64, &robust.tolerances, &mut scratch.errors);
            let mut diverged = false;
            for (i, o) in self.scene.occluders.iter().enumerate() {
                if !o.launched {
                    continue;
                }
                let e = scratch.errors[i];
                let state = e.apply(self.launch_state(params, i));
                diverged |= !(state.velocity.is_finite() && state.angular_velocity.is_finite());
                let t_max = self.plan.horizon + e.timing.abs();
                self.start_flight(&mut scratch.flights[i], i, state, e.cd, t_max);
            }
            integrate_grids(&mut scratch.flights);
            let mut mine = [0.0; TERM_COUNT];
            for (k, inst) in self.plan.instants.iter().enumerate() {
                for (i, o) in self.scene.occluders.iter().enumerate() {
                    ws.poses[i] = if o.launched {
                        scratch.flights[i].pose(inst.t - scratch.errors[i].timing)
                    } else {
                        (o.position, o.orientation)
                    };
                }
                self.shadow(ws);
                scratch.energies[k] = self.score_instant(inst, weights, ws, &mut mine).1;
            }
            let total = if diverged {
                energy::DIVERGED_ENERGY
            } else if worst {
                self.image_energy(&scratch.energies)
            } else {
                energy::weighted_total(&mine, weights)
            };
            scratch.totals.push(total);
            for t in IMAGE_AND_SCENE {
                raw[t as usize] += scale * mine[t as usize];
            }
        }
        let image = match robust.quantile {
            None => scratch.totals.iter().sum::<f64>() * scale,
            Some(q) => {
                scratch.totals.sort_by(f64::total_cmp);
                let h = (scratch.totals.len() - 1) as f64 * q;
                let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
                let (a, b) = (scratch.totals[lo], scratch.totals[hi]);
                a + (h - lo as f64) * (b - a)
            }
        };
        ws.multi = scratch;
        image
    }

    /// Launches that break the rules of free positions: a body whose footprint leaves
    /// the table's top, or two bodies overlapping at launch (at least one of them
    /// varying). Returns how many rules are broken and by how much in all (m of overhang
    /// or overlap).
    pub fn launch_violations(&self, held: Option<&Held>, params: &[f64]) -> (u32, f64) {
        let scene = &self.scene;
        let Some(table) = &scene.table else {
            return (0, 0.0);
        };
        let varies = |i: usize| held.is_none_or(|h| h.varying[i]);
        let n = scene.occluders.len();
        let mut bad = 0;
        let mut depth = 0.0;
        for i in 0..n {
            let o = &scene.occluders[i];
            if !o.launched || !varies(i) {
                continue;
            }
            let c = self.launch_position(params, i) + o.orientation * o.mass.local_com;
            let d = (c - table.center).abs();
            let over = (d.x + o.bounding_radius - table.half_extents.x)
                .max(d.y + o.bounding_radius - table.half_extents.y);
            if over > 0.0 {
                bad += 1;
                depth += over;
                continue;
            }
            if let Some(ts) = &self.table_shape {
                let p = self.launch_position(params, i);
                let d = table_signed_distance(&self.shapes[i], p, o.orientation, table, ts);
                if d < -LAUNCH_OVERLAP {
                    bad += 1;
                    depth -= d;
                }
            }
        }
        for i in 0..n {
            for j in (i + 1)..n {
                if !(varies(i) || varies(j)) {
                    continue;
                }
                let (a, b) = (&scene.occluders[i], &scene.occluders[j]);
                let (pa, pb) = (
                    self.launch_position(params, i),
                    self.launch_position(params, j),
                );
                let (ca, cb) = (
                    pa + a.orientation * a.mass.local_com,
                    pb + b.orientation * b.mass.local_com,
                );
                if ca.distance(cb) > a.bounding_radius + b.bounding_radius {
                    continue;
                }
                let d = signed_distance(
                    &self.shapes[i],
                    pa,
                    a.orientation,
                    &self.shapes[j],
                    pb,
                    b.orientation,
                );
                if d < -LAUNCH_OVERLAP {
                    bad += 1;
                    depth -= d;
                }
            }
        }
        (bad, depth)
    }

    /// The hint and barrier terms of the poses in `ws.poses` for `hints` and `target`;
    /// with `held` (the scene's own hints and target only), the held occluders' shares
    /// as it keeps them.
    pub(super) fn hint_and_barrier(
        &self,
        hints: &[Hint],
        target: &energy::TargetData,
        ws: &Workspace,
        raw: &mut [f64; TERM_COUNT],
        held: Option<&Held>,
    ) {
        let mut hint = 0.0;
        for (k, h) in hints.iter().enumerate() {
            hint += match held {
                Some(held) if !held.varying[h.occluder] => held.terms.hints[k],
                _ => self.hint_term(h, target, ws.poses[h.occluder]),
            };
        }
        raw[Term::Hint as usize] = hint;
        let mut barrier = 0.0;
        for (i, &pose) in ws.poses.iter().enumerate() {
            barrier += match held {
                Some(held) if !held.varying[i] => held.terms.barrier[i],
                _ => self.barrier_term(target, i, pose),
            };
        }
        raw[Term::Barrier as usize] = barrier;
    }

    /// Hint `h`'s share of the hint term, its occluder at `(p, q)`.
    pub(super) fn hint_term(
        &self,
        h: &Hint,
        target: &energy::TargetData,
        (p, q): (DVec3, DQuat),
    ) -> f64 {
        let world = p + q * h.point;
        h.weight * target.hint_distance(self.scene.camera.project(world), h.pixel)
    }

    /// Occluder `i`'s share of the barrier term at `(p, q)`.
    pub(super) fn barrier_term(
        &self,
        target: &energy::TargetData,
        i: usize,
        (p, q): (DVec3, DQuat),
    ) -> f64 {
        let local_com = self.scene.occluders[i].mass.local_com;
        target.barrier(self.scene.camera.project(p + q * local_com))
    }

    /// The IoU of the nominal launch `params` at every frame the reports show: every
    /// picture's instant, and with `hold` every frame of its window; in time order.
    pub fn frame_ious(&self, params: &[f64], ws: &mut Workspace) -> Vec<FrameIou> {
        let mut out = Vec::new();
        self.fly(params, ws);
        for (p, pic) in self.scene.pictures.iter().enumerate() {
            let offsets = self
                .scene
                .hold
                .as_ref()
                .map_or(vec![0.0], |h| h.frame_offsets());
            for dt in offsets {
                let t = pic.t + dt;
                self.shadow_at(t, ws);
                out.push(FrameIou {
                    t,
                    picture: p,
                    iou: energy::iou(&ws.mask, &self.pictures[p].mask),
                });
            }
        }
        out
    }

    /// The shadow at `time` (0 <= time <= the horizon) of the flight last flown into `ws`
    /// ([`Problem::fly`]): poses into `ws.poses`, shadow into `ws.mask`.
    pub fn shadow_at(&self, time: f64, ws: &mut Workspace) {
        for i in 0..self.scene.occluders.len() {
            ws.poses[i] = self.state_at(ws, i, time).0;
        }
        self.shadow(ws);
    }
}

/// Where occluder `i`'s position offsets sit in a vector of `n` occluders' values.
fn position_slot(n: usize, i: usize) -> std::ops::Range<usize> {
    let start = Launch::LEN * n + POSITION_LEN * i;
    start..start + POSITION_LEN
}
