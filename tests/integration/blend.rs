//! `bsa blend` and `bsa video` through Blender: every example's .blend shows the picture
//! large from its view camera at the marker `t`; at 24, 25, 30 and 60 fps `t` is a whole
//! frame where Cycles draws the rasterizer's shadow; EEVEE draws it too; the slow motion
//! keeps it on screen; the video and its contact sheet are written. They need Blender's
//! bpy (`.venv-blender`), so they are ignored by plain `cargo test` and run by
//! `scripts/test.sh`. Renders are small and use one sample: these check geometry and
//! timing, not looks.

use std::path::Path;

use crate::util::{
    blender_script, bsa, bsa_leaving_no_temporaries, last_key_time, root, shared_full_solve,
    shared_quick_solve,
};

/// `bsa blend <dir> <args>`; the .blend written.
fn blend(dir: &Path, name: &str, out: &str, args: &[&str]) -> std::path::PathBuf {
    let file = dir.join(out);
    let mut a = vec![
        "blend",
        dir.to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
    ];
    a.extend_from_slice(args);
    let (ok, stdout, err) = bsa(&a);
    assert!(ok, "{name}: {err}");
    assert!(stdout.contains("marker `t` on frame"), "{stdout}");
    file
}

/// `blender/check_blend.py -- --blend FILE <args>`: its report.
fn check(file: &Path, args: &[&str]) -> serde_json::Value {
    let mut a = vec!["--blend", file.to_str().unwrap()];
    a.extend_from_slice(args);
    blender_script("check_blend.py", &a)
}

/// The shadow scene's mask of `file` in `engine` (at the marker `t`, or `--frame`) into
/// `png`, without the view: the report.
fn mask(file: &Path, png: &Path, extra: &[&str]) -> serde_json::Value {
    let mut a = vec!["--no-view", "--mask", png.to_str().unwrap()];
    a.extend_from_slice(extra);
    check(file, &a)
}

/// IoU of the dark pixels (< 128) of two grayscale PNGs of one size.
fn iou(a: &Path, b: &Path) -> f64 {
    let a = image::open(a).unwrap().to_luma8();
    let b = image::open(b).unwrap().to_luma8();
    assert_eq!(a.dimensions(), b.dimensions());
    let (mut inter, mut union) = (0u64, 0u64);
    for (p, q) in a.pixels().zip(b.pixels()) {
        let (p, q) = (p.0[0] < 128, q.0[0] < 128);
        inter += u64::from(p && q);
        union += u64::from(p || q);
    }
    inter as f64 / union.max(1) as f64
}

/// Every example's .blend, as an artist opens it: 24 fps, the marker `t` on a whole frame,
/// frames from the launch to the rest, the view camera (16:9) active at 1920 x 1080, the
/// shadow scene with the orthographic camera at the target's size, and at the marker's
/// frame the shadow picture's bounding box takes at least 40 % of the view's height.
#[test]
#[ignore = "needs Blender's bpy in .venv-blender (bash blender/setup_venv.sh); run by scripts/test.sh"]
fn every_example_blend_shows_the_picture_large_at_t() {
    for name in ["mickey", "fly", "tbc", "thinker"] {
        let dir = shared_full_solve(name);
        let file = blend(&dir, name, &format!("{name}.blend"), &[]);
        let v = check(&file, &[]);
        eprintln!("{name}: view {}", v["view"]);
        assert_eq!(v["fps"], 24.0, "{v}");
        assert_eq!(v["t_frame_whole"], true, "{v}");
        assert_eq!(v["frame_start"], 0, "{v}");
        let last = last_key_time(&dir);
        let end = v["frame_end"].as_f64().unwrap();
        // The last key (every body at rest), moved by less than a frame.
        assert!(
            end >= last * 24.0 - 1e-3 && end <= last * 24.0 + 2.0,
            "{name}: {end} vs {last} s"
        );
        assert_eq!(v["camera"], "camera_view");
        assert_eq!(v["camera_type"], "PERSP");
        assert_eq!(v["resolution"], serde_json::json!([1920, 1080]));
        assert_eq!(v["shadow_camera_type"], "ORTHO");
        assert_eq!(v["shadow_resolution"], serde_json::json!([640, 480]));
        assert_eq!(v["light_radius_m"], 0.0);
        let f = v["view"]["fraction"].as_f64().unwrap();
        assert!(
            f >= 0.4,
            "{name}: the picture takes {f} of the frame's height"
        );
    }
}

/// At 24, 25, 30 and 60 fps, on Mickey and fly: `t` is a whole frame (the launch shifted
/// by less than a frame), every body is keyed there, and Cycles from the shadow scene at
/// that frame draws the rasterizer's shadow (IoU >= 0.995), with nothing hidden by hand:
/// the shadow camera's clipping keeps the bodies out of its view.
#[test]
#[ignore = "needs Blender's bpy in .venv-blender (bash blender/setup_venv.sh); run by scripts/test.sh"]
fn t_is_a_whole_frame_where_cycles_draws_the_rasterizers_shadow_at_any_fps() {
    for name in ["mickey", "fly"] {
        let dir = shared_full_solve(name);
        for fps in [24, 25, 30, 60] {
            let file = blend(
                &dir,
                name,
                &format!("{name}_{fps}.blend"),
                &["--fps", &fps.to_string()],
            );
            let png = dir.join(format!("mask_{fps}.png"));
            let v = mask(&file, &png, &[]);
            assert_eq!(v["fps"], fps as f64);
            assert_eq!(v["t_frame_whole"], true, "{v}");
            let t_frame = v["t_frame"].as_f64().unwrap();
            assert!((t_frame - 1.2 * fps as f64).abs() < 1.0, "{v}");
            // Two channels (location, rotation) of three or four components per body.
            assert!(v["channels_keyed_at_t"].as_u64().unwrap() >= 6, "{v}");
            assert_eq!(v["mask"]["covered_pixels"], 640 * 480);
            let i = iou(&png, &dir.join("shadow.png"));
            eprintln!("{name} at {fps} fps: t on frame {t_frame}, Cycles vs rasterizer IoU {i:.5}");
            assert!(i >= 0.995, "{name} at {fps} fps: IoU {i}");
        }
    }
}

