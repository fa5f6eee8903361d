//! Running Blender: finding the Python interpreter that has `bpy`, finding a script of
//! the repository's `blender/` folder, and running it to read the JSON of its
//! `BSA_RESULT` line.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// The Python interpreter that has `bpy`: `--python`, else `$BSA_PYTHON`, else
/// `.venv-blender/bin/python` in the current folder or a parent.
pub(super) fn python(explicit: Option<PathBuf>) -> Result<PathBuf> {
    if let Some(p) = explicit.or_else(|| std::env::var_os("BSA_PYTHON").map(PathBuf::from)) {
        if !p.exists() {
            bail!("the Python interpreter {} does not exist", p.display());
        }
        return Ok(p);
    }
    let cwd = std::env::current_dir().context("cannot read the current folder")?;
    for dir in cwd.ancestors() {
        let p = dir.join(".venv-blender/bin/python");
        if p.exists() {
            return Ok(p);
        }
    }
    bail!(
        "no Python with Blender's bpy module found: run `bash blender/setup_venv.sh` (needs Python 3.11) \
         from the repository, or pass --python / set BSA_PYTHON"
    )
}

/// A script of the `blender/` folder, found next to the current folder or a parent.
pub(super) fn script(name: &str) -> Result<PathBuf> {
    let cwd = std::env::current_dir().context("cannot read the current folder")?;
    for dir in cwd.ancestors() {
        let p = dir.join("blender").join(name);
        if p.is_file() {
            return Ok(p);
        }
    }
    bail!("cannot find blender/{name}: run bsa from the repository (or a folder inside it)")
}

/// Run a Blender script and return the JSON of its `BSA_RESULT` line.
pub(super) fn run(python: &Path, script: &Path, args: &[String]) -> Result<serde_json::Value> {
    let out = std::process::Command::new(python)
        .arg(script)
        .arg("--")
        .args(args)
        .output()
        .with_context(|| format!("cannot run {}", python.display()))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The last result line counts: Blender and its add-ons may print their own lines
    // before it, and a script reports exactly once, at its end.
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("BSA_RESULT "));
    let value: Option<serde_json::Value> = match line {
        Some(l) => Some(serde_json::from_str(l).with_context(|| {
            let l: String = l.chars().take(200).collect();
            format!(
                "{} printed a result line that is not JSON under {}: BSA_RESULT {l}",
                script.display(),
                python.display()
            )
        })?),
        None => None,
    };
    match value {
        Some(v) if out.status.success() && v.get("error").is_none() => Ok(v),
        Some(v) => bail!(
            "{} failed: {}",
            script.display(),
            v.get("error").unwrap_or(&v)
        ),
        None => {
            // Without a result line the script died early: the end of its stderr is
            // what says why, and a missing `bpy` deserves a hint of its own.
            let err = String::from_utf8_lossy(&out.stderr);
            let tail: Vec<&str> = err.lines().rev().take(15).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            if err.contains("No module named 'bpy'") {
                bail!(
                    "{} has no bpy module: run `bash blender/setup_venv.sh`, or pass --python",
                    python.display()
                );
            }
            // Success without the line: the interpreter did not run the script as
            // Blender's Python does (`/bin/true`, a wrapper that swallows its output);
            // "failed (exit status: 0)" said nothing of that.
            if out.status.success() {
                let said = if tail.is_empty() {
                    String::new()
                } else {
                    format!("; its error output ends:\n{}", tail.join("\n"))
                };
                bail!(
                    "{} ended without its result line (BSA_RESULT) under the interpreter {}, which exited with status 0: \
                     pass --python (or set BSA_PYTHON) to a Python with Blender's bpy module (`bash blender/setup_venv.sh` makes .venv-blender/bin/python){said}",
                    script.display(),
                    python.display()
                );
            }
            bail!(
                "{} failed ({}):\n{}",
                script.display(),
                out.status,
                tail.join("\n")
            )
        }
    }
}
