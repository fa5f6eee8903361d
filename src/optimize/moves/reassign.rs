//! Reassign: send bodies to other parts of the picture.
//!
//! [`Swap`]: two bodies each take the other's part, at the size that part has now,
//! at the other's place in space, or at the other's whole part; two bodies of one kind
//! and different shapes each take the other's pose and place too (an exchange).
//! [`Fill`]: a body sent to the largest bare part of the
//! target at that part's size, laid along it where it is elongated. The trades of
//! places among three bodies are seats on each other's places ([`super::seat`]).

use glam::DVec2;

use super::sight::{aim, exchange_poses, exchangeable, lays, long_axis, send, send_to_part};
use super::spin::turn_spin;
use super::{Move, Offers, Round};
use crate::geometry::shape::Shape;
use crate::shadow::mask::Mask;

/// Every two bodies swapped (three ways) or exchanged.
pub(super) struct Swap;

impl Move for Swap {
    fn name(&self) -> &'static str {
        "swap"
    }

    fn offer(&self, r: &Round, out: &mut Offers) {
        let (problem, params) = (r.problem, r.params);
        for (a, &i) in r.movable.iter().enumerate() {
            for &j in &r.movable[a + 1..] {
                let (Some(si), Some(sj)) = (r.sights[i], r.sights[j]) else {
                    continue;
                };
                // Each takes the other's part of the picture at the size that part has
                // now (the picture changes only by the two shapes) ...
                out.candidate.copy_from_slice(params);
                send(problem, out.candidate, i, sj.on_receiver, si, sj.area);
                send(problem, out.candidate, j, si.on_receiver, sj, si.area);
                out.offer(&[i, j]);
                // ... or the other's place in space (each part's size changes by the
                // ratio of the two bodies' sizes) ...
                out.candidate.copy_from_slice(params);
                aim(problem, out.candidate, i, sj.com);
                aim(problem, out.candidate, j, si.com);
                out.offer(&[i, j]);
                // ... or, where both parts are known, the other's part at its whole
                // size: two bodies each on the other's part, both too small for it (one
                // kept low under the other's flight), gain nothing from a swap at the
                // sizes the parts have now.
                if let (Some(part_i), Some(part_j)) = (si.part, sj.part) {
                    out.candidate.copy_from_slice(params);
                    send_to_part(problem, out.candidate, i, si, part_j);
                    send_to_part(problem, out.candidate, j, sj, part_i);
                    out.offer(&[i, j]);
                }
                // ... or each takes the other's pose and place (`exchange_poses`),
                // polished: each body is a little off its new part as it stands.
                if r.exchanges_wanted && exchangeable(&problem.scene, i, j) {
                    out.candidate.copy_from_slice(params);
                    exchange_poses(
                        problem,
                        out.candidate,
                        (i, si),
                        (j, sj),
                        &r.turned,
                        out.flight,
                    );
                    let e = out.search.evaluate(out.candidate, out.ws);
                    let mut launch = out.candidate.clone();
                    out.search.polish(&mut launch, e, &[i, j], out.ws);
                    out.offer_launch(&launch, &[i, j]);
                }
            }
        }
    }
}

/// The largest bare part of the target filled by each body in turn.
pub(super) struct Fill;

impl Move for Fill {
    fn name(&self) -> &'static str {
        "fill"
    }

    fn offer(&self, r: &Round, out: &mut Offers) {
        let Some((area, centroid, (x0, y0))) = r.hole else {
            return;
        };
        let problem = r.problem;
        let on_receiver = problem.canvas.pixel_to_world(centroid.x, centroid.y);
        // The hole's long axis, to lay a body along as it is sent there: a piece sent
        // end-on to a part that shows it lying rarely beats the picture it leaves, and
        // the lay alone cannot follow.
        let mut seed = Mask::new(r.bare.width(), r.bare.height());
        seed.set(x0, y0);
        let hole_axis = long_axis(&r.bare.connected_to(&seed).moments());
        for &i in r.movable {
            let Some(si) = r.sights[i] else { continue };
            out.candidate.copy_from_slice(r.params);
            let com = send(problem, out.candidate, i, on_receiver, si, area as f64);
            out.offer(&[i]);
            let Some(angle) = hole_axis else { continue };
            if matches!(problem.scene.occluders[i].shape, Shape::Sphere { .. }) {
                continue;
            }
            let now = r.turned[i];
            let sent = out.candidate.clone();
            for rotation in lays(problem, i, now, com, angle) {
                out.candidate.copy_from_slice(&sent);
                turn_spin(problem, out.candidate, i, now, rotation, true, out.flight);
                out.offer(&[i]);
            }
        }
    }
}

/// The largest bare part of the target: its area (pixels), centroid and a pixel of it.
pub(super) type Hole = (usize, DVec2, (usize, usize));
