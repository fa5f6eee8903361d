//! The command line end to end: `bsa check`, `solve` with every output file, `eval`
//! reading a solution back, and clear errors from `export`, `validate`, `blend` and
//! `video` when their input is missing, corrupt or belongs to another scene, or their
//! options are out of range.

use std::path::Path;
use std::process::Command;

use crate::util::{bsa, quick_solve, root, solve, tmpdir, variant};

#[test]
fn check_accepts_mickey() {
    let (ok, out, err) = bsa(&["check", "scenes/mickey"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("scene `mickey`") && out.contains("ok"),
        "{out}"
    );
}

/// Cut every stage of a scene's JSON to `iterations` of `population` samples.
fn short_stages(v: &mut serde_json::Value, iterations: usize, population: usize) {
    for s in v["stages"].as_array_mut().unwrap() {
        s["max_iterations"] = iterations.into();
        s["population"] = population.into();
    }
}

#[test]
fn solve_says_when_a_shadow_reaches_beyond_the_picture() {
    // A fourth ball that stays on the table far to the side: its shadow lies outside the
    // picture, and the solve says so by name.
    let d = variant("cli-outside", |v| {
        v["occluders"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({
                "name": "aside", "shape": { "sphere": { "radius": 0.3 } },
                "position": [3.5, 0.0, 0.3], "mass": 1.0, "launched": false
            }));
        short_stages(v, 3, 8);
    });
    let stdout = solve(&d, &d.join("out"), &[]);
    let note = stdout
        .lines()
        .find(|l| l.starts_with("note: at t the shadow"))
        .unwrap_or_else(|| panic!("no note: {stdout}"));
    assert!(note.contains("aside"), "{note}");
    assert!(!note.contains("head"), "{note}");
}

#[test]
fn solve_and_eval_from_the_command_line() {
    // A short run of the real command (few iterations) writes every output file, and
    // `eval` reads the solution back.
    let d = variant("cli", |v| short_stages(v, 5, 12));
    let out = d.join("out");
    let stdout = solve(&d, &out, &["--report"]);
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
        "convergence.svg",
        "report.html",
        "mickey.glb",
        "launch.csv",
        "trajectory.csv",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
        // solve says what it wrote: every file, not only the exports.
        assert!(stdout.contains(f), "solve did not list {f}: {stdout}");
    }
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let solution: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("solution.json")).unwrap()).unwrap();
    let samples = solution["samples"].as_u64().unwrap() as usize;
    // Two stages of 5 iterations of 12 samples, and the moves tried before each run.
    assert!(samples >= 2 * 5 * 12, "{samples} samples");
    assert_eq!(
        csv.lines().count(),
        1 + samples,
        "one row per sample plus the header"
    );
    assert!(csv.starts_with(
        "stage_number,iteration,d0,d1,d2,xor,inner,outer,contact,reg,hint,barrier,total"
    ));
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
        ok && stdout.contains("xor")
            && stdout.contains("d0 (0th moment)")
            && stdout.contains("total"),
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

