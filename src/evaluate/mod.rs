//! One sample: launch velocities in, energy out.
//!
//! Main types: [`Problem`] (a [`Scene`] plus everything derived from it once: target
//! boundary masks and moments, contact shapes), [`Workspace`] (per-worker buffers, so
//! that evaluating a sample allocates nothing), [`Outcome`] (what the flight did) and
//! [`Evaluation`] (the ten raw terms, the weighted total, IoU).
//!
//! Data flow of [`Problem::evaluate`]:
//! 1. exact free flight of every launched body from its launch pose ([`FreeFlight`]);
//! 2. first contact between bodies, or of a launched body with the table, before `t`
//!    ([`crate::sim::contact`]) gives `t_sim` and `n_contact`;
//! 3. poses at `t`: the bodies carry on by free flight after the stop (the contact only
//!    costs its penalty), and a body that lands stays on the table (its vertical motion
//!    is absorbed, its horizontal motion and spin go on), so it is never lost under it;
//! 4. the exact shadow at `t` into a bit mask ([`crate::shadow::raster`]);
//! 5. the energy terms ([`crate::energy`]).
//!
//! Taking the shadow at `t` rather than at the stop matters: the field notes record that
//! CMA-ES otherwise learns to collide within milliseconds and freeze a good picture.
//!
//! The numeric core does not fail: non-finite launch values or a diverged flight give
//! [`DIVERGED_ENERGY`], never an error.
//!
//! A scene with several pictures, a hold window, air in the loop, launch errors or free
//! launch positions scores several shadows per sample: see [`instants`].
//!
//! The contact search of steps 2 and 3 is in `contacts`, the shadow of step 4 in
//! `shadow`.

use glam::{DQuat, DVec3};

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::energy::{
    self, ImageSums, TargetData, Term, Weights, DIVERGED_ENERGY, REG_ALPHA, TERM_COUNT,
};
use crate::geometry::distance::{table_shape, ContactShape};
use crate::geometry::shape::Shape;
use crate::scene::{Launch, Scene};
use crate::shadow::mask::Mask;
use crate::shadow::raster::{MeshSilhouette, RasterScratch, ShadowCamera};
use crate::sim::contact::BallStart;
use crate::sim::flight::{integrate_grids, FlightConfig, FreeFlight};

mod batch;
mod contacts;
pub mod instants;
mod shadow;

pub use batch::MAX_BATCH;
pub use instants::{FrameIou, Instant, Physics, Plan, Robust, REFERENCE_DRAW};

pub use crate::scene::MAX_TURN;

/// The most worker threads a solve or a budget may ask for: each holds a workspace of
/// its own (masks, flights), and beyond the machine's cores more threads only cost (a
/// solve of three blocks took 50 s on 1024 threads of 2 cores, 0.4 s on one).
pub const MAX_THREADS: usize = 256;

/// The phases [`Problem::profile`] times, in the order a sample runs them.
pub const PROFILE_PHASES: [&str; 11] = [
    "flight",
    "contacts",
    "shadow",
    "d0",
    "d1",
    "d2",
    "xor",
    "inner",
    "outer",
    "contact+reg+hint+barrier",
    "sample (all terms)",
];

/// How far the canvas reaches beyond each edge of the picture, at least, as a fraction
/// of the picture's longer side. (A quarter cost Mickey's samples 12 %; an eighth, with
/// the rows' last word filled, costs nothing measurable.)
pub const CANVAS_MARGIN: f64 = 0.125;

/// The margin (pixels, on every side) of the canvas of a `width` x `height` picture:
/// [`CANVAS_MARGIN`] of the longer side, widened so that the canvas's rows fill their
/// last 64-bit word (the words are scanned anyway).
pub fn canvas_margin(width: usize, height: usize) -> usize {
    let least = (CANVAS_MARGIN * width.max(height) as f64).ceil() as usize;
    ((width + 2 * least).next_multiple_of(64) - width) / 2
}

