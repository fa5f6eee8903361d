//! Pose searches at `t` in pixels: [`fit_pose`] mends a block's pose on its own part,
//! [`seat_pose`] scans a body's poses over a place of the picture (a mesh's place, or
//! a side of a part that a hidden block shares, [`Seats::splits`]); both draw one body's
//! shadow ([`Seat`]) over the others' and count wrong pixels, then
//! [`launch_to`] reaches the pose found.
//!
//! Data flow: [`Seats`] (or [`fit_and_launch`]) takes the others' shadows from the
//! workspace, [`Seat`] draws body `i` alone at trial poses, the best pose is launched.

use glam::{DQuat, DVec2, DVec3};

use super::spin::{launch_to, spin_guesses};
use super::{allowed_depth, lowest_centre, Sight, MIN_DEPTH, REVOLUTION};
use crate::evaluate::{Held, Problem, Workspace};
use crate::geometry::shape::Shape;
use crate::optimize::cmaes::{Cmaes, CmaesConfig};
use crate::scene::Launch;
use crate::shadow::mask::Mask;
use crate::sim::flight::FreeFlight;

/// A place of the picture for a body's shadow, as [`Seat::place`] takes it: centroid
/// (canvas pixels), area (pixels) and the depth of a body that casts it (0 at the
/// light, 1 on the receiver), where the search for its own depth starts.
pub(super) type Place = (DVec2, f64, f64);

/// Turn (rad) of the first steps of [`fit_pose`] about each world axis.
pub(super) const POSE_TURN: f64 = 0.1;
/// Shift (pixels of its shadow on the receiver) of the first steps of [`fit_pose`]
/// across the line of sight.
pub(super) const POSE_SHIFT: f64 = 3.0;
/// Change of depth (a fraction of it) of the first steps of [`fit_pose`].
pub(super) const POSE_DEPTH: f64 = 0.03;
/// The first step of [`Seat::evolve`], in units of the compass's first steps (0.03 rad,
/// 0.9 pixel, 0.9 % of the depth).
pub(super) const POSE_CMA_STEP: f64 = 0.3;
/// Poses per generation of [`Seat::evolve`] (the default for six dimensions is 9).
pub(super) const POSE_CMA_POPULATION: usize = 12;
/// Generations of [`Seat::evolve`] at most, and without a gain before it stops.
pub(super) const POSE_CMA_GENERATIONS: usize = 300;
pub(super) const POSE_CMA_STAGNATION: usize = 40;
/// Times [`fit_pose`] halves its steps; it sweeps each step size until a sweep gains
/// nothing, at most [`POSE_SWEEPS`] times.
pub(super) const POSE_LEVELS: usize = 5;
pub(super) const POSE_SWEEPS: usize = 4;

/// One body's shadow drawn at trial poses at `t` over every other shadow (`others`),
/// against the target: the pose searches of [`fit_pose`] and [`seat_pose`] count the
/// wrong pixels of the whole picture for each pose, drawing the one body alone.
pub(super) struct Seat<'a> {
    problem: &'a Problem,
    i: usize,
    /// Only body `i`, for [`Problem::shadow_only`].
    only: Vec<bool>,
    /// The lowest its centre of mass may be ([`lowest_centre`]).
    floor: Option<f64>,
    /// The wrong pixels of the others' shadows alone.
    base: i64,
    /// The target or another shadow: a pixel of the body's shadow there is not wrong,
    /// or was counted in `base` already.
    dark: Mask,
    /// The target pixels that no other shadow covers.
    bare: Mask,
}

impl<'a> Seat<'a> {
    fn new(problem: &'a Problem, i: usize, others: &Mask) -> Self {
        let target = &problem.target.mask;
        let mut only = vec![false; problem.scene.occluders.len()];
        only[i] = true;
        let mut dark = others.clone();
        dark.or_assign(target);
        Seat {
            problem,
            i,
            only,
            floor: lowest_centre(problem, i),
            base: others.xor_count(target) as i64,
            dark,
            bare: target.and_not(others),
        }
    }

    /// The depth of a centre of mass along its line from the light: 0 at the light, 1
    /// on the receiver.
    fn depth(&self, com: DVec3) -> f64 {
        let scene = &self.problem.scene;
        let light = scene.camera.light;
        let normal = scene.receiver.normal;
        (com - light).dot(normal) / (scene.receiver.center - light).dot(normal)
    }

    /// Draw the body's shadow alone, centre of mass at `com`, turned to `q`, into
    /// `ws.mask` (`ws.poses[i]` holds the pose).
    fn draw(&self, com: DVec3, q: DQuat, ws: &mut Workspace) {
        let local = self.problem.scene.occluders[self.i].mass.local_com;
        ws.poses[self.i] = (com - q * local, q);
        self.problem.shadow_only(&self.only, ws);
    }

