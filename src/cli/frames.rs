//! The pictures and tables of a scene with several instants (`targets`, `hold`), shared
//! by `solve`, `render` and `eval`: the IoU at every frame, an overlay per picture and
//! one of the hold window's worst frame; and the shadows that reach beyond the picture.

use std::path::Path;

use anyhow::Result;

use crate::evaluate::{FrameIou, Problem, Workspace};
use crate::output::files;

/// The names of the occluders whose shadows reach beyond the picture, for the poses of
/// the last evaluation on `ws` (`solve`'s note, `eval`'s line).
pub(super) fn outside_names(problem: &Problem, ws: &Workspace) -> Vec<String> {
    problem
        .shadows_in_image(ws)
        .iter()
        .zip(&problem.scene.occluders)
        .filter(|(inside, _)| !**inside)
        .map(|(_, o)| o.name.clone())
        .collect()
}

/// The frame with the lowest IoU (the first of equals).
pub(super) fn worst(frames: &[FrameIou]) -> Option<FrameIou> {
    frames
        .iter()
        .copied()
        .reduce(|a, b| if b.iou < a.iou { b } else { a })
}

/// Write, for a scene with several pictures, `shadow_<k>.png` and `overlay_<k>.png` at
/// every picture's instant (`k` from 1), and with `hold` `overlay_worst.png` at the
/// window's worst frame; `ws` must hold the flight of `params` ([`Problem::fly`]).
/// Returns the names of the files written.
pub(super) fn write_pictures(
    dir: &Path,
    problem: &Problem,
    frames: &[FrameIou],
    ws: &mut Workspace,
) -> Result<Vec<String>> {
    let scene = &problem.scene;
    let mut written = Vec::new();
    if scene.pictures.len() > 1 {
        for (k, pic) in scene.pictures.iter().enumerate() {
            problem.shadow_at(pic.t, ws);
            let picture = problem.picture_of(&ws.mask);
            let img =
                crate::output::picture::mask_image(picture.width(), picture.height(), &|x, y| {
                    picture.get(x, y)
                });
            let (shadow, overlay) = (
                format!("shadow_{}.png", k + 1),
                format!("overlay_{}.png", k + 1),
            );
            files::save_png(&img, &dir.join(&shadow))?;
            let title = format!("{}: picture {} at t = {} s", scene.name, k + 1, pic.t);
            files::save_overlay(&dir.join(&overlay), &pic.target, &picture, &title)?;
            written.extend([shadow, overlay]);
        }
    }
    if let (Some(hold), Some(w)) = (&scene.hold, worst(frames)) {
        problem.shadow_at(w.t, ws);
        let pic = &scene.pictures[w.picture];
        let title = format!(
            "{}: worst frame, t {:+.3} s (+-{} s)",
            scene.name,
            w.t - pic.t,
            hold.window
        );
        files::save_overlay(
            &dir.join("overlay_worst.png"),
            &pic.target,
            &problem.picture_of(&ws.mask),
            &title,
        )?;
        written.push("overlay_worst.png".into());
    }
    Ok(written)
}

/// Print the IoU at every frame, a line per picture: its instant, the worst frame and
/// each frame's IoU.
pub(super) fn print(problem: &Problem, frames: &[FrameIou]) {
    let scene = &problem.scene;
    for (k, pic) in scene.pictures.iter().enumerate() {
        let mine: Vec<&FrameIou> = frames.iter().filter(|f| f.picture == k).collect();
        let Some(w) = worst(&mine.iter().map(|f| **f).collect::<Vec<_>>()) else {
            continue;
        };
        let at_t = mine
            .iter()
            .find(|f| f.t == pic.t)
            .map_or(f64::NAN, |f| f.iou);
        match &scene.hold {
            None => println!("  picture {} at t = {} s: IoU {:.4}", k + 1, pic.t, at_t),
            Some(h) => {
                println!(
                    "  picture {} at t = {} s: IoU {:.4}; hold +-{} s, {} frames at {} fps: worst IoU {:.4} at t {:+.4} s",
                    k + 1,
                    pic.t,
                    at_t,
                    h.window,
                    mine.len(),
                    h.fps,
                    w.iou,
                    w.t - pic.t
                );
                let list: Vec<String> = mine.iter().map(|f| format!("{:.3}", f.iou)).collect();
                println!("    IoU per frame: {}", list.join(" "));
            }
        }
    }
}
