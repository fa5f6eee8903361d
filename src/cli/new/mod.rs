//! `bsa new`: a scene from a picture and a box of objects ([`crate::design`]). The
//! objects' shapes are loaded (and checked) through a first scene file that holds one
//! of each ([`first`], which also widens the picture for an automatic inventory's thin
//! parts); the design places their shadows on the picture, plans the launches and
//! writes the scene; the start guess is then made contact-free with the exact contact
//! search and the scene written again; `start.png` shows the start guess over the
//! target. Everything the user reads (the start IoU, a contact) comes from the scene
//! file as written, loaded afresh.
//!
//! The design search ([`crate::compose`]) designs the picture under every
//! setting and, by default ([`ChooseBy::Solve`]), races the designs by their trial
//! solves; the best is written.
//!
//! Until the scene is written, `bsa new` works in scratch files in the folder (a copy of
//! the target, the first scene, one scene per design; [`Scratch`] removes them however
//! the command ends): an error or a Ctrl-C leaves the folder's `scene.json` and
//! `target.png` as they were, and the folder's scene is only replaced, target first, once
//! the new one is complete.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{bail, Context, Result};
use serde_json::{json, Value};

use crate::compose::{self, tolerant, Search, SearchError, Solved, Variant};
use crate::design::inventory::{Auto, AutoKind, Inventory, Kind};
use crate::design::launch::Plan;
use crate::design::plant::Stage;
use crate::design::{self, chess, DesignError};
use crate::energy::Weights;
use crate::evaluate::Problem;
use crate::output::files;
use crate::scene::launcher::Tolerances;
use crate::scene::{Contacts, Scene, SceneError};

use super::guard::NothingWritten;
use super::plant::Design;
use super::scratch::Scratch;
use super::{load, NewArgs};

/// Ctrl-C presses (and SIGTERMs) during `bsa new`: the trial solves stop at once, and
/// no scene is written.
mod first;
mod search;

use first::{first_scene, wider};

static INTERRUPTS: AtomicUsize = AtomicUsize::new(0);

/// The scratch copy of the target that the first scene and the designs load.
const SCRATCH_TARGET: &str = ".bsa-new-target.png";
/// The first scene (one object of each kind), which reads and checks every input.
const SCRATCH_PROBE: &str = ".bsa-new-probe.json";

/// The validated options of `bsa new`.
pub(super) struct Options {
    dir: PathBuf,
    target: PathBuf,
    inventory: Inventory,
    seed: u64,
    stage: Stage,
    /// Whether `--width` was given: without it, an automatic inventory may widen the
    /// picture ([`design::advice::auto_width`]).
    width_given: bool,
    choose_by: ChooseBy,
    /// `--launcher`: design for it, with the file it was read from (if any).
    launcher: Option<(Tolerances, Option<PathBuf>)>,
}

/// How `bsa new` chooses among its designs (one per ceiling and order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum ChooseBy {
    /// The design whose solve (as `bsa solve` runs it) ends at the best picture.
    Solve,
    /// The design whose start guess reads best.
    Start,
}

impl Options {
    pub(super) fn new(args: NewArgs) -> Result<Options> {
        let design = Design::new(args.design)?;
        let launcher = match args.launcher {
            None => None,
            Some(None) => Some((Tolerances::default(), None)),
            Some(Some(f)) => Some((super::launcher::read(&f, design.stage.t)?, Some(f))),
        };
        if launcher.is_some() && args.choose_by == ChooseBy::Start {
            bail!("--launcher measures every design's solve at the launcher: it needs --choose-by solve");
        }
        Ok(Options {
            dir: args.dir,
            target: args.target,
            inventory: design.inventory,
            seed: design.seed,
            stage: design.stage,
            width_given: design.width_given,
            choose_by: args.choose_by,
            launcher,
        })
    }
}

/// One distinct object of the inventory, as the scene file writes it.
struct Prototype {
    /// The object as the list gives it (a mesh's path as the user typed it).
    kind: Kind,
    stem: String,
    shape: Value,
    density: f64,
}

