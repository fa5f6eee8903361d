//! The table of seats of a round ([`Seats`]): each body seated on its own place, two
//! on each other's, a hidden block and another on the two halves of a part cut across
//! ([`Seats::splits`]), and the trades of places ranked by seats made one at a time
//! ([`Seats::trade_scan`]), each refined by [`seat_pose`]'s search.

use glam::{DQuat, DVec2, DVec3};

use super::pose::{seat_pose, Place, Seat, SEAT_KEPT};
use super::Sight;
use crate::evaluate::{Held, Problem, Workspace};
use crate::shadow::mask::Mask;

/// The launch kept, as [`seat_pose`] sees it: the bodies' poses at `t` and sights.
pub(super) struct Seats<'a> {
    pub(super) problem: &'a Problem,
    pub(super) held: &'a Held,
    /// The bodies of the stage.
    pub(super) vary: &'a [bool],
    /// Every body's pose at `t` (origin, orientation).
    pub(super) now: &'a [(DVec3, DQuat)],
    pub(super) sights: &'a [Option<Sight>],
}

/// `f` of each of `items`, beside each other on the pool the caller runs on, each thread
/// with a workspace of its own; the results in the items' order. Every seat sets up the
/// workspace it reads ([`Seats::others`]), so they are those of the items one after the
/// other. A round's seats are its costliest moves: hundreds of poses drawn per seat.
/// One item, or one thread, runs on the caller's `ws`, with no workspace made for it.
pub(super) fn each<T: Sync, R: Send>(
    problem: &Problem,
    items: &[T],
    ws: &mut Workspace,
    f: impl Fn(&T, &mut Workspace) -> R + Sync,
) -> Vec<R> {
    use rayon::prelude::*;
    if items.len() < 2 || rayon::current_num_threads() < 2 {
        return items.iter().map(|item| f(item, ws)).collect();
    }
    items
        .par_iter()
        .map_init(|| problem.workspace(), |ws, item| f(item, ws))
        .collect()
}

