//! Validation: the raw scene in, a [`Scene`] out, with every field checked and every
//! error naming the file and the field ([`SceneError`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DQuat, DVec2, DVec3};

use super::raw::*;
use super::start::{auto_order, raw_start_overrides, Aim};
use super::*;
use crate::energy::{Term, Weights, TERM_COUNT};
use crate::geometry::distance::{
    signed_distance, table_shape, table_signed_distance, ContactShape,
};
use crate::geometry::shape::{self, Shape, TriMesh};
use crate::shadow::mask::Mask;
use crate::shadow::raster::{ImageRect, ShadowCamera};

pub(super) struct Validator<'a> {
    pub(super) file: &'a Path,
    pub(super) dir: &'a Path,
}

impl Validator<'_> {
    pub(super) fn field_err(
        &self,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> SceneError {
        SceneError::Field {
            path: self.file.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    pub(super) fn resolve(&self, rel: &str) -> PathBuf {
        let p = Path::new(rel);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.dir.join(p)
        }
    }

    pub(super) fn scene(&self, raw: RawScene, default_name: String) -> Result<Scene> {
        let name = raw.name.clone().unwrap_or(default_name);
        if name.is_empty() || name == "." || name == ".." || name.contains(['/', '\\']) {
            return Err(self.field_err("name", "must be a non-empty name without path separators"));
        }
        let specs = self.pictures(&raw)?;
        let t = specs.last().expect("at least one picture").t;
        let dt = self.positive("timestep", raw.timestep.unwrap_or(DEFAULT_TIMESTEP))?;
        let hold = match &raw.hold {
            Some(h) => Some(self.hold(h, specs[0].t, dt)?),
            None => None,
        };
        let horizon = t + hold.as_ref().map_or(0.0, |h| h.window);
        if horizon > MAX_T {
            return Err(self.field_err(
                "hold.window",
                format!("ends at {horizon} s, after the longest flight allowed ({MAX_T} s)"),
            ));
        }
        if dt > t {
            return Err(self.field_err(
                "timestep",
                format!(
                    "must not exceed t = {} s, got {}",
                    super::bounds::short(t),
                    super::bounds::short(dt)
                ),
            ));
        }
        // Every key from launch to t is stored (trajectory, export, continuation), so
        // their count bounds memory.
        if horizon / dt > MAX_KEYS {
            return Err(self.field_err(
                "timestep",
                format!(
                    "gives {:.0} keys up to t = {t} s, more than the {MAX_KEYS:e} allowed; use a timestep of at least {:e} s",
                    (horizon / dt).ceil(),
                    horizon / MAX_KEYS
                ),
            ));
        }
        let gravity = self.vec3_len_within(
            "gravity",
            raw.gravity.unwrap_or(DEFAULT_GRAVITY),
            MAX_GRAVITY,
        )?;
        // The objects are launched upwards from the table's top and come down: every
        // start guess and design counts on it (z is up).
        if gravity.z.is_nan() || gravity.z >= 0.0 {
            return Err(self.field_err(
                "gravity",
                format!(
                    "must pull down (a negative z, z is up), got {:?}",
                    gravity.to_array()
                ),
            ));
        }
        let light = self.vec3("light", raw.light)?;
        let receiver = self.receiver(&raw.receiver, light)?;
        let target = specs.last().expect("at least one picture").target.clone();
        let camera = ShadowCamera::new(
            light,
            ImageRect {
                center: receiver.center,
                u: receiver.u,
                v: receiver.v,
                width_m: receiver.width,
                height_m: receiver.height,
                width_px: target.width(),
                height_px: target.height(),
            },
        );
        let table = match &raw.table {
            None => None,
            Some(tb) => {
                let center = self.vec3("table.center", tb.center)?;
                let mut half = DVec3::ZERO;
                for i in 0..3 {
                    half[i] = self.positive_within(
                        &format!("table.size[{i}]"),
                        tb.size[i],
                        MAX_COORDINATE,
                    )? / 2.0;
                }
                Some(Table {
                    center,
                    half_extents: half,
                })
            }
        };
        let rise = self.within(
            "start.rise",
            raw.start
                .as_ref()
                .and_then(|s| s.rise)
                .unwrap_or(DEFAULT_START_RISE),
            MAX_COORDINATE,
        )?;
        if raw.occluders.is_empty() {
            return Err(self.field_err("occluders", "needs at least one occluder"));
        }
        if raw.occluders.len() > MAX_OCCLUDERS {
            return Err(self.field_err(
                "occluders",
                format!(
                    "holds {} occluders, more than the {MAX_OCCLUDERS} supported (the solver keeps data per pair of occluders)",
                    raw.occluders.len()
                ),
            ));
        }
        let mut occluders = Vec::with_capacity(raw.occluders.len());
        for (i, ro) in raw.occluders.iter().enumerate() {
            let o = self.occluder(i, ro, (t, horizon), gravity, rise)?;
            if RESERVED_NAMES.contains(&o.name.as_str()) {
                return Err(self.field_err(
                    format!("occluders[{i}].name"),
                    format!(
                        "`{}` is the name of a node of the glTF export; occluders may not use {}",
                        o.name,
                        RESERVED_NAMES.map(|n| format!("`{n}`")).join(", ")
                    ),
                ));
            }
            if occluders.iter().any(|p: &Occluder| p.name == o.name) {
                return Err(self.field_err(
                    format!("occluders[{i}].name"),
                    format!(
                        "`{}` is used by two occluders; names must be unique",
                        o.name
                    ),
                ));
            }
            occluders.push(o);
        }
        if !occluders.iter().any(|o| o.launched) {
            return Err(self.field_err(
                "occluders",
                "no occluder is launched; there is nothing to optimise",
            ));
        }
        self.check_overlaps(&occluders, table.as_ref())?;
        self.check_room_under_light(&occluders, &receiver, light)?;
        let pictures = self.with_hints(specs, &occluders)?;
        let hints: Vec<Hint> = pictures.iter().flat_map(|p| p.hints.clone()).collect();
        let positions = self.positions(raw.positions.as_deref(), table.is_some())?;
        let aim = raw
            .start
            .as_ref()
            .and_then(|s| s.aim.clone())
            .unwrap_or_else(|| "hints".to_string());
        match aim.as_str() {
            // The earliest picture an occluder has hints in aims it (later ones first,
            // so that earlier ones overwrite them).
            "hints" => {
                let free_on = table
                    .as_ref()
                    .filter(|_| positions == LaunchPositions::Free);
                let explicit = raw_start_overrides(&raw);
                let aim = |t| Aim {
                    camera: &camera,
                    receiver: &receiver,
                    t,
                    gravity,
                    rise,
                    free_on,
                };
                for p in pictures.iter().rev() {
                    aim(p.t).apply(&mut occluders, &p.hints, &explicit);
                }
                if let [a, b, ..] = &pictures[..] {
                    aim(a.t).apply_between(b.t, &b.hints, &mut occluders, &a.hints, &explicit);
                }
            }
            "up" => {}
            other => {
                return Err(self.field_err(
                    "start.aim",
                    format!("must be \"hints\" or \"up\", got \"{other}\""),
                ))
            }
        }
        self.check_start_guess(&occluders)?;
        let defaults = Weights::default_for(target.count() as f64);
        let (stages, strategy) = self.stages(&raw, &occluders, defaults)?;
        let contacts = match raw.contacts.as_deref() {
            None | Some("constraint") => Contacts::Constraint,
            Some("penalty") => Contacts::Penalty,
            Some(other) => {
                return Err(self.field_err(
                    "contacts",
                    format!("must be \"constraint\" or \"penalty\", got \"{other}\""),
                ))
            }
        };
        if stages.len() > MAX_STAGES {
            return Err(self.field_err(
                "strategy",
                format!(
                    "expands to {} stages, more than the {MAX_STAGES} supported",
                    stages.len()
                ),
            ));
        }
        Ok(Scene {
            name,
            source: self.file.to_path_buf(),
            target,
            t,
            pictures,
            hold,
            positions,
            dt,
            gravity,
            light,
            receiver,
            camera,
            table,
            occluders,
            hints,
            stages,
            strategy,
            seed: raw.seed.unwrap_or(1),
            contacts,
        })
    }

    fn receiver(&self, r: &RawReceiver, light: DVec3) -> Result<Receiver> {
        let center = self.vec3("receiver.center", r.center)?;
        let u = self.unit("receiver.u", r.u)?;
        let v = self.unit("receiver.v", r.v)?;
        if u.dot(v).abs() > 1e-6 {
            return Err(self.field_err("receiver.v", "must be perpendicular to receiver.u"));
        }
        let width = self.positive_within("receiver.width", r.width, 2.0 * MAX_COORDINATE)?;
        let height = self.positive_within("receiver.height", r.height, 2.0 * MAX_COORDINATE)?;
        let normal = u.cross(v).normalize();
        let h = (light - center).dot(normal);
        // The image is seen from the light's side with u to the right and v up, so the
        // light must be strictly in front of the receiver (on the side of u x v).
        if h <= 1e-9 {
            return Err(self.field_err(
                "light",
                format!(
                    "the light is on or behind the receiver plane (its height above the plane along u x v is {h:.4} m); it must be in front"
                ),
            ));
        }
        Ok(Receiver {
            center,
            u,
            v,
            normal,
            width,
            height,
        })
    }

    pub(super) fn target(&self, field: &str, rel: &str) -> Result<Mask> {
        let path = self.resolve(rel);
        let bytes = super::read_input(&path).map_err(|error| SceneError::Named {
            path: self.file.to_path_buf(),
            field: field.to_string(),
            named: path.clone(),
            error,
        })?;
        let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
            .map_err(|e| SceneError::TargetNotPng {
                path: path.clone(),
                reason: e.to_string(),
            })?
            .to_rgba8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
            return Err(SceneError::TargetNotPng {
                path,
                reason: format!("{w} x {h} pixels is larger than the {MAX_IMAGE_SIDE} x {MAX_IMAGE_SIDE} supported"),
            });
        }
        let mask = Mask::from_fn(w, h, |x, y| {
            let p = img.get_pixel(x as u32, y as u32).0;
            // Rec. 709 luma of the 8-bit values; dark means below half luminance, and a
            // (mostly) transparent pixel is never shadow.
            let luma = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            p[3] >= 128 && luma < 127.5
        });
        if mask.count() == 0 {
            return Err(SceneError::TargetEmpty { path });
        }
        Ok(mask)
    }

    fn occluder(
        &self,
        i: usize,
        ro: &RawOccluder,
        (t, horizon): (f64, f64),
        gravity: DVec3,
        rise: f64,
    ) -> Result<Occluder> {
        let f = |s: &str| format!("occluders[{i}].{s}");
        if ro.name.trim().is_empty() {
            return Err(self.field_err(f("name"), "must not be empty"));
        }
        let shape = match &ro.shape {
            RawShape::Sphere { radius } => Shape::Sphere {
                radius: self.positive_within(&f("shape.sphere.radius"), *radius, MAX_COORDINATE)?,
            },
            RawShape::Box { size } => {
                let mut half = DVec3::ZERO;
                for k in 0..3 {
                    half[k] = self.positive_within(
                        &f(&format!("shape.box.size[{k}]")),
                        size[k],
                        MAX_COORDINATE,
                    )? / 2.0;
                }
                Shape::Cuboid { half_extents: half }
            }
            RawShape::Mesh { obj, scale } => {
                let given_scale = scale.is_some();
                let scale = self.positive_within(
                    &f("shape.mesh.scale"),
                    scale.unwrap_or(1.0),
                    MAX_COORDINATE,
                )?;
                let path = self.resolve(obj);
                let limits = shape::ObjLimits {
                    max_coordinate: MAX_COORDINATE,
                    max_triangles: MAX_MESH_TRIANGLES,
                    max_bytes: MAX_OBJ_BYTES,
                };
                let mesh: TriMesh =
                    shape::load_obj_checked(&path, scale, &limits).map_err(|error| {
                        // A mesh that is too large or too small once scaled is the
                        // scale's fault when one was given, not the file's.
                        let scale_fault = given_scale
                            && matches!(
                                error,
                                shape::ObjError::OutOfRange { .. }
                                    | shape::ObjError::NonFiniteVertex { .. }
                            );
                        SceneError::Obj {
                            path: self.file.to_path_buf(),
                            field: f(if scale_fault {
                                "shape.mesh.scale"
                            } else {
                                "shape.mesh.obj"
                            }),
                            error,
                        }
                    })?;
                Shape::Mesh(Arc::new(mesh))
            }
        };
        let position = self.vec3(&f("position"), ro.position)?;
        let orientation = match ro.orientation {
            None => DQuat::IDENTITY,
            Some(q) => {
                // Components are bounded so that the quaternion's length cannot
                // overflow; only its direction matters.
                for (k, x) in q.iter().enumerate() {
                    self.within(&f(&format!("orientation[{k}]")), *x, MAX_COORDINATE)?;
                }
                let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
                if q.length() < 1e-9 {
                    return Err(self.field_err(
                        f("orientation"),
                        "must be a non-zero quaternion [x, y, z, w]",
                    ));
                }
                q.normalize()
            }
        };
        let volume = shape.volume();
        let density = match (ro.mass, ro.density) {
            (Some(m), None) => self.positive_within(&f("mass"), m, MAX_MASS)? / volume,
            (None, Some(d)) => self.positive_within(&f("density"), d, MAX_MASS)?,
            (None, None) => {
                return Err(
                    self.field_err(f("mass"), "give either `mass` (kg) or `density` (kg/m^3)")
                )
            }
            (Some(_), Some(_)) => {
                return Err(
                    self.field_err(f("density"), "give either `mass` or `density`, not both")
                )
            }
        };
        let mass = shape.mass_properties_checked(density).ok_or_else(|| {
            self.field_err(
                f("shape"),
                "is too small or too large to give a finite, positive mass and inertia",
            )
        })?;
        let launched = ro.launched.unwrap_or(true);
        // The default start guess launches straight up so that the centre of mass is
        // `rise` metres higher at t: a neutral, collision-free, in-view starting point.
        let g_up = -gravity.z;
        let default_v = DVec3::new(0.0, 0.0, (rise + 0.5 * g_up * t * t) / t);
        let start_velocity = match ro.start_velocity {
            Some(v) => self.vec3_len_within(&f("start_velocity"), v, MAX_SPEED)?,
            None => default_v,
        };
        let start_angular_velocity = match ro.start_angular_velocity {
            Some(w) => {
                let field = f("start_angular_velocity");
                let w = self.vec3_len_within(&field, w, MAX_SPEED)?;
                if launched && w.length() * horizon > MAX_TURN {
                    return Err(self.field_err(field, too_fast_spin(w.length(), horizon)));
                }
                w
            }
            None => DVec3::ZERO,
        };
        let bounding_radius = shape.bounding_radius(mass.local_com);
        Ok(Occluder {
            name: ro.name.clone(),
            shape,
            mass,
            position,
            orientation,
            launched,
            start_velocity,
            start_angular_velocity,
            bounding_radius,
        })
    }

    /// The start guess aimed at the hints is computed from several fields (hints,
    /// receiver, light, t); even within their bounds their combination could ask for
    /// an absurd speed, so it is checked here, where the error can still name the scene.
    fn check_start_guess(&self, occ: &[Occluder]) -> Result<()> {
        for (i, o) in occ.iter().enumerate() {
            for (what, v) in [
                ("start_velocity", o.start_velocity),
                ("start_angular_velocity", o.start_angular_velocity),
            ] {
                let len = v.length();
                if len.is_nan() || len > MAX_SPEED {
                    return Err(self.field_err(
                        format!("occluders[{i}].{what}"),
                        format!(
                            "the start guess aimed at the hints needs a speed of {len:e}, more than the {MAX_SPEED:e} allowed; check `hints`, `receiver` and `light`, or set `start.aim` to \"up\""
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Every launched body must fit between the receiver and the light, or it can never
    /// cast a whole shadow: a light lower than a body is thick (a typo of centimetres
    /// for metres, or a light put at the table's height) is inside or below the body
    /// wherever it flies, and the solve ends at IoU near 0 with nothing to say why.
    /// A body's least width is its width across the direction where it is thinnest
    /// ([`least_width`]).
    fn check_room_under_light(
        &self,
        occ: &[Occluder],
        receiver: &Receiver,
        light: DVec3,
    ) -> Result<()> {
        let room = (light - receiver.center).dot(receiver.normal);
        for (i, o) in occ.iter().enumerate() {
            if !o.launched {
                continue;
            }
            // No body wider than its bounding sphere: most scenes need no more.
            if 2.0 * o.bounding_radius < room {
                continue;
            }
            let width = least_width(&o.shape);
            if width >= room {
                return Err(SceneError::NoRoomUnderLight {
                    path: self.file.to_path_buf(),
                    index: i,
                    name: o.name.clone(),
                    room,
                    width,
                });
            }
        }
        Ok(())
    }

    fn check_overlaps(&self, occ: &[Occluder], table: Option<&Table>) -> Result<()> {
        // Tolerance for resting contact: bodies may touch (a ball on the floor) but not
        // interpenetrate by more than a tenth of a millimetre.
        const TOL: f64 = 1e-4;
        for i in 0..occ.len() {
            for j in (i + 1)..occ.len() {
                let (a, b) = (&occ[i], &occ[j]);
                let (sa, sb) = (ContactShape::new(&a.shape), ContactShape::new(&b.shape));
                let d = signed_distance(
                    &sa,
                    a.position,
                    a.orientation,
                    &sb,
                    b.position,
                    b.orientation,
                );
                if d < -TOL {
                    return Err(SceneError::Overlap {
                        path: self.file.to_path_buf(),
                        what: format!("occluders `{}` and `{}`", occ[i].name, occ[j].name),
                        depth: -d,
                    });
                }
            }
            if let Some(tb) = table {
                let o = &occ[i];
                let s = ContactShape::new(&o.shape);
                let d = table_signed_distance(&s, o.position, o.orientation, tb, &table_shape(tb));
                if d < -TOL {
                    return Err(SceneError::Overlap {
                        path: self.file.to_path_buf(),
                        what: format!("occluder `{}` and the table", occ[i].name),
                        depth: -d,
                    });
                }
            }
        }
        Ok(())
    }

    pub(super) fn hint(&self, field: &str, h: &RawHint, occ: &[Occluder]) -> Result<Hint> {
        let occluder = occ
            .iter()
            .position(|o| o.name == h.occluder)
            .ok_or_else(|| {
                self.field_err(
                    format!("{field}.occluder"),
                    format!("names occluder `{}`, which does not exist", h.occluder),
                )
            })?;
        let point = self.vec3(&format!("{field}.point"), h.point)?;
        let px = self.within(&format!("{field}.pixel[0]"), h.pixel[0], MAX_PIXEL)?;
        let py = self.within(&format!("{field}.pixel[1]"), h.pixel[1], MAX_PIXEL)?;
        let weight = self.weight(&format!("{field}.weight"), h.weight.unwrap_or(1.0))?;
        Ok(Hint {
            occluder,
            point,
            pixel: DVec2::new(px, py),
            weight,
        })
    }

    /// Hints in a text file, one per line: `occluder x y z px py [weight]`; `#` starts a
    /// comment. This is the paper's "hints stored separately in a text file".
    pub(super) fn hints_file(
        &self,
        field: &str,
        path: &Path,
        occ: &[Occluder],
    ) -> Result<Vec<Hint>> {
        let text = super::read_input_text(path).map_err(|error| SceneError::Named {
            path: self.file.to_path_buf(),
            field: field.to_string(),
            named: path.to_path_buf(),
            error,
        })?;
        let mut out = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let err = |reason: String| SceneError::HintLine {
                path: path.to_path_buf(),
                line: k + 1,
                reason,
            };
            let parts: Vec<&str> = line.split_whitespace().collect();
            if parts.len() != 6 && parts.len() != 7 {
                return Err(err(format!(
                    "expected `occluder x y z px py [weight]`, got {} fields",
                    parts.len()
                )));
            }
            let mut nums = [0.0f64; 6];
            for (n, s) in parts[1..].iter().enumerate() {
                let x: f64 = s
                    .parse()
                    .map_err(|_| err(format!("`{s}` is not a number")))?;
                if !x.is_finite() {
                    return Err(err(format!("`{s}` is not a finite number")));
                }
                nums[n] = x;
            }
            let raw = RawHint {
                occluder: parts[0].to_string(),
                point: [nums[0], nums[1], nums[2]],
                pixel: [nums[3], nums[4]],
                weight: if parts.len() == 7 {
                    Some(nums[5])
                } else {
                    None
                },
            };
            let h = self
                .hint(&format!("hints (line {})", k + 1), &raw, occ)
                .map_err(|e| err(e.to_string()))?;
            out.push(h);
        }
        Ok(out)
    }

    fn stage(
        &self,
        field: &str,
        rs: &RawStage,
        default_name: String,
        default_vary: &[usize],
        occ: &[Occluder],
        defaults: StageDefaults,
    ) -> Result<Stage> {
        let mut w = [0.0; TERM_COUNT];
        if rs.weights.is_none() {
            w = defaults.weights.0;
        }
        for (key, value) in rs.weights.iter().flatten() {
            let term = Term::from_key(key).ok_or_else(|| {
                self.field_err(
                    format!("{field}.weights.{key}"),
                    format!(
                        "unknown energy term; use one of {}",
                        Term::ALL.map(|t| t.key()).join(", ")
                    ),
                )
            })?;
            w[term as usize] = self.weight(&format!("{field}.weights.{key}"), *value)?;
        }
        if w.iter().all(|&x| x == 0.0) {
            return Err(self.field_err(
                format!("{field}.weights"),
                "gives every term a weight of 0, so the stage has nothing to optimise; leave `weights` out for the defaults",
            ));
        }
        let vary = match &rs.vary {
            None => default_vary.to_vec(),
            Some(RawVary::All(s)) if s == "all" => occ
                .iter()
                .enumerate()
                .filter(|(_, o)| o.launched)
                .map(|(i, _)| i)
                .collect(),
            Some(RawVary::All(s)) => {
                return Err(self.field_err(
                    format!("{field}.vary"),
                    format!("must be \"all\" or a list of occluder names, got \"{s}\""),
                ))
            }
            Some(RawVary::Names(names)) => {
                let mut out = Vec::new();
                for n in names {
                    let i = occ.iter().position(|o| &o.name == n).ok_or_else(|| {
                        self.field_err(
                            format!("{field}.vary"),
                            format!("names occluder `{n}`, which does not exist"),
                        )
                    })?;
                    if !occ[i].launched {
                        return Err(self.field_err(
                            format!("{field}.vary"),
                            format!("occluder `{n}` is not launched and cannot vary"),
                        ));
                    }
                    if !out.contains(&i) {
                        out.push(i);
                    }
                }
                out
            }
        };
        if vary.is_empty() {
            return Err(self.field_err(format!("{field}.vary"), "no occluder varies in this stage"));
        }
        let n = Launch::LEN * vary.len();
        let step =
            self.positive_within(&format!("{field}.step"), rs.step.unwrap_or(0.3), MAX_STEP)?;
        let max_iterations = rs.max_iterations.unwrap_or(150);
        if !(1..=MAX_ITERATIONS).contains(&max_iterations) {
            return Err(self.field_err(
                format!("{field}.max_iterations"),
                format!("must be between 1 and {MAX_ITERATIONS}, got {max_iterations}"),
            ));
        }
        let population = rs
            .population
            .unwrap_or(4 + (3.0 * (n as f64).ln()).floor() as usize);
        if !(4..=MAX_POPULATION).contains(&population) {
            return Err(self.field_err(
                format!("{field}.population"),
                format!("must be between 4 and {MAX_POPULATION}"),
            ));
        }
        let target_energy = match rs.target_energy {
            Some(x) => Some(self.finite(&format!("{field}.target_energy"), x)?),
            None => None,
        };
        let tol_fun = self.non_negative(&format!("{field}.tol_fun"), rs.tol_fun.unwrap_or(1e-9))?;
        let stagnation = rs.stagnation.unwrap_or(60);
        if !(1..=MAX_STAGNATION).contains(&stagnation) {
            return Err(self.field_err(
                format!("{field}.stagnation"),
                format!("must be between 1 and {MAX_STAGNATION} iterations, got {stagnation}"),
            ));
        }
        let restarts = rs.restarts.unwrap_or(defaults.restarts);
        if restarts > MAX_RESTARTS {
            return Err(self.field_err(
                format!("{field}.restarts"),
                format!("must be between 0 and {MAX_RESTARTS}, got {restarts}"),
            ));
        }
        let restart_iou = rs.restart_iou.unwrap_or(DEFAULT_RESTART_IOU);
        if !(0.0..=1.0).contains(&restart_iou) {
            return Err(self.field_err(
                format!("{field}.restart_iou"),
                format!("must be an IoU between 0 and 1, got {restart_iou}"),
            ));
        }
        let restart_gain = rs.restart_gain.unwrap_or(DEFAULT_RESTART_GAIN);
        if !(0.0..=1.0).contains(&restart_gain) {
            return Err(self.field_err(
                format!("{field}.restart_gain"),
                format!("must be an IoU gain between 0 and 1, got {restart_gain}"),
            ));
        }
        let objective = self.objective(&format!("{field}.objective"), rs.objective.as_deref())?;
        Ok(Stage {
            objective,
            name: rs.name.clone().unwrap_or(default_name),
            weights: Weights(w),
            vary,
            step,
            max_iterations,
            population,
            target_energy,
            tol_fun,
            stagnation,
            restarts,
            restart_iou,
            restart_gain,
        })
    }

    fn stages(
        &self,
        raw: &RawScene,
        occ: &[Occluder],
        defaults: Weights,
    ) -> Result<(Vec<Stage>, Strategy)> {
        let launched: Vec<usize> = occ
            .iter()
            .enumerate()
            .filter(|(_, o)| o.launched)
            .map(|(i, _)| i)
            .collect();
        match (&raw.strategy, &raw.stages) {
            (None | Some(RawStrategy::Scheduled), Some(list)) => {
                if list.is_empty() {
                    return Err(self.field_err("stages", "needs at least one stage"));
                }
                let stages = list
                    .iter()
                    .enumerate()
                    .map(|(i, s)| {
                        let d = StageDefaults::of(defaults, i + 1 == list.len());
                        self.stage(&format!("stages[{i}]"), s, format!("stage {}", i + 1), &launched, occ, d)
                    })
                    .collect::<Result<Vec<_>>>()?;
                Ok((stages, Strategy::Scheduled))
            }
            (None | Some(RawStrategy::Scheduled), None) => Err(self.field_err(
                "stages",
                "is required with the scheduled strategy (or give `strategy` of kind \"sequential\")",
            )),
            (Some(RawStrategy::Sequential { .. }), Some(_)) => Err(self.field_err(
                "stages",
                "the sequential strategy builds its own stages from `strategy.stage` and `strategy.final`; remove `stages`",
            )),
            (Some(RawStrategy::Sequential { order, rounds, stage, final_stage }), None) => {
                let rounds = match rounds.as_ref() {
                    None => 1,
                    Some(&r) if (1..=100).contains(&r) => r as usize,
                    Some(r) => {
                        return Err(self.field_err("strategy.rounds", format!("must be 1 to 100, got {r}")))
                    }
                };
                let order: Vec<usize> = match order {
                    None => auto_order(occ),
                    Some(RawOrder::Auto(s)) if s == "auto" => auto_order(occ),
                    Some(RawOrder::Auto(s)) => {
                        return Err(self.field_err("strategy.order", format!("must be \"auto\" or a list of occluder names, got \"{s}\"")))
                    }
                    Some(RawOrder::Names(names)) => {
                        let mut out = Vec::new();
                        for n in names {
                            let i = occ.iter().position(|o| &o.name == n).ok_or_else(|| {
                                self.field_err("strategy.order", format!("names occluder `{n}`, which does not exist"))
                            })?;
                            if !occ[i].launched {
                                return Err(self.field_err("strategy.order", format!("occluder `{n}` is not launched")));
                            }
                            if out.contains(&i) {
                                return Err(self.field_err("strategy.order", format!("occluder `{n}` is listed twice")));
                            }
                            out.push(i);
                        }
                        out
                    }
                };
                if stage.vary.is_some() {
                    return Err(self.field_err("strategy.stage.vary", "is set by the sequential strategy (one occluder per stage); remove it"));
                }
                let mut stages = Vec::new();
                for round in 1..=rounds {
                    for &i in &order {
                        // Later rounds are told apart in progress and reports.
                        let name = if round == 1 {
                            occ[i].name.clone()
                        } else {
                            format!("{} ({round})", occ[i].name)
                        };
                        let d = StageDefaults::of(defaults, false);
                        let s = self.stage("strategy.stage", stage, name, &[i], occ, d)?;
                        stages.push(s);
                    }
                }
                if let Some(fs) = final_stage {
                    let d = StageDefaults::of(defaults, true);
                    stages.push(self.stage("strategy.final", fs, "final".to_string(), &launched, occ, d)?);
                }
                Ok((stages, Strategy::Sequential { order }))
            }
        }
    }
}

/// What a stage gets for the fields its file leaves out, beyond the fixed defaults.
#[derive(Clone, Copy)]
struct StageDefaults {
    weights: Weights,
    restarts: usize,
}

impl StageDefaults {
    /// The defaults of a stage: the scene's default weights, and
    /// [`DEFAULT_RESTARTS`] for the last stage (the one that leaves the result), one
    /// restart for the others.
    fn of(weights: Weights, last: bool) -> StageDefaults {
        StageDefaults {
            weights,
            restarts: if last { DEFAULT_RESTARTS } else { 1 },
        }
    }
}

/// Why a launch's spin is refused: it turns the body more than [`MAX_TURN`] by the
/// horizon, and the fastest spin that does not.
pub fn too_fast_spin(spin: f64, horizon: f64) -> String {
    format!(
        "turns the body {:.0} rad by {horizon} s, more than the {MAX_TURN} rad (over 300 turns) allowed: at most {:.1} rad/s",
        spin * horizon,
        MAX_TURN / horizon
    )
}

/// Directions [`least_width`] tries for a mesh (a Fibonacci lattice over a half sphere:
/// a width is the same both ways).
const WIDTH_DIRECTIONS: usize = 2000;

/// A lower bound of a solid's least width (m): exact for a sphere and a box; for a mesh,
/// its least width over [`WIDTH_DIRECTIONS`] directions, less the most that the
/// directions between them could lower it (the lattice's spacing times the mesh's
/// diameter), so that no body is refused that could pass.
fn least_width(shape: &Shape) -> f64 {
    match shape {
        Shape::Sphere { radius } => 2.0 * radius,
        Shape::Cuboid { half_extents } => 2.0 * half_extents.min_element(),
        Shape::Mesh(_) => {
            let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
            let n = WIDTH_DIRECTIONS;
            let mut least = f64::INFINITY;
            for k in 0..n {
                let z = 1.0 - (k as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let a = golden * k as f64;
                let d = DVec3::new(r * a.cos(), r * a.sin(), z);
                least = least.min(d.dot(shape.support(d) - shape.support(-d)));
            }
            // Neighbouring lattice points are about sqrt(2 pi / n) rad apart on the half
            // sphere; a width changes by at most the diameter times the angle.
            let spacing = (2.0 * std::f64::consts::PI / n as f64).sqrt();
            (least - shape.bounding_radius(DVec3::ZERO) * 2.0 * spacing).max(0.0)
        }
    }
}
