//! The reader: [`read_poses_at`] evaluates every animated node of a .glb at a time, as
//! a glTF viewer or Blender would (LINEAR keys, slerp for rotations).

use super::*;

/// Re-read a .glb written by [`write_glb`] and evaluate every animated node at `time`
/// (s), returned in node order as (node name, body origin, body->world orientation) in
/// the Z-up world.
///
/// Translation keys are interpolated linearly and rotation keys by slerp (the glTF
/// LINEAR rule); times outside the keys clamp to the first or last key; a property
/// without a channel keeps the node's static value. Only the first animation is read,
/// as Blender does.
pub fn read_poses_at(glb: &[u8], time: f64) -> Result<Vec<(String, DVec3, DQuat)>, GltfError> {
    let doc = gltf::Gltf::from_slice(glb).map_err(GltfError::Parse)?;
    let blob = doc.blob.as_deref().ok_or(GltfError::MissingBinary)?;
    let anim = doc.animations().next().ok_or(GltfError::NoAnimation)?;

    // node index -> (translation track, rotation track)
    type Tracks = (Option<Track<DVec3>>, Option<Track<DQuat>>);
    let mut tracks: BTreeMap<usize, Tracks> = BTreeMap::new();
    for ch in anim.channels() {
        let node = ch.target().node();
        let node_name = node.name().unwrap_or("").to_string();
        let bad = |reason: &str| GltfError::BadChannel {
            node: node_name.clone(),
            reason: reason.into(),
        };
        let interpolation = match ch.sampler().interpolation() {
            gltf::animation::Interpolation::Linear => Interp::Linear,
            gltf::animation::Interpolation::Step => Interp::Step,
            gltf::animation::Interpolation::CubicSpline => {
                return Err(bad("CUBICSPLINE interpolation is not supported"))
            }
        };
        let reader = ch.reader(|buffer| match buffer.source() {
            gltf::buffer::Source::Bin => Some(blob),
            gltf::buffer::Source::Uri(_) => None,
        });
        let times: Vec<f64> = reader
            .read_inputs()
            .ok_or_else(|| bad("cannot read the key times"))?
            .map(f64::from)
            .collect();
        if times.is_empty() || times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(bad("key times are empty or not strictly increasing"));
        }
        let entry = tracks.entry(node.index()).or_default();
        match reader.read_outputs() {
            Some(gltf::animation::util::ReadOutputs::Translations(it)) => {
                let values: Vec<DVec3> = it.map(|p| pos_from_gltf(from_f32(p))).collect();
                if values.len() != times.len() {
                    return Err(bad("translation count differs from key count"));
                }
                entry.0 = Some(Track {
                    times,
                    values,
                    interpolation,
                });
            }
            Some(gltf::animation::util::ReadOutputs::Rotations(r)) => {
                let values: Vec<DQuat> = r
                    .into_f32()
                    .map(|q| quat_from_gltf(quat_from_f32(q)))
                    .collect();
                if values.len() != times.len() {
                    return Err(bad("rotation count differs from key count"));
                }
                if values.iter().any(|q| !q.is_finite() || q.length() < 0.5) {
                    return Err(bad("rotation keys are not unit quaternions"));
                }
                entry.1 = Some(Track {
                    times,
                    values,
                    interpolation,
                });
            }
            // Scale and morph weights do not move a rigid body's frame.
            Some(_) => {}
            None => return Err(bad("cannot read the key values")),
        }
    }

    let mut out = Vec::with_capacity(tracks.len());
    for (index, (tr, rot)) in tracks {
        let node = doc
            .nodes()
            .nth(index)
            .ok_or_else(|| GltfError::BadChannel {
                node: format!("#{index}"),
                reason: "targets a missing node".into(),
            })?;
        let (t0, r0, _) = node.transform().decomposed();
        let p = match &tr {
            Some(track) => track.sample(time, |a, b, s| a.lerp(b, s)),
            None => pos_from_gltf(from_f32(t0)),
        };
        let q = match &rot {
            Some(track) => track.sample(time, |a, b, s| a.slerp(b, s)),
            None => quat_from_gltf(quat_from_f32(r0)),
        };
        out.push((node.name().unwrap_or("").to_string(), p, q.normalize()));
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------
// Animation evaluation (reader side).
// ---------------------------------------------------------------------------------

#[derive(Clone, Copy)]
pub(super) enum Interp {
    Linear,
    Step,
}

pub(super) struct Track<T> {
    pub(super) times: Vec<f64>,
    pub(super) values: Vec<T>,
    pub(super) interpolation: Interp,
}

impl<T: Copy> Track<T> {
    pub(super) fn sample(&self, time: f64, mix: impl Fn(T, T, f64) -> T) -> T {
        let last = self.times.len() - 1;
        if time <= self.times[0] {
            return self.values[0];
        }
        if time >= self.times[last] {
            return self.values[last];
        }
        // First key strictly after `time`; it exists and is > 0 after the clamps above.
        let k = self.times.partition_point(|&x| x <= time);
        let (a, b) = (k - 1, k);
        match self.interpolation {
            Interp::Step => self.values[a],
            Interp::Linear => {
                let s = (time - self.times[a]) / (self.times[b] - self.times[a]);
                mix(self.values[a], self.values[b], s)
            }
        }
    }
}
