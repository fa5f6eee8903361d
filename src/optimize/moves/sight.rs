//! Where each body is at `t` as the moves see it ([`Sight`]: its line of sight from
//! the light, depth, shadow and part of the target), and the aiming the moves share:
//! send a body's centre of mass to a point at `t` ([`aim`]), along its line of sight
//! ([`slide`]) or onto a part of the picture at that part's size ([`send`]).

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::spin::turn_spin;
use crate::evaluate::{Problem, Workspace};
use crate::geometry::shape::Shape;
use crate::scene::velocity_reaching;
use crate::scene::Launch;
use crate::shadow::mask::{Mask, Moments};
use crate::sim::flight::{FreeFlight, LaunchState};

/// Fraction of the light-to-receiver distance (along a line of sight) that a moved body's
/// centre may take, at least: a body closer to the light than this casts a shadow over
/// ten times its size.
pub(super) const MIN_DEPTH: f64 = 0.1;

/// Clearance (m) kept between a moved body's lowest possible point and the table top.
pub(super) const TABLE_CLEARANCE: f64 = 0.01;

/// Where one launched body is at `t`, as the moves see it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sight {
    /// The centre of mass.
    pub(super) com: DVec3,
    /// The point of the receiver plane on the light's line through the centre of mass.
    pub(super) on_receiver: DVec3,
    /// The centre's depth along that line: 0 at the light, 1 on the receiver.
    pub(super) depth: f64,
    /// The body's own shadow area (pixels), alone, at its pose at `t`.
    pub(super) area: f64,
    /// Its own shadow's centroid (canvas pixels); `None` when it misses the canvas.
    pub(super) centroid: Option<DVec2>,
    /// The body's part of the target: the target pixels that are bare or that it
    /// covers, connected to those it covers; its area (pixels) and centroid (canvas
    /// pixels). `None` when its shadow is on no target pixel, when another body's
    /// shadow borders the part, or when the shadow and the part differ in shape
    /// (elongations further apart than [`SAME_SHAPE`]): a change of size does not
    /// mend a wrong face.
    pub(super) part: Option<(f64, DVec2)>,
    /// The angle (rad, image axes) of the long axis of the body's shadow and of its
    /// part, where both are elongated (see [`long_axis`]).
    pub(super) axes: Option<(f64, f64)>,
    /// The angle of its part's long axis, where the part is elongated and the shadow
    /// is not.
    pub(super) part_axis: Option<f64>,
}

