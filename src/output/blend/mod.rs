//! The plan of a .blend ready to render: everything `bsa blend` decides about the film,
//! computed here (and tested) so that `blender/make_blend.py` only applies it.
//!
//! Data flow: [`plan`] takes the scene, its [`Track`] and the [`BlendOptions`] and
//! returns a [`Plan`] (serialised as JSON for the script): the frame of every key
//! ([`timing::TimeMap`]: `t` on a whole frame, an optional slow motion around `t`), the
//! frame range from the launch to the rest, the view camera's keyframes
//! ([`camera`]: a shot following the bodies, a close shot of the picture at `t`), the
//! picture's rectangle, the contact sheet's frames and, if asked, the trajectory curves.
//! See `docs/blender.md`.

use glam::DVec3;
use serde::Serialize;

use crate::evaluate::Problem;
use crate::output::trajectory::Track;

pub mod camera;
pub mod timing;

use camera::Pose;
use timing::{Readable, SlowMotion, TimeMap};

/// What `bsa blend` was asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendOptions {
    /// Frames per second of the film.
    pub fps: u32,
    /// Render size of the view camera (pixels).
    pub resolution: [u32; 2],
    /// Slow the motion around `t` so that the picture stays on screen.
    pub slow_motion: bool,
    /// Draw each body's flight to `t` as a curve.
    pub curves: bool,
}

/// Why a plan cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum BlendError {
    /// `plan`: the options are out of range (the CLI checks them first).
    #[error("{0}")]
    Options(String),
    /// `plan`: the target picture has no dark pixel, so there is no picture to frame.
    #[error("the target picture of scene `{0}` has no dark pixel: there is no picture to frame")]
    NoPicture(String),
    /// `plan`: the track has no key at `t` (not made by `trajectory::track`).
    #[error("the track has no key at t")]
    NoKeyAtT,
}

/// One keyframe of the view camera.
#[derive(Clone, Debug, Serialize)]
pub struct CameraKey {
    pub frame: f64,
    pub location: [f64; 3],
    /// Camera -> world, `[w, x, y, z]` as Blender's `rotation_quaternion`.
    pub rotation_wxyz: [f64; 4],
    /// `follow` (the bodies of the moment and the picture) or `close` (the picture).
    pub shot: &'static str,
}

/// The view camera: 16:9, vertical field of view, keyframes (Bezier in Blender).
#[derive(Clone, Debug, Serialize)]
pub struct CameraPlan {
    pub fov_y_rad: f64,
    pub aspect: f64,
    pub keys: Vec<CameraKey>,
    /// Share of the frame's height the picture's bounding box takes at `t`.
    pub picture_fraction_at_t: f64,
    /// Share of the picture the bodies at `t` hide from the close shot (bounding spheres).
    pub picture_hidden_at_t: f64,
    /// The close shot's elevation above the horizontal (degrees).
    pub close_elevation_deg: f64,
}

/// The picture's readable window and how long it stays on screen.
#[derive(Clone, Debug, Serialize)]
pub struct ReadablePlan {
    pub iou_at_t: f64,
    /// Motion times (s) between which the IoU stays >= 0.9 of its value at t.
    pub window_s: [f64; 2],
    /// Their frames.
    pub frames: [f64; 2],
    /// Seconds of film the window lasts.
    pub on_screen_s: f64,
}

/// The slow motion, when asked and needed.
#[derive(Clone, Debug, Serialize)]
pub struct SlowPlan {
    pub factor: f64,
    /// Motion times (s) of the window played `factor` times slower (ramps outside it).
    pub window_s: [f64; 2],
    pub ramp_s: [f64; 2],
}

/// A body's flight to `t` (centre of mass at every key).
#[derive(Clone, Debug, Serialize)]
pub struct Curve {
    pub name: String,
    pub points: Vec<[f64; 3]>,
}

/// A frame of the contact sheet.
#[derive(Clone, Debug, Serialize)]
pub struct SheetFrame {
    pub label: String,
    pub frame: i64,
}

