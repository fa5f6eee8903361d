//! Assignment moves: the global jumps that CMA-ES does not make.
//!
//! A joint stage refines launches locally; it does not send a body across the picture.
//! Two failures follow on problems that have a perfect answer: two bodies each cover
//! the other's part (a large sphere lowered onto a small blob while the small sphere
//! sits high on the large one), and a body hidden under another's shadow while a part
//! of the target stays bare (the image energy does not change while it moves under the
//! other shadow, so nothing draws it out). [`improve`] tries, from the best launch so
//! far:
//! - **swap** bodies `i` and `j`: each is sent to the other's line of sight from the
//!   light, at the depth where its own shadow has the other's area, so that the picture
//!   is unchanged up to the two shapes; or each is sent to the other's place in space;
//!   or, where both bodies' parts are known (see `fit`), each to the other's part at
//!   the part's whole size; or, for two bodies of one kind and different shapes, each
//!   to the other's pose at `t` and place (an **exchange**, [`MoveReport::exchanges`]:
//!   rarely better as it stands, so the solver also refines the best few before it
//!   judges them);
//! - **fill** the largest bare part of the target with body `i`: sent to the line of
//!   sight through the part's centroid, at the depth where its shadow has the part's
//!   area, and, if it is not a sphere and the part is elongated, also laid along the
//!   part (below; a piece sent there end-on rarely beats the picture it leaves); a body
//!   whose shadow left the canvas, which no image term sees, is sent the same way;
//! - **fit** body `i` to its own part: the target pixels it covers and the bare ones
//!   connected to them (a body left too small or off-centre on its blob, which CMA-ES
//!   steps toward slowly when the right size is far: chess pieces that must fly five
//!   times closer to the light), the same way;
//! - **turn** a body that is not a sphere a quarter or half turn about a world axis,
//!   and a mesh whose three principal moments differ (a knight) about its own principal
//!   axes too, about its centre of mass and moved so that its shadow keeps its centroid
//!   (a half turn about its long axis mirrors a lying knight's profile, the mistake the
//!   other moves leave: the knight's head on the wrong side);
//! - **align** it: turn it about its line of sight so that its shadow's long axis lies
//!   along its part's (both elongated, from their second moments);
//! - **lay** it: turn its own long axis (of least inertia) across the line of sight
//!   along its part's long axis, either way round (a piece seen end-on casts a round
//!   shadow with no axis to align);
//! - **fit the poses** of the blocks: each block in turn, the others' shadows kept, is
//!   searched on its pose at `t` itself (turns, shifts and depth,
//!   [`fit_pose`](pose::fit_pose)) for fewer wrong pixels, then launched there (its
//!   spin by [`spin_reaching`]): one candidate that moves every block that gained. The
//!   blocks that a pass's best move or its polished swaps and exchanges moved are
//!   fitted so too, after their polish (a block turned onto another face or sent to a
//!   new part rarely has its part's size, place and tilt at once). A tumbling block's
//!   launch spin reaches its pose through the whole flight, so a block tilted a little
//!   the wrong way is a narrow valley for CMA-ES and a smooth one here. A call that
//!   asks for it ([`MoveOptions::evolve_fits`], the last stage's polish) refines each
//!   fit by CMA-ES over the pose's six moves at once (`Seat::evolve`): an outline a
//!   pixel or two off its part can need a turn, a shift and a change of depth together.
//! - **seat** a mesh, in the first pass of a call ([`seat_pose`](pose::seat_pose)):
//!   posed at `t` with its axis (of symmetry for a lathed piece, else its long axis, at
//!   six rolls about it) in each of 64 directions, each placed on a place of the
//!   picture (the centroid and area of a shadow), the best three refined by the compass
//!   search of the pose fit, then launched there. Each mesh is seated on its own place,
//!   and two meshes of one kind and different shapes each on the other's (every pair
//!   scanned, the best [`SEAT_PAIRS`] refined): a piece on a wrong
//!   face, or a king and a queen on each other's parts in poses no quarter or half turn
//!   reaches, is a flat valley of the image energy that no local step and no other move
//!   leaves. A call that asks for it ([`MoveOptions::seat_blocks`], the last stage's
//!   polish) seats every block on its own place too, and seats in every pass.
//! - **split** a part between a hidden block and another, in the first pass of a call
//!   too ([`Seats::splits`](pose::Seats::splits)): a block whose shadow adds fewer
//!   than [`HIDDEN`](pose::HIDDEN) of its pixels to the picture (hidden under the
//!   others' shadows) is seated, as a mesh is, on one side of another block's part cut
//!   across its long axis, and that block on the other side; the partners are the
//!   [`SPLIT_PARTNERS`](pose::SPLIT_PARTNERS) blocks with the most wrong pixels around their shadows. One
//!   block drawn across two parts, the block meant for one of them hidden under a
//!   third, is a state where moving either alone makes the picture worse: the hidden
//!   block sent to the sliver of bare target beside the long shadow covers little,
//!   and the long shadow pulled back bares what the hidden block does not yet cover.
//! - **trade** places among bodies of one kind and different shapes, in every pass of
//!   a call that asks for it ([`MoveOptions::trades`]; the solver asks once, in its
//!   last stage, when the picture stays poor, and judges it without the hints): two or
//!   three blocks, or meshes where few, each seated, as a mesh is, on the place of the
//!   next, the cycles ranked by a table of seats
//!   ([`Seats::trade_scan`](pose::Seats::trade_scan)). A shadow's size is its body's
//!   size over its depth, so a long block end-on and low can draw a small block's part,
//!   the small block high up a medium one's, and the medium one high up the long one's
//!   (or a queen the king's part, the king the bishop's, the bishop the queen's): three
//!   wrong parts at once, where a swap of two leaves one wrong and often draws a worse
//!   picture than the one it leaves. Such a call seats the meshes in every pass too.
//!   A trade of meshes is offered even when its seats draw a worse picture (up to
//!   [`TRADE_SLACK`] times the wrong pixels kept) and reported
//!   ([`MoveReport::trades`]): a piece's seat in a cluster of overlapping pieces is
//!   too coarse to show the trade that mends the cluster, so the solver searches the
//!   reported trades when none is taken.
//!
//! Align, lay, the turns about a body's own axes, the seats and the exchanges ask for
//! an orientation at `t`; the launch spin that reaches it is solved by Newton's method
//! on the free flight ([`spin_reaching`]), since adding `angle / t` to the spin turns a
//! tumbling block somewhere else.
//!
//! A move guesses a depth from the size of a shadow that is often wrong itself (a body
//! left too low behind a contact), so the few moves of a pass that make the best
//! pictures are **polished**: each body they moved slides along its line of sight, a
//! few steps of shrinking size, while the picture gets better ([`Search::polish`]).
//!
//! A move changes a body's launch velocity only (its spin is kept, or turned): the
//! centre of mass of a free flight in a vacuum is at `c0 + v t + g t^2 / 2` at `t`, so
//! the velocity that puts it at a point is exact. Every candidate is evaluated like any
//! sample and ranked by the solver's rank (contacts first under the constraint mode);
//! the best one is taken when it ranks better than the current best, and the search
//! repeats from it. A pass costs at most `n (n - 1) + 2 n + 15 m + 18 k + 1` samples
//! for `n` launched bodies of which `m` are not spheres and `k` are meshes with three
//! distinct principal moments, and at most [`POLISHED`] times 6 per moved body for the
//! polish; each fit of the polish costs 2 samples more; a pose fit draws at most `1 +
//! 12 POSE_LEVELS POSE_SWEEPS` (241) shadows of one block, which are not samples (no
//! flight, no contact search). The seats of a first pass cost at most `s + SEAT_PAIRS`
//! samples for `s` meshes, and draw about `3 r 64` shadows per seat scanned (`r` rolls:
//! 1 or 6) and `12 SEAT_STEPS.1 POSE_SWEEPS` (336) per pose refined. The splits cost at
//! most [`SPLITS`](pose::SPLITS) samples more, and draw two seats' scans for each of at most
//! `SPLIT_HIDDEN SPLIT_PARTNERS 2 SPLIT_CUTS.len()` (36) cuts, only where a block is
//! hidden; finding the hidden blocks draws, once a call, each block's shadow alone and
//! the others' without it (1.05 to 1.1 times the solve's time on the planted blocks
//! where no block is hidden). The trades draw one seat (a scan and its best pose
//! refined) for each ordered pair of bodies of a group of different shapes (at most `b (b
//! - 1)` for `b` blocks, [`MAX_MESH_TRADES`] for meshes) and cost at most
//! [`TRADES`](pose::TRADES) samples more a pass for blocks and
//! [`MESH_TRADES`](pose::MESH_TRADES) for meshes, each polished.

