//! From shadows on the picture to launches: every placed object's pose and position at
//! `t` (on the light ray through its shadow's centre, at the height of its
//! magnification), its slot on the table, and the launch velocity and spin that take it
//! there ([`Plan`]); and the scene file that holds them.
//!
//! The flight of a body is a parabola and, turning about a principal axis, a constant
//! spin, so the start guess reaches the planned pose exactly. The relative position of
//! two bodies moves linearly from their relative launch position to their relative
//! position at `t` (gravity cancels), so two straight paths on the table's plane that do
//! not cross give bodies that never meet side by side: the slots are assigned to the
//! objects by the least total horizontal distance to their positions at `t`, a matching
//! in which no two paths cross (swapping the ends of two crossing paths would shorten
//! both). [`super::separate`] then checks the flights with the exact contact search.

use glam::{DQuat, DVec2, DVec3};
use serde_json::{json, Value};

use super::assign::assign;
use super::cover::{to_pixel, Frame, Placement};
use super::plant::default_strategy;
use super::pose::{families, lift_at, rest_radius, Family, Pose};
use crate::geometry::shape::{MassProperties, Shape};
use crate::scene::velocity_reaching;
use crate::shadow::raster::ShadowCamera;
use crate::sim::aim::Spin;
use crate::sim::flight::{FlightConfig, FreeFlight};

/// An object of the box, ready to be placed.
#[derive(Clone, Debug)]
pub struct Object {
    /// Name stem (`box`, `sphere`, `pawn`, ...): occluders are named `stem_N`.
    pub stem: String,
    pub shape: Shape,
    /// The shape as the scene file writes it.
    pub shape_json: Value,
    /// kg/m^3.
    pub density: f64,
}

impl Object {
    pub fn families(&self) -> Vec<Family> {
        families(&self.shape)
    }
}

/// The stage the plan flies in, taken from a loaded scene.
#[derive(Clone, Debug)]
pub struct Geometry {
    pub camera: ShadowCamera,
    pub table_top: f64,
    pub gravity: DVec3,
    pub t: f64,
    /// The highest flight at `t`, as a fraction of the light's height above the
    /// receiver (one of [`super::CEILINGS`]).
    pub ceiling: f64,
    /// Every body starts already in its pose at `t` (a launcher holds it so) and flies
    /// without spin, so that a launcher's spin error has no spin to scale; else it rests
    /// on the table and turns into its pose in flight.
    pub posed: bool,
}

impl Geometry {
    pub fn frame(&self) -> Frame {
        Frame::new(
            self.camera.width_m / self.camera.width_px as f64,
            self.camera.light_height(),
            self.ceiling,
        )
    }
}

/// One object's plan.
#[derive(Clone, Debug)]
pub struct Planned {
    pub object: Object,
    pub name: String,
    pub pose: Pose,
    pub placement: Placement,
    /// Roll the other way (the same top view for a box).
    pub flip: bool,
    /// Launch slot index.
    pub slot: usize,
}

/// Every object's plan and the slots on the table.
#[derive(Clone, Debug)]
pub struct Plan {
    pub geometry: Geometry,
    pub objects: Vec<Planned>,
    pub slots: Vec<DVec2>,
    /// Why the `auto:` kinds' count stopped, when there are any.
    pub auto_stop: Option<super::AutoStop>,
}

/// The launch of one planned object: pose on the table and start velocities.
#[derive(Clone, Copy, Debug)]
pub struct Start {
    pub position: DVec3,
    pub orientation: DQuat,
    pub velocity: DVec3,
    pub angular_velocity: DVec3,
}

impl Plan {
    /// Plan `placements` of `objects` (one each, in placement order), with slots laid
    /// out in front of the picture and assigned by distance.
    pub fn new(geometry: Geometry, objects: Vec<Object>, placements: Vec<Placement>) -> Plan {
        let mut counts = std::collections::HashMap::new();
        let mut planned: Vec<Planned> = placements
            .into_iter()
            .map(|p| {
                let object = objects[p.object].clone();
                let pose = object.families()[p.family].pose(p.alpha);
                let n = counts.entry(object.stem.clone()).or_insert(0);
                *n += 1;
                let name = format!("{}_{}", object.stem, n);
                Planned {
                    object,
                    name,
                    pose,
                    placement: p,
                    flip: false,
                    slot: 0,
                }
            })
            .collect();
        planned.sort_by_key(|p| p.placement.object);
        let mut plan = Plan {
            geometry,
            objects: planned,
            slots: Vec::new(),
            auto_stop: None,
        };
        plan.slots = plan.slot_grid();
        let targets: Vec<DVec2> = (0..plan.objects.len())
            .map(|k| plan.centre_at_t(k).truncate())
            .collect();
        let cost: Vec<Vec<f64>> = targets
            .iter()
            .map(|p| plan.slots.iter().map(|s| s.distance(*p)).collect())
            .collect();
        for (k, s) in assign(&cost).into_iter().enumerate() {
            plan.objects[k].slot = s;
        }
        plan
    }

