//! The .blend's clock: which frame shows which instant of the motion.
//!
//! [`TimeMap`] sends a time of the motion (s after the launch) to a frame of the film at
//! `fps`: the launch is shifted by less than a frame so that `t` falls on a whole frame,
//! and an optional slow motion stretches the window around `t` where the picture reads
//! (found by [`readable_window`] with the rasterizer), easing in and out over
//! [`RAMP_FILM_S`] of film on each side, so that the picture stays on screen at least
//! [`MIN_ON_SCREEN_S`].

use crate::energy;
use crate::evaluate::Problem;
use crate::output::trajectory::Track;

/// The picture counts as readable while its IoU with the target is at least this
/// fraction of its IoU at `t`.
pub const READABLE_FRACTION: f64 = 0.9;
/// How long (s of film) the slow motion keeps the readable picture on screen, at least.
pub const MIN_ON_SCREEN_S: f64 = 0.5;
/// What the slow motion aims at (s of film), a margin above [`MIN_ON_SCREEN_S`].
const AIM_ON_SCREEN_S: f64 = 0.6;
/// The largest slow-down factor.
pub const MAX_SLOWDOWN: f64 = 64.0;
/// Seconds of film over which the rate eases from normal speed to the slow motion, on
/// each side of the window (the rate changes linearly with the motion's time, over
/// `2 RAMP_FILM_S / (1 + factor)` of it).
pub const RAMP_FILM_S: f64 = 0.4;
/// How far from `t` (s) the readable window is searched, and its step as a fraction of
/// the scene's timestep.
const SEARCH_S: f64 = 1.0;
const SEARCH_STEPS_PER_DT: f64 = 8.0;

/// The readable window around `t`: `[t - before, t + after]`, where the shadow's IoU
/// with the target stays at least [`READABLE_FRACTION`] of its value at `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readable {
    pub iou_at_t: f64,
    pub before_s: f64,
    pub after_s: f64,
}

impl Readable {
    pub fn len_s(&self) -> f64 {
        self.before_s + self.after_s
    }
}

/// The readable window of a track: the shadow drawn by the rasterizer at the track's
/// poses (interpolated between keys) every `dt / 8`, outward from `t` until the IoU drops
/// below [`READABLE_FRACTION`] of its value at `t` (searched up to 1 s each way).
pub fn readable_window(problem: &Problem, track: &Track) -> Readable {
    let t = problem.scene.t;
    let mut ws = problem.workspace();
    let mut iou_at = |time: f64| {
        ws.poses.copy_from_slice(&track.poses_at(time));
        problem.shadow(&mut ws);
        energy::iou(&ws.mask, &problem.target.mask)
    };
    let iou_at_t = iou_at(t);
    let step = problem.scene.dt / SEARCH_STEPS_PER_DT;
    let last = (SEARCH_S / step).ceil() as usize;
    let mut reach = |sign: f64| {
        let mut ok = 0.0;
        for k in 1..=last {
            let d = k as f64 * step;
            let time = t + sign * d;
            if time < 0.0 || iou_at(time) < READABLE_FRACTION * iou_at_t {
                break;
            }
            ok = d;
        }
        ok
    };
    let before_s = reach(-1.0);
    let after_s = reach(1.0);
    Readable {
        iou_at_t,
        before_s,
        after_s,
    }
}

/// A slow motion: the motion's window `[start, end]` (s) plays `factor` times slower,
/// the rate easing linearly from 1 to `factor` over `ramp_in` before it and back over
/// `ramp_out` after it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlowMotion {
    pub start: f64,
    pub end: f64,
    pub factor: f64,
    pub ramp_in: f64,
    pub ramp_out: f64,
}

impl SlowMotion {
    /// The slow motion that keeps the readable window of `r` around `t` on screen for
    /// about 0.6 s (at least [`MIN_ON_SCREEN_S`], unless [`MAX_SLOWDOWN`] caps it), or
    /// `None` when it already stays that long at normal speed.
    pub fn for_window(t: f64, r: &Readable) -> Option<SlowMotion> {
        let len = r.len_s();
        if len >= MIN_ON_SCREEN_S {
            return None;
        }
        let factor = (AIM_ON_SCREEN_S / len.max(1e-9)).min(MAX_SLOWDOWN);
        let start = (t - r.before_s).max(0.0);
        let ramp = 2.0 * RAMP_FILM_S / (1.0 + factor);
        Some(SlowMotion {
            start,
            end: t + r.after_s,
            factor,
            ramp_in: ramp.min(start),
            ramp_out: ramp,
        })
    }

    /// Seconds of film for the motion's `[0, time]`.
    fn film_time(&self, time: f64) -> f64 {
        let k = self.factor - 1.0;
        // The extra film time of a ramp from rate 1 to `factor` over `len`, `s` into it.
        let ramp = |s: f64, len: f64| {
            if len <= 0.0 {
                0.0
            } else {
                k * s * s / (2.0 * len)
            }
        };
        let a = self.start - self.ramp_in;
        let mut extra = 0.0;
        if time > a {
            extra += ramp((time - a).min(self.ramp_in), self.ramp_in);
        }
        if time > self.start {
            extra += k * (time.min(self.end) - self.start);
        }
        if time > self.end {
            let s = (time - self.end).min(self.ramp_out);
            // Rate from `factor` down to 1: the full ramp's extra minus the part not yet run.
            let full = ramp(self.ramp_out, self.ramp_out);
            let rest = ramp(self.ramp_out - s, self.ramp_out);
            extra += full - rest;
        }
        time + extra
    }
}