/// A scene plus everything the hot loop derives from it once.
///
/// Shadows are drawn on a canvas larger than the picture by [`canvas_margin`] on every
/// side, and the targets are padded to it: a shadow beyond the picture's edge then counts
/// as shadow where the target has none (in XOR, the moments, the IoU) instead of costing
/// nothing, which had let the solver hide a body it could not place. Every mask a
/// [`Workspace`] holds is a canvas mask; [`Problem::picture_of`] cuts the picture out.
pub struct Problem {
    pub scene: Scene,
    /// The shadow camera of the canvas: `scene.camera` widened by `margin`.
    pub canvas: ShadowCamera,
    /// Pixels of canvas beyond each edge of the picture.
    pub margin: usize,
    /// The target of the scene's `t` (the last picture), on the canvas.
    pub target: TargetData,
    /// Every picture's target, as `scene.pictures`.
    pub pictures: Vec<TargetData>,
    /// What a sample is scored on: instants, physics, launch errors.
    pub plan: Plan,
    pub shapes: Vec<ContactShape>,
    table_shape: Option<ContactShape>,
    /// Whether each mesh is closed and outward-oriented (enables back-face culling).
    closed: Vec<bool>,
    /// Silhouette data of each closed, outward-oriented mesh (the fast shadow path).
    silhouettes: Vec<Option<MeshSilhouette>>,
    pub flight: FlightConfig,
}

/// What [`Held`] keeps of the terms that add up a share per occluder or hint.
struct HeldTerms {
    reg: Vec<f64>,
    barrier: Vec<f64>,
    hints: Vec<f64>,
}

/// Occluder `i`'s share of the regularization: its launch speed and spin.
fn reg_term(params: &[f64], i: usize) -> f64 {
    let Launch {
        velocity: v,
        angular_velocity: w,
    } = Launch::get(params, i);
    REG_ALPHA * v.length() + (1.0 - REG_ALPHA) * w.length()
}

/// Per-worker reusable buffers.
pub struct Workspace {
    flights: Vec<FreeFlight>,
    /// The flights of a batch's later samples ([`Problem::evaluate_held_draws`]), each
    /// swapped into `flights` while its sample is evaluated.
    batch: Vec<Vec<FreeFlight>>,
    pub mask: Mask,
    /// The held shadow `mask` was last drawn over and the rows drawn in (outside them
    /// `mask` is that shadow), while `mask` is written by nothing but
    /// [`Problem::shadow_with`]: a sample over the same held shadow restores those
    /// rows rather than copying it whole.
    over: Option<(u64, Range<usize>)>,
    raster: RasterScratch,
    world_vertices: Vec<DVec3>,
    /// Pose of every occluder at `t` (body origin, orientation), from the last sample.
    pub poses: Vec<(DVec3, DQuat)>,
    /// Time of each body's landing on the table (it stays there), if before t.
    landing: Vec<Option<f64>>,
    /// Time of each body's first table contact (a landing or sinking in), if before t.
    table_hit: Vec<Option<f64>>,
    /// Times of the pair contacts found in the last sample (room for every pair).
    pair_hits: Vec<f64>,
    /// Whether each pair contact searched in the last sample (after the held ones in
    /// `pair_hits`) counts in [`Outcome::own_contact`].
    pair_counts: Vec<bool>,
    /// Each varying body's launch if it is a ball flying without drag, for the pair
    /// searches ([`Held`] has the held ones').
    balls: Vec<Option<BallStart>>,
    /// The varying bodies of the last sample, in order.
    varying: Vec<usize>,
    /// Buffers of the multi-evaluation.
    multi: instants::Scratch,
}

impl Workspace {
    /// Time at which occluder `i` landed on the table (and stayed there) in the last
    /// [`Problem::fly`], if it did before `t`.
    pub fn landing_time(&self, i: usize) -> Option<f64> {
        self.landing[i]
    }
}

