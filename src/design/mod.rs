//! Designing scenes from a box of objects.
//!
//! `bsa new` ([`design`]): [`inventory`] (the object list a user writes, and the
//! built-in [`chess`] set), [`picture`] (distance transform, ridge and local direction
//! of the target), [`pose`] (how each object can be posed at `t` and its top view),
//! [`cover`] (the greedy cover of the picture by the objects' shadows, with heights
//! apart where shadows touch, then objects of different shapes exchanged where both
//! fit better), [`launch`] (poses at `t`, slots on the table, start
//! velocities and spins, hints and the scene file), [`assign`] (slots by least total
//! distance), [`separate`] (the start guess made contact-free with the exact contact
//! search). The method is documented in `docs/design.md`.
//!
//! `bsa plant` ([`plant`]): problems with a known answer, a random contact-free launch
//! whose shadow becomes the target.

pub mod advice;
pub mod assign;
pub mod chess;
pub mod cover;
pub mod inventory;
pub mod launch;
pub mod picture;
pub mod plant;
pub mod pose;
pub mod separate;

use crate::geometry::shape::Shape;
use cover::{Cover, Placement};
use launch::{Geometry, Object, Plan};
use picture::Picture;

/// The objects of a design: those given, and the kinds the design may add while they
/// pay for themselves, each with the most it may add.
#[derive(Clone, Debug)]
pub struct Request {
    pub fixed: Vec<Object>,
    pub auto: Vec<(AutoObject, usize)>,
}

impl Request {
    /// Whether both [`ORDERS`] make the same design: the objects given are of one shape
    /// (or none), so best fit first places them in the order of size too, each where
    /// it gains most, and the `auto:` kinds are added after them the same way.
    pub fn one_order(&self) -> bool {
        self.fixed.windows(2).all(|w| w[0].shape == w[1].shape)
    }

    /// The ceilings its designs are made under: [`AUTO_CEILINGS`] where an `auto:` item
    /// adds objects of a given size, else [`CEILINGS`].
    pub fn ceilings(&self) -> &'static [f64] {
        match self
            .auto
            .iter()
            .any(|(a, _)| matches!(a, AutoObject::Given(_)))
        {
            true => &AUTO_CEILINGS,
            false => &CEILINGS,
        }
    }
}

/// A kind of object an `auto:` item may add.
#[derive(Clone, Debug)]
pub enum AutoObject {
    /// Copies of this object.
    Given(Object),
    /// Spheres of any radius (whole millimetres) at this density.
    Sphere { density: f64 },
}

impl AutoObject {
    /// What one of these takes of [`AUTO_CAP`]: a ball 1, any other object 2 (its
    /// contacts and its shadow cost the solve more than a ball's closed forms).
    pub fn cap_weight(&self) -> usize {
        match self {
            AutoObject::Sphere { .. } => 1,
            AutoObject::Given(o) => match o.shape {
                Shape::Sphere { .. } => 1,
                _ => 2,
            },
        }
    }
}

/// An automatic count adds the next object while it raises the design's IoU by at
/// least this much ([`add_auto`]): a quarter of a point, a shadow that adds a
/// four-hundredth of the picture's dark part. On the organic silhouettes of set 22, the
/// share of its own shadow an object had to gain (0.3) stopped an elephant at three
/// balls: the ball with the largest gain spilled over the body drawn already, and the
/// legs stayed bare. Half a point stopped set 30's pictures where the next object
/// would still add 0.003 to 0.005, most of them: at a quarter, `auto:sphere` ended 13
/// of the 14 higher and none lower (median 0.9515 to 0.9736, 25 to 38.5 balls) in 1.5
/// times the time; the three maple block sizes 12 higher and 1 lower (median 0.9633 to
/// 0.9702) in 1.2 times.
pub const AUTO_MIN_RISE: f64 = 0.0025;
/// ... and stops at this many balls of the automatic kinds, for the solve's time, which
/// grows with the bodies; any other object counts as two ([`AutoObject::cap_weight`]).
/// On the sixteen organic silhouettes of set 23 a cap of 24 bound six balls-only
/// designs, all with thin legs or arms; the chair's start guess reads 0.814 at 24 balls,
/// 0.888 at 32 and 0.924 at its own 40. A ball's contacts and shadow are closed forms:
/// a sample of set 29's moose cost 4.2 us a body with 55 balls, 9.1 us with 14 blocks
/// (`bsa solve --report`). On set 29, `bsa new` + `bsa solve` of up to 64 balls took a
/// median of 50 s for IoU 0.877, of up to 32 balls 16 s for 0.816.
pub const AUTO_CAP: usize = 64;
/// Share of the target (0 to 1) left bare from which the objects are too few for the
/// picture: an automatic count then goes on past [`AUTO_MIN_RISE`] while the next object
/// gains anything, up to [`AUTO_CAP`], and `bsa new`'s note says what would help. Thin
/// parts (legs, antennae, a tail) each need several small objects, each of which adds
/// less than [`AUTO_MIN_RISE`]; the rise alone left a crab's four legs bare (16 % of its
/// target, IoU 0.826 after the solve) at 24 balls, below the cap.
pub const BARE_SHARE: f64 = 0.15;

