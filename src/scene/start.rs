//! The start of the search: the initial launch guess aimed at the hints, and the
//! automatic order of the sequential strategy.

use glam::{DVec2, DVec3};

use super::launch::velocity_reaching;
use super::raw::RawScene;
use super::{Hint, Occluder, Receiver, Table};
use crate::geometry::distance::{signed_distance, ContactShape};
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
    /// With free launch positions, the table a body may be moved on: under its aim point
    /// (launched straight up) where it fits.
    pub free_on: Option<&'a Table>,
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
            free_on,
        } = *self;
        let n = receiver.normal;
        let light_height = (camera.light - receiver.center).dot(n);
        for i in 0..occ.len() {
            let o = &occ[i];
            if !o.launched || explicit[i] {
                continue;
            }
            let Some((pixel, point)) = mean_hint(hints, i) else {
                continue;
            };
            let mut com0 = o.launch_com();
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
            if let Some(table) = free_on {
                let under = DVec3::new(com_t.x, com_t.y, com0.z);
                if let Some(spot) = free_spot(occ, i, under, table) {
                    occ[i].position += spot - com0;
                    com0 = spot;
                }
            }
            let o = &mut occ[i];
            let v = velocity_reaching(com0, com_t, gravity, t);
            // Absurd hint values can overflow; keep the straight-up start then.
            if v.is_finite() {
                o.start_velocity = v;
            }
        }
    }
}

/// The nearest place for occluder `i`'s centre of mass to `want` (same height) where it
/// fits on the table: `want` itself, else the first free one on rings of growing radius
/// (half its bounding radius apart, 16 places a ring, up to 8 rings).
fn free_spot(occ: &[Occluder], i: usize, want: DVec3, table: &Table) -> Option<DVec3> {
    let o = &occ[i];
    let step = 0.5 * o.bounding_radius;
    let origin_of = |com: DVec3| o.position + (com - o.launch_com());
    std::iter::once(want)
        .chain((1..=8).flat_map(|ring| {
            (0..16).map(move |k| {
                let a = std::f64::consts::TAU * k as f64 / 16.0;
                want + ring as f64 * step * DVec3::new(a.cos(), a.sin(), 0.0)
            })
        }))
        .find(|&com| fits(occ, i, origin_of(com), table))
}

impl Aim<'_> {
    /// With free positions, for the occluders hinted both in this picture (at `self.t`,
    /// aimed by [`Aim::apply`] already) and in a later one (`later_hints` at `later_t`):
    /// move the launch across the table so that a straight launch meets both aim points
    /// in the horizontal (its vertical launch and so its heights are this picture's).
    pub(super) fn apply_between(
        &self,
        later_t: f64,
        later_hints: &[Hint],
        occ: &mut [Occluder],
        hints: &[Hint],
        explicit: &[bool],
    ) {
        let Some(table) = self.free_on else {
            return;
        };
        let (t, g) = (self.t, self.gravity);
        let n = self.receiver.normal;
        let light_height = (self.camera.light - self.receiver.center).dot(n);
        for i in 0..occ.len() {
            let o = &occ[i];
            if !o.launched || explicit[i] || mean_hint(hints, i).is_none() {
                continue;
            }
            let Some((pixel, point)) = mean_hint(later_hints, i) else {
                continue;
            };
            let com0 = o.launch_com();
            let v = o.start_velocity;
            let at = |s: f64| com0 + v * s + 0.5 * g * s * s;
            let offset = o.orientation * (point - o.mass.local_com);
            // The later aim point: on its hint's ray, at the height the launch has then.
            let h = (at(later_t) + offset - self.receiver.center).dot(n);
            let h = h.clamp(0.05 * light_height, 0.9 * light_height);
            let on_plane = self.camera.pixel_to_world(pixel.x, pixel.y);
            let later = on_plane + h / light_height * (self.camera.light - on_plane) - offset;
            let now = at(t);
            let mut drift = (later - now) / (later_t - t);
            drift.z = 0.0;
            let want = now - drift * t;
            let want = DVec3::new(want.x, want.y, com0.z);
            if let Some(spot) = free_spot(occ, i, want, table) {
                let o = &mut occ[i];
                let v = velocity_reaching(spot, now, g, t);
                if v.is_finite() {
                    o.position += spot - com0;
                    o.start_velocity = v;
                }
            }
        }
    }
}

/// The weighted mean pixel and body point of occluder `i`'s hints, if it has any.
fn mean_hint(hints: &[Hint], i: usize) -> Option<(DVec2, DVec3)> {
    let mine: Vec<&Hint> = hints
        .iter()
        .filter(|h| h.occluder == i && h.weight > 0.0)
        .collect();
    if mine.is_empty() {
        return None;
    }
    let wsum: f64 = mine.iter().map(|h| h.weight).sum();
    let pixel = mine.iter().map(|h| h.pixel * h.weight).sum::<DVec2>() / wsum;
    let point = mine.iter().map(|h| h.point * h.weight).sum::<DVec3>() / wsum;
    Some((pixel, point))
}

/// The room a body moved by the start guess keeps from its neighbours, as a share of
/// their bounding radii summed: bodies launched side by side with a spin sweep their
/// corners around, and touching neighbours would collide at once.
const ROOM: f64 = 0.25;

/// Whether occluder `i` moved to `position` stays on the table's top and clear of every
/// other occluder (by [`ROOM`]).
fn fits(occ: &[Occluder], i: usize, position: DVec3, table: &Table) -> bool {
    let o = &occ[i];
    let c = position + o.orientation * o.mass.local_com;
    let d = (c - table.center).abs();
    if !(d.x + o.bounding_radius <= table.half_extents.x
        && d.y + o.bounding_radius <= table.half_extents.y
        && position.is_finite())
    {
        return false;
    }
    let mine = ContactShape::new(&o.shape);
    occ.iter().enumerate().all(|(j, p)| {
        let room = ROOM * (o.bounding_radius + p.bounding_radius);
        j == i
            || c.distance(p.launch_com()) > o.bounding_radius + p.bounding_radius + room
            || signed_distance(
                &mine,
                position,
                o.orientation,
                &ContactShape::new(&p.shape),
                p.position,
                p.orientation,
            ) > room
    })
}

/// The automatic sequential order: largest occluders first, since they fix most of the
/// picture and the small ones then fill in details around them. Ties keep file order.
pub fn auto_order(occ: &[Occluder]) -> Vec<usize> {
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
