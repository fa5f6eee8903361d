//! Building the glTF document: the private `Builder` (buffers, accessors, nodes,
//! materials), the cameras, the flight animation and the occluders' colours.

use super::*;

// ---------------------------------------------------------------------------------
// Building the document.
// ---------------------------------------------------------------------------------

/// Mesh data in the Z-up body frame, before the change of axes.
pub(super) struct MeshData {
    pub(super) positions: Vec<DVec3>,
    pub(super) normals: Vec<DVec3>,
    /// Texture coordinates (glTF's: origin at the image's top left), one per position.
    pub(super) uvs: Vec<[f64; 2]>,
    pub(super) indices: Vec<u32>,
}

pub(super) struct Builder {
    pub(super) root: json::Root,
    pub(super) bin: Vec<u8>,
    /// The wood materials made so far (one each, shared by the objects of that wood).
    woods: Vec<(Wood, Index<json::Material>)>,
}

impl Builder {
    pub(super) fn new() -> Self {
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
            woods: Vec::new(),
        }
    }

    /// Append one buffer view, 4-byte aligned (every component here is 4 bytes wide).
    pub(super) fn view(
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
    pub(super) fn float_accessor(
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

    pub(super) fn index_accessor(&mut self, indices: &[u32]) -> json::Index<json::Accessor> {
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

    pub(super) fn material(
        &mut self,
        name: &str,
        rgba: [f32; 4],
        roughness: f32,
    ) -> Index<json::Material> {
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

    /// The material of a wood: its procedural texture (a PNG in the binary buffer,
    /// repeated) as base colour through `TEXCOORD_0`; made once, then shared.
    pub(super) fn wood(&mut self, wood: Wood) -> Index<json::Material> {
        if let Some((_, m)) = self.woods.iter().find(|(w, _)| *w == wood) {
            return *m;
        }
        let name = wood.name();
        let view = self.view(&wood.png(), None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(name.into()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let sampler = self.root.push(json::texture::Sampler {
            mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
            min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
            name: None,
            wrap_s: Valid(json::texture::WrappingMode::Repeat),
            wrap_t: Valid(json::texture::WrappingMode::Repeat),
            extensions: None,
            extras: Default::default(),
        });
        let texture = self.root.push(json::Texture {
            name: Some(name.into()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: Default::default(),
        });
        let material = self.root.push(json::Material {
            name: Some(name.into()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([1.0; 4]),
                base_color_texture: Some(json::texture::Info {
                    index: texture,
                    tex_coord: 0,
                    extensions: None,
                    extras: Default::default(),
                }),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(wood.roughness()),
                ..Default::default()
            },
            ..Default::default()
        });
        self.woods.push((wood, material));
        material
    }

    /// One triangle-list primitive, its data converted to glTF axes.
    pub(super) fn mesh(
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
        let uv: Vec<f32> = data
            .uvs
            .iter()
            .flat_map(|&[u, v]| [u as f32, v as f32])
            .collect();
        let uvs = self.float_accessor(
            &uv,
            json::accessor::Type::Vec2,
            2,
            false,
            Some(json::buffer::Target::ArrayBuffer),
        );
        let indices = self.index_accessor(&data.indices);
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
        attributes.insert(Valid(json::mesh::Semantic::Normals), normals);
        attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), uvs);
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

    pub(super) fn finish(mut self) -> Result<Vec<u8>, GltfError> {
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
pub(super) fn shadow_camera(
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
pub(super) fn view_camera(b: &mut Builder, scene: &Scene, traj: &Track) -> Index<json::Node> {
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
pub(super) fn flight_animation(
    b: &mut Builder,
    traj: &Track,
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
pub(super) fn occluder_colour(i: usize) -> [f32; 4] {
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
