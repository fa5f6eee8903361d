//! Steps 2 and 3 of a sample's evaluation, the contacts: the first contact before `t`
//! between two bodies or a body and the table, with the count and the contact time a
//! stage ranks by ([`Outcome`]), and the searches for one body or one pair.

use super::{Held, Outcome, Problem, Workspace};
use crate::sim::contact::{self, BallStart, Body, Motion};
use crate::sim::flight::FreeFlight;

/// Contacts closer together in time than this (s) are counted as one event's contacts.
const SIMULTANEOUS: f64 = 1e-6;

impl Problem {
    /// Occluder `i`'s motion: its flight in `flights` if launched, else its launch pose.
    fn motion<'a>(&self, i: usize, flights: &'a [FreeFlight]) -> Motion<'a> {
        let o = &self.scene.occluders[i];
        if o.launched {
            Motion::Flying(&flights[i])
        } else {
            Motion::Fixed {
                origin: o.position,
                orientation: o.orientation,
                com: o.launch_com(),
            }
        }
    }

    /// Step 2: the first contact before `t`. Every contact is given an order key (table
    /// contacts by occluder, then pairs in `(i, j)` order) and the first is the least
    /// (time, key): a plain scan in key order, which is also what makes the held
    /// occluders' cached contacts combine with the varying ones' to the same answer.
    /// A pair is only searched up to the best time so far (plus the simultaneity window):
    /// every contact that can change the outcome is still found, whatever the order.
    pub(super) fn first_contact(&self, held: Option<&Held>, ws: &mut Workspace) -> Outcome {
        let scene = &self.scene;
        let t = self.plan.horizon;
        let n = scene.occluders.len();
        let varies = |i: usize| held.is_none_or(|h| h.varying[i]);
        let ignored = |i: usize| held.is_some_and(|h| h.ignored[i]);
        // The first contact of all, and the first that involves a varying body.
        let mut best = (f64::INFINITY, usize::MAX);
        let mut own = f64::INFINITY;
        let mut first = None;
        // Landings are needed for every body (they decide its pose at t), so they are
        // searched over the whole flight.
        for i in 0..n {
            let c = match held {
                Some(h) if !h.varying[i] => (h.landing[i], h.table_hit[i]),
                _ => self.table_contact(i, &ws.flights),
            };
            (ws.landing[i], ws.table_hit[i]) = c;
            if let Some(time) = ws.table_hit[i] {
                if (time, i) < best {
                    best = (time, i);
                    first = Some((i, None));
                }
                if varies(i) {
                    own = own.min(time);
                }
            }
        }
        ws.pair_hits.clear();
        if let Some(h) = held {
            for &(tc, key, i, j) in &h.pair_hits {
                ws.pair_hits.push(tc);
                if (tc, key) < best {
                    best = (tc, key);
                    first = Some((i, Some(j)));
                }
            }
        }
        let held_pairs = ws.pair_hits.len();
        ws.pair_counts.clear();
        let flights_of = |k: usize| match held {
            Some(h) if !h.varying[k] => &h.flights[..],
            _ => &ws.flights[..],
        };
        ws.varying.clear();
        ws.varying.extend((0..n).filter(|&k| varies(k)));
        for &k in &ws.varying {
            ws.balls[k] = BallStart::of(&self.body(k, &ws.flights));
        }
        let ball = |k: usize| match held {
            Some(h) if !h.varying[k] => &h.balls[k],
            _ => &ws.balls[k],
        };
        for i in 0..n {
            // The pairs of `i` with a varying body, in the order of their keys: a
            // stage of one body searches 63 of a picture's 2,016 pairs of 64 balls.
            let (all, later) = if varies(i) {
                (i + 1..n, &[][..])
            } else {
                let from = ws.varying.partition_point(|&k| k <= i);
                (0..0, &ws.varying[from..])
            };
            for j in all.chain(later.iter().copied()) {
                if !scene.occluders[i].launched && !scene.occluders[j].launched {
                    continue;
                }
                let key = pair_key(n, i, j);
                // Every pair searched here involves a varying body: it is searched up
                // to the first such contact, which finds the first contact of all too.
                let horizon = t.min(own + SIMULTANEOUS);
                // Two balls touching at launch (`Err`) take the whole search.
                let hit = match (ball(i), ball(j)) {
                    (Some(a), Some(b)) => contact::ball_pair_contact_time(a, b, horizon).ok(),
                    _ => None,
                }
                .unwrap_or_else(|| self.pair_contact(i, flights_of(i), j, flights_of(j), horizon));
                if let Some(tc) = hit {
                    ws.pair_hits.push(tc);
                    ws.pair_counts.push(!ignored(i) && !ignored(j));
                    if !ignored(i) && !ignored(j) {
                        own = own.min(tc);
                    }
                    if (tc, key) < best {
                        best = (tc, key);
                        first = Some((i, Some(j)));
                    }
                }
            }
        }
        let own_contact = if own < t {
            let cut = own + SIMULTANEOUS;
            let count = (0..n)
                .filter(|&i| varies(i) && ws.table_hit[i].is_some_and(|tl| tl <= cut))
                .count()
                + ws.pair_hits[held_pairs..]
                    .iter()
                    .zip(&ws.pair_counts)
                    .filter(|&(&tc, &counts)| counts && tc <= cut)
                    .count();
            (t - own) * count.max(1) as f64
        } else {
            0.0
        };
        outcome(ws, t, (best.0, first), own_contact)
    }

    /// Occluder `i`'s first table contact over the flight to `t`: (its landing, its first
    /// table contact). Only a real landing stops the body; sinking into the table before
    /// leaving it (a spinning box tipping a corner in) costs a contact, but the body flies
    /// on, so its launch speed still shapes its shadow at t.
    pub(super) fn table_contact(
        &self,
        i: usize,
        flights: &[FreeFlight],
    ) -> (Option<f64>, Option<f64>) {
        let scene = &self.scene;
        let (Some(table), Some(ts)) = (&scene.table, &self.table_shape) else {
            return (None, None);
        };
        if !scene.occluders[i].launched {
            return (None, None);
        }
        let c = contact::table_contact(&self.body(i, flights), table, ts, self.plan.horizon);
        (c.filter(|c| c.landed).map(|c| c.time), c.map(|c| c.time))
    }

    /// First contact of occluders `i` and `j` (their flights in `fi` and `fj`) up to
    /// `horizon`.
    pub(super) fn pair_contact(
        &self,
        i: usize,
        fi: &[FreeFlight],
        j: usize,
        fj: &[FreeFlight],
        horizon: f64,
    ) -> Option<f64> {
        contact::pair_contact_time(&self.body(i, fi), &self.body(j, fj), horizon)
    }

    /// Occluder `i` (its flight in `flights`) as the contact searches see it.
    pub(super) fn body<'a>(&'a self, i: usize, flights: &'a [FreeFlight]) -> Body<'a> {
        Body {
            motion: self.motion(i, flights),
            shape: &self.shapes[i],
            radius: self.scene.occluders[i].bounding_radius,
        }
    }
}

/// The order key of the pair `(i, j)`, `i < j`, of `n` occluders: after the `n` table
/// contacts, the pairs in `(i, j)` order.
pub(super) fn pair_key(n: usize, i: usize, j: usize) -> usize {
    n + i * (n - 1) - i * i.saturating_sub(1) / 2 + (j - i - 1)
}

/// The outcome of a sample flown to `t` whose first contact is at `best` (infinite when
/// there is none), between the bodies `first`: every contact within [`SIMULTANEOUS`] of
/// it counts.
fn outcome(
    ws: &Workspace,
    t: f64,
    (best, first): (f64, Option<(usize, Option<usize>)>),
    own_contact: f64,
) -> Outcome {
    if best >= t {
        return Outcome {
            t_sim: t,
            n_contacts: 0,
            first_contact: None,
            own_contact,
        };
    }
    let cut = best + SIMULTANEOUS;
    let count = ws
        .table_hit
        .iter()
        .flatten()
        .filter(|&&tl| tl <= cut)
        .count()
        + ws.pair_hits.iter().filter(|&&tc| tc <= cut).count();
    Outcome {
        t_sim: best,
        n_contacts: (count as u32).max(1),
        first_contact: first,
        own_contact,
    }
}