/// What happened in flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// Time at which the simulation stopped (= `t` without contact).
    pub t_sim: f64,
    /// Number of contacts at the stop (0 without contact).
    pub n_contacts: u32,
    /// The first contact's participants: (occluder, other occluder or `None` for the table).
    pub first_contact: Option<(usize, Option<usize>)>,
    /// The contact time `(t - t_first) n` of the contacts that involve a body the
    /// evaluation varies (all of them outside a stage): a stage ranks its samples by
    /// what it can change, so that a contact between two held bodies does not make every
    /// sample equally infeasible. 0 without such a contact.
    pub own_contact: f64,
}

/// The energy of one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Evaluation {
    /// Unweighted value of every term (0 for terms that were skipped by weight 0).
    pub raw: [f64; TERM_COUNT],
    /// Weighted total with the weights it was evaluated with.
    pub total: f64,
    pub outcome: Outcome,
    /// Intersection over union of the shadow at `t` and the target.
    pub iou: f64,
}

impl Evaluation {
    /// The evaluation of a sample that diverged (or of none yet): it ranks last.
    pub fn diverged() -> Evaluation {
        Evaluation {
            raw: [f64::NAN; TERM_COUNT],
            total: DIVERGED_ENERGY,
            outcome: Outcome {
                t_sim: 0.0,
                n_contacts: 0,
                first_contact: None,
                own_contact: 0.0,
            },
            iou: 0.0,
        }
    }

    /// Weighted value of each term.
    pub fn weighted(&self, w: &Weights) -> [f64; TERM_COUNT] {
        w.weigh(&self.raw)
    }
}

/// Whether occluder `i` is in the set `which` (everything is in `None`).
fn among(which: Option<&[bool]>, i: usize) -> bool {
    which.is_none_or(|w| w[i])
}

/// A held shadow ([`Held`], [`instants::HeldInstant`]) and a key no other held shadow
/// has, so that a workspace whose mask was drawn over it knows it and restores only the
/// rows it drew in ([`Workspace`]'s `over`) instead of copying the whole shadow again.
pub(crate) struct HeldMask {
    mask: Mask,
    key: u64,
}

impl HeldMask {
    fn new(mask: Mask) -> HeldMask {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        HeldMask {
            mask,
            key: NEXT.fetch_add(1, Ordering::Relaxed),
        }
    }
}

impl std::ops::Deref for HeldMask {
    type Target = Mask;
    fn deref(&self) -> &Mask {
        &self.mask
    }
}

/// What a stage holds fixed, computed once per stage by [`Problem::hold`] so that a
/// sample pays only for what varies ([`Problem::evaluate_held`]): the held occluders'
/// flights, table contacts and poses at `t`, every contact between two of them before
/// `t`, and their shadow.
pub struct Held {
    /// The launch values the held occluders keep.
    base: Vec<f64>,
    /// Whether each occluder varies (is computed per sample).
    varying: Vec<bool>,
    /// Flights of the held launched occluders (the varying ones' are unused).
    flights: Vec<FreeFlight>,
    /// The held balls' launches, for the pair searches ([`BallStart`]).
    balls: Vec<Option<BallStart>>,
    /// The held occluders' shares of the regularization and barrier terms, and the held
    /// hints' of the hint term, as every sample would compute them again.
    terms: HeldTerms,
    poses: Vec<(DVec3, DQuat)>,
    landing: Vec<Option<f64>>,
    table_hit: Vec<Option<f64>>,
    /// Every contact between two held occluders up to `t`: (time, order key, i, j).
    pair_hits: Vec<(f64, usize, usize, usize)>,
    /// The held occluders' shadow at `t`, and its image sums (every term's).
    mask: HeldMask,
    sums: ImageSums,
    /// Held occluders whose contacts with the varying ones do not count in
    /// [`Outcome::own_contact`]: bodies still at their start guess, which a later stage
    /// will move anyway (see [`Held::ignore_contacts_with`]).
    ignored: Vec<bool>,
    /// Their poses and shadow at every instant of the plan (unless it is simple).
    instants: Vec<instants::HeldInstant>,
    /// The stage's hold objective is `worst` ([`Held::for_stage`]).
    worst: bool,
}