/// The line of sight, depth and own shadow area of every launched body at `t`, after
/// an evaluation on `ws`; `None` for a body that is not between the light and the
/// receiver. A body whose shadow misses the canvas gets the area it would have on the
/// picture's centre line, and no part.
/// `bare` is the target minus the whole shadow, which `ws` holds.
pub(super) fn sights(
    problem: &Problem,
    movable: &[usize],
    bare: &Mask,
    ws: &mut Workspace,
) -> Vec<Option<Sight>> {
    let scene = &problem.scene;
    let n = scene.occluders.len();
    let light = scene.camera.light;
    let normal = scene.receiver.normal;
    let mut out = vec![None; n];
    let mut only = vec![false; n];
    let full = ws.mask.clone();
    for &i in movable {
        let (origin, q) = ws.poses[i];
        let com = origin + q * scene.occluders[i].mass.local_com;
        let down = (scene.receiver.center - light).dot(normal);
        let along = (com - light).dot(normal);
        if along.abs() < 1e-12 || down / along <= 1.0 {
            continue;
        }
        let depth = along / down;
        only.fill(false);
        only[i] = true;
        problem.shadow_only(&only, ws);
        let area = ws.mask.count() as f64;
        if area == 0.0 {
            // A shadow beyond the canvas costs nothing in the image terms, and no local
            // search finds its way back. Its area is taken where it would fall at the
            // same depth on the picture's centre line (a shadow's size goes with the
            // depth, hardly with the ray), so that the fill move can send it to a bare
            // part like any other body.
            let on_centre = light + (scene.receiver.center - light) * depth;
            let kept = ws.poses[i];
            ws.poses[i].0 = kept.0 + (on_centre - com);
            problem.shadow_only(&only, ws);
            ws.poses[i] = kept;
            let area = ws.mask.count() as f64;
            if area > 0.0 {
                out[i] = Some(Sight {
                    com,
                    on_receiver: light + (com - light) / depth,
                    depth,
                    area,
                    centroid: None,
                    part: None,
                    axes: None,
                    part_axis: None,
                });
            }
            continue;
        }
        let part = part_of(&problem.target.mask, &ws.mask, bare);
        // A part that another body's shadow borders is shared: its size is not this
        // body's to take.
        let others = full.and_not(&ws.mask);
        let shared = part.dilate(3).and_count(&others) > 0;
        let m = part.moments();
        let own = ws.mask.moments();
        let same_shape = elongation(&own)
            .zip(elongation(&m))
            .is_some_and(|(a, b)| a.max(b) / a.min(b) < SAME_SHAPE);
        let part_axis = long_axis(&m).filter(|_| !shared);
        let own_axis = long_axis(&own);
        let axes = own_axis.zip(part_axis);
        let part_axis = part_axis.filter(|_| own_axis.is_none());
        out[i] = Some(Sight {
            com,
            on_receiver: light + (com - light) / depth,
            depth,
            area,
            centroid: own.centroid(),
            part: m
                .centroid()
                .filter(|_| !shared && same_shape)
                .map(|c| (m.count, c)),
            axes,
            part_axis,
        });
    }
    out
}

/// A body's part of the target, from its own shadow `own`: the target pixels it covers
/// and the bare ones (`bare`) connected to them.
pub(super) fn part_of(target: &Mask, own: &Mask, bare: &Mask) -> Mask {
    let covered = target.and(own);
    let mut mine = bare.clone();
    mine.or_assign(&covered);
    mine.connected_to(&covered)
}

/// Set body `i`'s launch velocity in `params` so that its centre of mass is at `t` on
/// the light's line through `on_receiver`, at the depth where its shadow (now `own`)
/// has `area` pixels: the shadow's size goes as the inverse of the depth.
/// Returns the centre of mass aimed at.
pub(super) fn send(
    problem: &Problem,
    params: &mut [f64],
    i: usize,
    on_receiver: DVec3,
    own: Sight,
    area: f64,
) -> DVec3 {
    let light = problem.scene.camera.light;
    let depth = own.depth * (own.area / area).sqrt();
    let com = light + (on_receiver - light) * allowed_depth(problem, i, on_receiver, depth);
    aim(problem, params, i, com);
    com
}

/// `depth` along the light's line through `on_receiver`, kept where body `i`'s lowest
/// point stays above the table (for a level table under the light) and within
/// [`MIN_DEPTH`] and the receiver.
pub(super) fn allowed_depth(
    problem: &Problem,
    i: usize,
    on_receiver: DVec3,
    mut depth: f64,
) -> f64 {
    let light = problem.scene.camera.light;
    if let Some(top) = lowest_centre(problem, i) {
        let drop = light.z - on_receiver.z;
        if drop > 0.0 && light.z > top {
            depth = depth.min((light.z - top) / drop);
        }
    }
    depth.clamp(MIN_DEPTH, 1.0)
}

/// [`send`] body `i` (now `own`) to a part of the picture, `(area, centroid)` as
/// [`Sight::part`] gives it: onto the line of sight through the centroid, at the size of
/// the whole part.
pub(super) fn send_to_part(
    problem: &Problem,
    params: &mut [f64],
    i: usize,
    own: Sight,
    part: (f64, DVec2),
) {
    let (area, centroid) = part;
    let on_receiver = problem.canvas.pixel_to_world(centroid.x, centroid.y);
    send(problem, params, i, on_receiver, own, area);
}

