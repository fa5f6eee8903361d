//! `bsa video`: render an MP4 of the flight with Blender (`blender/render_video.py`)
//! from the scene's perspective camera.

use std::path::PathBuf;

use anyhow::{bail, Result};

use super::{blender, load, VideoArgs};

/// The smallest frame side accepted, in pixels.
const MIN_SIDE: u32 = 16;

/// The validated options of `bsa video`.
pub(super) struct Options {
    dir: PathBuf,
    /// `None`: `DIR/<scene>.mp4`, known once the scene is loaded.
    out: Option<PathBuf>,
    /// At least 1.
    samples: u32,
    /// At least [`MIN_SIDE`] each.
    width: u32,
    height: u32,
    /// Finite and positive when given.
    seconds: Option<f64>,
    python: Option<PathBuf>,
}

impl Options {
    pub(super) fn new(args: VideoArgs) -> Result<Options> {
        if args.samples == 0 || args.width < MIN_SIDE || args.height < MIN_SIDE {
            bail!(
                "--samples must be at least 1 and the frame at least {MIN_SIDE}x{MIN_SIDE} pixels"
            );
        }
        if let Some(s) = args.seconds {
            if !(s.is_finite() && s > 0.0) {
                bail!("--seconds must be positive, got {s}");
            }
        }
        Ok(Options {
            dir: args.dir,
            out: args.out,
            samples: args.samples,
            width: args.width,
            height: args.height,
            seconds: args.seconds,
            python: args.python,
        })
    }
}

/// Render the video and print where it went, with the script's report.
pub(super) fn run(opts: &Options) -> Result<()> {
    let dir = &opts.dir;
    let (problem, _) = load::solution_dir(dir, None)?;
    let glb = load::glb(dir, &problem)?;
    let python = blender::python(opts.python.clone())?;
    let script = blender::script("render_video.py")?;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| dir.join(format!("{}.mp4", problem.scene.name)));
    let mut args = vec![
        "--glb".to_string(),
        glb.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--samples".into(),
        opts.samples.to_string(),
        "--width".into(),
        opts.width.to_string(),
        "--height".into(),
        opts.height.to_string(),
    ];
    if let Some(s) = opts.seconds {
        args.extend(["--seconds".into(), s.to_string()]);
    }
    let result = blender::run(&python, &script, &args)?;
    println!("wrote {} ({})", out.display(), result);
    Ok(())
}
