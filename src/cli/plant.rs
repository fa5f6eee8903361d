//! `bsa plant`: a problem with a known answer ([`crate::design::plant`]): the scene, its
//! target (the shadow of a random contact-free launch) and that launch.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::design::inventory::{self, Inventory, Item};
use crate::design::plant::{self, Layout, MeshFile, Stage};
use crate::energy::Weights;
use crate::evaluate::Problem;
use crate::geometry::shape::{load_obj, ObjError};
use crate::output::{files, picture};
use crate::scene::Launch;
use crate::shadow::mask::Mask;

use super::scratch::Scratch;
use super::{load, DesignArgs, PlantArgs};

/// Draws before `bsa plant` gives up on an inventory.
const ATTEMPTS: usize = 2000;

/// The validated options of `bsa plant`.
pub(super) struct Options {
    dir: PathBuf,
    items: Vec<Item>,
    seed: u64,
    stage: Stage,
}

impl Options {
    pub(super) fn new(args: PlantArgs) -> Result<Options> {
        let design = Design::new(args.design)?;
        if !design.inventory.autos.is_empty() {
            bail!("--objects: bsa plant draws a fixed box of objects; auto: items are for bsa new");
        }
        Ok(Options {
            dir: args.dir,
            items: design.inventory.items,
            seed: design.seed,
            stage: design.stage,
        })
    }
}

/// The validated objects and stage of `bsa new` and `bsa plant`.
pub(super) struct Design {
    pub(super) inventory: Inventory,
    pub(super) seed: u64,
    pub(super) stage: Stage,
    /// Whether `--width` was given (else the stage has the default width).
    pub(super) width_given: bool,
}

impl Design {
    pub(super) fn new(args: DesignArgs) -> Result<Design> {
        let inventory = read_inventory(&args.objects)?;
        let width = args.width.unwrap_or(Stage::default().picture_width);
        for (name, value, lo, hi) in [
            ("--width", width, 0.01, 1000.0),
            ("--light-height", args.light_height, 0.1, 1000.0),
            ("--t", args.t, 0.05, 60.0),
        ] {
            if !(value.is_finite() && value >= lo && value <= hi) {
                bail!("{name} must be between {lo} and {hi}, got {value}");
            }
        }
        Ok(Design {
            inventory,
            seed: args.seed,
            stage: Stage {
                picture_width: width,
                light_height: args.light_height,
                t: args.t,
                ..Stage::default()
            },
            width_given: args.width.is_some(),
        })
    }
}

/// The `--objects` argument: a list, or a JSON file (a name ending in `.json`) whose
/// mesh paths are relative to its folder.
fn read_inventory(arg: &str) -> Result<Inventory> {
    if arg.to_ascii_lowercase().ends_with(".json") {
        let path = std::path::Path::new(arg);
        let text = crate::scene::read_input_text(path)
            .with_context(|| format!("--objects: cannot read {}", path.display()))?;
        let base = path.parent().unwrap_or(std::path::Path::new("."));
        return inventory::parse_json(&text, base, &crate::scene::path_kind)
            .with_context(|| format!("--objects {}", path.display()));
    }
    inventory::parse(arg, &crate::scene::path_kind).context("--objects")
}

/// A mesh of `--objects`, read for the layout, and the absolute path the planted scene
/// names it by.
fn read_mesh(obj: &std::path::Path, scale: f64) -> Result<MeshFile, ObjError> {
    Ok(MeshFile {
        mesh: load_obj(obj, scale)?,
        path: std::fs::canonicalize(obj).unwrap_or_else(|_| obj.to_path_buf()),
    })
}

pub(super) fn run(opts: &Options) -> Result<()> {
    let layout = Layout::new(opts.stage.clone(), &opts.items, &read_mesh)?;
    let dir = &opts.dir;
    let created = !dir.exists();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let name = dir
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("planted")
        .to_string();
    let (w, h) = opts.stage.pixels;
    // The draw works in scratch files: the folder's scene is replaced only once the new
    // one is complete (see `scratch`).
    let (scratch_target, scratch_scene) = (".bsa-plant-target.png", ".bsa-plant-scene.json");
    let scratch = Scratch::new(
        vec![dir.join(scratch_target), dir.join(scratch_scene)],
        dir,
        created,
    );
    let write_scene =
        |file: &str, target: &str, hints: &[(usize, glam::DVec3, glam::DVec2)]| -> Result<()> {
            let json = layout.scene_json(&name, target, hints, opts.seed);
            files::write_atomic(
                &dir.join(file),
                serde_json::to_string_pretty(&json)?.as_bytes(),
            )?;
            Ok(())
        };
    // The scene needs a target to load: a placeholder until the draw gives the real one.
    let placeholder = Mask::from_fn(w, h, |x, y| x == w / 2 && y == h / 2);
    write_target(&dir.join(scratch_target), &placeholder)?;
    write_scene(scratch_scene, scratch_target, &[])?;
    let scene = load::scene(&dir.join(scratch_scene)).map_err(|e| {
        // Told in the options' terms: the scratch scene is no file of the user's.
        match e.downcast_ref::<crate::scene::SceneError>() {
            Some(crate::scene::SceneError::NoRoomUnderLight {
                name, room, width, ..
            }) => anyhow::anyhow!(
                "--light-height {room}: object `{name}` of --objects is {width:.3} m thick where it is thinnest, so it can never pass whole between the light and the picture; raise the light above {width:.3} m (or check the units: metres)"
            ),
            _ => e,
        }
    })?;
    let problem = Problem::new(scene);
    let params = plant::draw_launch(&problem, opts.seed, ATTEMPTS)?;
    let mut ws = problem.workspace();
    problem.evaluate(&params, &Weights::default(), &mut ws);
    let target = problem.picture_of(&ws.mask);
    let hints = plant::hints(&problem, &target);
    write_target(&dir.join("target.png"), &target)?;
    write_scene("scene.json", "target.png", &hints)?;
    // The planted launch, as a launch file `bsa render` reads.
    let scene = &problem.scene;
    let mut launch = serde_json::Map::new();
    for (i, o) in scene.occluders.iter().enumerate() {
        let l = Launch::get(&params, i);
        launch.insert(
            o.name.clone(),
            serde_json::json!({"velocity": l.velocity.to_array(), "angular_velocity": l.angular_velocity.to_array()}),
        );
    }
    files::write_atomic(
        &dir.join("planted.json"),
        serde_json::to_string_pretty(&launch)?.as_bytes(),
    )?;
    scratch.written();
    // The scene as a user gets it: loads, and its start guess aimed at the hints.
    let problem = Problem::new(load::scene(dir)?);
    let start = problem.evaluate(
        &problem.scene.start_parameters(),
        &Weights::default(),
        &mut ws,
    );
    println!(
        "{}: {} object{}, target {} shadow pixels; the planted launch (IoU 1) is in {}; start guess IoU {:.4}; wrote {}/{{scene.json, target.png, planted.json}}",
        name,
        layout.len(),
        if layout.len() == 1 { "" } else { "s" },
        target.count(),
        dir.join("planted.json").display(),
        start.iou,
        dir.display()
    );
    Ok(())
}

fn write_target(file: &std::path::Path, mask: &Mask) -> Result<()> {
    let img = picture::mask_image(mask.width(), mask.height(), &|x, y| mask.get(x, y));
    files::save_png(&img, file)?;
    Ok(())
}
