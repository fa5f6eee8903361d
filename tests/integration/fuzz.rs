//! The fuzzing harness of issue #13: scene mutations generated from the schema, run
//! against `bsa check` and, for a subset that check accepts, a short `bsa solve`, each
//! under a timeout. Every field of a scene that uses every optional field (a sphere, a
//! box and a mesh occluder, table, hints, start, a hold window, free positions, two
//! stages) is given a wrong type, is
//! removed, and is set to 0, -1, 1e300, -1e300, 1e-300 and 1e12; every array is also
//! made huge. `fuzz_obj_and_png_bytes_are_handled_cleanly` does the same for the bytes of
//! the OBJ and PNG readers (seeded flips, truncations, garbage lines). The
//! cases are enumerated in a fixed order, so a failure names a case that can be rerun.
//!
//! "Handled cleanly" means: the process ended by itself within the timeout, with exit
//! code 0 or 1 (never 101, a panic, nor a signal such as an abort on allocation), no
//! "panicked" in its stderr, and a failure's first stderr line starts with `error:`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use crate::util::{root, tmpdir};

/// Time allowed to one `bsa check` (a clean run takes well under a second).
const CHECK_TIMEOUT: Duration = Duration::from_secs(20);
/// Time allowed to one short `bsa solve` (two iterations per stage).
const SOLVE_TIMEOUT: Duration = Duration::from_secs(60);
/// How many of the accepted mutations also get a short solve.
const SOLVES: usize = 24;
/// Length of a "huge" array.
const HUGE: usize = 5000;

const CUBE_OBJ: &str = "v -.2 -.2 -.2\nv .2 -.2 -.2\nv -.2 .2 -.2\nv .2 .2 -.2\nv -.2 -.2 .2\nv .2 -.2 .2\nv -.2 .2 .2\nv .2 .2 .2\nf 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

