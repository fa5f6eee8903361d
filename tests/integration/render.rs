//! `bsa render`: the shadow of any launch, from a solve's `solution.json`, its
//! `launch.csv` or a minimal launch file, and clear errors for launch files that do not
//! fit the scene.

use std::path::Path;

use crate::util::{bsa, quick_solve, read_json, root, solve, tmpdir, value_after};

fn render(scene: &Path, launch: &Path, out: &Path) -> (bool, String, String) {
    bsa(&[
        "render",
        scene.to_str().unwrap(),
        "--solution",
        launch.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn render_reproduces_the_solves_shadow_from_solution_json_and_launch_csv() {
    for name in ["mickey", "fly"] {
        let scene = root().join("scenes").join(name);
        let solved = quick_solve(&scene, &format!("render-{name}"));
        let scene_file = solved.parent().unwrap();
        let want = std::fs::read(solved.join("shadow.png")).unwrap();
        for launch in ["solution.json", "launch.csv"] {
            let out = solved.join(format!("render-{launch}"));
            let (ok, stdout, err) = render(scene_file, &solved.join(launch), &out);
            assert!(ok && stdout.contains("IoU at"), "{name} {launch}: {err}");
            let got = std::fs::read(out.join("shadow.png")).unwrap();
            assert!(
                got == want,
                "{name}: shadow from {launch} differs from the solve's"
            );
            assert!(out.join("overlay.png").is_file());
        }
    }
}

#[test]
fn render_takes_a_minimal_launch_file_and_another_instant() {
    let d = tmpdir("render-minimal");
    let launch = d.join("launch.json");
    std::fs::write(
        &launch,
        r#"{"head": {"velocity": [0.0, 1.5, 6.35], "angular_velocity": [0.2, 0.5, 0.2]},
            "left_ear": {"velocity": [1.46, -0.39, 7.06]},
            "right_ear": {"velocity": [-1.46, -0.39, 7.06]}}"#,
    )
    .unwrap();
    let scene = root().join("scenes/mickey");
    let (ok, out, err) = render(&scene, &launch, &d.join("t"));
    assert!(ok, "{err}");
    // Near the seed-1 solution: the picture reads as Mickey.
    let iou: f64 = out.split("IoU at 1.2 s ").nth(1).unwrap()[..6]
        .parse()
        .unwrap();
    assert!(iou > 0.9, "{out}");
    let (ok, out, err) = bsa(&[
        "render",
        scene.to_str().unwrap(),
        "--solution",
        launch.to_str().unwrap(),
        "--out",
        d.join("early").to_str().unwrap(),
        "--at",
        "0.6",
    ]);
    assert!(ok && out.contains("IoU at 0.6 s"), "{err}");
    let (ok, _, err) = bsa(&[
        "render",
        scene.to_str().unwrap(),
        "--solution",
        launch.to_str().unwrap(),
        "--at",
        "5",
    ]);
    assert!(!ok && err.contains("after t"), "{err}");
}

#[test]
fn bad_launch_files_name_the_file_and_the_entry() {
    let d = tmpdir("render-bad");
    let scene = root().join("scenes/mickey");
    let cases: [(&str, &str, &[&str]); 9] = [
        (
            "null.json",
            r#"{"head": null, "left_ear": {"velocity": [1, 0, 7]}}"#,
            &["null.json", "`head`", "expected an entry"],
        ),
        (
            // Under the speed limit, but 2400 rad by t: the solver would not fly it, and
            // every shadow would silently be missing.
            "spin.json",
            r#"{"head": {"velocity": [0, 1, 6], "angular_velocity": [2000, 0, 0]},
                "left_ear": {"velocity": [1, 0, 7]}, "right_ear": {"velocity": [-1, 0, 7]}}"#,
            &["spin.json", "`head`", "`angular_velocity`", "2400 rad"],
        ),
        (
            "fast.csv",
            "name,vx_m_s,vy_m_s,vz_m_s,wx_rad_s,wy_rad_s,wz_rad_s\nhead,0,1,1e300,0,0,0\n",
            &["fast.csv", "row 2", "`velocity`", "1e300 m/s"],
        ),
        (
            "unknown.json",
            r#"{"head": {"velocity": [0, 1, 6]}, "left_ear": {"velocity": [1, 0, 7]},
                "right_ear": {"velocity": [-1, 0, 7]}, "nose": {"velocity": [0, 0, 1]}}"#,
            &["unknown.json", "`nose`", "no occluder"],
        ),
        (
            "missing.json",
            r#"{"head": {"velocity": [0, 1, 6]}}"#,
            &["missing.json", "no launch for occluder `left_ear`"],
        ),
        (
            "typo.json",
            r#"{"head": {"velocty": [0, 1, 6]}}"#,
            &["typo.json", "velocty"],
        ),
        (
            "missing.csv",
            "name,vx_m_s,vy_m_s,vz_m_s,wx_rad_s,wy_rad_s,wz_rad_s\nhead,0,1,6,0,0,0\n",
            &["missing.csv", "no launch for occluder `left_ear`"],
        ),
        (
            "nan.csv",
            "name,vx_m_s,vy_m_s,vz_m_s,wx_rad_s,wy_rad_s,wz_rad_s\nhead,0,NaN,6,0,0,0\n",
            &["nan.csv", "row 2", "`velocity` must be a finite number"],
        ),
        (
            "columns.csv",
            "name,vx,vy,vz\nhead,0,1,6\n",
            &["columns.csv", "no column `vx_m_s`"],
        ),
    ];
    for (file, text, expect) in cases {
        let path = d.join(file);
        std::fs::write(&path, text).unwrap();
        let (ok, _, err) = render(&scene, &path, &d.join("out"));
        assert!(!ok && !err.contains("panicked"), "{file}: {err}");
        for e in expect {
            assert!(err.contains(e), "{file}: expected `{e}` in: {err}");
        }
    }
}