/// Everything `blender/make_blend.py` applies (see `docs/blender.md`).
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    pub scene: String,
    pub fps: u32,
    pub resolution: [u32; 2],
    /// The target's size (pixels): the shadow scene's render size.
    pub target_size: [usize; 2],
    pub t_s: f64,
    /// The frame of `t`: whole.
    pub t_frame: i64,
    /// A timeline marker for each picture after the first of a sequence (the first is the
    /// marker `t`), at the whole frame nearest its instant.
    pub markers: Vec<SheetFrame>,
    /// The frame of the launch (`0 <= launch_frame < 1` without slow motion before it).
    pub launch_frame: f64,
    pub frame_start: i64,
    /// The first whole frame at or after the last key (every body at rest).
    pub frame_end: i64,
    /// Every key of the glb's animation (s) and its frame.
    pub key_times_s: Vec<f64>,
    pub key_frames: Vec<f64>,
    /// With slow motion, every whole frame of it and its ramps with the motion's time it
    /// shows, `[frame, time]`: keys added there follow the slow motion's smooth rate
    /// (between the glb's keys, a step apart, Blender would interpolate linearly in
    /// frames).
    pub frame_times: Vec<[f64; 2]>,
    pub at_rest: bool,
    pub rest_since_s: Option<f64>,
    pub readable: ReadablePlan,
    pub slow_motion: Option<SlowPlan>,
    /// The bounding box of the target's dark pixels on the receiver (world, m).
    pub picture_corners: [[f64; 3]; 4],
    pub camera: CameraPlan,
    pub curves: Vec<Curve>,
    pub contact_sheet: Vec<SheetFrame>,
}

/// Lead-in of the close shot before `t`, hold after it and the moves between the shots
/// (s of film).
const CLOSE_BEFORE_S: f64 = 0.15;
const CLOSE_AFTER_S: f64 = 0.25;
const PUSH_IN_S: f64 = 0.4;
const PULL_OUT_S: f64 = 0.8;
/// Seconds of film between the keys of a move between shots.
const MOVE_STEP_S: f64 = 1.0 / 12.0;
/// Seconds of film between the following shot's keys.
const FOLLOW_STEP_S: f64 = 0.25;
/// The following shot frames at least a sphere of this share of the picture's diagonal
/// (radius) about the bodies' centre.
const FOLLOW_MIN_SHARE: f64 = 0.35;

/// The plan of the .blend of `problem`'s solution moving as `track`.
pub fn plan(problem: &Problem, track: &Track, opts: &BlendOptions) -> Result<Plan, BlendError> {
    let scene = &problem.scene;
    if !(1..=240).contains(&opts.fps) {
        return Err(BlendError::Options(format!(
            "fps must be 1 to 240, got {}",
            opts.fps
        )));
    }
    let t = scene.t;
    let t_key = *track.times.get(track.t_index).ok_or(BlendError::NoKeyAtT)?;
    if (t_key - t).abs() > 1e-9 * t.max(1.0) {
        return Err(BlendError::NoKeyAtT);
    }
    let (corners, dark) =
        picture(problem).ok_or_else(|| BlendError::NoPicture(scene.name.clone()))?;

    // The clock.
    let readable = timing::readable_window(problem, track);
    let slow = if opts.slow_motion {
        SlowMotion::for_window(t, &readable)
    } else {
        None
    };
    let fps = f64::from(opts.fps);
    let map = TimeMap::new(fps, t, slow);
    let key_frames: Vec<f64> = track.times.iter().map(|&x| map.frame_of(x)).collect();
    let t_frame = map.frame_of(t).round() as i64;
    let markers = scene
        .pictures
        .iter()
        .enumerate()
        .skip(1)
        .map(|(k, p)| SheetFrame {
            label: format!("picture {} ({:.2} s)", k + 1, p.t),
            frame: map.frame_of(p.t).round() as i64,
        })
        .collect();
    let frame_times = match slow {
        Some(s) => {
            let a = map.frame_of(s.start - s.ramp_in).floor() as i64;
            let b = map.frame_of(s.end + s.ramp_out).ceil() as i64;
            (a..=b)
                .map(|f| [f as f64, map.time_of(f as f64)])
                .filter(|[_, time]| *time >= 0.0)
                .collect()
        }
        None => Vec::new(),
    };
    let last = *key_frames.last().unwrap_or(&0.0);
    let frame_end = (last - 1e-6).ceil() as i64;
    let frame_start = map.frame_of(0.0).floor() as i64;

    // The camera.
    let at_t = bodies(problem, &track.poses[track.t_index]);
    let (dir, close, hidden) = camera::choose_close_shot(scene, &corners, &dark, &at_t);
    let follow_dir = camera::follow_direction(dir);
    let min_radius = FOLLOW_MIN_SHARE * corners[0].distance(corners[2]);
    let follow = |time: f64| {
        camera::follow_shot(
            follow_dir,
            &bodies(problem, &track.poses_at(time)),
            min_radius,
        )
    };
    let keys = camera_keys(&map, t, &readable, frame_start, frame_end, close, follow);

    let readable_plan = {
        let window = [t - readable.before_s, t + readable.after_s];
        let frames = window.map(|x| map.frame_of(x));
        ReadablePlan {
            iou_at_t: readable.iou_at_t,
            window_s: window,
            frames,
            on_screen_s: (frames[1] - frames[0]) / fps,
        }
    };
    let curves = if opts.curves {
        curves(problem, track)
    } else {
        Vec::new()
    };
    let contact_sheet = contact_sheet(&map, track, t, frame_start, frame_end);
    Ok(Plan {
        scene: scene.name.clone(),
        fps: opts.fps,
        resolution: opts.resolution,
        target_size: [scene.target.width(), scene.target.height()],
        t_s: t,
        t_frame,
        markers,
        launch_frame: map.frame_of(0.0),
        frame_start,
        frame_end,
        key_times_s: track.times.clone(),
        key_frames,
        frame_times,
        at_rest: track.rest.at_rest,
        rest_since_s: track.rest.since,
        readable: readable_plan,
        slow_motion: slow.map(|s| SlowPlan {
            factor: s.factor,
            window_s: [s.start, s.end],
            ramp_s: [s.ramp_in, s.ramp_out],
        }),
        picture_corners: corners.map(|c| c.to_array()),
        camera: CameraPlan {
            fov_y_rad: camera::FOV_Y,
            aspect: camera::ASPECT,
            keys,
            picture_fraction_at_t: camera::picture_fraction(&close, &corners),
            picture_hidden_at_t: hidden,
            close_elevation_deg: dir.z.clamp(-1.0, 1.0).asin().to_degrees(),
        },
        curves,
        contact_sheet,
    })
}