mod pose;
mod spin;

use glam::{DMat3, DQuat, DVec2, DVec3};

use pose::{fit_and_launch, fits_pose, Seats, SEAT_KEPT, SEAT_PAIRS};
pub use spin::spin_reaching;
use spin::{launch_to, spin_guesses, turn_spin};

use crate::energy::{Term, Weights, DIVERGED_ENERGY};
use crate::evaluate::{Evaluation, Held, Problem, Workspace};
use crate::geometry::shape::Shape;
use crate::scene::Launch;
use crate::shadow::mask::{Mask, Moments};
use crate::sim::flight::{FreeFlight, LaunchState};

/// Fraction of the light-to-receiver distance (along a line of sight) that a moved body's
/// centre may take, at least: a body closer to the light than this casts a shadow over
/// ten times its size.
const MIN_DEPTH: f64 = 0.1;

/// The turns tried for a body that is not a sphere (rad, about each world axis): a
/// quarter turn either way and a half turn, added to its rotation by `t` through its
/// launch spin (exact for a spin about a principal axis, close otherwise).
const TURNS: [f64; 3] = [
    std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    std::f64::consts::PI,
];

/// A body whose shadow's area is within this factor of its part's (either way) is not
/// sent to its part: CMA-ES's local steps fix small errors of size, and a fit move
/// taken there only perturbs the search (it cost the planted blocks 0.02 of IoU).
const FIT_TOLERANCE: f64 = 1.5;

/// Clearance (m) kept between a moved body's lowest possible point and the table top.
const TABLE_CLEARANCE: f64 = 0.01;

/// Where one launched body is at `t`, as the moves see it.
#[derive(Clone, Copy, Debug)]
struct Sight {
    /// The centre of mass.
    com: DVec3,
    /// The point of the receiver plane on the light's line through the centre of mass.
    on_receiver: DVec3,
    /// The centre's depth along that line: 0 at the light, 1 on the receiver.
    depth: f64,
    /// The body's own shadow area (pixels), alone, at its pose at `t`.
    area: f64,
    /// Its own shadow's centroid (canvas pixels); `None` when it misses the canvas.
    centroid: Option<DVec2>,
    /// The body's part of the target: the target pixels that are bare or that it
    /// covers, connected to those it covers; its area (pixels) and centroid (canvas
    /// pixels). `None` when its shadow is on no target pixel, when another body's
    /// shadow borders the part, or when the shadow and the part differ in shape
    /// (elongations further apart than [`SAME_SHAPE`]): a change of size does not
    /// mend a wrong face.
    part: Option<(f64, DVec2)>,
    /// The angle (rad, image axes) of the long axis of the body's shadow and of its
    /// part, where both are elongated (see [`long_axis`]).
    axes: Option<(f64, f64)>,
    /// The angle of its part's long axis, where the part is elongated and the shadow
    /// is not.
    part_axis: Option<f64>,
}

/// What one call of [`improve`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MoveReport {
    /// Moves taken.
    pub accepted: usize,
    /// Samples evaluated.
    pub samples: usize,
    /// The launch of the candidate with the lowest energy of all, when it has a contact
    /// and a lower energy than the launch kept: a better picture that a local search
    /// may free of its contact (the caller may start a run from it).
    pub promising: Option<Vec<f64>>,
    /// The exchanges of pose and place of two bodies of one kind and different shapes
    /// (see [`improve`]) from the launch kept, each after [`Search::polish`], best
    /// picture first: rarely better as they stand (each body is off its new part by a
    /// little), they are worth a short local search of the two bodies. Empty when the
    /// last pass took a move.
    pub exchanges: Vec<Exchange>,
    /// The energy of the launch kept without the contact term (as [`Exchange::free`]).
    pub kept_free: f64,
    /// The trades of meshes of the last pass of a call that trades
    /// ([`MoveOptions::trades`]), as seated and polished, best picture first, even those
    /// that draw a worse picture than the launch kept (up to [`TRADE_SLACK`] times its
    /// wrong pixels): a trade in a cluster of overlapping pieces draws a worse picture
    /// until the pieces around have moved to make room, which a local search of the
    /// traded pieces may do (the caller's). Empty when the last pass took a move.
    pub trades: Vec<Trade>,
}

/// Two or three bodies each seated on the next one's place (see [`MoveReport::trades`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Trade {
    pub launch: Vec<f64>,
    pub bodies: Vec<usize>,
    /// Its energy without the contact term (as [`Exchange::free`]).
    pub free: f64,
}

/// Two bodies that took each other's pose and place.
#[derive(Clone, Debug, PartialEq)]
pub struct Exchange {
    pub launch: Vec<f64>,
    pub bodies: [usize; 2],
    /// Its energy without the contact term.
    pub free: f64,
}

/// Depth changes tried for a moved body, one after the other (fractions of its depth
/// along its line of sight from the light; a shadow's size goes as the inverse of the
/// depth): a move guesses the depth from the size of a shadow that is itself often
/// wrong (a body left too low behind a contact), and a swap of two bodies of close
/// sizes only pays once both have the size of their new part.
const DEPTH_STEPS: [f64; 3] = [0.16, 0.08, 0.04];

/// A trade of meshes is offered (and reported, [`MoveReport::trades`]) when its seats
/// draw fewer than this many times the wrong pixels of the picture kept (blocks: fewer
/// than the picture kept). The planted chess 10903 (a rook, a bishop and a knight each
/// on the next one's place in a cluster of four overlapping pieces) is mended by a trade
/// whose seats draw 1.6 times the energy of the launch kept.
const TRADE_SLACK: i64 = 4;

/// Moves of a pass polished by [`Search::polish`]: those whose pictures rank first.
const POLISHED: usize = 4;

