//! `bsa validate`: render the shadow at `t` with Blender Cycles and compare it with the
//! rasterizer's ([`crate::output::cycles`]); writes `cycles_mask.png`,
//! `validate_diff.png` and `validate.json` into the solution folder.

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::output::{cycles, files};

use super::{blender, load, ValidateArgs};

/// The validated options of `bsa validate`.
pub(super) struct Options {
    dir: PathBuf,
    scene: Option<PathBuf>,
    python: Option<PathBuf>,
}

impl Options {
    /// `validate` has no option values to check: the folder and the interpreter are
    /// checked when they are used.
    pub(super) fn new(args: ValidateArgs) -> Options {
        Options {
            dir: args.dir,
            scene: args.scene,
            python: args.python,
        }
    }
}

/// Render with Cycles, compare, write the results and print a summary.
pub(super) fn run(opts: &Options) -> Result<()> {
    let dir = &opts.dir;
    let (problem, solution) = load::solution_dir(dir, opts.scene.as_deref())?;
    let glb = load::glb(dir, &problem)?;
    let python = blender::python(opts.python.clone())?;
    let script = blender::script("render_shadow.py")?;
    let mask_path = dir.join("cycles_mask.png");
    let result = blender::run(
        &python,
        &script,
        &[
            "--glb".into(),
            glb.display().to_string(),
            "--out".into(),
            mask_path.display().to_string(),
        ],
    )?;
    let img = image::open(&mask_path)
        .with_context(|| format!("cannot read the Cycles mask {}", mask_path.display()))?
        .to_luma8();
    let mask = cycles::cycles_mask(&img, &problem.scene.target)?;
    let c = cycles::compare(&problem, &solution.parameters(), &mask);
    let diff_path = dir.join("validate_diff.png");
    files::save_png(&c.difference, &diff_path)?;
    let report = c.report(&problem.scene.name, &mask_path, &diff_path, result);
    files::write_atomic(
        &dir.join("validate.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    println!(
        "{}: Cycles vs rasterizer at t: IoU {:.5}, {} XOR pixels ({} vs {} shadow pixels); difference image {} (black both, red Cycles only, blue rasterizer only)",
        problem.scene.name,
        c.iou,
        c.xor_pixels,
        c.cycles_shadow_pixels,
        c.rasterizer_shadow_pixels,
        diff_path.display()
    );
    Ok(())
}