impl Held {
    /// The launch values of every occluder that the held ones keep (6 per occluder).
    pub fn base(&self) -> &[f64] {
        &self.base
    }

    /// Let the stage's ranking ignore contacts between a varying body and the held
    /// occluders `i` with `unplaced[i]`: the first pass of the sequential strategy places
    /// one body at a time, and a body still at its start guess is not an obstacle the
    /// body being placed must go around. The contacts still count in the outcome's
    /// `t_sim` and `n_contacts` (the reports), and varying occluders are never ignored.
    pub fn ignore_contacts_with(&mut self, unplaced: &[bool]) {
        for (i, flag) in self.ignored.iter_mut().enumerate() {
            *flag = unplaced[i] && !self.varying[i];
        }
    }
}

impl Problem {
    /// The fixed part of the samples that change only the occluders in `vary`, the
    /// others keeping their launch values in `base`. If `base` holds a value that makes
    /// every sample diverge (non-finite, spinning too fast), nothing is computed: such a
    /// sample is caught before anything held is used.
    pub fn hold(&self, base: &[f64], vary: &[usize]) -> Held {
        let scene = &self.scene;
        let n = scene.occluders.len();
        let mut varying = vec![false; n];
        for &i in vary {
            varying[i] = true;
        }
        let mut ws = self.workspace();
        let mut held = Held {
            base: base.to_vec(),
            varying,
            flights: Vec::new(),
            balls: vec![None; n],
            terms: HeldTerms {
                reg: vec![0.0; n],
                barrier: vec![0.0; n],
                hints: vec![0.0; scene.hints.len()],
            },
            poses: vec![(DVec3::ZERO, DQuat::IDENTITY); n],
            landing: vec![None; n],
            table_hit: vec![None; n],
            pair_hits: Vec::new(),
            mask: HeldMask::new(ws.mask.clone()),
            sums: self.image_sums(&ws.mask, 0..usize::MAX, &Weights::all_ones()),
            ignored: vec![false; n],
            instants: Vec::new(),
            worst: self.plan.worst,
        };
        if base.iter().any(|x| !x.is_finite()) || self.spins_too_fast(base) {
            return held;
        }
        let kept: Vec<bool> = held.varying.iter().map(|v| !v).collect();
        self.launch(Some(&kept), base, &mut ws.flights);
        for i in 0..n {
            if !held.varying[i] {
                held.balls[i] = BallStart::of(&self.body(i, &ws.flights));
                (held.landing[i], held.table_hit[i]) = self.table_contact(i, &ws.flights);
                ws.landing[i] = held.landing[i];
                held.poses[i] = self.state_at(&ws, i, scene.t).0;
                ws.poses[i] = held.poses[i];
            }
            for j in (i + 1)..n {
                let both_fixed = !scene.occluders[i].launched && !scene.occluders[j].launched;
                if held.varying[i] || held.varying[j] || both_fixed {
                    continue;
                }
                if let Some(tc) =
                    self.pair_contact(i, &ws.flights, j, &ws.flights, self.plan.horizon)
                {
                    held.pair_hits.push((tc, contacts::pair_key(n, i, j), i, j));
                }
            }
        }
        for i in (0..n).filter(|&i| !held.varying[i]) {
            held.terms.reg[i] = reg_term(base, i);
            held.terms.barrier[i] = self.barrier_term(&self.target, i, held.poses[i]);
        }
        for (k, h) in scene.hints.iter().enumerate() {
            if !held.varying[h.occluder] {
                held.terms.hints[k] = self.hint_term(h, &self.target, held.poses[h.occluder]);
            }
        }
        self.shadow_with(None, Some(&kept), &mut ws);
        held.mask = HeldMask::new(ws.mask.clone());
        held.sums = self.image_sums(&held.mask, 0..usize::MAX, &Weights::all_ones());
        held.instants = self.hold_instants(&kept, &mut ws);
        held.flights = std::mem::take(&mut ws.flights);
        held
    }

