//! The cover's second look: the greedy's placements improved once all are down
//! ([`Cover::polish`]: each refined against the others; [`Cover::exchange`]: objects
//! of different shapes on each other's places; [`Cover::replace`]: every object placed
//! anew on what the others leave).

use super::*;

impl Cover<'_> {
    /// Undo the greedy's short sight: `rounds` times, each placement in turn is lifted
    /// off and refined (pattern search from where it is) against all the others. An
    /// early placement can then give up what a later one covers better (a wide shadow
    /// over a junction, say). A placement's height rule is kept against the others.
    pub fn polish(&mut self, rounds: usize) {
        for _ in 0..rounds {
            for k in 0..self.placements.len() {
                self.redraw(Some(k));
                let p = self.placements[k].clone();
                let lifted = self.lift_heights(&[k]);
                let c = Candidate {
                    centre: p.centre,
                    theta: p.theta,
                    m: p.m,
                    alpha: p.alpha,
                };
                let (gain, c) = self.refine(&self.families[k].clone(), c);
                self.put_back(lifted);
                if gain.is_finite() {
                    let pose = self.families[k].pose(c.alpha);
                    self.placements[k] = self.placement(p.object, p.family, &pose, c, gain);
                    self.heights[k] = (self.frame.height(c.m), pose.half_height);
                }
            }
        }
        self.redraw(None);
    }

    /// Undo the greedy's other short sight, which object goes where: for every two
    /// placements of objects of different shapes (`same` tells those an exchange cannot
    /// improve), each object is tried on the other's place (every pose family and roll of
    /// its own, the other's direction either way round, the magnification that gives the
    /// other's area, then refined) and the exchange is kept when the two gain more
    /// together.
    /// Largest first, the greedy gives the largest object the place it covers best at
    /// any magnification, which is often a smaller object's place (a king on the
    /// queen's silhouette). `families[k]` are placement `k`'s object's pose families.
    /// Returns the exchanges made.
    pub fn exchange(
        &mut self,
        families: &[Vec<Family>],
        same: &dyn Fn(usize, usize) -> bool,
    ) -> usize {
        let n = self.placements.len();
        let mut made = 0;
        for a in 0..n {
            for b in a + 1..n {
                if same(a, b) {
                    continue;
                }
                self.show(a, false);
                self.show(b, false);
                let now = self.pair_gain(a, b);
                let saved = [a, b].map(|k| {
                    (
                        self.placements[k].clone(),
                        self.families[k].clone(),
                        self.heights[k],
                    )
                });
                let old_a = self.placements[a].clone();
                let mut kept = false;
                if let Some((pa, fa)) = self.placed_on(a, &families[a], b) {
                    let gain_a = pa.gain;
                    self.set(a, pa, fa);
                    self.show(a, true);
                    // `b` is off the picture while it looks for its new place.
                    let lifted = self.lift_heights(&[b]);
                    let found = self.placed_at(b, &families[b], &old_a);
                    self.put_back(lifted);
                    if let Some((pb, fb)) = found {
                        if gain_a + pb.gain > now + 1e-6 {
                            self.set(b, pb, fb);
                            kept = true;
                            made += 1;
                        }
                    }
                    if !kept {
                        self.show(a, false);
                    }
                }
                if kept {
                    self.show(b, true);
                } else {
                    for (k, (p, f, h)) in [a, b].into_iter().zip(saved) {
                        (self.placements[k], self.families[k], self.heights[k]) = (p, f, h);
                    }
                    self.show(a, true);
                    self.show(b, true);
                }
            }
        }
        made
    }

    /// Undo the greedy's third short sight, where each object went at all: each
    /// placement in turn is lifted off and its object placed anew anywhere on what the
    /// others leave (the same search as the greedy's, [`Cover::best`]), and the new
    /// placement is kept when it gains more than the old one there. The greedy and the
    /// exchanges can leave a part bare while two objects share another: lifted off, one
    /// of them gains more on the bare part than on the shared one. `families[k]` are
    /// placement `k`'s object's pose families. Returns the placements moved.
    pub fn replace(&mut self, families: &[Vec<Family>]) -> usize {
        let mut made = 0;
        for (k, fams) in families.iter().enumerate().take(self.placements.len()) {
            self.redraw(Some(k));
            let lifted = self.lift_heights(&[k]);
            let now = self.gain_of(k).unwrap_or(f64::NEG_INFINITY);
            let found = self.best(self.placements[k].object, fams);
            self.put_back(lifted);
            if let Some(p) = found {
                if p.gain > now + 1e-6 {
                    let family = fams[p.family].clone();
                    self.set(k, p, family);
                    made += 1;
                }
            }
        }
        self.redraw(None);
        made
    }

    /// Placement `k` becomes `p` (its object kept) in pose family `family`.
    fn set(&mut self, k: usize, p: Placement, family: Family) {
        let pose = family.pose(p.alpha);
        self.heights[k] = (self.frame.height(p.m), pose.half_height);
        self.placements[k] = Placement {
            object: self.placements[k].object,
            ..p
        };
        self.families[k] = family;
    }

    /// The gain of placements `a` and `b` together, on the picture covered by all the
    /// others (a first, then b on what a leaves); the maps are drawn without `a` and `b`,
    /// and left so.
    fn pair_gain(&mut self, a: usize, b: usize) -> f64 {
        let lifted = self.lift_heights(&[a, b]);
        let ga = self.gain_of(a);
        self.show(a, true);
        // `b` is placed against `a` as it stands: `a`'s height counts again.
        self.heights[a] = lifted[0].1;
        let gb = self.gain_of(b);
        self.show(a, false);
        self.put_back(lifted);
        match (ga, gb) {
            (Some(x), Some(y)) => x + y,
            _ => f64::NEG_INFINITY,
        }
    }

    /// The gain of placement `k` as it stands, on the maps as they are.
    fn gain_of(&self, k: usize) -> Option<f64> {
        let p = &self.placements[k];
        let pose = self.families[k].pose(p.alpha);
        let c = Candidate {
            centre: p.centre,
            theta: p.theta,
            m: p.m,
            alpha: p.alpha,
        };
        self.score(&pose.outline.samples(FINE_SAMPLES), &c, pose.half_height)
    }

    /// Object `k` (with its pose `families`) placed where placement `on` is, on the maps
    /// drawn without `k` and `on`, neither of which constrains its height. Returns the
    /// placement and its family; the maps are not changed.
    fn placed_on(
        &mut self,
        k: usize,
        families: &[Family],
        on: usize,
    ) -> Option<(Placement, Family)> {
        let target = self.placements[on].clone();
        let lifted = self.lift_heights(&[k, on]);
        let found = self.placed_at(k, families, &target);
        self.put_back(lifted);
        found
    }

    /// The best placement of object `k` (with its pose `families`) at `spot`'s place:
    /// started from every family and roll, `spot`'s direction either way round and the
    /// magnification of `spot`'s area, the best start refined. The maps are not changed.
    fn placed_at(
        &self,
        k: usize,
        families: &[Family],
        spot: &Placement,
    ) -> Option<(Placement, Family)> {
        let mpp = self.frame.metres_per_px;
        let mut starts: Vec<(f64, usize, Candidate)> = Vec::new();
        for (fi, fam) in families.iter().enumerate() {
            for alpha in fam.alphas() {
                let pose = fam.pose(alpha);
                let area = pose.outline.area();
                if area <= 0.0 {
                    continue;
                }
                let m = (spot.area / area).sqrt() * mpp;
                let m = m.clamp(self.frame.m_lo, self.frame.m_hi);
                let samples = pose.outline.samples(COARSE_SAMPLES);
                for turn in [0.0, std::f64::consts::PI] {
                    let c = Candidate {
                        centre: spot.centre,
                        theta: spot.theta + turn,
                        m,
                        alpha,
                    };
                    if let Some(g) = self.score(&samples, &c, pose.half_height) {
                        starts.push((g, fi, c));
                    }
                }
            }
        }
        starts.sort_by(|x, y| y.0.total_cmp(&x.0));
        let mut best: Option<(f64, usize, Candidate)> = None;
        for &(_, fi, c) in starts.iter().take(2) {
            let (g, c) = self.refine(&families[fi], c);
            if g.is_finite() && best.as_ref().is_none_or(|b| g > b.0) {
                best = Some((g, fi, c));
            }
        }
        let (gain, fi, c) = best?;
        let pose = families[fi].pose(c.alpha);
        Some((self.placement(k, fi, &pose, c, gain), families[fi].clone()))
    }
}
