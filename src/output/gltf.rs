//! Animated glTF 2.0 binary (.glb) export of a solved scene, and a reader for checking it.
//!
//! Data flow: a validated [`Scene`] plus a sampled [`Trajectory`] (one pose per occluder
//! per simulation step) go into [`write_glb`], which builds a `gltf::json::Root` and one
//! binary buffer with a private `Builder` (meshes from [`Shape`]s, materials, the
//! receiver quad, the table box, a KHR_lights_punctual point light, two cameras and one
//! LINEAR animation named `flight`) and returns the bytes of a .glb. [`read_poses_at`]
//! parses such bytes again with the `gltf` crate and evaluates every animated node at a
//! time, which is how the tests (and anyone downstream) check that what Blender or a web
//! viewer will see is what the simulation computed. Errors of both directions are
//! [`GltfError`]s. See `docs/gltf.md` for the file's content and how to validate it.
//!
//! Axes: the project's world is right-handed Z-up, glTF is right-handed Y-up; a point
//! `(x, y, z)` is written `(x, z, -y)`, i.e. the change of axes `C` is a rotation of -90
//! degrees about X. A body pose `(o, R)` becomes the node transform `(C o, C R C^-1)`
//! and the mesh vertices are written as `C p_body`, so that
//! `C (R p + o) = (C R C^-1)(C p) + C o`: one node per occluder carries both the mesh and
//! the animation, and the importer's inverse change of axes gives the Z-up world back.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DMat3, DQuat, DVec3};
use gltf::json;
use json::validation::{Checked::Valid, USize64};
use json::Index;

use crate::geometry::shape::{Shape, TriMesh};
use crate::scene::Scene;

/// Value of `asset.generator` and of the scene extras' `generator`.
pub const GENERATOR: &str = "ballistic-shadow-art";
/// Name of the single animation.
pub const ANIMATION_NAME: &str = "flight";
/// Luminous intensity of the point light (cd). Only its presence and position matter for
/// hard shadows; 1000 cd lights a receiver a few metres away well in a PBR viewer.
pub const LIGHT_INTENSITY_CD: f64 = 1000.0;

/// UV sphere resolution: segments around the polar axis and rings from pole to pole.
/// 128 x 64 keeps the inscribed polyhedron's shadow within about a pixel of the exact
/// sphere's at 640 x 480 (48 x 24 left 261 of 84k Mickey pixels uncovered in Cycles).
const SPHERE_SEGMENTS: usize = 128;
const SPHERE_RINGS: usize = 64;
/// The receiver quad is this much larger than the image rectangle so that the view
/// camera shows shadows that leave the picture, while the shadow camera frames exactly
/// the rectangle.
const RECEIVER_MARGIN: f64 = 1.5;
/// Faces of an OBJ mesh whose normals differ by more than this share no vertex normal
/// (crease angle): cubes stay flat, finely tessellated curved surfaces look smooth.
const CREASE_ANGLE_DEG: f64 = 40.0;
/// Field of view of the perspective `camera_view` (vertical) and its aspect ratio.
const VIEW_YFOV_DEG: f64 = 40.0;
const VIEW_ASPECT: f64 = 16.0 / 9.0;
/// Elevation of `camera_view` above the horizontal (degrees).
const VIEW_ELEVATION_DEG: f64 = 35.0;

/// Sampled flight of all occluders, one key per simulation step.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Key times (s), strictly increasing from 0; contains t exactly (at index `t_index`).
    pub times: Vec<f64>,
    /// poses[k][i]: occluder i at times[k], (body origin, body->world orientation), Z-up world.
    pub poses: Vec<Vec<(DVec3, DQuat)>>,
    pub t_index: usize,
    /// Frames per second the animation is meant for (1/dt of the scene).
    pub fps: f64,
}

