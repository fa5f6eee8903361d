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

pub mod assign;
pub mod chess;
pub mod cover;
pub mod inventory;
pub mod launch;
pub mod picture;
pub mod plant;
pub mod pose;
pub mod separate;

use cover::{Cover, Placement};
use launch::{Geometry, Object, Plan};
use picture::Picture;

/// The objects of a design: those given, and the kinds the design may add while they
/// pay for themselves.
#[derive(Clone, Debug)]
pub struct Request {
    pub fixed: Vec<Object>,
    pub auto: Option<AutoRequest>,
}

/// What an `auto:` item may add.
#[derive(Clone, Debug)]
pub enum AutoRequest {
    /// Copies of these objects, at most the given number of each.
    Objects(Vec<(Object, usize)>),
    /// Spheres of any radius (whole millimetres) at this density.
    Spheres { density: f64 },
}

/// An automatic count stops when the next object's shadow would gain less than this
/// share of its own area (new target pixels minus new background pixels), ...
pub const AUTO_MIN_SHARE: f64 = 0.3;
/// ... or when less than this share of the target is left uncovered, ...
pub const AUTO_OPEN_SHARE: f64 = 0.01;
/// ... or at this many objects of the automatic kind.
pub const AUTO_CAP: usize = 24;

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
    #[error("no object of the auto: kind covers enough of the picture to be worth launching (each would cover less than {:.0} % of its own shadow's area with new target)", AUTO_MIN_SHARE * 100.0)]
    NothingWorthIt,
}

/// Design a scene: place every object's shadow on `picture` (largest first), add
/// objects of the `auto:` kind while they gain enough, and plan the launches.
pub fn design(
    picture: &Picture,
    geometry: Geometry,
    request: &Request,
) -> Result<Plan, DesignError> {
    let frame = geometry.frame();
    let mut cover = Cover::new(picture, frame);
    let mut objects = request.fixed.clone();
    let mut order: Vec<usize> = (0..objects.len()).collect();
    order.sort_by(|&a, &b| {
        objects[b]
            .shape
            .volume()
            .total_cmp(&objects[a].shape.volume())
            .then(a.cmp(&b))
    });
    for k in order {
        let fams = objects[k].families();
        let p = cover.best(k, &fams).ok_or_else(|| DesignError::NoRoom {
            index: k + 1,
            stem: objects[k].stem.clone(),
        })?;
        let family = fams[p.family].clone();
        cover.commit(p, family);
    }
    let target = picture.count() as f64;
    if let Some(auto) = &request.auto {
        let mut left: Vec<usize> = match auto {
            AutoRequest::Objects(list) => list.iter().map(|x| x.1).collect(),
            AutoRequest::Spheres { .. } => vec![AUTO_CAP],
        };
        for _ in 0..AUTO_CAP {
            if (cover.open() as f64) < AUTO_OPEN_SHARE * target {
                break;
            }
            let k = objects.len();
            let mut best: Option<(Placement, Object, usize)> = None;
            match auto {
                AutoRequest::Objects(list) => {
                    for (i, (o, _)) in list.iter().enumerate() {
                        if left[i] == 0 {
                            continue;
                        }
                        let fams = o.families();
                        if let Some(p) = cover.best(k, &fams) {
                            let worth = p.gain >= AUTO_MIN_SHARE * p.area;
                            if worth && best.as_ref().is_none_or(|b| p.gain > b.0.gain) {
                                best = Some((p, o.clone(), i));
                            }
                        }
                    }
                }
                AutoRequest::Spheres { density } => {
                    if let Some((p, radius)) = cover.best_disc(k) {
                        if p.gain >= AUTO_MIN_SHARE * p.area {
                            best = Some((p, sphere(radius, *density), 0));
                        }
                    }
                }
            }
            let Some((p, o, i)) = best else { break };
            left[i] -= 1;
            let family = o.families()[p.family].clone();
            objects.push(o);
            cover.commit(p, family);
        }
    }
    if objects.is_empty() {
        return Err(DesignError::NothingWorthIt);
    }
    // Which object goes where, reconsidered (see `Cover::exchange`).
    let fams: Vec<Vec<pose::Family>> = cover
        .placements
        .iter()
        .map(|p| objects[p.object].families())
        .collect();
    let shapes: Vec<&crate::geometry::shape::Shape> = cover
        .placements
        .iter()
        .map(|p| &objects[p.object].shape)
        .collect();
    for _ in 0..EXCHANGE_ROUNDS {
        if cover.exchange(&fams, &|a, b| shapes[a] == shapes[b]) == 0 {
            break;
        }
    }
    cover.polish(POLISH_ROUNDS);
    Ok(Plan::new(geometry, objects, cover.placements))
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