/// The evaluations of one call of [`improve`]: counts them, shows each to the caller's
/// record, and keeps the promising launch (see [`MoveReport::promising`]).
struct Search<'a> {
    problem: &'a Problem,
    held: &'a Held,
    weights: &'a Weights,
    record: &'a mut dyn FnMut(&Evaluation),
    samples: usize,
    promising: Option<(f64, Vec<f64>)>,
}

impl Search<'_> {
    /// The energy without the contact term: the picture and the scene's pulls.
    fn free(&self, e: &Evaluation) -> f64 {
        e.total - self.weights.get(Term::Contact) * e.raw[Term::Contact as usize]
    }

    fn evaluate(&mut self, candidate: &[f64], ws: &mut Workspace) -> Evaluation {
        let e = self
            .problem
            .evaluate_held(self.held, candidate, self.weights, ws);
        self.samples += 1;
        (self.record)(&e);
        if e.outcome.own_contact > 0.0
            && e.total < DIVERGED_ENERGY
            && self.promising.as_ref().is_none_or(|p| self.free(&e) < p.0)
        {
            self.promising = Some((self.free(&e), candidate.to_vec()));
        }
        e
    }

    /// Slide each body a move moved (`candidate`, evaluated as `best`) along its line of
    /// sight from the light, one step size after the other, keeping a change when it
    /// makes a better picture (the energy without contacts: the slide looks for the size
    /// of the new part, and a contact on the way there often goes at the right size; the
    /// caller ranks the result with its contacts). `candidate` ends as the best launch
    /// found; returns its evaluation.
    fn polish(
        &mut self,
        candidate: &mut [f64],
        mut best: Evaluation,
        bodies: &[usize],
        ws: &mut Workspace,
    ) -> Evaluation {
        let mut trial = candidate.to_vec();
        for &b in bodies {
            for step in DEPTH_STEPS {
                for factor in [1.0 - step, 1.0 + step] {
                    trial.copy_from_slice(candidate);
                    if !slide(self.problem, &mut trial, b, factor) {
                        continue;
                    }
                    let e = self.evaluate(&trial, ws);
                    if self.free(&e) < self.free(&best) {
                        best = e;
                        candidate.copy_from_slice(&trial);
                    }
                }
            }
        }
        best
    }
}

/// A move of a pass, as evaluated: the launch, the bodies it moved, and its evaluation.
struct Offer {
    launch: Vec<f64>,
    bodies: Vec<usize>,
    eval: Evaluation,
}

/// How far [`improve`] goes.
#[derive(Clone, Copy, Debug)]
pub struct MoveOptions {
    /// Moves taken at most (passes that end with a move).
    pub max_moves: usize,
    /// Polish the moves of one body too, not only the swaps. A caller leaves it off where
    /// the best is not yet a local optimum of its own (the first run of a stage that
    /// places one body): there, a move's gain over an unrefined start says little of
    /// where the search ends (on the 飞 example, a polished turn taken so left the hook
    /// stroke 0.004 of IoU worse).
    pub polish_single: bool,
    /// Trade places among bodies of one kind and different shapes, and seat the meshes,
    /// in every pass ([`Seats::trade_scan`](pose::Seats::trade_scan)); a call that asks
    /// for trades where no group may trade (no two blocks of different sizes, and no two
    /// meshes of different shapes among at most [`MAX_MESH_TRADES`] ordered pairs)
    /// moves nothing.
    pub trades: bool,
    /// Seat the blocks on their own places too, as the meshes are, in every pass (a
    /// block tilted the wrong way, its outline near its part's). The last stage's polish
    /// asks for it; the stages' calls do not: there it lowered as many planted block
    /// problems as it raised (a seat taken early leaves a block's part to the runs after
    /// it in a pose that is not yet its own).
    pub seat_blocks: bool,
    /// Refine each fit of a block by CMA-ES over its pose after the compass search
    /// ([`fit_pose`](pose::fit_pose)'s `thorough`). The last stage's polish asks for it;
    /// the stages' calls do not: there, on the 35 planted problems of seeds 11400 to
    /// 11406, it raised 12 and lowered 8 (boxes 11402 0.9847 to 0.9955, but boxes12 11401
    /// 0.9960 to 0.9724), where in the polish alone, whose moves are kept only where the
    /// picture is no worse, it raised 8 and lowered 1 (by 0.0001).
    pub evolve_fits: bool,
}