/// The ceilings the design tries (the highest flight at `t`, as a fraction of the light's
/// height): `bsa new` designs the picture once under each and keeps the start guess
/// that reads best. A high ceiling lets an object's shadow grow large, and the greedy
/// cover, largest object first, then stretches the largest object over as much of the
/// picture as it can, across a bend or over a junction that smaller objects would take
/// better; a lower ceiling keeps the shadows nearer their objects' own sizes. Which one
/// suits a picture depends on its strokes' lengths against the objects', so each is
/// tried (on "to fly" with its six blocks the start guess reads 0.852, 0.869, 0.834 and
/// 0.840 under them, and the solve from the best ends 0.04 higher).
pub const CEILINGS: [f64; 4] = [0.8, 0.7, 0.6, 0.5];

/// The ceilings of a design where an `auto:` item adds objects of a given size (a block,
/// a mesh, a chess piece, a ball of a given radius): the four steps of [`CEILINGS`], 0.2
/// lower. Such an object's shadow is sized by its height alone, and under a high ceiling
/// the greedy cover magnifies each shadow over as much as it can, so the count stops
/// early at shadows that spill over the picture's edges and bridge its gaps; lower,
/// the shadows keep near the objects' own sizes and more of them pay their way
/// ([`AUTO_MIN_RISE`]). Balls of `auto:sphere` are sized by their radii instead and keep
/// [`CEILINGS`]. On set 32's fourteen silhouettes, designed under both sets of ceilings
/// (`bsa new`'s trial solves): the three maple blocks' best trial median 0.9349 under
/// [`CEILINGS`], 0.9500 under these, as under all six of 0.8 to 0.3, and 10 of 14
/// kept the lowest of [`CEILINGS`]; balls' 0.9579 under [`CEILINGS`] and under all six.
pub const AUTO_CEILINGS: [f64; 4] = [0.6, 0.5, 0.4, 0.3];

/// In which order the greedy cover places the objects.
///
/// Neither order is better on every picture: on the planted problems of seeds 9000 to
/// 9005 (through `bsa new`) the trial solves kept a best-fit-first design for 17 of the
/// 30 and a largest-first one for 13, so `bsa new` designs under both ([`ORDERS`]) and
/// keeps the design whose trial solve ends best.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// The largest object (by volume) first: it takes the place where its shadow gains
    /// most, and smaller objects fill in around it. Large objects are not left
    /// without a place that fits them, but the first one may stretch over parts that
    /// a smaller object fits exactly (a long block across the end of a stroke that a
    /// short block draws whole).
    LargestFirst,
    /// The placement that fits best first ([`fit`]): every kind of object left is
    /// placed where it gains most, and the one whose shadow lies most wholly on target,
    /// weighed by what it gains, is committed; the others are placed again around it.
    /// Parts that one object draws exactly are taken by it before a larger object
    /// spills over them.
    BestFitFirst,
}

/// The orders `bsa new` designs under, each under every ceiling of [`CEILINGS`].
pub const ORDERS: [Order; 2] = [Order::LargestFirst, Order::BestFitFirst];

impl Order {
    /// How `bsa new` names the order in its report.
    pub fn label(self) -> &'static str {
        match self {
            Order::LargestFirst => "largest object first",
            Order::BestFitFirst => "best fit first",
        }
    }
}

/// How well a placement fits, for [`Order::BestFitFirst`]: its gain (new target minus
/// new background, pixels) times the square of its precision (gain over its shadow's
/// area). The square makes a shadow that lies wholly on target outrank a larger one
/// that gains more but spills over the background or over parts already covered;
/// among shadows that fit as well, the larger gain wins.
pub fn fit(p: &Placement) -> f64 {
    let precision = (p.gain / p.area.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.gain * precision * precision
}

/// When no trial solve of `bsa new`'s designs ends at this IoU or more, it designs
/// again with [`Cover::replace`] under the ceilings of its best designs
/// ([`ANEW_CEILINGS`]) and keeps the best of both rounds. The second round runs only
/// where the first leaves a picture that a solve's own moves rarely mend (the
/// solver's trades start under the same IoU).
pub const REPLACE_BELOW: f64 = 0.985;

/// How many ceilings the second round designs under: those of the first round's best
/// designs, best first. In 65 runs of `bsa new` on organic silhouettes of sets 23, 27
/// and 28 (the logs of their trial solves under every setting), the best design of
/// both rounds was the first round's or under one of its two best ceilings in 55; in
/// the other ten it was at most 0.006 better (0.0004 on average over the 65). Under the
/// best ceiling alone, 20 lost, up to 0.011. Two cost two trial solves instead of four
/// (in each order that differs); the examples keep their designs.
pub const ANEW_CEILINGS: usize = 2;

/// Rounds of [`Cover::polish`] after the greedy pass.
pub const POLISH_ROUNDS: usize = 2;

/// Rounds of [`Cover::exchange`] after the greedy pass, at most (they stop at the first
/// that exchanges nothing): an object that is on a third object's place reaches its
/// own through two exchanges.
pub const EXCHANGE_ROUNDS: usize = 4;

/// Why a picture cannot be designed.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// Every placement of an object breaks the height rule.
    #[error("no room for object {index} ({stem}): every place on the picture needs a height that another shadow there already takes")]
    NoRoom { index: usize, stem: String },
    /// An automatic count found nothing worth adding and there is no other object.
    #[error("no object of the auto: kind is worth launching (none would raise the picture's IoU by {AUTO_MIN_RISE} or more)")]
    NothingWorthIt,
    /// The picture's dark part is less than [`LEAST_DARK_SHARE`] of the least shadow
    /// that the object with the smallest one can cast ([`check_dark_part`]).
    #[error("the picture's dark part ({dark_pixels} pixels, {dark_area:.3e} m^2) is less than {LEAST_DARK_SHARE} of the least shadow object {} can cast ({least_shadow:.3e} m^2): no shadow of it can draw the picture", object + 1)]
    TooLittleDark {
        dark_pixels: u64,
        /// m^2.
        dark_area: f64,
        /// Index of the object, in the list given to [`check_dark_part`].
        object: usize,
        /// m^2, [`least_shadow_area`].
        least_shadow: f64,
    },
}

