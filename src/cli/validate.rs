//! `bsa validate`: render the shadow at `t` with Blender Cycles and compare it with the
//! rasterizer's ([`crate::output::cycles`]); writes `cycles_mask.png`,
//! `validate_diff.png` and `validate.json` into the solution folder. A scene with several
//! pictures is rendered at each picture's instant (`cycles_mask_<k>.png`,
//! `validate_diff_<k>.png`, one entry each in `validate.json`). It is a check: below
//! `--min-iou` (at any picture) it ends with an error, after writing all of that.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::output::{cycles, files};
use crate::scene::short;

use super::{blender, load, ValidateArgs};

/// The least IoU of Cycles' shadow and the rasterizer's that `validate` accepts unless
/// `--min-iou` says otherwise. Cycles reproduces the shadows to a few pixels (IoU 0.9995
/// or more on the examples, docs/results.md: the rim of Blender's polygon spheres), so
/// 0.99 passes them with room and fails a .glb of another scene or launch.
pub(super) const DEFAULT_MIN_IOU: f64 = 0.99;

/// The validated options of `bsa validate`.
pub(super) struct Options {
    dir: PathBuf,
    scene: Option<PathBuf>,
    python: Option<PathBuf>,
    /// From 0 to 1.
    min_iou: f64,
}

impl Options {
    /// Checks `--min-iou`; the folder and the interpreter are checked when they are used.
    pub(super) fn new(args: ValidateArgs) -> Result<Options> {
        let min_iou = args.min_iou;
        if !(min_iou.is_finite() && (0.0..=1.0).contains(&min_iou)) {
            bail!(
                "--min-iou must be an IoU from 0 to 1, got {}",
                short(min_iou)
            );
        }
        Ok(Options {
            dir: args.dir,
            scene: args.scene,
            python: args.python,
            min_iou,
        })
    }
}

/// How well Cycles and the rasterizer agree at one picture's instant.
struct Agreement {
    /// The instant, for the message: `t`, or `t = 1 s (picture 2)`.
    at: String,
    iou: f64,
    /// The difference image written for it.
    diff: PathBuf,
}

/// The verdict of `validate`: an error naming each picture whose IoU is below `min_iou`
/// (a NaN counts as below), the IoU and the threshold.
fn check_agreement(agreements: &[Agreement], min_iou: f64) -> Result<()> {
    let below: Vec<String> = agreements
        .iter()
        .filter(|a| a.iou.is_nan() || a.iou < min_iou)
        .map(|a| {
            // Five decimals as the summary line prints, unless they round up to the
            // threshold: 0.989996 must not read 0.99000 next to --min-iou 0.99.
            let mut iou = format!("{:.5}", a.iou);
            if iou.parse::<f64>().is_ok_and(|x| x >= min_iou) {
                iou = a.iou.to_string();
            }
            format!(
                "IoU {iou} at {} (difference image {})",
                a.at,
                a.diff.display()
            )
        })
        .collect();
    if below.is_empty() {
        return Ok(());
    }
    bail!(
        "Cycles and the rasterizer disagree: {}, below --min-iou {} (red: Cycles' shadow only, blue: the rasterizer's only; is the .glb this solution's? `bsa export` writes it again)",
        below.join("; "),
        short(min_iou)
    )
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
    let mut agreements = Vec::new();
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
        let at = if several {
            format!("t = {} s (picture {})", pic.t, k + 1)
        } else {
            "t".into()
        };
        println!(
            "{}: Cycles vs rasterizer at {at}: IoU {:.5}, {} XOR pixels ({} vs {} shadow pixels); difference image {} (black both, red Cycles only, blue rasterizer only)",
            scene.name,
            c.iou,
            c.xor_pixels,
            c.cycles_shadow_pixels,
            c.rasterizer_shadow_pixels,
            diff_path.display()
        );
        agreements.push(Agreement {
            at,
            iou: c.iou,
            diff: diff_path,
        });
    }
    let mut json = if several {
        serde_json::json!({ "scene": scene.name, "pictures": reports })
    } else {
        reports.remove(0)
    };
    json["min_iou"] = serde_json::json!(opts.min_iou);
    // The report and the pictures are written whatever the verdict, so that a failed
    // check can be looked at.
    files::write_atomic(
        &dir.join("validate.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    check_agreement(&agreements, opts.min_iou)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(iou: f64) -> Agreement {
        Agreement {
            at: "t".into(),
            iou,
            diff: PathBuf::from("out/validate_diff.png"),
        }
    }

    #[test]
    fn agreement_below_the_threshold_is_an_error_naming_the_iou_and_the_threshold() {
        // A .glb of another scene: no shadow pixel in common.
        let msg = check_agreement(&[at(0.0)], DEFAULT_MIN_IOU)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("IoU 0.00000 at t") && msg.contains("below --min-iou 0.99"),
            "{msg}"
        );
        assert!(msg.contains("out/validate_diff.png"), "{msg}");
        // Just below the threshold reads below it.
        let msg = check_agreement(&[at(0.989996)], 0.99)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("IoU 0.989996 at t"), "{msg}");
        // The examples' agreement passes, and so does the threshold itself.
        check_agreement(&[at(0.99958)], DEFAULT_MIN_IOU).unwrap();
        check_agreement(&[at(0.99)], 0.99).unwrap();
        check_agreement(&[at(0.0)], 0.0).unwrap();
        // A NaN never passes.
        assert!(check_agreement(&[at(f64::NAN)], 0.0).is_err());
        // Of several pictures, only those below are named.
        let pictures = [
            Agreement {
                at: "t = 0.6 s (picture 1)".into(),
                ..at(1.0)
            },
            Agreement {
                at: "t = 1 s (picture 2)".into(),
                ..at(0.5)
            },
        ];
        let msg = check_agreement(&pictures, 0.99).unwrap_err().to_string();
        assert!(
            msg.contains("IoU 0.50000 at t = 1 s (picture 2)") && !msg.contains("picture 1"),
            "{msg}"
        );
    }
}