impl Prototype {
    /// The object as the user's list names it: `sphere:R`, `box:XxYxZ`,
    /// `mesh:FILE[@SCALE]` (the path as given, not as the scene file writes it), or the
    /// chess piece.
    fn describe(&self) -> String {
        match &self.kind {
            Kind::Sphere { radius } => format!("sphere:{radius}"),
            Kind::Box { size } => format!("box:{}x{}x{}", size[0], size[1], size[2]),
            Kind::Mesh { obj, scale } if *scale != 1.0 => {
                format!("mesh:{}@{scale}", obj.display())
            }
            Kind::Mesh { obj, .. } => format!("mesh:{}", obj.display()),
            Kind::Chess { piece } => format!("the chess {piece}"),
        }
    }
}

/// The scene file's shape of a kind (chess pieces are written beside the scene).
fn prototype(dir: &Path, kind: &Kind, density: f64) -> Result<Prototype> {
    let (stem, shape) = match kind {
        Kind::Sphere { radius } => ("sphere".to_string(), json!({"sphere": {"radius": radius}})),
        Kind::Box { size } => ("box".to_string(), json!({"box": {"size": size}})),
        Kind::Mesh { obj, scale } => {
            let stem = obj
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("mesh")
                .to_string();
            let path = mesh_path(dir, obj)
                .with_context(|| format!("--objects: mesh:{}", obj.display()))?;
            (stem, json!({"mesh": {"obj": path, "scale": scale}}))
        }
        Kind::Chess { piece } => {
            let rel = format!("pieces/{piece}.obj");
            let path = dir.join(&rel);
            let text = chess::obj(piece).expect("checked by the inventory");
            match std::fs::read(&path) {
                Ok(old) if old == text.as_bytes() => {}
                Ok(_) => bail!(
                    "{} exists and is not the built-in {piece}: remove it, or list it as mesh:{}",
                    path.display(),
                    path.display()
                ),
                Err(_) => files::write_atomic(&path, text.as_bytes())?,
            }
            (piece.clone(), json!({"mesh": {"obj": rel}}))
        }
    };
    Ok(Prototype {
        kind: kind.clone(),
        stem,
        shape,
        density,
    })
}

/// An OBJ path as the scene in `dir` names it: relative when the file is inside `dir`,
/// else absolute. The path is the user's, relative to the current folder: when it
/// cannot be resolved there, this is an error, never a path the scene would read
/// relative to `dir` (and so perhaps another file).
fn mesh_path(dir: &Path, obj: &Path) -> Result<String> {
    let abs = std::fs::canonicalize(obj)
        .with_context(|| format!("cannot find the OBJ file {}", obj.display()))?;
    Ok(
        match std::fs::canonicalize(dir)
            .ok()
            .and_then(|d| abs.strip_prefix(d).ok().map(Path::to_path_buf))
        {
            Some(rel) => rel.display().to_string(),
            None => abs.display().to_string(),
        },
    )
}

/// A kind an `auto:` item may add: its prototype (`None`: spheres of any radius, at the
/// density), and the most it may add.
struct AutoSlot {
    proto: Option<usize>,
    density: f64,
    limit: usize,
}

/// The prototypes of an inventory, the prototype of each item, and the `auto:` kinds.
type Prototypes = (Vec<Prototype>, Vec<usize>, Vec<AutoSlot>);