/// Greedy moves of the occluders in `vary` from `params` (the launch of every
/// occluder), whose evaluation is `best`: at most `options.max_moves` moves are taken,
/// each the best-ranked candidate of a pass (after [`Search::polish`] of the few best
/// pictures) when it ranks better than the current launch.
/// `params` and `best` are updated in place; `held` is the stage's (it holds only
/// occluders not in `vary`); `record` sees every candidate's evaluation.
#[allow(clippy::too_many_arguments)]
pub fn improve(
    problem: &Problem,
    held: &Held,
    vary: &[usize],
    weights: &Weights,
    rank: &dyn Fn(&Evaluation) -> f64,
    params: &mut [f64],
    best: &mut Evaluation,
    options: MoveOptions,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> MoveReport {
    let scene = &problem.scene;
    let movable: Vec<usize> = vary
        .iter()
        .copied()
        .filter(|&i| scene.occluders[i].launched)
        .collect();
    let mut report = MoveReport::default();
    let blocks: Vec<usize> = movable
        .iter()
        .copied()
        .filter(|&i| fits_pose(&scene.occluders[i].shape))
        .collect();
    let meshes: Vec<usize> = movable
        .iter()
        .copied()
        .filter(|&i| matches!(scene.occluders[i].shape, Shape::Mesh(_)))
        .collect();
    // The groups that trade places: the blocks, and the meshes where few enough.
    let shape = |i: usize| &scene.occluders[i].shape;
    let trades: Vec<&[usize]> = [&blocks[..], &meshes[..]]
        .into_iter()
        .filter(|group| {
            options.trades
                && group.iter().any(|&i| shape(i) != shape(group[0]))
                && (group.len() * group.len().saturating_sub(1) <= MAX_MESH_TRADES
                    || fits_pose(shape(group[0])))
        })
        .collect();
    if movable.is_empty() || (options.trades && trades.is_empty()) {
        return report;
    }
    let mut search = Search {
        problem,
        held,
        weights,
        record,
        samples: 0,
        promising: None,
    };
    let mut candidate = params.to_vec();
    let mut chosen = params.to_vec();
    let mut flight = FreeFlight::default();
    let mut exchanges: Vec<Exchange> = Vec::new();
    let mut trade_offers: Vec<Trade> = Vec::new();
    let pairs = movable
        .iter()
        .enumerate()
        .map(|(a, &i)| {
            movable[a + 1..]
                .iter()
                .filter(|&&j| exchangeable(scene, i, j))
                .count()
        })
        .sum::<usize>();
    let exchanges_wanted = pairs <= MAX_EXCHANGE_PAIRS;
    let vary: Vec<bool> = (0..scene.occluders.len())
        .map(|k| movable.contains(&k))
        .collect();
    for pass in 0..options.max_moves {
        let current = problem.evaluate_held(held, params, weights, ws);
        let wrong = problem.target.mask.xor_count(&ws.mask) as i64;
        // The orientations at `t` of the launch kept (the offers below overwrite `ws`).
        let current_poses = ws.poses.clone();
        let turned: Vec<DQuat> = current_poses.iter().map(|p| p.1).collect();
        let bare = problem.target.mask.and_not(&ws.mask);
        let sights = sights(problem, &movable, &bare, ws);
        let hole = bare
            .blobs()
            .into_iter()
            .max_by(|a, b| a.0.cmp(&b.0).then(b.1.x.total_cmp(&a.1.x)));
        let mut best_rank = rank(&current);
        let mut found = None;
        // Every move of the pass, evaluated; the best few are then polished.
        let mut offers: Vec<Offer> = Vec::new();
        exchanges.clear();
        // Offers made so far, and those of them that are trades of meshes.
        let made = std::cell::Cell::new(0);
        let mut mesh_trades = 0..0;
        let mut offer =
            |candidate: &[f64], bodies: &[usize], search: &mut Search, ws: &mut Workspace| {
                made.set(made.get() + 1);
                let eval = search.evaluate(candidate, ws);
                offers.push(Offer {
                    launch: candidate.to_vec(),
                    bodies: bodies.to_vec(),
                    eval,
                });
            };
        for (a, &i) in movable.iter().enumerate() {
            for &j in &movable[a + 1..] {
                let (Some(si), Some(sj)) = (sights[i], sights[j]) else {
                    continue;
                };
                // Each takes the other's part of the picture at the size that part has
                // now (the picture changes only by the two shapes) ...
                candidate.copy_from_slice(params);
                send(problem, &mut candidate, i, sj.on_receiver, si, sj.area);
                send(problem, &mut candidate, j, si.on_receiver, sj, si.area);
                offer(&candidate, &[i, j], &mut search, ws);
                // ... or the other's place in space (each part's size changes by the
                // ratio of the two bodies' sizes) ...
                candidate.copy_from_slice(params);
                aim(problem, &mut candidate, i, sj.com);
                aim(problem, &mut candidate, j, si.com);
                offer(&candidate, &[i, j], &mut search, ws);
                // ... or, where both parts are known, the other's part at its whole size:
                // two bodies each on the other's part, both too small for it (one kept
                // low under the other's flight), gain nothing from a swap at the sizes
                // the parts have now.
                if let (Some(part_i), Some(part_j)) = (si.part, sj.part) {
                    candidate.copy_from_slice(params);
                    send_to_part(problem, &mut candidate, i, si, part_j);
                    send_to_part(problem, &mut candidate, j, sj, part_i);
                    offer(&candidate, &[i, j], &mut search, ws);
                }
                // ... or each takes the other's pose and place (`exchange_poses`),
                // polished and kept for the caller too.
                if exchanges_wanted && exchangeable(scene, i, j) {
                    candidate.copy_from_slice(params);
                    exchange_poses(
                        problem,
                        &mut candidate,
                        (i, si),
                        (j, sj),
                        &turned,
                        &mut flight,
                    );
                    let e = search.evaluate(&candidate, ws);
                    let mut launch = candidate.clone();
                    let e = search.polish(&mut launch, e, &[i, j], ws);
                    offer(&launch, &[i, j], &mut search, ws);
                    exchanges.push(Exchange {
                        launch,
                        bodies: [i, j],
                        free: search.free(&e),
                    });
                }
            }
        }
        if let Some((area, centroid, (x0, y0))) = hole {
            let on_receiver = problem.canvas.pixel_to_world(centroid.x, centroid.y);
            // The hole's long axis, to lay a body along as it is sent there: a piece
            // sent end-on to a part that shows it lying rarely beats the picture it
            // leaves, and the lay alone cannot follow.
            let mut seed = Mask::new(bare.width(), bare.height());
            seed.set(x0, y0);
            let hole_axis = long_axis(&bare.connected_to(&seed).moments());
            for &i in &movable {
                let Some(si) = sights[i] else { continue };
                candidate.copy_from_slice(params);
                let com = send(problem, &mut candidate, i, on_receiver, si, area as f64);
                offer(&candidate, &[i], &mut search, ws);
                let Some(angle) = hole_axis else { continue };
                if matches!(scene.occluders[i].shape, Shape::Sphere { .. }) {
                    continue;
                }
                let now = turned[i];
                let sent = candidate.clone();
                for rotation in lays(problem, i, now, com, angle) {
                    candidate.copy_from_slice(&sent);
                    turn_spin(problem, &mut candidate, i, now, rotation, true, &mut flight);
                    offer(&candidate, &[i], &mut search, ws);
                }
            }
        }
        for &i in &movable {
            let Some(si) = sights[i] else { continue };
            let Some(part) = si.part else {
                continue;
            };
            // Close to its part's size already: the local search does the rest.
            if (si.area / part.0).ln().abs() < FIT_TOLERANCE.ln() {
                continue;
            }
            candidate.copy_from_slice(params);
            send_to_part(problem, &mut candidate, i, si, part);
            offer(&candidate, &[i], &mut search, ws);
        }
        for &i in &movable {
            if matches!(scene.occluders[i].shape, Shape::Sphere { .. }) {
                continue;
            }
            let now = turned[i];
            // An asymmetric mesh (a knight, most meshes a user brings) also turns about
            // its own principal axes: a half turn about its long axis mirrors a lying
            // knight's profile, which a turn about a world axis does only by also moving
            // its long axis off its part. Its spin is not about one axis, so the turn is
            // solved on the flight. Its centre of mass is rarely the middle of its shadow,
            // so each turn is offered about it, and moved so that the shadow keeps its
            // centroid (`recentre`): the first undoes a wrong turn, the second mends a
            // wrong profile on its place.
            if let (Shape::Mesh(_), Some(si)) = (&scene.occluders[i].shape, sights[i]) {
                for axis in own_axes(&scene.occluders[i].mass).into_iter().flatten() {
                    for angle in TURNS {
                        candidate.copy_from_slice(params);
                        let rotation = (now * axis, angle);
                        turn_spin(problem, &mut candidate, i, now, rotation, true, &mut flight);
                        offer(&candidate, &[i], &mut search, ws);
                        recentre(problem, &mut candidate, i, si, &mut flight, ws);
                        offer(&candidate, &[i], &mut search, ws);
                    }
                }
            }
            let mut turn =
                |axis: DVec3, angle: f64, exact: bool, search: &mut Search, ws: &mut Workspace| {
                    candidate.copy_from_slice(params);
                    let rotation = (axis, angle);
                    turn_spin(
                        problem,
                        &mut candidate,
                        i,
                        now,
                        rotation,
                        exact,
                        &mut flight,
                    );
                    offer(&candidate, &[i], search, ws);
                };
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                for angle in TURNS {
                    turn(axis, angle, false, &mut search, ws);
                }
            }
            // Align the shadow's long axis with its part's: a turn about the line of
            // sight (image y points down, so try both senses).
            if let Some((own, part)) = sights[i].and_then(|si| si.axes) {
                let mut delta = part - own;
                while delta > std::f64::consts::FRAC_PI_2 {
                    delta -= std::f64::consts::PI;
                }
                while delta <= -std::f64::consts::FRAC_PI_2 {
                    delta += std::f64::consts::PI;
                }
                if delta.abs() > MIN_ALIGN {
                    let sight = sights[i].expect("axes come with a sight");
                    let axis = (sight.com - scene.camera.light).normalize();
                    turn(axis, delta, true, &mut search, ws);
                    turn(axis, -delta, true, &mut search, ws);
                }
            }
            // Lay the body's long axis along its part's, across the line of sight,
            // either way round: a piece seen end-on, a block on its end, whose shadow
            // has no long axis to align. (Laying a body whose shadow has one, when the
            // align move does not mend it, cost the planted blocks 0.01 of IoU.)
            if let Some((sight, angle)) = sights[i].and_then(|si| Some((si, si.part_axis?))) {
                for (axis, angle) in lays(problem, i, now, sight.com, angle) {
                    turn(axis, angle, true, &mut search, ws);
                }
            }
        }
        // Seat the meshes (`seat_pose`), in the first pass only (in every pass of a call
        // that trades: a trade of two often leaves a third body to seat; and of a call
        // that seats the blocks: in a cluster of blocks, one seated anew lets the next
        // find its own pose): a scan of every pose costs a few thousand shadows of one
        // body, and a seat that the first pass did not take is rarely taken after a
        // smaller move.
        if pass == 0 || options.trades || options.seat_blocks {
            let seats = Seats {
                problem,
                held,
                vary: &vary,
                now: &current_poses,
                sights: &sights,
            };
            let mut offer_seats =
                |seated: &[(usize, (DVec3, DQuat))], search: &mut Search, ws: &mut Workspace| {
                    candidate.copy_from_slice(params);
                    for &(b, pose) in seated {
                        let guesses = spin_guesses(
                            problem,
                            b,
                            Launch::get(params, b).angular_velocity,
                            turned[b],
                            pose.1,
                        );
                        if !launch_to(problem, b, pose, &guesses, &mut candidate, &mut flight) {
                            return;
                        }
                    }
                    let bodies: Vec<usize> = seated.iter().map(|s| s.0).collect();
                    offer(&candidate, &bodies, search, ws);
                };
            // Each on its own place ...
            // (the blocks too where the caller asks) ...
            let own: Vec<usize> = if options.seat_blocks {
                meshes.iter().chain(&blocks).copied().collect()
            } else {
                meshes.clone()
            };
            for &i in &own {
                if let Some((cost, pose)) = seats.own(i, ws) {
                    if cost < wrong {
                        offer_seats(&[(i, pose)], &mut search, ws);
                    }
                }
            }
            // ... and two of a kind each on the other's: every pair scanned, the best
            // refined.
            let mut scanned: Vec<(i64, usize, usize)> = Vec::new();
            for (a, &i) in meshes.iter().enumerate() {
                for &j in &meshes[a + 1..] {
                    if !exchanges_wanted || !exchangeable(scene, i, j) {
                        continue;
                    }
                    if let Some((cost, _)) = seats.pair(i, j, 0, ws) {
                        scanned.push((cost, i, j));
                    }
                }
            }
            scanned.sort();
            for &(_, i, j) in scanned.iter().take(SEAT_PAIRS) {
                if let Some((cost, [pi, pj])) = seats.pair(i, j, SEAT_KEPT, ws) {
                    if cost < wrong {
                        offer_seats(&[(i, pi), (j, pj)], &mut search, ws);
                    }
                }
            }
            // ... and a hidden block seated beside another on that one's part, cut in
            // two: every cut scanned, the best refined.
            for (r, j, [place_r, place_j]) in seats.split_scan(&blocks, &bare, ws) {
                let two = seats.two((r, place_r), (j, place_j), SEAT_KEPT, ws);
                if let Some((cost, [pr, pj])) = two {
                    if cost < wrong {
                        offer_seats(&[(r, pr), (j, pj)], &mut search, ws);
                    }
                }
            }
            // ... and, when the caller asks, bodies of one kind and different shapes each
            // on the next one's place: the cycles the table of seats ranks best, refined.
            for group in &trades {
                let of_meshes = matches!(shape(group[0]), Shape::Mesh(_));
                let (cap, slack) = if of_meshes {
                    (pose::MESH_TRADES, TRADE_SLACK)
                } else {
                    (pose::TRADES, 1)
                };
                let first = made.get();
                for cycle in seats.trade_scan(group, cap, ws) {
                    if let Some((cost, poses)) = seats.many(&cycle, SEAT_KEPT, ws) {
                        if cost < slack * wrong {
                            let seated: Vec<(usize, (DVec3, DQuat))> =
                                cycle.iter().map(|c| c.0).zip(poses).collect();
                            offer_seats(&seated, &mut search, ws);
                        }
                    }
                }
                if of_meshes {
                    mesh_trades = first..made.get();
                }
            }
            ws.poses.copy_from_slice(&current_poses);
        }
        // Every block fitted to the picture on its pose at `t`, one after the other
        // (`fit_pose`), and launched there.
        let is_block = |i: usize| fits_pose(&scene.occluders[i].shape);
        {
            candidate.copy_from_slice(params);
            ws.poses.copy_from_slice(&current_poses);
            let mut fitted = Vec::new();
            for &i in &blocks {
                if fit_and_launch(
                    problem,
                    held,
                    &vary,
                    i,
                    &mut candidate,
                    options.evolve_fits,
                    ws,
                    &mut flight,
                ) {
                    fitted.push(i);
                }
            }
            if !fitted.is_empty() {
                offer(&candidate, &fitted, &mut search, ws);
            }
        }
        trade_offers = offers[mesh_trades]
            .iter()
            .map(|o| Trade {
                launch: o.launch.clone(),
                bodies: o.bodies.clone(),
                free: search.free(&o.eval),
            })
            .collect();
        // Polish the moves that made the best pictures (a move that made a poor one
        // seldom becomes the best by a change of depth), then take the best-ranked.
        offers.sort_by(|a, b| search.free(&a.eval).total_cmp(&search.free(&b.eval)));
        let mut polished = 0;
        for offer in offers.iter_mut() {
            if polished < POLISHED && (options.polish_single || offer.bodies.len() > 1) {
                offer.eval = search.polish(&mut offer.launch, offer.eval, &offer.bodies, ws);
                polished += 1;
                // The blocks it moved fitted on their new poses too, for the best move and
                // for swaps and exchanges: a block turned onto another face, or sent to a
                // new part, rarely has its part's size, place and tilt at once. (Fitting
                // those of all four best moves raised the hand-made "to fly" a little more
                // at 1.1 to 1.35 times the time, over its 0.5 s: the spins that reach
                // fitted poses are faster, and every later flight of a faster tumbling
                // block costs more.)
                let fit = polished == 1 || offer.bodies.len() > 1;
                if fit && offer.bodies.iter().any(|&b| is_block(b)) {
                    candidate.copy_from_slice(&offer.launch);
                    search.evaluate(&candidate, ws);
                    let mut moved = false;
                    for &b in offer.bodies.iter().filter(|&&b| is_block(b)) {
                        moved |= fit_and_launch(
                            problem,
                            held,
                            &vary,
                            b,
                            &mut candidate,
                            options.evolve_fits,
                            ws,
                            &mut flight,
                        );
                    }
                    if moved {
                        let e = search.evaluate(&candidate, ws);
                        if search.free(&e) < search.free(&offer.eval) {
                            offer.eval = e;
                            offer.launch.copy_from_slice(&candidate);
                        }
                    }
                }
            }
            let r = rank(&offer.eval);
            if r < best_rank {
                best_rank = r;
                chosen.copy_from_slice(&offer.launch);
                found = Some(offer.eval);
            }
        }
        match found {
            Some(e) => {
                params.copy_from_slice(&chosen);
                *best = e;
                report.accepted += 1;
                // Exchanges and trades of the launch before this move are stale.
                exchanges.clear();
                trade_offers.clear();
            }
            None => break,
        }
    }
    // Leave the workspace holding the kept launch's flight and shadow.
    *best = problem.evaluate_held(held, params, weights, ws);
    report.samples = search.samples;
    let kept = search.free(best);
    exchanges.sort_by(|a, b| a.free.total_cmp(&b.free));
    report.exchanges = exchanges;
    trade_offers.sort_by(|a, b| a.free.total_cmp(&b.free));
    report.trades = trade_offers;
    report.kept_free = kept;
    report.promising = search
        .promising
        .filter(|(energy, _)| *energy < kept)
        .map(|(_, launch)| launch);
    report
}