    pub fn new(scene: Scene) -> Problem {
        let margin = canvas_margin(scene.target.width(), scene.target.height());
        let canvas = scene.camera.widened(margin);
        let target = TargetData::on_canvas(&scene.target, margin);
        let pictures = if scene.pictures.len() == 1 {
            vec![target.clone()]
        } else {
            scene
                .pictures
                .iter()
                .map(|p| TargetData::on_canvas(&p.target, margin))
                .collect()
        };
        let plan = Plan::of(&scene);
        let shapes = scene
            .occluders
            .iter()
            .map(|o| ContactShape::new(&o.shape))
            .collect();
        let closed = scene
            .occluders
            .iter()
            .map(|o| match &o.shape {
                Shape::Mesh(m) => m.is_closed_and_oriented() && m.signed_volume() > 0.0,
                _ => true,
            })
            .collect();
        let table_shape = scene.table.as_ref().map(table_shape);
        let silhouettes = scene
            .occluders
            .iter()
            .zip(&closed)
            .map(|(o, &closed)| match &o.shape {
                Shape::Mesh(m) if closed => MeshSilhouette::new(&m.vertices, &m.triangles),
                _ => None,
            })
            .collect();
        Problem {
            scene,
            canvas,
            margin,
            target,
            pictures,
            plan,
            shapes,
            table_shape,
            closed,
            silhouettes,
            flight: FlightConfig::default(),
        }
    }

    /// The picture's part of a canvas mask (a shadow drawn by this problem).
    pub fn picture_of(&self, canvas_mask: &Mask) -> Mask {
        canvas_mask.cropped(self.margin)
    }

    /// A fresh workspace for one worker thread.
    pub fn workspace(&self) -> Workspace {
        let n = self.scene.occluders.len();
        let max_vertices = self
            .scene
            .occluders
            .iter()
            .map(|o| match &o.shape {
                Shape::Mesh(m) => m.vertices.len(),
                _ => 8,
            })
            .max()
            .unwrap_or(8);
        Workspace {
            flights: (0..n).map(|_| FreeFlight::default()).collect(),
            batch: (1..MAX_BATCH)
                .map(|_| (0..n).map(|_| FreeFlight::default()).collect())
                .collect(),
            mask: Mask::new(self.canvas.width_px, self.canvas.height_px),
            over: None,
            raster: RasterScratch::default(),
            world_vertices: Vec::with_capacity(max_vertices),
            poses: vec![(DVec3::ZERO, DQuat::IDENTITY); n],
            landing: vec![None; n],
            table_hit: vec![None; n],
            pair_hits: Vec::with_capacity(n * n.saturating_sub(1) / 2),
            pair_counts: Vec::with_capacity(n * n.saturating_sub(1) / 2),
            balls: vec![None; n],
            varying: Vec::with_capacity(n),
            multi: instants::Scratch::new(n, &self.plan),
        }
    }

    /// The memory one [`Workspace`] takes (bytes), about: its shadow mask, a pose per body
    /// and a flight per body and sample of a batch (an asymmetric body's grid of
    /// orientations, a few hundred), and the pair contacts.
    pub fn workspace_bytes(&self) -> usize {
        let n = self.scene.occluders.len();
        let mask = Mask::new(1, 1);
        let words = self.canvas.width_px.div_ceil(64) * self.canvas.height_px;
        std::mem::size_of::<Workspace>()
            + std::mem::size_of_val(&mask)
            + 8 * words
            + MAX_BATCH * n * (std::mem::size_of::<FreeFlight>() + 32 * 300 + 64)
            + 9 * n * n.saturating_sub(1) / 2
    }