    /// The wrong pixels of the whole picture with the body at this pose: those of the
    /// others alone, plus the pixels of its shadow `s` on neither the target nor another
    /// shadow, minus those of `s` on bare target. Counted on `s` alone, whose rows are
    /// few, rather than on the whole canvas. `i64::MAX` below the table's reach.
    fn cost(&self, com: DVec3, q: DQuat, ws: &mut Workspace) -> i64 {
        if self.floor.is_some_and(|z| com.z < z) {
            return i64::MAX;
        }
        self.draw(com, q, ws);
        let s = &ws.mask;
        self.base + s.count() as i64
            - s.and_count(&self.dark) as i64
            - s.and_count(&self.bare) as i64
    }

    /// The light, two directions across the line of sight from it to `com`, and the
    /// first step of a shift along them ([`POSE_SHIFT`] pixels of the shadow, in metres
    /// at `com`): the frame of the pose searches' shifts and changes of depth.
    fn axes(&self, com: DVec3) -> (DVec3, DVec3, DVec3, f64) {
        let light = self.problem.scene.camera.light;
        let sight = (com - light).normalize();
        let e1 = sight.any_orthonormal_vector();
        let e2 = sight.cross(e1);
        let c = &self.problem.canvas;
        let pixel = (c.pixel_to_world(1.0, 0.0) - c.pixel_to_world(0.0, 0.0)).length();
        (light, e1, e2, POSE_SHIFT * pixel * self.depth(com))
    }

    /// A compass search from the pose `(com, q)`, whose cost is `start`: turns about the
    /// world axes, shifts across the line of sight and changes of depth, first `first`
    /// times the steps [`POSE_TURN`], [`POSE_SHIFT`] and [`POSE_DEPTH`], halved `levels`
    /// times; each size is swept until a sweep gains nothing, at most [`POSE_SWEEPS`]
    /// times. Returns the best cost and pose.
    fn compass(
        &self,
        (com, q): (DVec3, DQuat),
        start: i64,
        (first, levels): (f64, usize),
        ws: &mut Workspace,
    ) -> (i64, DVec3, DQuat) {
        let (light, e1, e2, shift) = self.axes(com);
        let (mut com, mut q, mut best) = (com, q, start);
        let mut h = first;
        for _ in 0..levels {
            for _ in 0..POSE_SWEEPS {
                let mut gained = false;
                for k in 0..6 {
                    for sign in [1.0, -1.0] {
                        let (tc, tq) = match k {
                            0..=2 => {
                                let axis = [DVec3::X, DVec3::Y, DVec3::Z][k];
                                (com, DQuat::from_axis_angle(axis, sign * h * POSE_TURN) * q)
                            }
                            3 => (com + e1 * (sign * h * shift), q),
                            4 => (com + e2 * (sign * h * shift), q),
                            _ => (light + (com - light) * (1.0 + sign * h * POSE_DEPTH), q),
                        };
                        let e = self.cost(tc, tq, ws);
                        if e < best {
                            (best, com, q) = (e, tc, tq.normalize());
                            gained = true;
                            break;
                        }
                    }
                }
                if !gained {
                    break;
                }
            }
            h *= 0.5;
        }
        (best, com, q)
    }

    /// A CMA-ES search from the pose `(com, q)`, whose cost is `start`, over the same
    /// six moves as [`Seat::compass`] (turns about the world axes, shifts across the line
    /// of sight, a change of depth, in units of the compass's first steps), all at once:
    /// [`POSE_CMA_STEP`], [`POSE_CMA_POPULATION`], at most [`POSE_CMA_GENERATIONS`]
    /// generations, stopped after [`POSE_CMA_STAGNATION`] without a gain. Returns the
    /// best cost and pose (the start when nothing is better). Deterministic: its seed is
    /// the body's index.
    ///
    /// Why: a block's outline a pixel or two off its part lies in a valley of the pixel
    /// count along a combination of the moves (a turn and a shift and a change of depth
    /// together, the outline's perspective kept), where every move alone costs pixels;
    /// the compass stops there, CMA-ES learns the valley's direction.
    fn evolve(
        &self,
        (com, q): (DVec3, DQuat),
        start: i64,
        ws: &mut Workspace,
    ) -> (i64, DVec3, DQuat) {
        let (light, e1, e2, shift) = self.axes(com);
        let pose = |y: &[f64]| {
            let turn = DVec3::new(y[0], y[1], y[2]) * POSE_TURN;
            let tq = (DQuat::from_scaled_axis(turn) * q).normalize();
            let tc = com + e1 * (y[3] * shift) + e2 * (y[4] * shift);
            (light + (tc - light) * (1.0 + y[5] * POSE_DEPTH), tq)
        };
        let config = CmaesConfig {
            population: Some(POSE_CMA_POPULATION),
            max_generations: POSE_CMA_GENERATIONS,
            // Costs are whole pixels: any gain counts, and equal costs do not stop it.
            tol_fun: 0.0,
            stagnation_window: POSE_CMA_STAGNATION,
            ..CmaesConfig::default()
        };
        let mut cma = Cmaes::new(&[0.0; 6], POSE_CMA_STEP, config, self.i as u64);
        let mut best = (start, com, q);
        let mut fitness = [0.0; POSE_CMA_POPULATION];
        let mut trial = [0.0; 6 * POSE_CMA_POPULATION];
        loop {
            trial.copy_from_slice(cma.ask());
            for (f, y) in fitness.iter_mut().zip(trial.chunks_exact(6)) {
                let (tc, tq) = pose(y);
                let cost = self.cost(tc, tq, ws);
                *f = cost as f64;
                if cost < best.0 {
                    best = (cost, tc, tq);
                }
            }
            cma.tell(&fitness);
            if cma.stop().is_some() {
                return best;
            }
        }
    }

