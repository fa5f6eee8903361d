//! `bsa new`: a scene from a picture and a box of objects ([`crate::design`]): the
//! objects laid out on the floor in front of the picture, one hint per object where it
//! covers the most of the picture ([`crate::design::cover`]), the start guess aimed at
//! the hints, the default strategy; and `start.png`, the start guess over the target.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::design::cover;
use crate::design::inventory::Item;
use crate::design::plant::{Layout, Stage};
use crate::energy::Weights;
use crate::evaluate::Problem;
use crate::output::files;

use super::plant::Design;
use super::{load, NewArgs};

/// The validated options of `bsa new`.
pub(super) struct Options {
    dir: PathBuf,
    target: PathBuf,
    items: Vec<Item>,
    seed: u64,
    stage: Stage,
}

impl Options {
    pub(super) fn new(args: NewArgs) -> Result<Options> {
        let design = Design::new(args.design)?;
        Ok(Options {
            dir: args.dir,
            target: args.target,
            items: design.items,
            seed: design.seed,
            stage: design.stage,
        })
    }
}

pub(super) fn run(opts: &Options) -> Result<()> {
    let bytes = std::fs::read(&opts.target)
        .with_context(|| format!("cannot read --target {}", opts.target.display()))?;
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .with_context(|| format!("--target {} is not a readable PNG", opts.target.display()))?;
    let stage = Stage {
        pixels: (img.width() as usize, img.height() as usize),
        ..opts.stage.clone()
    };
    let layout = Layout::new(stage.clone(), &opts.items)?;
    let dir = &opts.dir;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    files::write_atomic(&dir.join("target.png"), &bytes)?;
    let name = dir
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string();
    let scene_file = dir.join("scene.json");
    let write_scene = |hints: &[(usize, glam::DVec2)]| -> Result<()> {
        let json = layout.scene_json(&name, "target.png", hints, opts.seed);
        files::write_atomic(&scene_file, serde_json::to_string_pretty(&json)?.as_bytes())?;
        Ok(())
    };
    write_scene(&[])?;
    let problem = Problem::new(
        load::scene(dir).with_context(|| format!("from --target {}", opts.target.display()))?,
    );
    // An object whose shadow is wider than the picture cannot be part of it.
    let scene = &problem.scene;
    for o in &scene.occluders {
        let shadow = 2.0 * o.bounding_radius * 1.5;
        if shadow > scene.receiver.width.min(scene.receiver.height) {
            bail!(
                "object `{}` ({:.3} m across) casts a shadow of about {:.2} m, larger than the {:.2} x {:.2} m picture: use a wider picture (--width) or smaller objects",
                o.name,
                2.0 * o.bounding_radius,
                shadow,
                scene.receiver.width,
                scene.receiver.height
            );
        }
    }
    let hints = cover::cover_hints(&problem, &problem.target.mask);
    write_scene(&hints)?;
    let problem = Problem::new(load::scene(dir)?);
    let mut ws = problem.workspace();
    let start = problem.evaluate(
        &problem.scene.start_parameters(),
        &Weights::default(),
        &mut ws,
    );
    files::save_overlay(
        &dir.join("start.png"),
        &problem.scene.target,
        &ws.mask,
        &format!("{name}: the start guess at t, before any solve"),
    )?;
    println!(
        "{}: {} objects; start guess IoU {:.4}{}; wrote {}/{{scene.json, target.png, start.png}}; next: bsa solve {}",
        name,
        layout.len(),
        start.iou,
        if start.outcome.n_contacts > 0 {
            format!(" (with a contact at {:.3} s)", start.outcome.t_sim)
        } else {
            String::new()
        },
        dir.display(),
        dir.display()
    );
    Ok(())
}