#[test]
fn a_planted_problem_is_solvable_by_its_planted_launch() {
    let d = tmpdir("plant");
    let dir = d.join("three");
    let (ok, out, err) = bsa(&[
        "plant",
        dir.to_str().unwrap(),
        "--objects",
        "sphere:0.15,sphere:0.2*2",
        "--seed",
        "5",
        "--width",
        "4",
    ]);
    assert!(ok && out.contains("3 objects"), "{err}");
    let scene = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    assert!(scene.contains("\"hints\""), "{scene}");
    let (ok, out, err) = render(&dir, &dir.join("planted.json"), &d.join("render"));
    assert!(ok && out.contains("IoU at 1.2 s 1.0000"), "{out} {err}");
    assert!(out.contains("no contact before t"), "{out}");
}

#[test]
fn plant_refuses_bad_inventories_and_ones_that_cannot_fit() {
    let d = tmpdir("plant-bad");
    for (objects, extra, expect) in [
        ("cone:1", vec![], "unknown kind `cone`"),
        ("sphere:0.1,box:1x2", vec![], "item 2"),
        ("mesh:/nonexistent.obj", vec![], "/nonexistent.obj"),
        ("sphere:0.5*8", vec!["--width", "1"], "does not fit"),
    ] {
        let dir = d.join("p");
        let mut args = vec!["plant", dir.to_str().unwrap(), "--objects", objects];
        args.extend(extra);
        let (ok, _, err) = bsa(&args);
        assert!(!ok && !err.contains("panicked"), "{objects}: {err}");
        assert!(
            err.contains(expect),
            "{objects}: expected `{expect}` in: {err}"
        );
        // The scratch files are the command's own business, not the user's inputs.
        assert!(!err.contains(".bsa-new"), "{objects}: {err}");
    }
}

/// `bsa new DIR` of Mickey's target (a 4 m picture) with `objects`: (success, stdout,
/// stderr).
fn new_mickey(dir: &Path, objects: &str) -> (bool, String, String) {
    let target = root().join("scenes/mickey/target.png");
    bsa(&[
        "new",
        dir.to_str().unwrap(),
        "--target",
        target.to_str().unwrap(),
        "--objects",
        objects,
        "--width",
        "4",
    ])
}

