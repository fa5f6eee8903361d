//! Moves: the global jumps that CMA-ES's local steps do not make.
//!
//! A round of moves ([`improve`]) asks every [`Move`] of the registry ([`MOVES`]) for
//! its offers from the launch kept (a [`Round`]: each body's [`Sight`], the bare
//! target, its largest hole), evaluates each as a sample, slides the few best in depth
//! ([`Search::polish`]) and fits their blocks, and takes the best-ranked when it ranks
//! better than the launch kept; rounds repeat while one takes a move. The moves, one
//! family a file, are what `docs/solver.md` tabulates:
//! - [`reassign`]: send bodies to other parts ([`Swap`], and the exchanges of pose
//!   and place; [`Fill`] the largest bare part);
//! - [`reorient`]: search a mesh's pose where it is ([`Reorient`]: turns, align, lay);
//! - [`seat`]: place and pose a body from scratch ([`Seat`]: seats on its own place, on
//!   another's, on half of a part, and the trades of places; [`PoseFit`] of blocks);
//! - [`slide`]: depth and size ([`Fit`], and the slides of [`Search::polish`]).
//!
//! A move changes a body's launch velocity, and its spin where it asks for an
//! orientation at `t` (the spin that reaches it by Newton's method on the free flight,
//! [`spin_reaching`]): the centre of mass of a free flight in a vacuum is at
//! `c0 + v t + g t^2 / 2` at `t`, so the velocity that puts it at a point is exact
//! ([`sight`]). Every candidate is evaluated like any sample and ranked by the solver's rank
//! (contacts first under the constraint mode).

mod pose;
mod reassign;
mod reorient;
mod seat;
mod seats;
mod sight;
mod slide;
mod spin;

use glam::{DQuat, DVec3};

use pose::{fit_and_launch, fits_pose};
use reassign::{Fill, Hole, Swap};
use reorient::Reorient;
use seat::{PoseFit, Seat};
use sight::{exchangeable, sights, Sight, MAX_EXCHANGE_PAIRS, MAX_MESH_TRADES};
// The moves' shared geometry, for the pose and spin searches.
use sight::{aim, allowed_depth, lowest_centre, MIN_DEPTH, REVOLUTION};
use slide::Fit;
pub use spin::spin_reaching;

use crate::energy::{Term, Weights, DIVERGED_ENERGY};
use crate::evaluate::{Evaluation, Held, Problem, Workspace};
use crate::geometry::shape::Shape;
use crate::output::solution::MoveRecord;
use crate::scene::Scene;
use crate::shadow::mask::Mask;
use crate::sim::flight::FreeFlight;

/// A move: offers candidates from the launch kept.
trait Move: Sync {
    /// What a pass's record calls the moves of this kind that it took
    /// ([`MoveReport::taken`]).
    fn name(&self) -> &'static str;
    /// Evaluate this move's candidates from the round's launch into `out`.
    fn offer(&self, round: &Round, out: &mut Offers);
}

/// The registry of moves, in the order a round asks them (the order of equal offers).
const MOVES: [&dyn Move; 6] = [&Swap, &Fill, &Fit, &Reorient, &Seat, &PoseFit];

/// What a round of moves sees of the launch kept.
struct Round<'a> {
    problem: &'a Problem,
    held: &'a Held,
    /// The launch kept, of every body.
    params: &'a [f64],
    /// The launched bodies that vary, the blocks and the meshes among them.
    movable: &'a [usize],
    blocks: &'a [usize],
    meshes: &'a [usize],
    /// Whether each body varies.
    vary: &'a [bool],
    /// The wrong pixels of the picture kept.
    wrong: i64,
    /// Each body's orientation at `t`, and its pose.
    turned: Vec<DQuat>,
    current_poses: Vec<(DVec3, DQuat)>,
    sights: Vec<Option<Sight>>,
    /// The target that no shadow covers, and its largest blob.
    bare: Mask,
    hole: Option<Hole>,
    /// The call's first round.
    first: bool,
    options: MoveOptions,
    /// Whether exchanges of pose and place are offered (few pairs could exchange).
    exchanges_wanted: bool,
    /// The groups of bodies that trade places in this call.
    trades: &'a [&'a [usize]],
}

/// The offers of a round, evaluated, and the scratch the moves build them in.
struct Offers<'s, 'a> {
    search: &'s mut Search<'a>,
    ws: &'s mut Workspace,
    /// The candidate launch a move edits, then offers.
    candidate: &'s mut Vec<f64>,
    flight: &'s mut FreeFlight,
    list: Vec<Offer>,
    /// The name the offers get: the move's, or the kind of its offers it now makes.
    name: &'static str,
}