/// The prototypes of the inventory: one per distinct item, then those of the `auto:`
/// kind; and for each item, its prototype.
fn prototypes(dir: &Path, inv: &Inventory) -> Result<Prototypes> {
    let mut protos: Vec<(Kind, f64)> = Vec::new();
    let mut of_item = Vec::new();
    for item in &inv.items {
        let at = protos
            .iter()
            .position(|p| p.0 == item.kind && p.1 == item.density)
            .unwrap_or_else(|| {
                protos.push((item.kind.clone(), item.density));
                protos.len() - 1
            });
        of_item.push(at);
    }
    // The auto: kinds' prototypes and how many of each they may add.
    let mut auto = Vec::new();
    for a in &inv.autos {
        // The design's own cap bounds an item without `*N`.
        let limit = a.limit.unwrap_or(usize::MAX);
        let kinds: Vec<(Kind, usize)> = match &a.kind {
            AutoKind::Sphere { radius: Some(r) } => vec![(Kind::Sphere { radius: *r }, limit)],
            AutoKind::Sphere { radius: None } => {
                auto.push(AutoSlot {
                    proto: None,
                    density: a.density,
                    limit,
                });
                continue;
            }
            AutoKind::Box { size } => vec![(Kind::Box { size: *size }, limit)],
            AutoKind::Mesh { obj, scale } => vec![(
                Kind::Mesh {
                    obj: obj.clone(),
                    scale: *scale,
                },
                limit,
            )],
            AutoKind::Chess => chess::PIECES
                .iter()
                .map(|(p, n)| {
                    (
                        Kind::Chess {
                            piece: p.to_string(),
                        },
                        *n,
                    )
                })
                .collect(),
        };
        for (kind, n) in kinds {
            protos.push((kind, a.density));
            auto.push(AutoSlot {
                proto: Some(protos.len() - 1),
                density: a.density,
                limit: n,
            });
        }
    }
    let protos = protos
        .iter()
        .map(|(k, d)| prototype(dir, k, *d))
        .collect::<Result<Vec<_>>>()?;
    Ok((protos, of_item, auto))
}

pub(super) fn run(opts: &Options) -> Result<()> {
    let bytes = crate::scene::read_input(&opts.target)
        .with_context(|| format!("cannot read --target {}", opts.target.display()))?;
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .with_context(|| format!("--target {} is not a readable PNG", opts.target.display()))?;
    let mut stage = Stage {
        pixels: (img.width() as usize, img.height() as usize),
        ..opts.stage.clone()
    };
    let dir = &opts.dir;
    let created = !dir.exists();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let probe_file = dir.join(SCRATCH_PROBE);
    let most_settings = compose::most_designs(&design::CEILINGS)
        .max(compose::most_designs(&design::AUTO_CEILINGS))
        .max(compose::most_designs(&tolerant::LAUNCHER_CEILINGS));
    let design_files: Vec<PathBuf> = (0..most_settings)
        .map(|k| dir.join(format!(".bsa-new-design-{k}.json")))
        .collect();
    let scratch = Scratch::new(
        [dir.join(SCRATCH_TARGET), probe_file.clone()]
            .into_iter()
            .chain(design_files.iter().cloned())
            .collect(),
        dir,
        created,
    );
    files::write_atomic(&dir.join(SCRATCH_TARGET), &bytes)?;
    // With ctrlc's "termination" feature this handles SIGTERM (and SIGHUP) like Ctrl-C.
    ctrlc::set_handler(|| {
        if INTERRUPTS.fetch_add(2, Ordering::SeqCst) == 0 {
            eprintln!("\ninterrupt: stopping; no scene will be written");
        }
    })
    .context("cannot install the Ctrl-C handler")?;
    let name = dir
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string();
    let scene_file = dir.join("scene.json");
    let write = |file: &Path, json: &Value| -> Result<()> {
        files::write_atomic(file, serde_json::to_string_pretty(json)?.as_bytes())?;
        Ok(())
    };
    let (protos, of_item, auto) = prototypes(dir, &opts.inventory)?;
    let first = |stage: &Stage| {
        let kinds = (protos.as_slice(), of_item.as_slice(), auto.as_slice());
        first_scene(stage, &name, kinds, (&opts.target, &probe_file), &write)
    };
    let (mut scene, mut request, mut picture, mut geometry) = first(&stage)?;
    let now = stage.picture_width;
    if let Some(width) = wider(opts, &name, now, (&picture, &geometry, &request)) {
        stage.picture_width = width;
        (scene, request, picture, geometry) = first(&stage)?;
    }
    // One design per setting, in parallel, each written to its own file beside the
    // scene (mesh paths are relative to the folder) and made contact-free; then, by
    // default, the designs that differ race, and the best is kept.
    let trial = opts.choose_by == ChooseBy::Solve;
    let search = Search {
        picture: &picture,
        geometry: &geometry,
        request: &request,
        scenes: &search::DesignFiles(&design_files),
        name: &name,
        target: SCRATCH_TARGET,
        seed: opts.seed,
        trial,
        ceilings: request.ceilings(),
        launcher: None,
        rounds: 2,
    };
    let (kept, frontier, trials) = search::run(&search, opts.launcher.as_ref().map(|l| l.0));
    if INTERRUPTS.load(Ordering::SeqCst) > 0 {
        return Err(NothingWritten {
            dir: dir.display().to_string(),
        }
        .into());
    }
    let Ok(Variant {
        plan,
        moves,
        solved,
        ..
    }) = kept
    else {
        let err = match kept.err().flatten() {
            Some(SearchError::Design(e)) => e.into(),
            Some(SearchError::Scenes(e)) => anyhow::Error::from_boxed(e),
            Some(e) => e.into(),
            None => unreachable!("every setting gave a design or an error"),
        };
        return Err(design_in_users_terms(err, opts, &scene, &protos, &of_item));
    };
    // The folder's scene is replaced only now, target first: a scene.json is never left
    // beside a target it was not made for.
    files::write_atomic(&dir.join("target.png"), &bytes)?;
    let mut json = plan.scene_json(&name, "target.png", opts.seed);
    if let Some((tol, _)) = &opts.launcher {
        json["launcher"] = serde_json::to_value(tol)?;
    }
    write(&scene_file, &json)?;
    scratch.written();
    if let Some(line) = trials.filter(|_| trial) {
        println!("{name}: {line}");
    }
    if let Some(f) = &frontier {
        search::write_frontier(dir, &name, f)?;
    }
    // What the user gets: the scene as written, loaded afresh.
    tell_written(opts, &name, (&plan, moves, solved), &search)
}