/// The line of sight, depth and own shadow area of every launched body at `t`, after
/// an evaluation on `ws`; `None` for a body that is not between the light and the
/// receiver. A body whose shadow misses the canvas gets the area it would have on the
/// picture's centre line, and no part.
/// `bare` is the target minus the whole shadow, which `ws` holds.
fn sights(
    problem: &Problem,
    movable: &[usize],
    bare: &Mask,
    ws: &mut Workspace,
) -> Vec<Option<Sight>> {
    let scene = &problem.scene;
    let n = scene.occluders.len();
    let light = scene.camera.light;
    let normal = scene.receiver.normal;
    let mut out = vec![None; n];
    let mut only = vec![false; n];
    let full = ws.mask.clone();
    for &i in movable {
        let (origin, q) = ws.poses[i];
        let com = origin + q * scene.occluders[i].mass.local_com;
        let down = (scene.receiver.center - light).dot(normal);
        let along = (com - light).dot(normal);
        if along.abs() < 1e-12 || down / along <= 1.0 {
            continue;
        }
        let depth = along / down;
        only.fill(false);
        only[i] = true;
        problem.shadow_only(&only, ws);
        let area = ws.mask.count() as f64;
        if area == 0.0 {
            // A shadow beyond the canvas costs nothing in the image terms, and no local
            // search finds its way back. Its area is taken where it would fall at the
            // same depth on the picture's centre line (a shadow's size goes with the
            // depth, hardly with the ray), so that the fill move can send it to a bare
            // part like any other body.
            let on_centre = light + (scene.receiver.center - light) * depth;
            let kept = ws.poses[i];
            ws.poses[i].0 = kept.0 + (on_centre - com);
            problem.shadow_only(&only, ws);
            ws.poses[i] = kept;
            let area = ws.mask.count() as f64;
            if area > 0.0 {
                out[i] = Some(Sight {
                    com,
                    on_receiver: light + (com - light) / depth,
                    depth,
                    area,
                    centroid: None,
                    part: None,
                    axes: None,
                    part_axis: None,
                });
            }
            continue;
        }
        let part = part_of(&problem.target.mask, &ws.mask, bare);
        // A part that another body's shadow borders is shared: its size is not this
        // body's to take.
        let others = full.and_not(&ws.mask);
        let shared = part.dilate(3).and_count(&others) > 0;
        let m = part.moments();
        let own = ws.mask.moments();
        let same_shape = elongation(&own)
            .zip(elongation(&m))
            .is_some_and(|(a, b)| a.max(b) / a.min(b) < SAME_SHAPE);
        let part_axis = long_axis(&m).filter(|_| !shared);
        let own_axis = long_axis(&own);
        let axes = own_axis.zip(part_axis);
        let part_axis = part_axis.filter(|_| own_axis.is_none());
        out[i] = Some(Sight {
            com,
            on_receiver: light + (com - light) / depth,
            depth,
            area,
            centroid: own.centroid(),
            part: m
                .centroid()
                .filter(|_| !shared && same_shape)
                .map(|c| (m.count, c)),
            axes,
            part_axis,
        });
    }
    out
}