/// Set body `i`'s launch velocity in `params` so that its centre of mass is at `target`
/// at `t` (its spin is kept).
pub(super) fn aim(problem: &Problem, params: &mut [f64], i: usize, target: DVec3) {
    let scene = &problem.scene;
    let t = scene.t;
    let start = scene.occluders[i].launch_com();
    let mut launch = Launch::get(params, i);
    launch.velocity = velocity_reaching(start, target, scene.gravity, t);
    launch.set(params, i);
}

/// Move body `i`'s centre of mass at `t` along its line from the light to `factor` times
/// its depth (its spin is kept); `false`, and `params` unchanged, when the centre would
/// leave the space between the light and the receiver or come within reach of the table.
pub(super) fn slide(problem: &Problem, params: &mut [f64], i: usize, factor: f64) -> bool {
    let scene = &problem.scene;
    let o = &scene.occluders[i];
    let t = scene.t;
    let light = scene.camera.light;
    let com = o.launch_com() + Launch::get(params, i).velocity * t + 0.5 * scene.gravity * t * t;
    let normal = scene.receiver.normal;
    let down = (scene.receiver.center - light).dot(normal);
    let depth = (com - light).dot(normal) / down * factor;
    if !(MIN_DEPTH..=1.0).contains(&depth) {
        return false;
    }
    let target = light + (com - light) * factor;
    if lowest_centre(problem, i).is_some_and(|top| target.z < top) {
        return false;
    }
    aim(problem, params, i, target);
    true
}

/// The lowest height a moved body's centre of mass may take at `t`: its bounding sphere
/// and [`TABLE_CLEARANCE`] above the table top (`None` without a table).
pub(super) fn lowest_centre(problem: &Problem, i: usize) -> Option<f64> {
    let o = &problem.scene.occluders[i];
    let table = problem.scene.table.as_ref()?;
    Some(table.top() + o.bounding_radius + TABLE_CLEARANCE)
}

/// Largest ratio of two elongations ([`elongation`]) that count as the same shape.
pub(super) const SAME_SHAPE: f64 = 1.3;

/// Smallest turn (rad) of an align move: below it, CMA-ES's local steps do better.
pub(super) const MIN_ALIGN: f64 = 0.1;

/// Ratio of the principal second moments above which a shadow has a long axis.
pub(super) const ELONGATED: f64 = 1.5;

/// The angle (rad, in image axes: x right, y down) of the long axis of the pixels whose
/// moments are `m`, when they are elongated (principal moments in a ratio of at least
/// [`ELONGATED`]).
pub(super) fn long_axis(m: &Moments) -> Option<f64> {
    let [a, b, c] = m.central_second()?;
    (elongation(m)? >= ELONGATED).then(|| 0.5 * (2.0 * b).atan2(a - c))
}

/// The ratio of the larger principal second moment to the smaller (1 for a disc), or
/// `None` for an empty or degenerate set.
pub(super) fn elongation(m: &Moments) -> Option<f64> {
    let [a, b, c] = m.central_second()?;
    let half = 0.5 * (a + c);
    let root = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let (large, small) = (half + root, half - root);
    (small > 0.0).then(|| large / small)
}

/// A body whose long axis is already within this cosine of its part's direction is not
/// laid along it again (about 18 degrees).
pub(super) const LAID: f64 = 0.95;