#[test]
fn new_designs_a_scene_that_solve_takes_as_it_is() {
    let dir = tmpdir("new").into_child("mickey");
    let (ok, out, err) = new_mickey(&dir, "sphere:0.6,sphere:0.35*2");
    assert!(ok && out.contains("start guess IoU"), "{err}");
    // Three spheres for Mickey's three discs: nothing to note.
    assert!(!err.contains("note:"), "{err}");
    // A trial reaches 0.985 (`design::REPLACE_BELOW`), so the designs are not made
    // again with their objects placed anew.
    let trials = trials(&out);
    let (orders, kept) = (&trials.orders, &trials.kept.1);
    let best = finished(orders).fold(0.0, f64::max);
    assert!(best >= 0.985, "{out}");
    assert_eq!(orders.len(), 2, "{out}");
    assert!(!kept.contains("placed anew"), "{out}");
    // Exactly the three files: the designs tried under the other ceilings are gone.
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(files, ["scene.json", "start.png", "target.png"]);
    let (ok, _, err) = bsa(&["check", dir.to_str().unwrap()]);
    assert!(ok, "{err}");
}

#[test]
fn new_tells_when_the_objects_cannot_cover_the_picture() {
    // One small sphere for Mickey's head and two ears: most of the picture stays bare
    // whatever the solve does, and the user is told what to bring.
    let dir = tmpdir("new-few").into_child("mickey");
    let (ok, _, err) = new_mickey(&dir, "sphere:0.35");
    assert!(ok, "{err}");
    assert!(
        err.contains("note: the objects leave") && err.contains("% of the picture bare"),
        "{err}"
    );
    assert!(err.contains("auto:"), "{err}");
}

#[test]
fn new_refuses_pictures_objects_and_options_it_cannot_use() {
    let d = tmpdir("new-bad");
    let blank = d.join("blank.png");
    image::GrayImage::from_pixel(64, 48, image::Luma([255]))
        .save(&blank)
        .unwrap();
    let mickey = root().join("scenes/mickey/target.png");
    let m = mickey.to_str().unwrap();
    for (target, objects, extra, expect) in [
        (
            blank.to_str().unwrap(),
            "sphere:0.1",
            vec![],
            "no dark pixel",
        ),
        (
            m,
            "sphere:5",
            vec![],
            "--objects: sphere:5 (10.000 m across)",
        ),
        (m, "sphere:1e-9", vec![], "less than one pixel"),
        // Under a pixel at the lower ceilings of an auto: item of a given size (0.6 of
        // the light's height), though not at 0.8.
        (
            m,
            "auto:box:0.0004x0.0004x0.0004",
            vec![],
            "less than one pixel",
        ),
        (m, "mesh:Cargo.toml", vec![], "--objects: mesh:"),
        (m, "cube:1", vec![], "unknown kind `cube`"),
        (m, "box:1e300x1x1", vec![], "at most 1000, got 1e300"),
        (m, "sphere:0.1/-1e300", vec![], "kg/m^3, got -1e300"),
        (
            m,
            "mesh:/nonexistent/piece.obj",
            vec![],
            "/nonexistent/piece.obj",
        ),
        (m, "chess:emperor", vec![], "unknown chess piece `emperor`"),
        (m, "auto:chess*3", vec![], "drop *N"),
        (m, "sphere:0.1", vec!["--t", "0"], "--t"),
        (
            m,
            "sphere:0.1",
            vec!["--light-height", "-1"],
            "--light-height",
        ),
        ("/nonexistent.png", "sphere:0.1", vec![], "/nonexistent.png"),
    ] {
        let dir = d.join("s");
        let mut args = vec![
            "new",
            dir.to_str().unwrap(),
            "--target",
            target,
            "--objects",
            objects,
        ];
        args.extend(extra);
        let (ok, _, err) = bsa(&args);
        assert!(!ok && !err.contains("panicked"), "{objects}: {err}");
        assert!(
            err.contains(expect),
            "{objects}: expected `{expect}` in: {err}"
        );
    }
}