    /// Slots on the table in front of the picture (negative y): rows of room for the
    /// largest object plus half as much again (at least 5 cm), a row as wide as 1.75
    /// pictures, half as many slots again as objects.
    fn slot_grid(&self) -> Vec<DVec2> {
        let cam = &self.geometry.camera;
        let rho = (0..self.objects.len())
            .map(|k| rest_radius(&self.objects[k].object.shape, self.launch_turn(k)))
            .fold(0.0, f64::max);
        let pitch = 2.0 * rho + rho.max(0.05);
        let n = self.objects.len();
        let wanted = (3 * n).div_ceil(2).max(1);
        if self.geometry.posed {
            return ring_slots(cam, rho, pitch, wanted);
        }
        let cols = ((1.75 * cam.width_m / pitch).floor() as usize + 1)
            .min(wanted)
            .max(1);
        let rows = wanted.div_ceil(cols);
        let front = cam.center.y - 0.5 * cam.height_m - (2.0 * rho + 0.1).max(0.15 * cam.height_m);
        let mut out = Vec::with_capacity(rows * cols);
        for r in 0..rows {
            for c in 0..cols {
                let x = cam.center.x + (c as f64 - 0.5 * (cols - 1) as f64) * pitch;
                out.push(DVec2::new(x, front - r as f64 * pitch));
            }
        }
        out
    }

    /// Height (m above the receiver) of object `k`'s pose centre at `t`.
    pub fn height(&self, k: usize) -> f64 {
        self.geometry.frame().height(self.objects[k].placement.m)
    }

    /// Where object `k`'s pose centre is at `t`: on the light ray through its shadow's
    /// centre, at the height of its magnification.
    pub fn centre_at_t(&self, k: usize) -> DVec3 {
        let cam = &self.geometry.camera;
        let p = &self.objects[k].placement;
        let on_plane = cam.pixel_to_world(p.centre.x, p.centre.y);
        let s = self.height(k) / cam.light_height();
        on_plane + s * (cam.light - on_plane)
    }

    /// Body frame -> world at `t`, without the yaw, for object `k`.
    fn unyawed(&self, k: usize) -> DQuat {
        let o = &self.objects[k];
        let turn = if o.flip { -o.pose.turn } else { o.pose.turn };
        if o.pose.turn_axis == DVec3::ZERO {
            o.pose.rest
        } else {
            DQuat::from_axis_angle(o.pose.turn_axis, turn) * o.pose.rest
        }
    }

    /// Object `k`'s orientation at launch before its yaw: its rest pose, or its pose
    /// at `t` when [`Geometry::posed`].
    fn launch_turn(&self, k: usize) -> DQuat {
        match self.geometry.posed {
            true => self.unyawed(k),
            false => self.objects[k].pose.rest,
        }
    }

    /// The launch of object `k`.
    pub fn start(&self, k: usize) -> Start {
        let g = &self.geometry;
        let o = &self.objects[k];
        let yaw = DQuat::from_rotation_z(o.placement.theta);
        let q_t = yaw * self.unyawed(k);
        let origin_t = self.centre_at_t(k) - yaw * o.pose.centre;
        let q0 = yaw * self.launch_turn(k);
        let slot = self.slots[o.slot];
        let lift = match g.posed {
            true => lift_at(&o.object.shape, q0),
            false => o.pose.lift,
        };
        let origin0 = DVec3::new(slot.x, slot.y, g.table_top + lift + 1e-6);
        let mass = o.object.shape.mass_properties(o.object.density);
        let com = mass.local_com;
        let (com0, com_t) = (origin0 + q0 * com, origin_t + q_t * com);
        let t = g.t;
        let velocity = velocity_reaching(com0, com_t, g.gravity, t);
        let turn = if o.flip { -o.pose.turn } else { o.pose.turn };
        let angular_velocity = match g.posed {
            true => DVec3::ZERO,
            false => spin_to(&mass, q0, q_t, yaw * o.pose.turn_axis * (turn / t), t),
        };
        Start {
            position: origin0,
            orientation: q0,
            velocity,
            angular_velocity,
        }
    }

