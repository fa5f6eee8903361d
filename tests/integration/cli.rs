//! The command line end to end: `bsa check`, `solve` with every output file, `eval`
//! reading a solution back, and clear errors from `export`, `validate`, `blend` and
//! `video` when their input is missing, corrupt or belongs to another scene, or their
//! options are out of range.

use std::path::Path;
use std::process::Command;

use crate::util::{
    bsa, quick_solve, read_json, root, shared_quick_solve, solve, tmpdir, value_after, variant,
    zero_tolerances,
};

#[test]
fn check_accepts_mickey() {
    let (ok, out, err) = bsa(&["check", "scenes/mickey"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("scene `mickey`") && out.contains("ok"),
        "{out}"
    );
    // What a solve will cost, before it runs: its time, samples and memory.
    let cost = out
        .lines()
        .find(|l| l.contains("cost"))
        .expect("a cost line");
    assert!(
        cost.contains("a solve takes about")
            && cost.contains("samples at most")
            && cost.contains("of memory"),
        "{cost}"
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

/// `blend`, `video` and `validate` refuse bad options with the option's name, before any
/// work.
#[test]
fn bad_options_of_blend_and_video() {
    let d = tmpdir("blend-options");
    let dir = d.to_str().unwrap();
    // A .blend given to `video` (only its existence is checked before the options).
    let given = d.join("given.blend");
    std::fs::write(&given, b"not read").unwrap();
    let given = given.to_str().unwrap();
    let solution = d.join("solution.json");
    let solution = solution.to_str().unwrap();
    for (args, says) in [
        // An --out that would put the film over a solve's own files, or into a folder.
        (
            vec!["blend", dir, "--out", solution],
            "must name a .blend file",
        ),
        (
            vec!["video", dir, "--out", solution],
            "must name a .mp4 file",
        ),
        (vec!["video", dir, "--out", dir], "is a folder"),
        // Options that build a .blend, with a .blend to render as it is.
        (
            vec!["video", dir, "--blend", given, "--slowmo"],
            "--slowmo builds the .blend",
        ),
        (
            vec!["video", dir, "--blend", given, "--fps", "30"],
            "--fps builds the .blend",
        ),
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
        // An IoU is from 0 to 1.
        (
            vec!["validate", dir, "--min-iou", "1.5"],
            "--min-iou must be an IoU from 0 to 1, got 1.5",
        ),
        (
            vec!["validate", dir, "--min-iou", "-0.1"],
            "--min-iou must be",
        ),
        (
            vec!["validate", dir, "--min-iou", "NaN"],
            "--min-iou must be",
        ),
        (
            vec!["validate", dir, "--min-iou", "inf"],
            "--min-iou must be",
        ),
    ] {
        let (ok, _, err) = bsa(&args);
        assert!(
            !ok && err.contains(says) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

/// An interpreter that exits 0 without running Blender's script (`/bin/true`) is named,
/// and the missing result line said: the message was "failed (exit status: 0)".
#[test]
fn a_python_that_ends_without_the_scripts_result_line_is_named() {
    let out = quick_solve(&root().join("scenes/mickey"), "python-true");
    let dir = out.to_str().unwrap();
    for (cmd, script) in [
        ("blend", "make_blend.py"),
        ("video", "make_blend.py"),
        ("validate", "render_shadow.py"),
    ] {
        let (ok, _, err) = bsa(&[cmd, dir, "--python", "/bin/true"]);
        assert!(
            !ok && err.contains(&format!("{script} ended without its result line"))
                && err.contains("under the interpreter /bin/true")
                && err.contains("--python")
                && !err.contains("exit status: 0"),
            "{cmd}: {err}"
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

/// A closed OBJ cube of half side `half` (m), centred on the origin.
fn cube_obj(path: &Path, half: f64) {
    let mut text = String::new();
    for z in [-half, half] {
        for (x, y) in [(-half, -half), (half, -half), (half, half), (-half, half)] {
            text.push_str(&format!("v {x} {y} {z}\n"));
        }
    }
    text.push_str("f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

/// A `w` x `h` picture, black where `dark` holds, white elsewhere.
fn picture(path: &Path, w: u32, h: u32, dark: impl Fn(u32, u32) -> bool) {
    image::GrayImage::from_fn(w, h, |x, y| image::Luma([if dark(x, y) { 0 } else { 255 }]))
        .save(path)
        .unwrap();
}

/// A 64 x 48 picture of a disc of radius 4 pixels: a sphere of 0.1 m on the default
/// 1.6 m wide picture.
fn disc(path: &Path) {
    picture(path, 64, 48, |x, y| {
        let (dx, dy) = (x as i64 - 32, y as i64 - 24);
        dx * dx + dy * dy <= 16
    });
}

/// `bsa new` in `cwd` (relative paths are the user's): (success, stdout, stderr).
fn new_in(cwd: &Path, target: &Path, objects: &str, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec![
        "new",
        "out",
        "--target",
        target.to_str().unwrap(),
        "--objects",
        objects,
    ];
    args.extend_from_slice(extra);
    bsa_in(cwd, &args)
}

#[test]
fn new_says_at_what_width_its_objects_can_draw_the_thin_parts() {
    // A disc 50 px across on six legs 2 px wide and 50 long, a third of the picture, at
    // 1.6 m over 160 px: legs 2 cm wide, for blocks whose least side (3.5 cm) casts at
    // least 3.9 cm. Their shadows spill over the legs whatever the solve does.
    let d = tmpdir("new-thin");
    let target = d.join("thin.png");
    picture(&target, 160, 120, |x, y| {
        let (dx, dy) = (x as i64 - 80, y as i64 - 35);
        dx * dx + dy * dy <= 625
            || (60..110).contains(&y)
                && [40, 60, 70, 90, 100, 120]
                    .iter()
                    .any(|&l| (l..l + 2).contains(&x))
    });
    let blocks = "box:0.14x0.07x0.035*4";
    let (ok, _, err) = new_in(&d, &target, blocks, &["--choose-by", "start"]);
    assert!(ok, "{err}");
    let thin = "narrower than the narrowest shadow the objects cast (3.9 cm)";
    assert!(err.contains(thin), "{err}");
    let width: f64 =
        value_after(&err, "at --width ").unwrap_or_else(|| panic!("no width in: {err}"));
    assert!(width > 1.6, "{err}");
    // At that width the legs are as wide as the blocks' shadows.
    let w = width.to_string();
    let wider = tmpdir("new-thin-wider");
    let (ok, _, err) = new_in(
        &wider,
        &target,
        blocks,
        &["--choose-by", "start", "--width", &w],
    );
    assert!(ok && !err.contains("narrower than"), "{err}");
    // The same block as an automatic item, and no --width: bsa new takes that width
    // itself, says so and writes it, and so leaves no thin parts to tell of.
    let auto = tmpdir("new-thin-auto");
    let (ok, out, err) = new_in(
        &auto,
        &target,
        "auto:box:0.14x0.07x0.035",
        &["--choose-by", "start"],
    );
    assert!(ok && !err.contains("narrower than"), "{err}");
    let taken: f64 =
        value_after(&out, "a picture ").unwrap_or_else(|| panic!("no width taken: {out}"));
    assert_eq!(taken, width, "{out}");
    let scene = read_json(&auto.join("out/scene.json"));
    assert_eq!(scene["receiver"]["width"].as_f64(), Some(width));
}

#[test]
fn new_names_a_missing_mesh_as_typed_and_never_reads_one_beside_the_scene() {
    // The file is missing where the user's path points (the current folder) but there
    // is one of that name inside the output folder: before the fix the scene read that
    // one instead, or an error named `out/obj/...`, a path the user never typed.
    let d = tmpdir("new-mesh-missing");
    let target = d.join("disc.png");
    disc(&target);
    cube_obj(&d.join("out/obj/cube.obj"), 0.05);
    let (ok, _, err) = new_in(&d, &target, "mesh:obj/cube.obj", &["--choose-by", "start"]);
    assert!(!ok, "a mesh was read from beside the scene: {err}");
    assert!(
        err.contains("--objects")
            && err.contains("item 1 `mesh:obj/cube.obj`")
            && err.contains("cannot read the OBJ file obj/cube.obj")
            && err.contains("relative to the current folder")
            && !err.contains("out/obj"),
        "{err}"
    );
    // In a JSON list: the file and the entry, and the path as the list's folder makes it.
    std::fs::create_dir_all(d.join("lists")).unwrap();
    std::fs::write(
        d.join("lists/box.json"),
        r#"[{"kind": "sphere", "radius": 0.1}, {"kind": "mesh", "obj": "cube.obj"}]"#,
    )
    .unwrap();
    let (ok, _, err) = new_in(&d, &target, "lists/box.json", &[]);
    assert!(
        !ok && err.contains("--objects lists/box.json")
            && err.contains("objects[1].obj")
            && err.contains("lists/cube.obj")
            && !err.contains("out/"),
        "{err}"
    );
    // Where it is, the scene names it so that it is found from any folder.
    cube_obj(&d.join("obj/cube.obj"), 0.05);
    let (ok, _, err) = new_in(&d, &target, "mesh:obj/cube.obj", &["--choose-by", "start"]);
    assert!(ok, "{err}");
    let (ok, _, err) = bsa(&["check", d.join("out").to_str().unwrap()]);
    assert!(ok, "{err}");
}

#[test]
fn new_tells_an_object_too_large_for_the_picture_by_its_item_not_by_a_scratch_file() {
    // A cube of +-5e5 m overlapped the table of the first (scratch) scene, and the error
    // named that file and its occluder.
    let d = tmpdir("new-mesh-huge");
    let target = d.join("disc.png");
    disc(&target);
    cube_obj(&d.join("obj/big.obj"), 5e5);
    for objects in ["mesh:obj/big.obj", "sphere:0.1,mesh:obj/big.obj"] {
        let (ok, _, err) = new_in(&d, &target, objects, &[]);
        assert!(!ok && !err.contains("panicked"), "{objects}: {err}");
        assert!(
            err.contains("--objects: mesh:obj/big.obj (1.732e6 m across)")
                && err.contains("larger than the 1.60 x 1.20 m picture")
                && !err.contains(".bsa-new")
                && !err.contains("overlap"),
            "{objects}: {err}"
        );
    }
}

#[test]
fn new_refuses_an_empty_item_and_an_unknown_key_of_a_json_list() {
    let d = tmpdir("new-empty-item");
    let target = d.join("disc.png");
    disc(&target);
    let (ok, _, err) = new_in(&d, &target, "sphere:0.1,,sphere:0.1", &[]);
    assert!(
        !ok && err.contains("--objects") && err.contains("item 2 is empty"),
        "{err}"
    );
    std::fs::write(
        d.join("list.json"),
        r#"{"objects": [{"kind": "sphere", "radius": 0.1}], "extra": 1}"#,
    )
    .unwrap();
    let (ok, _, err) = new_in(&d, &target, "list.json", &[]);
    assert!(
        !ok && err.contains("--objects list.json") && err.contains("extra: unknown key"),
        "{err}"
    );
}

#[test]
fn new_says_a_count_above_the_maximum_is_too_many_not_malformed() {
    let d = tmpdir("new-count-huge");
    let target = d.join("disc.png");
    disc(&target);
    let (ok, _, err) = new_in(
        &d,
        &target,
        "sphere:0.1*1000000000000000000000000000000",
        &[],
    );
    assert!(
        !ok && err.contains("is more than the 64 objects a list may hold")
            && !err.contains("not a whole number"),
        "{err}"
    );
}

#[test]
fn new_names_the_auto_item_and_the_picture_when_no_object_is_worth_launching() {
    // A one-pixel line: every shadow of a 0.1 m cube (at least 10 x 10 pixels) covers a
    // row of it at most.
    let d = tmpdir("new-nothing-worth");
    let target = d.join("line.png");
    picture(&target, 160, 120, |x, y| y == 60 && (20..140).contains(&x));
    let (ok, _, err) = new_in(&d, &target, "auto:box:0.1x0.1x0.1", &[]);
    assert!(!ok && !err.contains("panicked"), "{err}");
    assert!(
        err.contains("--objects auto:box:0.1x0.1x0.1")
            && err.contains(&format!("--target {}", target.display()))
            && err.contains("120 dark pixels")
            && err.contains("smaller objects")
            && err.contains("--width"),
        "{err}"
    );
}

#[test]
fn new_refuses_a_picture_whose_dark_part_is_smaller_than_any_shadow_of_the_objects() {
    let d = tmpdir("new-dot");
    // One dark pixel (0.025 m) against spheres of 0.1 m: designed and solved to IoU
    // 0.014 before the fix, with no word.
    let dot = d.join("dot.png");
    picture(&dot, 64, 48, |x, y| x == 10 && y == 10);
    let (ok, _, err) = new_in(&d, &dot, "sphere:0.1*2", &["--choose-by", "start"]);
    assert!(!ok, "{err}");
    assert!(
        err.contains(&format!("--target {}", dot.display()))
            && err.contains("dark part (1 pixel of 64 x 48")
            && err.contains("--objects sphere:0.1")
            && err.contains("--width 6.549 or more"),
        "{err}"
    );
    // A 2 x 2 dot in 8000 x 8000 pixels: 71 s of designs and trial solves to IoU 0
    // before the fix; now refused before any design.
    let huge = d.join("huge.png");
    picture(&huge, 8000, 8000, |x, y| {
        (3999..4001).contains(&x) && (3999..4001).contains(&y)
    });
    let start = std::time::Instant::now();
    let (ok, _, err) = new_in(&d, &huge, "sphere:0.1*2", &[]);
    assert!(
        !ok && err.contains("dark part (4 pixels of 8000 x 8000"),
        "{err}"
    );
    assert!(start.elapsed().as_secs() < 30, "{:?}", start.elapsed());
    // The disc a sphere of 0.1 m casts is a picture it can draw.
    let disc_png = d.join("disc.png");
    disc(&disc_png);
    let (ok, _, err) = new_in(&d, &disc_png, "sphere:0.1", &["--choose-by", "start"]);
    assert!(ok, "{err}");
}

#[test]
fn new_says_how_the_solver_treats_a_contact_as_the_scene_it_wrote_does() {
    // A light 0.1 m high keeps the flights low: two long thin sticks' start guess
    // lands before t. The scene is written with the default contacts mode (a
    // constraint), and the message said "the solver treats it as a penalty".
    let d = tmpdir("new-contact-mode");
    let target = root().join("scenes/mickey/target.png");
    let (ok, out, err) = new_in(
        &d,
        &target,
        "box:0.6x0.02x0.02*2",
        &["--light-height", "0.1", "--choose-by", "start"],
    );
    assert!(ok, "{err}");
    assert!(out.contains("with a contact at"), "{out}");
    let scene = std::fs::read_to_string(d.join("out/scene.json")).unwrap();
    assert!(!scene.contains("penalty"), "{scene}");
    assert!(
        !out.contains("penalty") && out.contains("the solver ranks launches without one first"),
        "{out}"
    );
}

#[test]
fn new_refuses_a_light_lower_than_an_object_is_thick() {
    // Spheres 0.2 m across under a light 0.1 m up were designed and solved (the old
    // version of the test above used them) though no launch can pass one whole
    // between the light and the picture.
    let d = tmpdir("new-light-too-low");
    let target = root().join("scenes/mickey/target.png");
    let (ok, _, err) = new_in(
        &d,
        &target,
        "box:0.3x0.05x0.05,sphere:0.1*2",
        &["--light-height", "0.15"],
    );
    assert!(!ok, "accepted");
    assert!(
        err.contains("--light-height 0.150")
            && err.contains("--objects sphere:0.1 is 0.200 m thick")
            && err.contains("raise the light above 0.200 m")
            && !err.contains("probe"),
        "{err}"
    );
    assert!(!d.join("out").exists(), "left a folder behind");
    // `bsa plant` says it in its options' terms too, not of its scratch scene.
    let planted = d.join("planted");
    let (ok, _, err) = bsa(&[
        "plant",
        planted.to_str().unwrap(),
        "--objects",
        "sphere:0.2",
        "--light-height",
        "0.3",
    ]);
    assert!(!ok, "accepted");
    assert!(
        err.contains("--light-height 0.3: object `sphere_1` of --objects is 0.400 m thick")
            && !err.contains(".bsa-plant"),
        "{err}"
    );
    assert!(!planted.exists(), "left a folder behind");
}

#[test]
fn new_and_plant_say_one_object_not_one_objects() {
    let d = tmpdir("new-one-object");
    let target = d.join("disc.png");
    disc(&target);
    let (ok, out, err) = new_in(&d, &target, "sphere:0.1", &["--choose-by", "start"]);
    assert!(ok && out.contains("out: 1 object;"), "{out}{err}");
    let (ok, out, err) = bsa_in(&d, &["plant", "planted", "--objects", "sphere:0.15"]);
    assert!(ok && out.contains("planted: 1 object,"), "{out}{err}");
}

#[test]
fn budget_errors_name_the_flag_to_change() {
    let out = quick_solve(&root().join("scenes/mickey"), "budget-flags");
    let dir = out.to_str().unwrap();
    for (flag, value, says) in [
        ("--rho", "-1", "air density"),
        ("--cd", "-0.5", "drag coefficient"),
        ("--speed-tol", "80", "speed tolerance"),
        ("--direction-tol", "-1", "direction tolerance"),
        ("--spin-tol", "200", "spin tolerance"),
        ("--timing-tol", "-2", "timing tolerance"),
        ("--position-tol", "200", "position tolerance"),
        ("--orientation-tol", "-1", "orientation tolerance"),
        ("--spin-floor-tol", "99", "spin floor tolerance"),
        ("--cd-tol", "99", "cd tolerance"),
        ("--samples", "0", "samples"),
        ("--search-samples", "100000000", "search samples"),
        ("--threads", "0", "threads"),
        ("--iou-threshold", "1.2", "IoU threshold"),
    ] {
        let (ok, _, err) = bsa(&["budget", dir, flag, value, "-q"]);
        assert!(!ok && !err.contains("panicked"), "{flag} {value}: {err}");
        assert!(
            err.contains(&format!("error: {flag}: ")) && err.contains(says),
            "{flag} {value}: {err}"
        );
    }
    // A launcher file: a misspelt field and a value out of range, each named with it.
    let file = out.join("launcher.json");
    std::fs::write(&file, r#"{"direction": 0.1}"#).unwrap();
    let (ok, _, err) = bsa(&["budget", dir, "--launcher", file.to_str().unwrap(), "-q"]);
    assert!(
        !ok && err.contains("launcher.json") && err.contains("unknown field `direction`"),
        "{err}"
    );
    std::fs::write(&file, r#"{"position_mm": 500}"#).unwrap();
    let (ok, _, err) = bsa(&["budget", dir, "--launcher", file.to_str().unwrap(), "-q"]);
    assert!(
        !ok && err.contains("launcher.json: the position tolerance"),
        "{err}"
    );
    // No launch error at all: every Monte Carlo launch would be the same one.
    let (zeros, says) = zero_tolerances(8);
    let (ok, _, err) = bsa(&[&["budget", dir][..], &zeros, &["-q"]].concat());
    assert!(!ok && err.contains(&format!("error: {says}")), "{err}");
}

/// Tiny and huge numbers the user gave read as written (1e-300), in the summary, the
/// Markdown, the plots, the report page and the errors; `{}` printed three hundred
/// digits.
#[test]
fn budget_prints_tiny_and_huge_numbers_in_exponent_form() {
    let out = quick_solve(&root().join("scenes/mickey"), "budget-exponents");
    let dir = out.to_str().unwrap();
    let digits = |text: &str| text.contains("0000000000") || text.contains("9999999999");
    let (ok, stdout, err) = bsa(&[
        "budget",
        dir,
        "--iou-threshold",
        "1e-300",
        "--speed-tol",
        "1e-300",
        "--samples",
        "40",
        "--search-samples",
        "40",
        "-q",
    ]);
    assert!(ok, "{err}");
    assert!(
        stdout.contains("P(IoU >= 1e-300)") && stdout.contains("speed 1e-300 %"),
        "{stdout}"
    );
    assert!(!digits(&stdout), "{stdout}");
    for file in [
        "budget.md",
        "report.html",
        "budget_hist.svg",
        "budget_tolerances.svg",
    ] {
        let text = std::fs::read_to_string(out.join(file)).unwrap();
        assert!(text.contains("1e-300"), "{file}: {text}");
        assert!(!digits(&text), "{file} has a long run of digits");
    }
    for (flag, says) in [
        ("--iou-threshold", "at most 1, got 1e300"),
        ("--speed-tol", "between 0 and 50 %, got 1e300"),
        ("--rho", "kg/m^3, got 1e300"),
        ("--cd", "between 0 and 10, got 1e300"),
    ] {
        let (ok, _, err) = bsa(&["budget", dir, flag, "1e300", "-q"]);
        assert!(!ok && err.contains(says) && !digits(&err), "{flag}: {err}");
    }
}

#[test]
fn resume_goes_on_as_the_solve_was_started_or_says_why_not() {
    // A different seed, or air or launch errors for the remaining stages only, would
    // silently mix two solves in one record.
    let scene = root().join("scenes/mickey");
    let out = quick_solve(&scene, "resume-options");
    let dir = out.parent().unwrap().to_str().unwrap();
    let out = out.to_str().unwrap();
    for (extra, says) in [
        (vec!["--seed", "99"], "not --seed 99"),
        (vec!["--air"], "in vacuum, not --air"),
        (vec!["--robust"], "without launch errors, not --robust"),
    ] {
        let mut args = vec!["solve", dir, "--out", out, "--resume", "-q"];
        args.extend(extra.iter().copied());
        let (ok, _, err) = bsa(&args);
        assert!(!ok && err.contains(says), "{extra:?}: {err}");
    }
}

#[test]
fn budget_and_solve_refuse_more_threads_than_the_limit() {
    let scene = root().join("scenes/mickey");
    let out = quick_solve(&scene, "threads-limit");
    let (ok, _, err) = bsa(&["budget", out.to_str().unwrap(), "--threads", "100000"]);
    assert!(
        !ok && err.contains("--threads") && err.contains("256"),
        "{err}"
    );
    let (ok, _, err) = bsa(&["solve", scene.to_str().unwrap(), "--threads", "1000"]);
    assert!(
        !ok && err.contains("--threads must be between 1 and 256"),
        "{err}"
    );
}

#[test]
fn a_solution_file_given_for_its_folder_and_a_robust_tolerance_name_what_to_change() {
    let scene = root().join("scenes/mickey");
    let out = quick_solve(&scene, "file-for-folder");
    let file = out.join("solution.json");
    let (ok, _, err) = bsa(&["export", file.to_str().unwrap()]);
    assert!(
        !ok && err.contains("is a file: give the solve's output folder"),
        "{err}"
    );
    let (ok, _, err) = bsa(&[
        "solve",
        scene.to_str().unwrap(),
        "--robust",
        "--speed-tol",
        "-1",
        "--out",
        out.with_file_name("robust").to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("--speed-tol:"), "{err}");
}

#[test]
fn a_refused_resume_does_not_call_the_damaged_file_the_best_so_far() {
    let scene = root().join("scenes/mickey");
    let out = quick_solve(&scene, "resume-damaged");
    let file = out.join("solution.json");
    let text = std::fs::read_to_string(&file).unwrap();
    std::fs::write(&file, &text[..text.len() / 2]).unwrap();
    let dir = out.parent().unwrap();
    let (ok, _, err) = bsa(&[
        "solve",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resume",
        "-q",
    ]);
    assert!(!ok && err.contains("cannot resume from"), "{err}");
    assert!(!err.contains("best so far"), "{err}");
}

#[test]
fn a_solution_whose_scene_file_is_gone_names_the_recorded_path() {
    let scene = root().join("scenes/mickey");
    let out = quick_solve(&scene, "scene-gone");
    let file = out.join("solution.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    v["scene"] = "gone-scene".into();
    v["scene_file"] = "../nowhere/scene.json".into();
    std::fs::write(&file, serde_json::to_string(&v).unwrap()).unwrap();
    let (ok, _, err) = bsa(&["export", out.to_str().unwrap()]);
    assert!(
        !ok && err.contains("nowhere/scene.json") && err.contains("--scene"),
        "{err}"
    );
}

/// A solution whose recorded scene file is not a scene: the error names the solution
/// and the scene file, for `export` and `budget` alike (it named the scene file alone).
#[test]
fn a_recorded_scene_that_is_no_scene_is_named_with_its_solution() {
    let solved = shared_quick_solve("mickey");
    let d = tmpdir("bad-recorded-scene");
    let scene = d.join("scene.json");
    std::fs::write(&scene, "not a scene").unwrap();
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let mut solution = read_json(&solved.join("solution.json"));
    solution["scene_file"] = scene.display().to_string().into();
    std::fs::write(
        out.join("solution.json"),
        serde_json::to_string_pretty(&solution).unwrap(),
    )
    .unwrap();
    let file = out.join("solution.json");
    for args in [vec!["export"], vec!["budget", "-q"]] {
        let mut args = args;
        args.insert(1, out.to_str().unwrap());
        let (ok, _, err) = bsa(&args);
        let first = err.lines().next().unwrap_or("");
        assert!(
            !ok && first.contains(&file.display().to_string())
                && first.contains(&scene.display().to_string())
                && err.contains("expected")
                && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

/// A solution.json that cannot be read is reported as unreadable, with the OS reason,
/// not as missing. Run as root, which reads the file whatever its mode, the test says
/// so and checks nothing (the unit test
/// `an_unreadable_solution_is_named_unreadable_not_missing` checks the wording on a
/// permission error of the OS).
#[test]
fn an_unreadable_solution_is_not_called_missing() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmpdir("unreadable-solution");
    let file = d.join("solution.json");
    // Never read, so any content will do.
    std::fs::write(&file, "{}").unwrap();
    std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o000)).unwrap();
    if std::fs::read(&file).is_ok() {
        // Root: the commands would read the solution and run in full.
        eprintln!("note: {} is readable after chmod 000 (running as root): the permission error is not checked here", file.display());
        return;
    }
    for cmd in ["export", "budget"] {
        let (ok, _, err) = bsa(&[cmd, d.to_str().unwrap(), "--scene", "scenes/mickey"]);
        assert!(!err.contains("no solution.json"), "{cmd}: {err}");
        assert!(
            !ok && err.contains("cannot read")
                && err.contains(&file.display().to_string())
                && err.contains("ermission denied"),
            "{cmd}: {err}"
        );
    }
    std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o644)).unwrap();
}
