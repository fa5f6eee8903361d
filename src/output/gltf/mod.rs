//! Animated glTF 2.0 binary (.glb) export of a solved scene, and a reader for checking it.
//!
//! Data flow: a validated [`Scene`] plus a sampled [`Track`] (one pose per occluder
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
use crate::output::trajectory::{LaunchRow, Track};
use crate::scene::Scene;

mod build;
mod meshes;
mod read;
mod wood;

use build::*;
use meshes::*;
pub use read::read_poses_at;
use wood::Wood;
pub use wood::WOOD_TILE_M;

/// Value of `asset.generator` and of the scene extras' `generator`.
pub const GENERATOR: &str = "ballistic-shadow-art";
/// Name of the single animation.
pub const ANIMATION_NAME: &str = "flight";
/// Illuminance (lux) that the point light gives at the picture's centre: `683 pi` lux,
/// i.e. pi W/m^2 in Blender's 683 lm/W, so that the white diffuse receiver renders at
/// scene-linear 1.0 there (well exposed under Blender's default AgX view transform; the
/// same level as `blender/render_video.py`'s automatic energy). See [`light_intensity_cd`].
pub const TARGET_ILLUMINANCE_LUX: f64 = 683.0 * std::f64::consts::PI;
/// The table box is written this far (m) below its true place, along `-receiver.normal`,
/// so that its top face, usually in the receiver's plane, does not shadow the receiver in
/// a renderer (Cycles renders a coplanar table top as a black receiver). Bodies resting on
/// the table at launch then float 2 mm above it; the receiver, and so the exact shadow
/// geometry, is untouched.
pub const TABLE_DROP_M: f64 = 0.002;

/// Luminous intensity (cd) of the point light so that the illuminance at the receiver
/// centre is [`TARGET_ILLUMINANCE_LUX`]: `E = I cos(theta) / r^2`, so `I = E r^3 / h`, with
/// `r` the light's distance to the centre and `h` its height above the receiver plane
/// (`r` if the light is not on the normal's side). 6 m straight above: about 77 000 cd,
/// which Blender's importer turns into `cd 4 pi / 683` = 1421 W.
pub fn light_intensity_cd(scene: &Scene) -> f64 {
    let rc = &scene.receiver;
    let d = scene.light - rc.center;
    let r = d.length();
    let h = d.dot(rc.normal);
    let h = if h > 1e-9 * r { h } else { r };
    TARGET_ILLUMINANCE_LUX * r * r * r / h
}

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
    /// `write_glb_with_launches`: not one launch per occluder.
    #[error("{got} launches for {expected} occluders")]
    LaunchCount { expected: usize, got: usize },
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
pub fn write_glb(scene: &Scene, traj: &Track) -> Result<Vec<u8>, GltfError> {
    write_glb_with_launches(scene, traj, None)
}

/// As [`write_glb`], with each occluder's launch (`launches[i]` for occluder `i`, as
/// written to launch.csv) in its node's `extras`, which Blender's importer turns into
/// custom properties: `scene`, `launched`, `mass_kg`, `launch_velocity_m_s` and
/// `angular_velocity_rad_s` (vectors in the project's Z-up world frame, which is also
/// Blender's). Without launches the extras hold only `scene`.
pub fn write_glb_with_launches(
    scene: &Scene,
    traj: &Track,
    launches: Option<&[LaunchRow]>,
) -> Result<Vec<u8>, GltfError> {
    check_input(scene, traj)?;
    if let Some(l) = launches {
        if l.len() != scene.occluders.len() {
            return Err(GltfError::LaunchCount {
                expected: scene.occluders.len(),
                got: l.len(),
            });
        }
    }
    let mut b = Builder::new();

    let occluder_nodes = occluder_nodes(&mut b, scene, traj, launches)?;
    let mut scene_nodes = occluder_nodes.clone();
    surface_nodes(&mut b, scene, &mut scene_nodes)?;
    scene_nodes.push(light_node(&mut b, scene));

    let (w_px, h_px) = (scene.target.width(), scene.target.height());
    scene_nodes.push(shadow_camera(&mut b, scene, w_px, h_px)?);
    scene_nodes.push(view_camera(&mut b, scene, traj));

    flight_animation(&mut b, traj, &occluder_nodes)?;

    let extras = scene_extras(scene, traj);
    let gltf_scene = b.root.push(json::Scene {
        extensions: None,
        extras: Some(serde_json::value::to_raw_value(&extras)?),
        name: Some(scene.name.clone()),
        nodes: scene_nodes,
    });
    b.root.scene = Some(gltf_scene);
    b.finish()
}

