//! Helpers shared by the integration tests: running the `bsa` binary, fresh temporary
//! folders, variants of the Mickey scene, quick solves through the command line, and the
//! check that a tool an ignored test needs is installed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex, OnceLock};

/// The repository root, where the tests run `bsa`.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs the `bsa` binary from the repository root: (success, stdout, stderr).
pub fn bsa(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_bsa"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run bsa");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `bsa solve SCENE --out OUT -q EXTRA...`, which must succeed; its stdout.
pub fn solve(scene: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "solve",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    let (ok, stdout, err) = bsa(&args);
    assert!(ok, "{err}");
    stdout
}

/// The JSON file at `path`, which must exist and parse.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A fresh, empty folder under the system's temporary folder, named after the test.
pub fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bsa-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn mickey_json() -> serde_json::Value {
    let text = std::fs::read_to_string(root().join("scenes/mickey/scene.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Write a variant of the Mickey scene into a fresh folder (with the real target).
pub fn variant(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    let d = tmpdir(name);
    std::fs::copy(
        root().join("scenes/mickey/target.png"),
        d.join("target.png"),
    )
    .unwrap();
    let mut v = mickey_json();
    edit(&mut v);
    std::fs::write(
        d.join("scene.json"),
        serde_json::to_string_pretty(&v).unwrap(),
    )
    .unwrap();
    d
}

/// Every folder of `scenes/` that holds a scene.json.
pub fn example_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("scene.json").is_file())
        .collect();
    v.sort();
    assert!(!v.is_empty());
    v
}

/// Solve a scene quickly (few iterations, one round) into a fresh folder with the CLI,
/// which also writes the .glb and the CSV tables.
pub fn quick_solve(scene: &Path, name: &str) -> PathBuf {
    let d = tmpdir(name);
    let text = std::fs::read_to_string(scene.join("scene.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    // Keep the scene's own files reachable: absolute target, meshes and hints paths.
    let abs = |p: &serde_json::Value| {
        serde_json::Value::from(scene.join(p.as_str().unwrap()).display().to_string())
    };
    if v.get("target").is_some() {
        v["target"] = abs(&v["target"]);
    }
    if let Some(h) = v.get("hints").filter(|h| h.is_string()).cloned() {
        v["hints"] = abs(&h);
    }
    // A sequence: every picture's target.
    for p in v
        .get_mut("targets")
        .and_then(|t| t.as_array_mut())
        .into_iter()
        .flatten()
    {
        p["target"] = abs(&p["target"]);
    }
    for o in v["occluders"].as_array_mut().unwrap() {
        if let Some(obj) = o["shape"].get("mesh").map(|m| m["obj"].clone()) {
            o["shape"]["mesh"]["obj"] = abs(&obj);
        }
    }
    if let Some(stages) = v.get_mut("stages").and_then(|s| s.as_array_mut()) {
        for s in stages {
            s["max_iterations"] = 4.into();
        }
    }
    if let Some(st) = v.get_mut("strategy").filter(|s| s["kind"] == "sequential") {
        st["rounds"] = 1.into();
        for k in ["stage", "final"] {
            if st.get(k).is_some() {
                st[k]["max_iterations"] = 4.into();
            }
        }
    }
    std::fs::write(d.join("scene.json"), serde_json::to_string(&v).unwrap()).unwrap();
    let out = d.join("out");
    solve(&d, &out, &[]);
    out
}

/// Panics, saying how to install it, when a tool that an ignored test needs is missing:
/// an ignored test that is run runs for real or fails, it never passes without checking.
pub fn require(path: &Path, install: &str) {
    assert!(
        path.exists(),
        "{} is missing: {install} (scripts/test.sh does it)",
        path.display()
    );
}

/// `make()`'s folder, made once per test process under `key` and shared by the tests
/// that ask for it (they only add files of their own to it).
fn shared(key: String, make: impl FnOnce() -> PathBuf) -> PathBuf {
    type Cells = BTreeMap<String, Arc<OnceLock<PathBuf>>>;
    static CELLS: Mutex<Cells> = Mutex::new(BTreeMap::new());
    let cell = CELLS.lock().unwrap().entry(key).or_default().clone();
    cell.get_or_init(make).clone()
}

/// [`quick_solve`] of the example `scenes/<name>`, once per test process.
pub fn shared_quick_solve(name: &str) -> PathBuf {
    shared(format!("quick-{name}"), || {
        quick_solve(
            &root().join("scenes").join(name),
            &format!("shared-quick-{name}"),
        )
    })
}

/// The full solve of the example `scenes/<name>` (its own stages, as the README's
/// command), once per test process: the pictures the examples really make.
pub fn shared_full_solve(name: &str) -> PathBuf {
    shared(format!("full-{name}"), || {
        let out = tmpdir(&format!("shared-full-{name}")).join("out");
        solve(Path::new(&format!("scenes/{name}")), &out, &[]);
        out
    })
}

/// Runs `blender/<script> -- <args>` with the bpy venv (which it requires) and returns
/// the JSON of its `BSA_RESULT` line, refusing a reported error.
pub fn blender_script(script: &str, args: &[&str]) -> serde_json::Value {
    let python = root().join(".venv-blender/bin/python");
    require(&python, "bash blender/setup_venv.sh");
    let o = Command::new(python)
        .arg(root().join("blender").join(script))
        .arg("--")
        .args(args)
        .output()
        .expect("the bpy virtualenv (bash blender/setup_venv.sh)");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("BSA_RESULT "))
        .unwrap_or_else(|| panic!("{script}: {}", String::from_utf8_lossy(&o.stderr)));
    let v: serde_json::Value = serde_json::from_str(line).unwrap();
    assert!(v.get("error").is_none(), "{script}: {v}");
    v
}

/// The time of the last key of an output folder's trajectory.csv (s): the end of the
/// animation, every body at rest.
pub fn last_key_time(dir: &Path) -> f64 {
    let traj = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let last = traj.lines().last().unwrap();
    last.split(',').next().unwrap().parse().unwrap()
}