/// A body's part of the target, from its own shadow `own`: the target pixels it covers
/// and the bare ones (`bare`) connected to them.
fn part_of(target: &Mask, own: &Mask, bare: &Mask) -> Mask {
    let covered = target.and(own);
    let mut mine = bare.clone();
    mine.or_assign(&covered);
    mine.connected_to(&covered)
}

/// Set body `i`'s launch velocity in `params` so that its centre of mass is at `t` on
/// the light's line through `on_receiver`, at the depth where its shadow (now `own`)
/// has `area` pixels: the shadow's size goes as the inverse of the depth.
/// Returns the centre of mass aimed at.
fn send(
    problem: &Problem,
    params: &mut [f64],
    i: usize,
    on_receiver: DVec3,
    own: Sight,
    area: f64,
) -> DVec3 {
    let light = problem.scene.camera.light;
    let depth = own.depth * (own.area / area).sqrt();
    let com = light + (on_receiver - light) * allowed_depth(problem, i, on_receiver, depth);
    aim(problem, params, i, com);
    com
}

/// `depth` along the light's line through `on_receiver`, kept where body `i`'s lowest
/// point stays above the table (for a level table under the light) and within
/// [`MIN_DEPTH`] and the receiver.
fn allowed_depth(problem: &Problem, i: usize, on_receiver: DVec3, mut depth: f64) -> f64 {
    let light = problem.scene.camera.light;
    if let Some(top) = lowest_centre(problem, i) {
        let drop = light.z - on_receiver.z;
        if drop > 0.0 && light.z > top {
            depth = depth.min((light.z - top) / drop);
        }
    }
    depth.clamp(MIN_DEPTH, 1.0)
}

/// [`send`] body `i` (now `own`) to a part of the picture, `(area, centroid)` as
/// [`Sight::part`] gives it: onto the line of sight through the centroid, at the size of
/// the whole part.
fn send_to_part(problem: &Problem, params: &mut [f64], i: usize, own: Sight, part: (f64, DVec2)) {
    let (area, centroid) = part;
    let on_receiver = problem.canvas.pixel_to_world(centroid.x, centroid.y);
    send(problem, params, i, on_receiver, own, area);
}

/// Set body `i`'s launch velocity in `params` so that its centre of mass is at `target`
/// at `t` (its spin is kept).
fn aim(problem: &Problem, params: &mut [f64], i: usize, target: DVec3) {
    let scene = &problem.scene;
    let t = scene.t;
    let start = scene.occluders[i].launch_com();
    let mut launch = Launch::get(params, i);
    launch.velocity = (target - start - 0.5 * scene.gravity * t * t) / t;
    launch.set(params, i);
}