/// The bodies' centres of mass at `poses` and their bounding radii.
fn bodies(problem: &Problem, poses: &[(DVec3, glam::DQuat)]) -> Vec<(DVec3, f64)> {
    problem
        .scene
        .occluders
        .iter()
        .zip(poses)
        .map(|(o, (p, q))| (*p + *q * o.mass.local_com, o.bounding_radius))
        .collect()
}

/// Each body's flight to `t`: its centre of mass at every key.
fn curves(problem: &Problem, track: &Track) -> Vec<Curve> {
    let mut out: Vec<Curve> = problem
        .scene
        .occluders
        .iter()
        .map(|o| Curve {
            name: o.name.clone(),
            points: Vec::with_capacity(track.t_index + 1),
        })
        .collect();
    for poses in &track.poses[..=track.t_index] {
        for (c, (p, _)) in out.iter_mut().zip(bodies(problem, poses)) {
            c.points.push(p.to_array());
        }
    }
    out
}

/// The contact sheet's frames: the launch, mid-flight (`t / 2`), `t`, and the last frame.
fn contact_sheet(
    map: &TimeMap,
    track: &Track,
    t: f64,
    frame_start: i64,
    frame_end: i64,
) -> Vec<SheetFrame> {
    let end_time = *track.times.last().unwrap_or(&t);
    let after = if track.rest.at_rest {
        "at rest"
    } else {
        "the end"
    };
    [
        ("launch (0 s)".to_string(), frame_start),
        (
            format!("mid-flight ({:.2} s)", t / 2.0),
            map.frame_of(t / 2.0).round() as i64,
        ),
        (
            format!("t = {t} s: the picture"),
            map.frame_of(t).round() as i64,
        ),
        (format!("after: {after} ({end_time:.2} s)"), frame_end),
    ]
    .into_iter()
    .map(|(label, frame)| SheetFrame { label, frame })
    .collect()
}

/// The receiver point at the centre of pixel-space point `(x, y)` of the target (pixels
/// from the top left).
fn receiver_point(problem: &Problem, x: f64, y: f64) -> DVec3 {
    let rc = &problem.scene.receiver;
    let (w, h) = (
        problem.scene.target.width() as f64,
        problem.scene.target.height() as f64,
    );
    rc.center + rc.u * ((x / w - 0.5) * rc.width) + rc.v * ((0.5 - y / h) * rc.height)
}