/// Why a .glb could not be written or read back.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// `write_glb`: the trajectory has no key at all.
    #[error("the trajectory has no keys")]
    EmptyTrajectory,
    /// `write_glb`: `times` and `poses` have different lengths.
    #[error("the trajectory has {times} key times but {poses} pose lists")]
    KeyCount { times: usize, poses: usize },
    /// `write_glb`: a pose list does not have one pose per occluder.
    #[error("key {key} has {got} poses but the scene has {expected} occluders")]
    OccluderCount {
        key: usize,
        expected: usize,
        got: usize,
    },
    /// `write_glb`: a key time is negative, not finite, or not strictly after the previous
    /// one once stored as f32 (glTF stores times as f32; keys closer than its resolution
    /// would collapse).
    #[error("key time {index} ({time} s) is negative, not finite, or not strictly after the previous key in f32")]
    TimesNotIncreasing { index: usize, time: f64 },
    /// `write_glb`: `t_index` is not an index of `times`.
    #[error("t_index {t_index} is out of range for {keys} keys")]
    TIndexOutOfRange { t_index: usize, keys: usize },
    /// `write_glb`: `times[t_index]` is not the scene's instant `t`.
    #[error("times[t_index] = {key_time} s is not the scene's t = {t} s")]
    TNotAKey { t: f64, key_time: f64 },
    /// `write_glb`: `fps` is not a positive finite number.
    #[error("fps must be positive and finite, got {0}")]
    BadFps(f64),
    /// `write_glb`: a pose, the light or the receiver holds a NaN or infinity.
    #[error("{0} is not finite")]
    NonFinite(String),
    /// `write_glb`: an occluder mesh has no triangle of non-zero area.
    #[error("occluder `{0}` has a mesh without any non-degenerate triangle")]
    EmptyMesh(String),
    /// `write_glb`: the binary buffer would exceed the 4 GiB a GLB can hold.
    #[error("the binary buffer would exceed the GLB size limit")]
    TooLarge,
    /// `write_glb`: serialising the JSON chunk failed.
    #[error("cannot serialise the glTF JSON")]
    Json(#[from] serde_json::Error),
    /// `write_glb`: assembling the GLB container failed.
    #[error("cannot assemble the GLB")]
    Write(#[source] gltf::Error),
    /// `read_poses_at`: the bytes are not a valid glTF/GLB.
    #[error("cannot parse the glTF")]
    Parse(#[source] gltf::Error),
    /// `read_poses_at`: the GLB has no binary chunk.
    #[error("the GLB has no binary chunk")]
    MissingBinary,
    /// `read_poses_at`: the file has no animation.
    #[error("the glTF has no animation")]
    NoAnimation,
    /// `read_poses_at`: a channel of the animation cannot be evaluated.
    #[error("animation channel of node `{node}`: {reason}")]
    BadChannel { node: String, reason: String },
}

/// Write the scene and its flight as a .glb (bytes only; the caller decides where they go).
///
/// Every occluder becomes a node named like it, carrying its mesh and a translation and
/// a rotation channel with one LINEAR key per entry of `traj.times`; the static transform
/// of those nodes is the pose at `t`, so that a viewer that ignores animations shows the
/// picture.
pub fn write_glb(scene: &Scene, traj: &Trajectory) -> Result<Vec<u8>, GltfError> {
    check_input(scene, traj)?;
    let mut b = Builder::new();

    let mut scene_nodes = Vec::new();

    // Occluders: node i is occluder i, which `read_poses_at` does not rely on but keeps
    // the file easy to read.
    let n = scene.occluders.len();
    let mut occluder_nodes = Vec::with_capacity(n);
    for (i, occ) in scene.occluders.iter().enumerate() {
        let data = match &occ.shape {
            Shape::Sphere { radius } => sphere_mesh(*radius),
            Shape::Cuboid { half_extents } => cuboid_mesh(*half_extents),
            Shape::Mesh(mesh) => {
                let d = trimesh_mesh(mesh);
                if d.indices.is_empty() {
                    return Err(GltfError::EmptyMesh(occ.name.clone()));
                }
                d
            }
        };
        let material = b.material(&occ.name, occluder_colour(i), 0.5);
        let mesh = b.mesh(&occ.name, &data, material)?;
        let (o, q) = traj.poses[traj.t_index][i];
        let node = b.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(occ.name.clone()),
            translation: Some(to_f32(pos_to_gltf(o))),
            rotation: Some(json::scene::UnitQuaternion(quat_to_f32(quat_to_gltf(q)))),
            ..Default::default()
        });
        occluder_nodes.push(node);
        scene_nodes.push(node);
    }

    // Receiver: a white quad around the image rectangle, front face towards the light.
    let rc = &scene.receiver;
    let white = b.material("white", [1.0, 1.0, 1.0, 1.0], 1.0);
    let quad = quad_mesh(
        rc.u * (RECEIVER_MARGIN * rc.width / 2.0),
        rc.v * (RECEIVER_MARGIN * rc.height / 2.0),
        rc.normal,
    );
    let mesh = b.mesh("receiver", &quad, white)?;
    scene_nodes.push(b.root.push(json::Node {
        mesh: Some(mesh),
        name: Some("receiver".into()),
        translation: Some(to_f32(pos_to_gltf(rc.center))),
        ..Default::default()
    }));

    // Table: the same white as the receiver, because its top face usually lies in the
    // receiver plane and two coplanar surfaces of different colours flicker in viewers.
    if let Some(table) = &scene.table {
        let mesh = b.mesh("table", &cuboid_mesh(table.half_extents), white)?;
        scene_nodes.push(b.root.push(json::Node {
            mesh: Some(mesh),
            name: Some("table".into()),
            translation: Some(to_f32(pos_to_gltf(table.center))),
            ..Default::default()
        }));
    }

    // Point light (KHR_lights_punctual): intensity in candela, infinite range.
    let light = b
        .root
        .push(json::extensions::scene::khr_lights_punctual::Light {
            color: [1.0, 1.0, 1.0],
            extensions: None,
            extras: Default::default(),
            intensity: LIGHT_INTENSITY_CD as f32,
            name: Some("light".into()),
            range: None,
            spot: None,
            type_: Valid(json::extensions::scene::khr_lights_punctual::Type::Point),
        });
    b.root.extensions_used.push("KHR_lights_punctual".into());
    // The update syntax keeps this compiling if someone enables gltf's `extensions`
    // feature, which adds a field to the node extensions.
    #[allow(clippy::needless_update)]
    let light_ext = json::extensions::scene::Node {
        khr_lights_punctual: Some(
            json::extensions::scene::khr_lights_punctual::KhrLightsPunctual { light },
        ),
        ..Default::default()
    };
    scene_nodes.push(b.root.push(json::Node {
        name: Some("light".into()),
        translation: Some(to_f32(pos_to_gltf(scene.light))),
        extensions: Some(light_ext),
        ..Default::default()
    }));

    let (w_px, h_px) = (scene.target.width(), scene.target.height());
    scene_nodes.push(shadow_camera(&mut b, scene, w_px, h_px)?);
    scene_nodes.push(view_camera(&mut b, scene, traj));

    flight_animation(&mut b, traj, &occluder_nodes)?;

    let extras = serde_json::json!({
        "t": scene.t,
        "fps": traj.fps,
        "t_frame": scene.t * traj.fps,
        "dt": scene.dt,
        "target_width": w_px,
        "target_height": h_px,
        "scene": scene.name,
        "generator": GENERATOR,
    });
    let gltf_scene = b.root.push(json::Scene {
        extensions: None,
        extras: Some(serde_json::value::to_raw_value(&extras)?),
        name: Some(scene.name.clone()),
        nodes: scene_nodes,
    });
    b.root.scene = Some(gltf_scene);
    b.finish()
}

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
// Input checks.
// ---------------------------------------------------------------------------------

