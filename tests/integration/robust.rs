//! Faults and bad input of the audit of issue #13: every case gets a clear error naming
//! the file and the field (never a panic, an abort or a hang), and a good result already
//! in the output folder survives an interrupted or failing solve, as a scene in its
//! folder survives a `bsa new` or `bsa plant` that fails or is interrupted.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::util::{bsa, root, tmpdir, variant, TempDir};

/// `bsa check` on the scene in `dir` fails cleanly, its first stderr line naming `field`.
fn assert_refused(dir: &Path, field: &str) {
    let (ok, _, err) = bsa(&["check", dir.to_str().unwrap()]);
    assert!(!ok, "accepted {}", dir.display());
    assert!(!err.contains("panicked"), "panicked: {err}");
    let first = err.lines().next().unwrap_or("");
    assert!(
        first.starts_with("error:") && err.contains(field),
        "the error does not name `{field}`:\n{err}"
    );
}

/// An edit of the Mickey scene.
type Edit = Box<dyn Fn(&mut serde_json::Value)>;

#[test]
fn audit_magnitudes_are_refused_naming_the_field() {
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "orientation",
            Box::new(|v| {
                v["occluders"][0]["orientation"] = serde_json::json!([1e300, 1e300, 1e300, 1e300])
            }),
            "occluders[0].orientation[0]",
        ),
        (
            "receiver-v",
            Box::new(|v| v["receiver"]["v"] = serde_json::json!([0.0, 1e300, 1e300])),
            "receiver.v[1]",
        ),
        ("t", Box::new(|v| v["t"] = 1e300.into()), "`t`"),
        ("t-long", Box::new(|v| v["t"] = 1e6.into()), "`t`"),
        (
            "timestep",
            Box::new(|v| v["timestep"] = 1e-9.into()),
            "`timestep`",
        ),
        (
            "gravity",
            Box::new(|v| v["gravity"] = serde_json::json!([0.0, 0.0, 1e300])),
            "gravity[2]",
        ),
        (
            "position",
            Box::new(|v| v["occluders"][0]["position"][0] = 1e300.into()),
            "occluders[0].position[0]",
        ),
        (
            "light",
            Box::new(|v| v["light"][2] = 1e300.into()),
            "light[2]",
        ),
        (
            "width",
            Box::new(|v| v["receiver"]["width"] = 1e300.into()),
            "receiver.width",
        ),
        (
            "start-velocity",
            Box::new(|v| {
                v["occluders"][0]["start_velocity"] = serde_json::json!([0.0, 0.0, 1e300])
            }),
            "occluders[0].start_velocity[2]",
        ),
        (
            "hint-pixel",
            Box::new(|v| v["hints"][0]["pixel"][0] = 1e300.into()),
            "hints[0].pixel[0]",
        ),
        (
            "stagnation",
            Box::new(|v| v["stages"][0]["stagnation"] = 1_000_000_000_000u64.into()),
            "stages[0].stagnation",
        ),
        (
            "spheres",
            Box::new(|v| {
                let o = v["occluders"][0].clone();
                let list: Vec<serde_json::Value> = (0..10_000)
                    .map(|i| {
                        let mut o = o.clone();
                        o["name"] = format!("s{i}").into();
                        o
                    })
                    .collect();
                v["occluders"] = list.into();
            }),
            "`occluders`",
        ),
    ];
    for (name, edit, field) in cases {
        let d = variant(&format!("audit-{name}"), |v| edit(v));
        assert_refused(&d, field);
    }
}

/// A scene of one mesh occluder (the OBJ text given) in a fresh folder.
fn mesh_scene(name: &str, obj: Option<&str>, scale: Option<f64>) -> TempDir {
    let d = variant(name, |v| {
        v["occluders"][0]["shape"] = serde_json::json!({ "mesh": { "obj": "m.obj" } });
        if let Some(s) = scale {
            v["occluders"][0]["shape"]["mesh"]["scale"] = s.into();
        }
    });
    if let Some(text) = obj {
        std::fs::write(d.join("m.obj"), text).unwrap();
    }
    d
}

const CUBE_VERTICES: &str =
    "v -.3 -.3 -.3\nv .3 -.3 -.3\nv -.3 .3 -.3\nv .3 .3 -.3\nv -.3 -.3 .3\nv .3 -.3 .3\nv -.3 .3 .3\nv .3 .3 .3\n";
const CUBE_FACES: [&str; 6] = [
    "f 1 3 4 2\n",
    "f 5 6 8 7\n",
    "f 1 2 6 5\n",
    "f 3 7 8 4\n",
    "f 1 5 7 3\n",
    "f 2 4 8 6\n",
];