/// A 160 x 120 picture of two bars (a T), black on white.
/// The start guess's IoU that `bsa new` printed.
fn start_iou(out: &str) -> f64 {
    out.split("start guess IoU ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{out}"))
}

fn two_bars(path: &Path) {
    image::GrayImage::from_fn(160, 120, |x, y| {
        let bar = (30..130).contains(&x) && (20..34).contains(&y);
        let stem = (73..87).contains(&x) && (20..100).contains(&y);
        image::Luma([if bar || stem { 0 } else { 255 }])
    })
    .save(path)
    .unwrap();
}

#[test]
fn new_lays_blocks_along_strokes_with_two_hints_and_a_contact_free_start() {
    let d = tmpdir("new-blocks");
    let target = d.join("t.png");
    two_bars(&target);
    let dir = d.join("t");
    let (ok, out, err) = bsa(&[
        "new",
        dir.to_str().unwrap(),
        "--target",
        target.to_str().unwrap(),
        "--objects",
        "box:0.14x0.035x0.035*2",
        "--width",
        "0.8",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("no contact before t"), "{out}");
    let iou = start_iou(&out);
    assert!(iou > 0.6, "{out}");
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("scene.json")).unwrap()).unwrap();
    // Elongated blocks get both ends as hints; every start guess is explicit.
    assert_eq!(scene["hints"].as_array().unwrap().len(), 4);
    for o in scene["occluders"].as_array().unwrap() {
        assert!(o["start_velocity"].is_array() && o["start_angular_velocity"].is_array());
    }
    let (ok, check, err) = bsa(&["check", dir.to_str().unwrap()]);
    assert!(ok && check.contains("no contact before t"), "{check}{err}");
}

#[test]
fn new_reads_a_json_list_chess_pieces_and_chooses_a_count() {
    let d = tmpdir("new-json");
    let target = d.join("t.png");
    two_bars(&target);
    let list = d.join("objects.json");
    std::fs::write(
        &list,
        r#"[{"kind": "chess", "piece": "pawn", "count": 2}, {"kind": "box", "size": [0.05, 0.02, 0.02], "count": "auto"},
            {"kind": "box", "size": [0.02, 0.02, 0.02], "count": "auto", "at_most": 1}]"#,
    )
    .unwrap();
    let dir = d.join("j");
    let args = |objects: &str| {
        vec![
            "new".to_string(),
            dir.to_str().unwrap().to_string(),
            "--target".into(),
            target.to_str().unwrap().into(),
            "--objects".into(),
            objects.into(),
            "--width".into(),
            "0.4".into(),
            "--light-height".into(),
            "3".into(),
        ]
    };
    let run = |a: Vec<String>| bsa(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let (ok, out, err) = run(args(list.to_str().unwrap()));
    assert!(ok, "{err}");
    assert!(dir.join("pieces/pawn.obj").is_file());
    let chosen: usize = value_after(&out, " objects (").unwrap_or_else(|| panic!("{out}"));
    assert!(
        chosen >= 1 && out.contains("chosen by auto:, which stopped as"),
        "{out}"
    );
    // At most one cube, as the list says.
    let scene: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("scene.json")).unwrap()).unwrap();
    let cubes = scene["occluders"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|o| o["shape"]["box"]["size"] == serde_json::json!([0.02, 0.02, 0.02]))
        .count();
    assert!(cubes <= 1, "{cubes} cubes");
    // A JSON list's errors name the entry and the field.
    std::fs::write(&list, r#"[{"kind": "box", "size": [0.1, 0.1]}]"#).unwrap();
    let (ok, _, err) = run(args(list.to_str().unwrap()));
    assert!(!ok && err.contains("objects[0].size"), "{err}");
}