fn check_input(scene: &Scene, traj: &Trajectory) -> Result<(), GltfError> {
    let keys = traj.times.len();
    if keys == 0 {
        return Err(GltfError::EmptyTrajectory);
    }
    if traj.poses.len() != keys {
        return Err(GltfError::KeyCount {
            times: keys,
            poses: traj.poses.len(),
        });
    }
    let mut prev: Option<f32> = None;
    for (index, &time) in traj.times.iter().enumerate() {
        let t32 = time as f32;
        if !time.is_finite() || time < 0.0 || prev.is_some_and(|p| t32 <= p) {
            return Err(GltfError::TimesNotIncreasing { index, time });
        }
        prev = Some(t32);
    }
    if traj.t_index >= keys {
        return Err(GltfError::TIndexOutOfRange {
            t_index: traj.t_index,
            keys,
        });
    }
    // The lead builds times as k * dt; allow the rounding of that product, nothing more.
    let key_time = traj.times[traj.t_index];
    if (key_time - scene.t).abs() > 1e-9 * scene.t.abs().max(1.0) {
        return Err(GltfError::TNotAKey {
            t: scene.t,
            key_time,
        });
    }
    if !(traj.fps.is_finite() && traj.fps > 0.0) {
        return Err(GltfError::BadFps(traj.fps));
    }
    let n = scene.occluders.len();
    for (key, poses) in traj.poses.iter().enumerate() {
        if poses.len() != n {
            return Err(GltfError::OccluderCount {
                key,
                expected: n,
                got: poses.len(),
            });
        }
        for (i, (o, q)) in poses.iter().enumerate() {
            if !o.is_finite() || !q.is_finite() || q.length() < 0.5 {
                return Err(GltfError::NonFinite(format!(
                    "pose of occluder `{}` at key {key}",
                    scene.occluders[i].name
                )));
            }
        }
    }
    let rc = &scene.receiver;
    for (what, v) in [
        ("the light position", scene.light),
        ("the receiver centre", rc.center),
        ("the receiver axes", rc.u + rc.v + rc.normal),
        ("the receiver size", DVec3::new(rc.width, rc.height, 0.0)),
    ] {
        if !v.is_finite() {
            return Err(GltfError::NonFinite(what.into()));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------
// Axes.
// ---------------------------------------------------------------------------------

/// Z-up world -> glTF Y-up: `C p` with `C` the rotation of -90 degrees about X.
fn pos_to_gltf(p: DVec3) -> DVec3 {
    // `0.0 - y` rather than `-y` so that a zero is written as 0, not -0.
    DVec3::new(p.x, p.z, 0.0 - p.y)
}

/// glTF Y-up -> Z-up world: `C^-1 p`.
fn pos_from_gltf(p: DVec3) -> DVec3 {
    DVec3::new(p.x, 0.0 - p.z, p.y)
}

/// `C q C^-1`: the scalar part is unchanged and the vector part rotates like a point;
/// written component-wise so that it is exact.
fn quat_to_gltf(q: DQuat) -> DQuat {
    DQuat::from_xyzw(q.x, q.z, -q.y, q.w)
}

fn quat_from_gltf(q: DQuat) -> DQuat {
    DQuat::from_xyzw(q.x, -q.z, q.y, q.w)
}

/// The change of axes as a rotation, for frames that are glTF-native (cameras).
fn axes_rotation() -> DQuat {
    DQuat::from_rotation_x(-FRAC_PI_2)
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

fn from_f32(v: [f32; 3]) -> DVec3 {
    DVec3::new(v[0].into(), v[1].into(), v[2].into())
}

fn quat_to_f32(q: DQuat) -> [f32; 4] {
    let q = q.normalize();
    [q.x as f32, q.y as f32, q.z as f32, q.w as f32]
}

fn quat_from_f32(q: [f32; 4]) -> DQuat {
    DQuat::from_xyzw(q[0].into(), q[1].into(), q[2].into(), q[3].into()).normalize()
}

// ---------------------------------------------------------------------------------
// Animation evaluation (reader side).
// ---------------------------------------------------------------------------------

#[derive(Clone, Copy)]
enum Interp {
    Linear,
    Step,
}

struct Track<T> {
    times: Vec<f64>,
    values: Vec<T>,
    interpolation: Interp,
}

impl<T: Copy> Track<T> {
    fn sample(&self, time: f64, mix: impl Fn(T, T, f64) -> T) -> T {
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

// ---------------------------------------------------------------------------------
// Building the document.
// ---------------------------------------------------------------------------------

/// Mesh data in the Z-up body frame, before the change of axes.
struct MeshData {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    indices: Vec<u32>,
}

struct Builder {
    root: json::Root,
    bin: Vec<u8>,
}

impl Builder {
    fn new() -> Self {
        let root = json::Root {
            asset: json::Asset {
                copyright: None,
                extensions: None,
                extras: Default::default(),
                generator: Some(GENERATOR.into()),
                min_version: None,
                version: "2.0".into(),
            },
            ..Default::default()
        };
        Builder {
            root,
            bin: Vec::new(),
        }
    }

    /// Append one buffer view, 4-byte aligned (every component here is 4 bytes wide).
    fn view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// A float accessor of `type_` over `components` (flat), with min/max when asked:
    /// the validator wants them on POSITION and on animation inputs only.
    fn float_accessor(
        &mut self,
        components: &[f32],
        type_: json::accessor::Type,
        width: usize,
        with_bounds: bool,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = components.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let (min, max) = if with_bounds {
            let mut lo = vec![f32::INFINITY; width];
            let mut hi = vec![f32::NEG_INFINITY; width];
            for chunk in components.chunks(width) {
                for (j, &x) in chunk.iter().enumerate() {
                    lo[j] = lo[j].min(x);
                    hi[j] = hi[j].max(x);
                }
            }
            (Some(serde_json::json!(lo)), Some(serde_json::json!(hi)))
        } else {
            (None, None)
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64((components.len() / width) as u64),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::F32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn index_accessor(&mut self, indices: &[u32]) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ElementArrayBuffer));
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(indices.len() as u64),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::U32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(json::accessor::Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn material(&mut self, name: &str, rgba: [f32; 4], roughness: f32) -> Index<json::Material> {
        self.root.push(json::Material {
            name: Some(name.into()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(rgba),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(roughness),
                ..Default::default()
            },
            ..Default::default()
        })
    }

    /// One triangle-list primitive, its data converted to glTF axes.
    fn mesh(
        &mut self,
        name: &str,
        data: &MeshData,
        material: Index<json::Material>,
    ) -> Result<Index<json::Mesh>, GltfError> {
        if data.positions.len() > u32::MAX as usize || data.indices.len() > u32::MAX as usize {
            return Err(GltfError::TooLarge);
        }
        let flat = |vs: &[DVec3]| -> Vec<f32> {
            vs.iter()
                .flat_map(|&p| to_f32(pos_to_gltf(p)))
                .collect::<Vec<f32>>()
        };
        let positions = self.float_accessor(
            &flat(&data.positions),
            json::accessor::Type::Vec3,
            3,
            true,
            Some(json::buffer::Target::ArrayBuffer),
        );
        let normals = self.float_accessor(
            &flat(&data.normals),
            json::accessor::Type::Vec3,
            3,
            false,
            Some(json::buffer::Target::ArrayBuffer),
        );
        let indices = self.index_accessor(&data.indices);
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
        attributes.insert(Valid(json::mesh::Semantic::Normals), normals);
        Ok(self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.into()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        }))
    }

    fn finish(mut self) -> Result<Vec<u8>, GltfError> {
        // Pad here so that the buffer's byteLength equals the BIN chunk length exactly.
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        // Header (12) + two chunk headers (16) + JSON, all lengths u32.
        if self.bin.len() > (u32::MAX as usize) / 2 {
            return Err(GltfError::TooLarge);
        }
        self.root.push(json::Buffer {
            byte_length: USize64(self.bin.len() as u64),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let json_bytes = serde_json::to_vec(&self.root)?;
        if json_bytes.len() + self.bin.len() + 64 > u32::MAX as usize {
            return Err(GltfError::TooLarge);
        }
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                // `to_vec` computes and writes the real length.
                length: 0,
            },
            json: Cow::Owned(json_bytes),
            bin: Some(Cow::Owned(self.bin)),
        };
        glb.to_vec().map_err(GltfError::Write)
    }
}

/// Orthographic camera looking at the receiver along -normal from the light's side,
/// image right = u, image up = v, framing exactly the image rectangle.
fn shadow_camera(
    b: &mut Builder,
    scene: &Scene,
    w_px: usize,
    h_px: usize,
) -> Result<Index<json::Node>, GltfError> {
    let rc = &scene.receiver;
    // Stand at the light's distance from the plane: in front of everything the light
    // sees on the receiver. Orthographic, so the distance does not change the framing.
    let d = (scene.light - rc.center).dot(rc.normal).abs().max(1.0);
    let pixel_aspect = (rc.width / w_px as f64) / (rc.height / h_px as f64);
    let extras = serde_json::json!({
        "aspect": rc.width / rc.height,
        "target_width": w_px,
        "target_height": h_px,
        "pixel_aspect": pixel_aspect,
    });
    let camera = b.root.push(json::Camera {
        name: Some("camera_shadow".into()),
        orthographic: Some(json::camera::Orthographic {
            xmag: (rc.width / 2.0) as f32,
            ymag: (rc.height / 2.0) as f32,
            zfar: (1.5 * d + 1.0) as f32,
            znear: (0.001 * d) as f32,
            extensions: None,
            extras: Default::default(),
        }),
        perspective: None,
        type_: Valid(json::camera::Type::Orthographic),
        extensions: None,
        extras: Some(serde_json::value::to_raw_value(&extras)?),
    });
    // glTF cameras look along local -Z with +Y up: local axes (x, y, z) = (u, v, n).
    let frame = DQuat::from_mat3(&DMat3::from_cols(rc.u, rc.v, rc.normal));
    let rotation = axes_rotation() * frame;
    Ok(b.root.push(json::Node {
        camera: Some(camera),
        name: Some("camera_shadow".into()),
        translation: Some(to_f32(pos_to_gltf(rc.center + rc.normal * d))),
        rotation: Some(json::scene::UnitQuaternion(quat_to_f32(rotation))),
        ..Default::default()
    }))
}

/// Perspective camera that shows the whole flight and the receiver: from in front of the
/// picture's bottom edge, a little to the side, 35 degrees above the horizontal (world Z),
/// looking at the receiver centre, far enough that everything fits in the vertical fov.
fn view_camera(b: &mut Builder, scene: &Scene, traj: &Trajectory) -> Index<json::Node> {
    let rc = &scene.receiver;
    let target = rc.center;
    // Content radius about the target: the receiver quad and every body at every key.
    let mut r: f64 = 0.5 * RECEIVER_MARGIN * rc.width.hypot(rc.height);
    for poses in &traj.poses {
        for ((o, _), occ) in poses.iter().zip(&scene.occluders) {
            // The bounding radius about the body origin holds the body in any orientation.
            r = r.max((*o - target).length() + occ.shape.bounding_radius(DVec3::ZERO));
        }
    }
    let up = DVec3::Z;
    let base = rc.normal * 0.8 - rc.v + rc.u * 0.3;
    let horizontal = (base - up * base.dot(up))
        .try_normalize()
        .unwrap_or(-DVec3::Y);
    let elev = VIEW_ELEVATION_DEG.to_radians();
    let dir = (horizontal * elev.cos() + up * elev.sin()).normalize();
    let half_fov = (VIEW_YFOV_DEG.to_radians() / 2.0)
        .min((VIEW_ASPECT * (VIEW_YFOV_DEG.to_radians() / 2.0).tan()).atan());
    let dist = 1.05 * r / half_fov.sin();
    let camera = b.root.push(json::Camera {
        name: Some("camera_view".into()),
        orthographic: None,
        perspective: Some(json::camera::Perspective {
            aspect_ratio: Some(VIEW_ASPECT as f32),
            yfov: VIEW_YFOV_DEG.to_radians() as f32,
            zfar: Some((dist + 2.0 * r + 1.0) as f32),
            znear: (0.01 * dist).clamp(0.01, 1.0) as f32,
            extensions: None,
            extras: Default::default(),
        }),
        type_: Valid(json::camera::Type::Perspective),
        extensions: None,
        extras: Default::default(),
    });
    // Local +Z points back at the camera; +X to the right, level with the horizon.
    let z = dir;
    let x = up.cross(z).try_normalize().unwrap_or(DVec3::X);
    let y = z.cross(x);
    let rotation = axes_rotation() * DQuat::from_mat3(&DMat3::from_cols(x, y, z));
    b.root.push(json::Node {
        camera: Some(camera),
        name: Some("camera_view".into()),
        translation: Some(to_f32(pos_to_gltf(target + dir * dist))),
        rotation: Some(json::scene::UnitQuaternion(quat_to_f32(rotation))),
        ..Default::default()
    })
}

/// The single animation: one shared time accessor, a translation and a rotation sampler
/// per occluder, LINEAR, one key per simulation step.
fn flight_animation(
    b: &mut Builder,
    traj: &Trajectory,
    nodes: &[Index<json::Node>],
) -> Result<(), GltfError> {
    if nodes.is_empty() {
        // An animation without channels is invalid glTF; a scene without occluders
        // simply has no animation.
        return Ok(());
    }
    let times: Vec<f32> = traj.times.iter().map(|&t| t as f32).collect();
    let input = b.float_accessor(&times, json::accessor::Type::Scalar, 1, true, None);
    let mut samplers = Vec::with_capacity(2 * nodes.len());
    let mut channels = Vec::with_capacity(2 * nodes.len());
    for (i, &node) in nodes.iter().enumerate() {
        let translations: Vec<f32> = traj
            .poses
            .iter()
            .flat_map(|p| to_f32(pos_to_gltf(p[i].0)))
            .collect();
        // Keep consecutive keys in one hemisphere: LINEAR interpolation between q and -q
        // would sweep through a full turn (and Blender blends components, nlerp).
        let mut rotations = Vec::with_capacity(4 * traj.poses.len());
        let mut prev: Option<DQuat> = None;
        for p in &traj.poses {
            let mut q = quat_to_gltf(p[i].1).normalize();
            if prev.is_some_and(|pq| pq.dot(q) < 0.0) {
                q = -q;
            }
            prev = Some(q);
            rotations.extend(quat_to_f32(q));
        }
        let t_out = b.float_accessor(&translations, json::accessor::Type::Vec3, 3, false, None);
        let r_out = b.float_accessor(&rotations, json::accessor::Type::Vec4, 4, false, None);
        for (output, path) in [
            (t_out, json::animation::Property::Translation),
            (r_out, json::animation::Property::Rotation),
        ] {
            let sampler = Index::push(
                &mut samplers,
                json::animation::Sampler {
                    extensions: None,
                    extras: Default::default(),
                    input,
                    interpolation: Valid(json::animation::Interpolation::Linear),
                    output,
                },
            );
            channels.push(json::animation::Channel {
                sampler,
                target: json::animation::Target {
                    extensions: None,
                    extras: Default::default(),
                    node,
                    path: Valid(path),
                },
                extensions: None,
                extras: Default::default(),
            });
        }
    }
    b.root.push(json::Animation {
        extensions: None,
        extras: Default::default(),
        channels,
        name: Some(ANIMATION_NAME.into()),
        samplers,
    });
    Ok(())
}

/// Distinct, saturated colours: hues spaced by the golden angle never repeat closely.
fn occluder_colour(i: usize) -> [f32; 4] {
    let h = (0.08 + i as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = (0.75, 0.9);
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [(r + m) as f32, (g + m) as f32, (b + m) as f32, 1.0]
}

// ---------------------------------------------------------------------------------
// Meshes (Z-up body frame).
// ---------------------------------------------------------------------------------

/// UV sphere with smooth normals. Pole rows are duplicated per segment (so that the seam
/// and poles need no special normals), and the degenerate triangles at the poles are left
/// out.
fn sphere_mesh(radius: f64) -> MeshData {
    let (s, r) = (SPHERE_SEGMENTS, SPHERE_RINGS);
    let mut positions = Vec::with_capacity((r + 1) * (s + 1));
    let mut normals = Vec::with_capacity((r + 1) * (s + 1));
    for i in 0..=r {
        let theta = PI * i as f64 / r as f64;
        for j in 0..=s {
            let phi = 2.0 * PI * j as f64 / s as f64;
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            positions.push(n * radius);
            normals.push(n);
        }
    }
    let mut indices = Vec::with_capacity(6 * r * s);
    for i in 0..r {
        for j in 0..s {
            let a = (i * (s + 1) + j) as u32;
            let b = a + (s + 1) as u32;
            // (e_theta, e_phi, e_r) is right-handed, so a -> b (south) -> b+1 (east) is
            // counter-clockwise seen from outside.
            if i != r - 1 {
                indices.extend([a, b, b + 1]);
            }
            if i != 0 {
                indices.extend([a, b + 1, a + 1]);
            }
        }
    }
    MeshData {
        positions,
        normals,
        indices,
    }
}

/// 24-vertex box: four vertices per face so that every face has its own flat normal.
fn cuboid_mesh(h: DVec3) -> MeshData {
    let e = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut positions = Vec::with_capacity(24);
    let mut normals = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(36);
    for k in 0..3 {
        for sign in [1.0, -1.0] {
            let n = e[k] * sign;
            // In-face axes (a, b) with a x b = n, so the corner order below is CCW.
            let (a, b) = if sign > 0.0 {
                (e[(k + 1) % 3], e[(k + 2) % 3])
            } else {
                (e[(k + 2) % 3], e[(k + 1) % 3])
            };
            let base = positions.len() as u32;
            for (p, q) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(h * (n + a * p + b * q));
                normals.push(n);
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    MeshData {
        positions,
        normals,
        indices,
    }
}

/// Rectangle centred on the origin spanned by half-axes `hu`, `hv`, front face along `n`
/// (`hu x hv` is along `n`).
fn quad_mesh(hu: DVec3, hv: DVec3, n: DVec3) -> MeshData {
    let n = n.normalize();
    let positions = vec![-hu - hv, hu - hv, hu + hv, -hu + hv];
    let indices = if hu.cross(hv).dot(n) >= 0.0 {
        vec![0, 1, 2, 0, 2, 3]
    } else {
        vec![0, 2, 1, 0, 3, 2]
    };
    MeshData {
        positions,
        normals: vec![n; 4],
        indices,
    }
}

/// Triangle mesh with crease-angle normals: each corner averages (area-weighted) the
/// normals of the faces around its vertex that are within the crease angle of its own
/// face; corners with the same vertex and normal share one output vertex. Zero-area
/// triangles are dropped: they have no normal and draw nothing.
fn trimesh_mesh(mesh: &TriMesh) -> MeshData {
    let cos_crease = CREASE_ANGLE_DEG.to_radians().cos();
    let nv = mesh.vertices.len();
    let scale = mesh
        .vertices
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs().max_element()))
        .max(f64::MIN_POSITIVE);
    let mut faces: Vec<([u32; 3], DVec3, DVec3)> = Vec::with_capacity(mesh.triangles.len());
    for tri in &mesh.triangles {
        if tri.iter().any(|&i| i as usize >= nv) {
            continue;
        }
        let [a, b, c] = tri.map(|i| mesh.vertices[i as usize]);
        let area_n = (b - a).cross(c - a);
        if area_n.length() <= 1e-12 * scale * scale {
            continue;
        }
        faces.push((*tri, area_n, area_n.normalize()));
    }
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); nv];
    for (f, (tri, _, _)) in faces.iter().enumerate() {
        for &i in tri {
            incident[i as usize].push(f);
        }
    }
    let mut out = MeshData {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::with_capacity(3 * faces.len()),
    };
    let mut shared: HashMap<(u32, [u64; 3]), u32> = HashMap::new();
    for (tri, _, unit) in &faces {
        for &vi in tri {
            let sum: DVec3 = incident[vi as usize]
                .iter()
                .filter(|&&g| faces[g].2.dot(*unit) >= cos_crease)
                .map(|&g| faces[g].1)
                .sum();
            let n = sum.try_normalize().unwrap_or(*unit);
            let key = (vi, [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()]);
            let index = *shared.entry(key).or_insert_with(|| {
                out.positions.push(mesh.vertices[vi as usize]);
                out.normals.push(n);
                (out.positions.len() - 1) as u32
            });
            out.indices.push(index);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::RESERVED_NAMES;
    use std::collections::HashSet;
    use std::path::PathBuf;
    use std::sync::Arc;

    fn root_dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    fn mickey() -> Scene {
        crate::scene::load(&root_dir().join("scenes/mickey")).expect("scenes/mickey loads")
    }

    /// Mickey with a box, an OBJ-like cube mesh and a tilted launch orientation, to cover
    /// every shape kind.
    fn shapes_scene() -> Scene {
        let mut s = mickey();
        s.occluders[0].shape = Shape::Cuboid {
            half_extents: DVec3::new(0.4, 0.25, 0.15),
        };
        s.occluders[0].orientation = DQuat::from_rotation_z(0.3) * DQuat::from_rotation_x(0.2);
        let box_mesh = cuboid_mesh(DVec3::new(0.2, 0.3, 0.1));
        // Re-index the 24-vertex box into an 8-vertex closed mesh, as an OBJ would be.
        let mut verts: Vec<DVec3> = Vec::new();
        let tris: Vec<[u32; 3]> = box_mesh
            .indices
            .chunks(3)
            .map(|c| {
                let mut t = [0u32; 3];
                for (k, &i) in c.iter().enumerate() {
                    let p = box_mesh.positions[i as usize];
                    let j = verts
                        .iter()
                        .position(|q| q.distance(p) < 1e-12)
                        .unwrap_or_else(|| {
                            verts.push(p);
                            verts.len() - 1
                        });
                    t[k] = j as u32;
                }
                t
            })
            .collect();
        assert_eq!(verts.len(), 8);
        s.name = "shapes".into();
        s.occluders[1].shape = Shape::Mesh(Arc::new(TriMesh::new(verts, tris)));
        s
    }

    /// Exact ballistic flight with a steady spin about a fixed axis per body, keyed every
    /// `dt` from 0 to `t + 1 s`, with `times[t_index] = t` exactly.
    fn ballistic(scene: &Scene) -> Trajectory {
        let dt = scene.dt;
        let n_t = (scene.t / dt).round() as usize;
        let n_end = n_t + (1.0 / dt).round() as usize;
        let mut times: Vec<f64> = (0..=n_end).map(|k| k as f64 * dt).collect();
        times[n_t] = scene.t;
        let poses = times
            .iter()
            .map(|&t| {
                scene
                    .occluders
                    .iter()
                    .enumerate()
                    .map(|(i, o)| {
                        let v = DVec3::new(0.3 * i as f64 - 0.2, 0.5, 7.0);
                        let p = o.position + v * t + 0.5 * scene.gravity * t * t;
                        let axis = DVec3::new(1.0, 2.0, 3.0 + i as f64).normalize();
                        let q = DQuat::from_axis_angle(axis, (3.0 + i as f64) * t) * o.orientation;
                        // Canonical sign (w >= 0), as many integrators return it: the
                        // key sequence then jumps between hemispheres.
                        (p, if q.w < 0.0 { -q } else { q })
                    })
                    .collect()
            })
            .collect();
        Trajectory {
            times,
            poses,
            t_index: n_t,
            fps: 1.0 / dt,
        }
    }

    fn angle(a: DQuat, b: DQuat) -> f64 {
        // 2 asin |vec(a^-1 b)| is well conditioned near zero, unlike acos of the dot.
        let d = a.conjugate() * b;
        2.0 * d.xyz().length().min(1.0).asin()
    }

    fn doc(glb: &[u8]) -> gltf::Gltf {
        gltf::Gltf::from_slice(glb).expect("the written GLB parses")
    }

    #[test]
    fn round_trip_at_t_between_keys_and_at_every_key() {
        for scene in [mickey(), shapes_scene()] {
            let traj = ballistic(&scene);
            let glb = write_glb(&scene, &traj).expect("writes");
            // Largest position (m) and angle (rad) error of the poses read at `time`.
            let check = |time: f64, expect: &[(DVec3, DQuat)]| -> (f64, f64) {
                let got = read_poses_at(&glb, time).expect("reads");
                assert_eq!(got.len(), scene.occluders.len());
                let (mut ep_max, mut er_max) = (0.0_f64, 0.0_f64);
                for ((name, p, q), (occ, (ep, eq))) in
                    got.iter().zip(scene.occluders.iter().zip(expect))
                {
                    assert_eq!(name, &occ.name);
                    ep_max = ep_max.max(p.distance(*ep));
                    er_max = er_max.max(angle(*q, *eq));
                }
                (ep_max, er_max)
            };
            // At t: the key itself.
            let (at_t_p, at_t_r) = check(scene.t, &traj.poses[traj.t_index]);
            let (mut max_p, mut max_r) = (at_t_p, at_t_r);
            // Between keys: LINEAR means lerp of origins and slerp of orientations.
            for k in [3, traj.t_index - 1, traj.times.len() - 2] {
                let s = 0.37;
                let time = traj.times[k] + s * (traj.times[k + 1] - traj.times[k]);
                let expect: Vec<(DVec3, DQuat)> = traj.poses[k]
                    .iter()
                    .zip(&traj.poses[k + 1])
                    .map(|(a, b)| (a.0.lerp(b.0, s), a.1.slerp(b.1, s)))
                    .collect();
                let (p, r) = check(time, &expect);
                (max_p, max_r) = (max_p.max(p), max_r.max(r));
            }
            for (k, &time) in traj.times.iter().enumerate() {
                let (p, r) = check(time, &traj.poses[k]);
                (max_p, max_r) = (max_p.max(p), max_r.max(r));
            }
            println!(
                "{}: at t {at_t_p:.2e} m {at_t_r:.2e} rad; all keys and between keys {max_p:.2e} m {max_r:.2e} rad",
                scene.name
            );
            // f32 storage of times and values: ~1e-7 relative, far inside the 1e-5 asked.
            assert!(at_t_p < 1e-5 && at_t_r < 1e-5, "{at_t_p} m {at_t_r} rad");
            assert!(max_p < 1e-5 && max_r < 1e-5, "{max_p} m {max_r} rad");
        }
    }

    #[test]
    fn one_linear_animation_with_a_key_exactly_at_t() {
        let scene = mickey();
        let traj = ballistic(&scene);
        let glb = write_glb(&scene, &traj).unwrap();
        let d = doc(&glb);
        assert_eq!(d.animations().count(), 1);
        let anim = d.animations().next().unwrap();
        assert_eq!(anim.name(), Some(ANIMATION_NAME));
        assert_eq!(anim.channels().count(), 2 * scene.occluders.len());
        let blob = d.blob.as_deref().unwrap();
        for ch in anim.channels() {
            assert_eq!(
                ch.sampler().interpolation(),
                gltf::animation::Interpolation::Linear
            );
            let input = ch.sampler().input();
            assert!(input.min().is_some() && input.max().is_some());
            let times: Vec<f32> = ch.reader(|_| Some(blob)).read_inputs().unwrap().collect();
            assert_eq!(times.len(), traj.times.len());
            assert_eq!(times[traj.t_index], scene.t as f32);
        }
        let paths: HashSet<(usize, bool)> = anim
            .channels()
            .map(|c| {
                (
                    c.target().node().index(),
                    c.target().property() == gltf::animation::Property::Rotation,
                )
            })
            .collect();
        assert_eq!(paths.len(), 2 * scene.occluders.len());
    }

    #[test]
    fn rotation_keys_stay_in_one_hemisphere() {
        let scene = mickey();
        let traj = ballistic(&scene); // spins of 3-5 rad/s over 2.2 s cross hemispheres
        let glb = write_glb(&scene, &traj).unwrap();
        let d = doc(&glb);
        let blob = d.blob.as_deref().unwrap();
        let mut crossings = 0;
        for ch in d.animations().next().unwrap().channels() {
            if let Some(gltf::animation::util::ReadOutputs::Rotations(r)) =
                ch.reader(|_| Some(blob)).read_outputs()
            {
                let qs: Vec<[f32; 4]> = r.into_f32().collect();
                for w in qs.windows(2) {
                    let dot: f32 = (0..4).map(|k| w[0][k] * w[1][k]).sum();
                    assert!(dot > 0.0);
                }
                let input: Vec<DQuat> = traj.poses.iter().map(|p| p[0].1).collect();
                crossings += input.windows(2).filter(|w| w[0].dot(w[1]) < 0.0).count();
            }
        }
        assert!(crossings > 0, "the test trajectory should need sign flips");
    }

    #[test]
    fn scene_extras_and_generator() {
        let scene = mickey();
        let traj = ballistic(&scene);
        let d = doc(&write_glb(&scene, &traj).unwrap());
        assert_eq!(d.as_json().asset.generator.as_deref(), Some(GENERATOR));
        let s = d.default_scene().unwrap();
        let extras: serde_json::Value =
            serde_json::from_str(s.extras().as_ref().unwrap().get()).unwrap();
        assert_eq!(extras["t"].as_f64(), Some(scene.t));
        assert_eq!(extras["fps"].as_f64(), Some(traj.fps));
        assert!((extras["t_frame"].as_f64().unwrap() - scene.t * traj.fps).abs() < 1e-12);
        assert_eq!(
            extras["target_width"].as_u64(),
            Some(scene.target.width() as u64)
        );
        assert_eq!(
            extras["target_height"].as_u64(),
            Some(scene.target.height() as u64)
        );
        assert_eq!(extras["generator"].as_str(), Some(GENERATOR));
    }

    #[test]
    fn node_names_light_and_cameras() {
        let scene = mickey();
        let traj = ballistic(&scene);
        let d = doc(&write_glb(&scene, &traj).unwrap());
        let names: Vec<&str> = d.nodes().filter_map(|n| n.name()).collect();
        for occ in &scene.occluders {
            assert!(names.contains(&occ.name.as_str()));
        }
        for n in RESERVED_NAMES {
            assert!(names.contains(&n), "{n}");
        }
        assert_eq!(names.len(), scene.occluders.len() + RESERVED_NAMES.len());
        assert!(d.extensions_used().any(|e| e == "KHR_lights_punctual"));

        let node = |name: &str| d.nodes().find(|n| n.name() == Some(name)).unwrap();
        let light = node("light").light().unwrap();
        assert_eq!(light.intensity(), LIGHT_INTENSITY_CD as f32);
        assert!(light.range().is_none());
        let (lt, _, _) = node("light").transform().decomposed();
        assert!(pos_from_gltf(from_f32(lt)).distance(scene.light) < 1e-6);

        let rc = &scene.receiver;
        let cam = node("camera_shadow");
        match cam.camera().unwrap().projection() {
            gltf::camera::Projection::Orthographic(o) => {
                assert_eq!(o.xmag(), (rc.width / 2.0) as f32);
                assert_eq!(o.ymag(), (rc.height / 2.0) as f32);
                assert!(o.znear() > 0.0 && o.zfar() > o.znear());
                // The receiver lies between the clipping planes.
                let (t, _, _) = cam.transform().decomposed();
                let dist = (pos_from_gltf(from_f32(t)) - rc.center).dot(rc.normal);
                assert!(dist > o.znear() as f64 && dist < o.zfar() as f64);
            }
            _ => panic!("camera_shadow must be orthographic"),
        }
        // Local -Z (view direction) is -normal and local +Y (image up) is v, in Z-up world.
        let (_, r, _) = cam.transform().decomposed();
        let q = axes_rotation().conjugate() * quat_from_f32(r);
        assert!((q * -DVec3::Z).distance(-rc.normal) < 1e-6);
        assert!((q * DVec3::Y).distance(rc.v) < 1e-6);
        assert!((q * DVec3::X).distance(rc.u) < 1e-6);

        let view = node("camera_view");
        match view.camera().unwrap().projection() {
            gltf::camera::Projection::Perspective(p) => {
                assert!((p.yfov() as f64 - VIEW_YFOV_DEG.to_radians()).abs() < 1e-6);
                assert!(p.aspect_ratio().is_some());
                // It looks at the receiver centre.
                let (t, r, _) = view.transform().decomposed();
                let eye = pos_from_gltf(from_f32(t));
                let q = axes_rotation().conjugate() * quat_from_f32(r);
                let to_target = (rc.center - eye).normalize();
                assert!((q * -DVec3::Z).distance(to_target) < 1e-6);
                assert!(eye.z > rc.center.z, "view from above");
            }
            _ => panic!("camera_view must be perspective"),
        }
    }

    #[test]
    fn world_z_is_gltf_y() {
        let scene = mickey();
        let mut traj = ballistic(&scene);
        for (k, poses) in traj.poses.iter_mut().enumerate() {
            for p in poses.iter_mut() {
                *p = (DVec3::new(1.0, 2.0, 0.1 * k as f64), DQuat::IDENTITY);
            }
        }
        let d = doc(&write_glb(&scene, &traj).unwrap());
        let blob = d.blob.as_deref().unwrap();
        let ch = d
            .animations()
            .next()
            .unwrap()
            .channels()
            .find(|c| c.target().property() == gltf::animation::Property::Translation)
            .unwrap();
        let Some(gltf::animation::util::ReadOutputs::Translations(it)) =
            ch.reader(|_| Some(blob)).read_outputs()
        else {
            panic!("translations")
        };
        let keys: Vec<[f32; 3]> = it.collect();
        for w in keys.windows(2) {
            assert!(w[1][1] > w[0][1], "world +z moves along glTF +y");
            assert_eq!(w[1][0], w[0][0]);
            assert_eq!(w[1][2], w[0][2]);
        }
        assert_eq!(keys[0], [1.0, 0.0, -2.0]);
        // A quarter turn about world Z is a quarter turn about glTF Y.
        let q = quat_to_gltf(DQuat::from_rotation_z(FRAC_PI_2));
        assert!(angle(q, DQuat::from_rotation_y(FRAC_PI_2)) < 1e-12);
    }

    /// The mesh vertices, placed by the node's transform at t, land where the body's
    /// vertices are in the Z-up world: mesh axes and node transform agree.
    #[test]
    fn meshes_placed_by_nodes_match_the_world() {
        let scene = shapes_scene();
        let traj = ballistic(&scene);
        let glb = write_glb(&scene, &traj).unwrap();
        let d = doc(&glb);
        let blob = d.blob.as_deref().unwrap();
        let poses = read_poses_at(&glb, scene.t).unwrap();
        for (i, occ) in scene.occluders.iter().enumerate() {
            let node = d.nodes().find(|n| n.name() == Some(&occ.name)).unwrap();
            let (o, q) = traj.poses[traj.t_index][i];
            let (_, po, pq) = &poses[i];
            let prim = node.mesh().unwrap().primitives().next().unwrap();
            let reader = prim.reader(|_| Some(blob));
            let verts: Vec<DVec3> = reader
                .read_positions()
                .unwrap()
                .map(|p| pos_from_gltf(from_f32(p)))
                .collect();
            let normals: Vec<DVec3> = reader
                .read_normals()
                .unwrap()
                .map(|p| pos_from_gltf(from_f32(p)))
                .collect();
            for n in &normals {
                assert!((n.length() - 1.0).abs() < 1e-6);
            }
            // Every world vertex of the body is within f32 rounding of its true place.
            let body_verts: Vec<DVec3> = match &occ.shape {
                Shape::Sphere { radius } => verts.iter().map(|v| v.normalize() * *radius).collect(),
                Shape::Cuboid { half_extents } => cuboid_mesh(*half_extents).positions,
                Shape::Mesh(m) => m.vertices.clone(),
            };
            for bv in &body_verts {
                let truth = o + q * *bv;
                let nearest = verts
                    .iter()
                    .map(|v| (*po + *pq * *v).distance(truth))
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest < 1e-5, "{}: {nearest}", occ.name);
            }
            // Outward winding: each face normal points away from the body origin.
            let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            for t in idx.chunks(3) {
                let [a, b, c] = [0, 1, 2].map(|k| verts[t[k] as usize]);
                let n = (b - a).cross(c - a);
                assert!(n.dot(a + b + c) > 0.0, "{} winding", occ.name);
            }
        }
    }

    #[test]
    fn receiver_faces_the_light() {
        let scene = mickey();
        let d = doc(&write_glb(&scene, &ballistic(&scene)).unwrap());
        let blob = d.blob.as_deref().unwrap();
        let node = d.nodes().find(|n| n.name() == Some("receiver")).unwrap();
        let prim = node.mesh().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|_| Some(blob));
        let v: Vec<DVec3> = reader
            .read_positions()
            .unwrap()
            .map(|p| pos_from_gltf(from_f32(p)))
            .collect();
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        let rc = &scene.receiver;
        let to_light = scene.light - rc.center;
        for t in idx.chunks(3) {
            let [a, b, c] = [0, 1, 2].map(|k| v[t[k] as usize]);
            assert!((b - a).cross(c - a).dot(to_light) > 0.0);
        }
        let half_w = v.iter().map(|p| p.dot(rc.u)).fold(0.0, f64::max);
        assert!((half_w - RECEIVER_MARGIN * rc.width / 2.0).abs() < 1e-6);
    }

    #[test]
    fn crease_normals_keep_a_cube_flat() {
        let scene = shapes_scene();
        let Shape::Mesh(m) = &scene.occluders[1].shape else {
            panic!()
        };
        let d = trimesh_mesh(m);
        assert_eq!(d.positions.len(), 24);
        assert_eq!(d.indices.len(), 36);
        for n in &d.normals {
            assert!((n.abs().max_element() - 1.0).abs() < 1e-12);
        }
        // A finely tessellated sphere comes out smooth: fewer vertices than corners.
        let s = sphere_mesh(1.0);
        let mesh = TriMesh::new(
            s.positions.clone(),
            s.indices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
        );
        let d = trimesh_mesh(&mesh);
        assert!(d.positions.len() < d.indices.len() / 2);
    }

    #[test]
    fn bad_input_is_reported() {
        let scene = mickey();
        let good = ballistic(&scene);
        let mut t = good.clone();
        t.times[t.t_index] += 1e-3;
        assert!(matches!(
            write_glb(&scene, &t),
            Err(GltfError::TNotAKey { .. })
        ));
        let mut t = good.clone();
        t.poses[5].pop();
        assert!(matches!(
            write_glb(&scene, &t),
            Err(GltfError::OccluderCount { key: 5, .. })
        ));
        let mut t = good.clone();
        t.times[7] = t.times[6];
        assert!(matches!(
            write_glb(&scene, &t),
            Err(GltfError::TimesNotIncreasing { index: 7, .. })
        ));
        let mut t = good.clone();
        t.poses[2][0].0.x = f64::NAN;
        assert!(matches!(
            write_glb(&scene, &t),
            Err(GltfError::NonFinite(_))
        ));
        let mut t = good.clone();
        t.fps = 0.0;
        assert!(matches!(write_glb(&scene, &t), Err(GltfError::BadFps(_))));
        assert!(matches!(
            read_poses_at(b"not a glb", 0.0),
            Err(GltfError::Parse(_))
        ));
    }

    /// Writes sample files for the Khronos validator and Blender (not run in CI):
    /// `cargo test --lib output::gltf::tests::write_sample_glbs -- --ignored`, then
    /// validate `/tmp/gltf/*.glb` (see docs/gltf.md). `BSA_GLTF_SCENE=<dir>` adds a scene.
    #[test]
    #[ignore]
    fn write_sample_glbs() {
        let out = PathBuf::from("/tmp/gltf");
        std::fs::create_dir_all(&out).unwrap();
        let mut scenes = vec![mickey(), shapes_scene()];
        if let Ok(dir) = std::env::var("BSA_GLTF_SCENE") {
            scenes.push(crate::scene::load(std::path::Path::new(&dir)).unwrap());
        }
        for scene in scenes {
            let glb = write_glb(&scene, &ballistic(&scene)).unwrap();
            let path = out.join(format!("{}.glb", scene.name));
            std::fs::write(&path, glb).unwrap();
            println!("wrote {}", path.display());
        }
    }
}