/// Move body `i`'s centre of mass at `t` along its line from the light to `factor` times
/// its depth (its spin is kept); `false`, and `params` unchanged, when the centre would
/// leave the space between the light and the receiver or come within reach of the table.
fn slide(problem: &Problem, params: &mut [f64], i: usize, factor: f64) -> bool {
    let scene = &problem.scene;
    let o = &scene.occluders[i];
    let t = scene.t;
    let light = scene.camera.light;
    let com = o.launch_com() + Launch::get(params, i).velocity * t + 0.5 * scene.gravity * t * t;
    let normal = scene.receiver.normal;
    let down = (scene.receiver.center - light).dot(normal);
    let depth = (com - light).dot(normal) / down * factor;
    if !(MIN_DEPTH..=1.0).contains(&depth) {
        return false;
    }
    let target = light + (com - light) * factor;
    if lowest_centre(problem, i).is_some_and(|top| target.z < top) {
        return false;
    }
    aim(problem, params, i, target);
    true
}

/// The lowest height a moved body's centre of mass may take at `t`: its bounding sphere
/// and [`TABLE_CLEARANCE`] above the table top (`None` without a table).
fn lowest_centre(problem: &Problem, i: usize) -> Option<f64> {
    let o = &problem.scene.occluders[i];
    let table = problem.scene.table.as_ref()?;
    Some(table.top() + o.bounding_radius + TABLE_CLEARANCE)
}

/// Largest ratio of two elongations ([`elongation`]) that count as the same shape.
const SAME_SHAPE: f64 = 1.3;

/// Smallest turn (rad) of an align move: below it, CMA-ES's local steps do better.
const MIN_ALIGN: f64 = 0.1;

/// Ratio of the principal second moments above which a shadow has a long axis.
const ELONGATED: f64 = 1.5;

/// The angle (rad, in image axes: x right, y down) of the long axis of the pixels whose
/// moments are `m`, when they are elongated (principal moments in a ratio of at least
/// [`ELONGATED`]).
fn long_axis(m: &Moments) -> Option<f64> {
    let [a, b, c] = m.central_second()?;
    (elongation(m)? >= ELONGATED).then(|| 0.5 * (2.0 * b).atan2(a - c))
}

/// The ratio of the larger principal second moment to the smaller (1 for a disc), or
/// `None` for an empty or degenerate set.
fn elongation(m: &Moments) -> Option<f64> {
    let [a, b, c] = m.central_second()?;
    let half = 0.5 * (a + c);
    let root = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let (large, small) = (half + root, half - root);
    (small > 0.0).then(|| large / small)
}

/// A body whose long axis is already within this cosine of its part's direction is not
/// laid along it again (about 18 degrees).
const LAID: f64 = 0.95;

/// The turns (world axis, angle) that lay body `i`, at orientation `now` with its centre
/// of mass at `com`, with its long axis across the line of sight along the image angle
/// `angle`, either way round; none when it lies so already (within [`LAID`]).
fn lays(problem: &Problem, i: usize, now: DQuat, com: DVec3, angle: f64) -> Vec<(DVec3, f64)> {
    let cam = &problem.scene.camera;
    let along = (com - cam.light).normalize();
    let d = cam.u * angle.cos() - cam.v * angle.sin();
    let d = (d - along * d.dot(along)).normalize_or_zero();
    let long = now * problem.scene.occluders[i].mass.long_axis();
    if d == DVec3::ZERO || long.dot(d).abs() >= LAID {
        return Vec::new();
    }
    [d, -d]
        .iter()
        .map(|&end| DQuat::from_rotation_arc(long, end).to_axis_angle())
        .collect()
}

/// Exchanges are offered only among at most this many pairs of bodies that could
/// exchange: each costs two Newton solves of a launch spin in every pass of moves. THE
/// THINKER's sixteen pieces make 89 such pairs, which took its solve from 4.2 to 7.9 s
/// (hand-made, seed 2: from 3.5 to 6.5 s, for no gain), and tbc's six units and six half
/// pillars 36, which took the hand-made tbc from 1.42 to 1.93 s (seed 1, for no gain);
/// the planted problems' six chess pieces make 15 pairs.
const MAX_EXCHANGE_PAIRS: usize = 30;

/// Meshes trade places ([`MoveOptions::trades`]) where at most this many ordered pairs
/// of them are scanned: the six pieces of the planted chess problems make 30, each
/// scan drawing a few thousand shadows of a mesh; THE THINKER's sixteen would make 240,
/// several seconds over its solve. Blocks, whose shadows are eight corners, always
/// trade.
const MAX_MESH_TRADES: usize = 30;

/// Whether bodies `i` and `j` may exchange poses and places: of one kind (two meshes,
/// two boxes; a sphere's pose shows nothing) and of different shapes.
fn exchangeable(scene: &crate::scene::Scene, i: usize, j: usize) -> bool {
    let (a, b) = (&scene.occluders[i].shape, &scene.occluders[j].shape);
    canonical(a).is_some() && std::mem::discriminant(a) == std::mem::discriminant(b) && a != b
}

/// Set the launches of bodies `i` and `j` (now seen as `si`, `sj`, turned to `turned` at
/// `t`) in `params` so that each takes the other's orientation at `t` (the spin that
/// reaches it, by [`spin_reaching`]; frames matched by [`canonical`]) and the other's
/// line of sight, at the depth where its shadow has the other's size (as their bounding
/// radii go): two bodies of one family in the same kind of pose (a king and a bishop
/// lying down) often end each drawing the other's shadow at the other's size, which no
/// swap that keeps the poses reproduces.
fn exchange_poses(
    problem: &Problem,
    params: &mut [f64],
    (i, si): (usize, Sight),
    (j, sj): (usize, Sight),
    turned: &[DQuat],
    flight: &mut FreeFlight,
) {
    let scene = &problem.scene;
    let frame = |k: usize| canonical(&scene.occluders[k].shape).unwrap_or(DQuat::IDENTITY);
    let (ci, cj) = (frame(i), frame(j));
    let want_i = turned[j] * cj * ci.conjugate();
    let want_j = turned[i] * ci * cj.conjugate();
    for (b, want) in [(i, want_i), (j, want_j)] {
        let rotation = (want * turned[b].conjugate()).to_axis_angle();
        turn_spin(problem, params, b, turned[b], rotation, true, flight);
    }
    let ratio = scene.occluders[i].bounding_radius / scene.occluders[j].bounding_radius;
    let as_j = Sight {
        area: sj.area * ratio * ratio,
        ..sj
    };
    let as_i = Sight {
        area: si.area / (ratio * ratio),
        ..si
    };
    send(problem, params, i, sj.on_receiver, as_j, sj.area);
    send(problem, params, j, si.on_receiver, as_i, si.area);
}

