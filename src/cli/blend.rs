//! `bsa blend`: a .blend ready to render. The exports are refreshed (the same files unless
//! the solution changed), [`crate::output::blend::plan`] decides frames, cameras and slow
//! motion, and Blender's Python applies the plan with `blender/make_blend.py`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::output::blend::{self, BlendOptions, Plan};
use crate::output::trajectory::DEFAULT_MAX_AFTER;

use super::{blender, export, load, BlendArgs};

/// The largest frame side accepted, in pixels (Blender's limit is far above it).
const MAX_SIDE: u32 = 16384;
/// The smallest.
pub(super) const MIN_SIDE: u32 = 16;

/// The validated options of `bsa blend`.
pub(super) struct Options {
    pub(super) dir: PathBuf,
    pub(super) scene: Option<PathBuf>,
    /// `None`: `DIR/<scene>.blend`.
    pub(super) out: Option<PathBuf>,
    pub(super) blend: BlendOptions,
    pub(super) python: Option<PathBuf>,
}

/// `WxH` as two sides within [`MIN_SIDE`]..=[`MAX_SIDE`]; `flag` names the option in errors.
pub(super) fn parse_resolution(text: &str, flag: &str) -> Result<[u32; 2]> {
    let parts: Vec<&str> = text.split(['x', 'X']).collect();
    let sides: Option<Vec<u32>> = match parts.as_slice() {
        [w, h] => w
            .trim()
            .parse()
            .ok()
            .and_then(|w| h.trim().parse().ok().map(|h| vec![w, h])),
        _ => None,
    };
    match sides.as_deref() {
        Some(&[w, h])
            if (MIN_SIDE..=MAX_SIDE).contains(&w) && (MIN_SIDE..=MAX_SIDE).contains(&h) =>
        {
            Ok([w, h])
        }
        Some(_) => bail!("{flag} {text}: each side must be {MIN_SIDE} to {MAX_SIDE} pixels"),
        None => bail!("{flag} must be WIDTHxHEIGHT in pixels (e.g. 1920x1080), got `{text}`"),
    }
}

/// `--fps`: a whole number of frames per second from 1 to 240.
pub(super) fn check_fps(fps: u32) -> Result<()> {
    if !(1..=240).contains(&fps) {
        bail!("--fps must be a whole number of frames per second from 1 to 240, got {fps}");
    }
    Ok(())
}

/// An output file of `flag`: it must end in `.ext` and must not be a folder, so that a
/// slip such as `--out DIR/solution.json` cannot put a film over a solve's files.
pub(super) fn check_out(out: &Path, ext: &str, flag: &str) -> Result<()> {
    if out.is_dir() {
        bail!(
            "{flag} {}: is a folder; give the file to write (NAME.{ext})",
            out.display()
        );
    }
    if !out.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)) {
        bail!(
            "{flag} {}: must name a .{ext} file (it would be written there)",
            out.display()
        );
    }
    Ok(())
}

impl Options {
    pub(super) fn new(args: BlendArgs) -> Result<Options> {
        check_fps(args.fps)?;
        if let Some(out) = &args.out {
            check_out(out, "blend", "--out")?;
        }
        let resolution = parse_resolution(&args.resolution, "--resolution")?;
        Ok(Options {
            dir: args.dir,
            scene: args.scene,
            out: args.out,
            blend: BlendOptions {
                fps: args.fps,
                resolution,
                slow_motion: args.slowmo,
                curves: args.curves,
            },
            python: args.python,
        })
    }
}

/// What [`build`] made.
pub(super) struct Built {
    pub(super) blend: PathBuf,
    pub(super) plan: Plan,
    /// The line about the motion after `t` (at rest when, or stopped at the cap).
    pub(super) rest: String,
}

/// Write the .blend and print what it holds.
pub(super) fn run(opts: &Options) -> Result<()> {
    let built = build(opts)?;
    println!("{}", describe(&built));
    Ok(())
}

/// Refresh the exports, plan the film and write the .blend.
pub(super) fn build(opts: &Options) -> Result<Built> {
    let (problem, solution) = load::solution_dir(&opts.dir, opts.scene.as_deref())?;
    let python = blender::python(opts.python.clone())?;
    let script = blender::script("make_blend.py")?;
    let (_, track) = export::write_exports(&opts.dir, &problem, &solution, DEFAULT_MAX_AFTER)?;
    let rest = export::rest_summary(&problem, &track, DEFAULT_MAX_AFTER);
    let glb = load::glb(&opts.dir, &problem)?;
    let plan = blend::plan(&problem, &track, &opts.blend)
        .with_context(|| format!("cannot plan the .blend of {}", opts.dir.display()))?;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| opts.dir.join(format!("{}.blend", problem.scene.name)));
    let plan_file = PlanFile::write(&plan)?;
    blender::run(
        &python,
        &script,
        &[
            "--glb".into(),
            glb.display().to_string(),
            "--plan".into(),
            plan_file.0.display().to_string(),
            "--out".into(),
            out.display().to_string(),
        ],
    )?;
    Ok(Built {
        blend: out,
        plan,
        rest,
    })
}

/// What the .blend holds, for people.
pub(super) fn describe(b: &Built) -> String {
    let p = &b.plan;
    let slow = match &p.slow_motion {
        Some(s) => format!(
            "slow motion x{:.1} from {:.3} to {:.3} s",
            s.factor, s.window_s[0], s.window_s[1]
        ),
        None => "no slow motion".into(),
    };
    format!(
        "wrote {}: {} fps, frames {} to {} (launch at frame {:.2}, marker `t` on frame {}), {}; \
         the picture (IoU >= 0.9 of its {:.4} at t) stays on screen {:.2} s; camera_view {}x{} \
         (the picture {:.0} % of the frame's height at t, seen from {:.0} degrees up), scene \
         `{}_shadow` with camera_shadow \
         at {}x{}{}\n{}",
        b.blend.display(),
        p.fps,
        p.frame_start,
        p.frame_end,
        p.launch_frame,
        p.t_frame,
        slow,
        p.readable.iou_at_t,
        p.readable.on_screen_s,
        p.resolution[0],
        p.resolution[1],
        100.0 * p.camera.picture_fraction_at_t,
        p.camera.close_elevation_deg,
        p.scene,
        p.target_size[0],
        p.target_size[1],
        if p.curves.is_empty() {
            String::new()
        } else {
            format!(", {} trajectory curves", p.curves.len())
        },
        b.rest
    )
}

/// The plan as a JSON file for the script, removed when dropped.
struct PlanFile(PathBuf);

impl PlanFile {
    fn write(plan: &Plan) -> Result<PlanFile> {
        let path = std::env::temp_dir().join(format!(
            "bsa-blend-plan-{}-{}.json",
            std::process::id(),
            plan.scene
        ));
        let file = PlanFile(path);
        write(&file.0, &serde_json::to_vec(plan)?)?;
        Ok(file)
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

impl Drop for PlanFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}