impl Seats<'_> {
    /// The shadows of every body but `bodies`, at their poses now.
    fn others(&self, bodies: &[usize], ws: &mut Workspace) -> Mask {
        ws.poses.copy_from_slice(self.now);
        let mut which = self.vary.to_vec();
        for &b in bodies {
            which[b] = false;
        }
        self.problem.shadow_held_and(self.held, &which, ws);
        ws.mask.clone()
    }

    /// Where body `i` casts its shadow now: its centroid, area and depth.
    fn place(&self, i: usize) -> Option<Place> {
        let s = self.sights[i]?;
        Some((s.centroid?, s.area, s.depth))
    }

    /// Body `i` seated on its own place: the wrong pixels of the picture and its pose.
    pub(super) fn own(&self, i: usize, ws: &mut Workspace) -> Option<(i64, (DVec3, DQuat))> {
        let place = self.place(i)?;
        let seat = Seat::new(self.problem, i, &self.others(&[i], ws));
        let (cost, com, q) = seat_pose(&seat, self.now[i].1, place, SEAT_KEPT, ws)?;
        Some((cost, (com, q)))
    }

    /// Bodies `i` and `j` each seated on the other's place ([`Seats::two`]).
    pub(super) fn pair(
        &self,
        i: usize,
        j: usize,
        kept: usize,
        ws: &mut Workspace,
    ) -> Option<(i64, [(DVec3, DQuat); 2])> {
        self.two((i, self.place(j)?), (j, self.place(i)?), kept, ws)
    }

    /// Body `i` seated on `place_i` and body `j` on `place_j` (`(centroid, area, depth)`
    /// as [`Seat::place`] takes them), `i` first ([`Seats::many`]). Returns the wrong
    /// pixels of the picture and the two poses.
    pub(super) fn two(
        &self,
        (i, place_i): (usize, Place),
        (j, place_j): (usize, Place),
        kept: usize,
        ws: &mut Workspace,
    ) -> Option<(i64, [(DVec3, DQuat); 2])> {
        let (cost, poses) = self.many(&[(i, place_i), (j, place_j)], kept, ws)?;
        Some((cost, [poses[0], poses[1]]))
    }

    /// Bodies seated each on its place (`(body, (centroid, area, depth))`), in order:
    /// the first over the shadows of every body not seated, each next over those and
    /// the shadows of the bodies seated before it; `kept` as [`seat_pose`] takes it.
    /// Returns the wrong pixels of the picture and the poses, in order.
    pub(super) fn many(
        &self,
        seated: &[(usize, Place)],
        kept: usize,
        ws: &mut Workspace,
    ) -> Option<(i64, Vec<(DVec3, DQuat)>)> {
        let bodies: Vec<usize> = seated.iter().map(|s| s.0).collect();
        let mut others = self.others(&bodies, ws);
        let mut poses = Vec::with_capacity(seated.len());
        let mut cost = 0;
        for (k, &(b, place)) in seated.iter().enumerate() {
            let seat = Seat::new(self.problem, b, &others);
            let (c, com, q) = seat_pose(&seat, self.now[b].1, place, kept, ws)?;
            if k + 1 < seated.len() {
                seat.draw(com, q, ws);
                others.or_assign(&ws.mask);
            }
            cost = c;
            poses.push((com, q));
        }
        Some((cost, poses))
    }

    /// Trades of places among `blocks` (of one kind) worth refining, best first, at most
    /// `cap`: each a cycle of two to `longest` bodies of different shapes, each to be
    /// seated on the place of the next (the last on the first's), as `(body, place)`.
    ///
    /// Each body is seated ([`seat_pose`], its scan's best pose refined) on the place of
    /// every body of another shape, over the picture without the two, once; that seat's
    /// change of the picture's wrong pixels, added over a cycle to what taking its
    /// bodies out costs the picture, ranks the cycle. A table of one seat per ordered
    /// pair (`n (n - 1)` at most) ranks every cycle ([`cycles`]), where seating each
    /// cycle alone would cost a seat per body of every one. (The scan alone ranks blocks
    /// as well, but not pieces: a chess piece's scanned shadow is off by hundreds of
    /// pixels, more than a trade gains.)
    pub(super) fn trade_scan(
        &self,
        blocks: &[usize],
        (cap, longest): (usize, usize),
        ws: &mut Workspace,
    ) -> Vec<Vec<(usize, Place)>> {
        let target = &self.problem.target.mask;
        let shape = |a: usize| &self.problem.scene.occluders[blocks[a]].shape;
        let whole = self.others(&[], ws).xor_count(target) as i64;
        // What taking each block out costs the picture (wrong pixels).
        let out: Vec<i64> = blocks
            .iter()
            .map(|&i| self.others(&[i], ws).xor_count(target) as i64 - whole)
            .collect();
        // `on[a][b]`: the change of wrong pixels of block `a` seated on `b`'s place, over
        // the picture without both.
        let n = blocks.len();
        let pairs: Vec<(usize, usize, Place)> = (0..n * n)
            .map(|k| (k / n, k % n))
            .filter(|&(a, b)| shape(a) != shape(b))
            .filter_map(|(a, b)| Some((a, b, self.place(blocks[b])?)))
            .collect();
        let seated = each(self.problem, &pairs, ws, |&(a, b, place), ws| {
            let i = blocks[a];
            let seat = Seat::new(self.problem, i, &self.others(&[i, blocks[b]], ws));
            seat_pose(&seat, self.now[i].1, place, 1, ws).map(|(cost, _, _)| cost - seat.base)
        });
        let mut on = vec![vec![None; n]; n];
        for (&(a, b, _), change) in pairs.iter().zip(seated) {
            on[a][b] = change;
        }
        let mut trades: Vec<(i64, Vec<usize>)> = Vec::new();
        let linked = |a: usize, b: usize| on[a][b].is_some();
        cycles(n, longest, &linked, &mut |cycle| {
            let mut change = 0;
            for (k, &a) in cycle.iter().enumerate() {
                let Some(seated) = on[a][cycle[(k + 1) % cycle.len()]] else {
                    return;
                };
                change += out[a] + seated;
            }
            trades.push((change, cycle.to_vec()));
        });
        trades.sort_by_key(|c| c.0);
        trades
            .into_iter()
            .take(cap)
            .filter_map(|(_, cycle)| {
                (0..cycle.len())
                    .map(|k| {
                        let next = blocks[cycle[(k + 1) % cycle.len()]];
                        Some((blocks[cycle[k]], self.place(next)?))
                    })
                    .collect()
            })
            .collect()
    }

    /// Body `o`'s part of the target: the target pixels its shadow covers now and the
    /// bare ones connected to them.
    fn part(&self, o: usize, bare: &Mask, ws: &mut Workspace) -> Mask {
        self.alone(o, ws);
        super::sight::part_of(&self.problem.target.mask, &ws.mask, bare)
    }

    /// Draw body `i`'s shadow alone, at its pose now, into `ws.mask`.
    fn alone(&self, i: usize, ws: &mut Workspace) {
        ws.poses.copy_from_slice(self.now);
        let mut only = vec![false; self.vary.len()];
        only[i] = true;
        self.problem.shadow_only(&only, ws);
    }

    /// The bodies (of `bodies`) that the picture hardly needs where they are: fewer than
    /// [`HIDDEN`] of their shadow's pixels are target pixels that no other shadow
    /// covers (a block hidden under the others' shadows, or cast beside the picture).
    /// Most hidden first, at most [`SPLIT_HIDDEN`].
    fn hidden(&self, bodies: &[usize], ws: &mut Workspace) -> Vec<usize> {
        let mut found: Vec<(f64, usize)> = Vec::new();
        for &i in bodies {
            let others = self.others(&[i], ws);
            self.alone(i, ws);
            let area = ws.mask.count() as f64;
            let own = ws
                .mask
                .and(&self.problem.target.mask)
                .and_not_count(&others) as f64;
            if area > 0.0 && own < HIDDEN * area {
                found.push((own / area, i));
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        found.into_iter().take(SPLIT_HIDDEN).map(|f| f.1).collect()
    }

    /// The places a hidden body and body `j` may share: `j`'s part of the target (the
    /// target pixels its shadow covers and the bare ones connected to them) cut across
    /// its long axis at [`SPLIT_CUTS`] of its length, each side a place, `(hidden's
    /// place, j's place)`, both ways round; and the pixels of `wrong` (those the
    /// picture gets wrong) within three pixels of `j`'s shadow. Empty when `j` casts no
    /// shadow on the target.
    fn splits(
        &self,
        j: usize,
        bare: &Mask,
        wrong: &Mask,
        ws: &mut Workspace,
    ) -> (u64, Vec<[Place; 2]>) {
        let Some(depth) = self.sights[j].map(|s| s.depth) else {
            return (0, Vec::new());
        };
        let part = self.part(j, bare, ws);
        // `part` left body `j`'s shadow in the workspace.
        let near = ws.mask.dilate(3).and_count(wrong);
        let out = cut_across(&part, &SPLIT_CUTS)
            .into_iter()
            .flat_map(|[(cl, al), (ch, ah)]| {
                let (low, high) = ((cl, al, depth), (ch, ah, depth));
                [[low, high], [high, low]]
            })
            .collect();
        (near, out)
    }

    /// The splits of a part between a hidden block and another worth refining, best
    /// first, at most [`SPLITS`]: `(hidden, partner, [hidden's place, partner's
    /// place])`. Each hidden block ([`Seats::hidden`] of `blocks`) is tried with the
    /// [`SPLIT_PARTNERS`] other blocks with the most wrong pixels around their shadows,
    /// on every cut of [`Seats::splits`], both seated by a scan ([`Seats::two`], `kept`
    /// 0) and ranked by the picture's wrong pixels.
    pub(super) fn split_scan(
        &self,
        blocks: &[usize],
        bare: &Mask,
        ws: &mut Workspace,
    ) -> Vec<(usize, usize, [Place; 2])> {
        let hidden = self.hidden(blocks, ws);
        if hidden.is_empty() {
            return Vec::new();
        }
        // The pixels the picture gets wrong now: bare target and shadow off it.
        let mut wrong = self.others(&[], ws);
        let extra = wrong.and_not(&self.problem.target.mask);
        wrong.copy_from(bare);
        wrong.or_assign(&extra);
        let mut partners = Vec::new();
        for &j in blocks {
            let (near, places) = self.splits(j, bare, &wrong, ws);
            if near > 0 && !places.is_empty() {
                partners.push((std::cmp::Reverse(near), j, places));
            }
        }
        partners.sort_by_key(|p| (p.0, p.1));
        let mut scanned = Vec::new();
        for &r in &hidden {
            for (_, j, cuts) in partners.iter().filter(|p| p.1 != r).take(SPLIT_PARTNERS) {
                for &[place_r, place_j] in cuts {
                    if let Some((cost, _)) = self.two((r, place_r), (*j, place_j), 0, ws) {
                        scanned.push((cost, r, *j, [place_r, place_j]));
                    }
                }
            }
        }
        scanned.sort_by_key(|s| s.0);
        scanned
            .into_iter()
            .take(SPLITS)
            .map(|(_, r, j, places)| (r, j, places))
            .collect()
    }
}

/// Every cycle of two to `longest` distinct indices below `n`, its first the lowest,
/// each step `a -> b` one that `linked` allows, passed to `visit` as a path (the cycle
/// closes from its last back to its first, which `visit` judges): depth first, so
/// that `[a, b]` comes before the longer cycles that start with it, and a cycle of
/// three comes right after the pair it extends (the order of a table of pairs and
/// three-cycles).
fn cycles(
    n: usize,
    longest: usize,
    linked: &dyn Fn(usize, usize) -> bool,
    visit: &mut dyn FnMut(&[usize]),
) {
    fn grow(
        path: &mut Vec<usize>,
        n: usize,
        longest: usize,
        linked: &dyn Fn(usize, usize) -> bool,
        visit: &mut dyn FnMut(&[usize]),
    ) {
        let last = path[path.len() - 1];
        for next in path[0] + 1..n {
            if path.contains(&next) || !linked(last, next) {
                continue;
            }
            path.push(next);
            visit(path);
            if path.len() < longest {
                grow(path, n, longest, linked, visit);
            }
            path.pop();
        }
    }
    let mut path = Vec::with_capacity(longest);
    for first in 0..n {
        path.clear();
        path.push(first);
        grow(&mut path, n, longest, linked, visit);
    }
}

/// `part` cut across its long axis (of its second moments) at each fraction of its
/// pixels in `cuts`, counted along that axis: the centroid (pixels) and area (pixels) of
/// the side below the cut and of the side above, for each cut whose sides both hold
/// [`SPLIT_LEAST`] pixels or more.
fn cut_across(part: &Mask, cuts: &[f64]) -> Vec<[(DVec2, f64); 2]> {
    let m = part.moments();
    let (Some(c), Some([a, b, cc])) = (m.centroid(), m.central_second()) else {
        return Vec::new();
    };
    let angle = 0.5 * (2.0 * b).atan2(a - cc);
    let axis = DVec2::new(angle.cos(), angle.sin());
    let along = |x: usize, y: usize| (DVec2::new(x as f64, y as f64) - c).dot(axis);
    // The part's pixels (read from its rows' words, not pixel by pixel over the
    // canvas), and their distances along the axis, to cut at quantiles.
    let mut pixels: Vec<(usize, usize)> = Vec::with_capacity(m.count as usize);
    for y in part.row_range() {
        for (w, &word) in part.row(y).iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                pixels.push((64 * w + bits.trailing_zeros() as usize, y));
                bits &= bits - 1;
            }
        }
    }
    let mut sorted: Vec<f64> = pixels.iter().map(|&(x, y)| along(x, y)).collect();
    sorted.sort_by(f64::total_cmp);
    let mut out = Vec::new();
    for &cut in cuts {
        let at = sorted[((sorted.len() as f64 * cut) as usize).min(sorted.len() - 1)];
        let side = |low: bool| {
            let mut half = Mask::new(part.width(), part.height());
            for &(x, y) in &pixels {
                if (along(x, y) < at) == low {
                    half.set(x, y);
                }
            }
            let h = half.moments();
            h.centroid()
                .filter(|_| h.count >= SPLIT_LEAST)
                .map(|hc| (hc, h.count))
        };
        if let (Some(low), Some(high)) = (side(true), side(false)) {
            out.push([low, high]);
        }
    }
    out
}