    /// Evaluate one sample. `params` holds 6 values per occluder (`v` then `w`); values of
    /// non-launched occluders are ignored. Terms with weight 0 are skipped.
    pub fn evaluate(&self, params: &[f64], weights: &Weights, ws: &mut Workspace) -> Evaluation {
        self.evaluate_sample(None, params, weights, REFERENCE_DRAW, ws)
    }

    /// [`Problem::evaluate`] of a sample that differs from `held`'s base only in the
    /// occluders `held` lets vary: the held occluders' flights, contacts among them, poses
    /// and shadow come from `held`, so only the varying ones are flown, checked and drawn.
    /// The result is the same, bit for bit, as `evaluate` on the same `params`.
    pub fn evaluate_held(
        &self,
        held: &Held,
        params: &[f64],
        weights: &Weights,
        ws: &mut Workspace,
    ) -> Evaluation {
        debug_assert!(
            (0..self.scene.occluders.len())
                .filter(|&i| !held.varying[i])
                .all(|i| Launch::get(params, i) == Launch::get(&held.base, i)),
            "a held occluder's launch values differ from the held base"
        );
        self.evaluate_sample(Some(held), params, weights, REFERENCE_DRAW, ws)
    }

    pub(super) fn evaluate_sample(
        &self,
        held: Option<&Held>,
        params: &[f64],
        weights: &Weights,
        draw: u64,
        ws: &mut Workspace,
    ) -> Evaluation {
        if !self.launchable(params) {
            return Evaluation::diverged();
        }
        self.launch(held.map(|h| &h.varying[..]), params, &mut ws.flights);
        self.evaluate_launched(held, params, weights, draw, ws)
    }

    /// About how many rows [`energy::image_terms`] scans for the shadow `mask`: those of
    /// the shadow and of the target's outer band (which holds the target).
    fn scanned_rows(&self, mask: &Mask) -> usize {
        let (a, b) = (mask.row_range(), self.target.outer.row_range());
        match (a.is_empty(), b.is_empty()) {
            (true, _) => b.len(),
            (false, true) => a.len(),
            (false, false) => a.end.max(b.end) - a.start.min(b.start),
        }
    }

    /// The image sums of `mask` over `rows` that `weights` and the IoU need.
    fn image_sums(&self, mask: &Mask, rows: Range<usize>, weights: &Weights) -> ImageSums {
        ImageSums::of(&self.target, mask, rows, weights, true)
    }

    /// Whether a sample can be flown: every value finite, and no body spun past
    /// [`MAX_TURN`] (an evaluation of one that cannot is [`Evaluation::diverged`]).
    fn launchable(&self, params: &[f64]) -> bool {
        debug_assert_eq!(params.len(), self.variable_count());
        params.iter().all(|x| x.is_finite()) && !self.spins_too_fast(params)
    }

    /// The rest of [`Problem::evaluate_sample`] once its varying flights are in `ws`.
    fn evaluate_launched(
        &self,
        held: Option<&Held>,
        params: &[f64],
        weights: &Weights,
        draw: u64,
        ws: &mut Workspace,
    ) -> Evaluation {
        if !self.plan.simple() {
            return self.evaluate_plan(held, params, weights, draw, ws);
        }
        let outcome = self.land(held, ws);
        let drawn = self.shadow_with(held.map(|h| &h.mask), held.map(|h| &h.varying[..]), ws);
        let mut raw = [0.0; TERM_COUNT];
        let counts = match (held, drawn) {
            // The held shadow's sums with the rows the sample drew in replaced: only those
            // rows are counted again (twice: before and after), and the sums are exact
            // integers, so the terms are those of the whole mask, bit for bit. Where the
            // rows drawn are half of those the whole count scans, that is cheaper.
            (Some(h), Some(rows)) if 2 * rows.len() < self.scanned_rows(&ws.mask) => {
                let before = self.image_sums(&h.mask, rows.clone(), weights);
                let after = self.image_sums(&ws.mask, rows, weights);
                let sums = h.sums.replaced(&before, &after);
                energy::image_terms_of(&self.target, &sums, weights, &mut raw)
            }
            _ => energy::image_terms(&self.target, &ws.mask, weights, &mut raw),
        };
        self.physics_and_scene_terms(params, &outcome, ws, &mut raw, held);
        let total = energy::weighted_total(&raw, weights);
        let iou = energy::iou_of(&self.target, &ws.mask, counts);
        Evaluation {
            raw,
            total,
            outcome,
            iou,
        }
    }