impl<'s, 'a> Offers<'s, 'a> {
    fn new(
        search: &'s mut Search<'a>,
        ws: &'s mut Workspace,
        candidate: &'s mut Vec<f64>,
        flight: &'s mut FreeFlight,
    ) -> Self {
        Offers {
            search,
            ws,
            candidate,
            flight,
            list: Vec::new(),
            name: "",
        }
    }

    /// Evaluate the candidate as a move of `bodies` and keep it.
    fn offer(&mut self, bodies: &[usize]) {
        let eval = self.search.evaluate(self.candidate, self.ws);
        self.list.push(Offer {
            launch: self.candidate.clone(),
            bodies: bodies.to_vec(),
            eval,
            name: self.name,
        });
    }

    /// Evaluate `launch` as a move of `bodies` and keep it.
    fn offer_launch(&mut self, launch: &[f64], bodies: &[usize]) {
        let eval = self.search.evaluate(launch, self.ws);
        self.list.push(Offer {
            launch: launch.to_vec(),
            bodies: bodies.to_vec(),
            eval,
            name: self.name,
        });
    }
}

/// What one call of [`improve`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MoveReport {
    /// The moves taken, in order, each named by its [`Move`] (or the kind of that
    /// move's offers), as a pass records them.
    pub taken: Vec<MoveRecord>,
    /// Samples evaluated.
    pub samples: usize,
    /// The launch of the candidate with the lowest energy of all, when it has a contact
    /// and a lower energy than the launch kept: a better picture that a local search
    /// may free of its contact (the caller may start a run from it).
    pub promising: Option<Vec<f64>>,
}

/// Moves of a pass polished by [`Search::polish`]: those whose pictures rank first.
const POLISHED: usize = 4;

/// The evaluations of one call of [`improve`], or of one of its parallel parts: counts
/// them, keeps them in order for the caller's record, and keeps the promising launch
/// (see [`MoveReport::promising`]).
struct Search<'a> {
    problem: &'a Problem,
    held: &'a Held,
    weights: &'a Weights,
    records: Vec<Evaluation>,
    samples: usize,
    promising: Option<(f64, Vec<f64>)>,
}

impl<'a> Search<'a> {
    fn new(problem: &'a Problem, held: &'a Held, weights: &'a Weights) -> Self {
        Search {
            problem,
            held,
            weights,
            records: Vec::new(),
            samples: 0,
            promising: None,
        }
    }

    /// A search of its own for a part that runs beside the others ([`Scratch`]).
    fn part(&self) -> Search<'a> {
        Search::new(self.problem, self.held, self.weights)
    }

    /// Take in `part`'s evaluations as if they were made here, after those made so far:
    /// its promising launch (its first of the least energy) replaces this one's only
    /// where strictly lower, as each evaluation's does in [`Search::evaluate`].
    fn absorb(&mut self, part: Search<'a>) {
        self.samples += part.samples;
        self.records.extend(part.records);
        if let Some((energy, launch)) = part.promising {
            if self.promising.as_ref().is_none_or(|p| energy < p.0) {
                self.promising = Some((energy, launch));
            }
        }
    }

    /// The energy without the contact term: the picture and the scene's pulls.
    fn free(&self, e: &Evaluation) -> f64 {
        e.total - self.weights.get(Term::Contact) * e.raw[Term::Contact as usize]
    }

    fn evaluate(&mut self, candidate: &[f64], ws: &mut Workspace) -> Evaluation {
        let e = self
            .problem
            .evaluate_held(self.held, candidate, self.weights, ws);
        self.samples += 1;
        self.records.push(e);
        if e.outcome.own_contact > 0.0
            && e.total < DIVERGED_ENERGY
            && self.promising.as_ref().is_none_or(|p| self.free(&e) < p.0)
        {
            self.promising = Some((self.free(&e), candidate.to_vec()));
        }
        e
    }
}

/// A move of a pass, as evaluated: the launch, the bodies it moved, and its evaluation.
struct Offer {
    launch: Vec<f64>,
    bodies: Vec<usize>,
    eval: Evaluation,
    name: &'static str,
}

