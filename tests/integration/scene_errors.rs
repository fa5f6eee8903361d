//! Bad scenes get clear errors: `bsa check` fails without a panic, naming the file and
//! the field at fault.

use std::path::Path;

use crate::util::{bsa, tmpdir, variant};

/// `bsa check` on a bad scene must fail cleanly, naming the file and the field.
pub fn assert_rejected(dir: &Path, expect: &[&str]) {
    let (ok, _, err) = bsa(&["check", dir.to_str().unwrap()]);
    assert!(!ok, "accepted a bad scene in {}", dir.display());
    assert!(!err.contains("panicked"), "panicked: {err}");
    for e in expect {
        assert!(err.contains(e), "error message lacks `{e}`:\n{err}");
    }
}

#[test]
fn missing_scene_folder_is_named() {
    let (ok, _, err) = bsa(&["check", "scenes/does-not-exist"]);
    assert!(
        !ok && err.contains("does-not-exist") && !err.contains("panicked"),
        "{err}"
    );
}

#[test]
fn malformed_json_and_unknown_fields_are_refused() {
    // Malformed JSON.
    let d = tmpdir("malformed");
    std::fs::write(d.join("scene.json"), "{ \"t\": 1.2, ").unwrap();
    assert_rejected(&d, &["scene.json", "EOF"]);

    // Unknown field.
    let d = variant("unknown", |v| v["colour"] = "red".into());
    assert_rejected(&d, &["scene.json", "unknown field `colour`"]);
}

#[test]
fn a_file_the_scene_names_is_refused_naming_the_scene_the_field_and_the_file() {
    // Missing: the scene, its field and the file it names.
    let d = variant("target-missing", |v| v["target"] = "nowhere.png".into());
    assert_rejected(
        &d,
        &[
            "scene.json",
            "field `target`",
            "nowhere.png",
            "does not exist",
        ],
    );
    // There but unreadable (a folder: even root cannot read it as a file): said so, with
    // the system's reason.
    let d = variant("hints-unreadable", |v| v["hints"] = "hints.txt".into());
    std::fs::create_dir(d.join("hints.txt")).unwrap();
    assert_rejected(
        &d,
        &[
            "scene.json",
            "field `hints`",
            "hints.txt",
            "cannot be read: ",
        ],
    );
}

#[test]
fn occluder_named_after_an_export_node_is_refused_at_load() {
    // An occluder named after a node of the glTF export: refused when the scene is
    // loaded, not after the solve when the export runs.
    let d = variant("reserved", |v| v["occluders"][1]["name"] = "table".into());
    assert_rejected(&d, &["scene.json", "occluders[1].name", "`table`"]);
}

#[test]
fn target_that_is_not_a_png_or_has_no_dark_pixel_is_refused() {
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
}

#[test]
fn non_positive_time_radius_size_and_mass_are_refused() {
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
}

#[test]
fn infinity_and_nan_in_scene_hints_and_obj_are_refused() {
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
}