/// The turns (world axis, angle) that lay body `i`, at orientation `now` with its centre
/// of mass at `com`, with its long axis across the line of sight along the image angle
/// `angle`, either way round; none when it lies so already (within [`LAID`]).
pub(super) fn lays(
    problem: &Problem,
    i: usize,
    now: DQuat,
    com: DVec3,
    angle: f64,
) -> Vec<(DVec3, f64)> {
    let cam = &problem.scene.camera;
    let along = (com - cam.light).normalize();
    let d = cam.u * angle.cos() - cam.v * angle.sin();
    let d = (d - along * d.dot(along)).normalize_or_zero();
    let long = now * problem.scene.occluders[i].mass.long_axis();
    if d == DVec3::ZERO || long.dot(d).abs() >= LAID {
        return Vec::new();
    }
    [d, -d]
        .iter()
        .map(|&end| DQuat::from_rotation_arc(long, end).to_axis_angle())
        .collect()
}

/// Exchanges are offered only among at most this many pairs of bodies that could
/// exchange: each costs two Newton solves of a launch spin in every pass of moves. THE
/// THINKER's sixteen pieces make 89 such pairs, which took its solve from 4.2 to 7.9 s
/// (hand-made, seed 2: from 3.5 to 6.5 s, for no gain), and tbc's six units and six half
/// pillars 36, which took the hand-made tbc from 1.42 to 1.93 s (seed 1, for no gain);
/// the planted problems' six chess pieces make 15 pairs.
pub(super) const MAX_EXCHANGE_PAIRS: usize = 30;

/// Meshes trade places ([`Purpose::Trade`](super::Purpose::Trade)) where at most this many ordered pairs
/// of them are scanned: the six pieces of the planted chess problems make 30, each
/// scan drawing a few thousand shadows of a mesh; THE THINKER's sixteen would make 240,
/// several seconds over its solve. Blocks, whose shadows are eight corners, always
/// trade.
pub(super) const MAX_MESH_TRADES: usize = 30;

/// Whether bodies `i` and `j` may exchange poses and places: of one kind (two meshes,
/// two boxes; a sphere's pose shows nothing) and of different shapes.
pub(super) fn exchangeable(scene: &crate::scene::Scene, i: usize, j: usize) -> bool {
    let (a, b) = (&scene.occluders[i].shape, &scene.occluders[j].shape);
    canonical(a).is_some() && std::mem::discriminant(a) == std::mem::discriminant(b) && a != b
}

/// Set the launches of bodies `i` and `j` (now seen as `si`, `sj`, turned to `turned` at
/// `t`) in `params` so that each takes the other's orientation at `t` (the spin that
/// reaches it, by [`spin_reaching`](super::spin_reaching); frames matched by [`canonical`]) and the other's
/// line of sight, at the depth where its shadow has the other's size (as their bounding
/// radii go): two bodies of one family in the same kind of pose (a king and a bishop
/// lying down) often end each drawing the other's shadow at the other's size, which no
/// swap that keeps the poses reproduces.
pub(super) fn exchange_poses(
    problem: &Problem,
    params: &mut [f64],
    (i, si): (usize, Sight),
    (j, sj): (usize, Sight),
    turned: &[DQuat],
    flight: &mut FreeFlight,
) {
    let scene = &problem.scene;
    let frame = |k: usize| canonical(&scene.occluders[k].shape).unwrap_or(DQuat::IDENTITY);
    let (ci, cj) = (frame(i), frame(j));
    let want_i = turned[j] * cj * ci.conjugate();
    let want_j = turned[i] * ci * cj.conjugate();
    for (b, want) in [(i, want_i), (j, want_j)] {
        let rotation = (want * turned[b].conjugate()).to_axis_angle();
        turn_spin(problem, params, b, turned[b], rotation, true, flight);
    }
    let ratio = scene.occluders[i].bounding_radius / scene.occluders[j].bounding_radius;
    let as_j = Sight {
        area: sj.area * ratio * ratio,
        ..sj
    };
    let as_i = Sight {
        area: si.area / (ratio * ratio),
        ..si
    };
    send(problem, params, i, sj.on_receiver, as_j, sj.area);
    send(problem, params, j, si.on_receiver, as_i, si.area);
}