    /// The body turned to `q` and placed so that its shadow has about `area` pixels
    /// and its centroid at `centroid` (canvas pixels), from the depth `depth`: drawn
    /// twice to correct the depth (a shadow's area goes as the inverse square of the
    /// depth) and the line of sight (the shadow's centroid follows the point where the
    /// line meets the receiver), then once for the cost. Returns the cost and the
    /// centre of mass.
    fn place(
        &self,
        q: DQuat,
        (centroid, area, mut depth): Place,
        ws: &mut Workspace,
    ) -> (i64, DVec3) {
        let light = self.problem.scene.camera.light;
        let c = &self.problem.canvas;
        let want = c.pixel_to_world(centroid.x, centroid.y);
        let mut on_receiver = want;
        let mut com =
            light + (on_receiver - light) * allowed_depth(self.problem, self.i, on_receiver, depth);
        for _ in 0..2 {
            self.draw(com, q, ws);
            let m = ws.mask.moments();
            let Some(got) = m.centroid() else {
                return (i64::MAX, com);
            };
            depth *= (m.count / area).sqrt();
            on_receiver += want - c.pixel_to_world(got.x, got.y);
            com = light
                + (on_receiver - light) * allowed_depth(self.problem, self.i, on_receiver, depth);
        }
        (self.cost(com, q, ws), com)
    }
}

/// A better pose at `t` for body `i`, searched on the pose itself: the shadow of the
/// body at its pose in `ws.poses`, drawn over `others` (every other shadow), against the
/// target, by a compass search over turns about the world axes, shifts across its line
/// of sight and changes of depth ([`Seat::compass`]), then, when `thorough`, by CMA-ES
/// over all of them at once ([`Seat::evolve`]). A launch spin reaches an
/// orientation at `t` through the whole tumbling flight, where a small change of spin
/// turns the body anywhere; a wrongly tilted block whose outline is near its part's is
/// mended here in pixels, and the spin that reaches the pose is then solved for. Returns
/// the centre of mass and orientation found (`ws.poses[i]` holds it) when it draws fewer
/// wrong pixels than the pose it started from.
pub(super) fn fit_pose(
    problem: &Problem,
    i: usize,
    others: &Mask,
    thorough: bool,
    ws: &mut Workspace,
) -> Option<(DVec3, DQuat)> {
    let local = problem.scene.occluders[i].mass.local_com;
    let (origin, q0) = ws.poses[i];
    let com0 = origin + q0 * local;
    let seat = Seat::new(problem, i, others);
    if !(MIN_DEPTH..=1.0).contains(&seat.depth(com0)) {
        return None;
    }
    let start = seat.cost(com0, q0, ws);
    let (mut best, mut com, mut q) = seat.compass((com0, q0), start, (1.0, POSE_LEVELS), ws);
    if thorough {
        (best, com, q) = seat.evolve((com, q), best, ws);
    }
    ws.poses[i] = (com - q * local, q);
    (best < start).then_some((com, q))
}

/// Axis directions tried by [`seat_pose`], spread evenly over the sphere.
pub(super) const SEAT_DIRECTIONS: usize = 64;
/// Turns about its long axis tried by [`seat_pose`] for each direction of a body that
/// is not a solid of revolution (a sixth of a turn apart).
pub(super) const SEAT_ROLLS: usize = 6;
/// Poses of a scan that [`seat_pose`] refines by [`Seat::compass`].
pub(super) const SEAT_KEPT: usize = 3;
/// The first step (times [`POSE_TURN`] and the others) and halvings of the compass
/// search of a seat: from 0.4 rad down to the steps [`fit_pose`] ends with.
pub(super) const SEAT_STEPS: (f64, usize) = (4.0, 7);
/// Pairs seated on each other's places that [`improve`](super::improve) refines, those
/// whose scans draw the best pictures.
pub(super) const SEAT_PAIRS: usize = 16;

