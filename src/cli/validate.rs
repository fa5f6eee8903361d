//! `bsa validate`: render the shadow at `t` with Blender Cycles and compare it with the
//! rasterizer's ([`crate::output::cycles`]); writes `cycles_mask.png`,
//! `validate_diff.png` and `validate.json` into the solution folder. A scene with several
//! pictures is rendered at each picture's instant (`cycles_mask_<k>.png`,
//! `validate_diff_<k>.png`, one entry each in `validate.json`).

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
    let scene = &problem.scene;
    // One render per picture (a scene with several has them at several instants); the
    // files of a single picture keep their plain names.
    let several = scene.pictures.len() > 1;
    let mut reports = Vec::new();
    for (k, pic) in scene.pictures.iter().enumerate() {
        let suffix = if several {
            format!("_{}", k + 1)
        } else {
            String::new()
        };
        let mask_path = dir.join(format!("cycles_mask{suffix}.png"));
        let mut args = vec![
            "--glb".to_string(),
            glb.display().to_string(),
            "--out".into(),
            mask_path.display().to_string(),
        ];
        if several {
            args.extend(["--time".to_string(), pic.t.to_string()]);
        }
        let result = blender::run(&python, &script, &args)?;
        let img = image::open(&mask_path)
            .with_context(|| format!("cannot read the Cycles mask {}", mask_path.display()))?
            .to_luma8();
        let mask = cycles::cycles_mask(&img, &pic.target)?;
        let c = cycles::compare_at(&problem, &solution.parameters(), pic.t, &mask);
        let diff_path = dir.join(format!("validate_diff{suffix}.png"));
        files::save_png(&c.difference, &diff_path)?;
        let mut report = c.report(&scene.name, &mask_path, &diff_path, result);
        report["t_s"] = serde_json::json!(pic.t);
        reports.push(report);
        println!(
            "{}: Cycles vs rasterizer at {}: IoU {:.5}, {} XOR pixels ({} vs {} shadow pixels); difference image {} (black both, red Cycles only, blue rasterizer only)",
            scene.name,
            if several { format!("t = {} s (picture {})", pic.t, k + 1) } else { "t".into() },
            c.iou,
            c.xor_pixels,
            c.cycles_shadow_pixels,
            c.rasterizer_shadow_pixels,
            diff_path.display()
        );
    }
    let json = if several {
        serde_json::json!({ "scene": scene.name, "pictures": reports })
    } else {
        reports.remove(0)
    };
    files::write_atomic(
        &dir.join("validate.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    Ok(())
}