/// The rotation from a body's canonical frame to its own (body) frame, for a swap of
/// poses: a mesh's own frame (the pieces of one set share a convention: upright along
/// one axis, base at the origin), a box's axes sorted from the longest (x) to the
/// shortest (z); `None` for a sphere, whose pose shows nothing.
pub(super) fn canonical(shape: &Shape) -> Option<DQuat> {
    match shape {
        Shape::Sphere { .. } => None,
        Shape::Mesh(_) => Some(DQuat::IDENTITY),
        Shape::Cuboid { half_extents } => {
            let h = half_extents.to_array();
            let mut order = [0usize, 1, 2];
            order.sort_by(|&a, &b| h[b].total_cmp(&h[a]).then(a.cmp(&b)));
            let axis =
                |k: usize| DVec3::from_array(std::array::from_fn(|c| f64::from(u8::from(c == k))));
            let (x, y) = (axis(order[0]), axis(order[1]));
            // A right-handed frame: a box is symmetric under the sign of its third axis.
            Some(DQuat::from_mat3(&DMat3::from_cols(x, y, x.cross(y))))
        }
    }
}

/// Principal moments closer than this share of the largest count as equal for
/// [`own_axes`]: a body with two such moments is close to a solid of revolution (a king,
/// whose cross makes its two moments across its axis differ by 2e-4 of them; a knight's
/// differ by 8 %).
pub(super) const REVOLUTION: f64 = 0.01;

/// The body-frame principal axes of a body whose three principal moments differ (by
/// more than [`REVOLUTION`]), as a knight's do; `None` for one close to a solid of
/// revolution (a lathed chess piece: a turn about its axis shows the same shadow, and a
/// half turn across it is close to the half turns about world axes that the moves
/// already try).
pub(super) fn own_axes(mass: &crate::geometry::shape::MassProperties) -> Option<[DVec3; 3]> {
    let k = mass.principal_inertia;
    let tol = REVOLUTION * k.max_element();
    let distinct = (k.x - k.y).abs() > tol && (k.y - k.z).abs() > tol && (k.z - k.x).abs() > tol;
    distinct.then(|| [DVec3::X, DVec3::Y, DVec3::Z].map(|e| mass.principal_frame * e))
}