    /// Hints of object `k`: (body point, pixel); both ends of an elongated shadow, else
    /// its centre.
    pub fn hints(&self, k: usize) -> Vec<(DVec3, DVec2)> {
        let o = &self.objects[k];
        let p = &o.placement;
        let inv = self.unyawed(k).inverse();
        let scale = p.m / self.geometry.frame().metres_per_px;
        if o.pose.elongated() {
            let a = o.pose.outline.half_extents().x;
            [-a, a]
                .iter()
                .map(|&x| {
                    let body = inv * (o.pose.centre + DVec3::new(x, 0.0, 0.0));
                    (body, to_pixel(p.centre, p.theta, scale, DVec2::new(x, 0.0)))
                })
                .collect()
        } else {
            vec![(inv * o.pose.centre, p.centre)]
        }
    }

    /// The scene file: the stage of `geometry` (as `bsa new` lays it out), the objects
    /// on their slots with their start guesses, the hints, the default strategy.
    pub fn scene_json(&self, name: &str, target: &str, seed: u64) -> Value {
        let cam = &self.geometry.camera;
        let occluders: Vec<Value> = (0..self.objects.len())
            .map(|k| {
                let o = &self.objects[k];
                let s = self.start(k);
                json!({"name": o.name, "shape": o.object.shape_json,
                       "position": s.position.to_array(),
                       "orientation": s.orientation.to_array(),
                       "density": o.object.density,
                       "start_velocity": s.velocity.to_array(),
                       "start_angular_velocity": s.angular_velocity.to_array()})
            })
            .collect();
        let hints: Vec<Value> = (0..self.objects.len())
            .flat_map(|k| {
                self.hints(k).into_iter().map(move |(b, px)| {
                    json!({"occluder": self.objects[k].name, "point": b.to_array(), "pixel": [px.x, px.y]})
                })
            })
            .collect();
        let g = &self.geometry;
        json!({
            "name": name,
            "target": target,
            "t": g.t,
            "gravity": g.gravity.to_array(),
            "light": cam.light.to_array(),
            "receiver": {"center": cam.center.to_array(), "u": cam.u.to_array(), "v": cam.v.to_array(),
                         "width": cam.width_m, "height": cam.height_m},
            "table": {"center": [0.0, 0.0, g.table_top - 0.5], "size": [40.0, 40.0, 1.0]},
            "occluders": occluders,
            "hints": hints,
            "strategy": default_strategy(self.objects.len()),
            "seed": seed,
        })
    }

    /// The start guess as launch values (6 per object, the solver's layout).
    pub fn parameters(&self) -> Vec<f64> {
        (0..self.objects.len())
            .flat_map(|k| {
                let s = self.start(k);
                let mut v = s.velocity.to_array().to_vec();
                v.extend_from_slice(&s.angular_velocity.to_array());
                v
            })
            .collect()
    }
}

/// At least `wanted` slots around the picture of `cam`, on rings whose first keeps a
/// body of room `rho` 5 cm off the picture's edge, `pitch` apart along each ring and
/// between rings: a launcher design launches each body from near where it flies to,
/// since its miss grows with the length of its flight.
fn ring_slots(cam: &ShadowCamera, rho: f64, pitch: f64, wanted: usize) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(wanted);
    let mut off = rho + 0.05;
    while out.len() < wanted {
        let (hx, hy) = (0.5 * cam.width_m + off, 0.5 * cam.height_m + off);
        let perimeter = 4.0 * (hx + hy);
        let k = (perimeter / pitch).floor().max(4.0) as usize;
        for j in 0..k {
            // Arc length from the front left corner, counter-clockwise.
            let mut a = perimeter * j as f64 / k as f64;
            let side = [2.0 * hx, 2.0 * hy, 2.0 * hx, 2.0 * hy];
            let corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)];
            let dirs = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];
            let mut e = 0;
            while a > side[e] && e < 3 {
                a -= side[e];
                e += 1;
            }
            let (cx, cy) = corners[e];
            let (dx, dy) = dirs[e];
            out.push(DVec2::new(
                cam.center.x + cx + dx * a,
                cam.center.y + cy + dy * a,
            ));
        }
        off += pitch;
    }
    out
}

/// The miss (rad) under which a design's start spin reaches its pose: far below the
/// solver's own ([`crate::optimize`]'s moves stop at 1e-6), as a start guess is only aimed
/// once.
const DESIGN_TOLERANCE: f64 = 1e-9;

