//! `bsa new`'s first scene: the stage and one object of each kind ([`first_scene`]),
//! loaded and checked against the picture before any design, the design's inputs read
//! from it (request, picture, geometry), and the wider picture an automatic inventory
//! takes for its thin parts ([`wider`]).

use std::path::Path;

use anyhow::{bail, Result};
use serde_json::{json, Value};

use super::{amount, in_users_terms, AutoSlot, Options, Prototype, SCRATCH_TARGET};
use crate::cli::load;
use crate::design::launch::{Geometry, Object};
use crate::design::picture::Picture;
use crate::design::plant::{default_strategy, Stage};
use crate::design::{self, AutoObject, DesignError, Request};
use crate::scene::{Scene, SceneError};

/// Without `--width`, the wider picture an automatic inventory takes for its thin parts
/// ([`design::advice::auto_width`]) from `now` m, said on the first line.
pub(super) fn wider(
    opts: &Options,
    name: &str,
    now: f64,
    (picture, geometry, request): (&Picture, &Geometry, &Request),
) -> Option<f64> {
    if opts.width_given {
        return None;
    }
    let (width, thin) = design::advice::auto_width(picture, &geometry.frame(), request, now)?;
    println!(
        "{name}: a picture {width} m wide: at {now} m, {:.0} % of it is narrower than the narrowest shadow the objects cast ({:.1} cm); --width sets the width",
        100.0 * thin.share,
        100.0 * thin.least_width
    );
    Some(width)
}

/// The first scene of `stage`, with one object of each kind far apart above the table
/// (loading it reads and checks the target and every mesh), checked against the objects;
/// and the design's request, picture and geometry from it.
pub(super) fn first_scene(
    stage: &Stage,
    name: &str,
    (protos, of_item, auto): (&[Prototype], &[usize], &[AutoSlot]),
    (target, probe_file): (&Path, &Path),
    write: &dyn Fn(&Path, &Value) -> Result<()>,
) -> Result<(Scene, Request, Picture, Geometry)> {
    let mut probe = probe_json(protos, stage, name);
    if protos.is_empty() {
        // auto:sphere alone: a placeholder sphere, so that the scene loads.
        probe["occluders"] = json!([{"name": "probe", "shape": {"sphere": {"radius": 0.01}},
                                     "position": [0.0, 0.0, 1.0], "density": 1000.0}]);
    }
    write(probe_file, &probe)?;
    let (scene, light_err) = load_probe(probe_file, &probe, protos, target, write)?;
    let request = request_of(&scene, protos, (of_item, auto));
    check_sizes(&scene, protos, request.ceilings()[0])?;
    if let Some(e) = light_err {
        return Err(e);
    }
    check_dark_part(&scene, protos, target)?;
    let (picture, geometry) = picture_and_geometry(&scene);
    Ok((scene, request, picture, geometry))
}

/// The design's request: the list's fixed items as objects (each its prototype's
/// shape as the first scene loaded it), and the `auto:` kinds.
fn request_of(
    scene: &Scene,
    protos: &[Prototype],
    (of_item, auto): (&[usize], &[AutoSlot]),
) -> Request {
    let objects: Vec<Object> = protos
        .iter()
        .zip(&scene.occluders)
        .map(|(p, o)| Object {
            stem: p.stem.clone(),
            shape: o.shape.clone(),
            shape_json: p.shape.clone(),
            density: p.density,
        })
        .collect();
    Request {
        fixed: of_item.iter().map(|&k| objects[k].clone()).collect(),
        auto: auto
            .iter()
            .map(|a| {
                let kind = match a.proto {
                    Some(k) => AutoObject::Given(objects[k].clone()),
                    None => AutoObject::Sphere { density: a.density },
                };
                (kind, a.limit)
            })
            .collect(),
    }
}

/// The first scene's target as the design reads it, and its camera, table, gravity
/// and `t`.
fn picture_and_geometry(scene: &Scene) -> (Picture, Geometry) {
    let mask = &scene.target;
    let (w, h) = (mask.width(), mask.height());
    let picture = Picture::new(w, h, (0..w * h).map(|k| mask.get(k % w, k / w)).collect());
    let geometry = Geometry {
        camera: scene.camera.clone(),
        table_top: scene.table.as_ref().map_or(0.0, |t| t.top()),
        gravity: scene.gravity,
        t: scene.t,
        ceiling: design::CEILINGS[0],
        posed: false,
    };
    (picture, geometry)
}