/// The rotation from a body's canonical frame to its own (body) frame, for a swap of
/// poses: a mesh's own frame (the pieces of one set share a convention: upright along
/// one axis, base at the origin), a box's axes sorted from the longest (x) to the
/// shortest (z); `None` for a sphere, whose pose shows nothing.
fn canonical(shape: &Shape) -> Option<DQuat> {
    match shape {
        Shape::Sphere { .. } => None,
        Shape::Mesh(_) => Some(DQuat::IDENTITY),
        Shape::Cuboid { half_extents } => {
            let h = half_extents.to_array();
            let mut order = [0usize, 1, 2];
            order.sort_by(|&a, &b| h[b].total_cmp(&h[a]).then(a.cmp(&b)));
            let axis =
                |k: usize| DVec3::from_array(std::array::from_fn(|c| f64::from(u8::from(c == k))));
            let (x, y) = (axis(order[0]), axis(order[1]));
            // A right-handed frame: a box is symmetric under the sign of its third axis.
            Some(DQuat::from_mat3(&DMat3::from_cols(x, y, x.cross(y))))
        }
    }
}

/// Principal moments closer than this share of the largest count as equal for
/// [`own_axes`]: a body with two such moments is close to a solid of revolution (a king,
/// whose cross makes its two moments across its axis differ by 2e-4 of them; a knight's
/// differ by 8 %).
const REVOLUTION: f64 = 0.01;

/// The body-frame principal axes of a body whose three principal moments differ (by
/// more than [`REVOLUTION`]), as a knight's do; `None` for one close to a solid of
/// revolution (a lathed chess piece: a turn about its axis shows the same shadow, and a
/// half turn across it is close to the half turns about world axes that the moves
/// already try).
fn own_axes(mass: &crate::geometry::shape::MassProperties) -> Option<[DVec3; 3]> {
    let k = mass.principal_inertia;
    let tol = REVOLUTION * k.max_element();
    let distinct = (k.x - k.y).abs() > tol && (k.y - k.z).abs() > tol && (k.z - k.x).abs() > tol;
    distinct.then(|| [DVec3::X, DVec3::Y, DVec3::Z].map(|e| mass.principal_frame * e))
}

/// Move body `i` (seen as `own` before a turn that `params` now holds) at the same depth
/// so that its own shadow's centroid is back where it was: a turn keeps the centre of
/// mass, which an asymmetric body's shadow does not surround evenly. The shadow is drawn
/// alone at the turned pose, in `ws`.
fn recentre(
    problem: &Problem,
    params: &mut [f64],
    i: usize,
    own: Sight,
    flight: &mut FreeFlight,
    ws: &mut Workspace,
) {
    let scene = &problem.scene;
    let o = &scene.occluders[i];
    let Some(before) = own.centroid else { return };
    flight.reset(
        &o.mass,
        LaunchState::of(o, Launch::get(params, i)),
        scene.gravity,
        scene.t,
        &problem.flight,
    );
    ws.poses[i] = flight.pose(scene.t);
    let mut only = vec![false; scene.occluders.len()];
    only[i] = true;
    problem.shadow_only(&only, ws);
    let Some(after) = ws.mask.moments().centroid() else {
        return;
    };
    let c = &problem.canvas;
    let shift = c.pixel_to_world(before.x, before.y) - c.pixel_to_world(after.x, after.y);
    // A shift at depth `d` (0 at the light, 1 on the receiver) moves the shadow `1 / d`
    // times as far.
    aim(problem, params, i, own.com + shift * own.depth);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_canonical_frame_runs_from_its_longest_axis_to_its_shortest() {
        let shape = Shape::Cuboid {
            half_extents: DVec3::new(0.035, 0.14, 0.0175),
        };
        let q = canonical(&shape).expect("a box has a frame");
        assert!((q * DVec3::X - DVec3::Y).length() < 1e-12);
        assert!((q * DVec3::Y - DVec3::X).length() < 1e-12);
        // A proper rotation: the third axis is the shortest, either way along it.
        assert!(((q * DVec3::Z).dot(DVec3::Z).abs() - 1.0).abs() < 1e-12);
        assert!(canonical(&Shape::Sphere { radius: 0.1 }).is_none());
    }

    #[test]
    fn long_axis_gives_the_angle_of_an_elongated_blob() {
        for deg in [0.0f64, 30.0, -60.0, 89.0] {
            let a = deg.to_radians();
            let (c, s) = (a.cos(), a.sin());
            // A 60 x 10 px bar turned by `a` (image axes).
            let m = Mask::from_fn(200, 200, |x, y| {
                let (dx, dy) = (x as f64 + 0.5 - 100.0, y as f64 + 0.5 - 100.0);
                (dx * c + dy * s).abs() < 30.0 && (-dx * s + dy * c).abs() < 5.0
            });
            let got = long_axis(&m.moments()).expect("a bar is elongated");
            let mut d = got - a;
            d -= std::f64::consts::PI * (d / std::f64::consts::PI).round();
            assert!(d.abs() < 0.03, "{deg} deg: got {} deg", got.to_degrees());
        }
        let disc = Mask::from_fn(100, 100, |x, y| {
            let (dx, dy) = (x as f64 - 50.0, y as f64 - 50.0);
            dx * dx + dy * dy < 900.0
        });
        assert_eq!(long_axis(&disc.moments()), None);
    }

    #[test]
    fn only_a_body_far_from_a_solid_of_revolution_turns_about_its_own_axes() {
        let mass = |k: DVec3| crate::geometry::shape::MassProperties {
            mass: 0.05,
            local_com: DVec3::ZERO,
            principal_inertia: k,
            principal_frame: DQuat::from_rotation_z(0.3),
        };
        // The chess set's knight and king (kg m^2): the king's cross parts its two moments
        // across its axis by 2e-4 of them, the knight's head by 8 %.
        let knight = own_axes(&mass(DVec3::new(1.739e-6, 6.213e-6, 6.736e-6)));
        let axes = knight.expect("a knight turns about its own axes");
        assert!((axes[0] - DQuat::from_rotation_z(0.3) * DVec3::X).length() < 1e-12);
        assert!(own_axes(&mass(DVec3::new(1.776e-6, 1.9044e-5, 1.9047e-5))).is_none());
        assert!(own_axes(&mass(DVec3::splat(2e-6))).is_none());
    }

    #[test]
    fn lays_turn_the_long_axis_along_the_part_across_the_line_of_sight() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fly");
        let p = Problem::new(crate::scene::load(&dir).unwrap());
        let cam = &p.scene.camera;
        let mass = &p.scene.occluders[0].mass;
        let com = cam.light + DVec3::new(0.3, -0.2, -2.0);
        let along = (com - cam.light).normalize();
        for angle in [0.0f64, 0.7, -1.2] {
            // Stood on its end, along the line of sight: its shadow has no long axis.
            let now = DQuat::from_rotation_arc(mass.long_axis(), along);
            let turns = lays(&p, 0, now, com, angle);
            assert_eq!(turns.len(), 2);
            let d = cam.u * angle.cos() - cam.v * angle.sin();
            let d = (d - along * d.dot(along)).normalize();
            let ends: Vec<f64> = turns
                .iter()
                .map(|&(axis, a)| (DQuat::from_axis_angle(axis, a) * now * mass.long_axis()).dot(d))
                .collect();
            assert!(
                (ends[0] - 1.0).abs() < 1e-9 && (ends[1] + 1.0).abs() < 1e-9,
                "{ends:?}"
            );
            // Laid already: nothing to do.
            let laid = DQuat::from_axis_angle(turns[0].0, turns[0].1) * now;
            assert!(lays(&p, 0, laid, com, angle).is_empty());
        }
    }
}
