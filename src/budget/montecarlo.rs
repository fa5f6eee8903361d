//! The Monte Carlo machinery: [`Budget`] (a solution's vacuum launch, poses at `t` and
//! drag model per body), the seeded per-sample launch errors ([`BodyError`]), the
//! compensated launch in air and the IoU statistics ([`IouStats`]).

use super::*;

/// A solution's launch with its drag model.
pub struct Budget<'a> {
    pub problem: &'a Problem,
    /// Whether the bodies fly through air (else the exact parabola, as the solver's).
    pub air: bool,
    pub drag: DragConfig,
    /// Drag coefficients of every occluder.
    pub bodies: Vec<BodyDrag>,
    /// The vacuum launch (6 values per occluder).
    pub vacuum: Vec<f64>,
    /// Vacuum pose (origin, orientation) and centre of mass of every occluder at `t`.
    pub vacuum_pose: Vec<(DVec3, DQuat)>,
    pub vacuum_com: Vec<DVec3>,
    /// Landing time in the vacuum solution, if the body lands before `t`.
    pub landed: Vec<Option<f64>>,
    /// IoU at `t` in vacuum.
    pub vacuum_iou: f64,
}

/// Drag flights flown together in one batch (a multiple of four, the width of
/// [`drag::fly_each`]).
const MAX_BATCH: usize = 16;

/// Per-thread buffers of the budget.
pub struct BudgetWorkspace {
    pub(super) ws: Workspace,
    flight: FreeFlight,
    /// Per body, the last centre of mass with drag and the last orientation at `t`,
    /// with the bits of the inputs they were computed from. In a search over one error
    /// alone most bodies' other half does not change from sample to sample (a speed
    /// error leaves the spin, a spin error the drag flight), and a match gives the same
    /// bits as computing again.
    last_com: Vec<Option<([u64; 11], DVec3)>>,
    last_q: Vec<Option<([u64; 8], DQuat)>>,
    /// The drag flights a sample still has to fly, their bodies and results.
    flights: Vec<drag::Flight>,
    flown: Vec<usize>,
    flown_to: Vec<(DVec3, DVec3)>,
}

/// Statistics of a set of IoUs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IouStats {
    pub samples: usize,
    pub mean: f64,
    /// 5th percentile (linear interpolation between order statistics).
    pub p5: f64,
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// Fraction of samples with IoU >= the threshold ([`BudgetReport::iou_threshold`]).
    pub p_iou_at_least_threshold: f64,
    /// Samples whose flight diverged (counted with IoU 0).
    pub diverged: usize,
}

pub(super) fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = (sorted.len() - 1) as f64 * p;
    let i = h.floor() as usize;
    let j = (i + 1).min(sorted.len() - 1);
    sorted[i] + (h - i as f64) * (sorted[j] - sorted[i])
}

impl IouStats {
    /// Statistics of `ious`, counting those `>= threshold` as successes.
    pub fn new(ious: &[f64], diverged: usize, threshold: f64) -> IouStats {
        let mut s = ious.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len().max(1) as f64;
        IouStats {
            samples: ious.len(),
            mean: ious.iter().sum::<f64>() / n,
            p5: quantile(&s, 0.05),
            median: quantile(&s, 0.5),
            min: s.first().copied().unwrap_or(f64::NAN),
            max: s.last().copied().unwrap_or(f64::NAN),
            p_iou_at_least_threshold: ious.iter().filter(|&&x| x >= threshold).count() as f64 / n,
            diverged,
        }
    }
}

/// A progress sink for the long phases (the CLI draws a bar; `()` ignores it).
pub trait Progress: Sync {
    fn start(&self, _phase: &str, _total: u64) {}
    fn advance(&self, _n: u64) {}
    fn finish(&self) {}
}
impl Progress for () {}