/// A valid scene that uses every optional field, with tiny stage caps so that a short
/// solve of it takes a fraction of a second.
fn base_scene() -> Value {
    json!({
        "name": "fuzz",
        "target": "target.png",
        "t": 1.2,
        "timestep": 0.02,
        "gravity": [0.0, 0.0, -9.81],
        "light": [0.0, 0.0, 6.0],
        "receiver": { "center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0], "width": 4.0, "height": 3.0 },
        "table": { "center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0] },
        "occluders": [
            { "name": "head", "shape": { "sphere": { "radius": 0.6 } }, "position": [0.0, -2.0, 0.6],
              "orientation": [0.0, 0.0, 0.0, 1.0], "mass": 10.0, "launched": true,
              "start_velocity": [0.0, 1.5, 6.0], "start_angular_velocity": [0.0, 0.0, 1.0] },
            { "name": "box", "shape": { "box": { "size": [0.5, 0.5, 0.5] } }, "position": [-2.3, 0.9, 0.25], "density": 500.0 },
            { "name": "cube", "shape": { "mesh": { "obj": "cube.obj", "scale": 1.0 } }, "position": [2.3, 0.9, 0.2], "mass": 2.0 }
        ],
        "hints": [
            { "occluder": "head", "point": [0.0, 0.0, 0.0], "pixel": [320.0, 280.0], "weight": 1000.0 }
        ],
        "start": { "rise": 1.5, "aim": "hints" },
        "hold": { "window": 0.05, "instants": 2, "fps": 60, "objective": "mean" },
        "positions": "free",
        "stages": [
            { "name": "coarse", "weights": { "d0": 2, "d1": 10, "xor": 1, "hint": 0.1 }, "vary": "all", "step": 0.3,
              "max_iterations": 2, "population": 6, "target_energy": 0.0, "tol_fun": 1e-9, "stagnation": 5 },
            { "name": "fine", "weights": { "xor": 300, "contact": 50 }, "vary": ["head"], "max_iterations": 2, "population": 6,
              "objective": "worst" }
        ],
        "seed": 7
    })
}

/// One step of a path into a JSON value.
#[derive(Clone)]
enum Key {
    Field(String),
    Index(usize),
}

/// Every path to a value of `v` (objects' fields and arrays' elements), depth first.
fn paths(v: &Value, prefix: &mut Vec<Key>, out: &mut Vec<Vec<Key>>) {
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                prefix.push(Key::Field(k.clone()));
                out.push(prefix.clone());
                paths(c, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                prefix.push(Key::Index(i));
                out.push(prefix.clone());
                paths(c, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

fn name(path: &[Key]) -> String {
    let mut s = String::new();
    for k in path {
        match k {
            Key::Field(f) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(f);
            }
            Key::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// The parent of the value at `path`, and the last key.
fn parent_mut<'a>(v: &'a mut Value, path: &[Key]) -> &'a mut Value {
    let mut cur = v;
    for k in &path[..path.len() - 1] {
        cur = match k {
            Key::Field(f) => &mut cur[f.as_str()],
            Key::Index(i) => &mut cur[*i],
        };
    }
    cur
}

/// What a mutation does to the value at its path.
#[derive(Clone, Copy, Debug)]
enum Mutation {
    WrongType,
    Missing,
    Value(f64),
    Huge,
}

fn apply(base: &Value, path: &[Key], m: Mutation) -> Value {
    let mut v = base.clone();
    let parent = parent_mut(&mut v, path);
    let last = path.last().unwrap();
    let slot: &mut Value = match last {
        Key::Field(f) => &mut parent[f.as_str()],
        Key::Index(i) => &mut parent[*i],
    };
    match m {
        Mutation::WrongType => {
            *slot = if slot.is_string() {
                json!({ "a": 1 })
            } else {
                json!("x")
            }
        }
        Mutation::Missing => match (parent, last) {
            (Value::Object(o), Key::Field(f)) => {
                o.remove(f);
            }
            (Value::Array(a), Key::Index(i)) => {
                a.remove(*i);
            }
            _ => {}
        },
        Mutation::Value(x) => *slot = json!(x),
        Mutation::Huge => {
            let first = slot
                .as_array()
                .and_then(|a| a.first().cloned())
                .unwrap_or(json!(0.0));
            *slot = Value::Array(vec![first; HUGE]);
        }
    }
    v
}

/// Every mutation of every path of the base scene, in a fixed order.
fn cases(base: &Value) -> Vec<(String, Value, bool)> {
    let mut all = Vec::new();
    paths(base, &mut Vec::new(), &mut all);
    let mut out = Vec::new();
    for p in &all {
        let mut ms = vec![
            Mutation::WrongType,
            Mutation::Missing,
            Mutation::Value(0.0),
            Mutation::Value(-1.0),
            Mutation::Value(1e300),
            Mutation::Value(-1e300),
            Mutation::Value(1e-300),
            Mutation::Value(1e12),
        ];
        let is_array = {
            let mut v = base.clone();
            let parent = parent_mut(&mut v, p);
            match p.last().unwrap() {
                Key::Field(f) => parent[f.as_str()].is_array(),
                Key::Index(i) => parent[*i].is_array(),
            }
        };
        if is_array {
            ms.push(Mutation::Huge);
        }
        for m in ms {
            let huge = matches!(m, Mutation::Huge);
            out.push((format!("{} <- {m:?}", name(p)), apply(base, p, m), huge));
        }
    }
    out
}

/// How one run ended.
enum Outcome {
    Clean { ok: bool },
    Unclean(String),
}

/// Run `bsa` with `args` under `timeout`; stdout and stderr go to files in `dir`.
fn run(args: &[&str], dir: &Path, tag: &str, timeout: Duration) -> Outcome {
    let out_file = dir.join(format!("{tag}.out"));
    let err_file = dir.join(format!("{tag}.err"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_bsa"))
        .args(args)
        .current_dir(root())
        .stdout(std::fs::File::create(&out_file).unwrap())
        .stderr(std::fs::File::create(&err_file).unwrap())
        .stdin(Stdio::null())
        .spawn()
        .expect("run bsa");
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            return Outcome::Unclean(format!("no answer within {timeout:?} (hang)"));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let err = std::fs::read_to_string(&err_file).unwrap_or_default();
    let first = err.lines().next().unwrap_or("").to_string();
    match status.code() {
        _ if err.contains("panicked") => Outcome::Unclean(format!("panic: {first}")),
        Some(0) => Outcome::Clean { ok: true },
        Some(1) if err.lines().any(|l| l.starts_with("error:")) => Outcome::Clean { ok: false },
        Some(c) => Outcome::Unclean(format!("exit code {c}: {first}")),
        None => Outcome::Unclean(format!("killed by a signal (abort?): {first}")),
    }
}

#[test]
fn fuzz_scene_mutations_are_handled_cleanly() {
    let dir = tmpdir("fuzz");
    std::fs::copy(
        root().join("scenes/mickey/target.png"),
        dir.join("target.png"),
    )
    .unwrap();
    std::fs::write(dir.join("cube.obj"), CUBE_OBJ).unwrap();
    let base = base_scene();
    let cases = cases(&base);
    // The base scene itself must pass, or every mutation would test the same error.
    std::fs::write(dir.join("base.json"), base.to_string()).unwrap();
    let base_file = dir.join("base.json");
    match run(
        &["check", base_file.to_str().unwrap()],
        &dir,
        "base",
        CHECK_TIMEOUT,
    ) {
        Outcome::Clean { ok: true } => {}
        _ => panic!(
            "the base scene fails: {}",
            std::fs::read_to_string(dir.join("base.err")).unwrap()
        ),
    }

    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::<String>::new());
    let accepted = Mutex::new(Vec::<(usize, PathBuf)>::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some((label, scene, huge)) = cases.get(i) else {
                    break;
                };
                let file = dir.join(format!("case{i}.json"));
                std::fs::write(&file, scene.to_string()).unwrap();
                match run(
                    &["check", file.to_str().unwrap()],
                    &dir,
                    &format!("case{i}"),
                    CHECK_TIMEOUT,
                ) {
                    Outcome::Clean { ok } => {
                        if ok && !huge {
                            accepted.lock().unwrap().push((i, file));
                        }
                    }
                    Outcome::Unclean(why) => failures
                        .lock()
                        .unwrap()
                        .push(format!("check case {i} ({label}): {why}")),
                }
            });
        }
    });

    // A short solve of an even spread of the accepted mutations.
    let mut accepted = accepted.into_inner().unwrap();
    accepted.sort();
    let step = accepted.len().div_ceil(SOLVES).max(1);
    let solves: Vec<_> = accepted.iter().step_by(step).collect();
    let next = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some((i, file)) = solves.get(k) else {
                    break;
                };
                let out = dir.join(format!("out{i}"));
                let args = [
                    "solve",
                    file.to_str().unwrap(),
                    "--out",
                    out.to_str().unwrap(),
                    "--quiet",
                ];
                if let Outcome::Unclean(why) = run(&args, &dir, &format!("solve{i}"), SOLVE_TIMEOUT)
                {
                    failures
                        .lock()
                        .unwrap()
                        .push(format!("solve case {i} ({}): {why}", cases[*i].0));
                }
            });
        }
    });

    let failures = failures.into_inner().unwrap();
    let total = cases.len() + solves.len();
    println!(
        "{}/{} handled cleanly ({} check cases, {} of them accepted, {} short solves)",
        total - failures.len(),
        total,
        cases.len(),
        accepted.len(),
        solves.len()
    );
    assert!(cases.len() >= 500, "only {} cases", cases.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A small deterministic generator (SplitMix64), so that every run tries the same bytes.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A mutation of `bytes`: a few flipped bytes, a truncation, or inserted garbage.
fn mutate_bytes(rng: &mut Rng, bytes: &[u8]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    match rng.below(4) {
        0 => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
            }
        }
        1 => b.truncate(rng.below(b.len())),
        2 => {
            let garbage: &[&[u8]] = &[
                b"v 1e39 0 0\n",
                b"f 1 2 99999\n",
                b"f -1 -2 -3\n",
                b"v nan nan nan\n",
                b"f 1 1 1\n",
                b"\xff\xfe\n",
                b"f 0 1 2\n",
            ];
            let g = garbage[rng.below(garbage.len())];
            let i = rng.below(b.len());
            b.splice(i..i, g.iter().copied());
        }
        _ => {
            let i = rng.below(b.len());
            let j = (i + rng.below(64)).min(b.len());
            b.drain(i..j);
        }
    }
    b
}