/// Move body `i` (seen as `own` before a turn that `params` now holds) at the same depth
/// so that its own shadow's centroid is back where it was: a turn keeps the centre of
/// mass, which an asymmetric body's shadow does not surround evenly. The shadow is drawn
/// alone at the turned pose, in `ws`.
pub(super) fn recentre(
    problem: &Problem,
    params: &mut [f64],
    i: usize,
    own: Sight,
    flight: &mut FreeFlight,
    ws: &mut Workspace,
) {
    let scene = &problem.scene;
    let o = &scene.occluders[i];
    let Some(before) = own.centroid else { return };
    flight.reset(
        &o.mass,
        LaunchState::of(o, Launch::get(params, i)),
        scene.gravity,
        scene.t,
        &problem.flight,
    );
    ws.poses[i] = flight.pose(scene.t);
    let mut only = vec![false; scene.occluders.len()];
    only[i] = true;
    problem.shadow_only(&only, ws);
    let Some(after) = ws.mask.moments().centroid() else {
        return;
    };
    let c = &problem.canvas;
    let shift = c.pixel_to_world(before.x, before.y) - c.pixel_to_world(after.x, after.y);
    // A shift at depth `d` (0 at the light, 1 on the receiver) moves the shadow `1 / d`
    // times as far.
    aim(problem, params, i, own.com + shift * own.depth);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_canonical_frame_runs_from_its_longest_axis_to_its_shortest() {
        let shape = Shape::Cuboid {
            half_extents: DVec3::new(0.035, 0.14, 0.0175),
        };
        let q = canonical(&shape).expect("a box has a frame");
        assert!((q * DVec3::X - DVec3::Y).length() < 1e-12);
        assert!((q * DVec3::Y - DVec3::X).length() < 1e-12);
        // A proper rotation: the third axis is the shortest, either way along it.
        assert!(((q * DVec3::Z).dot(DVec3::Z).abs() - 1.0).abs() < 1e-12);
        assert!(canonical(&Shape::Sphere { radius: 0.1 }).is_none());
    }

    #[test]
    fn long_axis_gives_the_angle_of_an_elongated_blob() {
        for deg in [0.0f64, 30.0, -60.0, 89.0] {
            let a = deg.to_radians();
            let (c, s) = (a.cos(), a.sin());
            // A 60 x 10 px bar turned by `a` (image axes).
            let m = Mask::from_fn(200, 200, |x, y| {
                let (dx, dy) = (x as f64 + 0.5 - 100.0, y as f64 + 0.5 - 100.0);
                (dx * c + dy * s).abs() < 30.0 && (-dx * s + dy * c).abs() < 5.0
            });
            let got = long_axis(&m.moments()).expect("a bar is elongated");
            let mut d = got - a;
            d -= std::f64::consts::PI * (d / std::f64::consts::PI).round();
            assert!(d.abs() < 0.03, "{deg} deg: got {} deg", got.to_degrees());
        }
        let disc = Mask::from_fn(100, 100, |x, y| {
            let (dx, dy) = (x as f64 - 50.0, y as f64 - 50.0);
            dx * dx + dy * dy < 900.0
        });
        assert_eq!(long_axis(&disc.moments()), None);
    }

    #[test]
    fn only_a_body_far_from_a_solid_of_revolution_turns_about_its_own_axes() {
        let mass = |k: DVec3| crate::geometry::shape::MassProperties {
            mass: 0.05,
            local_com: DVec3::ZERO,
            principal_inertia: k,
            principal_frame: DQuat::from_rotation_z(0.3),
        };
        // The chess set's knight and king (kg m^2): the king's cross parts its two moments
        // across its axis by 2e-4 of them, the knight's head by 8 %.
        let knight = own_axes(&mass(DVec3::new(1.739e-6, 6.213e-6, 6.736e-6)));
        let axes = knight.expect("a knight turns about its own axes");
        assert!((axes[0] - DQuat::from_rotation_z(0.3) * DVec3::X).length() < 1e-12);
        assert!(own_axes(&mass(DVec3::new(1.776e-6, 1.9044e-5, 1.9047e-5))).is_none());
        assert!(own_axes(&mass(DVec3::splat(2e-6))).is_none());
    }

    #[test]
    fn lays_turn_the_long_axis_along_the_part_across_the_line_of_sight() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fly");
        let p = Problem::new(crate::scene::load(&dir).unwrap());
        let cam = &p.scene.camera;
        let mass = &p.scene.occluders[0].mass;
        let com = cam.light + DVec3::new(0.3, -0.2, -2.0);
        let along = (com - cam.light).normalize();
        for angle in [0.0f64, 0.7, -1.2] {
            // Stood on its end, along the line of sight: its shadow has no long axis.
            let now = DQuat::from_rotation_arc(mass.long_axis(), along);
            let turns = lays(&p, 0, now, com, angle);
            assert_eq!(turns.len(), 2);
            let d = cam.u * angle.cos() - cam.v * angle.sin();
            let d = (d - along * d.dot(along)).normalize();
            let ends: Vec<f64> = turns
                .iter()
                .map(|&(axis, a)| (DQuat::from_axis_angle(axis, a) * now * mass.long_axis()).dot(d))
                .collect();
            assert!(
                (ends[0] - 1.0).abs() < 1e-9 && (ends[1] + 1.0).abs() < 1e-9,
                "{ends:?}"
            );
            // Laid already: nothing to do.
            let laid = DQuat::from_axis_angle(turns[0].0, turns[0].1) * now;
            assert!(lays(&p, 0, laid, com, angle).is_empty());
        }
    }
}
