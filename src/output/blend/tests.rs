use super::*;
use crate::energy::Weights;
use crate::output::trajectory::{self, DEFAULT_MAX_AFTER};

/// An example scene whose target is replaced by the shadow of its own start guess at
/// `t` (a picture the launch makes exactly, IoU 1), with that launch's track.
fn planted(name: &str) -> (Problem, Track) {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    let mut scene = crate::scene::load(&dir).unwrap();
    let p = Problem::new(scene.clone());
    // The problem's start: with free positions it carries their offsets too.
    let params = p.start_parameters();
    let mut ws = p.workspace();
    p.evaluate(&params, &Weights::all_ones(), &mut ws);
    scene.target = p.picture_of(&ws.mask);
    let p = Problem::new(scene);
    let track = trajectory::track(&p, &params, DEFAULT_MAX_AFTER);
    (p, track)
}

fn options(fps: u32) -> BlendOptions {
    BlendOptions {
        fps,
        resolution: [1920, 1080],
        slow_motion: false,
        curves: false,
    }
}

#[test]
fn t_is_a_whole_frame_and_the_range_runs_from_launch_to_rest() {
    let (p, track) = planted("mickey");
    assert!(track.rest.at_rest);
    for fps in [24, 25, 30, 60] {
        let plan = plan(&p, &track, &options(fps)).unwrap();
        let f = plan.key_frames[track.t_index];
        assert_eq!(plan.t_frame as f64, f.round());
        assert!((f - f.round()).abs() < 1e-9, "{fps} fps: t on frame {f}");
        assert!((plan.t_frame as f64 - 1.2 * fps as f64).abs() < 1.0);
        assert!(
            (0.0..1.0).contains(&plan.launch_frame),
            "{}",
            plan.launch_frame
        );
        assert_eq!(plan.frame_start, 0);
        let last = *plan.key_frames.last().unwrap();
        assert!(plan.frame_end as f64 >= last - 1e-6 && (plan.frame_end as f64) < last + 1.0);
        assert!(plan.key_frames.windows(2).all(|w| w[1] > w[0]));
        // One frame per 1 / fps without slow motion.
        let k = track.t_index;
        let rate =
            (plan.key_frames[k + 1] - plan.key_frames[k]) / (track.times[k + 1] - track.times[k]);
        assert!((rate - fps as f64).abs() < 1e-6);
        assert!(plan.slow_motion.is_none());
        assert!(plan.curves.is_empty());
    }
    let plan = plan(&p, &track, &options(24)).unwrap();
    assert!((plan.launch_frame - 0.2).abs() < 1e-9);
    // The contact sheet: launch, mid-flight, t, at rest.
    let frames: Vec<i64> = plan.contact_sheet.iter().map(|s| s.frame).collect();
    assert_eq!(frames, vec![0, 15, 29, plan.frame_end]);
}

/// The view camera frames the picture large at t: the close shot holds from before t to
/// after it, and the picture's bounding box takes at least 40 % of the frame's height.
#[test]
fn the_view_camera_shows_the_picture_large_at_t() {
    for name in ["mickey", "fly", "thinker"] {
        let (p, track) = planted(name);
        let plan = plan(&p, &track, &options(24)).unwrap();
        let c = &plan.camera;
        assert!(
            c.picture_fraction_at_t >= 0.4,
            "{name}: {}",
            c.picture_fraction_at_t
        );
        let t = plan.t_frame as f64;
        let before = c.keys.iter().rev().find(|k| k.frame <= t).unwrap();
        let after = c.keys.iter().find(|k| k.frame >= t).unwrap();
        assert_eq!((before.shot, after.shot), ("close", "close"), "{name}");
        assert!(after.frame - t >= 0.5 * 24.0);
        assert_eq!(c.keys[0].shot, "follow");
        assert_eq!(c.keys[0].frame, 0.0);
        assert_eq!(c.keys.last().unwrap().shot, "follow");
        assert_eq!(c.keys.last().unwrap().frame, plan.frame_end as f64);
        assert!(c.keys.windows(2).all(|w| w[1].frame > w[0].frame));
        // Every following key frames the bodies of its instant.
        let map = TimeMap::new(24.0, p.scene.t, None);
        for k in c.keys.iter().filter(|k| k.shot == "follow") {
            let pose = camera::Pose {
                location: DVec3::from_array(k.location),
                rotation: glam::DQuat::from_xyzw(
                    k.rotation_wxyz[1],
                    k.rotation_wxyz[2],
                    k.rotation_wxyz[3],
                    k.rotation_wxyz[0],
                ),
                aim: DVec3::ZERO,
            };
            for (o, (pos, q)) in p
                .scene
                .occluders
                .iter()
                .zip(track.poses_at(map.time_of(k.frame)))
            {
                let (x, y, depth) = pose.project(pos + q * o.mass.local_com);
                assert!(
                    depth > 0.0 && x.abs() <= 1.0 && y.abs() <= 1.0,
                    "{name}: {} at frame {}",
                    o.name,
                    k.frame
                );
            }
        }
        eprintln!(
            "{name}: picture {:.2} of the frame's height at t, {:.3} hidden",
            c.picture_fraction_at_t, c.picture_hidden_at_t
        );
    }
}

