//! Loading the inputs of the subcommands: a scene, a solve's output folder (its
//! `solution.json` and the scene it was made for) and the folder's `<scene>.glb`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::evaluate::Problem;
use crate::output::files;
use crate::output::solution::Solution;
use crate::scene::{self, Scene};

/// Load and validate a scene folder or file.
pub(super) fn scene(path: &Path) -> Result<Scene> {
    // A scene error already names the file and the field; a context line above it
    // would push them off the first line of the message.
    Ok(scene::load(path)?)
}

/// The problem a saved solution is evaluated in: its scene with the bodies at the
/// solution's launch positions (a solve with free positions moved them), flown through
/// the solution's air (`bsa solve --air`).
pub(super) fn problem_for(mut scene: Scene, solution: &Solution) -> Problem {
    solution.place(&mut scene);
    let mut problem = Problem::new(scene);
    if let Some(air) = solution.air {
        problem.set_air(air);
    }
    problem
}

/// Load `DIR/solution.json` and its scene, and check that they belong together: the
/// names, counts and `t`, and the same shadow when re-evaluated (as budget checks), so
/// that export, validate and video refuse a solution of an edited scene.
pub(super) fn solution_dir(dir: &Path, scene: Option<&Path>) -> Result<(Problem, Solution)> {
    let file = dir.join("solution.json");
    let (problem, solution, scene_path) = solution_and_scene(dir, &file, scene)?;
    crate::budget::check_solution_current(&problem, &solution).with_context(|| {
        format!(
            "{} does not belong to the scene {} (pass the right one with --scene)",
            file.display(),
            scene_path.display()
        )
    })?;
    Ok((problem, solution))
}

/// Read the solution `file` (in the output folder `dir`) and load its scene: `scene` if
/// given, else the scene file it records, else `scenes/<its scene name>`. Does not check
/// that they belong together (the callers check in their own ways).
pub(super) fn solution_and_scene(
    dir: &Path,
    file: &Path,
    scene: Option<&Path>,
) -> Result<(Problem, Solution, PathBuf)> {
    if dir.is_file() {
        // The solution file itself where its folder was asked for.
        let folder = dir.parent().filter(|p| !p.as_os_str().is_empty());
        bail!(
            "{} is a file: give the solve's output folder ({})",
            dir.display(),
            folder.map_or(".".into(), |p| p.display().to_string())
        );
    }
    solution_file_found(dir, file, std::fs::metadata(file).map(|m| m.is_file()))?;
    let solution = files::read_solution(file)?;
    let scene_path = match scene {
        Some(p) => p.to_path_buf(),
        None => solution
            .scene_file
            .as_ref()
            .map(PathBuf::from)
            .filter(|p| p.exists())
            .unwrap_or_else(|| PathBuf::from("scenes").join(&solution.scene)),
    };
    let loaded = self::scene(&scene_path);
    let loaded = match (&loaded, scene, &solution.scene_file) {
        // The recorded scene file was gone and `scenes/<name>` was tried instead: say
        // so, with both paths and the way out.
        (Err(_), None, Some(recorded)) if !Path::new(recorded).exists() => loaded.with_context(|| {
            format!(
                "{} names the scene {recorded}, which does not exist, and {} could not stand in for it: put the scene back there, or pass it with --scene",
                file.display(),
                scene_path.display()
            )
        }),
        // The recorded scene file is there but is no scene: the scene's error alone
        // would not say why that file was read.
        (Err(_), None, Some(recorded)) => loaded.with_context(|| {
            format!(
                "{} names the scene {recorded}, which cannot be loaded: fix it, or pass the scene with --scene",
                file.display(),
            )
        }),
        _ => loaded,
    };
    let problem = problem_for(loaded?, &solution);
    Ok((problem, solution, scene_path))
}

/// Whether the solution `file` of the output folder `dir` is there to read, from what the
/// file system says of it (`Ok(is a file)`, or the error of looking): a missing file is
/// a folder that was never solved; a file that cannot be looked at (permission denied,
/// an I/O error) is named as unreadable, with the OS reason.
fn solution_file_found(dir: &Path, file: &Path, found: std::io::Result<bool>) -> Result<()> {
    match found {
        Ok(true) => Ok(()),
        Ok(false) => bail!(
            "{} has no solution.json ({} is not a file): run `bsa solve <scene> --out {}` first",
            dir.display(),
            file.display(),
            dir.display()
        ),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
            "{} has no solution.json: run `bsa solve <scene> --out {}` first",
            dir.display(),
            dir.display()
        ),
        Err(e) => bail!("cannot read {}: {e}", file.display()),
    }
}

/// The `<scene>.glb` of the output folder `dir`, checked to be a glTF file written by
/// `bsa export` (Blender would otherwise fail on it with a far less helpful message).
pub(super) fn glb(dir: &Path, problem: &Problem) -> Result<PathBuf> {
    let glb = dir.join(format!("{}.glb", problem.scene.name));
    if !glb.is_file() {
        bail!(
            "{} does not exist: run `bsa export {}` first",
            glb.display(),
            dir.display()
        );
    }
    crate::output::gltf::read_poses_at(
        &std::fs::read(&glb).with_context(|| format!("cannot read {}", glb.display()))?,
        0.0,
    )
    .with_context(|| {
        format!(
            "{} is not a valid glTF file from bsa: run `bsa export {}` again",
            glb.display(),
            dir.display()
        )
    })?;
    Ok(glb)
}

#[cfg(test)]
mod tests {
    use std::io::{Error, ErrorKind};
    use std::path::Path;

    use super::solution_file_found;

    #[test]
    fn an_unreadable_solution_is_named_unreadable_not_missing() {
        let (dir, file) = (Path::new("out"), Path::new("out/solution.json"));
        assert!(solution_file_found(dir, file, Ok(true)).is_ok());
        let missing = solution_file_found(dir, file, Err(Error::from(ErrorKind::NotFound)))
            .unwrap_err()
            .to_string();
        assert!(
            missing.contains("out has no solution.json: run `bsa solve"),
            "{missing}"
        );
        let denied = Error::from_raw_os_error(libc::EACCES);
        assert_eq!(denied.kind(), ErrorKind::PermissionDenied);
        let reason = denied.to_string();
        let unreadable = solution_file_found(dir, file, Err(denied))
            .unwrap_err()
            .to_string();
        assert_eq!(
            unreadable,
            format!("cannot read out/solution.json: {reason}")
        );
        assert!(reason.contains("ermission denied"), "{reason}");
        let folder = solution_file_found(dir, file, Ok(false))
            .unwrap_err()
            .to_string();
        assert!(folder.contains("is not a file"), "{folder}");
    }
}