/// Load the first scene ([`probe_json`]), telling its errors in the user's terms.
///
/// Its objects stand 10 m apart from 100 m above its table, so one some tens of metres
/// across overlaps another or the table: an overlap in a scratch file the user never
/// wrote, which says nothing of what is wrong. Then each object is loaded again alone,
/// with no table (one body overlaps nothing), so that its size is known and
/// [`check_sizes`] can say what is wrong with it.
///
/// A light lower than an object is thick is told after the sizes (an object too large
/// for the picture is the first thing to say): that object is loaded alone under a light
/// high above it, and the error returned beside the scene.
fn load_probe(
    file: &Path,
    probe: &Value,
    protos: &[Prototype],
    target: &Path,
    write: &dyn Fn(&Path, &Value) -> Result<()>,
) -> Result<(Scene, Option<anyhow::Error>)> {
    let err = match load::scene(file) {
        Ok(scene) => return Ok((scene, None)),
        Err(e) => e,
    };
    let no_room = |e: &anyhow::Error| {
        matches!(
            e.downcast_ref::<SceneError>(),
            Some(SceneError::NoRoomUnderLight { .. })
        )
    };
    if !no_room(&err)
        && !matches!(
            err.downcast_ref::<SceneError>(),
            Some(SceneError::Overlap { .. })
        )
    {
        return Err(in_users_terms(err, target, protos));
    }
    let mut first: Option<Scene> = None;
    let mut light_err = None;
    let mut occluders = Vec::with_capacity(protos.len());
    for (k, p) in protos.iter().enumerate() {
        let mut alone = probe.clone();
        alone["occluders"] = json!([probe["occluders"][k].clone()]);
        alone["strategy"] = default_strategy(1);
        if let Some(o) = alone.as_object_mut() {
            o.remove("table");
        }
        write(file, &alone)?;
        let in_terms = |e| in_users_terms(e, target, std::slice::from_ref(p));
        let scene = match load::scene(file) {
            Ok(scene) => scene,
            // Its size is checked first, under a light high above it.
            Err(e) if no_room(&e) => {
                light_err.get_or_insert(in_terms(e));
                alone["light"] = json!([0.0, 0.0, PROBE_HIGH_LIGHT]);
                write(file, &alone)?;
                load::scene(file).map_err(in_terms)?
            }
            Err(e) => return Err(in_terms(e)),
        };
        occluders.extend(scene.occluders.iter().cloned());
        first.get_or_insert(scene);
    }
    let mut scene = first.ok_or(err)?;
    // The designs take the objects' shapes from this scene, and the table's top from
    // it: none here, so the receiver's plane, where the first scene's table had it.
    scene.occluders = occluders;
    Ok((scene, light_err))
}

/// The light's height (m) under which [`load_probe`] loads objects thicker than the
/// light the user asked for is high, so that their sizes are checked first: the
/// highest a scene allows.
const PROBE_HIGH_LIGHT: f64 = crate::scene::MAX_COORDINATE;

/// A picture whose dark part is much smaller than any shadow the objects can cast
/// cannot be drawn by them ([`design::check_dark_part`]): refused before any design,
/// rather than designed and solved (a minute on an 8000 x 8000 picture) to IoU 0.
fn check_dark_part(scene: &Scene, protos: &[Prototype], target: &Path) -> Result<()> {
    let pixel = scene.receiver.width / scene.target.width() as f64;
    // The first scene holds one occluder per prototype, in order (a placeholder sphere
    // when there is none: `auto:sphere` alone, whose radii are chosen to fit).
    let least: Vec<f64> = scene
        .occluders
        .iter()
        .zip(protos)
        .map(|(o, _)| design::least_shadow_area(&o.shape, o.bounding_radius))
        .collect();
    match design::check_dark_part(scene.target.count(), pixel * pixel, &least) {
        Ok(()) => Ok(()),
        Err(DesignError::TooLittleDark {
            dark_pixels,
            dark_area,
            object,
            least_shadow,
        }) => {
            let width = scene.receiver.width;
            // The dark part's area grows with the square of the picture's width.
            let wider = width * (design::LEAST_DARK_SHARE * least_shadow / dark_area).sqrt();
            bail!(
                "--target {}: its dark part ({dark_pixels} pixel{} of {} x {}, {} m^2 at --width {width}) is less than half the least shadow that --objects {} can cast ({} m^2, {:.0} pixels, at any height and turn), so no launch can draw it: use a wider picture (--width {} or more), or smaller objects",
                target.display(),
                if dark_pixels == 1 { "" } else { "s" },
                scene.target.width(),
                scene.target.height(),
                amount(dark_area),
                protos[object].describe(),
                amount(least_shadow),
                least_shadow / (pixel * pixel),
                amount(wider),
            )
        }
        Err(e) => Err(e.into()),
    }
}

/// An object whose shadow is wider than the picture cannot be part of it; one whose
/// shadow is smaller than a pixel even at the request's highest ceiling cannot be seen
/// in it.
fn check_sizes(scene: &Scene, protos: &[Prototype], highest: f64) -> Result<()> {
    let pixel = scene.receiver.width / scene.target.width() as f64;
    // A body under the highest ceiling, a share c of the light's height above the
    // picture, casts a shadow 1 / (1 - c) times its size.
    let magnified = 1.0 / (1.0 - highest);
    for (o, p) in scene.occluders.iter().zip(protos) {
        let most = 2.0 * o.bounding_radius * magnified;
        if most < pixel {
            bail!(
                "--objects: {} ({:.2e} m across) casts a shadow of at most {:.2e} m, less than one pixel ({:.2e} m) of the {:.2} m wide picture: use larger objects or a narrower picture (--width)",
                p.describe(),
                2.0 * o.bounding_radius,
                most,
                pixel,
                scene.receiver.width
            );
        }
        let shadow = 2.0 * o.bounding_radius * 1.5;
        if shadow > scene.receiver.width.min(scene.receiver.height) {
            bail!(
                "--objects: {} ({} m across) casts a shadow of about {} m, larger than the {:.2} x {:.2} m picture, so it cannot be part of it: use a wider picture (--width) or smaller objects",
                p.describe(),
                amount(2.0 * o.bounding_radius),
                amount(shadow),
                scene.receiver.width,
                scene.receiver.height
            );
        }
    }
    Ok(())
}

/// The first scene file: the stage and one object of each kind.
fn probe_json(protos: &[Prototype], stage: &Stage, name: &str) -> Value {
    let occluders: Vec<Value> = protos
        .iter()
        .enumerate()
        .map(|(k, p)| {
            json!({"name": format!("{}_{}", p.stem, k + 1), "shape": p.shape,
                       "position": [0.0, -30.0, 100.0 + 10.0 * k as f64], "density": p.density})
        })
        .collect();
    stage.scene_json(name, SCRATCH_TARGET, occluders, protos.len().max(1))
}