/// The share of an object's least shadow ([`least_shadow_area`]) below which a
/// picture's whole dark part is refused ([`check_dark_part`]). One shadow of at least
/// twice the picture's dark area that covers all of it reads at IoU 0.5 at best; the
/// bound is loose (2/3 of a sphere's disc, less for a long body), so no picture that a
/// shadow of the object could match is refused. On the one-pixel dot of a 64 x 48
/// picture two spheres of 0.1 m ended at IoU 0.014, and a 2 x 2 dot on 8000 x 8000
/// pixels took 71 s of designs and trial solves to reach IoU 0.
pub const LEAST_DARK_SHARE: f64 = 0.5;

/// A lower bound of the area (m^2) of any shadow a body of `shape` casts on a plane
/// with the light on the other side of it: its volume over `2 bounding_radius`.
///
/// Why it holds: every ray from the light through the body meets the plane in the
/// shadow S, so the body lies in the cone from the light over S, between two distances
/// from the plane at most `2 r` apart; the cone's section there has area
/// `(1 - z / L)^2 |S| <= |S|`, so the volume is at most `2 r |S|`. This holds for any
/// pose, height and shape (concave meshes too), and is within 2/3 of a sphere's least
/// shadow (its own disc).
pub fn least_shadow_area(shape: &crate::geometry::shape::Shape, bounding_radius: f64) -> f64 {
    shape.volume() / (2.0 * bounding_radius)
}

/// Refuse a picture whose dark part (`dark_pixels` of `pixel_area` m^2 each) is less
/// than [`LEAST_DARK_SHARE`] of the smallest of `least_shadows` (m^2, one per kind of
/// object, [`least_shadow_area`]): every shadow of every object is then more than
/// twice the size of all there is to draw, and the design and its solves would end
/// far from the picture, however long they ran. No objects: nothing to refuse.
pub fn check_dark_part(
    dark_pixels: u64,
    pixel_area: f64,
    least_shadows: &[f64],
) -> Result<(), DesignError> {
    let Some((object, &least_shadow)) = least_shadows
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
    else {
        return Ok(());
    };
    let dark_area = dark_pixels as f64 * pixel_area;
    if dark_area < LEAST_DARK_SHARE * least_shadow {
        return Err(DesignError::TooLittleDark {
            dark_pixels,
            dark_area,
            object,
            least_shadow,
        });
    }
    Ok(())
}

/// Design a scene: place every object's shadow on `picture` (in `order`), add objects
/// of the `auto:` kind while they gain enough, exchange objects of different shapes
/// (not two balls made to measure) where both fit better ([`draft`]); then with
/// `replace` place each object anew where it gains more, polish, and plan the launches
/// ([`Draft::finish`]).
pub fn design(
    picture: &Picture,
    geometry: Geometry,
    request: &Request,
    order: Order,
    replace: bool,
) -> Result<Plan, DesignError> {
    Ok(draft(picture, geometry, request, order)?.finish(replace))
}

/// A design before its objects are placed anew and polished: what [`design`] makes of
/// a ceiling and an order whether or not it then places anew, so that `bsa new`'s
/// second round (the same ceilings and orders, placed anew) starts from its first
/// round's drafts instead of making them again.
#[derive(Clone)]
pub struct Draft<'a> {
    cover: Cover<'a>,
    geometry: Geometry,
    objects: Vec<Object>,
    /// The pose families of every placement's object.
    families: Vec<Vec<pose::Family>>,
    stop: Option<AutoStop>,
}

