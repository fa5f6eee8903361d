//! `bsa video`: render the film of the .blend that `bsa blend` writes (built first with
//! the same options, unless `--blend` names a file to render as it is) with
//! `blender/render_video.py`: an MP4 from the view camera and a contact sheet of four
//! stills (launch, mid-flight, `t`, after) beside it.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::output::blend::BlendOptions;
use crate::output::{files, picture};

use super::{blend, blender, VideoArgs};

/// `--fps`'s default (`VideoArgs`).
pub(super) const DEFAULT_FPS: u32 = 24;
/// The view camera's default render size.
const DEFAULT_RESOLUTION: [u32; 2] = [1920, 1080];
/// The widest contact sheet (pixels).
const SHEET_MAX_WIDTH: u32 = 1920;

/// The validated options of `bsa video`.
pub(super) struct Options {
    dir: PathBuf,
    /// `None`: `<stem of the .blend>.mp4` beside it.
    out: Option<PathBuf>,
    /// Render this .blend as it is, instead of building one.
    blend_file: Option<PathBuf>,
    build: BlendOptions,
    /// Given on the command line (else the .blend's own).
    resolution: Option<[u32; 2]>,
    /// At least 1.
    samples: u32,
    denoise: bool,
    /// Finite and positive when given.
    seconds: Option<f64>,
    sheet_only: bool,
    python: Option<PathBuf>,
}

impl Options {
    pub(super) fn new(args: VideoArgs) -> Result<Options> {
        if args.samples == 0 {
            bail!("--samples must be at least 1");
        }
        blend::check_fps(args.fps)?;
        let resolution = match &args.resolution {
            Some(r) => {
                let [w, h] = blend::parse_resolution(r, "--resolution")?;
                if w % 2 != 0 || h % 2 != 0 {
                    bail!("--resolution {r}: H.264 needs an even width and height");
                }
                Some([w, h])
            }
            None => None,
        };
        if let Some(s) = args.seconds {
            if !(s.is_finite() && s > 0.0) {
                bail!("--seconds must be positive, got {s}");
            }
        }
        if let Some(b) = &args.blend {
            if !b.is_file() {
                bail!(
                    "--blend {}: no such file (write one with `bsa blend`)",
                    b.display()
                );
            }
            // These options build the .blend; a given one is rendered as it is.
            let building = [
                (args.fps != DEFAULT_FPS, "--fps"),
                (args.slowmo, "--slowmo"),
                (args.curves, "--curves"),
            ];
            if let Some((_, flag)) = building.iter().find(|b| b.0) {
                bail!(
                    "{flag} builds the .blend, and --blend {} is rendered as it is: give one or the other (`bsa blend {flag} ...` writes a .blend with it)",
                    b.display()
                );
            }
        }
        if let Some(out) = &args.out {
            blend::check_out(out, "mp4", "--out")?;
        }
        Ok(Options {
            dir: args.dir,
            out: args.out,
            blend_file: args.blend,
            build: BlendOptions {
                fps: args.fps,
                resolution: resolution.unwrap_or(DEFAULT_RESOLUTION),
                slow_motion: args.slowmo,
                curves: args.curves,
            },
            resolution,
            samples: args.samples,
            denoise: args.denoise,
            seconds: args.seconds,
            sheet_only: args.sheet_only,
            python: args.python,
        })
    }
}

/// Build the .blend (unless given), render it and lay out the contact sheet.
pub(super) fn run(opts: &Options) -> Result<()> {
    let blend_path = match &opts.blend_file {
        Some(b) => b.clone(),
        None => {
            let built = blend::build(&blend::Options {
                dir: opts.dir.clone(),
                scene: None,
                out: None,
                blend: opts.build.clone(),
                python: opts.python.clone(),
            })?;
            println!("{}", blend::describe(&built));
            built.blend
        }
    };
    let stem = blend_path
        .file_stem()
        .map_or("film".into(), |s| s.to_string_lossy().into_owned());
    let folder = blend_path
        .parent()
        .map_or(opts.dir.clone(), Path::to_path_buf);
    let mp4 = opts
        .out
        .clone()
        .unwrap_or_else(|| folder.join(format!("{stem}.mp4")));
    let sheet_path = mp4.with_file_name(format!(
        "{}_contact_sheet.png",
        mp4.file_stem()
            .map_or(stem.clone(), |s| s.to_string_lossy().into_owned())
    ));
    let stills = Stills::new()?;
    let python = blender::python(opts.python.clone())?;
    let script = blender::script("render_video.py")?;
    let mut args = vec![
        "--blend".to_string(),
        blend_path.display().to_string(),
        "--samples".into(),
        opts.samples.to_string(),
        "--stills".into(),
        stills.0.display().to_string(),
    ];
    if opts.sheet_only {
        args.push("--no-video".into());
    } else {
        args.extend(["--out".into(), mp4.display().to_string()]);
    }
    if let Some([w, h]) = opts.resolution {
        args.extend(["--resolution".into(), format!("{w}x{h}")]);
    }
    if let Some(s) = opts.seconds {
        args.extend(["--seconds".into(), s.to_string()]);
    }
    if opts.denoise {
        args.push("--denoise".into());
    }
    let result = blender::run(&python, &script, &args)?;
    let sheet = contact_sheet(&result, &stem)?;
    files::save_png(&sheet, &sheet_path)?;
    if !opts.sheet_only {
        println!(
            "wrote {}: frames {} at {} fps, {}x{}, {} samples, rendered in {} s",
            mp4.display(),
            result["frames"],
            result["fps"],
            result["width"],
            result["height"],
            result["samples"],
            result["render_seconds"]
        );
    }
    println!(
        "wrote {} (launch, mid-flight, t, after)",
        sheet_path.display()
    );
    Ok(())
}

/// The contact sheet of the stills the script rendered.
fn contact_sheet(result: &serde_json::Value, name: &str) -> Result<image::RgbImage> {
    let Some(list) = result["stills"].as_array().filter(|l| !l.is_empty()) else {
        bail!("render_video.py rendered no still for the contact sheet");
    };
    let mut stills = Vec::with_capacity(list.len());
    for s in list {
        let png = s["png"].as_str().unwrap_or_default();
        let img = image::open(png)
            .with_context(|| format!("cannot read the still {png}"))?
            .to_rgb8();
        let label = format!(
            "frame {}: {}",
            s["frame"],
            s["label"].as_str().unwrap_or_default()
        );
        stills.push((img, label));
    }
    let title = format!(
        "{name}: {} fps, t on frame {}, {} samples",
        result["fps"].as_f64().unwrap_or(0.0),
        result["t_frame"],
        result["samples"]
    );
    Ok(picture::sheet::contact_sheet(
        &stills,
        &title,
        SHEET_MAX_WIDTH,
    )?)
}

/// A temporary folder for the stills, removed when dropped.
struct Stills(PathBuf);

impl Stills {
    fn new() -> Result<Stills> {
        let d = std::env::temp_dir().join(format!("bsa-stills-{}", std::process::id()));
        std::fs::create_dir_all(&d).with_context(|| format!("cannot create {}", d.display()))?;
        Ok(Stills(d))
    }
}

impl Drop for Stills {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
