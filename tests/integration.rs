//! The one integration-test binary: the `bsa` command line end to end, bad input,
//! determinism across thread counts, resume, the golden shadow image, and the Mickey
//! solve itself.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use bsa::evaluate::Problem;
use bsa::solver::{self, Observer, SampleRecord, Solution, SolveOptions};

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
    let now =
        bsa::picture::mask_image(ws.mask.width(), ws.mask.height(), &|x, y| ws.mask.get(x, y));
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
        let diff = bsa::picture::difference_image(
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