/// The first part of [`design`]: every object placed in `order`, the `auto:` kinds
/// added, objects exchanged.
pub fn draft<'a>(
    picture: &'a Picture,
    geometry: Geometry,
    request: &Request,
    order: Order,
) -> Result<Draft<'a>, DesignError> {
    let frame = geometry.frame();
    let mut cover = Cover::new(picture, frame);
    let mut objects = request.fixed.clone();
    let mut by_size: Vec<usize> = (0..objects.len()).collect();
    by_size.sort_by(|&a, &b| {
        objects[b]
            .shape
            .volume()
            .total_cmp(&objects[a].shape.volume())
            .then(a.cmp(&b))
    });
    match order {
        Order::LargestFirst => {
            for k in by_size {
                let fams = objects[k].families();
                let p = cover.best(k, &fams).ok_or_else(|| no_room(&objects, k))?;
                let family = fams[p.family].clone();
                cover.commit(p, family);
            }
        }
        Order::BestFitFirst => best_fit_first(&mut cover, &objects, &by_size)?,
    }
    let stop =
        (!request.auto.is_empty()).then(|| add_auto(&mut cover, &mut objects, &request.auto));
    if objects.is_empty() {
        return Err(DesignError::NothingWorthIt);
    }
    // Which object goes where, reconsidered (see `Cover::exchange`).
    let families: Vec<Vec<pose::Family>> = cover
        .placements
        .iter()
        .map(|p| objects[p.object].families())
        .collect();
    let shapes: Vec<&Shape> = cover
        .placements
        .iter()
        .map(|p| &objects[p.object].shape)
        .collect();
    let measured: Vec<bool> = cover
        .placements
        .iter()
        .map(|p| made_to_measure(request, &objects, p.object))
        .collect();
    let same = |a: usize, b: usize| shapes[a] == shapes[b] || measured[a] && measured[b];
    for _ in 0..EXCHANGE_ROUNDS {
        if cover.exchange(&families, &same) == 0 {
            break;
        }
    }
    Ok(Draft {
        cover,
        geometry,
        objects,
        families,
        stop,
    })
}

impl Draft<'_> {
    /// The rest of [`design`]: with `replace` each object placed anew where it gains
    /// more ([`Cover::replace`]), then the polish and the launches' plan.
    pub fn finish(mut self, replace: bool) -> Plan {
        if replace {
            self.cover.replace(&self.families);
        }
        self.cover.polish(POLISH_ROUNDS);
        let mut plan = Plan::new(self.geometry, self.objects, self.cover.placements);
        plan.auto_stop = self.stop;
        plan
    }
}

/// Why an automatic count stopped where it did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AutoStop {
    /// The next object would have raised the design's IoU by `rise` (the best it found),
    /// less than [`AUTO_MIN_RISE`], or by nothing where the target is bare
    /// ([`BARE_SHARE`]); `None`: no object of the kinds left has a place.
    Rise(Option<f64>),
    /// It reached its cap ([`AUTO_CAP`], or more where the list allows more) at this
    /// many objects.
    Cap(usize),
    /// Every kind reached the number the list allows of it.
    Used,
}

impl std::fmt::Display for AutoStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AutoStop::Rise(Some(r)) if *r <= 0.0 => {
                write!(
                    f,
                    "no more objects of the kind would raise the design's IoU"
                )
            }
            AutoStop::Rise(Some(r)) => write!(
                f,
                "one more would raise the design's IoU by {r:.4}, less than {AUTO_MIN_RISE}"
            ),
            AutoStop::Rise(None) => write!(f, "no more objects of the kind have a place"),
            AutoStop::Cap(n) => write!(f, "it reached its cap at {n} objects"),
            AutoStop::Used => write!(f, "the list allows no more of any kind"),
        }
    }
}

/// Add objects of the `auto:` kinds to `cover` (and `objects`), one at a time, each the
/// placement of any kind left that gains most, while the next raises the design's IoU
/// by at least [`AUTO_MIN_RISE`], or by anything while more than [`BARE_SHARE`] of the
/// target is bare; say why it stopped.
///
/// The rise is the placement's gain (new target minus new background pixels) over the
/// union of target and shadow so far: the IoU it adds when the picture is nearly
/// matched, and a bound below that otherwise. A shadow that spills over parts already
/// drawn costs nothing there, so a large ball that finishes a body beside a smaller
/// one that fills a leg is judged by what each adds, not by its share of its own area.
fn add_auto(
    cover: &mut Cover,
    objects: &mut Vec<Object>,
    auto: &[(AutoObject, usize)],
) -> AutoStop {
    let mut left: Vec<usize> = auto.iter().map(|x| x.1).collect();
    // A list that allows more than the cap, kind by kind, raises it: its author takes
    // the time of the solve of that many.
    let stated: usize = auto
        .iter()
        .filter(|(_, n)| *n != usize::MAX)
        .map(|(kind, n)| n * kind.cap_weight())
        .sum();
    let cap = AUTO_CAP.max(stated);
    let (before, mut taken) = (objects.len(), 0);
    let mut lazy = Lazy::new(auto.len());
    loop {
        if left.iter().all(|&n| n == 0) {
            return AutoStop::Used;
        }
        let fits = |i: usize| left[i] > 0 && taken + auto[i].0.cap_weight() <= cap;
        if !(0..auto.len()).any(fits) {
            return AutoStop::Cap(objects.len() - before);
        }
        let union = cover.union() as f64;
        // No placement gains more than the target left open.
        let open = cover.open() as f64;
        if open < AUTO_MIN_RISE * union {
            return AutoStop::Rise(Some(open / union));
        }
        // While the target is bare, any gain will do: a gain raises the IoU (new target
        // over new background beats target over union).
        let bare = open > BARE_SHARE * cover.target() as f64;
        let least = if bare { 0.0 } else { AUTO_MIN_RISE };
        let k = objects.len();
        let found = lazy.top(
            fits,
            |(p, _): &(Placement, Object)| p.gain,
            |i| match &auto[i].0 {
                AutoObject::Given(o) => cover.best(k, &o.families()).map(|p| (p, o.clone())),
                AutoObject::Sphere { density } => cover
                    .best_disc(k)
                    .map(|(p, radius)| (p, sphere(radius, *density))),
            },
        );
        let Some((i, (p, o))) = found else {
            return AutoStop::Rise(None);
        };
        let rise = p.gain / union;
        if rise < least || rise <= 0.0 {
            return AutoStop::Rise(Some(rise));
        }
        lazy.taken();
        left[i] -= 1;
        taken += auto[i].0.cap_weight();
        let family = o.families()[p.family].clone();
        objects.push(o);
        cover.commit(p, family);
    }
}