/// How far [`improve`] goes, from what, and what for.
#[derive(Clone, Copy, Debug)]
pub struct MoveOptions {
    /// Moves taken at most (passes that end with a move).
    pub max_moves: usize,
    /// Whether the best is a local optimum of its own search (a restart's start, a
    /// stage of several bodies, the polish): then the moves of one body are polished
    /// too, not only the swaps. Where it is not (the first run of a stage that places
    /// one body), a move's gain over an unrefined start says little of where the search
    /// ends (on the 飞 example, a polished turn taken so left the hook stroke 0.004 of
    /// IoU worse).
    pub settled: bool,
    pub purpose: Purpose,
}

/// What a call of [`improve`] is for: the pass that calls it. What each purpose's
/// rounds do beyond the moves every round offers is this table
/// ([`Purpose::trades`], [`Purpose::seats_blocks`], [`Purpose::evolves_fits`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// A stage's moves before its runs.
    Stage,
    /// The last stage's trades: bodies of one kind and different shapes trade places,
    /// and the meshes are seated, in every pass
    /// ([`Seats::trade_scan`](seats::Seats::trade_scan)); where no group may trade (no
    /// two blocks of different sizes, and no two meshes of different shapes among at
    /// most [`MAX_MESH_TRADES`] ordered pairs) nothing moves.
    Trade,
    /// The last stage's polish: the blocks are seated on their own places too, as the
    /// meshes are, in every pass (a block tilted the wrong way, its outline near its
    /// part's), and each fit of a block is refined by CMA-ES over its pose after the
    /// compass search ([`fit_pose`](pose::fit_pose)'s `thorough`).
    ///
    /// Neither in the stages' moves: there, seating the blocks lowered as many planted
    /// block problems as it raised (a seat taken early leaves a block's part to the runs
    /// after it in a pose that is not yet its own), and the refined fits raised 12 and
    /// lowered 8 of the 35 planted problems of seeds 11400 to 11406 (boxes 11402 0.9847
    /// to 0.9955, but boxes12 11401 0.9960 to 0.9724), where in the polish alone, whose
    /// moves are kept only where the picture is no worse, they raised 8 and lowered 1
    /// (by 0.0001).
    Polish,
}

impl Purpose {
    /// Whether bodies trade places in every pass.
    pub fn trades(self) -> bool {
        self == Purpose::Trade
    }

    /// Whether the blocks are seated on their own places in every pass.
    pub fn seats_blocks(self) -> bool {
        self == Purpose::Polish
    }

    /// Whether each fit of a block is refined by CMA-ES over its pose.
    pub fn evolves_fits(self) -> bool {
        self == Purpose::Polish
    }
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
    pool: &rayon::ThreadPool,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> MoveReport {
    let scene = &problem.scene;
    let mut report = MoveReport::default();
    let Bodies {
        movable,
        blocks,
        meshes,
    } = Bodies::of(scene, vary);
    let trades = trade_groups(scene, [&blocks, &meshes], options.purpose.trades());
    if movable.is_empty() || (options.purpose.trades() && trades.is_empty()) {
        return report;
    }
    let mut search = Search::new(problem, held, weights);
    let mut scratch = Scratch::per_thread(problem, params, pool);
    let exchanges_wanted = exchange_pairs(scene, &movable) <= MAX_EXCHANGE_PAIRS;
    let vary: Vec<bool> = (0..scene.occluders.len())
        .map(|k| movable.contains(&k))
        .collect();
    for pass in 0..options.max_moves {
        let current = problem.evaluate_held(held, params, weights, ws);
        let bare = problem.target.mask.and_not(&ws.mask);
        // The poses at `t` of the launch kept (the offers overwrite `ws`).
        let current_poses = ws.poses.clone();
        let round = Round {
            problem,
            held,
            params,
            movable: &movable,
            blocks: &blocks,
            meshes: &meshes,
            vary: &vary,
            wrong: problem.target.mask.xor_count(&ws.mask) as i64,
            turned: current_poses.iter().map(|p| p.1).collect(),
            sights: sights(problem, &movable, &bare, ws),
            hole: bare
                .blobs()
                .into_iter()
                .max_by(|a, b| a.0.cmp(&b.0).then(b.1.x.total_cmp(&a.1.x))),
            bare,
            current_poses,
            first: pass == 0,
            options,
            exchanges_wanted,
            trades: &trades,
        };
        // Every move of the round, evaluated; the best few are then polished.
        let mut offers = offer_all(pool, &round, &mut search, &mut scratch);
        // Polish the moves that made the best pictures (a move that made a poor one
        // seldom becomes the best by a change of depth), then take the best-ranked.
        offers.sort_by(|a, b| search.free(&a.eval).total_cmp(&search.free(&b.eval)));
        polish_best(
            pool,
            &mut offers,
            (held, &vary),
            options,
            &mut search,
            &mut scratch,
        );
        match best_offer(&offers, rank, &current) {
            Some(offer) => {
                let e = offer.eval;
                params.copy_from_slice(&offer.launch);
                report.taken.push(MoveRecord {
                    name: offer.name.to_string(),
                    iou_before: current.iou,
                    iou_after: e.iou,
                });
                *best = e;
            }
            None => break,
        }
    }
    for e in &search.records {
        record(e);
    }
    // Leave the workspace holding the kept launch's flight and shadow.
    *best = problem.evaluate_held(held, params, weights, ws);
    let kept = search.free(best);
    MoveReport {
        samples: search.samples,
        promising: search
            .promising
            .filter(|(energy, _)| *energy < kept)
            .map(|(_, launch)| launch),
        ..report
    }
}

/// The groups of bodies that trade places (none unless `trades`): the blocks, and the
/// meshes where few enough, each group only where its shapes differ.
fn trade_groups<'a>(scene: &Scene, groups: [&'a [usize]; 2], trades: bool) -> Vec<&'a [usize]> {
    let shape = |i: usize| &scene.occluders[i].shape;
    groups
        .into_iter()
        .filter(|group| {
            trades
                && group.iter().any(|&i| shape(i) != shape(group[0]))
                && (group.len() * group.len().saturating_sub(1) <= MAX_MESH_TRADES
                    || fits_pose(shape(group[0])))
        })
        .collect()
}

