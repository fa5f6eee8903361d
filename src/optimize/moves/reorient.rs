//! Reorient: search a mesh's pose where it is. [`Reorient`] turns a mesh a quarter or
//! half turn about each world axis, and one whose three principal moments differ (a
//! knight) about its own axes too, about its centre of mass and recentred so that its
//! shadow keeps its centroid (a half turn about its long axis mirrors a lying knight's
//! profile); it aligns the shadow's long axis with its part's (a turn about the line of
//! sight), and lays a mesh seen end-on along its part. The spin that reaches the new
//! orientation at `t` comes from [`turn_spin`]. A block's pose where it is is the pose
//! fit's ([`PoseFit`](super::seat::PoseFit)).

use glam::DVec3;

use super::sight::{lays, own_axes, recentre, MIN_ALIGN};
use super::spin::turn_spin;
use super::{Move, Offers, Round};
use crate::geometry::shape::Shape;

/// The turns tried for a mesh (rad, about each world axis): a
/// quarter turn either way and a half turn, added to its rotation by `t` through its
/// launch spin (exact for a spin about a principal axis, close otherwise).
const TURNS: [f64; 3] = [
    std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    std::f64::consts::PI,
];

/// Turns, aligns and lays of every mesh.
///
/// Not of blocks: the pose fit turns a block on its pose at `t` as well (a block turned
/// a quarter across its part or onto another face, test
/// `moves_fit_a_block_turned_across_its_part_back_along_it`), and a turn offered beside
/// it is taken where it ranks best as it stands, before the fit or the runs settle the
/// block. On the planted draws 14600 to 14800 (plant route, 63 problems with blocks),
/// leaving blocks to the fit raised 38 and lowered 15 (median 0.9849 to 0.9899, lowest
/// 0.9125 to 0.9258, 4 % fewer samples); turning them in the polish alone, whose moves
/// are kept only where the picture is no worse, then lowered 8 and raised 1.
pub(super) struct Reorient;

impl Move for Reorient {
    fn name(&self) -> &'static str {
        "reorient"
    }

    fn offer(&self, r: &Round, out: &mut Offers) {
        let (problem, params) = (r.problem, r.params);
        let scene = &problem.scene;
        for &i in r.movable {
            if !matches!(scene.occluders[i].shape, Shape::Mesh(_)) {
                continue;
            }
            let now = r.turned[i];
            // An asymmetric mesh (a knight, most meshes a user brings) also turns about
            // its own principal axes: a half turn about its long axis mirrors a lying
            // knight's profile, which a turn about a world axis does only by also moving
            // its long axis off its part. Its spin is not about one axis, so the turn is
            // solved on the flight. Its centre of mass is rarely the middle of its
            // shadow, so each turn is offered about it, and moved so that the shadow
            // keeps its centroid (`recentre`): the first undoes a wrong turn, the second
            // mends a wrong profile on its place.
            if let Some(si) = r.sights[i] {
                for axis in own_axes(&scene.occluders[i].mass).into_iter().flatten() {
                    for angle in TURNS {
                        out.candidate.copy_from_slice(params);
                        let rotation = (now * axis, angle);
                        turn_spin(problem, out.candidate, i, now, rotation, true, out.flight);
                        out.offer(&[i]);
                        recentre(problem, out.candidate, i, si, out.flight, out.ws);
                        out.offer(&[i]);
                    }
                }
            }
            let turn = |axis: DVec3, angle: f64, exact: bool, out: &mut Offers| {
                out.candidate.copy_from_slice(params);
                turn_spin(
                    problem,
                    out.candidate,
                    i,
                    now,
                    (axis, angle),
                    exact,
                    out.flight,
                );
                out.offer(&[i]);
            };
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                for angle in TURNS {
                    turn(axis, angle, false, out);
                }
            }
            // Align the shadow's long axis with its part's: a turn about the line of
            // sight (image y points down, so try both senses).
            if let Some((own, part)) = r.sights[i].and_then(|si| si.axes) {
                let mut delta = part - own;
                while delta > std::f64::consts::FRAC_PI_2 {
                    delta -= std::f64::consts::PI;
                }
                while delta <= -std::f64::consts::FRAC_PI_2 {
                    delta += std::f64::consts::PI;
                }
                if delta.abs() > MIN_ALIGN {
                    let sight = r.sights[i].expect("axes come with a sight");
                    let axis = (sight.com - scene.camera.light).normalize();
                    turn(axis, delta, true, out);
                    turn(axis, -delta, true, out);
                }
            }
            // Lay the mesh's long axis along its part's, across the line of sight,
            // either way round: a piece seen end-on, whose shadow has no long axis to
            // align.
            if let Some((sight, angle)) = r.sights[i].and_then(|si| Some((si, si.part_axis?))) {
                for (axis, angle) in lays(problem, i, now, sight.com, angle) {
                    turn(axis, angle, true, out);
                }
            }
        }
    }
}