#[test]
fn audit_meshes_get_errors_with_the_reason() {
    // A cube with a face missing: 4 boundary edges.
    let open = format!("{CUBE_VERTICES}{}", CUBE_FACES[..5].concat());
    assert_refused(
        &mesh_scene("open-mesh", Some(&open), None),
        "4 edges belong to a single triangle",
    );
    // A bad number: the line is named.
    let bad = format!("{CUBE_VERTICES}v 1 x 2\n{}", CUBE_FACES.concat());
    assert_refused(&mesh_scene("bad-number", Some(&bad), None), "m.obj:9");
    // A missing file and a folder: the OS reason.
    assert_refused(&mesh_scene("missing-obj", None, None), "No such file");
    let d = mesh_scene("dir-obj", None, None);
    std::fs::create_dir(d.join("m.obj")).unwrap();
    assert_refused(&d, "folder");
    // A huge scale is blamed, not the mesh.
    let cube = format!("{CUBE_VERTICES}{}", CUBE_FACES.concat());
    assert_refused(
        &mesh_scene("scale", Some(&cube), Some(1e300)),
        "shape.mesh.scale",
    );
    // And the closed cube is accepted.
    let d = mesh_scene("cube", Some(&cube), None);
    let (ok, _, err) = bsa(&["check", d.to_str().unwrap()]);
    assert!(ok, "{err}");
}

#[test]
fn export_refuses_an_unbounded_continuation() {
    let (ok, _, err) = bsa(&["export", "nowhere", "--after", "1e9"]);
    assert!(
        !ok && err.contains("--after") && !err.contains("panicked"),
        "{err}"
    );
}

/// A quick Mickey (a few iterations) and a slow one (stages that run until stopped).
fn quick_and_slow(name: &str) -> (TempDir, TempDir) {
    let quick = variant(&format!("{name}-quick"), |v| {
        for s in v["stages"].as_array_mut().unwrap() {
            s["max_iterations"] = 3.into();
            s["population"] = 8.into();
        }
    });
    // Four long stages: two presses of Ctrl-C within the first second always leave
    // stages undone, whichever stage they land in.
    let slow = variant(&format!("{name}-slow"), |v| {
        let stages = v["stages"].as_array_mut().unwrap();
        let again = stages.clone();
        stages.extend(again);
        for s in stages {
            s["max_iterations"] = 1_000_000.into();
            s["stagnation"] = 100_000.into();
            s["tol_fun"] = 0.0.into();
        }
    });
    (quick, slow)
}

fn solve(scene: &Path, out: &Path) -> (bool, String, String) {
    bsa(&[
        "solve",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ])
}

fn leftover_temporaries(out: &Path) -> Vec<String> {
    std::fs::read_dir(out)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp") || n.starts_with(".bsa-"))
        .collect()
}