/// One node per occluder, in occluder order, carrying its mesh, its material, its pose
/// at `t` and its launch in `extras`; returns the nodes, which the animation targets.
fn occluder_nodes(
    b: &mut Builder,
    scene: &Scene,
    traj: &Track,
    launches: Option<&[LaunchRow]>,
) -> Result<Vec<Index<json::Node>>, GltfError> {
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
        // Blocks are maple, meshes (the chess pieces) boxwood, each showing its own part
        // of the shared texture; balls keep a colour of their own.
        let mut data = data;
        let material = match &occ.shape {
            Shape::Sphere { .. } => b.material(&occ.name, occluder_colour(i), 0.5),
            Shape::Cuboid { .. } => b.wood(Wood::Maple),
            Shape::Mesh(_) => b.wood(Wood::Boxwood),
        };
        if !matches!(occ.shape, Shape::Sphere { .. }) {
            let golden = 0.618_033_988_749_895;
            offset_uvs(
                &mut data,
                [
                    (i as f64 * golden).fract(),
                    (i as f64 * golden * golden).fract(),
                ],
            );
        }
        let mesh = b.mesh(&occ.name, &data, material)?;
        let (o, q) = traj.poses[traj.t_index][i];
        let extras = occluder_extras(scene, launches.map(|l| &l[i]));
        let node = b.root.push(json::Node {
            extras: Some(serde_json::value::to_raw_value(&extras)?),
            mesh: Some(mesh),
            name: Some(occ.name.clone()),
            translation: Some(to_f32(pos_to_gltf(o))),
            rotation: Some(json::scene::UnitQuaternion(quat_to_f32(quat_to_gltf(q)))),
            ..Default::default()
        });
        occluder_nodes.push(node);
    }
    Ok(occluder_nodes)
}

/// An occluder node's `extras`: the scene's name, and the occluder's launch when given.
fn occluder_extras(scene: &Scene, launch: Option<&LaunchRow>) -> serde_json::Value {
    match launch {
        Some(l) => serde_json::json!({
            "scene": scene.name,
            "launched": l.launched,
            "mass_kg": l.mass_kg,
            "launch_velocity_m_s": [l.vx_m_s, l.vy_m_s, l.vz_m_s],
            "angular_velocity_rad_s": [l.wx_rad_s, l.wy_rad_s, l.wz_rad_s],
        }),
        None => serde_json::json!({ "scene": scene.name }),
    }
}

/// Push onto `scene_nodes` the receiver's node and, if the scene has a table, the
/// table's.
fn surface_nodes(
    b: &mut Builder,
    scene: &Scene,
    scene_nodes: &mut Vec<Index<json::Node>>,
) -> Result<(), GltfError> {
    // Receiver: a white quad around the image rectangle, front face towards the light.
    let rc = &scene.receiver;
    let white = b.material("white", [1.0, 1.0, 1.0, 1.0], 1.0);
    let quad = quad_mesh(
        rc.u * (RECEIVER_MARGIN * rc.width / 2.0),
        rc.v * (RECEIVER_MARGIN * rc.height / 2.0),
        rc.normal,
        RECEIVER_MARGIN,
    );
    let mesh = b.mesh("receiver", &quad, white)?;
    scene_nodes.push(b.root.push(json::Node {
        mesh: Some(mesh),
        name: Some("receiver".into()),
        translation: Some(to_f32(pos_to_gltf(rc.center))),
        ..Default::default()
    }));

    // Table: the same white as the receiver, lowered by TABLE_DROP_M so that its top face,
    // usually in the receiver plane, neither shadows the receiver nor flickers with it.
    if let Some(table) = &scene.table {
        let mesh = b.mesh("table", &cuboid_mesh(table.half_extents), white)?;
        scene_nodes.push(b.root.push(json::Node {
            mesh: Some(mesh),
            name: Some("table".into()),
            translation: Some(to_f32(pos_to_gltf(table.center - rc.normal * TABLE_DROP_M))),
            ..Default::default()
        }));
    }
    Ok(())
}

