//! Where a solve's results go, and the check that keeps two scenes' results apart.
//!
//! The output folder defaults to `export/<scene folder's name>`, not to the name inside
//! scene.json: a scene copied to a new folder keeps the original's JSON name, and must
//! not overwrite the original's results. A fresh solve into a folder that holds another
//! scene's (or another `t`'s) solution stops unless `--force`; any fresh solve removes
//! the files that describe the previous solution only (the error budget, another
//! scene's `.glb`), so that no stale file sits beside the new solution.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::output::files;
use crate::output::solution::Solution;
use crate::scene::Scene;

/// The files `bsa budget` writes beside a solution; they describe that solution's launch.
pub(super) const BUDGET_FILES: [&str; 7] = [
    "budget.md",
    "budget.json",
    "launch_drag.csv",
    "budget_hist.png",
    "budget_hist.svg",
    "budget_tolerances.png",
    "budget_tolerances.svg",
];

/// The folder a scene's results go to by default: `export/<name of the folder holding
/// scene.json>`, or `export/<scene name>` when that folder has no name (a scene file
/// at the file system's root).
pub(super) fn default_out(scene: &Scene) -> PathBuf {
    let source = std::fs::canonicalize(&scene.source).unwrap_or_else(|_| scene.source.clone());
    let folder = source
        .parent()
        .and_then(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| scene.name.clone());
    PathBuf::from("export").join(folder)
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// Why the solution in an output folder is not this scene's, or `None` when it is.
fn foreign(scene: &Scene, s: &Solution) -> Option<String> {
    if s.scene != scene.name {
        return Some(format!("scene `{}`", s.scene));
    }
    if let Some(f) = &s.scene_file {
        if !same_file(Path::new(f), &scene.source) {
            return Some(format!("scene `{}` from {f}", s.scene));
        }
    }
    if s.t != scene.t {
        return Some(format!("t = {} s (this scene has t = {} s)", s.t, scene.t));
    }
    None
}

/// Before a fresh (not resumed) solve into `out`: stop when `out` holds another scene's
/// or another `t`'s solution, unless `force`; then remove the files of the previous
/// solution that the solve does not rewrite. Returns the files removed.
pub(super) fn prepare(out: &Path, scene: &Scene, force: bool) -> Result<Vec<PathBuf>> {
    let file = out.join("solution.json");
    let mut stale: Vec<PathBuf> = Vec::new();
    if file.is_file() {
        let why = match files::read_solution(&file) {
            Ok(s) => foreign(scene, &s).map(|why| (why, Some(s.scene))),
            Err(e) => Some((format!("an unreadable solution ({e})"), None)),
        };
        if let Some((why, old_name)) = why {
            if !force {
                bail!(
                    "{} holds the results of {why}, not of this scene ({}, t = {} s); \
                     pass --out <folder> to keep both, or --force to replace them",
                    out.display(),
                    scene.source.display(),
                    scene.t
                );
            }
            if let Some(old) = old_name.filter(|n| *n != scene.name) {
                stale.push(out.join(format!("{old}.glb")));
            }
        }
    }
    stale.extend(BUDGET_FILES.iter().map(|f| out.join(f)));
    let mut removed = Vec::new();
    for f in stale.into_iter().filter(|f| f.is_file()) {
        std::fs::remove_file(&f)
            .map_err(|e| anyhow::anyhow!("cannot remove the stale {}: {e}", f.display()))?;
        removed.push(f);
    }
    Ok(removed)
}