/// The launch spin that turns a body from `q0` to `q_t` in `t` seconds of torque-free
/// flight ([`Spin::reaching`]), from `guess` (the turn's angle over `t` about its axis,
/// exact when that axis is a principal axis); `guess` itself where Newton's method does
/// not converge.
fn spin_to(mass: &MassProperties, q0: DQuat, q_t: DQuat, guess: DVec3, t: f64) -> DVec3 {
    let spin = Spin {
        mass,
        from: q0,
        t,
        flight: &FlightConfig::default(),
        tolerance: DESIGN_TOLERANCE,
    };
    spin.reaching(q_t, guess, &mut FreeFlight::default())
        .unwrap_or(guess)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadow::raster::ImageRect;
    use crate::sim::flight::LaunchState;

    fn geometry() -> Geometry {
        let camera = ShadowCamera::new(
            DVec3::new(0.0, 0.0, 6.0),
            ImageRect {
                center: DVec3::ZERO,
                u: DVec3::X,
                v: DVec3::Y,
                width_m: 1.6,
                height_m: 1.2,
                width_px: 640,
                height_px: 480,
            },
        );
        Geometry {
            camera,
            table_top: 0.0,
            gravity: DVec3::new(0.0, 0.0, -9.81),
            t: 1.2,
            ceiling: 0.8,
            posed: false,
        }
    }

    fn block() -> Object {
        Object {
            stem: "box".into(),
            shape: Shape::Cuboid {
                half_extents: DVec3::new(0.0175, 0.07, 0.035),
            },
            shape_json: json!({"box": {"size": [0.035, 0.14, 0.07]}}),
            density: 705.0,
        }
    }

    #[test]
    fn a_rolled_and_pitched_box_arrives_in_its_pose() {
        // Rolled about its long axis and pitched across it, a box turns about an axis
        // that is not principal: a constant spin about it misses the pose, the spin of
        // `spin_to` does not.
        let o = block();
        let mass = o.shape.mass_properties(o.density);
        let q0 = DQuat::from_rotation_z(0.3);
        let turn = DQuat::from_rotation_y(0.6) * DQuat::from_rotation_x(0.9);
        let q_t = DQuat::from_rotation_z(0.3) * turn;
        let (axis, angle) = turn.to_axis_angle();
        let t = 1.2;
        let guess = DQuat::from_rotation_z(0.3) * axis * (angle / t);
        let flown = |w: DVec3| {
            let mut f = FreeFlight::default();
            let launch = LaunchState {
                origin: DVec3::ZERO,
                orientation: q0,
                velocity: DVec3::ZERO,
                angular_velocity: w,
            };
            f.reset(&mass, launch, DVec3::ZERO, t, &FlightConfig::default());
            f.orientation(t).angle_between(q_t)
        };
        assert!(
            flown(guess) > 1e-3,
            "the constant spin should miss: {}",
            flown(guess)
        );
        let w = spin_to(&mass, q0, q_t, guess, t);
        // Within the flight's own accuracy (its RK4 grid follows the spin).
        assert!(flown(w) < 1e-6, "{}", flown(w));
        // About a principal axis the guess is exact and kept as it is.
        let q_roll = DQuat::from_rotation_z(0.3) * DQuat::from_rotation_y(0.9);
        let exact = DQuat::from_rotation_z(0.3) * DVec3::Y * (0.9 / t);
        assert_eq!(spin_to(&mass, q0, q_roll, exact, t), exact);
    }

    #[test]
    fn the_start_guess_flies_to_the_planned_pose_and_shadow() {
        let g = geometry();
        let placement = Placement {
            object: 0,
            family: 0,
            alpha: 0.4,
            centre: DVec2::new(400.0, 150.0),
            theta: 0.7,
            m: 2.0,
            gain: 0.0,
            area: 0.0,
        };
        let plan = Plan::new(g.clone(), vec![block()], vec![placement]);
        let s = plan.start(0);
        // Free flight for t: constant spin about a principal axis, parabola of the centre.
        let t = g.t;
        let w = s.angular_velocity;
        let q_t = DQuat::from_scaled_axis(w * t) * s.orientation;
        let p_t = s.position + s.velocity * t + 0.5 * g.gravity * t * t;
        // Its hints land on their pixels, and its ends lie along the stroke's angle.
        let hints = plan.hints(0);
        assert_eq!(hints.len(), 2);
        for (b, px) in &hints {
            let got = g.camera.project(p_t + q_t * *b).unwrap();
            assert!(got.distance(*px) < 1e-9, "{got} vs {px}");
        }
        let d = hints[1].1 - hints[0].1;
        assert!(((-d.y).atan2(d.x) - 0.7).abs() < 1e-9);
        // The centre is at the height of magnification 2, half the light's.
        assert!((p_t.z - 3.0).abs() < 1e-9);
        // The block starts on the table, on its largest face, in front of the picture.
        assert!((s.position.z - 0.0175).abs() < 1e-5 && s.position.y < -0.6);
        // Its long axis (body y) along the stroke at launch: yawed by theta.
        let axis = s.orientation * DVec3::Y;
        assert!((axis.y.atan2(axis.x) - 0.7).abs() < 1e-9);
    }
}