/// The bounding box of the target's dark pixels on the receiver (its four corners), and
/// up to about 2,000 of those pixels' centres (for the hidden share); `None` without a
/// dark pixel.
fn picture(problem: &Problem) -> Option<([DVec3; 4], Vec<DVec3>)> {
    let m = &problem.scene.target;
    let (w, h) = (m.width(), m.height());
    let count = m.count().max(1) as usize;
    let stride = ((count as f64 / 2000.0).sqrt().ceil() as usize).max(1);
    let (mut x0, mut x1, mut y0, mut y1) = (usize::MAX, 0, usize::MAX, 0);
    let mut dark = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if m.get(x, y) {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
                if x % stride == 0 && y % stride == 0 {
                    dark.push(receiver_point(problem, x as f64 + 0.5, y as f64 + 0.5));
                }
            }
        }
    }
    if x0 == usize::MAX {
        return None;
    }
    let (a, b) = (x0 as f64, (x1 + 1) as f64);
    let (c, d) = (y0 as f64, (y1 + 1) as f64);
    let corners = [(a, c), (b, c), (b, d), (a, d)].map(|(x, y)| receiver_point(problem, x, y));
    Some((corners, dark))
}

/// The view camera's keys: the following shot (the bodies of the moment) every
/// [`FOLLOW_STEP_S`] of film, a push in to the close shot of the picture reached
/// [`CLOSE_BEFORE_S`] before `t`, held until [`CLOSE_AFTER_S`] after the readable window
/// (at least 0.5 s after `t`), and a pull out back to the following shot for the fall and
/// the rest. The moves are keyed every [`MOVE_STEP_S`], eased, each pose a
/// [`Pose::blend`] of the following shot of its instant and the close shot.
fn camera_keys(
    map: &TimeMap,
    t: f64,
    readable: &Readable,
    frame_start: i64,
    frame_end: i64,
    close: Pose,
    follow: impl Fn(f64) -> Pose,
) -> Vec<CameraKey> {
    let fps = map.fps;
    let (start, end) = (frame_start as f64, frame_end as f64);
    let ft = map.frame_of(t);
    let arrive = (ft - CLOSE_BEFORE_S * fps).max(start);
    let leave =
        (map.frame_of(t + readable.after_s).max(ft + 0.5 * fps) + CLOSE_AFTER_S * fps).min(end);
    let push = (arrive - PUSH_IN_S * fps).max(start);
    let pull = (leave + PULL_OUT_S * fps).min(end);
    let following = |frame: f64| follow(map.time_of(frame));
    let ease = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    let mut keys: Vec<(f64, Pose, &'static str)> = Vec::new();
    // Following, up to the push in.
    let steps = |from: f64, to: f64, step: f64| {
        let n = ((to - from) / step).ceil().max(1.0) as usize;
        (0..=n).map(move |k| from + (to - from) * k as f64 / n as f64)
    };
    for f in steps(start, push, FOLLOW_STEP_S * fps) {
        keys.push((f, following(f), "follow"));
    }
    for f in steps(push, arrive, MOVE_STEP_S * fps) {
        let s = if arrive > push {
            (f - push) / (arrive - push)
        } else {
            1.0
        };
        keys.push((f, Pose::blend(&following(f), &close, ease(s)), "push"));
    }
    keys.push((arrive, close, "close"));
    keys.push((leave, close, "close"));
    if leave < end {
        for f in steps(leave, pull, MOVE_STEP_S * fps) {
            let s = (f - leave) / (pull - leave).max(1e-9);
            // The pull out's last key is the following shot itself; when the bodies come
            // to rest before the pull out is over, it is the last key of the film.
            let shot = if s >= 1.0 - 1e-9 { "follow" } else { "pull" };
            keys.push((f, Pose::blend(&close, &following(f), ease(s)), shot));
        }
        for f in steps(pull, end, FOLLOW_STEP_S * fps) {
            keys.push((f, following(f), "follow"));
        }
    }
    // Where two keys share a frame (the ends of the moves), the later one's shot counts
    // for the close shot's ends and the earlier one's elsewhere.
    keys.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut kept: Vec<(f64, Pose, &'static str)> = Vec::with_capacity(keys.len());
    for k in keys {
        match kept.last_mut() {
            Some(last) if k.0 <= last.0 + 1e-9 => {
                if k.2 == "close" {
                    *last = k;
                }
            }
            _ => kept.push(k),
        }
    }
    // Keep consecutive rotations in one hemisphere: Blender blends their components.
    let mut prev: Option<glam::DQuat> = None;
    kept.into_iter()
        .map(|(frame, pose, shot)| {
            let mut q = pose.rotation;
            if prev.is_some_and(|p| p.dot(q) < 0.0) {
                q = -q;
            }
            prev = Some(q);
            CameraKey {
                frame,
                location: pose.location.to_array(),
                rotation_wxyz: [q.w, q.x, q.y, q.z],
                shot,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
