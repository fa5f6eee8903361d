//! The one integration-test binary: the `bsa` command line end to end, bad input,
//! determinism across thread counts, resume, the golden shadow image, and the Mickey
//! solve itself.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use bsa::evaluate::Problem;
use bsa::optimize::solver::{self, Observer, SolveOptions};
use bsa::output::solution::{SampleRecord, Solution};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn bsa(args: &[&str]) -> (bool, String, String) {
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

fn tmpdir(name: &str) -> PathBuf {
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
fn variant(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
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

/// `bsa check` on a bad scene must fail cleanly, naming the file and the field.
fn assert_rejected(dir: &Path, expect: &[&str]) {
    let (ok, _, err) = bsa(&["check", dir.to_str().unwrap()]);
    assert!(!ok, "accepted a bad scene in {}", dir.display());
    assert!(!err.contains("panicked"), "panicked: {err}");
    for e in expect {
        assert!(err.contains(e), "error message lacks `{e}`:\n{err}");
    }
}

#[test]
fn check_accepts_mickey() {
    let (ok, out, err) = bsa(&["check", "scenes/mickey"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("scene `mickey`") && out.contains("ok"),
        "{out}"
    );
}

#[test]
fn bad_input_gets_clear_errors() {
    // Missing file.
    let (ok, _, err) = bsa(&["check", "scenes/does-not-exist"]);
    assert!(
        !ok && err.contains("does-not-exist") && !err.contains("panicked"),
        "{err}"
    );

    // Malformed JSON.
    let d = tmpdir("malformed");
    std::fs::write(d.join("scene.json"), "{ \"t\": 1.2, ").unwrap();
    assert_rejected(&d, &["scene.json", "EOF"]);

    // Unknown field.
    let d = variant("unknown", |v| v["colour"] = "red".into());
    assert_rejected(&d, &["scene.json", "unknown field `colour`"]);

    // An occluder named after a node of the glTF export: refused when the scene is
    // loaded, not after the solve when the export runs.
    let d = variant("reserved", |v| v["occluders"][1]["name"] = "table".into());
    assert_rejected(&d, &["scene.json", "occluders[1].name", "`table`"]);

    // Target that is not a PNG.
    let d = variant("notpng", |_| {});
    std::fs::write(d.join("target.png"), b"GIF89a not a png").unwrap();
    assert_rejected(&d, &["target.png", "not a readable PNG"]);

    // Target with no dark pixel.
    let d = variant("white", |_| {});
    image::GrayImage::from_pixel(64, 48, image::Luma([255]))
        .save(d.join("target.png"))
        .unwrap();
    assert_rejected(&d, &["target.png", "no dark pixel"]);

    // t <= 0.
    let d = variant("t0", |v| v["t"] = 0.0.into());
    assert_rejected(&d, &["scene.json", "`t`", "positive"]);
    let d = variant("tneg", |v| v["t"] = (-1.0).into());
    assert_rejected(&d, &["`t`", "positive"]);

    // Non-positive radius, size, mass.
    let d = variant("radius", |v| {
        v["occluders"][1]["shape"]["sphere"]["radius"] = 0.0.into()
    });
    assert_rejected(&d, &["occluders[1].shape.sphere.radius", "positive"]);
    let d = variant("size", |v| {
        v["occluders"][0]["shape"] = serde_json::json!({"box": {"size": [0.5, -0.1, 0.5]}});
    });
    assert_rejected(&d, &["occluders[0].shape.box.size[1]", "positive"]);
    let d = variant("mass", |v| v["occluders"][2]["mass"] = (-2.0).into());
    assert_rejected(&d, &["occluders[2].mass", "positive"]);

    // Infinity (JSON has no NaN literal; an overflowing number is how it arrives).
    let d = variant("inf", |_| {});
    let text = std::fs::read_to_string(d.join("scene.json"))
        .unwrap()
        .replacen("\"t\": 1.2", "\"t\": 1e999", 1);
    std::fs::write(d.join("scene.json"), text).unwrap();
    assert_rejected(&d, &["scene.json"]);
    // NaN in a hints file.
    let d = variant("nanhint", |v| v["hints"] = "hints.txt".into());
    std::fs::write(d.join("hints.txt"), "head 0 0 0 320 NaN 100\n").unwrap();
    assert_rejected(&d, &["hints.txt:1", "finite"]);
    // NaN in an OBJ.
    let d = variant("nanobj", |v| {
        v["occluders"][0]["shape"] = serde_json::json!({"mesh": {"obj": "bad.obj"}});
    });
    std::fs::write(
        d.join("bad.obj"),
        "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    assert_rejected(&d, &["bad.obj", "occluders[0].shape.mesh.obj"]);

    // OBJ with no faces.
    let d = variant("nofaces", |v| {
        v["occluders"][0]["shape"] = serde_json::json!({"mesh": {"obj": "empty.obj"}});
    });
    std::fs::write(d.join("empty.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    assert_rejected(&d, &["empty.obj", "occluders[0].shape.mesh.obj"]);

    // Light on, and behind, the receiver plane.
    let d = variant("lighton", |v| {
        v["light"] = serde_json::json!([0.0, 0.0, 0.0])
    });
    assert_rejected(&d, &["`light`", "behind the receiver"]);
    let d = variant("lightbehind", |v| {
        v["light"] = serde_json::json!([0.0, 0.0, -3.0])
    });
    assert_rejected(&d, &["`light`", "behind the receiver"]);

    // A hint naming a missing occluder.
    let d = variant("hint", |v| v["hints"][1]["occluder"] = "nose".into());
    assert_rejected(&d, &["hints[1].occluder", "`nose`"]);

    // Occluders overlapping at launch.
    let d = variant("overlap", |v| {
        v["occluders"][1]["position"] = serde_json::json!([0.3, -1.8, 0.6])
    });
    assert_rejected(&d, &["`head` and `left_ear` overlap"]);
}

fn small_mickey(iterations: usize) -> Problem {
    let mut scene = bsa::scene::load(&root().join("scenes/mickey")).unwrap();
    for s in &mut scene.stages {
        s.max_iterations = iterations;
        s.population = 16;
    }
    Problem::new(scene)
}

fn params_bits(s: &Solution) -> Vec<u64> {
    s.parameters().iter().map(|x| x.to_bits()).collect()
}

#[test]
fn same_seed_gives_bit_identical_solution_with_1_and_2_threads() {
    let p = small_mickey(12);
    let none = AtomicUsize::new(0);
    let run = |threads| {
        let opts = SolveOptions {
            threads: Some(threads),
            seed: Some(7),
            resume: None,
        };
        solver::solve(&p, &opts, &mut solver::Silent, &none)
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    assert_eq!(params_bits(&a), params_bits(&b));
    assert_eq!(a.total_energy.to_bits(), b.total_energy.to_bits());
    assert_eq!(ra, rb);
    // A different seed explores differently.
    let opts = SolveOptions {
        threads: Some(2),
        seed: Some(8),
        resume: None,
    };
    let (c, _) = solver::solve(&p, &opts, &mut solver::Silent, &none);
    assert_ne!(params_bits(&a), params_bits(&c));
}

/// Raises the interrupt counter twice once the first stage is done: the solve must stop
/// and hand back a solution with one completed stage.
struct StopAfterFirstStage<'a>(&'a AtomicUsize);
impl Observer for StopAfterFirstStage<'_> {
    fn stage_finished(&mut self, _s: &Solution, _r: &[SampleRecord]) {
        self.0.store(2, Ordering::SeqCst);
    }
}

#[test]
fn resume_continues_to_the_same_result() {
    let p = small_mickey(10);
    let opts = SolveOptions {
        threads: Some(2),
        seed: Some(3),
        resume: None,
    };
    let none = AtomicUsize::new(0);
    let (full, _) = solver::solve(&p, &opts, &mut solver::Silent, &none);
    assert!(full.complete);
    let counter = AtomicUsize::new(0);
    let (partial, _) = solver::solve(&p, &opts, &mut StopAfterFirstStage(&counter), &counter);
    assert_eq!(partial.stages_completed, 1);
    assert!(!partial.complete);
    // Round-trip through JSON as the CLI does.
    let text = serde_json::to_string(&partial).unwrap();
    let partial: Solution = serde_json::from_str(&text).unwrap();
    let opts2 = SolveOptions {
        resume: Some(partial),
        ..opts
    };
    let (resumed, _) = solver::solve(&p, &opts2, &mut solver::Silent, &none);
    assert_eq!(resumed.stages_completed, 2);
    assert_eq!(params_bits(&resumed), params_bits(&full));
}

#[test]
fn solve_and_eval_from_the_command_line() {
    // A short run of the real command (few iterations) writes every output file, and
    // `eval` reads the solution back.
    let d = variant("cli", |v| {
        for s in v["stages"].as_array_mut().unwrap() {
            s["max_iterations"] = 5.into();
            s["population"] = 12.into();
        }
    });
    let out = d.join("out");
    let (ok, stdout, err) = bsa(&[
        "solve",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--report",
    ]);
    assert!(ok, "{err}");
    assert!(
        stdout.contains("IoU at t") && stdout.contains("total samples"),
        "{stdout}"
    );
    for f in [
        "solution.json",
        "shadow.png",
        "overlay.png",
        "preview.png",
        "convergence.csv",
        "convergence.png",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + 2 * 5 * 12,
        "one row per sample plus the header"
    );
    assert!(
        csv.starts_with("stage,iteration,d0,d1,d2,xor,inner,outer,contact,reg,hint,barrier,total")
    );
    let sol = out.join("solution.json");
    let (ok, stdout, err) = bsa(&[
        "eval",
        d.to_str().unwrap(),
        "--solution",
        sol.to_str().unwrap(),
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for k in [
        "d0", "d1", "d2", "xor", "inner", "outer", "contact", "reg", "hint", "barrier",
    ] {
        assert!(v["terms"][k]["raw"].is_number(), "{k} missing: {stdout}");
    }
    let (ok, stdout, _) = bsa(&[
        "eval",
        d.to_str().unwrap(),
        "--solution",
        sol.to_str().unwrap(),
    ]);
    assert!(
        ok && stdout.contains("XOR") && stdout.contains("total"),
        "{stdout}"
    );
    // Resuming a complete solution does nothing and says so.
    let (ok, _, err) = bsa(&[
        "solve",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resume",
        "--quiet",
    ]);
    assert!(ok && err.contains("nothing to resume"), "{err}");
    // A solution from another scene is refused.
    let other = variant("cli-other", |v| v["name"] = "other".into());
    let (ok, _, err) = bsa(&[
        "eval",
        other.to_str().unwrap(),
        "--solution",
        sol.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("not `other`"), "{err}");
    // A corrupt solution file is refused.
    std::fs::write(&sol, "{ not json").unwrap();
    let (ok, _, err) = bsa(&[
        "eval",
        d.to_str().unwrap(),
        "--solution",
        sol.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("not a valid solution file") && !err.contains("panicked"),
        "{err}"
    );
}

/// The shadow of a fixed launch, compared with a committed golden image. Set
/// `BSA_UPDATE_GOLDEN=1` to regenerate it; on failure a diff image is written next to
/// the golden file (red: only in the golden, blue: only now).
#[test]
fn golden_shadow_of_a_fixed_launch() {
    let p = Problem::new(bsa::scene::load(&root().join("scenes/mickey")).unwrap());
    // Launch values written by hand: each ball thrown toward the middle of the picture,
    // the head with a spin that must not matter for a sphere.
    let params = [
        0.0, 1.6, 7.9, 0.0, 3.0, 0.0, //
        1.5, -0.4, 8.4, 0.0, 0.0, 0.0, //
        -1.5, -0.4, 8.4, 0.0, 0.0, 0.0,
    ];
    let mut ws = p.workspace();
    p.evaluate(&params, &bsa::energy::Weights::all_ones(), &mut ws);
    let golden = root().join("tests/golden/mickey_fixed_launch.png");
    let now = bsa::output::picture::mask_image(ws.mask.width(), ws.mask.height(), &|x, y| {
        ws.mask.get(x, y)
    });
    if std::env::var_os("BSA_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
        now.save(&golden).unwrap();
        return;
    }
    let old = image::open(&golden)
        .expect("golden image (run with BSA_UPDATE_GOLDEN=1 to create it)")
        .to_luma8();
    assert_eq!(old.dimensions(), now.dimensions());
    let differing = old
        .pixels()
        .zip(now.pixels())
        .filter(|(a, b)| a != b)
        .count();
    if differing > 0 {
        let diff = bsa::output::picture::difference_image(
            old.width() as usize,
            old.height() as usize,
            &|x, y| old.get_pixel(x as u32, y as u32).0[0] < 128,
            &|x, y| now.get_pixel(x as u32, y as u32).0[0] < 128,
        );
        let path = golden.with_file_name("mickey_fixed_launch.diff.png");
        diff.save(&path).unwrap();
        panic!(
            "{differing} pixels differ from the golden image; see {}",
            path.display()
        );
    }
}

#[test]
fn mickey_solves_to_iou_099_without_contact() {
    let p = Problem::new(bsa::scene::load(&root().join("scenes/mickey")).unwrap());
    let none = AtomicUsize::new(0);
    let (s, records) = solver::solve(&p, &SolveOptions::default(), &mut solver::Silent, &none);
    assert!(s.iou >= 0.99, "IoU {}", s.iou);
    assert_eq!(s.n_contacts, 0);
    assert_eq!(s.t_sim, s.t);
    assert_eq!(records.len(), s.samples);
}

/// Records the launch values after every stage.
struct StageSnapshots(Vec<Vec<f64>>);
impl Observer for StageSnapshots {
    fn stage_finished(&mut self, s: &Solution, _r: &[SampleRecord]) {
        self.0.push(s.parameters());
    }
}

#[test]
fn sequential_strategy_varies_one_occluder_per_stage_then_all() {
    // Mickey with boxes for ears and the sequential strategy in automatic order.
    let d = variant("sequential", |v| {
        v["occluders"][1]["shape"] = serde_json::json!({"box": {"size": [0.5, 0.4, 0.3]}});
        v["occluders"][1]["position"] = serde_json::json!([-2.3, 0.9, 0.15]);
        v["occluders"][2]["shape"] = serde_json::json!({"box": {"size": [0.6, 0.5, 0.4]}});
        v["occluders"][2]["position"] = serde_json::json!([2.3, 0.9, 0.2]);
        let stage = v["stages"][1].clone();
        v.as_object_mut().unwrap().remove("stages");
        let mut one = stage.clone();
        one["max_iterations"] = 8.into();
        one["population"] = 12.into();
        one.as_object_mut().unwrap().remove("name");
        let mut last = one.clone();
        last["step"] = 0.05.into();
        v["strategy"] =
            serde_json::json!({"kind": "sequential", "order": "auto", "stage": one, "final": last});
    });
    let scene = bsa::scene::load(&d).unwrap();
    let names: Vec<&str> = scene.stages.iter().map(|s| s.name.as_str()).collect();
    // Largest volume first: the head sphere, then the larger box, then the smaller one.
    assert_eq!(names, ["head", "right_ear", "left_ear", "final"]);
    assert_eq!(scene.stages[3].vary, vec![0, 1, 2]);
    let p = Problem::new(scene);
    let start = p.scene.start_parameters();
    let mut snaps = StageSnapshots(Vec::new());
    let none = AtomicUsize::new(0);
    let (s, _) = solver::solve(&p, &SolveOptions::default(), &mut snaps, &none);
    assert_eq!(s.stages_completed, 4);
    let mut before = start;
    for (k, after) in snaps.0.iter().take(3).enumerate() {
        let varied = p.scene.stages[k].vary[0];
        for i in 0..3 {
            let same = before[6 * i..6 * i + 6] == after[6 * i..6 * i + 6];
            assert_eq!(
                same,
                i != varied,
                "stage {k}: occluder {i} changed={}",
                !same
            );
        }
        before = after.clone();
    }
}

#[test]
fn sequential_rounds_repeat_the_pass_and_are_checked() {
    let with_rounds = |rounds: serde_json::Value| {
        variant("rounds", move |v| {
            let mut stage = v["stages"][1].clone();
            v.as_object_mut().unwrap().remove("stages");
            stage.as_object_mut().unwrap().remove("name");
            v["strategy"] = serde_json::json!({
                "kind": "sequential", "order": ["left_ear", "head"], "rounds": rounds,
                "stage": stage, "final": stage
            });
        })
    };
    let scene = bsa::scene::load(&with_rounds(2.into())).unwrap();
    let names: Vec<&str> = scene.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["left_ear", "head", "left_ear (2)", "head (2)", "final"]
    );
    assert_eq!(scene.stages[2].vary, vec![1]);
    for bad in [0, 101] {
        let err = bsa::scene::load(&with_rounds(bad.into())).unwrap_err();
        let msg = format!("{err:#}");
        assert!(
            msg.contains("strategy.rounds") && msg.contains("1 to 100"),
            "{msg}"
        );
    }
}

#[test]
fn example_scenes_start_without_contact_near_their_targets() {
    // The generator (tools/make_scenes.py) promises start guesses that fly without
    // contact; the solver's sequential stages rely on it (a held pair that collides hides
    // every later contact from the stage's penalty).
    for name in ["fly", "tbc", "thinker"] {
        let p = Problem::new(bsa::scene::load(&root().join("scenes").join(name)).unwrap());
        let mut ws = p.workspace();
        let e = p.evaluate(
            &p.scene.start_parameters(),
            &bsa::energy::Weights::all_ones(),
            &mut ws,
        );
        assert_eq!(
            e.outcome.n_contacts, 0,
            "{name}: {:?}",
            e.outcome.first_contact
        );
        assert!(e.iou > 0.5, "{name}: start IoU {}", e.iou);
    }
}

/// Raises the interrupt counter to 2 in the middle of the first stage (a double Ctrl-C).
struct StopMidFirstStage<'a>(&'a AtomicUsize);
impl Observer for StopMidFirstStage<'_> {
    fn iteration(&mut self, info: &solver::IterationInfo) {
        if info.stage_index == 0 && info.iteration == 3 {
            self.0.store(2, Ordering::SeqCst);
        }
    }
}

#[test]
fn a_stage_stopped_by_a_second_interrupt_runs_again_on_resume() {
    let p = small_mickey(10);
    let counter = AtomicUsize::new(0);
    let opts = SolveOptions {
        threads: Some(2),
        seed: Some(5),
        resume: None,
    };
    let (stopped, _) = solver::solve(&p, &opts, &mut StopMidFirstStage(&counter), &counter);
    assert_eq!(stopped.stages_completed, 0);
    assert!(!stopped.complete);
    assert_eq!(stopped.stages.len(), 1);
    assert!(
        stopped.stages[0].stop.starts_with("stopped"),
        "{}",
        stopped.stages[0].stop
    );
    // The best so far is kept: it is no worse than the start.
    let mut ws = p.workspace();
    let w = p.scene.stages[0].weights;
    let start = p.evaluate(&p.scene.start_parameters(), &w, &mut ws).total;
    let kept = p.evaluate(&stopped.parameters(), &w, &mut ws).total;
    assert!(kept <= start);
    let none = AtomicUsize::new(0);
    let (resumed, _) = solver::solve(
        &p,
        &SolveOptions {
            resume: Some(stopped),
            ..opts
        },
        &mut solver::Silent,
        &none,
    );
    assert_eq!(resumed.stages_completed, 2);
    assert!(resumed.complete);
    assert_eq!(resumed.stages.len(), 2);
    assert_eq!(resumed.stages[0].iterations, 10);
}

// ---------------------------------------------------------------------------------------
// Export: animated glTF, launch tables, the Khronos validator and the Blender cross-check.
// The tests that need Node's gltf-validator or Blender's bpy run when BSA_FULL_TESTS is set
// (scripts/test.sh, the README's test command, installs both and sets it); then a missing
// tool is a failure, not a skip.
// ---------------------------------------------------------------------------------------

fn full_tests() -> bool {
    let on = std::env::var_os("BSA_FULL_TESTS").is_some();
    if !on {
        eprintln!("skipped: needs gltf-validator and bpy; run `bash scripts/test.sh`");
    }
    on
}

/// Every folder of `scenes/` that holds a scene.json.
fn example_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("scene.json").is_file())
        .collect();
    v.sort();
    assert!(!v.is_empty());
    v
}

/// Solve a scene quickly (few iterations) into a fresh folder with the CLI, which also
/// writes the .glb and the CSV tables.
fn quick_solve(scene: &Path, name: &str) -> PathBuf {
    let d = tmpdir(name);
    let text = std::fs::read_to_string(scene.join("scene.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    // Keep the scene's own files reachable: absolute target, meshes and hints paths.
    let abs = |p: &serde_json::Value| {
        serde_json::Value::from(scene.join(p.as_str().unwrap()).display().to_string())
    };
    v["target"] = abs(&v["target"]);
    if let Some(h) = v.get("hints").filter(|h| h.is_string()).cloned() {
        v["hints"] = abs(&h);
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
    std::fs::write(d.join("scene.json"), serde_json::to_string(&v).unwrap()).unwrap();
    let out = d.join("out");
    let (ok, _, err) = bsa(&[
        "solve",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(ok, "{err}");
    out
}

#[test]
fn exported_glb_gives_the_solvers_poses_at_t() {
    let out = quick_solve(&root().join("scenes/mickey"), "glb-poses");
    let p = Problem::new(bsa::scene::load(&root().join("scenes/mickey")).unwrap());
    let sol = bsa::output::files::read_solution(&out.join("solution.json")).unwrap();
    let mut ws = p.workspace();
    p.fly(&sol.parameters(), &mut ws);
    let glb = std::fs::read(out.join("mickey.glb")).unwrap();
    let read = bsa::output::gltf::read_poses_at(&glb, p.scene.t).unwrap();
    for (i, o) in p.scene.occluders.iter().enumerate() {
        let (name, pos, q) = read
            .iter()
            .find(|(n, _, _)| n == &o.name)
            .expect("occluder node in the glb");
        let (want_p, want_q) = ws.poses[i];
        assert!(pos.distance(want_p) < 1e-5, "{name}: {pos} vs {want_p}");
        assert!(q.angle_between(want_q) < 1e-5, "{name}: {q} vs {want_q}");
    }
    // The launch table: one row per occluder, units in the header, consistent values.
    let mut r = csv::Reader::from_path(out.join("launch.csv")).unwrap();
    let header = r.headers().unwrap().clone();
    for col in [
        "name",
        "mass_kg",
        "com_x_m",
        "vx_m_s",
        "speed_m_s",
        "elevation_deg",
        "azimuth_deg",
        "wx_rad_s",
        "spin_rev_s",
        "spin_axis_body_x",
        "inertia_1_kg_m2",
        "com_offset_x_m",
        "com_at_t_x_m",
        "q_at_t_w",
    ] {
        assert!(header.iter().any(|h| h == col), "launch.csv lacks {col}");
    }
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 3);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for (row, l) in rows.iter().zip(&sol.occluders) {
        assert_eq!(&row[col("name")], l.name.as_str());
        let speed: f64 = row[col("speed_m_s")].parse().unwrap();
        let v = l.velocity;
        assert!((speed - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).abs() < 1e-9);
    }
    let traj = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(traj.starts_with("time_s,occluder,phase,x_m,y_m,z_m,qx,qy,qz,qw"));
    // 72 steps to t, the key at t, 60 steps after, 3 occluders each.
    assert_eq!(traj.lines().count(), 1 + 3 * (72 + 1 + 60));
}

#[test]
fn khronos_validator_finds_no_errors_or_warnings() {
    if !full_tests() {
        return;
    }
    for scene in example_scenes() {
        let name = scene.file_name().unwrap().to_str().unwrap().to_string();
        let out = quick_solve(&scene, &format!("validator-{name}"));
        let glb = out.join(format!("{name}.glb"));
        let o = Command::new("node")
            .arg(root().join("tools/gltf-validator/validate.js"))
            .arg(&glb)
            .output()
            .expect("node (install Node.js; scripts/test.sh sets up the validator)");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["errors"], 0, "{name}: {v}");
        assert_eq!(v["warnings"], 0, "{name}: {v}");
    }
}

#[test]
fn blender_cycles_mask_matches_the_rasterizer() {
    if !full_tests() {
        return;
    }
    for scene in example_scenes() {
        let name = scene.file_name().unwrap().to_str().unwrap().to_string();
        let out = quick_solve(&scene, &format!("cycles-{name}"));
        let (ok, stdout, err) = bsa(&["validate", out.to_str().unwrap()]);
        assert!(ok, "{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("validate.json")).unwrap())
                .unwrap();
        let iou = v["iou"].as_f64().unwrap();
        eprintln!("{name}: {stdout}");
        assert!(iou >= 0.995, "{name}: Cycles vs rasterizer IoU {iou}");
        assert!(out.join("validate_diff.png").is_file());
    }
}

#[test]
fn blender_imports_animation_light_cameras_and_frame_range() {
    if !full_tests() {
        return;
    }
    let out = quick_solve(&root().join("scenes/mickey"), "blender-import");
    let o = Command::new(root().join(".venv-blender/bin/python"))
        .arg(root().join("blender/check_import.py"))
        .args(["--", "--glb"])
        .arg(out.join("mickey.glb"))
        .output()
        .expect("the bpy virtualenv (bash blender/setup_venv.sh)");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("BSA_RESULT "))
        .unwrap_or_else(|| panic!("{}", String::from_utf8_lossy(&o.stderr)));
    let v: serde_json::Value = serde_json::from_str(line).unwrap();
    assert_eq!(v["fps"].as_f64().unwrap(), 60.0);
    assert_eq!(v["frame_t"].as_f64().unwrap(), 72.0);
    assert_eq!(v["frame_start"], 0);
    assert_eq!(v["frame_end"], 132, "t + 1 s at 60 fps");
    assert_eq!(v["cameras"]["camera_shadow"]["type"], "ORTHO");
    assert!(
        (v["cameras"]["camera_shadow"]["ortho_scale"]
            .as_f64()
            .unwrap()
            - 4.0)
            .abs()
            < 1e-5
    );
    assert_eq!(v["cameras"]["camera_view"]["type"], "PERSP");
    assert_eq!(v["lights"]["light"]["type"], "POINT");
    let light = &v["poses_at_t"]["light"]["location"];
    assert!((light[2].as_f64().unwrap() - 6.0).abs() < 1e-5, "{light}");
    // The animation plays: each occluder is where the solver put it at t.
    let p = Problem::new(bsa::scene::load(&root().join("scenes/mickey")).unwrap());
    let sol = bsa::output::files::read_solution(&out.join("solution.json")).unwrap();
    let mut ws = p.workspace();
    p.fly(&sol.parameters(), &mut ws);
    for (i, o) in p.scene.occluders.iter().enumerate() {
        let loc = &v["poses_at_t"][&o.name]["location"];
        let got = glam::DVec3::new(
            loc[0].as_f64().unwrap(),
            loc[1].as_f64().unwrap(),
            loc[2].as_f64().unwrap(),
        );
        assert!(
            got.distance(ws.poses[i].0) < 1e-4,
            "{}: Blender {got} vs solver {}",
            o.name,
            ws.poses[i].0
        );
    }
}

#[test]
fn video_of_mickey_renders() {
    if !full_tests() {
        return;
    }
    let out = quick_solve(&root().join("scenes/mickey"), "video");
    let mp4 = out.join("short.mp4");
    let (ok, _, err) = bsa(&[
        "video",
        out.to_str().unwrap(),
        "--out",
        mp4.to_str().unwrap(),
        "--samples",
        "1",
        "--width",
        "160",
        "--height",
        "120",
        "--seconds",
        "0.2",
    ]);
    assert!(ok, "{err}");
    let bytes = std::fs::read(&mp4).unwrap();
    assert!(
        bytes.len() > 1000 && &bytes[4..8] == b"ftyp",
        "not an MP4 ({} bytes)",
        bytes.len()
    );
}

#[test]
fn bad_input_to_export_validate_and_video() {
    // Missing solution.
    let empty = tmpdir("export-empty");
    for cmd in ["export", "validate", "video"] {
        let (ok, _, err) = bsa(&[cmd, empty.to_str().unwrap()]);
        assert!(
            !ok && err.contains("no solution.json") && !err.contains("panicked"),
            "{cmd}: {err}"
        );
    }
    let out = quick_solve(&root().join("scenes/mickey"), "export-bad");
    // A solution of another scene.
    let other = variant("export-other", |v| v["name"] = "other".into());
    let (ok, _, err) = bsa(&[
        "export",
        out.to_str().unwrap(),
        "--scene",
        other.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("does not belong") && err.contains("not `other`"),
        "{err}"
    );
    // No bpy in the given Python.
    let (ok, _, err) = bsa(&[
        "validate",
        out.to_str().unwrap(),
        "--python",
        "/nonexistent/python3",
    ]);
    assert!(!ok && err.contains("does not exist"), "{err}");
    let sys_python = ["/usr/bin/python3", "/usr/local/bin/python3"]
        .into_iter()
        .find(|p| Path::new(p).exists());
    if let Some(py) = sys_python {
        let has_bpy = Command::new(py)
            .args(["-c", "import bpy"])
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false);
        if !has_bpy {
            let (ok, _, err) = bsa(&["validate", out.to_str().unwrap(), "--python", py]);
            assert!(
                !ok && err.contains("no bpy module") && err.contains("setup_venv.sh"),
                "{err}"
            );
        }
    }
    // A corrupt .glb.
    std::fs::write(out.join("mickey.glb"), b"glTF garbage").unwrap();
    for cmd in ["validate", "video"] {
        let (ok, _, err) = bsa(&[cmd, out.to_str().unwrap()]);
        assert!(
            !ok && err.contains("not a valid glTF") && !err.contains("panicked"),
            "{cmd}: {err}"
        );
    }
    // A missing .glb.
    std::fs::remove_file(out.join("mickey.glb")).unwrap();
    let (ok, _, err) = bsa(&["validate", out.to_str().unwrap()]);
    assert!(!ok && err.contains("run `bsa export"), "{err}");
    // A corrupt solution.
    std::fs::write(out.join("solution.json"), "[1, 2").unwrap();
    let (ok, _, err) = bsa(&["export", out.to_str().unwrap()]);
    assert!(!ok && err.contains("not a valid solution file"), "{err}");
}

// ---------------------------------------------------------------------------------------
// Error budget (`bsa budget`)
// ---------------------------------------------------------------------------------------

#[test]
fn budget_of_a_quick_mickey_solve() {
    let out = quick_solve(&root().join("scenes/mickey"), "budget");
    let dir = out.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "budget",
            dir,
            "--samples",
            "300",
            "--search-samples",
            "40",
            "-q",
        ];
        args.extend_from_slice(extra);
        bsa(&args)
    };
    let (ok, stdout, err) = run(&["--threads", "1"]);
    assert!(ok, "{err}");
    assert!(stdout.contains("drag-compensated launch"), "{stdout}");
    for f in [
        "budget.md",
        "budget.json",
        "launch_drag.csv",
        "budget_hist.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let json1 = std::fs::read_to_string(out.join("budget.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json1).unwrap();
    // The quick solve may stay below the threshold: then no search and no plot of it.
    let reachable = v["threshold_unreachable"].is_null();
    assert_eq!(reachable, out.join("budget_tolerances.png").is_file());
    assert_eq!(reachable, !v["search"].is_null());
    assert_eq!(
        reachable,
        !stdout.contains("threshold unreachable"),
        "{stdout}"
    );
    // A threshold above any IoU: reported unreachable, clearly, and not searched.
    let (ok, stdout, err) = run(&["--iou-threshold", "1"]);
    assert!(ok, "{err}");
    assert!(stdout.contains("threshold unreachable"), "{stdout}");
    assert!(stdout.contains("no launcher precision"), "{stdout}");
    let v1: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("budget.json")).unwrap()).unwrap();
    assert_eq!(v1["iou_threshold"], 1.0);
    assert!(v1["search"].is_null() && !v1["threshold_unreachable"].is_null());
    assert!(!out.join("budget_tolerances.png").is_file());
    let md = std::fs::read_to_string(out.join("budget.md")).unwrap();
    assert!(md.contains("Unreachable at any tolerance"), "{md}");
    for o in v["occluders"].as_array().unwrap() {
        assert!(o["compensated_com_error_m"].as_f64().unwrap() < 1e-3, "{o}");
        assert!(o["position_error_m"].as_f64().unwrap() > 0.05, "{o}");
    }
    let vac = v["iou_vacuum"].as_f64().unwrap();
    let comp = v["iou_drag_compensated"].as_f64().unwrap();
    assert!((vac - comp).abs() <= 0.01, "{vac} vs {comp}");
    assert_eq!(v["monte_carlo"]["samples"], 300);
    // The default threshold is 0.9, recorded; P(IoU >= threshold) is a probability.
    assert_eq!(v["iou_threshold"], 0.9);
    let p = v["monte_carlo"]["p_iou_at_least_threshold"]
        .as_f64()
        .unwrap();
    assert!((0.0..=1.0).contains(&p), "{p}");
    assert!(v["monte_carlo"].get("p_iou_at_least_0_9").is_none());
    // Same columns as launch.csv, other velocities.
    let header = |f: &str| {
        let mut r = csv::Reader::from_path(out.join(f)).unwrap();
        let h = r.headers().unwrap().clone();
        let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
        (h, rows)
    };
    let (h1, r1) = header("launch.csv");
    let (h2, r2) = header("launch_drag.csv");
    assert_eq!(h1, h2);
    assert_eq!(r1.len(), r2.len());
    let speed = h1.iter().position(|c| c == "speed_m_s").unwrap();
    for (a, b) in r1.iter().zip(&r2) {
        let (a, b): (f64, f64) = (a[speed].parse().unwrap(), b[speed].parse().unwrap());
        assert!(b > a, "drag compensation must launch faster: {a} vs {b}");
    }
    // Deterministic whatever the thread count; solution.json given directly works too.
    let sol = out.join("solution.json");
    let (ok, _, err) = bsa(&[
        "budget",
        sol.to_str().unwrap(),
        "--samples",
        "300",
        "--search-samples",
        "40",
        "--threads",
        "2",
        "-q",
    ]);
    assert!(ok, "{err}");
    let json2 = std::fs::read_to_string(out.join("budget.json")).unwrap();
    assert_eq!(json1, json2);

    // Bad input: clear errors, no panic.
    for (args, expect) in [
        (vec!["--rho", "-1"], "air density"),
        (vec!["--cd", "-0.5"], "drag coefficient"),
        (vec!["--speed-tol", "80"], "speed tolerance"),
        (vec!["--timing-tol", "-2"], "timing tolerance"),
        (vec!["--samples", "0"], "samples"),
        (vec!["--iou-threshold", "0"], "IoU threshold"),
        (vec!["--iou-threshold", "1.2"], "IoU threshold"),
        (vec!["--iou-threshold", "-0.5"], "IoU threshold"),
    ] {
        let (ok, _, err) = run(&args);
        assert!(!ok, "accepted {args:?}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(err.contains(expect), "{args:?}: {err}");
    }
    let (ok, _, err) = bsa(&["budget", "scenes", "-q"]);
    assert!(!ok && err.contains("no solution.json"), "{err}");
    // A solution of another scene.
    let other = variant("budget-other", |v| v["name"] = "other".into());
    let (ok, _, err) = run(&["--scene", other.to_str().unwrap()]);
    assert!(!ok && err.contains("does not belong"), "{err}");
    // The same scene, edited after the solve.
    let edited = variant("budget-edited", |v| {
        v["occluders"][0]["position"] = serde_json::json!([0.2, -2.0, 0.6])
    });
    let (ok, _, err) = run(&["--scene", edited.to_str().unwrap()]);
    assert!(!ok && err.contains("edited"), "{err}");
}