#[test]
fn new_tries_lower_ceilings_where_the_largest_block_would_span_a_bend() {
    // On 飞 with its six blocks, the design under the highest ceiling alone stretches a
    // long block over the stem and its bend (start IoU 0.852); a lower ceiling keeps it
    // on the straight part and reads better (0.869).
    let d = tmpdir("new-ceilings");
    let out = new_fly(&d.join("fly"), &["--choose-by", "start"]);
    assert!(!out.contains("trial solves"), "{out}");
    let iou = start_iou(&out);
    assert!(iou > 0.86, "{out}");
    assert!(out.contains("no contact before t"), "{out}");
}

/// `bsa new DIR` of 飞 with its six blocks and `extra` options, which must succeed; its
/// standard output.
fn new_fly(dir: &Path, extra: &[&str]) -> String {
    let target = root().join("scenes/fly/target.png");
    let mut args = vec![
        "new",
        dir.to_str().unwrap(),
        "--target",
        target.to_str().unwrap(),
        "--objects",
        "box:0.2794x0.06985x0.0349*2,box:0.1397x0.06985x0.0349*4",
    ];
    args.extend_from_slice(extra);
    let (ok, out, err) = bsa(&args);
    assert!(ok, "{err}");
    out
}

/// What `bsa new` printed of its trial solves: the ceilings, each order's trial IoUs
/// (`None` for a design that an earlier one made too, "same"; `Some(None)` for one the
/// race of the designs left behind before its last stage), the second round's ceilings
/// and orders when it ran (labelled "..., placed anew"), and the ceiling and order it
/// kept.
struct Trials {
    ceilings: Vec<f64>,
    anew_under: Vec<f64>,
    orders: Vec<(String, Vec<Option<Option<f64>>>)>,
    kept: (f64, String),
}

impl Trials {
    /// The kept design's trial: `Some(None)` if the race left it behind.
    fn kept_trial(&self) -> Option<Option<f64>> {
        let (ceiling, order) = &self.kept;
        let under = match order.ends_with("placed anew") {
            true => &self.anew_under,
            false => &self.ceilings,
        };
        let at = under.iter().position(|c| c == ceiling).unwrap();
        self.orders.iter().find(|o| &o.0 == order).unwrap().1[at]
    }
}

/// The IoUs of the designs that ran every stage of their trial.
fn finished(orders: &[(String, Vec<Option<Option<f64>>>)]) -> impl Iterator<Item = f64> + '_ {
    orders
        .iter()
        .flat_map(|o| o.1.iter().flatten().flatten().copied())
}

/// The trial solves' line of `bsa new`'s output, parsed ([`Trials`]).
fn trials(out: &str) -> Trials {
    let line = out
        .lines()
        .find(|l| l.contains("trial solves under ceilings "))
        .unwrap_or_else(|| panic!("{out}"));
    // A design the race left behind: its IoU where it stopped, marked.
    let mut marked = String::new();
    for (k, part) in line.split(" (raced out after ").enumerate() {
        match k {
            0 => marked.push_str(part),
            _ => {
                marked.push('~');
                marked.push_str(part.split_once("stages)").map_or(part, |p| p.1));
            }
        }
    }
    let line = marked.as_str();
    let between = |after: &str, before: &str| -> String {
        let s = line.split(after).nth(1).unwrap_or_else(|| panic!("{line}"));
        s.split(before).next().unwrap().to_string()
    };
    let numbers =
        |list: &str| -> Vec<f64> { list.split(" / ").map(|v| v.parse().unwrap()).collect() };
    let ceilings = numbers(&between("ceilings ", " of the"));
    let mut anew_under = Vec::new();
    let mut orders = Vec::new();
    for (round, part) in between("IoU ", "; kept")
        .split("; placed anew under ")
        .enumerate()
    {
        let part = match round {
            0 => part,
            _ => {
                let (under, part) = part.split_once(": ").unwrap_or_else(|| panic!("{line}"));
                anew_under = numbers(under);
                part
            }
        };
        for order in part.split("), ") {
            let (ious, label) = order.split_once(" (").unwrap_or_else(|| panic!("{line}"));
            let ious = ious
                .split(" / ")
                .map(|v| (v != "same").then(|| (!v.ends_with('~')).then(|| v.parse().unwrap())))
                .collect();
            let label = label.trim_end_matches(')');
            let label = match round {
                0 => label.to_string(),
                _ => format!("{label}, placed anew"),
            };
            orders.push((label, ious));
        }
    }
    let kept = between("kept the design under ", "\n")
        .split_once(", ")
        .map(|(c, o)| (c.parse().unwrap(), o.to_string()))
        .unwrap_or_else(|| panic!("{line}"));
    Trials {
        ceilings,
        anew_under,
        orders,
        kept,
    }
}