/// A body whose shadow adds fewer target pixels than this fraction of its area is
/// hidden ([`Seats::hidden`]).
pub(super) const HIDDEN: f64 = 0.25;
/// Hidden bodies split in with another, at most.
pub(super) const SPLIT_HIDDEN: usize = 2;
/// Where [`Seats::splits`] cuts a part along its long axis (fractions of its pixels).
pub(super) const SPLIT_CUTS: [f64; 3] = [1.0 / 3.0, 0.5, 2.0 / 3.0];
/// Bodies a hidden body is split in with: those with the most wrong pixels around
/// their shadows.
pub(super) const SPLIT_PARTNERS: usize = 3;
/// Pixels a side of a cut holds at least.
const SPLIT_LEAST: f64 = 16.0;
/// Splits that [`improve`](super::improve) refines, those whose scans draw the best
/// pictures.
pub(super) const SPLITS: usize = 4;

/// Trades of blocks that [`improve`](super::improve) refines ([`Seats::trade_scan`]),
/// those ranked best by the table of seats. The table ranks a trade by seats made one
/// at a time over the picture without their two blocks, so a trade whose seats share a
/// cluster of overlapping shadows is ranked off: on the planted boxes 11504 the trade
/// that mends it (a long block end-on in a cluster, a short one stretched over a long
/// block's part) is the fifth, and on boxes12 11505 it lies beyond the twelfth. Refining the best
/// 30 raised those two from 0.9631 and 0.9698 to 0.9733 and 0.9833 (and boxes12 11405
/// from 0.9629 to 0.9693) and changed none of the other 39 problems with blocks of the
/// draws 11400 and 11500 (`git show c030f18:docs/results.md`, "More trades of blocks refined"); 80 found
/// nothing more.
pub(super) const TRADES: usize = 30;