/// `n` directions spread evenly over the unit sphere (a Fibonacci lattice).
pub(super) fn sphere_directions(n: usize) -> impl Iterator<Item = DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n).map(move |k| {
        let z = 1.0 - (2 * k + 1) as f64 / n as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * k as f64;
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

/// The body-frame axis of a body with two equal principal moments (within
/// [`REVOLUTION`] of the largest): the axis of the third, a lathed chess piece's axis of
/// symmetry. `None` when all three differ, or all three are equal.
pub(super) fn symmetry_axis(mass: &crate::geometry::shape::MassProperties) -> Option<DVec3> {
    let k = mass.principal_inertia.to_array();
    let tol = REVOLUTION * mass.principal_inertia.max_element();
    let close = |a: usize, b: usize| (k[a] - k[b]).abs() <= tol;
    let odd = match (close(1, 2), close(0, 2), close(0, 1)) {
        (true, false, false) => 0,
        (false, true, false) => 1,
        (false, false, true) => 2,
        _ => return None,
    };
    Some(mass.principal_frame * DVec3::AXES[odd])
}

/// Seat body `i` (`seat`, turned to `now` at `t`) on a place of the picture, `(centroid,
/// area, depth)` as [`Seat::place`] takes it: posed with its axis (of symmetry for a
/// solid of revolution, else its long axis, then turned about it by [`SEAT_ROLLS`]) in
/// each of [`SEAT_DIRECTIONS`] directions, by the least turn from `now`, each placed at
/// the place's centroid and area; the `kept` best poses are then refined by a compass
/// search ([`SEAT_STEPS`]), none when `kept` is 0 (a scan). Returns the best cost and
/// pose, centre of mass and orientation.
///
/// The other moves turn a piece by quarter and half turns from where it is; a piece
/// on a wrong face or seen from a wrong side (a queen lying where a standing king casts
/// the part, a rook showing its base) is far from every such turn of its pose, and the
/// image energy between them is flat. The scan looks at every pose at once.
pub(super) fn seat_pose(
    seat: &Seat,
    now: DQuat,
    place: Place,
    kept: usize,
    ws: &mut Workspace,
) -> Option<(i64, DVec3, DQuat)> {
    let mass = &seat.problem.scene.occluders[seat.i].mass;
    let (axis, rolls) = match symmetry_axis(mass) {
        Some(axis) => (axis, 1),
        None => (mass.long_axis(), SEAT_ROLLS),
    };
    let from = now * axis;
    // A scan (`kept` 0) keeps its best pose too.
    let keep = kept.max(1);
    let mut best: Vec<(i64, DVec3, DQuat)> = Vec::with_capacity(keep + 1);
    for d in sphere_directions(SEAT_DIRECTIONS) {
        let tilted = DQuat::from_rotation_arc(from, d) * now;
        for r in 0..rolls {
            let roll = std::f64::consts::TAU * r as f64 / rolls as f64;
            let q = (DQuat::from_axis_angle(d, roll) * tilted).normalize();
            let (cost, com) = seat.place(q, place, ws);
            if cost == i64::MAX {
                continue;
            }
            let at = best.partition_point(|b| b.0 <= cost);
            if at < keep {
                best.insert(at, (cost, com, q));
                best.truncate(keep);
            }
        }
    }
    if kept == 0 {
        return best.first().copied();
    }
    best.into_iter()
        .map(|(cost, com, q)| seat.compass((com, q), cost, SEAT_STEPS, ws))
        .min_by_key(|b| b.0)
}

/// The launch kept, as [`seat_pose`] sees it: the bodies' poses at `t` and sights.
pub(super) struct Seats<'a> {
    pub(super) problem: &'a Problem,
    pub(super) held: &'a Held,
    /// The bodies of the stage.
    pub(super) vary: &'a [bool],
    /// Every body's pose at `t` (origin, orientation).
    pub(super) now: &'a [(DVec3, DQuat)],
    pub(super) sights: &'a [Option<Sight>],
}

impl Seats<'_> {
    /// The shadows of every body but `bodies`, at their poses now.
    fn others(&self, bodies: &[usize], ws: &mut Workspace) -> Mask {
        ws.poses.copy_from_slice(self.now);
        let mut which = self.vary.to_vec();
        for &b in bodies {
            which[b] = false;
        }
        self.problem.shadow_held_and(self.held, &which, ws);
        ws.mask.clone()
    }

    /// Where body `i` casts its shadow now: its centroid, area and depth.
    fn place(&self, i: usize) -> Option<Place> {
        let s = self.sights[i]?;
        Some((s.centroid?, s.area, s.depth))
    }

    /// Body `i` seated on its own place: the wrong pixels of the picture and its pose.
    pub(super) fn own(&self, i: usize, ws: &mut Workspace) -> Option<(i64, (DVec3, DQuat))> {
        let place = self.place(i)?;
        let seat = Seat::new(self.problem, i, &self.others(&[i], ws));
        let (cost, com, q) = seat_pose(&seat, self.now[i].1, place, SEAT_KEPT, ws)?;
        Some((cost, (com, q)))
    }

    /// Bodies `i` and `j` each seated on the other's place ([`Seats::two`]).
    pub(super) fn pair(
        &self,
        i: usize,
        j: usize,
        kept: usize,
        ws: &mut Workspace,
    ) -> Option<(i64, [(DVec3, DQuat); 2])> {
        self.two((i, self.place(j)?), (j, self.place(i)?), kept, ws)
    }

    /// Body `i` seated on `place_i` and body `j` on `place_j` (`(centroid, area, depth)`
    /// as [`Seat::place`] takes them), `i` first ([`Seats::many`]). Returns the wrong
    /// pixels of the picture and the two poses.
    pub(super) fn two(
        &self,
        (i, place_i): (usize, Place),
        (j, place_j): (usize, Place),
        kept: usize,
        ws: &mut Workspace,
    ) -> Option<(i64, [(DVec3, DQuat); 2])> {
        let (cost, poses) = self.many(&[(i, place_i), (j, place_j)], kept, ws)?;
        Some((cost, [poses[0], poses[1]]))
    }

    /// Bodies seated each on its place (`(body, (centroid, area, depth))`), in order:
    /// the first over the shadows of every body not seated, each next over those and
    /// the shadows of the bodies seated before it; `kept` as [`seat_pose`] takes it.
    /// Returns the wrong pixels of the picture and the poses, in order.
    pub(super) fn many(
        &self,
        seated: &[(usize, Place)],
        kept: usize,
        ws: &mut Workspace,
    ) -> Option<(i64, Vec<(DVec3, DQuat)>)> {
        let bodies: Vec<usize> = seated.iter().map(|s| s.0).collect();
        let mut others = self.others(&bodies, ws);
        let mut poses = Vec::with_capacity(seated.len());
        let mut cost = 0;
        for (k, &(b, place)) in seated.iter().enumerate() {
            let seat = Seat::new(self.problem, b, &others);
            let (c, com, q) = seat_pose(&seat, self.now[b].1, place, kept, ws)?;
            if k + 1 < seated.len() {
                seat.draw(com, q, ws);
                others.or_assign(&ws.mask);
            }
            cost = c;
            poses.push((com, q));
        }
        Some((cost, poses))
    }

    /// Trades of places among `bodies` (of one kind) worth refining, best first, at most
    /// `cap`: each two or three bodies of different shapes, each to be seated on
    /// the place of the next (the last on the first's), as `(body, place)`.
    ///
    /// Each body is seated ([`seat_pose`], its scan's best pose refined) on the place of
    /// every body of another shape, over the picture without the two, once; that seat's
    /// change of the picture's wrong pixels, added over a cycle to what taking its
    /// bodies out costs the picture, ranks the cycle. A table of one seat per ordered
    /// pair (`n (n - 1)` at most) ranks every pair and three-cycle, where seating each
    /// cycle alone would cost three seats for each of `n (n - 1) (n - 2) / 3`
    /// three-cycles. (The scan alone ranks blocks as well, but not pieces: a chess
    /// piece's scanned shadow is off by hundreds of pixels, more than a trade gains.)
    pub(super) fn trade_scan(
        &self,
        blocks: &[usize],
        cap: usize,
        ws: &mut Workspace,
    ) -> Vec<Vec<(usize, Place)>> {
        let target = &self.problem.target.mask;
        let shape = |a: usize| &self.problem.scene.occluders[blocks[a]].shape;
        let whole = self.others(&[], ws).xor_count(target) as i64;
        // What taking each block out costs the picture (wrong pixels).
        let out: Vec<i64> = blocks
            .iter()
            .map(|&i| self.others(&[i], ws).xor_count(target) as i64 - whole)
            .collect();
        // `on[a][b]`: the change of wrong pixels of block `a` seated on `b`'s place, over
        // the picture without both.
        let n = blocks.len();
        let mut on = vec![vec![None; n]; n];
        for (a, &i) in blocks.iter().enumerate() {
            for (b, &j) in blocks.iter().enumerate() {
                let Some(place) = self.place(j).filter(|_| shape(a) != shape(b)) else {
                    continue;
                };
                let seat = Seat::new(self.problem, i, &self.others(&[i, j], ws));
                if let Some((cost, _, _)) = seat_pose(&seat, self.now[i].1, place, 1, ws) {
                    on[a][b] = Some(cost - seat.base);
                }
            }
        }
        let mut cycles: Vec<(i64, Vec<usize>)> = Vec::new();
        let mut consider = |cycle: &[usize]| {
            let mut change = 0;
            for (k, &a) in cycle.iter().enumerate() {
                let Some(seated) = on[a][cycle[(k + 1) % cycle.len()]] else {
                    return;
                };
                change += out[a] + seated;
            }
            cycles.push((change, cycle.to_vec()));
        };
        // Each cycle once: its first block the lowest index; a pair has one direction,
        // three blocks two.
        for a in 0..n {
            for b in a + 1..n {
                consider(&[a, b]);
                for c in a + 1..n {
                    if c != b {
                        consider(&[a, b, c]);
                    }
                }
            }
        }
        cycles.sort_by_key(|c| c.0);
        cycles
            .into_iter()
            .take(cap)
            .filter_map(|(_, cycle)| {
                (0..cycle.len())
                    .map(|k| {
                        let next = blocks[cycle[(k + 1) % cycle.len()]];
                        Some((blocks[cycle[k]], self.place(next)?))
                    })
                    .collect()
            })
            .collect()
    }

    /// Body `o`'s part of the target: the target pixels its shadow covers now and the
    /// bare ones connected to them.
    fn part(&self, o: usize, bare: &Mask, ws: &mut Workspace) -> Mask {
        self.alone(o, ws);
        super::sight::part_of(&self.problem.target.mask, &ws.mask, bare)
    }

    /// Draw body `i`'s shadow alone, at its pose now, into `ws.mask`.
    fn alone(&self, i: usize, ws: &mut Workspace) {
        ws.poses.copy_from_slice(self.now);
        let mut only = vec![false; self.vary.len()];
        only[i] = true;
        self.problem.shadow_only(&only, ws);
    }

    /// The bodies (of `bodies`) that the picture hardly needs where they are: fewer than
    /// [`HIDDEN`] of their shadow's pixels are target pixels that no other shadow
    /// covers (a block hidden under the others' shadows, or cast beside the picture).
    /// Most hidden first, at most [`SPLIT_HIDDEN`].
    fn hidden(&self, bodies: &[usize], ws: &mut Workspace) -> Vec<usize> {
        let mut found: Vec<(f64, usize)> = Vec::new();
        for &i in bodies {
            let others = self.others(&[i], ws);
            self.alone(i, ws);
            let area = ws.mask.count() as f64;
            let own = ws
                .mask
                .and(&self.problem.target.mask)
                .and_not_count(&others) as f64;
            if area > 0.0 && own < HIDDEN * area {
                found.push((own / area, i));
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        found.into_iter().take(SPLIT_HIDDEN).map(|f| f.1).collect()
    }

    /// The places a hidden body and body `j` may share: `j`'s part of the target (the
    /// target pixels its shadow covers and the bare ones connected to them) cut across
    /// its long axis at [`SPLIT_CUTS`] of its length, each side a place, `(hidden's
    /// place, j's place)`, both ways round; and the pixels of `wrong` (those the
    /// picture gets wrong) within three pixels of `j`'s shadow. Empty when `j` casts no
    /// shadow on the target.
    fn splits(
        &self,
        j: usize,
        bare: &Mask,
        wrong: &Mask,
        ws: &mut Workspace,
    ) -> (u64, Vec<[Place; 2]>) {
        let Some(depth) = self.sights[j].map(|s| s.depth) else {
            return (0, Vec::new());
        };
        let part = self.part(j, bare, ws);
        // `part` left body `j`'s shadow in the workspace.
        let near = ws.mask.dilate(3).and_count(wrong);
        let out = cut_across(&part, &SPLIT_CUTS)
            .into_iter()
            .flat_map(|[(cl, al), (ch, ah)]| {
                let (low, high) = ((cl, al, depth), (ch, ah, depth));
                [[low, high], [high, low]]
            })
            .collect();
        (near, out)
    }

    /// The splits of a part between a hidden block and another worth refining, best
    /// first, at most [`SPLITS`]: `(hidden, partner, [hidden's place, partner's
    /// place])`. Each hidden block ([`Seats::hidden`] of `blocks`) is tried with the
    /// [`SPLIT_PARTNERS`] other blocks with the most wrong pixels around their shadows,
    /// on every cut of [`Seats::splits`], both seated by a scan ([`Seats::two`], `kept`
    /// 0) and ranked by the picture's wrong pixels.
    pub(super) fn split_scan(
        &self,
        blocks: &[usize],
        bare: &Mask,
        ws: &mut Workspace,
    ) -> Vec<(usize, usize, [Place; 2])> {
        let hidden = self.hidden(blocks, ws);
        if hidden.is_empty() {
            return Vec::new();
        }
        // The pixels the picture gets wrong now: bare target and shadow off it.
        let mut wrong = self.others(&[], ws);
        let extra = wrong.and_not(&self.problem.target.mask);
        wrong.copy_from(bare);
        wrong.or_assign(&extra);
        let mut partners = Vec::new();
        for &j in blocks {
            let (near, places) = self.splits(j, bare, &wrong, ws);
            if near > 0 && !places.is_empty() {
                partners.push((std::cmp::Reverse(near), j, places));
            }
        }
        partners.sort_by_key(|p| (p.0, p.1));
        let mut scanned = Vec::new();
        for &r in &hidden {
            for (_, j, cuts) in partners.iter().filter(|p| p.1 != r).take(SPLIT_PARTNERS) {
                for &[place_r, place_j] in cuts {
                    if let Some((cost, _)) = self.two((r, place_r), (*j, place_j), 0, ws) {
                        scanned.push((cost, r, *j, [place_r, place_j]));
                    }
                }
            }
        }
        scanned.sort_by_key(|s| s.0);
        scanned
            .into_iter()
            .take(SPLITS)
            .map(|(_, r, j, places)| (r, j, places))
            .collect()
    }
}

/// `part` cut across its long axis (of its second moments) at each fraction of its
/// pixels in `cuts`, counted along that axis: the centroid (pixels) and area (pixels) of
/// the side below the cut and of the side above, for each cut whose sides both hold
/// [`SPLIT_LEAST`] pixels or more.
fn cut_across(part: &Mask, cuts: &[f64]) -> Vec<[(DVec2, f64); 2]> {
    let m = part.moments();
    let (Some(c), Some([a, b, cc])) = (m.centroid(), m.central_second()) else {
        return Vec::new();
    };
    let angle = 0.5 * (2.0 * b).atan2(a - cc);
    let axis = DVec2::new(angle.cos(), angle.sin());
    let along = |x: usize, y: usize| (DVec2::new(x as f64, y as f64) - c).dot(axis);
    // The part's pixels by their distance along the axis, to cut at quantiles.
    let mut sorted: Vec<f64> = Vec::with_capacity(m.count as usize);
    for y in 0..part.height() {
        for x in 0..part.width() {
            if part.get(x, y) {
                sorted.push(along(x, y));
            }
        }
    }
    sorted.sort_by(f64::total_cmp);
    let mut out = Vec::new();
    for &cut in cuts {
        let at = sorted[((sorted.len() as f64 * cut) as usize).min(sorted.len() - 1)];
        let side = |low: bool| {
            let half = Mask::from_fn(part.width(), part.height(), |x, y| {
                part.get(x, y) && (along(x, y) < at) == low
            });
            let h = half.moments();
            h.centroid()
                .filter(|_| h.count >= SPLIT_LEAST)
                .map(|hc| (hc, h.count))
        };
        if let (Some(low), Some(high)) = (side(true), side(false)) {
            out.push([low, high]);
        }
    }
    out
}

/// A body whose shadow adds fewer target pixels than this fraction of its area is
/// hidden ([`Seats::hidden`]).
pub(super) const HIDDEN: f64 = 0.25;
/// Hidden bodies split in with another, at most.
pub(super) const SPLIT_HIDDEN: usize = 2;
/// Where [`Seats::splits`] cuts a part along its long axis (fractions of its pixels).
pub(super) const SPLIT_CUTS: [f64; 3] = [1.0 / 3.0, 0.5, 2.0 / 3.0];
/// Bodies a hidden body is split in with: those with the most wrong pixels around
/// their shadows.
pub(super) const SPLIT_PARTNERS: usize = 3;
/// Pixels a side of a cut holds at least.
const SPLIT_LEAST: f64 = 16.0;
/// Splits that [`improve`](super::improve) refines, those whose scans draw the best
/// pictures.
pub(super) const SPLITS: usize = 4;

/// Trades of blocks that [`improve`](super::improve) refines ([`Seats::trade_scan`]),
/// those ranked best by the scans. The table ranks a trade by seats made one at a time
/// over the picture without their two blocks, so a trade whose seats share a cluster of
/// overlapping shadows is ranked off: on the planted boxes 11504 the trade that mends
/// it (a long block end-on in a cluster, a short one stretched over a long block's
/// part) is the fifth, and on boxes12 11505 it lies beyond the twelfth. Refining the best
/// 30 raised those two from 0.9631 and 0.9698 to 0.9733 and 0.9833 (and boxes12 11405
/// from 0.9629 to 0.9693) and changed none of the other 39 problems with blocks of the
/// draws 11400 and 11500 (`git show c030f18:docs/results.md`, "More trades of blocks refined"); 80 found
/// nothing more.
pub(super) const TRADES: usize = 30;

/// Trades of meshes that [`improve`](super::improve) refines and reports
/// ([`MoveReport::trades`](super::MoveReport::trades)): the table's ranks say little of
/// them (a piece's scanned shadow is off by hundreds of pixels), so most of the table
/// (six pieces make 15 pairs and 40 three-cycles at most).
pub(super) const MESH_TRADES: usize = 40;

/// [`fit_pose`] body `i` (whose pose at `t` `ws.poses` holds, as for every body in
/// `vary`) on the picture of the held bodies and the other bodies of `vary`, and launch
/// it there in `candidate`: its spin by [`spin_reaching`](super::spin::spin_reaching)
/// and its velocity by [`aim`](super::aim); `thorough` as [`fit_pose`] takes it.
/// `true` when it moved; otherwise `candidate` and its pose are unchanged.
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_and_launch(
    problem: &Problem,
    held: &Held,
    vary: &[bool],
    i: usize,
    candidate: &mut [f64],
    thorough: bool,
    ws: &mut Workspace,
    flight: &mut FreeFlight,
) -> bool {
    let mut which = vary.to_vec();
    which[i] = false;
    problem.shadow_held_and(held, &which, ws);
    let others = ws.mask.clone();
    let kept = ws.poses[i];
    let Some((com, q)) = fit_pose(problem, i, &others, thorough, ws) else {
        ws.poses[i] = kept;
        return false;
    };
    // The first guess only, the turn added to the spin: a fit turns the block a little
    // from where it is, and Newton's method on a tumbling body's flight can stray from a
    // guess a whole turn away.
    let spin = Launch::get(candidate, i).angular_velocity;
    let guesses = spin_guesses(problem, i, spin, kept.1, q);
    if launch_to(problem, i, (com, q), &guesses[..1], candidate, flight) {
        true
    } else {
        ws.poses[i] = kept;
        false
    }
}

/// Whether [`fit_pose`] is tried on a body of this shape: blocks only. A sphere has no
/// orientation, and on the hand-made THE THINKER the chess pieces fitted so ended lower
/// (IoU 0.905 / 0.900 / 0.925 on seeds 1 to 3, against 0.915 / 0.908 / 0.916).
pub(super) fn fits_pose(shape: &Shape) -> bool {
    matches!(shape, Shape::Cuboid { .. })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_directions_are_unit_and_cover_the_sphere() {
        let dirs: Vec<DVec3> = sphere_directions(SEAT_DIRECTIONS).collect();
        assert_eq!(dirs.len(), SEAT_DIRECTIONS);
        for d in &dirs {
            assert!((d.length() - 1.0).abs() < 1e-12, "{d}");
        }
        // Every direction of a finer lattice lies within 20 degrees of one of them, so
        // a seat scan misses no pose by more than its refinement steps correct.
        let worst = sphere_directions(2000)
            .map(|p| dirs.iter().map(|d| d.dot(p)).fold(-1.0, f64::max))
            .fold(1.0, f64::min);
        assert!(
            worst > 20f64.to_radians().cos(),
            "gap of {} deg",
            worst.acos().to_degrees()
        );
        // Spread, not bunched: the mean is close to the centre.
        let mean = dirs.iter().sum::<DVec3>() / dirs.len() as f64;
        assert!(mean.length() < 0.05, "{mean}");
    }

    #[test]
    fn a_part_is_cut_across_its_long_axis_at_fractions_of_its_pixels() {
        // A bar 40 pixels long and 10 wide, lying along x, then standing along y.
        for lying in [true, false] {
            let part = Mask::from_fn(64, 64, |x, y| {
                let (u, v) = if lying { (x, y) } else { (y, x) };
                (10..50).contains(&u) && (20..30).contains(&v)
            });
            let cuts = cut_across(&part, &[0.25, 0.5]);
            assert_eq!(cuts.len(), 2);
            for ([(low, a_low), (high, a_high)], share) in cuts.into_iter().zip([0.25, 0.5]) {
                assert_eq!(a_low + a_high, 400.0);
                assert!((a_low - 400.0 * share).abs() <= 10.0, "{a_low} for {share}");
                // Each side's centroid lies on the bar's centre line, in its own half.
                let (along_low, across_low) = if lying {
                    (low.x, low.y)
                } else {
                    (low.y, low.x)
                };
                let (along_high, across_high) = if lying {
                    (high.x, high.y)
                } else {
                    (high.y, high.x)
                };
                assert!((across_low - across_high).abs() < 1e-9);
                let end = 10.0 + 40.0 * share;
                assert!((along_low - (10.0 + end) / 2.0).abs() < 1.0, "{along_low}");
                assert!(
                    (along_high - (end + 50.0) / 2.0).abs() < 1.0,
                    "{along_high}"
                );
            }
        }
        // A side under the least pixels is no place: a cut at the bar's very end.
        let bar = Mask::from_fn(64, 64, |x, y| {
            (10..50).contains(&x) && (20..30).contains(&y)
        });
        assert!(cut_across(&bar, &[0.01]).is_empty());
    }

    #[test]
    fn only_a_solid_of_revolution_has_a_symmetry_axis() {
        let frame = DQuat::from_rotation_z(0.3);
        let mass = |k: DVec3| crate::geometry::shape::MassProperties {
            mass: 0.05,
            local_com: DVec3::ZERO,
            principal_inertia: k,
            principal_frame: frame,
        };
        // The king: its axis is the principal axis of the odd (smallest) moment.
        let king = symmetry_axis(&mass(DVec3::new(1.776e-6, 1.9044e-5, 1.9047e-5)));
        let axis = king.expect("a king is close to a solid of revolution");
        assert!((axis - frame * DVec3::X).length() < 1e-12, "{axis}");
        // The odd moment in another slot names another axis.
        let disc = symmetry_axis(&mass(DVec3::new(1e-5, 2e-5, 1e-5)));
        assert!((disc.expect("a disc has an axis") - frame * DVec3::Y).length() < 1e-12);
        // The knight's three moments differ; a sphere's or a cube's are all equal.
        assert!(symmetry_axis(&mass(DVec3::new(1.739e-6, 6.213e-6, 6.736e-6))).is_none());
        assert!(symmetry_axis(&mass(DVec3::splat(2e-6))).is_none());
    }
}