#[test]
fn new_keeps_the_design_that_solves_best_and_solve_ends_where_its_trial_did() {
    // On 飞 the design with the best start (under 0.7) is not the one that solves best
    // (under 0.6: 0.949 against 0.943 with seed 1).
    let d = tmpdir("new-trials");
    let dir = d.join("fly");
    let out = new_fly(&dir, &[]);
    let t = trials(&out);
    assert_eq!(t.ceilings.len(), 4, "{out}");
    // Fly's trials end under 0.985 (`design::REPLACE_BELOW`), so its designs are made
    // again with the objects placed anew, and the best of both rounds is kept.
    let labels: Vec<&str> = t.orders.iter().map(|o| o.0.as_str()).collect();
    assert_eq!(
        labels,
        [
            "largest object first",
            "best fit first",
            "largest object first, placed anew",
            "best fit first, placed anew"
        ],
        "{out}"
    );
    // The second round is made under the ceilings of the first round's two best trials
    // (`design::ANEW_CEILINGS`), best first.
    let mut first: Vec<(f64, f64)> = t.orders[..2]
        .iter()
        .flat_map(|o| t.ceilings.iter().zip(&o.1))
        .filter_map(|(&c, iou)| Some(((*iou)??, c)))
        .collect();
    first.sort_by(|a, b| b.partial_cmp(a).unwrap());
    let mut best_ceilings: Vec<f64> = Vec::new();
    for (_, c) in first {
        if !best_ceilings.contains(&c) {
            best_ceilings.push(c);
        }
    }
    assert_eq!(t.anew_under, best_ceilings[..2], "{out}");
    // Every design is solved once: the first order's all, the second's where it
    // differs; the race (one rung, `compose::RUNGS`) runs each to its end.
    assert!(t.orders[0].1.iter().all(Option::is_some), "{out}");
    assert!(t.orders[..2].iter().all(|o| o.1.len() == 4), "{out}");
    assert!(t.orders[2..].iter().all(|o| o.1.len() == 2), "{out}");
    assert!(!t.orders.iter().any(|o| o.1.contains(&Some(None))), "{out}");
    let best = finished(&t.orders).fold(0.0, f64::max);
    assert_eq!(t.kept_trial(), Some(Some(best)), "{out}");
    // The written scene is the design that was tried: its solve's last stage ends where
    // the trial did, and its polish (which the trials leave out, with the trades; fly's
    // solve takes none) goes on from there to a picture no worse. One attempt: a second
    // one starts from the same design with another seed, and may end better elsewhere.
    let solved = d.join("out");
    solve(&dir, &solved, &["--attempts", "1"]);
    let solution = read_json(&solved.join("solution.json"));
    let iou = solution["iou"].as_f64().unwrap();
    let stages = solution["stages"].as_array().unwrap();
    let stop = stages.last().unwrap()["stop"].as_str().unwrap();
    let polished: Vec<f64> = stop
        .split("polished ")
        .nth(1)
        .and_then(|s| s.split(", IoU ").nth(1))
        .map(|s| s.split(" to ").filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| panic!("no polish in `{stop}`"));
    assert_eq!(polished.len(), 2, "{stop}");
    assert!(
        (polished[0] - best).abs() < 1e-4 && (polished[1] - iou).abs() < 1e-4,
        "solve {iou} ({stop}), trial {best}: {out}"
    );
    assert!(iou >= best, "solve {iou}, trial {best}");
    // The example in scenes/fly is this design, byte for byte: the examples come from
    // `bsa new`, and a change of the design shows here until they are made again.
    let designed = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    let committed = std::fs::read_to_string(root().join("scenes/fly/scene.json")).unwrap();
    assert!(
        designed == committed,
        "scenes/fly/scene.json is not what `bsa new` designs today: run bash scripts/make-examples.sh"
    );
}

