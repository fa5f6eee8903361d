//! `bsa export`: the animated glTF (`<scene>.glb`), `launch.csv` and `trajectory.csv` of
//! a saved solution. [`write_exports`] is also the last step of `bsa solve`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::evaluate::Problem;
use crate::output::files;
use crate::output::solution::Solution;
use crate::output::trajectory::Track;
use crate::scene::{MAX_KEYS, MAX_T};
use crate::sim::continuation::{REST_HOLD_S, REST_SPEED_M_S};

use super::{load, ExportArgs};

/// The validated options of `bsa export`.
pub(super) struct Options {
    dir: PathBuf,
    scene: Option<PathBuf>,
    /// Longest rapier continuation after `t` (s): finite and not negative.
    after: f64,
}

impl Options {
    pub(super) fn new(args: ExportArgs) -> Result<Options> {
        let after = args.after;
        if !(after.is_finite() && (0.0..=MAX_T).contains(&after)) {
            bail!(
                "--after must be a number of seconds from 0 to {MAX_T}, got {}",
                crate::scene::short(after)
            );
        }
        Ok(Options {
            dir: args.dir,
            scene: args.scene,
            after,
        })
    }
}

/// Load the solution folder and write its exports next to the solution.
pub(super) fn run(opts: &Options) -> Result<()> {
    let (problem, solution) = load::solution_dir(&opts.dir, opts.scene.as_deref())?;
    let (msg, _) = write_exports(&opts.dir, &problem, &solution, opts.after)?;
    println!("{msg}");
    Ok(())
}

/// `<scene>.glb`, `launch.csv` and `trajectory.csv`, the continuation running until every
/// body is at rest or `after` seconds after `t`; returns a summary (a line, and a second
/// one when the cap stopped the motion) and the track. A file whose bytes would not
/// change is left alone (its modification time too).
pub(super) fn write_exports(
    dir: &Path,
    problem: &Problem,
    solution: &Solution,
    after: f64,
) -> Result<(String, Track)> {
    // The continuation stores a pose per key and body, so its key count is bounded as
    // the scene's is.
    let keys = after / problem.scene.dt;
    if keys > MAX_KEYS {
        bail!(
            "--after {after} s is {keys:.0} keys of {} s, more than the {MAX_KEYS:e} allowed; give a shorter --after",
            problem.scene.dt
        );
    }
    let params = solution.parameters();
    let track = crate::output::trajectory::track(problem, &params, after);
    let name = &problem.scene.name;
    let launches = crate::output::trajectory::launch_rows(problem, &params);
    let glb = crate::output::gltf::write_glb_with_launches(&problem.scene, &track, Some(&launches))
        .context("cannot build the glTF file")?;
    files::write_if_changed(&dir.join(format!("{name}.glb")), &glb)?;
    let path = dir.join("launch.csv");
    files::write_if_changed(&path, &files::csv_bytes(&path, &launches)?)?;
    let path = dir.join("trajectory.csv");
    let rows = crate::output::trajectory::trajectory_rows(problem, &track);
    files::write_if_changed(&path, &files::csv_bytes(&path, &rows)?)?;
    let msg = format!(
        "wrote {}/{{{name}.glb, launch.csv, trajectory.csv}}: {} keys, t = {} s at key {}; {}",
        dir.display(),
        track.times.len(),
        problem.scene.t,
        track.t_index,
        rest_summary(problem, &track, after)
    );
    Ok((msg, track))
}

/// How the motion after `t` ended, in words: at rest (when), or stopped at the cap with
/// the bodies still moving and what to do.
pub(super) fn rest_summary(problem: &Problem, track: &Track, after: f64) -> String {
    let t = problem.scene.t;
    let end = track.times.last().copied().unwrap_or(t);
    match track.rest.since {
        Some(since) if track.rest.at_rest => format!(
            "every body at rest {:.2} s after t (no point faster than {REST_SPEED_M_S} m/s for {REST_HOLD_S} s); the animation ends at {end:.2} s",
            since - t
        ),
        _ if after == 0.0 => format!("the animation ends at t, {end:.2} s (--after 0)"),
        _ => {
            let moving: Vec<String> = problem
                .scene
                .occluders
                .iter()
                .zip(&track.rest.last_speeds)
                .filter(|(_, &s)| s >= REST_SPEED_M_S)
                .map(|(o, s)| format!("{} {s:.3} m/s", o.name))
                .collect();
            if moving.is_empty() {
                // Slow enough at the cap, but not yet for the time that counts as rest.
                return format!(
                    "the motion after t stopped at the cap of --after {after} s before the bodies had been still for {REST_HOLD_S} s; the animation ends at {end:.2} s; give a longer --after to see them settle"
                );
            }
            format!(
                "the motion after t stopped at the cap of --after {after} s with {} still moving ({}): the animation ends with them in motion; give a longer --after",
                moving.len(),
                moving.join(", ")
            )
        }
    }
}