/// The first of the offers that ranks best, if it ranks better than the launch kept
/// (`current`) and mends something: it draws a better picture, or the launch kept has a
/// contact of its own.
///
/// A move that draws the same picture mends nothing the runs would not: two equal balls
/// sent each to the other's part rank better where their launches are slower, and on a
/// design of 64 balls with a dozen radii such swaps were taken pass after pass, each
/// pass 4,096 samples of every ball (set 33's jellyfish: the last stage's moves and
/// polish 57 moves and 31 s for IoU +0.0011; the whole solve 63 s, 26 s without them).
fn best_offer<'a>(
    offers: &'a [Offer],
    rank: &dyn Fn(&Evaluation) -> f64,
    current: &Evaluation,
) -> Option<&'a Offer> {
    let mut best = (rank(current), None);
    let mends = |e: &Evaluation| e.iou > current.iou || current.outcome.own_contact > 0.0;
    for offer in offers.iter().filter(|o| mends(&o.eval)) {
        let r = rank(&offer.eval);
        if r < best.0 {
            best = (r, Some(offer));
        }
    }
    best.1
}

/// The launched bodies of `vary`, and the blocks and meshes among them.
struct Bodies {
    movable: Vec<usize>,
    blocks: Vec<usize>,
    meshes: Vec<usize>,
}

impl Bodies {
    fn of(scene: &crate::scene::Scene, vary: &[usize]) -> Bodies {
        let movable: Vec<usize> = vary
            .iter()
            .copied()
            .filter(|&i| scene.occluders[i].launched)
            .collect();
        let of = |keep: &dyn Fn(&Shape) -> bool| -> Vec<usize> {
            movable
                .iter()
                .copied()
                .filter(|&i| keep(&scene.occluders[i].shape))
                .collect()
        };
        let blocks = of(&fits_pose);
        let meshes = of(&|s| matches!(s, Shape::Mesh(_)));
        Bodies {
            movable,
            blocks,
            meshes,
        }
    }
}

/// The pairs of `movable` bodies that could exchange pose and place.
fn exchange_pairs(scene: &crate::scene::Scene, movable: &[usize]) -> usize {
    movable
        .iter()
        .enumerate()
        .map(|(a, &i)| {
            movable[a + 1..]
                .iter()
                .filter(|&&j| exchangeable(scene, i, j))
                .count()
        })
        .sum()
}

