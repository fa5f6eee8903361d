//! Seat: place and pose a body from scratch. [`Seat`] scans every pose of a mesh (and
//! of a block where the caller asks) on its own place, of two meshes of one kind each
//! on the other's, of a hidden block and another on the two halves of that one's part,
//! and, in a call that trades, of bodies moved onto each other's places;
//! the best are refined ([`Seats`]) and launched there. [`PoseFit`] fits every block
//! to the picture on its pose at `t` (turns, shifts and depth) and launches it there.

use glam::{DQuat, DVec3};

use super::pose::{fit_and_launch, SEAT_KEPT, SEAT_PAIRS};
use super::seats::{self, Seats};
use super::sight::exchangeable;
use super::spin::{launch_to, spin_guesses};
use super::{Move, Offers, Round};
use crate::geometry::shape::Shape;
use crate::scene::Launch;

/// The seats of a round: in the first round of a call only (in every round of a call
/// that trades: a trade of two often leaves a third body to seat; and of a call that
/// seats the blocks: in a cluster of blocks, one seated anew lets the next find its own
/// pose), since a scan of every pose costs a few thousand shadows of one body, and a
/// seat that the first round did not take is rarely taken after a smaller move.
pub(super) struct Seat;

impl Move for Seat {
    fn name(&self) -> &'static str {
        "seat"
    }

    fn offer(&self, r: &Round, out: &mut Offers) {
        let purpose = r.options.purpose;
        if !(r.first || purpose.trades() || purpose.seats_blocks()) {
            return;
        }
        let problem = r.problem;
        let seats = Seats {
            problem,
            held: r.held,
            vary: r.vary,
            now: &r.current_poses,
            sights: &r.sights,
        };
        // Each on its own place (the blocks too where the caller asks) ...
        let own: Vec<usize> = if purpose.seats_blocks() {
            r.meshes.iter().chain(r.blocks).copied().collect()
        } else {
            r.meshes.to_vec()
        };
        let owned = seats::each(problem, &own, out.ws, |&i, ws| seats.own(i, ws));
        for (&i, found) in own.iter().zip(owned) {
            if let Some((_, pose)) = found.filter(|f| f.0 < r.wrong) {
                seat(r, &[(i, pose)], out);
            }
        }
        // ... and two of a kind each on the other's: every pair scanned, the best
        // refined.
        out.name = "seat pair";
        let pairs: Vec<(usize, usize)> = r
            .meshes
            .iter()
            .enumerate()
            .flat_map(|(a, &i)| r.meshes[a + 1..].iter().map(move |&j| (i, j)))
            .filter(|&(i, j)| r.exchanges_wanted && exchangeable(&problem.scene, i, j))
            .collect();
        let scans = seats::each(problem, &pairs, out.ws, |&(i, j), ws| {
            seats.pair(i, j, 0, ws)
        });
        let mut scanned: Vec<(i64, usize, usize)> = (pairs.iter().zip(scans))
            .filter_map(|(&(i, j), found)| Some((found?.0, i, j)))
            .collect();
        scanned.sort();
        scanned.truncate(SEAT_PAIRS);
        let refined = seats::each(problem, &scanned, out.ws, |&(_, i, j), ws| {
            seats.pair(i, j, SEAT_KEPT, ws)
        });
        for (&(_, i, j), found) in scanned.iter().zip(refined) {
            if let Some((_, [pi, pj])) = found.filter(|f| f.0 < r.wrong) {
                seat(r, &[(i, pi), (j, pj)], out);
            }
        }
        // ... and a hidden block seated beside another on that one's part, cut in two:
        // every cut scanned, the best refined.
        out.name = "split";
        for (h, j, [place_h, place_j]) in seats.split_scan(r.blocks, &r.bare, out.ws) {
            let two = seats.two((h, place_h), (j, place_j), SEAT_KEPT, out.ws);
            if let Some((cost, [ph, pj])) = two {
                if cost < r.wrong {
                    seat(r, &[(h, ph), (j, pj)], out);
                }
            }
        }
        // ... and, when the caller asks, bodies of one kind and different shapes moved
        // onto each other's places: the trades the table of seats ranks best, refined.
        out.name = "trade";
        let shape = |i: usize| &problem.scene.occluders[i].shape;
        for group in r.trades {
            let (cap, longest) = match shape(group[0]) {
                Shape::Mesh(_) => (seats::MESH_TRADES, group.len()),
                _ => (seats::TRADES, seats::BLOCK_CYCLE),
            };
            let trades = seats.trade_scan(group, (cap, longest), out.ws);
            let found = seats::each(problem, &trades, out.ws, |trade, ws| {
                seats.many(trade, SEAT_KEPT, ws)
            });
            for (trade, found) in trades.iter().zip(found) {
                if let Some((_, poses)) = found.filter(|f| f.0 < r.wrong) {
                    let seated: Vec<(usize, (DVec3, DQuat))> =
                        trade.iter().map(|c| c.0).zip(poses).collect();
                    seat(r, &seated, out);
                }
            }
        }
        out.ws.poses.copy_from_slice(&r.current_poses);
    }
}

/// Offer the launch kept with each of `seated`'s bodies launched to its pose at `t`
/// (the spin by Newton's method from the guesses of [`spin_guesses`]); nothing when a
/// spin is not found.
fn seat(r: &Round, seated: &[(usize, (DVec3, DQuat))], out: &mut Offers) {
    let problem = r.problem;
    out.candidate.copy_from_slice(r.params);
    for &(b, pose) in seated {
        let guesses = spin_guesses(
            problem,
            b,
            Launch::get(r.params, b).angular_velocity,
            r.turned[b],
            pose.1,
        );
        if !launch_to(problem, b, pose, &guesses, out.candidate, out.flight) {
            return;
        }
    }
    let bodies: Vec<usize> = seated.iter().map(|s| s.0).collect();
    out.offer(&bodies);
}

/// Every block fitted to the picture on its pose at `t`, one after the other
/// ([`fit_and_launch`]), and launched there: one offer of the blocks that gained.
pub(super) struct PoseFit;

impl Move for PoseFit {
    fn name(&self) -> &'static str {
        "pose fit"
    }

    fn offer(&self, r: &Round, out: &mut Offers) {
        out.candidate.copy_from_slice(r.params);
        out.ws.poses.copy_from_slice(&r.current_poses);
        let mut fitted = Vec::new();
        for &i in r.blocks {
            if fit_and_launch(
                r.problem,
                r.held,
                r.vary,
                i,
                out.candidate,
                r.options.purpose.evolves_fits(),
                out.ws,
                out.flight,
            ) {
                fitted.push(i);
            }
        }
        if !fitted.is_empty() {
            out.offer(&fitted);
        }
    }
}