#[test]
fn obj_with_no_faces_is_refused() {
    let d = variant("nofaces", |v| {
        v["occluders"][0]["shape"] = serde_json::json!({"mesh": {"obj": "empty.obj"}});
    });
    std::fs::write(d.join("empty.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    assert_rejected(&d, &["empty.obj", "occluders[0].shape.mesh.obj"]);
}

#[test]
fn light_on_or_behind_the_receiver_is_refused() {
    let d = variant("lighton", |v| {
        v["light"] = serde_json::json!([0.0, 0.0, 0.0])
    });
    assert_rejected(&d, &["`light`", "behind the receiver"]);
    let d = variant("lightbehind", |v| {
        v["light"] = serde_json::json!([0.0, 0.0, -3.0])
    });
    assert_rejected(&d, &["`light`", "behind the receiver"]);
}

#[test]
fn hint_naming_a_missing_occluder_is_refused() {
    let d = variant("hint", |v| v["hints"][1]["occluder"] = "nose".into());
    assert_rejected(&d, &["hints[1].occluder", "`nose`"]);
}

#[test]
fn occluders_overlapping_at_launch_are_refused() {
    let d = variant("overlap", |v| {
        v["occluders"][1]["position"] = serde_json::json!([0.3, -1.8, 0.6])
    });
    assert_rejected(&d, &["`head` and `left_ear` overlap"]);
}

#[test]
fn gravity_that_does_not_pull_down_is_refused() {
    for (name, g) in [("gravityup", 9.81), ("gravityflat", 0.0)] {
        let d = variant(name, |v| v["gravity"] = serde_json::json!([0.0, 0.0, g]));
        assert_rejected(&d, &["scene.json", "`gravity`", "must pull down"]);
    }
}

#[test]
fn a_light_nearer_the_receiver_than_a_body_is_thick_is_refused() {
    // Mickey's head is 1.2 m across: under a light 0.3 m up it solved to IoU 0.06 with
    // no word of why.
    let d = variant("lightlow", |v| {
        v["light"] = serde_json::json!([0.0, 0.0, 0.3])
    });
    assert_rejected(
        &d,
        &[
            "scene.json",
            "`light`",
            "0.3000 m",
            "`head`",
            "1.2000 m thick",
        ],
    );
    // A light just above the head's width is allowed.
    let d = variant("lightjust", |v| {
        v["light"] = serde_json::json!([0.0, 0.0, 1.25])
    });
    let (ok, _, err) = bsa(&["check", d.to_str().unwrap()]);
    assert!(ok, "{err}");
}

#[test]
fn instants_outside_a_hundredth_of_a_second_to_a_minute_are_refused() {
    // A tiny `t` is named as itself, in a short form, not blamed on the timestep.
    let d = variant("ttiny", |v| v["t"] = 1e-300.into());
    assert_rejected(&d, &["`t`", "at least 0.01 s", "1e-300"]);
    let d = variant("thour", |v| v["t"] = 3600.0.into());
    assert_rejected(&d, &["`t`", "at most 60"]);
}

#[test]
fn a_start_spin_of_more_than_2000_rad_by_t_is_refused() {
    // 5000 rad/s is under the speed limit (1e4) but would turn the ear 6000 rad by
    // t = 1.2 s: the solver treats such a sample as diverged, so every body's shadow
    // would silently be missing.
    let d = variant("spin", |v| {
        v["occluders"][1]["start_angular_velocity"] = serde_json::json!([0.0, 0.0, 5000.0])
    });
    assert_rejected(
        &d,
        &[
            "occluders[1].start_angular_velocity",
            "6000 rad",
            "at most 1666.7 rad/s",
        ],
    );
}

#[test]
fn a_stage_whose_weights_are_all_zero_is_refused() {
    for (name, w) in [
        ("weights0", serde_json::json!({"xor": 0.0, "hint": 0.0})),
        ("weightsempty", serde_json::json!({})),
    ] {
        let d = variant(name, move |v| v["stages"][0]["weights"] = w.clone());
        assert_rejected(&d, &["stages[0].weights", "nothing to optimise"]);
    }
}

#[test]
fn wrong_values_inside_enums_name_their_path() {
    // A shape of two kinds, and a hint's pixel of three numbers: serde alone says "expected
    // value" and "did not match any variant".
    let d = variant("twokinds", |v| {
        v["occluders"][1]["shape"] =
            serde_json::json!({"sphere": {"radius": 0.3}, "box": {"size": [0.1, 0.1, 0.1]}});
    });
    assert_rejected(&d, &["`occluders[1].shape`", "give one of"]);
    let d = variant("shapefield", |v| {
        v["occluders"][1]["shape"] = serde_json::json!({"sphere": {"radius": 0.3, "r": 1}});
    });
    assert_rejected(&d, &["`occluders[1].shape`", "unknown field `r`"]);
    let d = variant("pixel3", |v| {
        v["hints"][1]["pixel"] = serde_json::json!([1.0, 2.0, 3.0])
    });
    assert_rejected(&d, &["`hints`", "hint [1]", "`pixel`"]);
    let d = variant("launchedtext", |v| {
        v["occluders"][2]["launched"] = "yes".into()
    });
    assert_rejected(&d, &["`occluders[2].launched`", "expected a boolean"]);
}

#[cfg(unix)]
#[test]
fn endless_files_are_refused_instead_of_read() {
    // A device as the mesh or the target: there is no length to check, and it never ends.
    let d = variant("devmesh", |v| {
        v["occluders"][0]["shape"] = serde_json::json!({"mesh": {"obj": "/dev/zero"}});
    });
    assert_rejected(&d, &["occluders[0].shape.mesh.obj", "not a regular file"]);
    let d = variant("devtarget", |v| v["target"] = "/dev/zero".into());
    assert_rejected(&d, &["/dev/zero", "256 MiB"]);
}

#[test]
fn a_weight_out_of_range_states_the_range_weights_take() {
    let d = variant("hintweight", |v| v["hints"][0]["weight"] = 1e13.into());
    assert_rejected(&d, &["hints[0].weight", "from 0 to 1e12", "1e13"]);
}

#[test]
fn a_scene_launcher_out_of_range_or_misspelt_is_refused_naming_its_field() {
    let d = variant("launcher-range", |v| {
        v["launcher"] = serde_json::json!({"orientation_deg": 90.0})
    });
    assert_rejected(
        &d,
        &["scene.json", "launcher", "orientation tolerance", "45"],
    );
    let d = variant("launcher-field", |v| {
        v["launcher"] = serde_json::json!({"orientation": 0.5})
    });
    assert_rejected(&d, &["scene.json", "unknown field `orientation`"]);
}