/// The point light's node (KHR_lights_punctual, declared as used): intensity in candela
/// ([`light_intensity_cd`]), infinite range.
fn light_node(b: &mut Builder, scene: &Scene) -> Index<json::Node> {
    let light = b
        .root
        .push(json::extensions::scene::khr_lights_punctual::Light {
            color: [1.0, 1.0, 1.0],
            extensions: None,
            extras: Default::default(),
            intensity: light_intensity_cd(scene) as f32,
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
    b.root.push(json::Node {
        name: Some("light".into()),
        translation: Some(to_f32(pos_to_gltf(scene.light))),
        extensions: Some(light_ext),
        ..Default::default()
    })
}

/// The glTF scene's `extras`: the instant `t` (also as a frame), the timestep, the
/// target's size and the generator; with several instants, each picture's instant and
/// the hold window.
fn scene_extras(scene: &Scene, traj: &Track) -> serde_json::Value {
    let (w_px, h_px) = (scene.target.width(), scene.target.height());
    let mut extras = serde_json::json!({
        "t": scene.t,
        "fps": traj.fps,
        "t_frame": scene.t * traj.fps,
        "dt": scene.dt,
        "target_width": w_px,
        "target_height": h_px,
        "scene": scene.name,
        "generator": GENERATOR,
    });
    if !scene.single_instant() {
        // Every picture's instant (a marker each in Blender), and the hold window.
        extras["instants"] = scene
            .pictures
            .iter()
            .enumerate()
            .map(|(k, p)| {
                serde_json::json!({
                    "picture": k + 1,
                    "t": p.t,
                    "frame": p.t * traj.fps,
                    "target": p.file.file_name().map(|f| f.to_string_lossy().into_owned()),
                })
            })
            .collect();
        if let Some(h) = &scene.hold {
            extras["hold_window_s"] = serde_json::json!(h.window);
        }
    }
    extras
}

// ---------------------------------------------------------------------------------
// Input checks.
// ---------------------------------------------------------------------------------

pub(super) fn check_input(scene: &Scene, traj: &Track) -> Result<(), GltfError> {
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
pub(super) fn pos_to_gltf(p: DVec3) -> DVec3 {
    // `0.0 - y` rather than `-y` so that a zero is written as 0, not -0.
    DVec3::new(p.x, p.z, 0.0 - p.y)
}

/// glTF Y-up -> Z-up world: `C^-1 p`.
pub(super) fn pos_from_gltf(p: DVec3) -> DVec3 {
    DVec3::new(p.x, 0.0 - p.z, p.y)
}

/// `C q C^-1`: the scalar part is unchanged and the vector part rotates like a point;
/// written component-wise so that it is exact.
pub(super) fn quat_to_gltf(q: DQuat) -> DQuat {
    DQuat::from_xyzw(q.x, q.z, -q.y, q.w)
}

pub(super) fn quat_from_gltf(q: DQuat) -> DQuat {
    DQuat::from_xyzw(q.x, -q.z, q.y, q.w)
}

/// The change of axes as a rotation, for frames that are glTF-native (cameras).
pub(super) fn axes_rotation() -> DQuat {
    DQuat::from_rotation_x(-FRAC_PI_2)
}

pub(super) fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

pub(super) fn from_f32(v: [f32; 3]) -> DVec3 {
    DVec3::new(v[0].into(), v[1].into(), v[2].into())
}

pub(super) fn quat_to_f32(q: DQuat) -> [f32; 4] {
    let q = q.normalize();
    [q.x as f32, q.y as f32, q.z as f32, q.w as f32]
}

pub(super) fn quat_from_f32(q: [f32; 4]) -> DQuat {
    DQuat::from_xyzw(q[0].into(), q[1].into(), q[2].into(), q[3].into()).normalize()
}

#[cfg(test)]
mod tests;
