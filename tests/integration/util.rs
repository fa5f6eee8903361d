//! Helpers shared by the integration tests: running the `bsa` binary, fresh temporary
//! folders (removed when the test passes, kept when it fails), variants of the Mickey
//! scene, quick solves through the command line, and the check that a tool an ignored
//! test needs is installed.

use std::collections::BTreeMap;
use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex, Once, OnceLock};

/// The repository root, where the tests run `bsa`.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs the `bsa` binary from the repository root: (success, stdout, stderr).
pub fn bsa(args: &[&str]) -> (bool, String, String) {
    outcome(bsa_command(args).output().expect("run bsa"))
}

/// [`bsa`] with a temporary folder of its own ([`leaving_no_temporaries`]): what it
/// renders through Blender (`validate`, `video`) leaves nothing behind.
pub fn bsa_leaving_no_temporaries(args: &[&str]) -> (bool, String, String) {
    outcome(leaving_no_temporaries(&mut bsa_command(args), args[0]).expect("run bsa"))
}

fn bsa_command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_bsa"));
    c.args(args).current_dir(root());
    c
}

/// Success, stdout and stderr of a finished command.
fn outcome(out: std::process::Output) -> (bool, String, String) {
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `cmd` with a temporary folder of its own (`TMPDIR`) and fails, naming `who`, if
/// anything is left in it when the command ends.
fn leaving_no_temporaries(cmd: &mut Command, who: &str) -> std::io::Result<std::process::Output> {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let scratch = tmpdir(&format!("tmp-{who}-{call}"));
    let out = cmd.env("TMPDIR", &*scratch).output()?;
    let left: Vec<_> = std::fs::read_dir(&*scratch)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "{who} left {left:?} in its TMPDIR");
    Ok(out)
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

/// The number (or other value) that follows `marker` in `text`, up to the next space.
pub fn value_after<T: std::str::FromStr>(text: &str, marker: &str) -> Option<T> {
    text.split(marker).nth(1)?.split(' ').next()?.parse().ok()
}

/// The JSON file at `path`, which must exist and parse.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A test's temporary folder, which derefs to a path in it (the folder itself, or a
/// child of it after [`TempDir::into_child`]). Dropped after the test passed it removes
/// the whole folder; dropped while the test panics it keeps it and prints its path, so
/// that what the failed test left can be looked at. Every test run left ~100 MB behind
/// when the folders were never removed.
///
/// Keep the guard for as long as the folder is used: `tmpdir(name).join("x")` drops it
/// (and removes the folder) at the end of the statement.
#[must_use = "dropping the guard removes the folder"]
pub struct TempDir {
    /// The folder removed on drop.
    root: PathBuf,
    /// The path the guard stands for: `root` or a path inside it.
    path: PathBuf,
}

impl TempDir {
    /// The same guard standing for `name` inside the path it stood for (not created): a
    /// helper can return its output folder and keep the whole folder alive with it.
    pub fn into_child(mut self, name: &str) -> TempDir {
        self.path = self.path.join(name);
        self
    }

    /// Gives up the removal on drop: (the folder, the path the guard stood for).
    fn leak(self) -> (PathBuf, PathBuf) {
        let this = std::mem::ManuallyDrop::new(self);
        (this.root.clone(), this.path.clone())
    }
}

impl Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        keep_or_remove(&self.root);
    }
}

/// Removes `root` after a test that passed; during a panic keeps it and says where.
fn keep_or_remove(root: &Path) {
    if std::thread::panicking() {
        eprintln!("kept {} for the failed test", root.display());
    } else {
        let _ = std::fs::remove_dir_all(root);
    }
}

