//! The start of the search: the initial launch guess aimed at the hints, and the
//! automatic order of the sequential strategy.

use glam::{DVec2, DVec3};

use super::raw::RawScene;
use super::{Hint, Occluder, Receiver};
use crate::shadow::raster::ShadowCamera;

/// Which occluders have an explicit `start_velocity` (those are never re-aimed).
pub(super) fn raw_start_overrides(raw: &RawScene) -> Vec<bool> {
    raw.occluders
        .iter()
        .map(|o| o.start_velocity.is_some())
        .collect()
}

/// Aim the initial guess of every launched occluder that has hints (and no explicit
/// `start_velocity`): its centre of mass is sent to the point where its hints' light
/// rays are `rise` higher above the receiver than it starts, so the search starts with
/// the hints met, in flight and clear of the table. Launching straight up instead puts
/// the shadows far outside the picture, and the first iterations then find that
/// lowering a body shrinks its distance to the picture fastest: it lands, and a landed
/// body's shadow no longer depends on its vertical launch speed (a plateau that CMA-ES
/// cannot cross; see docs/energies.md).
pub(super) struct Aim<'a> {
    pub camera: &'a ShadowCamera,
    pub receiver: &'a Receiver,
    /// The instant of the picture (s).
    pub t: f64,
    pub gravity: DVec3,
    /// How much higher than its start the hint point is at `t` (m).
    pub rise: f64,
}

impl Aim<'_> {
    /// Re-aim every launched occluder that has hints and no explicit start velocity
    /// (`explicit[i]`).
    pub(super) fn apply(&self, occ: &mut [Occluder], hints: &[Hint], explicit: &[bool]) {
        let Aim {
            camera,
            receiver,
            t,
            gravity,
            rise,
        } = *self;
        let n = receiver.normal;
        let light_height = (camera.light - receiver.center).dot(n);
        for (i, o) in occ.iter_mut().enumerate() {
            if !o.launched || explicit[i] {
                continue;
            }
            let mine: Vec<&Hint> = hints
                .iter()
                .filter(|h| h.occluder == i && h.weight > 0.0)
                .collect();
            if mine.is_empty() {
                continue;
            }
            let wsum: f64 = mine.iter().map(|h| h.weight).sum();
            let pixel = mine.iter().map(|h| h.pixel * h.weight).sum::<DVec2>() / wsum;
            let point = mine.iter().map(|h| h.point * h.weight).sum::<DVec3>() / wsum;
            let com0 = o.launch_com();
            // Offset from the centre of mass to the (mean) hint point, in the launch orientation.
            let offset = o.orientation * (point - o.mass.local_com);
            let on_plane = camera.pixel_to_world(pixel.x, pixel.y);
            // Height of the hint point above the receiver at t: the start height plus `rise`,
            // kept strictly between the receiver and the light.
            let h0 = (com0 + offset - receiver.center).dot(n);
            let h = (h0 + rise).clamp(0.05 * light_height, 0.9 * light_height);
            // The point on the ray light -> on_plane at height h: X + s (L - X) with s = h / H.
            let s = h / light_height;
            let hint_at_t = on_plane + s * (camera.light - on_plane);
            let com_t = hint_at_t - offset;
            let v = (com_t - com0 - 0.5 * gravity * t * t) / t;
            // Absurd hint values can overflow; keep the straight-up start then.
            if v.is_finite() {
                o.start_velocity = v;
            }
        }
    }
}

/// The automatic sequential order: largest occluders first, since they fix most of the
/// picture and the small ones then fill in details around them. Ties keep file order.
pub(super) fn auto_order(occ: &[Occluder]) -> Vec<usize> {
    let mut idx: Vec<usize> = occ
        .iter()
        .enumerate()
        .filter(|(_, o)| o.launched)
        .map(|(i, _)| i)
        .collect();
    idx.sort_by(|&a, &b| {
        occ[b]
            .shape
            .volume()
            .total_cmp(&occ[a].shape.volume())
            .then(a.cmp(&b))
    });
    idx
}