/// Tell the user what was written: the scene as written, loaded afresh, its start
/// guess drawn into `start.png`, a line of what it holds and, when the objects leave
/// much of the picture bare or in parts too thin for them (the picture and objects that
/// `drawn` designed from), a note.
fn tell_written(
    opts: &Options,
    name: &str,
    (plan, moves, solved): (&Plan, usize, Option<Solved>),
    drawn: &Search,
) -> Result<()> {
    let dir = &opts.dir;
    let problem = Problem::new(load::scene(dir)?);
    let mut ws = problem.workspace();
    let start = problem.evaluate(
        &problem.scene.start_parameters(),
        &Weights::default(),
        &mut ws,
    );
    let start_picture = problem.picture_of(&ws.mask);
    files::save_overlay(
        &dir.join("start.png"),
        &problem.scene.target,
        &start_picture,
        &format!("{name}: the start guess at t, before any solve"),
    )?;
    let n = plan.objects.len();
    let heights: Vec<f64> = (0..n).map(|k| plan.height(k)).collect();
    let chosen = n - opts.inventory.items.len();
    // The scene's contacts mode, as written (bsa new writes the default, a constraint).
    let contact_rule = match problem.scene.contacts {
        Contacts::Constraint => "the solver ranks launches without one first",
        Contacts::Penalty => "the solver treats it as a penalty",
    };
    println!(
        "{}: {} object{}{}; heights at t {:.2} to {:.2} m; {} move{} to keep the flights apart; start guess IoU {:.4}, {}; wrote {}/{{scene.json, target.png, start.png}}; next: bsa solve {}",
        name,
        n,
        if n == 1 { "" } else { "s" },
        match plan.auto_stop {
            Some(why) => format!(" ({chosen} chosen by auto:, which stopped as {why})"),
            None => String::new(),
        },
        heights.iter().copied().fold(f64::INFINITY, f64::min),
        heights.iter().copied().fold(0.0, f64::max),
        moves,
        if moves == 1 { "" } else { "s" },
        start.iou,
        if start.outcome.n_contacts > 0 {
            format!("with a contact at {:.3} s ({contact_rule})", start.outcome.t_sim)
        } else {
            "no contact before t".to_string()
        },
        dir.display(),
        dir.display()
    );
    let target = &problem.scene.target;
    let missed = target.and_not_count(&start_picture) as f64 / target.count().max(1) as f64;
    let iou = solved.map_or(start.iou, |s| s.iou);
    let thin = || design::advice::thin_parts(drawn.picture, &drawn.geometry.frame(), drawn.request);
    if let Some(note) = design::advice::note(missed, iou, plan.auto_stop, &thin) {
        eprintln!("{name}: note: {note}");
    }
    Ok(())
}