/// A fresh, empty folder under the system's temporary folder, named after the test;
/// removed when the guard is dropped, unless the test failed.
pub fn tmpdir(name: &str) -> TempDir {
    let d = std::env::temp_dir().join(format!("bsa-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    TempDir {
        root: d.clone(),
        path: d,
    }
}

fn mickey_json() -> serde_json::Value {
    let text = std::fs::read_to_string(root().join("scenes/mickey/scene.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Write a variant of the Mickey scene into a fresh folder (with the real target).
pub fn variant(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> TempDir {
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
/// which also writes the .glb and the CSV tables: the guard of the folder, standing for
/// the solve's output folder `out` in it (beside the edited scene.json).
pub fn quick_solve(scene: &Path, name: &str) -> TempDir {
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
    solve(&d, &d.join("out"), &[]);
    d.into_child("out")
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

/// A folder made once per test process and shared by the tests that ask for it (they
/// only add files of their own to it), which derefs to the path its maker returned.
/// Each test holds one of these while it uses the folder: the folder outlives every
/// test, so it is removed when the test process exits, unless a test that held it
/// failed (that test's output then says it was kept).
pub struct SharedDir {
    root: PathBuf,
    path: PathBuf,
}

impl Deref for SharedDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for SharedDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for SharedDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept {} for the failed test", self.root.display());
            lock(&SHARED_ROOTS).retain(|r| *r != self.root);
        }
    }
}

/// The shared folders to remove when the test process exits.
static SHARED_ROOTS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The lock of `m`, also after a panic in another test poisoned it.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes the shared folders (run by the C library's `exit`, which the test harness
/// ends with whether the tests passed or not). It must not panic: a panic cannot
/// unwind out of an `extern "C"` function.
extern "C" fn remove_shared_roots() {
    for root in lock(&SHARED_ROOTS).drain(..) {
        let _ = std::fs::remove_dir_all(root);
    }
}

/// `make()`'s folder, made once per test process under `key`: see [`SharedDir`].
fn shared(key: String, make: impl FnOnce() -> TempDir) -> SharedDir {
    type Cells = BTreeMap<String, Arc<OnceLock<(PathBuf, PathBuf)>>>;
    static CELLS: Mutex<Cells> = Mutex::new(BTreeMap::new());
    static AT_EXIT: Once = Once::new();
    AT_EXIT.call_once(|| {
        // SAFETY: `atexit` only records the function, which takes no arguments, touches
        // no thread-local state and never unwinds.
        let rc = unsafe { libc::atexit(remove_shared_roots) };
        assert_eq!(rc, 0, "atexit refused the removal of the shared folders");
    });
    let cell = lock(&CELLS).entry(key).or_default().clone();
    let (root, path) = cell
        .get_or_init(|| {
            // The maker's own guard keeps the folder if the maker fails; once made, the
            // folder is the process's to remove.
            let (root, path) = make().leak();
            lock(&SHARED_ROOTS).push(root.clone());
            (root, path)
        })
        .clone();
    SharedDir { root, path }
}

/// [`quick_solve`] of the example `scenes/<name>`, once per test process.
pub fn shared_quick_solve(name: &str) -> SharedDir {
    shared(format!("quick-{name}"), || {
        quick_solve(
            &root().join("scenes").join(name),
            &format!("shared-quick-{name}"),
        )
    })
}

/// The full solve of the example `scenes/<name>` (its own stages, as the README's
/// command), once per test process: the pictures the examples really make.
pub fn shared_full_solve(name: &str) -> SharedDir {
    shared(format!("full-{name}"), || {
        let out = tmpdir(&format!("shared-full-{name}")).into_child("out");
        solve(Path::new(&format!("scenes/{name}")), &out, &[]);
        out
    })
}

/// Runs `blender/<script> -- <args>` with the bpy venv (which it requires) and returns
/// the JSON of its `BSA_RESULT` line, refusing a reported error.
///
/// The script runs with a temporary folder of its own (`TMPDIR`), which must be empty
/// when it ends: a script leaves none of its renders behind.
pub fn blender_script(script: &str, args: &[&str]) -> serde_json::Value {
    let python = root().join(".venv-blender/bin/python");
    require(&python, "bash blender/setup_venv.sh");
    let mut cmd = Command::new(python);
    cmd.arg(root().join("blender").join(script))
        .arg("--")
        .args(args);
    let o = leaving_no_temporaries(&mut cmd, script)
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

/// A test's folder is gone once its guard is dropped after a pass, child paths included;
/// a test that panics keeps it (every test run left ~100 MB behind before).
#[test]
fn temporary_folders_are_removed_after_a_pass_and_kept_after_a_failure() {
    let passed = tmpdir("guard-passed").into_child("out");
    std::fs::create_dir_all(&*passed).unwrap();
    std::fs::write(passed.join("file"), "x").unwrap();
    let root = passed.parent().unwrap().to_path_buf();
    drop(passed);
    assert!(!root.exists(), "{} was left behind", root.display());

    let failed = std::thread::spawn(|| {
        let d = tmpdir("guard-failed");
        std::fs::write(d.join("file"), "x").unwrap();
        panic!("a failing test, on purpose: {}", d.display());
    })
    .join();
    let kept = std::env::temp_dir().join(format!("bsa-test-{}-guard-failed", std::process::id()));
    assert!(failed.is_err() && kept.join("file").is_file());
    std::fs::remove_dir_all(kept).unwrap();
}

/// A generated file kept in the repository: with `BSA_REGENERATE=1`, write `made` to
/// `path`; otherwise fail where the committed file differs, naming `what` and `how` to
/// regenerate it.
pub fn generated(path: &Path, made: &str, what: &str, how: &str) {
    if std::env::var_os("BSA_REGENERATE").is_some_and(|v| v == "1") {
        std::fs::write(path, made).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let committed = std::fs::read_to_string(path).unwrap_or_default();
    if committed != made {
        let line = committed
            .lines()
            .zip(made.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(committed.lines().count().min(made.lines().count()));
        panic!(
            "{what} from line {}: regenerate with `BSA_REGENERATE=1 {how}`\ncommitted: {:?}\ngenerated: {:?}",
            line + 1,
            committed.lines().nth(line),
            made.lines().nth(line)
        );
    }
}

/// The launcher's error flags, in the order the CLI names them.
pub const LAUNCHER_FLAGS: [&str; 8] = [
    "--speed-tol",
    "--direction-tol",
    "--spin-tol",
    "--timing-tol",
    "--position-tol",
    "--orientation-tol",
    "--spin-floor-tol",
    "--cd-tol",
];

/// The first `n` of [`LAUNCHER_FLAGS`], each set to 0, and the error that refuses them.
pub fn zero_tolerances(n: usize) -> (Vec<&'static str>, String) {
    let args = LAUNCHER_FLAGS[..n].iter().flat_map(|f| [*f, "0"]).collect();
    (
        args,
        format!("{} are all 0", LAUNCHER_FLAGS[..n].join(", ")),
    )
}