/// EEVEE, with the file's own light, world and shadow settings (only the samples lowered),
/// draws the hard shadow from the shadow scene at `t`: IoU >= 0.95 against the target and
/// against the rasterizer. Headless EEVEE runs on software OpenGL here: one frame.
#[test]
#[ignore = "needs Blender's bpy in .venv-blender (bash blender/setup_venv.sh); run by scripts/test.sh"]
fn eevee_draws_the_hard_shadow_at_t() {
    let dir = shared_full_solve("mickey");
    let file = blend(&dir, "mickey", "mickey_eevee.blend", &[]);
    let png = dir.join("eevee_mask.png");
    let v = mask(&file, &png, &["--engine", "EEVEE"]);
    let target = iou(&png, &root().join("scenes/mickey/target.png"));
    let raster = iou(&png, &dir.join("shadow.png"));
    let m = &v["mask"];
    eprintln!(
        "EEVEE at t: IoU {target:.4} vs target, {raster:.4} vs rasterizer; lit {} shadow {}; {} s",
        m["lit_mean"], m["shadow_mean"], m["render_seconds"]
    );
    assert!(target >= 0.95 && raster >= 0.95, "{target} {raster}");
    let ratio = m["lit_mean"].as_f64().unwrap() / m["shadow_mean"].as_f64().unwrap().max(1e-9);
    assert!(ratio >= 2.0, "lit / shadow {ratio}");
}

/// With --slowmo the readable picture (IoU >= 0.9 of its value at t) stays on screen at
/// least 0.5 s: Cycles at the first and last frames of that window still draws it, and t
/// is still a whole frame. With --curves each body's flight is a curve that neither casts
/// a shadow nor lights the scene (the picture at t is unchanged).
#[test]
#[ignore = "needs Blender's bpy in .venv-blender (bash blender/setup_venv.sh); run by scripts/test.sh"]
fn slow_motion_keeps_the_picture_on_screen_and_curves_cast_no_shadow() {
    let dir = shared_full_solve("fly");
    let file = blend(
        &dir,
        "fly",
        "fly_slowmo.blend",
        &["--fps", "25", "--slowmo", "--curves"],
    );
    let at_t = dir.join("slowmo_t.png");
    let v = mask(&file, &at_t, &[]);
    assert_eq!(v["t_frame_whole"], true, "{v}");
    assert_eq!(v["curves"].as_array().unwrap().len(), 6, "{v}");
    assert_eq!(v["curves_cast_shadows"], false);
    assert_eq!(v["curves_light_the_scene"], false);
    let i_t = iou(&at_t, &dir.join("shadow.png"));
    assert!(i_t >= 0.995, "the curves changed the picture: {i_t}");
    let frames: Vec<f64> = v["readable_frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect();
    let on_screen = (frames[1] - frames[0]) / 25.0;
    assert!(on_screen >= 0.5, "{on_screen} s on screen: {v}");
    assert!(v["slow_motion_factor"].as_f64().unwrap() > 1.0);
    let target = root().join("scenes/fly/target.png");
    let at_t_iou = iou(&at_t, &target);
    for (k, f) in [frames[0].ceil(), frames[1].floor()].iter().enumerate() {
        let png = dir.join(format!("slowmo_{k}.png"));
        mask(&file, &png, &["--frame", &f.to_string()]);
        let i = iou(&png, &target);
        eprintln!("fly slow motion: frame {f}: IoU {i:.4} vs {at_t_iou:.4} at t, {on_screen:.2} s on screen");
        assert!(i >= 0.9 * at_t_iou - 0.01, "frame {f}: IoU {i}");
    }
}

/// `bsa video`: the .blend first, then an MP4 from the view camera and the contact sheet
/// of four stills beside it (small and one sample here).
#[test]
#[ignore = "needs Blender's bpy in .venv-blender (bash blender/setup_venv.sh); run by scripts/test.sh"]
fn video_writes_an_mp4_and_a_contact_sheet() {
    let dir = shared_quick_solve("mickey");
    let mp4 = dir.join("short.mp4");
    let (ok, stdout, err) = bsa_leaving_no_temporaries(&[
        "video",
        dir.to_str().unwrap(),
        "--out",
        mp4.to_str().unwrap(),
        "--samples",
        "1",
        "--resolution",
        "160x90",
        "--seconds",
        "0.25",
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("short_contact_sheet.png"), "{stdout}");
    let bytes = std::fs::read(&mp4).unwrap();
    assert!(
        bytes.len() > 1000 && &bytes[4..8] == b"ftyp",
        "not an MP4 ({} bytes)",
        bytes.len()
    );
    let sheet = image::open(dir.join("short_contact_sheet.png"))
        .unwrap()
        .to_rgb8();
    // Two columns of 160 x 90 stills with gaps, two rows with labels, a title.
    assert_eq!(sheet.width(), 8 + 2 * (160 + 8));
    assert!(sheet.height() > 2 * 90, "{}", sheet.height());
    assert!(dir.join("mickey.blend").is_file());
}