/// Slide the [`POLISHED`] best of `offers` (sorted best first; those of one body only
/// where `options.settled`) in depth ([`Search::polish`]), and fit the blocks of
/// the best one and of every polished swap on their new poses
/// ([`fit_and_launch`]), keeping a fit that draws a better
/// picture. A block turned onto another face, or sent to a new part, rarely has its
/// part's size, place and tilt at once. (Fitting those of all four best moves raised
/// the hand-made "to fly" a little more at 1.1 to 1.35 times the time: the spins that
/// reach fitted poses are faster, and every later flight of a faster tumbling block
/// costs more.) Each offer is polished beside the others ([`beside`]).
fn polish_best<'a>(
    pool: &rayon::ThreadPool,
    offers: &mut [Offer],
    (held, vary): (&Held, &[bool]),
    options: MoveOptions,
    search: &mut Search<'a>,
    scratch: &mut [Scratch],
) {
    let problem = search.problem;
    let is_block = |i: usize| fits_pose(&problem.scene.occluders[i].shape);
    let chosen: Vec<(usize, &mut Offer)> = offers
        .iter_mut()
        .filter(|o| options.settled || o.bodies.len() > 1)
        .take(POLISHED)
        .enumerate()
        .collect();
    beside(pool, search, chosen, scratch, |(rank, offer), out| {
        offer.eval = out
            .search
            .polish(&mut offer.launch, offer.eval, &offer.bodies, out.ws);
        let fit = rank == 0 || offer.bodies.len() > 1;
        if !(fit && offer.bodies.iter().any(|&b| is_block(b))) {
            return;
        }
        out.candidate.copy_from_slice(&offer.launch);
        out.search.evaluate(out.candidate, out.ws);
        let mut moved = false;
        for &b in offer.bodies.iter().filter(|&&b| is_block(b)) {
            moved |= fit_and_launch(
                problem,
                held,
                vary,
                b,
                out.candidate,
                options.purpose.evolves_fits(),
                out.ws,
                out.flight,
            );
        }
        if moved {
            let e = out.search.evaluate(out.candidate, out.ws);
            if out.search.free(&e) < out.search.free(&offer.eval) {
                offer.eval = e;
                offer.launch.copy_from_slice(out.candidate);
            }
        }
    });
}

/// What a thread works in on the parts of a round ([`beside`]): a workspace, a
/// candidate launch and a flight.
struct Scratch {
    ws: Workspace,
    candidate: Vec<f64>,
    flight: FreeFlight,
}

impl Scratch {
    /// One for each of `pool`'s threads.
    fn per_thread(problem: &Problem, params: &[f64], pool: &rayon::ThreadPool) -> Vec<Scratch> {
        (0..pool.current_num_threads())
            .map(|_| Scratch {
                ws: problem.workspace(),
                candidate: params.to_vec(),
                flight: FreeFlight::default(),
            })
            .collect()
    }
}

/// Every move of `round`, evaluated, each beside the others ([`beside`]): their offers
/// in the registry's order.
fn offer_all<'a>(
    pool: &rayon::ThreadPool,
    round: &Round,
    search: &mut Search<'a>,
    scratch: &mut [Scratch],
) -> Vec<Offer> {
    beside(pool, search, MOVES.to_vec(), scratch, |m, out| {
        out.name = m.name();
        m.offer(round, out)
    })
    .into_iter()
    .flatten()
    .collect()
}

/// Run `work` on each of `items` beside the others on `pool`, each with a search of its
/// own, the pool's threads taking the next item as they come free, each on a scratch of
/// its own (one per thread); then absorb the items' searches into `search` in the items'
/// order and return what each offered, in that order. Each item sets up the workspace
/// and candidate it reads (as when one scratch served them all, one after the other),
/// so the offers, the samples and their order are those of the items run one after the
/// other, whatever the threads.
///
/// Why: a round's moves and polish draw thousands of shadows of one body (a seat scans
/// hundreds of poses, a thorough fit evolves one), and on one thread they left the
/// second core idle for a third of a solve of blocks or chess pieces.
fn beside<'a, T: Send>(
    pool: &rayon::ThreadPool,
    search: &mut Search<'a>,
    items: Vec<T>,
    scratch: &mut [Scratch],
    work: impl Fn(T, &mut Offers<'_, 'a>) + Sync,
) -> Vec<Vec<Offer>> {
    use rayon::prelude::*;
    let queue = std::sync::Mutex::new(items.into_iter().enumerate());
    let next = || queue.lock().unwrap_or_else(|e| e.into_inner()).next();
    let parent = &*search;
    let mut done: Vec<(usize, Search<'a>, Vec<Offer>)> = pool.install(|| {
        scratch
            .par_iter_mut()
            .flat_map_iter(|s| {
                let mut mine = Vec::new();
                while let Some((k, item)) = next() {
                    let mut part = parent.part();
                    let mut out =
                        Offers::new(&mut part, &mut s.ws, &mut s.candidate, &mut s.flight);
                    work(item, &mut out);
                    let offered = out.list;
                    mine.push((k, part, offered));
                }
                mine
            })
            .collect()
    });
    done.sort_by_key(|d| d.0);
    done.into_iter()
        .map(|(_, part, offered)| {
            search.absorb(part);
            offered
        })
        .collect()
}