#[test]
fn eval_of_a_launch_table_points_to_render() {
    let d = tmpdir("eval-csv");
    let table = d.join("launch.csv");
    std::fs::write(&table, "name,vx_m_s\n").unwrap();
    let scene = root().join("scenes/mickey");
    let (ok, _, err) = bsa(&[
        "eval",
        scene.to_str().unwrap(),
        "--solution",
        table.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("launch.csv") && err.contains("bsa render"),
        "{err}"
    );
}

#[test]
fn new_for_a_launcher_keeps_a_shorter_hop_that_reads_more_often_and_writes_its_frontier() {
    let dir = tmpdir("new-launcher").into_child("mickey");
    let target = root().join("scenes/mickey/target.png");
    let args = |extra: &[&str]| -> Vec<String> {
        let mut a: Vec<String> = ["new", dir.to_str().unwrap(), "--target"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        a.push(target.to_str().unwrap().to_string());
        a.extend(["--objects", "sphere:0.6,sphere:0.35*2", "--width", "4"].map(String::from));
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    // A launcher file with a misspelt field is refused before any design, naming it.
    let bad = dir.with_file_name("bad-launcher.json");
    std::fs::write(&bad, r#"{"speed": 0.5}"#).unwrap();
    let a = args(&["--launcher", bad.to_str().unwrap()]);
    let (ok, _, err) = bsa(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        !ok && err.contains("bad-launcher.json") && err.contains("unknown field `speed`"),
        "{err}"
    );
    let a = args(&["--launcher"]);
    let (ok, out, err) = bsa(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{err}");
    let line = out
        .lines()
        .find(|l| l.contains("for the launcher, kept the design at t = "))
        .unwrap_or_else(|| panic!("{out}"));
    let number_after = |text: &str, key: &str| -> f64 {
        let rest = &text[text.find(key).unwrap_or_else(|| panic!("{key}: {text}")) + key.len()..];
        rest.split([' ', ',', '%']).next().unwrap().parse().unwrap()
    };
    // Mickey's balls reach their poses at any instant: a shorter hop misses by less.
    let t = number_after(line, "at t = ");
    assert!(t < 1.2, "{line}");
    let kept = number_after(line, "IoU - 0.05) ");
    let standard = number_after(line, "(the standard design: IoU ");
    assert!(standard > 0.99, "{line}");
    let standard_p = number_after(&line[line.find("standard design").unwrap()..], ", ");
    assert!(kept > standard_p, "{line}");
    // The frontier beside the scene, and the launcher in it.
    for f in [
        "frontier.md",
        "frontier.csv",
        "frontier.png",
        "frontier.svg",
        "scene.json",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let scene: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("scene.json")).unwrap()).unwrap();
    assert_eq!(scene["launcher"]["direction_deg"], 0.25);
    assert_eq!(scene["t"].as_f64(), Some(t));
    let md = std::fs::read_to_string(dir.join("frontier.md")).unwrap();
    assert_eq!(md.matches("**kept**").count(), 1, "{md}");
    assert!(
        md.contains("| 1.2 | at rest, spun |") && md.contains("| in its pose |"),
        "{md}"
    );
    // The solve's report says what launcher it needs and shows the frontier.
    let out_dir = dir.with_file_name("mickey-out");
    let (ok, solved, err) = bsa(&[
        "solve",
        dir.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(ok && solved.contains("launcher it needs"), "{err}");
    let page = std::fs::read_to_string(out_dir.join("report.html")).unwrap();
    assert!(
        page.contains("What launcher it needs")
            && page.contains("The designs tried for the launcher")
    );
}