impl<'a> Budget<'a> {
    /// The budget of launch values `params` (6 per occluder) in `problem`.
    pub fn new(
        problem: &'a Problem,
        params: &[f64],
        drag: DragConfig,
    ) -> Result<Budget<'a>, BudgetError> {
        drag.validate()?;
        let scene = &problem.scene;
        if params.len() != scene.variable_count() {
            return Err(BudgetError::Parameters {
                expected: scene.variable_count(),
                found: params.len(),
            });
        }
        let bodies = scene
            .occluders
            .iter()
            .map(|o| BodyDrag::new(&o.shape, o.mass.mass, &drag))
            .collect();
        let mut ws = problem.workspace();
        problem.fly(params, &mut ws);
        let n = scene.occluders.len();
        let vacuum_pose = ws.poses.clone();
        let vacuum_com = (0..n)
            .map(|i| vacuum_pose[i].0 + vacuum_pose[i].1 * scene.occluders[i].mass.local_com)
            .collect();
        let landed = (0..n).map(|i| ws.landing_time(i)).collect();
        problem.shadow(&mut ws);
        let vacuum_iou = energy::iou(&ws.mask, &problem.target.mask);
        Ok(Budget {
            problem,
            air: true,
            drag,
            bodies,
            vacuum: params.to_vec(),
            vacuum_pose,
            vacuum_com,
            landed,
            vacuum_iou,
        })
    }

    /// The budget of launch values `params` flown in a vacuum, as the solver flies them:
    /// the launcher's errors alone.
    pub fn vacuum(problem: &'a Problem, params: &[f64]) -> Result<Budget<'a>, BudgetError> {
        Ok(Budget {
            air: false,
            ..Budget::new(problem, params, DragConfig::default())?
        })
    }

    pub fn workspace(&self) -> BudgetWorkspace {
        let n = self.problem.scene.occluders.len();
        BudgetWorkspace {
            ws: self.problem.workspace(),
            flight: FreeFlight::default(),
            last_com: vec![None; n],
            last_q: vec![None; n],
            flights: Vec::with_capacity(n),
            flown: Vec::with_capacity(n),
            flown_to: Vec::with_capacity(n),
        }
    }

    /// Centre of mass at `t` of occluder `i` launched with `v`, `w` through air, with
    /// errors `e`; its orientation at `t` too when `flight` is given.
    fn pose(
        &self,
        i: usize,
        v: DVec3,
        w: DVec3,
        e: &BodyError,
        flight: Option<&mut FreeFlight>,
    ) -> (DVec3, DQuat) {
        let Some((s, tau)) = self.perturbed(i, v, w, e) else {
            return (DVec3::NAN, DQuat::NAN);
        };
        let com = self.drag_com_of(i, &s, e.cd, tau);
        let q = flight.map_or(DQuat::IDENTITY, |f| self.orientation_of(i, &s, tau, f));
        (com, q)
    }

    /// The launch occluder `i` gets when asked for `v`, `w` with errors `e`, and its
    /// flight time; `None` for a launch no flight can follow.
    fn perturbed(&self, i: usize, v: DVec3, w: DVec3, e: &BodyError) -> Option<(LaunchState, f64)> {
        let scene = &self.problem.scene;
        let asked = Launch {
            velocity: v,
            angular_velocity: w,
        };
        let s = e.apply(LaunchState::of(&scene.occluders[i], asked));
        let tau = scene.t - e.timing;
        let w = s.angular_velocity;
        (s.velocity.is_finite() && w.is_finite() && w.length() * scene.t <= MAX_TURN)
            .then_some((s, tau))
    }

    /// Occluder `i`'s centre of mass at launch `s`.
    fn launch_com(&self, i: usize, s: &LaunchState) -> DVec3 {
        s.origin + s.orientation * self.problem.scene.occluders[i].mass.local_com
    }

    /// Occluder `i`'s drag model with its drag coefficient off by the factor
    /// `1 + cd_error`.
    fn body_with_cd(&self, i: usize, cd_error: f64) -> BodyDrag {
        if cd_error != 0.0 {
            self.bodies[i].with_cd_factor(1.0 + cd_error)
        } else {
            self.bodies[i]
        }
    }

    /// Fly the drag flights queued in `bws` together and keep their centres of mass in
    /// its memo under `keys`.
    fn fly_batch(&self, bws: &mut BudgetWorkspace, keys: &[[u64; 11]; MAX_BATCH]) {
        bws.flown_to.clear();
        bws.flown_to
            .resize(bws.flights.len(), (DVec3::ZERO, DVec3::ZERO));
        let scene = &self.problem.scene;
        drag::fly_each(
            &bws.flights,
            scene.gravity,
            self.drag.max_step,
            &mut bws.flown_to,
        );
        for (k, &i) in bws.flown.iter().enumerate() {
            bws.last_com[i] = Some((keys[k], bws.flown_to[k].0));
        }
        bws.flights.clear();
        bws.flown.clear();
    }

    /// Centre of mass with drag of occluder `i` after `tau` from launch `s`, its drag
    /// coefficient off by the factor `1 + cd_error`.
    fn drag_com_of(&self, i: usize, s: &LaunchState, cd_error: f64, tau: f64) -> DVec3 {
        let scene = &self.problem.scene;
        if !self.air {
            return self.launch_com(i, s) + s.velocity * tau + scene.gravity * (0.5 * tau * tau);
        }
        let body = self.body_with_cd(i, cd_error);
        drag::fly(
            &body,
            self.launch_com(i, s),
            s.velocity,
            s.angular_velocity,
            scene.gravity,
            tau,
            self.drag.max_step,
        )
        .0
    }

    /// Orientation of occluder `i` after `tau` from launch `s` (drag exerts no torque in
    /// the model, so it is the torque-free one).
    fn orientation_of(&self, i: usize, s: &LaunchState, tau: f64, f: &mut FreeFlight) -> DQuat {
        let scene = &self.problem.scene;
        let o = &scene.occluders[i];
        f.reset(
            &o.mass,
            LaunchState {
                velocity: DVec3::ZERO,
                ..*s
            },
            scene.gravity,
            tau.max(scene.t),
            &self.problem.flight,
        );
        f.orientation(tau)
    }

    /// Drag poses at `t` of every occluder for launch `params` with errors `errors`
    /// (one per occluder) into the workspace, then the shadow and its IoU. Returns
    /// `(IoU, diverged)`; a diverged flight has IoU 0.
    pub fn iou(
        &self,
        params: &[f64],
        errors: &[BodyError],
        bws: &mut BudgetWorkspace,
    ) -> (f64, bool) {
        let scene = &self.problem.scene;
        let bits = |x: DVec3| x.to_array().map(f64::to_bits);
        // First the drag flights that the memo does not hold, flown together; then the
        // orientations; then the poses.
        bws.flights.clear();
        bws.flown.clear();
        let mut keys = [[0u64; 11]; MAX_BATCH];
        for (i, o) in scene.occluders.iter().enumerate() {
            if !o.launched {
                continue;
            }
            let Launch {
                velocity: v,
                angular_velocity: w,
            } = Launch::get(params, i);
            let e = &errors[i];
            let Some((s, tau)) = self.perturbed(i, v, w, e) else {
                return (0.0, true);
            };
            let (v, w, com0) = (s.velocity, s.angular_velocity, self.launch_com(i, &s));
            // The drag flight reads the spin only through the Magnus lift.
            let wb = if self.bodies[i].magnus_radius.is_some() {
                bits(w)
            } else {
                [0; 3]
            };
            let (vb, cb) = (bits(v), bits(com0));
            let key = [
                vb[0],
                vb[1],
                vb[2],
                wb[0],
                wb[1],
                wb[2],
                tau.to_bits(),
                e.cd.to_bits(),
                cb[0],
                cb[1],
                cb[2],
            ];
            if !self.air {
                bws.last_com[i] = Some((key, self.drag_com_of(i, &s, e.cd, tau)));
            } else if bws.last_com[i].is_none_or(|(k, _)| k != key) {
                if bws.flown.len() == MAX_BATCH {
                    self.fly_batch(bws, &keys);
                }
                keys[bws.flown.len()] = key;
                bws.flown.push(i);
                bws.flights.push(drag::Flight {
                    body: self.body_with_cd(i, e.cd),
                    x0: com0,
                    v0: v,
                    w,
                    duration: tau,
                });
            }
            let (wb, qb) = (bits(w), s.orientation.to_array().map(f64::to_bits));
            let q_key = [
                wb[0],
                wb[1],
                wb[2],
                tau.to_bits(),
                qb[0],
                qb[1],
                qb[2],
                qb[3],
            ];
            if bws.last_q[i].is_none_or(|(k, _)| k != q_key) {
                let q = self.orientation_of(i, &s, tau, &mut bws.flight);
                bws.last_q[i] = Some((q_key, q));
            }
        }
        self.fly_batch(bws, &keys);
        for (i, o) in scene.occluders.iter().enumerate() {
            if !o.launched {
                bws.ws.poses[i] = (o.position, o.orientation);
                continue;
            }
            let (com, q) = match (bws.last_com[i], bws.last_q[i]) {
                (Some((_, com)), Some((_, q))) => (com, q),
                _ => unreachable!("every launched body was flown above"),
            };
            if !(com.is_finite() && q.is_finite()) {
                return (0.0, true);
            }
            bws.ws.poses[i] = (com - q * o.mass.local_com, q);
        }
        self.problem.shadow(&mut bws.ws);
        (energy::iou(&bws.ws.mask, &self.problem.target.mask), false)
    }

    /// Centre of mass with drag at `t` of occluder `i` for launch `params`.
    pub fn drag_com(&self, params: &[f64], i: usize, e: &BodyError) -> DVec3 {
        let o = &self.problem.scene.occluders[i];
        if !o.launched {
            return o.launch_com();
        }
        let Launch {
            velocity: v,
            angular_velocity: w,
        } = Launch::get(params, i);
        self.pose(i, v, w, e, None).0
    }

    /// Orientation with drag at `t` of occluder `i` (drag exerts no torque in the model).
    pub fn drag_orientation(&self, params: &[f64], i: usize) -> DQuat {
        let o = &self.problem.scene.occluders[i];
        if !o.launched {
            return o.orientation;
        }
        let Launch {
            velocity: v,
            angular_velocity: w,
        } = Launch::get(params, i);
        let mut f = FreeFlight::default();
        self.pose(i, v, w, &BodyError::default(), Some(&mut f)).1
    }

    /// Launch velocity of occluder `i` that brings its centre of mass with drag to its
    /// vacuum position at `t`: Newton on the 3 velocity components with a central
    /// finite-difference Jacobian and step halving. Returns (velocity, iterations,
    /// residual in m).
    pub fn compensate_body(&self, i: usize) -> (DVec3, usize, f64) {
        let scene = &self.problem.scene;
        let o = &scene.occluders[i];
        let Launch {
            velocity: v_vac,
            angular_velocity: w,
        } = Launch::get(&self.vacuum, i);
        if !o.launched {
            return (DVec3::ZERO, 0, 0.0);
        }
        let target = self.vacuum_com[i];
        let e = BodyError::default();
        let f = |v: DVec3| self.pose(i, v, w, &e, None).0 - target;
        let mut v = v_vac;
        let mut r = f(v);
        // A first guess: make up the shortfall evenly over the flight.
        let guess = v - r / scene.t;
        let rg = f(guess);
        if rg.length() < r.length() {
            v = guess;
            r = rg;
        }
        let mut it = 0;
        while it < MAX_NEWTON && r.length() > NEWTON_TOL && r.is_finite() {
            it += 1;
            let h = 1e-6 * (1.0 + v.length());
            let mut cols = [DVec3::ZERO; 3];
            for (j, c) in cols.iter_mut().enumerate() {
                let mut d = DVec3::ZERO;
                d[j] = h;
                *c = (f(v + d) - f(v - d)) / (2.0 * h);
            }
            let jac = DMat3::from_cols(cols[0], cols[1], cols[2]);
            let dv = -(jac.inverse() * r);
            if !dv.is_finite() {
                break;
            }
            let mut lambda = 1.0;
            let mut improved = false;
            while lambda > 1e-6 {
                let vn = v + dv * lambda;
                let rn = f(vn);
                if rn.length() < r.length() {
                    v = vn;
                    r = rn;
                    improved = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !improved {
                break;
            }
        }
        (v, it, r.length())
    }

    /// The compensated launch (6 values per occluder; spins unchanged), with per-body
    /// Newton iterations and residuals.
    pub fn compensate(&self) -> (Vec<f64>, Vec<(usize, f64)>) {
        let mut params = self.vacuum.clone();
        let mut info = Vec::new();
        for i in 0..self.problem.scene.occluders.len() {
            let (v, it, res) = self.compensate_body(i);
            if self.problem.scene.occluders[i].launched {
                Launch {
                    velocity: v,
                    ..Launch::get(&params, i)
                }
                .set(&mut params, i);
            }
            info.push((it, res));
        }
        (params, info)
    }

    /// IoUs of `n` Monte Carlo samples of launch `params` at tolerances `tol`, in sample
    /// order, with the diverged count.
    pub fn monte_carlo(
        &self,
        params: &[f64],
        tol: &Tolerances,
        n: usize,
        seed: u64,
        pool: &rayon::ThreadPool,
        progress: &dyn Progress,
    ) -> (Vec<f64>, usize) {
        let out = if tol.is_zero() {
            // Without errors every sample is the exact compensated launch (a zero
            // tolerance draws zero errors, and a zero error changes no bit): one will do.
            let one = self.samples(params, tol, 0..n.min(1), seed, pool, &());
            progress.advance(n as u64);
            vec![one.first().copied().unwrap_or((0.0, false)); n]
        } else {
            let out = self.samples(params, tol, 0..n, seed, pool, progress);
            progress.advance(n as u64 % 64);
            out
        };
        let diverged = out.iter().filter(|r| r.1).count();
        (out.into_iter().map(|r| r.0).collect(), diverged)
    }

    /// Whether `P(IoU >= threshold) >= PROBABILITY_TARGET` over the `n` samples of
    /// [`Budget::monte_carlo`]: the same answer as counting them all, but the samples are
    /// taken a chunk at a time and the count stops as soon as it is decided (enough
    /// successes, or too many failures), which is most of the time in a tolerance search.
    pub fn reaches(
        &self,
        params: &[f64],
        tol: &Tolerances,
        n: usize,
        seed: u64,
        threshold: f64,
        pool: &rayon::ThreadPool,
    ) -> bool {
        /// Samples taken between two looks at the count: few, so that a launcher that
        /// fails stops soon after its `n - needed + 1`-th miss (13 of 128). Each draw
        /// comes from its own index, so the answer is the same for any chunk; 16 against
        /// 128 took THE THINKER's launcher needs from 1.12 to 0.87 s.
        const CHUNK: usize = 16;
        // The least number of successes whose fraction reaches the target, as IouStats
        // computes the fraction.
        let Some(needed) = (0..=n).find(|&c| c as f64 / n.max(1) as f64 >= PROBABILITY_TARGET)
        else {
            return false;
        };
        if tol.is_zero() {
            let (ious, _) = self.monte_carlo(params, tol, n.min(1), seed, pool, &());
            let each = ious.first().is_some_and(|&x| x >= threshold);
            return if each { n >= needed } else { needed == 0 };
        }
        let (mut yes, mut no) = (0, 0);
        let mut start = 0;
        loop {
            if yes >= needed {
                return true;
            }
            if no > n - needed || start >= n {
                return false;
            }
            let end = (start + CHUNK).min(n);
            for (iou, _) in self.samples(params, tol, start..end, seed, pool, &()) {
                if iou >= threshold {
                    yes += 1;
                } else {
                    no += 1;
                }
            }
            start = end;
        }
    }

    /// (IoU, diverged) of the samples `range`, in sample order.
    fn samples(
        &self,
        params: &[f64],
        tol: &Tolerances,
        range: std::ops::Range<usize>,
        seed: u64,
        pool: &rayon::ThreadPool,
        progress: &dyn Progress,
    ) -> Vec<(f64, bool)> {
        let nb = self.problem.scene.occluders.len();
        let done = AtomicU64::new(0);
        pool.install(|| {
            range
                .into_par_iter()
                .map_init(
                    || (self.workspace(), vec![BodyError::default(); nb]),
                    |(bws, errs), k| {
                        draw_errors(seed, k as u64, tol, errs);
                        let r = self.iou(params, errs, bws);
                        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                        if d.is_multiple_of(64) {
                            progress.advance(64);
                        }
                        r
                    },
                )
                .collect()
        })
    }
}