    /// Whether a launched body would turn more than [`MAX_TURN`] radians by `t`: no real
    /// launch does, and the asymmetric-body integrator's step grid grows with the turn.
    fn spins_too_fast(&self, params: &[f64]) -> bool {
        self.scene.occluders.iter().enumerate().any(|(i, o)| {
            o.launched
                && Launch::get(params, i).angular_velocity.length() * self.plan.horizon > MAX_TURN
        })
    }

    /// Step 1: the exact free flight of every launched body (that varies) in `flights`.
    fn launch(&self, which: Option<&[bool]>, params: &[f64], flights: &mut [FreeFlight]) {
        self.start_flights(which, params, flights);
        integrate_grids(flights);
    }

    /// [`Problem::launch`] but for the tumbling bodies' grids, which the caller integrates
    /// ([`integrate_grids`]) beside others.
    fn start_flights(&self, which: Option<&[bool]>, params: &[f64], flights: &mut [FreeFlight]) {
        let scene = &self.scene;
        for (i, o) in scene.occluders.iter().enumerate() {
            if o.launched && among(which, i) {
                let state = self.launch_state(params, i);
                self.start_flight(&mut flights[i], i, state, 0.0, self.plan.horizon);
            }
        }
    }

    /// Steps 1-3: flights, first contact, poses at `t` (into `ws.poses`).
    pub fn fly(&self, params: &[f64], ws: &mut Workspace) -> Outcome {
        self.fly_with(None, params, ws)
    }

    fn fly_with(&self, held: Option<&Held>, params: &[f64], ws: &mut Workspace) -> Outcome {
        self.launch(held.map(|h| &h.varying[..]), params, &mut ws.flights);
        self.land(held, ws)
    }

    /// Steps 2-3 after [`Problem::launch`]: first contact, poses at `t`.
    pub(super) fn land(&self, held: Option<&Held>, ws: &mut Workspace) -> Outcome {
        let scene = &self.scene;
        let t = scene.t;
        let outcome = self.first_contact(held, ws);
        for i in 0..scene.occluders.len() {
            ws.poses[i] = match held {
                Some(h) if !h.varying[i] => h.poses[i],
                _ => self.state_at(ws, i, t).0,
            };
        }
        outcome
    }

    /// State of occluder `i` at `time` (0 <= time <= t) in the solver's model, after
    /// [`Problem::fly`] has run on `ws`: ((body origin, orientation), (centre-of-mass
    /// velocity, angular velocity)). A body that has landed stays on the table: the table
    /// absorbs its vertical motion and it slides on with its horizontal velocity.
    pub fn state_at(
        &self,
        ws: &Workspace,
        i: usize,
        time: f64,
    ) -> ((DVec3, DQuat), (DVec3, DVec3)) {
        let o = &self.scene.occluders[i];
        if !o.launched {
            return ((o.position, o.orientation), (DVec3::ZERO, DVec3::ZERO));
        }
        let f = &ws.flights[i];
        let q = f.orientation(time);
        let w = f.angular_velocity(time);
        let (com, v) = match ws.landing[i] {
            Some(tl) if tl < time => {
                let mut vh = f.com_velocity(tl);
                vh.z = 0.0;
                (f.com(tl) + vh * (time - tl), vh)
            }
            _ => (f.com(time), f.com_velocity(time)),
        };
        ((com - q * o.mass.local_com, q), (v, w))
    }