/// `bsa ARGS` started in the repository, its stderr piped.
fn spawn(args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_bsa"))
        .args(args)
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Wait (a minute at most) until `file` exists.
fn wait_for(file: &Path) {
    let start = Instant::now();
    while !file.exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn an_interrupted_solve_keeps_the_previous_complete_solution() {
    let (quick, slow) = quick_and_slow("interrupt");
    let out = tmpdir("interrupt-out");
    let (ok, _, err) = solve(&quick, &out);
    assert!(ok, "{err}");
    let before = std::fs::read(out.join("solution.json")).unwrap();

    let child = spawn(&[
        "solve",
        slow.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        // Another scene file than the one the folder holds: replacing it is meant.
        "--force",
    ]);
    // Once the previous solution is set aside the solve is under way; give it time to
    // install its signal handler and start the first stage.
    wait_for(&out.join("solution.prev.json"));
    std::thread::sleep(Duration::from_millis(500));
    // SIGTERM twice, handled like two presses of Ctrl-C.
    for _ in 0..2 {
        let _ = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status();
        std::thread::sleep(Duration::from_millis(100));
    }
    let result = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(130), "{err}");
    assert!(err.contains("--resume"), "{err}");
    assert_eq!(
        std::fs::read(out.join("solution.json")).unwrap(),
        before,
        "the previous complete solution was replaced"
    );
    assert!(out.join("solution.partial.json").is_file());
    assert!(
        leftover_temporaries(&out).is_empty(),
        "{:?}",
        leftover_temporaries(&out)
    );
}

#[test]
fn a_solve_that_cannot_write_keeps_the_previous_complete_solution_and_no_temporaries() {
    // Stand-in for a full disk: a write of the second solve fails (its convergence plot's
    // name is taken by a non-empty folder, which no rename can replace).
    let (quick, _) = quick_and_slow("diskfull");
    let out = tmpdir("diskfull-out");
    let (ok, _, err) = solve(&quick, &out);
    assert!(ok, "{err}");
    let before = std::fs::read(out.join("solution.json")).unwrap();
    std::fs::remove_file(out.join("convergence.png")).unwrap();
    std::fs::create_dir_all(out.join("convergence.png/x")).unwrap();
    let (ok, _, err) = solve(&quick, &out);
    assert!(!ok && !err.contains("panicked"), "{err}");
    assert!(err.contains("previous complete solution is kept"), "{err}");
    assert_eq!(std::fs::read(out.join("solution.json")).unwrap(), before);
    assert!(
        leftover_temporaries(&out).is_empty(),
        "{:?}",
        leftover_temporaries(&out)
    );

    // What a SIGKILL leaves: the previous solution aside, a stale lock, no solution.json.
    // The next solve that fails still puts the previous one back.
    std::fs::rename(out.join("solution.json"), out.join("solution.prev.json")).unwrap();
    std::fs::write(out.join(".bsa-solve.lock"), "4999999\n").unwrap();
    let (ok, _, err) = solve(&quick, &out);
    assert!(
        !ok && err.contains("previous complete solution is kept"),
        "{err}"
    );
    assert_eq!(std::fs::read(out.join("solution.json")).unwrap(), before);
}

#[test]
fn a_second_solve_into_a_locked_folder_is_refused_and_a_stale_lock_taken_over() {
    let (quick, _) = quick_and_slow("lock");
    let out = tmpdir("lock-out");
    // This test's own process is alive: the lock is held.
    std::fs::write(
        out.join(".bsa-solve.lock"),
        format!("{}\n", std::process::id()),
    )
    .unwrap();
    let (ok, _, err) = solve(&quick, &out);
    assert!(!ok && err.contains("another `bsa solve`"), "{err}");
    assert!(!out.join("solution.json").exists());
    // No process has this id (above Linux's pid_max).
    std::fs::write(out.join(".bsa-solve.lock"), "4999999\n").unwrap();
    let (ok, _, err) = solve(&quick, &out);
    assert!(ok && err.contains("taking over the lock"), "{err}");
    assert!(!out.join(".bsa-solve.lock").exists());
}

#[test]
fn a_solve_into_an_unwritable_output_is_refused_before_any_work() {
    let (quick, _) = quick_and_slow("unwritable");
    let d = tmpdir("unwritable-out");
    // A file where the folder should be: nothing can be created in it, even as root.
    let out = d.join("file");
    std::fs::write(&out, "not a folder").unwrap();
    let start = Instant::now();
    let (ok, _, err) = solve(&quick, &out.join("sub"));
    assert!(!ok && err.contains("output folder"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(20));
}

#[test]
fn eval_and_export_refuse_a_solution_of_an_edited_scene() {
    let (quick, _) = quick_and_slow("edited");
    let out = tmpdir("edited-out");
    let (ok, _, err) = solve(&quick, &out);
    assert!(ok, "{err}");
    // The same names, counts and t, but the head is moved: the shadow differs.
    let edited = variant("edited-scene", |v| {
        for s in v["stages"].as_array_mut().unwrap() {
            s["max_iterations"] = 3.into();
            s["population"] = 8.into();
        }
        v["occluders"][0]["position"][0] = 0.5.into();
    });
    let (o, e) = (out.to_str().unwrap(), edited.to_str().unwrap());
    let (ok, _, err) = bsa(&["export", o, "--scene", e]);
    assert!(!ok && err.contains("does not belong"), "{err}");
    let sol = out.join("solution.json");
    let (ok, _, err) = bsa(&["eval", e, "--solution", sol.to_str().unwrap()]);
    assert!(!ok && err.contains("does not match"), "{err}");
    // The scene it was made for is still accepted.
    let (ok, _, err) = bsa(&["export", o, "--scene", quick.to_str().unwrap()]);
    assert!(ok, "{err}");
}

/// The OBJ text of a closed UV sphere of radius 1 (`m` meridians, `n` bands):
/// `2 m (n - 1)` triangles.
fn uv_sphere_obj(m: usize, n: usize) -> String {
    use std::fmt::Write;
    let mut s = String::from("v 0 0 1\n");
    for i in 1..n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..m {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
            let (x, y, z) = (th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            writeln!(s, "v {x:.7} {y:.7} {z:.7}").unwrap();
        }
    }
    s.push_str("v 0 0 -1\n");
    let ring = |i: usize, j: usize| 2 + i * m + j % m;
    for j in 0..m {
        writeln!(s, "f 1 {} {}", ring(0, j), ring(0, j + 1)).unwrap();
    }
    for i in 0..n - 2 {
        for j in 0..m {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            writeln!(s, "f {a} {c} {d}\nf {a} {d} {b}").unwrap();
        }
    }
    let last = (n - 1) * m + 2;
    for j in 0..m {
        writeln!(s, "f {} {last} {}", ring(n - 2, j), ring(n - 2, j + 1)).unwrap();
    }
    s
}

#[test]
fn solve_and_export_of_75k_and_100k_triangle_spheres_do_not_panic() {
    // parry's hull of these spheres has no faces; the continuation (after t, in solve
    // and export) used to panic on it after solution.json was written.
    for (m, n) in [(250, 151), (250, 201)] {
        let d = variant(&format!("sphere-{n}"), |v| {
            v["occluders"][0]["shape"] =
                serde_json::json!({ "mesh": { "obj": "sphere.obj", "scale": 0.6 } });
            for s in v["stages"].as_array_mut().unwrap() {
                s["max_iterations"] = 2.into();
                s["population"] = 6.into();
            }
        });
        std::fs::write(d.join("sphere.obj"), uv_sphere_obj(m, n)).unwrap();
        let out = d.join("out");
        let (ok, _, err) = solve(&d, &out);
        assert!(ok, "{err}");
        let (ok, _, err) = bsa(&[
            "export",
            out.to_str().unwrap(),
            "--scene",
            d.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        assert!(out.join("mickey.glb").is_file());
    }
}

#[test]
fn output_piped_into_a_reader_that_goes_away_is_no_panic() {
    // `bsa check scene | head -1`: the reader closes the pipe after one line.
    let mut child = Command::new(env!("CARGO_BIN_EXE_bsa"))
        .args(["check", "scenes/thinker"])
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(out.status.code(), Some(101), "{err}");
}

/// A folder holding a scene of its own: its `scene.json` and `target.png` (Mickey's).
fn folder_with_a_scene(name: &str) -> (TempDir, Vec<u8>, Vec<u8>) {
    let dir = tmpdir(name);
    let scene = b"{\"a scene\": \"of the user's\"}".to_vec();
    let target = std::fs::read(root().join("scenes/mickey/target.png")).unwrap();
    std::fs::write(dir.join("scene.json"), &scene).unwrap();
    std::fs::write(dir.join("target.png"), &target).unwrap();
    (dir, scene, target)
}

/// The folder holds its scene as it was, and nothing else.
fn assert_untouched(dir: &Path, scene: &[u8], target: &[u8]) {
    assert_eq!(
        std::fs::read(dir.join("scene.json")).unwrap(),
        scene,
        "scene.json changed"
    );
    assert_eq!(
        std::fs::read(dir.join("target.png")).unwrap(),
        target,
        "target.png changed"
    );
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["scene.json", "target.png"],
        "files left in {}",
        dir.display()
    );
}

#[test]
fn new_refusing_its_input_leaves_the_folders_scene_as_it_was() {
    // Before the fix the first scene (one object of each kind) replaced scene.json and
    // the new target replaced target.png before the objects were checked.
    let (dir, scene, target) = folder_with_a_scene("new-refused");
    let fly = root().join("scenes/fly/target.png");
    for objects in ["sphere:5", "chess,sphere:5"] {
        let (ok, _, err) = bsa(&[
            "new",
            dir.to_str().unwrap(),
            "--target",
            fly.to_str().unwrap(),
            "--objects",
            objects,
        ]);
        assert!(!ok && err.contains("larger than the"), "{objects}: {err}");
        assert_untouched(&dir, &scene, &target);
    }
}

#[test]
fn an_interrupted_new_writes_nothing_and_leaves_no_scratch_files() {
    let (dir, scene, target) = folder_with_a_scene("new-interrupted");
    let thinker = root().join("scenes/thinker/target.png");
    let child = spawn(&[
        "new",
        dir.to_str().unwrap(),
        "--target",
        thinker.to_str().unwrap(),
        "--objects",
        "chess",
        "--width",
        "0.96",
        "--light-height",
        "3",
    ]);
    // Once a design's scratch scene exists, the designs and their trial solves are under
    // way (they take seconds for sixteen pieces).
    wait_for(&dir.join(".bsa-new-design-0.json"));
    std::thread::sleep(Duration::from_millis(200));
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let result = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(130), "{err}");
    assert!(err.contains("no scene written"), "{err}");
    assert_untouched(&dir, &scene, &target);
}

#[test]
fn plant_failing_to_draw_leaves_the_folders_scene_as_it_was() {
    // Before the fix a placeholder scene and target replaced the folder's before the
    // draw, which fails here.
    let (dir, scene, target) = folder_with_a_scene("plant-refused");
    let (ok, _, err) = bsa(&[
        "plant",
        dir.to_str().unwrap(),
        "--objects",
        "sphere:0.5*40",
        "--width",
        "1",
    ]);
    assert!(!ok && err.contains("does not fit"), "{err}");
    assert_untouched(&dir, &scene, &target);
}