/// Trades of meshes that [`improve`](super::improve) seats and offers: the table's ranks
/// say little of them (a piece's scanned shadow is off by hundreds of pixels), so many
/// of its trades (six pieces of six shapes make 409 cycles, 15 pairs and 40 three-cycles
/// of them).
pub(super) const MESH_TRADES: usize = 40;

/// The blocks in a trade at most: pairs and cycles of three. A trade of blocks is judged
/// as seated, without the runs that search a trade of meshes, and the table ranks it by
/// adding one estimate per block. With cycles of four, the planted boxes12 problems of
/// seeds 14300 and 14400 (plant route) fell in 6 of 14 and rose in 2 (the lowest from
/// 0.9592 to 0.9153 and from 0.9758 to 0.9682); the boxes problems of the same seeds
/// rose in 2 of 14 (by 0.0008 and 0.0065). The meshes, six at most
/// ([`MAX_MESH_TRADES`](super::sight::MAX_MESH_TRADES)), trade in cycles of any length.
pub(super) const BLOCK_CYCLE: usize = 3;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycles_come_each_once_from_their_lowest_and_after_the_pair_they_extend() {
        let all = |n, longest, linked: &dyn Fn(usize, usize) -> bool| {
            let mut seen: Vec<Vec<usize>> = Vec::new();
            cycles(n, longest, linked, &mut |c| seen.push(c.to_vec()));
            seen
        };
        let any = |_: usize, _: usize| true;
        // Six of six shapes: 15 pairs, 40 cycles of three, 90 of four, 144 of five, 120
        // of six; up to three, in the order of a table of pairs and three-cycles.
        assert_eq!(all(6, 6, &any).len(), 409);
        let short = all(6, 3, &any);
        let mut table = Vec::new();
        for a in 0..6 {
            for b in a + 1..6 {
                table.push(vec![a, b]);
                for c in (a + 1..6).filter(|&c| c != b) {
                    table.push(vec![a, b, c]);
                }
            }
        }
        assert_eq!(short, table);
        // No step that `linked` forbids: two kinds alternate.
        let alternate = |a: usize, b: usize| a % 2 != b % 2;
        let found = all(6, 6, &alternate);
        assert!(found
            .iter()
            .all(|c| c.windows(2).all(|w| w[0] % 2 != w[1] % 2)));
        assert_eq!(found.iter().filter(|c| c.len() == 2).count(), 9);
    }

    #[test]
    fn a_part_is_cut_across_its_long_axis_at_fractions_of_its_pixels() {
        // A bar 40 pixels long and 10 wide, lying along x, then standing along y.
        for lying in [true, false] {
            let part = Mask::from_fn(64, 64, |x, y| {
                let (u, v) = if lying { (x, y) } else { (y, x) };
                (10..50).contains(&u) && (20..30).contains(&v)
            });
            let cuts = cut_across(&part, &[0.25, 0.5]);
            assert_eq!(cuts.len(), 2);
            for ([(low, a_low), (high, a_high)], share) in cuts.into_iter().zip([0.25, 0.5]) {
                assert_eq!(a_low + a_high, 400.0);
                assert!((a_low - 400.0 * share).abs() <= 10.0, "{a_low} for {share}");
                // Each side's centroid lies on the bar's centre line, in its own half.
                let (along_low, across_low) = if lying {
                    (low.x, low.y)
                } else {
                    (low.y, low.x)
                };
                let (along_high, across_high) = if lying {
                    (high.x, high.y)
                } else {
                    (high.y, high.x)
                };
                assert!((across_low - across_high).abs() < 1e-9);
                let end = 10.0 + 40.0 * share;
                assert!((along_low - (10.0 + end) / 2.0).abs() < 1.0, "{along_low}");
                assert!(
                    (along_high - (end + 50.0) / 2.0).abs() < 1.0,
                    "{along_high}"
                );
            }
        }
        // A side under the least pixels is no place: a cut at the bar's very end.
        let bar = Mask::from_fn(64, 64, |x, y| {
            (10..50).contains(&x) && (20..30).contains(&y)
        });
        assert!(cut_across(&bar, &[0.01]).is_empty());
    }
}
