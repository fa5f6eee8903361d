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
fn ballistic(scene: &Scene) -> Track {
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
    Track {
        times,
        poses,
        t_index: n_t,
        fps: 1.0 / dt,
        continuation_from: n_t,
        rest: Default::default(),
        instant_indices: vec![n_t],
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
    assert_eq!(light.intensity(), light_intensity_cd(&scene) as f32);
    // The illuminance at the receiver centre is the target: E = I cos / r^2.
    let d = scene.light - scene.receiver.center;
    let e = light.intensity() as f64 * d.dot(scene.receiver.normal) / d.length().powi(3);
    assert!((e / TARGET_ILLUMINANCE_LUX - 1.0).abs() < 1e-6, "{e} lux");
    // The table is lowered by TABLE_DROP_M: its top face is below the receiver plane.
    let table = scene.table.as_ref().unwrap();
    let (tt, _, _) = node("table").transform().decomposed();
    let top = (pos_from_gltf(from_f32(tt)) - scene.receiver.center).dot(scene.receiver.normal)
        + table.half_extents.z;
    assert!((top + TABLE_DROP_M).abs() < 1e-6, "table top at {top} m");
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
    // One normal per corner and face: 24 (position, normal) pairs; the cylindrical
    // texture's seam splits a few more vertices, with the same normals.
    let pairs: HashSet<[u64; 6]> = d
        .positions
        .iter()
        .zip(&d.normals)
        .map(|(p, n)| [p.x, p.y, p.z, n.x, n.y, n.z].map(f64::to_bits))
        .collect();
    assert_eq!(pairs.len(), 24);
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

#[test]
fn occluder_nodes_carry_extras_and_launches_must_match() {
    let scene = mickey();
    let traj = ballistic(&scene);
    let d = doc(&write_glb(&scene, &traj).unwrap());
    for occ in &scene.occluders {
        let node = d.nodes().find(|n| n.name() == Some(&occ.name)).unwrap();
        let extras: serde_json::Value =
            serde_json::from_str(node.extras().as_ref().unwrap().get()).unwrap();
        assert_eq!(extras["scene"], scene.name.as_str());
    }
    assert!(matches!(
        write_glb_with_launches(&scene, &traj, Some(&[])),
        Err(GltfError::LaunchCount { got: 0, .. })
    ));
}

/// Every mesh carries texture coordinates, one per vertex; blocks are maple and meshes
/// boxwood, both textured through `TEXCOORD_0`; balls keep a colour of their own.
#[test]
fn meshes_have_texture_coordinates_and_wood_materials() {
    let scene = shapes_scene();
    let glb = write_glb(&scene, &ballistic(&scene)).unwrap();
    let g = doc(&glb);
    let mut materials = HashSet::new();
    for mesh in g.meshes() {
        for p in mesh.primitives() {
            let pos = p.get(&gltf::Semantic::Positions).unwrap();
            let uv = p.get(&gltf::Semantic::TexCoords(0)).expect("TEXCOORD_0");
            assert_eq!(uv.count(), pos.count(), "{:?}", mesh.name());
            let m = p.material();
            let textured = m.pbr_metallic_roughness().base_color_texture().is_some();
            let name = mesh.name().unwrap().to_string();
            materials.insert((name, m.name().unwrap().to_string(), textured));
        }
    }
    // shapes_scene: a box (occluder 0), a mesh (1) and a ball (2).
    let o = &scene.occluders;
    for (i, material, textured) in [(0, "maple", true), (1, "boxwood", true)] {
        assert!(
            materials.contains(&(o[i].name.clone(), material.to_string(), textured)),
            "{materials:?}"
        );
    }
    assert!(
        materials.contains(&(o[2].name.clone(), o[2].name.clone(), false)),
        "{materials:?}"
    );
    assert_eq!(g.textures().count(), 2);
    for image in g.images() {
        let gltf::image::Source::View { mime_type, .. } = image.source() else {
            panic!("an embedded image");
        };
        assert_eq!(mime_type, "image/png");
    }
}

/// Box faces: texture coordinates in tiles of `WOOD_TILE_M`, `u` along the longest axis
/// in the face (the grain). Meshes: cylindrical about z, and no triangle stretched across
/// the seam. The receiver: 0..1 over the picture's rectangle, top left at (0, 0).
#[test]
fn texture_coordinates_follow_the_grain_and_the_picture() {
    let h = DVec3::new(0.14, 0.035, 0.0175);
    let d = cuboid_mesh(h);
    for face in 0..6 {
        let c = &d.uvs[4 * face..4 * face + 4];
        let n = d.normals[4 * face];
        let span = |k: usize| {
            c.iter().map(|uv| uv[k]).fold(f64::NEG_INFINITY, f64::max)
                - c.iter().map(|uv| uv[k]).fold(f64::INFINITY, f64::min)
        };
        // The face's two extents, longest first.
        let mut ext: Vec<f64> = (0..3)
            .filter(|&k| n[k] == 0.0)
            .map(|k| 2.0 * h[k])
            .collect();
        ext.sort_by(|a, b| b.total_cmp(a));
        assert!(
            (span(0) - ext[0] / WOOD_TILE_M).abs() < 1e-12,
            "face {face}"
        );
        assert!(
            (span(1) - ext[1] / WOOD_TILE_M).abs() < 1e-12,
            "face {face}"
        );
    }

    let scene = crate::scene::load(&root_dir().join("scenes/thinker")).unwrap();
    let Shape::Mesh(m) = &scene.occluders[0].shape else {
        panic!("the king is a mesh")
    };
    let d = trimesh_mesh(m);
    assert_eq!(d.uvs.len(), d.positions.len());
    let around = d.uvs.iter().map(|uv| uv[1]).fold(0.0, f64::max);
    for tri in d.indices.chunks(3) {
        let v: Vec<f64> = tri.iter().map(|&i| d.uvs[i as usize][1]).collect();
        let spread = v.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
            - v.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        assert!(spread < 0.5 * around, "a triangle across the seam: {v:?}");
        for &i in tri {
            let (p, uv) = (d.positions[i as usize], d.uvs[i as usize]);
            assert!((uv[0] - p.z / WOOD_TILE_M).abs() < 1e-12);
        }
    }

    let q = quad_mesh(DVec3::X * 3.0, DVec3::Y * 2.25, DVec3::Z, 1.5);
    for (p, uv) in q.positions.iter().zip(&q.uvs) {
        // The picture is 4 x 3 m: x from -2 to 2 maps to 0..1, y from 1.5 (top) to -1.5.
        assert!((uv[0] - (p.x + 2.0) / 4.0).abs() < 1e-12, "{p} {uv:?}");
        assert!((uv[1] - (1.5 - p.y) / 3.0).abs() < 1e-12, "{p} {uv:?}");
    }
}