#[test]
fn fuzz_obj_and_png_bytes_are_handled_cleanly() {
    let dir = tmpdir("fuzz-bytes");
    let png = std::fs::read(root().join("scenes/mickey/target.png")).unwrap();
    let mut scene = base_scene();
    scene["occluders"][2]["shape"]["mesh"]["obj"] = "m.obj".into();
    let mut rng = Rng(13);
    let mut failures = Vec::new();
    let cases = 150;
    for i in 0..cases {
        let case = dir.join(format!("b{i}"));
        std::fs::create_dir_all(&case).unwrap();
        let (obj, target) = if i % 2 == 0 {
            (mutate_bytes(&mut rng, CUBE_OBJ.as_bytes()), png.clone())
        } else {
            (CUBE_OBJ.as_bytes().to_vec(), mutate_bytes(&mut rng, &png))
        };
        std::fs::write(case.join("m.obj"), obj).unwrap();
        std::fs::write(case.join("target.png"), target).unwrap();
        std::fs::write(case.join("scene.json"), scene.to_string()).unwrap();
        if let Outcome::Unclean(why) = run(
            &["check", case.to_str().unwrap()],
            &case,
            "check",
            CHECK_TIMEOUT,
        ) {
            failures.push(format!("bytes case {i}: {why}"));
        }
    }
    println!(
        "{}/{cases} handled cleanly (OBJ and PNG bytes)",
        cases - failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&dir);
}
