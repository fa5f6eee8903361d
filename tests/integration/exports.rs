//! Exports of a solve: the animated glTF gives back the solver's poses at t, the launch
//! and trajectory tables, the Khronos validator's verdict on every example scene, and the
//! error budget (`bsa budget`).

use std::process::Command;

use bsa::evaluate::Problem;

use crate::util::{bsa, example_scenes, quick_solve, require, root, shared_quick_solve, variant};

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
        // launch.csv prints micrometres per second, the precision a launcher can use.
        assert!((speed - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).abs() <= 5e-7);
    }
    let traj = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(traj.starts_with("time_s,occluder,phase,x_m,y_m,z_m,qx,qy,qz,qw"));
    // 72 steps to t, the key at t, then a key per step until every body is at rest
    // (more than the 0.25 s hold, less than the 30 s cap), 3 occluders each.
    let rows = traj.lines().count() - 1;
    assert_eq!(rows % 3, 0);
    let keys = rows / 3;
    assert!(keys > 72 + 1 + 15 && keys < 72 + 1 + 30 * 60, "{keys} keys");
    // Each body's quaternion keeps its sign from key to key (q and -q are one rotation,
    // but a reader interpolating the table would swing the long way round).
    let mut last: std::collections::HashMap<String, [f64; 4]> = Default::default();
    for line in traj.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let q: Vec<f64> = f[6..10].iter().map(|x| x.parse().unwrap()).collect();
        let q = [q[0], q[1], q[2], q[3]];
        if let Some(p) = last.insert(f[1].to_string(), q) {
            let dot: f64 = (0..4).map(|k| p[k] * q[k]).sum();
            assert!(dot > 0.0, "sign flip at {line}");
        }
    }
}

/// The motion after t runs until every body is at rest, so the last frame of every
/// export (trajectory.csv and the glb's animation) shows every body at rest: between the
/// last two keys no point of any body moves faster than the stated threshold (1 cm/s),
/// measured here from the files' poses alone.
#[test]
fn every_export_ends_with_every_body_at_rest() {
    use bsa::sim::continuation::{point_speed, REST_HOLD_S, REST_SPEED_M_S};
    for scene in example_scenes() {
        let name = scene.file_name().unwrap().to_str().unwrap().to_string();
        let out = shared_quick_solve(&name);
        let problem = Problem::new(bsa::scene::load(&scene).unwrap());
        let radius: Vec<f64> = problem
            .scene
            .occluders
            .iter()
            .map(|o| o.shape.bounding_radius(glam::DVec3::ZERO))
            .collect();
        // trajectory.csv: each occluder's last two rows.
        let mut r = csv::Reader::from_path(out.join("trajectory.csv")).unwrap();
        let mut keys: std::collections::BTreeMap<String, Vec<(f64, glam::DVec3, glam::DQuat)>> =
            Default::default();
        for row in r.records() {
            let row = row.unwrap();
            let f = |k: usize| row[k].parse::<f64>().unwrap();
            keys.entry(row[1].to_string()).or_default().push((
                f(0),
                glam::DVec3::new(f(3), f(4), f(5)),
                glam::DQuat::from_xyzw(f(6), f(7), f(8), f(9)),
            ));
        }
        let mut fastest: f64 = 0.0;
        for (i, o) in problem.scene.occluders.iter().enumerate() {
            let k = &keys[&o.name];
            let (a, b) = (k[k.len() - 2], k[k.len() - 1]);
            let s = point_speed((a.1, a.2), (b.1, b.2), b.0 - a.0, radius[i]);
            assert!(
                s < REST_SPEED_M_S,
                "{name}: {} moves at {s} m/s at the end",
                o.name
            );
            fastest = fastest.max(s);
            // At rest for the whole hold, not just over the last step.
            let hold = (REST_HOLD_S / problem.scene.dt) as usize;
            let a = k[k.len() - 1 - hold];
            let drift = a.1.distance(b.1);
            assert!(
                drift < REST_SPEED_M_S * REST_HOLD_S,
                "{name}: {} drifts {drift} m",
                o.name
            );
        }
        // The glb's animation: the same, from its last two keys.
        let glb = std::fs::read(out.join(format!("{name}.glb"))).unwrap();
        let end = keys.values().next().unwrap().last().unwrap().0;
        let dt = problem.scene.dt;
        let a = bsa::output::gltf::read_poses_at(&glb, end - dt).unwrap();
        let b = bsa::output::gltf::read_poses_at(&glb, end).unwrap();
        for (i, o) in problem.scene.occluders.iter().enumerate() {
            let pa = a.iter().find(|(n, _, _)| n == &o.name).unwrap();
            let pb = b.iter().find(|(n, _, _)| n == &o.name).unwrap();
            let s = point_speed((pa.1, pa.2), (pb.1, pb.2), dt, radius[i]);
            assert!(
                s < REST_SPEED_M_S,
                "{name}.glb: {} moves at {s} m/s at the end",
                o.name
            );
        }
        eprintln!("{name}: last key at {end:.3} s, fastest point {fastest:.2e} m/s");
    }
}

#[test]
#[ignore = "needs the Khronos validator (npm ci in tools/gltf-validator); run by scripts/test.sh"]
fn khronos_validator_finds_no_errors_or_warnings() {
    require(
        &root().join("tools/gltf-validator/node_modules/gltf-validator"),
        "npm ci in tools/gltf-validator",
    );
    for scene in example_scenes() {
        let name = scene.file_name().unwrap().to_str().unwrap().to_string();
        let out = shared_quick_solve(&name);
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
        assert_eq!(v["hints"], 0, "{name}: {v}");
        // The only infos: texture coordinates of untextured meshes (balls, receiver,
        // table), which are there for the artist.
        for m in v["messages"].as_array().unwrap() {
            let m = m.as_str().unwrap();
            assert!(
                m.starts_with("info UNUSED_OBJECT") && m.contains("/attributes/TEXCOORD_0"),
                "{name}: {m}"
            );
        }
    }
}

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