/// Whether object `k` is a ball that `auto:sphere` made for its place: its radius fits
/// the part it was placed on, so two such balls on each other's places would each need
/// the other's radius, and an exchange of them can gain nothing. On the moose of set 29
/// with up to 64 balls (53 kept, of 21 radii), trying every two took 84 % of the
/// design's time. Balls of stated radii are exchanged: on planted draw 13400, a
/// design that left them where the greedy put them solved spheres 13403 to IoU 0.9853
/// instead of 1.
fn made_to_measure(request: &Request, objects: &[Object], k: usize) -> bool {
    let given = |o: &Object| {
        request.auto.iter().any(|(kind, _)| match kind {
            AutoObject::Given(g) => g.shape == o.shape,
            AutoObject::Sphere { .. } => false,
        })
    };
    k >= request.fixed.len()
        && matches!(objects[k].shape, Shape::Sphere { .. })
        && request
            .auto
            .iter()
            .any(|(kind, _)| matches!(kind, AutoObject::Sphere { .. }))
        && !given(&objects[k])
}

/// Why object `k` has no place.
fn no_room(objects: &[Object], k: usize) -> DesignError {
    DesignError::NoRoom {
        index: k + 1,
        stem: objects[k].stem.clone(),
    }
}

/// Greedy choice among kinds of objects, lazily: each kind's last placement found, and
/// whether it was found on the cover as it is now. A commit mostly takes pixels away
/// from the other kinds' placements (or takes away their height; it also makes the
/// background it covers free, which rarely matters), so their placements found before
/// it bound what they can score after it from above: the kind with the highest bound
/// is placed again, and chosen if it still scores best. This costs about one placement
/// search per object beyond the first, instead of one per kind left: with the three
/// maple block sizes, `bsa new --choose-by start` of set 29's moose took 23.3 s
/// instead of 30.9, for the same design.
struct Lazy<T> {
    found: Vec<Option<T>>,
    fresh: Vec<bool>,
}

impl<T: Clone> Lazy<T> {
    fn new(kinds: usize) -> Self {
        Lazy {
            found: vec![None; kinds],
            fresh: vec![false; kinds],
        }
    }

    /// The kind among those `live` whose placement, found (`find`) on the cover as it
    /// is, scores best, and that placement; `None` when none has a place. Ties go to
    /// the earlier kind.
    fn top(
        &mut self,
        live: impl Fn(usize) -> bool,
        score: impl Fn(&T) -> f64,
        mut find: impl FnMut(usize) -> Option<T>,
    ) -> Option<(usize, T)> {
        loop {
            // A kind never placed is unbounded; one that found no place stays so.
            let bound = |i: usize| match (&self.found[i], self.fresh[i]) {
                (Some(t), _) => score(t),
                (None, false) => f64::INFINITY,
                (None, true) => f64::NEG_INFINITY,
            };
            let top = (0..self.found.len()).filter(|&i| live(i)).fold(
                None,
                |t: Option<usize>, i| match t {
                    Some(t) if bound(t) >= bound(i) => Some(t),
                    _ => Some(i),
                },
            )?;
            if self.fresh[top] {
                return self.found[top].clone().map(|t| (top, t));
            }
            self.found[top] = find(top);
            self.fresh[top] = true;
        }
    }

    /// A placement was committed: every kind's is a bound now.
    fn taken(&mut self) {
        self.fresh.iter_mut().for_each(|f| *f = false);
    }
}

/// Place `objects` (indices `by_size`, largest first) on `cover` in
/// [`Order::BestFitFirst`], the kinds (objects of one shape, whose first left stands
/// for all) chosen by [`Lazy`].
fn best_fit_first(
    cover: &mut Cover,
    objects: &[Object],
    by_size: &[usize],
) -> Result<(), DesignError> {
    // Kinds in order of size, with the members not yet placed.
    let mut kinds: Vec<std::collections::VecDeque<usize>> = Vec::new();
    for &k in by_size {
        match kinds
            .iter_mut()
            .find(|g| objects[g[0]].shape == objects[k].shape)
        {
            Some(g) => g.push_back(k),
            None => kinds.push([k].into()),
        }
    }
    let mut lazy = Lazy::new(kinds.len());
    while let Some(first) = kinds.iter().position(|g| !g.is_empty()) {
        let Some((i, p)) = lazy.top(
            |i| !kinds[i].is_empty(),
            fit,
            |i| cover.best(kinds[i][0], &objects[kinds[i][0]].families()),
        ) else {
            return Err(no_room(objects, kinds[first][0]));
        };
        let k = kinds[i].pop_front().expect("a kind has members");
        let family = objects[k].families()[p.family].clone();
        cover.commit(Placement { object: k, ..p }, family);
        lazy.taken();
    }
    Ok(())
}