/// Slow motion keeps the readable picture on screen for at least half a second, with t
/// still on a whole frame; without it the window lasts its real length.
#[test]
fn slow_motion_keeps_the_picture_on_screen() {
    let (p, track) = planted("fly");
    let normal = plan(&p, &track, &options(24)).unwrap();
    let r = &normal.readable;
    assert!(
        (r.iou_at_t - 1.0).abs() < 1e-12,
        "the planted picture: {}",
        r.iou_at_t
    );
    let real = r.window_s[1] - r.window_s[0];
    assert!(real > 0.0 && (r.on_screen_s - real).abs() < 1e-9);
    let slow = plan(
        &p,
        &track,
        &BlendOptions {
            slow_motion: true,
            curves: true,
            ..options(25)
        },
    )
    .unwrap();
    assert!(
        slow.readable.on_screen_s >= timing::MIN_ON_SCREEN_S,
        "{:?}",
        slow.readable
    );
    assert!(slow.slow_motion.is_some());
    let f = slow.key_frames[track.t_index];
    assert!((f - f.round()).abs() < 1e-9 && f.round() as i64 == slow.t_frame);
    // Every frame of the slow motion is keyed with the time it shows, t on its frame.
    let ft = &slow.frame_times;
    assert!(ft.len() as f64 >= 0.6 * 25.0, "{} frames", ft.len());
    assert!(ft
        .windows(2)
        .all(|w| w[1][0] == w[0][0] + 1.0 && w[1][1] > w[0][1]));
    let at_t = ft.iter().find(|[f, _]| *f == slow.t_frame as f64).unwrap();
    assert!((at_t[1] - p.scene.t).abs() < 1e-9, "{at_t:?}");
    assert!(normal.frame_times.is_empty());
    // Curves: each body's centre of mass from the launch to t.
    assert_eq!(slow.curves.len(), p.scene.occluders.len());
    for (c, o) in slow.curves.iter().zip(&p.scene.occluders) {
        assert_eq!(c.points.len(), track.t_index + 1);
        let (pos, q) = track.poses[track.t_index][p
            .scene
            .occluders
            .iter()
            .position(|x| x.name == o.name)
            .unwrap()];
        let com = pos + q * o.mass.local_com;
        assert!(DVec3::from_array(*c.points.last().unwrap()).distance(com) < 1e-12);
    }
}

#[test]
fn bad_options_and_blank_pictures_are_refused() {
    let (mut p, track) = planted("mickey");
    assert!(matches!(
        plan(&p, &track, &options(0)),
        Err(BlendError::Options(_))
    ));
    p.scene.target.clear();
    assert!(matches!(
        plan(&p, &track, &options(24)),
        Err(BlendError::NoPicture(_))
    ));
}

#[test]
fn a_sequence_gets_a_marker_for_each_later_picture() {
    let (p, track) = planted("sequence");
    let pictures = &p.scene.pictures;
    assert!(pictures.len() >= 2);
    for fps in [24, 25, 30, 60] {
        let plan = plan(&p, &track, &options(fps)).unwrap();
        assert_eq!(plan.markers.len(), pictures.len() - 1, "{fps} fps");
        for (m, pic) in plan.markers.iter().zip(&pictures[1..]) {
            // The later pictures are after t, at their own instant.
            let expected = plan.t_frame as f64 + (pic.t - plan.t_s) * f64::from(fps);
            assert!((m.frame as f64 - expected).abs() <= 1.0, "{fps} fps: {m:?}");
        }
    }
    let (mickey, track) = planted("mickey");
    assert!(plan(&mickey, &track, &options(24))
        .unwrap()
        .markers
        .is_empty());
}

/// Bodies that come to rest before the pull out is over: the film ends on the pull
/// out's last key, which is the following shot of its instant, and says so.
#[test]
fn a_film_that_ends_during_the_pull_out_ends_on_a_following_key() {
    let (fps, t) = (24.0, 1.2);
    let map = TimeMap::new(fps, t, None);
    let readable = Readable {
        iou_at_t: 1.0,
        before_s: 0.05,
        after_s: 0.05,
    };
    let pose = |x: f64| {
        let location = DVec3::new(x, -5.0, 2.0);
        Pose {
            location,
            rotation: glam::DQuat::IDENTITY,
            aim: location - DVec3::Z,
        }
    };
    let close = pose(0.0);
    let end_at = |end_s: f64| {
        camera_keys(
            &map,
            t,
            &readable,
            0,
            map.frame_of(end_s).round() as i64,
            close,
            pose,
        )
    };
    // The film ends a little after the close shot is left: within the pull out.
    let leave = map.frame_of(t + 0.5) + CLOSE_AFTER_S * fps;
    let keys = end_at(map.time_of(leave + 0.5 * PULL_OUT_S * fps));
    let last = keys.last().unwrap();
    assert_eq!(last.shot, "follow", "{keys:?}");
    let follow = pose(map.time_of(last.frame));
    assert!((DVec3::from_array(last.location) - follow.location).length() < 1e-9);
    // A film that ends well after the pull out ends on a following key too.
    assert_eq!(end_at(t + 4.0).last().unwrap().shot, "follow");
}
