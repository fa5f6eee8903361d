//! `bsa export`: the animated glTF (`<scene>.glb`), `launch.csv` and `trajectory.csv` of
//! a saved solution. [`write_exports`] is also the last step of `bsa solve`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::evaluate::Problem;
use crate::output::files;
use crate::output::solution::Solution;
use crate::scene::{MAX_KEYS, MAX_T};

use super::{load, ExportArgs};

/// The validated options of `bsa export`.
pub(super) struct Options {
    dir: PathBuf,
    scene: Option<PathBuf>,
    /// Seconds of rapier continuation after `t`: finite and not negative.
    after: f64,
}

impl Options {
    pub(super) fn new(args: ExportArgs) -> Result<Options> {
        let after = args.after;
        if !(after.is_finite() && (0.0..=MAX_T).contains(&after)) {
            bail!("--after must be a number of seconds from 0 to {MAX_T}, got {after}");
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
    let msg = write_exports(&opts.dir, &problem, &solution, opts.after)?;
    println!("{msg}");
    Ok(())
}

/// `<scene>.glb`, `launch.csv` and `trajectory.csv`; returns a one-line summary.
pub(super) fn write_exports(
    dir: &Path,
    problem: &Problem,
    solution: &Solution,
    after: f64,
) -> Result<String> {
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
    files::write_atomic(&dir.join(format!("{name}.glb")), &glb)?;
    files::write_csv(&dir.join("launch.csv"), &launches)?;
    files::write_csv(
        &dir.join("trajectory.csv"),
        &crate::output::trajectory::trajectory_rows(problem, &track),
    )?;
    Ok(format!(
        "wrote {}/{{{name}.glb, launch.csv, trajectory.csv}}: {} keys, t = {} s at key {}",
        dir.display(),
        track.times.len(),
        problem.scene.t,
        track.t_index
    ))
}