    fn physics_and_scene_terms(
        &self,
        params: &[f64],
        outcome: &Outcome,
        ws: &Workspace,
        raw: &mut [f64; TERM_COUNT],
        held: Option<&Held>,
    ) {
        self.physics_terms(params, outcome, raw, held);
        self.hint_and_barrier(&self.scene.hints, &self.target, ws, raw, held);
    }

    /// The contact term (contact time before the horizon times the count) and the
    /// regularization (the held occluders' shares from `held`).
    fn physics_terms(
        &self,
        params: &[f64],
        outcome: &Outcome,
        raw: &mut [f64; TERM_COUNT],
        held: Option<&Held>,
    ) {
        let scene = &self.scene;
        raw[Term::Contact as usize] =
            (self.plan.horizon - outcome.t_sim) * outcome.n_contacts as f64;
        let mut reg = 0.0;
        for (i, o) in scene.occluders.iter().enumerate() {
            if o.launched {
                reg += match held {
                    Some(h) if !h.varying[i] => h.terms.reg[i],
                    _ => reg_term(params, i),
                };
            }
        }
        raw[Term::Reg as usize] = reg;
    }

    /// Full parameter vector from a stage's varying subset.
    pub fn expand(&self, base: &[f64], vary: &[usize], x: &[f64], out: &mut [f64]) {
        out.copy_from_slice(base);
        for (k, &i) in vary.iter().enumerate() {
            Launch::copy(x, k, out, i);
        }
        self.expand_positions(vary, x, out);
    }

    /// Time each phase of one sample, averaged over `reps` repetitions on this thread
    /// (microseconds). Used for the per-term timings in `solution.json`.
    pub fn profile(&self, params: &[f64], reps: usize, ws: &mut Workspace) -> Vec<(String, f64)> {
        use std::time::Instant;
        let reps = reps.max(1);
        let all = Weights::all_ones();
        let mut out: Vec<(String, f64)> = Vec::new();
        let time = |f: &mut dyn FnMut()| {
            let start = Instant::now();
            for _ in 0..reps {
                f();
            }
            start.elapsed().as_secs_f64() * 1e6 / reps as f64
        };
        let us = time(&mut || {
            self.launch(None, params, &mut ws.flights);
        });
        out.push((PROFILE_PHASES[0].into(), us));
        let us = time(&mut || {
            std::hint::black_box(self.first_contact(None, ws));
        });
        out.push((PROFILE_PHASES[1].into(), us));
        self.fly(params, ws);
        let us = time(&mut || self.shadow(ws));
        out.push((PROFILE_PHASES[2].into(), us));
        let m = ws.mask.clone();
        for term in [
            Term::D0,
            Term::D1,
            Term::D2,
            Term::Xor,
            Term::Inner,
            Term::Outer,
        ] {
            let mut w = Weights::default();
            w.0[term as usize] = 1.0;
            let mut raw = [0.0; TERM_COUNT];
            let us = time(&mut || {
                std::hint::black_box(energy::image_terms(
                    &self.target,
                    std::hint::black_box(&m),
                    &w,
                    &mut raw,
                ));
            });
            debug_assert!(PROFILE_PHASES[3..9].contains(&term.key()));
            out.push((term.key().into(), us));
        }
        let outcome = self.fly(params, ws);
        let mut raw = [0.0; TERM_COUNT];
        let us = time(&mut || self.physics_and_scene_terms(params, &outcome, ws, &mut raw, None));
        out.push((PROFILE_PHASES[9].into(), us));
        let us = time(&mut || {
            std::hint::black_box(self.evaluate(params, &all, ws));
        });
        out.push((PROFILE_PHASES[10].into(), us));
        out
    }
}

#[cfg(test)]
mod tests;