/// A sphere object of `radius` (m) at `density`.
pub fn sphere(radius: f64, density: f64) -> Object {
    Object {
        stem: "sphere".into(),
        shape: crate::geometry::shape::Shape::Sphere { radius },
        shape_json: serde_json::json!({"sphere": {"radius": radius}}),
        density,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn placement(gain: f64, area: f64) -> Placement {
        Placement {
            object: 0,
            family: 0,
            alpha: 0.0,
            centre: DVec2::ZERO,
            theta: 0.0,
            m: 2.0,
            gain,
            area,
        }
    }

    #[test]
    fn the_least_shadow_bounds_every_shadow_and_a_tiny_picture_is_refused() {
        use crate::geometry::shape::Shape;
        // A sphere's least shadow is its disc; the bound is 2/3 of it.
        let ball = Shape::Sphere { radius: 0.1 };
        let least = least_shadow_area(&ball, 0.1);
        let disc = std::f64::consts::PI * 0.01;
        assert!((least - disc * 2.0 / 3.0).abs() < 1e-12, "{least}");
        // A box's least shadow is at least its smallest face; the bound is below it.
        let brick = Shape::Cuboid {
            half_extents: glam::DVec3::new(0.05, 0.025, 0.015),
        };
        let r = glam::DVec3::new(0.05, 0.025, 0.015).length();
        assert!(least_shadow_area(&brick, r) < 0.05 * 0.03);
        // One dark pixel of 0.025 m against the ball: refused; the ball's disc drawn on
        // the picture: kept, and so is a picture with no object to weigh.
        let pixel_area = 0.025 * 0.025;
        assert!(matches!(
            check_dark_part(1, pixel_area, &[least, 1.0]),
            Err(DesignError::TooLittleDark { object: 0, .. })
        ));
        let disc_pixels = (disc / pixel_area) as u64;
        assert!(check_dark_part(disc_pixels, pixel_area, &[least]).is_ok());
        assert!(check_dark_part(1, pixel_area, &[]).is_ok());
    }

    #[test]
    fn only_balls_made_to_measure_are_left_unexchanged() {
        // A stated ball, then what `auto:sphere` and `auto:sphere:0.02` added.
        let objects = [
            sphere(0.1, 705.0),
            sphere(0.05, 705.0),
            sphere(0.02, 705.0),
            block(0.1, 0.05, 0.03),
        ];
        let request = |auto: Vec<(AutoObject, usize)>| Request {
            fixed: vec![objects[0].clone()],
            auto,
        };
        let both = request(vec![
            (AutoObject::Sphere { density: 705.0 }, usize::MAX),
            (AutoObject::Given(objects[2].clone()), usize::MAX),
            (AutoObject::Given(objects[3].clone()), usize::MAX),
        ]);
        let measured = |r: &Request| -> Vec<bool> {
            (0..objects.len())
                .map(|k| made_to_measure(r, &objects, k))
                .collect()
        };
        assert_eq!(measured(&both), [false, true, false, false]);
        // Without auto:sphere no ball is made to measure.
        let given = request(vec![(AutoObject::Given(objects[2].clone()), usize::MAX)]);
        assert_eq!(measured(&given), [false; 4]);
    }

    #[test]
    fn a_shadow_wholly_on_target_fits_better_than_a_larger_one_that_spills() {
        let exact = placement(1000.0, 1000.0);
        // 1,500 pixels of new target and 500 of background.
        let spilling = placement(1000.0, 2000.0);
        assert!(fit(&exact) > fit(&spilling));
        // Among exact fits the larger gain wins.
        assert!(fit(&placement(2000.0, 2000.0)) > fit(&exact));
        // Mostly background: no fit at all.
        assert!(fit(&placement(-50.0, 1000.0)) <= 0.0);
        assert_eq!(fit(&exact), 1000.0);
    }

    /// A picture whose pixel (x, y) is on where `on` says, 320 x 240 at 2.5 mm per
    /// pixel under a light 6 m up.
    pub(super) fn scene(on: impl Fn(f64, f64) -> bool) -> (Picture, cover::Frame) {
        let (w, h) = (320, 240);
        let px = (0..w * h)
            .map(|k| on((k % w) as f64 + 0.5, (k / w) as f64 + 0.5))
            .collect();
        (Picture::new(w, h, px), cover::Frame::new(0.0025, 6.0, 0.8))
    }

    pub(super) fn block(x: f64, y: f64, z: f64) -> Object {
        Object {
            stem: "box".into(),
            shape: crate::geometry::shape::Shape::Cuboid {
                half_extents: glam::DVec3::new(x, y, z) / 2.0,
            },
            shape_json: serde_json::json!({"box": {"size": [x, y, z]}}),
            density: 705.0,
        }
    }

    #[test]
    fn an_automatic_count_draws_a_thin_leg_beside_a_body_drawn_already() {
        // A body (a disc of radius 60 px) on a leg 16 px wide and 70 long: the ball
        // that gains most after the body's spills over it, and the leg, a tenth of
        // the picture, must still be drawn.
        let leg = |x: f64, y: f64| (112.0..128.0).contains(&x) && (150.0..230.0).contains(&y);
        let (pic, frame) = scene(|x, y| (x - 120.0).hypot(y - 100.0) <= 60.0 || leg(x, y));
        let mut cover = Cover::new(&pic, frame);
        let mut objects = Vec::new();
        let auto = [(AutoObject::Sphere { density: 705.0 }, usize::MAX)];
        let stop = add_auto(&mut cover, &mut objects, &auto);
        assert!(matches!(stop, AutoStop::Rise(_)), "{stop:?}");
        let open_leg = (0..pic.on.len())
            .filter(|&k| cover.value[k] > 0 && leg((k % 320) as f64 + 0.5, (k / 320) as f64 + 0.5))
            .count();
        assert!(
            open_leg < 16 * 80 / 4,
            "{open_leg} pixels of the leg bare, {} balls",
            objects.len()
        );
        assert!((cover.open() as f64) < 0.05 * pic.count() as f64);
    }

    /// A body (a disc of radius 50 px) on four legs 6 px wide and 90 long, a fifth of
    /// the target.
    pub(super) fn body_on_legs() -> (Picture, cover::Frame) {
        let leg = |x: f64, y: f64| {
            (140.0..230.0).contains(&y)
                && [60.0, 100.0, 140.0, 180.0]
                    .iter()
                    .any(|&l| (l..l + 6.0).contains(&x))
        };
        scene(|x, y| (x - 124.0).hypot(y - 90.0) <= 50.0 || leg(x, y))
    }

    #[test]
    fn an_automatic_count_goes_on_while_much_of_the_target_is_bare() {
        // A ball on a leg of the body on legs adds under AUTO_MIN_RISE, so the rise
        // alone stops at the body and leaves the legs bare.
        let (pic, frame) = body_on_legs();
        let mut cover = Cover::new(&pic, frame);
        let mut objects = Vec::new();
        let auto = [(AutoObject::Sphere { density: 705.0 }, usize::MAX)];
        let stop = add_auto(&mut cover, &mut objects, &auto);
        let bare = cover.open() as f64 / pic.count() as f64;
        assert!(
            bare <= BARE_SHARE || stop == AutoStop::Cap(AUTO_CAP),
            "{stop:?} at {} balls, {:.0} % bare",
            objects.len(),
            100.0 * bare
        );
    }

    #[test]
    fn a_lazy_choice_takes_the_best_kind_and_searches_again_only_those_on_top() {
        // What each kind scores now; a kind taken scores less the next time.
        let mut now = vec![5.0, 3.0, 4.0];
        let mut lazy = Lazy::new(3);
        let mut searched = Vec::new();
        let mut order = Vec::new();
        for _ in 0..4 {
            let (i, score) = lazy
                .top(
                    |_| true,
                    |&s| s,
                    |i| {
                        searched.push(i);
                        Some(now[i])
                    },
                )
                .expect("every kind has a place");
            // The kind chosen is the best of what they score now.
            assert!(now.iter().all(|&s| s <= score), "{now:?}: {i} at {score}");
            order.push(i);
            now[i] -= 2.5;
            lazy.taken();
        }
        assert_eq!(order, [0, 2, 1, 0]);
        // Three searches to begin, then only the kinds whose bounds led.
        assert_eq!(searched, [0, 1, 2, 0, 2, 2, 1, 1, 0]);
        // A kind not live is never searched; none with a place gives none.
        let mut lazy: Lazy<f64> = Lazy::new(2);
        assert!(lazy.top(|i| i == 1, |&s| s, |_| None).is_none());
        assert_eq!(lazy.found, [None, None]);
    }

    #[test]
    fn both_orders_make_one_design_when_the_objects_given_are_of_one_shape() {
        // The design search makes it once then (`Request::one_order`).
        let (pic, _) = body_on_legs();
        let camera = crate::shadow::raster::ShadowCamera::new(
            glam::DVec3::new(0.0, 0.0, 6.0),
            crate::shadow::raster::ImageRect {
                center: glam::DVec3::ZERO,
                u: glam::DVec3::X,
                v: glam::DVec3::Y,
                width_m: 0.8,
                height_m: 0.6,
                width_px: 320,
                height_px: 240,
            },
        );
        let geometry = Geometry {
            camera,
            table_top: 0.0,
            gravity: glam::DVec3::new(0.0, 0.0, -9.81),
            t: 1.2,
            ceiling: 0.8,
            posed: false,
        };
        let plan = |request: &Request, order| {
            let plan = design(&pic, geometry.clone(), request, order, false);
            format!("{:?}", plan.expect("the picture has room"))
        };
        let (long, short) = (block(0.14, 0.07, 0.035), block(0.07, 0.035, 0.035));
        let one = Request {
            fixed: vec![long.clone(); 3],
            auto: vec![(AutoObject::Given(short.clone()), usize::MAX)],
        };
        assert!(one.one_order());
        let (a, b) = (
            plan(&one, Order::LargestFirst),
            plan(&one, Order::BestFitFirst),
        );
        assert_eq!(a, b);
        // Two shapes given: each order is designed.
        let two = Request {
            fixed: vec![long.clone(), short, long],
            auto: Vec::new(),
        };
        assert!(!two.one_order());
    }

    #[test]
    fn blocks_counted_automatically_draw_a_gapped_picture_better_under_the_lower_ceilings() {
        // A disc with two gaps 4 px wide across it (a pumpkin's ribs), and a block
        // whose shadow is 28 x 14 px at its own size: under the highest ceiling its
        // shadows grow over the gaps and the count stops early.
        let (pic, _) = scene(|x, y| {
            (x - 160.0).hypot(y - 120.0) <= 70.0
                && (x - 135.0).abs() >= 2.0
                && (x - 185.0).abs() >= 2.0
        });
        let half = AutoObject::Given(block(0.07, 0.035, 0.035));
        let design = |ceiling| {
            let mut cover = Cover::new(&pic, cover::Frame::new(0.0025, 6.0, ceiling));
            let mut objects = Vec::new();
            add_auto(&mut cover, &mut objects, &[(half.clone(), usize::MAX)]);
            let iou = (cover.target() - cover.open()) as f64 / cover.union() as f64;
            (objects.len(), iou)
        };
        let (high, low) = (design(CEILINGS[0]), design(AUTO_CEILINGS[3]));
        assert!(low.0 > high.0 && low.1 > high.1 + 0.01, "{high:?} {low:?}");
        // So a request with such an item is designed under the lower ceilings; balls,
        // which take their radii as they need, under the standard ones.
        let request = |kind| Request {
            fixed: Vec::new(),
            auto: vec![(kind, usize::MAX)],
        };
        assert_eq!(request(half.clone()).ceilings(), &AUTO_CEILINGS);
        let balls = request(AutoObject::Sphere { density: 705.0 });
        assert_eq!(balls.ceilings(), &CEILINGS);
    }

    #[test]
    fn an_automatic_count_stops_at_the_cap_unless_the_list_allows_more() {
        // Rows of ten dots 12 px across, 30 px apart: each takes a ball or a cube of its
        // own.
        let count = |kind: AutoObject, rows: f64, most: usize| {
            let (pic, frame) = scene(|x, y| {
                let (i, j) = ((x / 30.0).floor(), (y / 30.0).floor());
                i < 10.0 && j < rows && (x - 30.0 * i - 15.0).hypot(y - 30.0 * j - 15.0) <= 6.0
            });
            let mut cover = Cover::new(&pic, frame);
            let mut objects = Vec::new();
            let stop = add_auto(&mut cover, &mut objects, &[(kind, most)]);
            (objects.len(), stop)
        };
        let ball = || AutoObject::Sphere { density: 705.0 };
        let cap = AutoStop::Cap(AUTO_CAP);
        assert_eq!(count(ball(), 8.0, usize::MAX), (AUTO_CAP, cap));
        assert_eq!(count(ball(), 8.0, 70), (70, AutoStop::Used));
        assert_eq!(count(ball(), 8.0, 20), (20, AutoStop::Used));
        // A cube counts as two balls.
        let cube = AutoObject::Given(block(0.008, 0.008, 0.008));
        let half = AUTO_CAP / 2;
        assert_eq!(count(cube, 4.0, usize::MAX), (half, AutoStop::Cap(half)));
    }

    #[test]
    fn a_box_of_two_sizes_puts_the_small_block_where_the_large_one_would_spill() {
        // A bar 160 x 40 px, the top view of a 0.14 x 0.035 side at m = 2.86, and
        // apart from it a square 40 x 40 px, a 0.07 x 0.07 face at m = 1.43.
        let bar = |x: f64, y: f64| (40.0..200.0).contains(&x) && (60.0..100.0).contains(&y);
        let square = |x: f64, y: f64| (240.0..280.0).contains(&x) && (160.0..200.0).contains(&y);
        let (pic, frame) = scene(|x, y| bar(x, y) || square(x, y));
        let mut cover = Cover::new(&pic, frame);
        let mut objects = Vec::new();
        let (long, small) = (block(0.14, 0.07, 0.035), block(0.07, 0.07, 0.035));
        let auto = [
            (AutoObject::Given(long.clone()), usize::MAX),
            (AutoObject::Given(small.clone()), usize::MAX),
        ];
        let stop = add_auto(&mut cover, &mut objects, &auto);
        assert!(matches!(stop, AutoStop::Rise(_)), "{stop:?}");
        let on = |want: &dyn Fn(f64, f64) -> bool| -> Vec<&Object> {
            cover
                .placements
                .iter()
                .filter(|p| want(p.centre.x, p.centre.y))
                .map(|p| &objects[p.object])
                .collect()
        };
        assert_eq!(on(&bar).len(), 1, "{:?}", cover.placements);
        assert_eq!(on(&bar)[0].shape, long.shape);
        assert_eq!(on(&square).len(), 1, "{:?}", cover.placements);
        assert_eq!(on(&square)[0].shape, small.shape);
        // At most one of the small kind: the square is left to the long block, or bare.
        let mut cover = Cover::new(&pic, frame);
        let mut objects = Vec::new();
        let auto = [(AutoObject::Given(small), 1)];
        assert_eq!(add_auto(&mut cover, &mut objects, &auto), AutoStop::Used);
        assert_eq!(objects.len(), 1);
    }
}
