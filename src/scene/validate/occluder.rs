//! Validation of the occluders: each one's shape, pose, mass and start guess, the list
//! as a whole (count, names, something launched), and the checks between them and the
//! rest of the scene: overlaps at launch, room under the light, the aimed start guess.

use std::sync::Arc;

use glam::{DQuat, DVec3};

use super::Validator;
use crate::geometry::distance::{
    signed_distance, table_shape, table_signed_distance, ContactShape,
};
use crate::geometry::shape::{self, Shape, TriMesh};
use crate::scene::raw::{RawOccluder, RawShape};
use crate::scene::{
    Occluder, Receiver, Result, SceneError, Table, MAX_COORDINATE, MAX_MASS, MAX_MESH_TRIANGLES,
    MAX_OBJ_BYTES, MAX_OCCLUDERS, MAX_SPEED, MAX_TURN, RESERVED_NAMES,
};

/// The path of field `s` of occluder `i`: `occluders[i].s`.
fn field(i: usize, s: &str) -> String {
    format!("occluders[{i}].{s}")
}

impl Validator<'_> {
    /// Every occluder of the scene, validated in order, with names that are neither
    /// reserved nor used twice, and at least one of them launched.
    pub(super) fn occluders(
        &self,
        raw: &[RawOccluder],
        (t, horizon): (f64, f64),
        gravity: DVec3,
        rise: f64,
    ) -> Result<Vec<Occluder>> {
        if raw.is_empty() {
            return Err(self.field_err("occluders", "needs at least one occluder"));
        }
        if raw.len() > MAX_OCCLUDERS {
            return Err(self.field_err(
                "occluders",
                format!(
                    "holds {} occluders, more than the {MAX_OCCLUDERS} supported (the solver keeps data per pair of occluders)",
                    raw.len()
                ),
            ));
        }
        let mut occluders = Vec::with_capacity(raw.len());
        for (i, ro) in raw.iter().enumerate() {
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
        Ok(occluders)
    }

    fn occluder(
        &self,
        i: usize,
        ro: &RawOccluder,
        (t, horizon): (f64, f64),
        gravity: DVec3,
        rise: f64,
    ) -> Result<Occluder> {
        let f = |s: &str| field(i, s);
        if ro.name.trim().is_empty() {
            return Err(self.field_err(f("name"), "must not be empty"));
        }
        let shape = self.shape(i, &ro.shape)?;
        let position = self.vec3(&f("position"), ro.position)?;
        let orientation = self.orientation(i, ro.orientation)?;
        let volume = shape.volume();
        let density = self.density(i, ro, volume)?;
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
            Some(w) => self.start_spin(i, w, launched, horizon)?,
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

    /// Occluder `i`'s shape: a sphere, a box or a mesh, every size within
    /// [`MAX_COORDINATE`].
    fn shape(&self, i: usize, raw: &RawShape) -> Result<Shape> {
        let f = |s: &str| field(i, s);
        Ok(match raw {
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
            RawShape::Mesh { obj, scale } => self.mesh(i, obj, *scale)?,
        })
    }

    /// Occluder `i`'s mesh: the OBJ file `obj` (relative to the scene's folder) scaled by
    /// `scale`, within the limits on size, triangles and bytes.
    fn mesh(&self, i: usize, obj: &str, scale: Option<f64>) -> Result<Shape> {
        let f = |s: &str| field(i, s);
        let given_scale = scale.is_some();
        let scale =
            self.positive_within(&f("shape.mesh.scale"), scale.unwrap_or(1.0), MAX_COORDINATE)?;
        let path = self.resolve(obj);
        let limits = shape::ObjLimits {
            max_coordinate: MAX_COORDINATE,
            max_triangles: MAX_MESH_TRIANGLES,
            max_bytes: MAX_OBJ_BYTES,
        };
        let mesh: TriMesh = shape::load_obj_checked(&path, scale, &limits).map_err(|error| {
            // A mesh that is too large or too small once scaled is the
            // scale's fault when one was given, not the file's.
            let scale_fault = given_scale
                && matches!(
                    error,
                    shape::ObjError::OutOfRange { .. } | shape::ObjError::NonFiniteVertex { .. }
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
        Ok(Shape::Mesh(Arc::new(mesh)))
    }

    /// Occluder `i`'s orientation at launch: the identity, or a non-zero quaternion
    /// `[x, y, z, w]`, normalised.
    fn orientation(&self, i: usize, raw: Option<[f64; 4]>) -> Result<DQuat> {
        let f = |s: &str| field(i, s);
        let Some(q) = raw else {
            return Ok(DQuat::IDENTITY);
        };
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
        Ok(q.normalize())
    }

    /// Occluder `i`'s density (kg/m^3): given, or its `mass` over the shape's `volume`;
    /// exactly one of the two.
    fn density(&self, i: usize, ro: &RawOccluder, volume: f64) -> Result<f64> {
        let f = |s: &str| field(i, s);
        match (ro.mass, ro.density) {
            (Some(m), None) => Ok(self.positive_within(&f("mass"), m, MAX_MASS)? / volume),
            (None, Some(d)) => self.positive_within(&f("density"), d, MAX_MASS),
            (None, None) => {
                Err(self.field_err(f("mass"), "give either `mass` (kg) or `density` (kg/m^3)"))
            }
            (Some(_), Some(_)) => {
                Err(self.field_err(f("density"), "give either `mass` or `density`, not both"))
            }
        }
    }

    /// Occluder `i`'s start angular velocity `w`: bounded by [`MAX_SPEED`], and for a
    /// launched body by the turn it makes by the horizon ([`too_fast_spin`]).
    fn start_spin(&self, i: usize, w: [f64; 3], launched: bool, horizon: f64) -> Result<DVec3> {
        let field = field(i, "start_angular_velocity");
        let w = self.vec3_len_within(&field, w, MAX_SPEED)?;
        if launched && w.length() * horizon > MAX_TURN {
            return Err(self.field_err(field, too_fast_spin(w.length(), horizon)));
        }
        Ok(w)
    }

    /// The start guess aimed at the hints is computed from several fields (hints,
    /// receiver, light, t); even within their bounds their combination could ask for
    /// an absurd speed, so it is checked here, where the error can still name the scene.
    pub(super) fn check_start_guess(&self, occ: &[Occluder]) -> Result<()> {
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
    pub(super) fn check_room_under_light(
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

    /// No two occluders, and no occluder and the table, may interpenetrate at launch.
    pub(super) fn check_overlaps(&self, occ: &[Occluder], table: Option<&Table>) -> Result<()> {
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