/// An error of the first scene, which is a scratch file the user never wrote, told in
/// terms of the command's own inputs: `--target`, or the `--objects` item at fault.
fn in_users_terms(err: anyhow::Error, target: &Path, protos: &[Prototype]) -> anyhow::Error {
    let target = target.display();
    // `occluders[k]...` of the first scene is the k-th distinct object of the list.
    let object = |field: &str| -> Option<String> {
        let k: usize = field
            .strip_prefix("occluders[")?
            .split(']')
            .next()?
            .parse()
            .ok()?;
        protos.get(k).map(Prototype::describe)
    };
    match err.downcast_ref::<SceneError>() {
        Some(SceneError::TargetEmpty { .. }) => anyhow::anyhow!(
            "--target {target}: the picture has no dark pixel (dark = luminance below half, opaque); there is nothing to make"
        ),
        Some(SceneError::TargetNotPng { reason, .. }) => {
            anyhow::anyhow!("--target {target} is not a readable PNG: {reason}")
        }
        Some(SceneError::Obj { field, error, .. }) => match object(field) {
            Some(what) => anyhow::anyhow!("--objects: {what}: {error}"),
            None => err,
        },
        Some(SceneError::NoRoomUnderLight {
            index, room, width, ..
        }) => match protos.get(*index) {
            Some(p) => anyhow::anyhow!(
                "--light-height {}: --objects {} is {} m thick where it is thinnest, so it can never pass whole between the light and the picture; raise the light above {} m (or check the units: metres)",
                amount(*room),
                p.describe(),
                amount(*width),
                amount(*width),
            ),
            None => err,
        },
        Some(SceneError::Field { field, reason, .. }) => match object(field) {
            Some(what) => anyhow::anyhow!("--objects: {what}: {reason}"),
            None => err,
        },
        _ => err.context(format!("from --target {target} and --objects")),
    }
}

/// A length or area for a message: three decimals at everyday sizes, a power of ten
/// beyond them (a mesh of +-5e5 m is 1732050.808 m across otherwise, and a shadow of
/// 0.0013 m^2 would read 0.001).
fn amount(x: f64) -> String {
    if (0.1..1e4).contains(&x) {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

/// A design's error told in terms of the command's inputs: which `--objects` item, on
/// which `--target`, and what to change.
fn design_in_users_terms(
    err: anyhow::Error,
    opts: &Options,
    scene: &Scene,
    protos: &[Prototype],
    of_item: &[usize],
) -> anyhow::Error {
    let target = opts.target.display();
    let picture = format!(
        "--target {target} ({} dark pixels of {} x {}, {} m wide)",
        scene.target.count(),
        scene.target.width(),
        scene.target.height(),
        scene.receiver.width
    );
    match err.downcast_ref::<DesignError>() {
        Some(DesignError::NothingWorthIt) => {
            let auto: Vec<String> = opts.inventory.autos.iter().map(Auto::to_string).collect();
            let auto = auto.join(",");
            anyhow::anyhow!(
                "--objects {auto}: on {picture} no such object is worth launching: wherever its shadow falls it would raise the picture's IoU by less than {}; use smaller objects (auto:sphere chooses their size), or a wider picture (--width) so that the picture's strokes are wider against them",
                design::AUTO_MIN_RISE
            )
        }
        Some(DesignError::NoRoom { index, .. }) => {
            // The design's objects are the list's fixed items, in order.
            let what = of_item
                .get(index - 1)
                .and_then(|&k| protos.get(k))
                .map_or_else(|| format!("object {index}"), Prototype::describe);
            anyhow::anyhow!(
                "--objects: no room for {what} (object {index}) on {picture}: every place on the picture needs a height that another shadow there already takes; use fewer or smaller objects, or a wider picture (--width)"
            )
        }
        _ => err,
    }
}