/// Motion time to film frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeMap {
    pub fps: f64,
    /// Frames added to every frame so that `t` is a whole frame (0 <= shift < 1): the
    /// launch is at frame `shift`.
    pub shift: f64,
    pub slow: Option<SlowMotion>,
}

impl TimeMap {
    /// The map at `fps` whose frame of `t` is whole.
    pub fn new(fps: f64, t: f64, slow: Option<SlowMotion>) -> TimeMap {
        let mut map = TimeMap {
            fps,
            shift: 0.0,
            slow,
        };
        let f = map.frame_of(t);
        let whole = f.round();
        map.shift = if (f - whole).abs() < 1e-9 {
            whole - f
        } else {
            f.ceil() - f
        };
        map
    }

    /// The film frame (fractional) of the motion's `time` (s after the launch).
    pub fn frame_of(&self, time: f64) -> f64 {
        let film = self.slow.map_or(time, |s| s.film_time(time));
        film * self.fps + self.shift
    }

    /// The motion's time (s) shown at `frame`: the inverse of [`TimeMap::frame_of`]
    /// (bisection; the map increases).
    pub fn time_of(&self, frame: f64) -> f64 {
        let (mut lo, mut hi) = (-1.0, 1.0);
        while self.frame_of(hi) < frame {
            hi *= 2.0;
        }
        while self.frame_of(lo) > frame {
            lo *= 2.0;
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if self.frame_of(mid) < frame {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_falls_on_a_whole_frame_at_every_rate() {
        for fps in [24.0, 25.0, 30.0, 60.0, 23.0] {
            for t in [1.2, 1.0, 0.7345, 2.0 / 3.0] {
                let m = TimeMap::new(fps, t, None);
                let f = m.frame_of(t);
                assert!((f - f.round()).abs() < 1e-9, "{fps} fps, t {t}: frame {f}");
                assert!((0.0..1.0).contains(&m.shift), "{}", m.shift);
                assert!((m.frame_of(0.0) - m.shift).abs() < 1e-12);
                // Normal speed: one frame per 1 / fps.
                assert!((m.frame_of(t + 1.0) - f - fps).abs() < 1e-9);
            }
        }
        // 1.2 s at 24 fps is frame 28.8: the launch moves 0.2 frame later, t to 29.
        let m = TimeMap::new(24.0, 1.2, None);
        assert!((m.shift - 0.2).abs() < 1e-9 && (m.frame_of(1.2) - 29.0).abs() < 1e-9);
        assert_eq!(TimeMap::new(25.0, 1.2, None).shift, 0.0);
    }

    #[test]
    fn slow_motion_stretches_the_window_continuously() {
        let r = Readable {
            iou_at_t: 0.95,
            before_s: 0.02,
            after_s: 0.03,
        };
        let s = SlowMotion::for_window(1.2, &r).expect("50 ms needs a slow motion");
        assert!((s.factor - 12.0).abs() < 1e-9);
        let m = TimeMap::new(24.0, 1.2, Some(s));
        let f_t = m.frame_of(1.2);
        assert!((f_t - f_t.round()).abs() < 1e-9);
        // The window lasts factor x 50 ms = 0.6 s of film.
        let on_screen = (m.frame_of(1.23) - m.frame_of(1.18)) / 24.0;
        assert!((on_screen - 0.6).abs() < 1e-9, "{on_screen}");
        // Continuous and increasing, with a rate from 1 up to the factor and back.
        let mut prev = m.frame_of(0.0);
        let h = 1e-4;
        for k in 1..40_000 {
            let time = k as f64 * h;
            let f = m.frame_of(time);
            let rate = (f - prev) / h / 24.0;
            assert!(
                rate > 1.0 - 1e-6 && rate < s.factor + 1e-6,
                "{time}: {rate}"
            );
            prev = f;
        }
        // Normal speed long before and after, with the slow motion's extra film time;
        // each ramp lasts RAMP_FILM_S of film.
        let ramp = s.ramp_in;
        assert!((ramp * (1.0 + s.factor) / 2.0 - RAMP_FILM_S).abs() < 1e-12);
        let extra = (s.factor - 1.0) * (0.05 + ramp);
        assert!((m.frame_of(0.5) - 0.5 * 24.0 - m.shift).abs() < 1e-9);
        assert!((m.frame_of(3.0) - (3.0 + extra) * 24.0 - m.shift).abs() < 1e-6);
        // time_of inverts frame_of.
        for time in [0.0, 0.7, 1.19, 1.2, 1.215, 2.5] {
            assert!((m.time_of(m.frame_of(time)) - time).abs() < 1e-9);
        }
        // A window long enough needs none.
        let long = Readable {
            before_s: 0.3,
            after_s: 0.3,
            ..r
        };
        assert!(SlowMotion::for_window(1.2, &long).is_none());
    }
}