#[test]
fn bad_input_to_export_validate_and_video() {
    // Missing solution.
    let empty = tmpdir("export-empty");
    for cmd in ["export", "validate", "blend", "video"] {
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
    // A corrupt .glb (`blend` and `video` export it again from the solution first).
    std::fs::write(out.join("mickey.glb"), b"glTF garbage").unwrap();
    let (ok, _, err) = bsa(&["validate", out.to_str().unwrap()]);
    assert!(
        !ok && err.contains("not a valid glTF") && !err.contains("panicked"),
        "{err}"
    );
    // A missing .glb.
    std::fs::remove_file(out.join("mickey.glb")).unwrap();
    let (ok, _, err) = bsa(&["validate", out.to_str().unwrap()]);
    assert!(!ok && err.contains("run `bsa export"), "{err}");
    // A corrupt solution.
    std::fs::write(out.join("solution.json"), "[1, 2").unwrap();
    let (ok, _, err) = bsa(&["export", out.to_str().unwrap()]);
    assert!(!ok && err.contains("not a valid solution file"), "{err}");
}

/// `blend` and `video` refuse bad options with the option's name, before any work.
#[test]
fn bad_options_of_blend_and_video() {
    let d = tmpdir("blend-options");
    let dir = d.to_str().unwrap();
    for (args, says) in [
        (vec!["blend", dir, "--fps", "0"], "--fps must be"),
        (vec!["blend", dir, "--fps", "1000"], "--fps must be"),
        (
            vec!["blend", dir, "--resolution", "1920"],
            "--resolution must be WIDTHxHEIGHT",
        ),
        (
            vec!["blend", dir, "--resolution", "axb"],
            "--resolution must be WIDTHxHEIGHT",
        ),
        (
            vec!["blend", dir, "--resolution", "12x5"],
            "each side must be 16 to 16384",
        ),
        (
            vec!["video", dir, "--resolution", "161x90"],
            "even width and height",
        ),
        (
            vec!["video", dir, "--samples", "0"],
            "--samples must be at least 1",
        ),
        (
            vec!["video", dir, "--seconds", "-1"],
            "--seconds must be positive",
        ),
        (
            vec!["video", dir, "--blend", "/nonexistent/a.blend"],
            "--blend /nonexistent/a.blend: no such file",
        ),
    ] {
        let (ok, _, err) = bsa(&args);
        assert!(
            !ok && err.contains(says) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

/// Runs `bsa` in `cwd`: (success, stdout, stderr).
fn bsa_in(cwd: &Path, args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_bsa"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run bsa");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn copied_scene_with_the_original_name_never_touches_the_originals_results() {
    // A short Mickey in folder `mickey`, and a copy in folder `mickey_copy` that keeps
    // the JSON name `mickey` but has another t (the trap of issue #15).
    let base = tmpdir("trap");
    let src = variant("trap-src", |v| {
        short_stages(v, 3, 8);
    });
    let copy_scene = |folder: &str, t: Option<f64>| {
        let d = base.join(folder);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::copy(src.join("target.png"), d.join("target.png")).unwrap();
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(src.join("scene.json")).unwrap())
                .unwrap();
        if let Some(t) = t {
            v["t"] = t.into();
        }
        std::fs::write(d.join("scene.json"), v.to_string()).unwrap();
        d
    };
    let original = copy_scene("mickey", None);
    let copy = copy_scene("mickey_copy", Some(1.1));
    let work = base.join("work");
    std::fs::create_dir_all(&work).unwrap();
    let (ok, stdout, err) = bsa_in(&work, &["check", copy.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(
        stdout.contains("export/mickey_copy/"),
        "check must say where: {stdout}"
    );

    let (ok, _, err) = bsa_in(&work, &["solve", original.to_str().unwrap(), "-q"]);
    assert!(ok, "{err}");
    let results = work.join("export/mickey");
    let before = std::fs::read(results.join("solution.json")).unwrap();
    std::fs::write(results.join("budget.md"), "the original's budget").unwrap();

    // The copy goes to its own folder by default.
    let (ok, _, err) = bsa_in(&work, &["solve", copy.to_str().unwrap(), "-q"]);
    assert!(ok, "{err}");
    assert!(work.join("export/mickey_copy/solution.json").is_file());
    assert_eq!(
        std::fs::read(results.join("solution.json")).unwrap(),
        before
    );
    assert!(results.join("budget.md").is_file());

    // Sent into the original's folder, it stops with a clear message and writes nothing.
    let (ok, _, err) = bsa_in(
        &work,
        &[
            "solve",
            copy.to_str().unwrap(),
            "-q",
            "--out",
            "export/mickey",
        ],
    );
    assert!(!ok);
    assert!(
        err.contains("holds the results of") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(results.join("solution.json")).unwrap(),
        before
    );
    assert!(results.join("budget.md").is_file());

    // With --force it replaces them and removes the stale budget.
    let (ok, _, err) = bsa_in(
        &work,
        &[
            "solve",
            copy.to_str().unwrap(),
            "-q",
            "--out",
            "export/mickey",
            "--force",
        ],
    );
    assert!(ok, "{err}");
    assert_ne!(
        std::fs::read(results.join("solution.json")).unwrap(),
        before
    );
    assert!(!results.join("budget.md").exists(), "stale budget kept");
}
