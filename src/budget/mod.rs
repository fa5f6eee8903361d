//! The error budget of a real launch: air drag and launcher errors.
//!
//! Main types: [`Budget`] (a solution's vacuum launch, its poses at `t`, and the drag
//! model of every body), [`BudgetOptions`], [`Tolerances`] (1-sigma launch errors),
//! [`BudgetReport`] (what `budget.json` holds) and [`BudgetRun`] (the report plus the
//! compensated launch and the Monte Carlo IoUs). [`run`] does everything:
//!
//! 1. **Re-simulation with drag** ([`crate::sim::drag`]): every launched body's centre of mass
//!    is flown from its vacuum launch state through air; its orientation stays the exact
//!    torque-free one (drag torque is neglected, so the orientation error at `t` is zero
//!    by construction and is reported as such). The shadow at `t` is the project's exact
//!    rasterizer ([`Problem::shadow`]) at the drag poses; IoU against the target.
//! 2. **Compensation**: per body, Newton's method on the 3 launch-velocity components
//!    (central finite-difference Jacobian, step halving) so that the centre of mass with
//!    drag reaches its vacuum position at `t` (to 1e-9 m). The spin is kept.
//! 3. **Monte Carlo** over the compensated launch, in air: per body independent normal
//!    errors of launch speed, direction (two perpendicular components), spin rate, release
//!    time and drag coefficient (the model error). Sample `k` draws from its own
//!    `ChaCha8Rng` seeded from `(seed, k)`, and results are collected in sample order, so
//!    the report is bit-identical whatever the thread count.
//! 4. **Sensitivities** per body by central finite differences (IoU lost and centre-of-
//!    mass shift per 1 % speed, 1 deg, 1 ms, 1 % spin, 1 % drag coefficient).
//! 5. **Tolerance search**: the largest size of each error alone, and the largest common
//!    scale of the requested tolerances, that keep `P(IoU >= threshold) >= 95 %`
//!    (bracketing then bisection; every evaluation uses the same random draws, so `P` is
//!    a deterministic, nearly monotone function of the size). The threshold is
//!    [`BudgetOptions::iou_threshold`] (default [`IOU_THRESHOLD`], 0.9). When the
//!    compensated launch without any error is already below it, no launcher precision
//!    reaches it: the search is skipped and the report says so ([`Unreachable`]).
//!
//! The numeric core does not fail: a sample whose flight diverges gets IoU 0 and is
//! counted in [`IouStats::diverged`]. Contacts are not modelled with drag; a body that
//! lands before `t` in the vacuum solution is flagged in the report.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DMat3, DQuat, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::Serialize;

use crate::energy::{self, Weights};
use crate::evaluate::{launch_velocities, Problem, Workspace, MAX_TURN};
use crate::geometry::shape::Shape;
use crate::output::solution::{check_solution, MismatchError, Solution};
use crate::sim::drag::{self, BodyDrag, DragConfig, DragError};
use crate::sim::flight::{FreeFlight, LaunchState};

/// The default IoU a shadow must reach to "read" as the picture
/// ([`BudgetOptions::iou_threshold`]).
pub const IOU_THRESHOLD: f64 = 0.9;
/// The probability of reaching the IoU threshold that the tolerance search keeps.
pub const PROBABILITY_TARGET: f64 = 0.95;
/// Largest number of Monte Carlo samples accepted.
pub const MAX_SAMPLES: usize = 10_000_000;
/// Bisection steps of the tolerance search after bracketing (precision 2^-8 of a factor 2).
const BISECTIONS: usize = 7;
/// Points of each tolerance curve (from 0 to twice the largest tolerance).
const CURVE_POINTS: usize = 7;
/// Newton iterations of the compensation.
const MAX_NEWTON: usize = 40;
/// Centre-of-mass residual at which the compensation stops (m).
const NEWTON_TOL: f64 = 1e-9;

/// Launch errors, each the standard deviation of a normal error (1 sigma), independent
/// per body.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Tolerances {
    /// Launch speed (% of the speed). Default 0.5 %.
    pub speed_pct: f64,
    /// Launch direction (deg), each of two perpendicular components. Default 0.25 deg.
    pub direction_deg: f64,
    /// Spin rate (% of the angular speed; the axis is kept). Default 2 %.
    pub spin_pct: f64,
    /// Release time (ms): a body released `dt` late has at `t` its pose at `t - dt`.
    /// Default 1 ms.
    pub timing_ms: f64,
    /// Drag coefficient (% of Cd): the model error. Default 5 %.
    pub cd_pct: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            speed_pct: 0.5,
            direction_deg: 0.25,
            spin_pct: 2.0,
            timing_ms: 1.0,
            cd_pct: 5.0,
        }
    }
}

/// The five error kinds: key, unit, largest accepted tolerance.
pub const PARAMETERS: [(&str, &str, f64); 5] = [
    ("speed", "%", 50.0),
    ("direction", "deg", 45.0),
    ("spin", "%", 100.0),
    ("timing", "ms", 100.0),
    ("cd", "%", 50.0),
];

impl Tolerances {
    pub fn to_array(&self) -> [f64; 5] {
        [
            self.speed_pct,
            self.direction_deg,
            self.spin_pct,
            self.timing_ms,
            self.cd_pct,
        ]
    }

    pub fn from_array(a: [f64; 5]) -> Tolerances {
        Tolerances {
            speed_pct: a[0],
            direction_deg: a[1],
            spin_pct: a[2],
            timing_ms: a[3],
            cd_pct: a[4],
        }
    }

    /// Every tolerance finite and within `[0, limit]` ([`PARAMETERS`]); the timing also
    /// below a third of `t`.
    pub fn validate(&self, t: f64) -> Result<(), BudgetError> {
        for (value, (name, unit, max)) in self.to_array().into_iter().zip(PARAMETERS) {
            let max = if name == "timing" {
                max.min(t * 1000.0 / 3.0)
            } else {
                max
            };
            if !(value.is_finite() && (0.0..=max).contains(&value)) {
                return Err(BudgetError::Tolerance {
                    name,
                    unit,
                    value,
                    max,
                });
            }
        }
        Ok(())
    }
}

/// How to run the budget.
#[derive(Clone, Debug, PartialEq)]
pub struct BudgetOptions {
    pub drag: DragConfig,
    pub tolerances: Tolerances,
    /// Monte Carlo samples at the requested tolerances. Default 10,000.
    pub samples: usize,
    /// Samples per evaluation of the tolerance search (0: no search). Default 2,000.
    pub search_samples: usize,
    pub seed: u64,
    /// Worker threads (None: one per core). Results do not depend on it.
    pub threads: Option<usize>,
    /// The IoU a sample must reach to count as a success, in `(0, 1]`. Default
    /// [`IOU_THRESHOLD`] (0.9).
    pub iou_threshold: f64,
}

impl Default for BudgetOptions {
    fn default() -> Self {
        BudgetOptions {
            drag: DragConfig::default(),
            tolerances: Tolerances::default(),
            samples: 10_000,
            search_samples: 2_000,
            seed: 1,
            threads: None,
            iou_threshold: IOU_THRESHOLD,
        }
    }
}

/// Why a budget cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum BudgetError {
    #[error(transparent)]
    Drag(#[from] DragError),
    #[error("the {name} tolerance must be between 0 and {max} {unit}, got {value}")]
    Tolerance {
        name: &'static str,
        unit: &'static str,
        value: f64,
        max: f64,
    },
    #[error("the number of {what} must be between {min} and {max}, got {value}")]
    Samples {
        what: &'static str,
        value: usize,
        min: usize,
        max: usize,
    },
    #[error("the number of threads must be at least 1")]
    Threads,
    #[error("the IoU threshold must be greater than 0 and at most 1, got {0}")]
    Threshold(f64),
    #[error("the launch values hold {found} numbers, the scene needs {expected}")]
    Parameters { expected: usize, found: usize },
    #[error(transparent)]
    Mismatch(#[from] MismatchError),
    #[error("the scene was edited after the solve: the solution's shadow at t now has IoU {now:.6} and {contacts_now} contacts, the solution recorded IoU {recorded:.6} and {contacts_recorded} (solve again, or pass the scene it was made for)")]
    Stale {
        recorded: f64,
        now: f64,
        contacts_recorded: u32,
        contacts_now: u32,
    },
}

/// Check that a saved solution belongs to this scene as it is now: names, counts and `t`
/// ([`check_solution`]), and the same IoU and contact count at `t` when
/// re-evaluated (an edit of the scene that changes the shadow shows up here).
pub fn check_solution_current(problem: &Problem, s: &Solution) -> Result<(), BudgetError> {
    check_solution(&problem.scene, s)?;
    let mut ws = problem.workspace();
    let e = problem.evaluate(&s.parameters(), &Weights::all_ones(), &mut ws);
    if (e.iou - s.iou).abs() > 1e-9 || e.outcome.n_contacts != s.n_contacts {
        return Err(BudgetError::Stale {
            recorded: s.iou,
            now: e.iou,
            contacts_recorded: s.n_contacts,
            contacts_now: e.outcome.n_contacts,
        });
    }
    Ok(())
}

/// The actual errors of one body in one sample (not tolerances): relative speed error,
/// direction error (rad, two perpendicular components), relative spin error, release
/// delay (s), relative drag-coefficient error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyError {
    pub speed: f64,
    pub direction: [f64; 2],
    pub spin: f64,
    pub timing: f64,
    pub cd: f64,
}

/// A solution's launch with its drag model.
pub struct Budget<'a> {
    pub problem: &'a Problem,
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

/// Per-thread buffers of the budget.
pub struct BudgetWorkspace {
    ws: Workspace,
    flight: FreeFlight,
}

/// Rotate `v` by the direction error `d` (rad) about two axes perpendicular to it: the
/// horizontal one (`v x z`, or `v x x` for a vertical `v`) and the one completing it.
fn aim(v: DVec3, d: [f64; 2]) -> DVec3 {
    if d == [0.0, 0.0] {
        return v;
    }
    let u = v.normalize_or_zero();
    if u == DVec3::ZERO {
        return v;
    }
    let mut e1 = u.cross(DVec3::Z);
    if e1.length_squared() < 1e-12 {
        e1 = u.cross(DVec3::X);
    }
    let e1 = e1.normalize();
    let e2 = u.cross(e1);
    DQuat::from_scaled_axis(e1 * d[0] + e2 * d[1]) * v
}

/// SplitMix64 of `(seed, k)`: the seed of sample `k`'s generator.
fn sample_seed(seed: u64, k: u64) -> u64 {
    let mut z = seed
        .wrapping_mul(0xD1B5_4A32_D192_ED03)
        .wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k.wrapping_add(1)));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The errors of sample `k`: six standard normals per body, always drawn in the same
/// order (so that every tolerance size sees the same draws), scaled by the tolerances.
fn draw_errors(seed: u64, k: u64, tol: &Tolerances, out: &mut [BodyError]) {
    let mut rng = ChaCha8Rng::seed_from_u64(sample_seed(seed, k));
    for e in out.iter_mut() {
        let mut z = [0.0f64; 6];
        for zi in &mut z {
            *zi = StandardNormal.sample(&mut rng);
        }
        *e = BodyError {
            speed: z[0] * tol.speed_pct / 100.0,
            direction: [
                (z[1] * tol.direction_deg).to_radians(),
                (z[2] * tol.direction_deg).to_radians(),
            ],
            spin: z[3] * tol.spin_pct / 100.0,
            timing: z[4] * tol.timing_ms / 1000.0,
            cd: z[5] * tol.cd_pct / 100.0,
        };
    }
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

fn quantile(sorted: &[f64], p: f64) -> f64 {
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
            drag,
            bodies,
            vacuum: params.to_vec(),
            vacuum_pose,
            vacuum_com,
            landed,
            vacuum_iou,
        })
    }

    pub fn workspace(&self) -> BudgetWorkspace {
        BudgetWorkspace {
            ws: self.problem.workspace(),
            flight: FreeFlight::default(),
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
        let scene = &self.problem.scene;
        let o = &scene.occluders[i];
        let v = aim(v, e.direction) * (1.0 + e.speed);
        let w = w * (1.0 + e.spin);
        let tau = scene.t - e.timing;
        if !(v.is_finite() && w.is_finite()) || w.length() * scene.t > MAX_TURN {
            return (DVec3::NAN, DQuat::NAN);
        }
        let body = if e.cd != 0.0 {
            self.bodies[i].with_cd_factor(1.0 + e.cd)
        } else {
            self.bodies[i]
        };
        let (com, _) = drag::fly(
            &body,
            o.launch_com(),
            v,
            w,
            scene.gravity,
            tau,
            self.drag.max_step,
        );
        let q = match flight {
            Some(f) => {
                f.reset(
                    &o.mass,
                    LaunchState {
                        origin: o.position,
                        orientation: o.orientation,
                        velocity: v,
                        angular_velocity: w,
                    },
                    scene.gravity,
                    tau.max(scene.t),
                    &self.problem.flight,
                );
                f.orientation(tau)
            }
            None => DQuat::IDENTITY,
        };
        (com, q)
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
        for (i, o) in scene.occluders.iter().enumerate() {
            if !o.launched {
                bws.ws.poses[i] = (o.position, o.orientation);
                continue;
            }
            let (v, w) = launch_velocities(params, i);
            let (com, q) = self.pose(i, v, w, &errors[i], Some(&mut bws.flight));
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
        let (v, w) = launch_velocities(params, i);
        self.pose(i, v, w, e, None).0
    }

    /// Orientation with drag at `t` of occluder `i` (drag exerts no torque in the model).
    pub fn drag_orientation(&self, params: &[f64], i: usize) -> DQuat {
        let o = &self.problem.scene.occluders[i];
        if !o.launched {
            return o.orientation;
        }
        let (v, w) = launch_velocities(params, i);
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
        let (v_vac, w) = launch_velocities(&self.vacuum, i);
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
                params[6 * i..6 * i + 3].copy_from_slice(&v.to_array());
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
        let nb = self.problem.scene.occluders.len();
        let done = AtomicU64::new(0);
        let out: Vec<(f64, bool)> = pool.install(|| {
            (0..n)
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
        });
        progress.advance(n as u64 % 64);
        let diverged = out.iter().filter(|r| r.1).count();
        (out.into_iter().map(|r| r.0).collect(), diverged)
    }
}

/// Everything `budget.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BudgetReport {
    pub scene: String,
    pub t_s: f64,
    pub seed: u64,
    pub drag: DragConfig,
    pub tolerances: Tolerances,
    /// The IoU a sample must reach ([`BudgetOptions::iou_threshold`]).
    pub iou_threshold: f64,
    pub probability_target: f64,
    /// Set when the exact compensated launch is already below the threshold (no launcher
    /// precision can reach it; the tolerance search is skipped); `null` otherwise.
    pub threshold_unreachable: Option<Unreachable>,
    pub iou_vacuum: f64,
    /// The vacuum launch flown through air.
    pub iou_drag_uncompensated: f64,
    /// The compensated launch flown through air.
    pub iou_drag_compensated: f64,
    pub occluders: Vec<OccluderReport>,
    /// Monte Carlo of the compensated launch in air at the requested tolerances.
    pub monte_carlo: IouStats,
    pub histogram: Histogram,
    pub sensitivity: Vec<Sensitivity>,
    pub search: Option<ToleranceSearch>,
    pub notes: Vec<String>,
}

/// Drag figures of one occluder.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OccluderReport {
    pub name: String,
    pub shape: String,
    pub launched: bool,
    pub mass_kg: f64,
    pub cd: f64,
    pub reference_area_m2: f64,
    /// `k = rho Cd A / (2 m)` (1/m).
    pub drag_k_per_m: f64,
    pub terminal_speed_m_s: f64,
    pub vacuum_com_at_t_m: [f64; 3],
    /// The vacuum launch flown through air.
    pub drag_com_at_t_m: [f64; 3],
    pub position_error_m: f64,
    /// Angle between the vacuum and drag orientations at `t`: 0 by construction (drag
    /// torque is neglected).
    pub orientation_error_rad: f64,
    pub vacuum_velocity_m_s: [f64; 3],
    pub compensated_velocity_m_s: [f64; 3],
    pub speed_change_pct: f64,
    /// Distance of the compensated launch's centre of mass at `t` from the vacuum one.
    pub compensated_com_error_m: f64,
    pub newton_iterations: usize,
    /// Landing time in the vacuum solution (the drag model has no contacts).
    pub lands_before_t_in_vacuum_s: Option<f64>,
}

/// IoU histogram of the Monte Carlo samples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Histogram {
    pub lo: f64,
    pub hi: f64,
    pub counts: Vec<usize>,
}

impl Histogram {
    fn new(values: &[f64], bins: usize) -> Histogram {
        let min = values.iter().copied().fold(1.0, f64::min);
        let lo = ((min * 20.0).floor() / 20.0).clamp(0.0, 0.95);
        let hi = 1.0;
        let mut counts = vec![0; bins];
        for &v in values {
            let b = ((v - lo) / (hi - lo) * bins as f64).floor();
            let b = (b.max(0.0) as usize).min(bins - 1);
            counts[b] += 1;
        }
        Histogram { lo, hi, counts }
    }
}

/// Finite-difference sensitivities of one occluder (the others exact), compensated
/// launch in air: IoU lost and centre-of-mass shift at `t` per unit error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sensitivity {
    pub name: String,
    pub iou_lost_per_pct_speed: f64,
    pub iou_lost_per_deg: f64,
    pub iou_lost_per_ms: f64,
    pub iou_lost_per_pct_spin: f64,
    pub iou_lost_per_pct_cd: f64,
    pub mm_per_pct_speed: f64,
    pub mm_per_deg: f64,
    pub mm_per_ms: f64,
    pub mm_per_pct_cd: f64,
}

/// One point of a tolerance curve.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CurvePoint {
    pub size: f64,
    pub mean: f64,
    pub p5: f64,
    pub p_iou_at_least_threshold: f64,
}

/// The largest size of one error alone.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SingleTolerance {
    pub parameter: String,
    pub unit: String,
    /// Largest 1-sigma size keeping P(IoU >= threshold) >= 95 % (the others zero).
    pub largest: f64,
    /// True when even the accepted limit keeps it (no limit found within range).
    pub at_limit: bool,
    pub curve: Vec<CurvePoint>,
}

/// The tolerance search.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToleranceSearch {
    pub samples_per_evaluation: usize,
    pub single: Vec<SingleTolerance>,
    /// Largest common factor on the requested tolerances keeping
    /// P(IoU >= threshold) >= 95 %.
    pub joint_scale: f64,
    pub joint_tolerances: Tolerances,
    pub joint_at_limit: bool,
}

/// Why the threshold cannot be reached: even the exact compensated launch is below it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unreachable {
    /// Which IoUs are below the threshold: `"vacuum"`, `"compensated"` or both.
    pub below: Vec<String>,
    /// A threshold the exact compensated launch does reach (the largest multiple of 0.05
    /// not above the smaller of the vacuum and compensated IoUs), if any.
    pub suggested_threshold: Option<f64>,
    /// The explanation printed by the CLI and written to `budget.md`.
    pub message: String,
}

impl Unreachable {
    /// `None` when the exact compensated launch reaches `threshold`. The vacuum IoU below
    /// the threshold is reported with it; the search is only impossible when the
    /// compensated IoU is below (what every zero-tolerance sample flies).
    pub fn check(iou_vacuum: f64, iou_compensated: f64, threshold: f64) -> Option<Unreachable> {
        if iou_compensated >= threshold {
            return None;
        }
        let mut below = Vec::new();
        if iou_vacuum < threshold {
            below.push("vacuum".to_string());
        }
        below.push("compensated".to_string());
        let reach = iou_vacuum.min(iou_compensated);
        // Rounded so that 0.85 prints as 0.85, then checked against `reach` exactly.
        let mut suggestion = ((reach * 20.0).floor() / 20.0 * 100.0).round() / 100.0;
        if suggestion > reach {
            suggestion -= 0.05;
        }
        let suggested_threshold = (suggestion > 0.0).then_some(suggestion);
        let what = if iou_vacuum < threshold {
            format!("the vacuum solution reaches IoU {iou_vacuum:.4} < threshold {threshold}")
        } else {
            format!(
                "the vacuum solution reaches IoU {iou_vacuum:.4} but the drag-compensated launch only {iou_compensated:.4} < threshold {threshold}"
            )
        };
        let message = match suggested_threshold {
            Some(s) => format!(
                "{what}: no launcher precision can reach it (P(IoU >= {threshold}) is 0 at any tolerance); rerun with --iou-threshold {s}"
            ),
            None => format!("{what}: no launcher precision can reach it"),
        };
        Some(Unreachable {
            below,
            suggested_threshold,
            message,
        })
    }
}

/// The result of [`run`].
pub struct BudgetRun {
    pub report: BudgetReport,
    /// The compensated launch (6 values per occluder).
    pub compensated: Vec<f64>,
    /// Centre of mass at `t` of the compensated launch with drag.
    pub compensated_com: Vec<DVec3>,
    /// IoU of every Monte Carlo sample, in sample order.
    pub ious: Vec<f64>,
}

fn shape_name(s: &Shape) -> String {
    match s {
        Shape::Sphere { radius } => format!("sphere r={radius}"),
        Shape::Cuboid { half_extents: h } => {
            format!("box {}x{}x{}", 2.0 * h.x, 2.0 * h.y, 2.0 * h.z)
        }
        Shape::Mesh(m) => format!("mesh {} triangles", m.triangles.len()),
    }
}

/// Check the options against the scene.
pub fn validate_options(problem: &Problem, opts: &BudgetOptions) -> Result<(), BudgetError> {
    opts.drag.validate()?;
    opts.tolerances.validate(problem.scene.t)?;
    if !(1..=MAX_SAMPLES).contains(&opts.samples) {
        return Err(BudgetError::Samples {
            what: "samples",
            value: opts.samples,
            min: 1,
            max: MAX_SAMPLES,
        });
    }
    if opts.search_samples > MAX_SAMPLES {
        return Err(BudgetError::Samples {
            what: "search samples",
            value: opts.search_samples,
            min: 0,
            max: MAX_SAMPLES,
        });
    }
    if opts.threads == Some(0) {
        return Err(BudgetError::Threads);
    }
    if !(opts.iou_threshold > 0.0 && opts.iou_threshold <= 1.0) {
        return Err(BudgetError::Threshold(opts.iou_threshold));
    }
    Ok(())
}

/// The whole budget of launch values `params` (a solution's vacuum launch).
pub fn run(
    problem: &Problem,
    params: &[f64],
    opts: &BudgetOptions,
    progress: &dyn Progress,
) -> Result<BudgetRun, BudgetError> {
    validate_options(problem, opts)?;
    let b = Budget::new(problem, params, opts.drag)?;
    let scene = &problem.scene;
    let n = scene.occluders.len();
    let threads = opts.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("building a rayon thread pool only fails if threads cannot be spawned");
    let mut bws = b.workspace();
    let exact = vec![BodyError::default(); n];

    // 1. The vacuum launch through air.
    let iou_drag = b.iou(params, &exact, &mut bws).0;
    // 2. Compensation.
    let (comp, info) = b.compensate();
    let iou_comp = b.iou(&comp, &exact, &mut bws).0;
    let compensated_com: Vec<DVec3> = (0..n).map(|i| b.drag_com(&comp, i, &exact[i])).collect();
    let occluders: Vec<OccluderReport> = scene
        .occluders
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let bd = &b.bodies[i];
            let drag_com = b.drag_com(params, i, &exact[i]);
            let q_drag = b.drag_orientation(params, i);
            let (v_vac, _) = launch_velocities(params, i);
            let (v_comp, _) = launch_velocities(&comp, i);
            OccluderReport {
                name: o.name.clone(),
                shape: shape_name(&o.shape),
                launched: o.launched,
                mass_kg: o.mass.mass,
                cd: bd.cd,
                reference_area_m2: bd.area,
                drag_k_per_m: bd.k(),
                terminal_speed_m_s: bd.terminal_speed(scene.gravity.length()),
                vacuum_com_at_t_m: b.vacuum_com[i].to_array(),
                drag_com_at_t_m: drag_com.to_array(),
                position_error_m: drag_com.distance(b.vacuum_com[i]),
                orientation_error_rad: q_drag.angle_between(b.vacuum_pose[i].1),
                vacuum_velocity_m_s: v_vac.to_array(),
                compensated_velocity_m_s: v_comp.to_array(),
                speed_change_pct: if v_vac.length() > 0.0 {
                    100.0 * (v_comp.length() / v_vac.length() - 1.0)
                } else {
                    0.0
                },
                compensated_com_error_m: compensated_com[i].distance(b.vacuum_com[i]),
                newton_iterations: info[i].0,
                lands_before_t_in_vacuum_s: b.landed[i],
            }
        })
        .collect();

    // 3. Monte Carlo at the requested tolerances.
    progress.start("Monte Carlo", opts.samples as u64);
    let (ious, diverged) = b.monte_carlo(
        &comp,
        &opts.tolerances,
        opts.samples,
        opts.seed,
        &pool,
        progress,
    );
    progress.finish();
    let monte_carlo = IouStats::new(&ious, diverged, opts.iou_threshold);
    let threshold_unreachable = Unreachable::check(b.vacuum_iou, iou_comp, opts.iou_threshold);
    let histogram = Histogram::new(&ious, 50);

    // 4. Sensitivities.
    let sensitivity = sensitivities(&b, &comp, iou_comp, &pool);

    // 5. Tolerance search.
    // 5. Tolerance search (pointless when even an exact launch misses the threshold).
    let search = (opts.search_samples > 0 && threshold_unreachable.is_none())
        .then(|| search(&b, &comp, opts, &pool, progress));

    let mut notes = vec![
        "Drag torque is neglected: the orientation at t is the exact torque-free one, so the orientation error is 0 by construction.".to_string(),
        "Tolerances are 1-sigma normal errors, independent per body; direction: each of two perpendicular components.".to_string(),
        "The Monte Carlo flies the compensated launch through air; contacts are not modelled with drag.".to_string(),
    ];
    for (o, l) in scene.occluders.iter().zip(&b.landed) {
        if let Some(tl) = l {
            notes.push(format!(
                "`{}` lands on the table at {tl:.3} s in the vacuum solution; the drag model flies it freely to t.",
                o.name
            ));
        }
    }
    if let Some(u) = &threshold_unreachable {
        notes.push(format!(
            "Threshold unreachable: {}. The tolerance search was skipped.",
            u.message
        ));
    } else if b.vacuum_iou < opts.iou_threshold {
        notes.push(format!(
            "The vacuum solution reaches IoU {:.4} < threshold {}, but the drag-compensated launch reaches {:.4}.",
            b.vacuum_iou, opts.iou_threshold, iou_comp
        ));
    }
    if diverged > 0 {
        notes.push(format!(
            "{diverged} Monte Carlo samples diverged and count with IoU 0."
        ));
    }
    let report = BudgetReport {
        scene: scene.name.clone(),
        t_s: scene.t,
        seed: opts.seed,
        drag: opts.drag,
        tolerances: opts.tolerances,
        iou_threshold: opts.iou_threshold,
        probability_target: PROBABILITY_TARGET,
        threshold_unreachable,
        iou_vacuum: b.vacuum_iou,
        iou_drag_uncompensated: iou_drag,
        iou_drag_compensated: iou_comp,
        occluders,
        monte_carlo,
        histogram,
        sensitivity,
        search,
        notes,
    };
    Ok(BudgetRun {
        report,
        compensated: comp,
        compensated_com,
        ious,
    })
}

fn sensitivities(
    b: &Budget,
    comp: &[f64],
    base: f64,
    pool: &rayon::ThreadPool,
) -> Vec<Sensitivity> {
    let scene = &b.problem.scene;
    let n = scene.occluders.len();
    let launched: Vec<usize> = (0..n).filter(|&i| scene.occluders[i].launched).collect();
    pool.install(|| {
        launched
            .par_iter()
            .map_init(
                || b.workspace(),
                |bws, &i| {
                    let com0 = b.drag_com(comp, i, &BodyError::default());
                    // Mean IoU lost and mean COM shift (mm) over a set of single-body errors.
                    let mut eval = |errs: &[BodyError]| -> (f64, f64) {
                        let mut all = vec![BodyError::default(); n];
                        let (mut lost, mut mm) = (0.0, 0.0);
                        for e in errs {
                            all[i] = *e;
                            lost += base - b.iou(comp, &all, bws).0;
                            mm += 1000.0 * b.drag_com(comp, i, e).distance(com0);
                        }
                        (lost / errs.len() as f64, mm / errs.len() as f64)
                    };
                    let one = |f: &dyn Fn(f64) -> BodyError| [f(1.0), f(-1.0)];
                    let (s, s_mm) = eval(&one(&|x| BodyError {
                        speed: 0.01 * x,
                        ..Default::default()
                    }));
                    let d = 1f64.to_radians();
                    let (a, a_mm) = eval(&[
                        BodyError {
                            direction: [d, 0.0],
                            ..Default::default()
                        },
                        BodyError {
                            direction: [-d, 0.0],
                            ..Default::default()
                        },
                        BodyError {
                            direction: [0.0, d],
                            ..Default::default()
                        },
                        BodyError {
                            direction: [0.0, -d],
                            ..Default::default()
                        },
                    ]);
                    let (tm, t_mm) = eval(&one(&|x| BodyError {
                        timing: 0.001 * x,
                        ..Default::default()
                    }));
                    let (sp, _) = eval(&one(&|x| BodyError {
                        spin: 0.01 * x,
                        ..Default::default()
                    }));
                    let (cd, cd_mm) = eval(&one(&|x| BodyError {
                        cd: 0.01 * x,
                        ..Default::default()
                    }));
                    Sensitivity {
                        name: scene.occluders[i].name.clone(),
                        iou_lost_per_pct_speed: s,
                        iou_lost_per_deg: a,
                        iou_lost_per_ms: tm,
                        iou_lost_per_pct_spin: sp,
                        iou_lost_per_pct_cd: cd,
                        mm_per_pct_speed: s_mm,
                        mm_per_deg: a_mm,
                        mm_per_ms: t_mm,
                        mm_per_pct_cd: cd_mm,
                    }
                },
            )
            .collect()
    })
}

/// Largest `s` in `[0, limit]` with `ok(s)`, assuming `ok` is (nearly) monotone: bracket
/// by doubling from `start`, then bisect. Returns (largest, at_limit).
fn largest(start: f64, limit: f64, ok: &mut dyn FnMut(f64) -> bool) -> (f64, bool) {
    if !ok(0.0) {
        return (0.0, false);
    }
    let mut lo = 0.0;
    let mut hi = start.clamp(limit * 1e-6, limit);
    loop {
        if !ok(hi) {
            break;
        }
        lo = hi;
        if hi >= limit {
            return (limit, true);
        }
        hi = (2.0 * hi).min(limit);
    }
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, false)
}

fn search(
    b: &Budget,
    comp: &[f64],
    opts: &BudgetOptions,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) -> ToleranceSearch {
    let m = opts.search_samples;
    let seed = opts.seed;
    let t = b.problem.scene.t;
    let limits: Vec<f64> = PARAMETERS
        .iter()
        .map(|(name, _, max)| {
            if *name == "timing" {
                max.min(t * 1000.0 / 3.0)
            } else {
                *max
            }
        })
        .collect();
    let defaults = Tolerances::default().to_array();
    let user = opts.tolerances.to_array();
    let stats = |tol: &Tolerances| {
        let (ious, diverged) = b.monte_carlo(comp, tol, m, seed, pool, &());
        IouStats::new(&ious, diverged, opts.iou_threshold)
    };
    let ok = |s: &IouStats| s.p_iou_at_least_threshold >= PROBABILITY_TARGET;
    progress.start("tolerance search", 6);
    let mut single = Vec::new();
    for (p, (name, unit, _)) in PARAMETERS.iter().enumerate() {
        let at = |s: f64| {
            let mut a = [0.0; 5];
            a[p] = s;
            Tolerances::from_array(a)
        };
        let start = if user[p] > 0.0 { user[p] } else { defaults[p] };
        let (best, at_limit) = largest(start, limits[p], &mut |s| ok(&stats(&at(s))));
        let top = if best > 0.0 { 2.0 * best } else { 2.0 * start }.min(limits[p]);
        let curve = (0..CURVE_POINTS)
            .map(|j| {
                let size = top * j as f64 / (CURVE_POINTS - 1) as f64;
                let s = stats(&at(size));
                CurvePoint {
                    size,
                    mean: s.mean,
                    p5: s.p5,
                    p_iou_at_least_threshold: s.p_iou_at_least_threshold,
                }
            })
            .collect();
        single.push(SingleTolerance {
            parameter: name.to_string(),
            unit: unit.to_string(),
            largest: best,
            at_limit,
            curve,
        });
        progress.advance(1);
    }
    // The largest common factor on the requested tolerances.
    let max_scale = user
        .iter()
        .zip(&limits)
        .filter(|(u, _)| **u > 0.0)
        .map(|(u, l)| l / u)
        .fold(f64::INFINITY, f64::min);
    let (joint_scale, joint_at_limit) = if max_scale.is_finite() {
        let scaled = |s: f64| Tolerances::from_array(user.map(|u| u * s));
        largest(1.0, max_scale, &mut |s| ok(&stats(&scaled(s))))
    } else {
        (0.0, false)
    };
    progress.advance(1);
    progress.finish();
    ToleranceSearch {
        samples_per_evaluation: m,
        single,
        joint_scale,
        joint_tolerances: Tolerances::from_array(user.map(|u| u * joint_scale)),
        joint_at_limit,
    }
}

impl BudgetReport {
    /// The report as Markdown (`budget.md`).
    pub fn markdown(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let d = &self.drag;
        let t = &self.tolerances;
        let _ = writeln!(s, "# Error budget: `{}`\n", self.scene);
        let _ = writeln!(
            s,
            "Shadow at t = {} s. Air: rho = {} kg/m^3; Cd sphere {}, box {}, mesh {}; Magnus lift {}; RK4 step <= {} s. Seed {}.\n",
            self.t_s,
            d.rho,
            d.cd_sphere,
            d.cd_box,
            d.cd_mesh,
            if d.magnus { "on" } else { "off" },
            d.max_step,
            self.seed
        );
        let _ = writeln!(s, "## Drag\n");
        let _ = writeln!(
            s,
            "| IoU at t | vacuum | vacuum launch in air | compensated launch in air |\n|---|---|---|---|\n| | {:.4} | {:.4} | {:.4} |\n",
            self.iou_vacuum, self.iou_drag_uncompensated, self.iou_drag_compensated
        );
        if let Some(u) = &self.threshold_unreachable {
            let _ = writeln!(s, "**Threshold unreachable:** {}.\n", u.message);
        }
        let _ = writeln!(s, "| occluder | shape | Cd | A (m^2) | k (1/m) | v_T (m/s) | drag moves it by (mm) | orientation error (rad) | speed change (%) | compensated COM error (mm) | Newton it. |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
        for o in &self.occluders {
            if !o.launched {
                let _ = writeln!(
                    s,
                    "| {} | {} | | | | | stays put | | | | |",
                    o.name, o.shape
                );
                continue;
            }
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.5} | {:.5} | {:.2} | {:.1} | {:.1e} | {:+.3} | {:.2e} | {} |",
                o.name,
                o.shape,
                o.cd,
                o.reference_area_m2,
                o.drag_k_per_m,
                o.terminal_speed_m_s,
                1000.0 * o.position_error_m,
                o.orientation_error_rad,
                o.speed_change_pct,
                1000.0 * o.compensated_com_error_m,
                o.newton_iterations
            );
        }
        let _ = writeln!(s, "\nThe compensated launch table is `launch_drag.csv` (same columns as `launch.csv`; the predicted pose at t is the one with drag).\n");
        let m = &self.monte_carlo;
        let _ = writeln!(
            s,
            "## Monte Carlo ({} samples, compensated launch in air)\n",
            m.samples
        );
        let _ = writeln!(
            s,
            "1-sigma errors per body: speed {} %, direction {} deg, spin {} %, release timing {} ms, drag coefficient {} %.\n",
            t.speed_pct, t.direction_deg, t.spin_pct, t.timing_ms, t.cd_pct
        );
        let _ = writeln!(
            s,
            "| mean IoU | 5th percentile | median | min | P(IoU >= {}) | diverged |\n|---|---|---|---|---|---|\n| {:.4} | {:.4} | {:.4} | {:.4} | {:.1} % | {} |\n",
            self.iou_threshold,
            m.mean,
            m.p5,
            m.median,
            m.min,
            100.0 * m.p_iou_at_least_threshold,
            m.diverged
        );
        let _ = writeln!(s, "![IoU histogram](budget_hist.png)\n");
        let _ = writeln!(
            s,
            "## Sensitivity (one body at a time, central differences)\n"
        );
        let _ = writeln!(s, "| occluder | IoU lost / 1 % speed | / 1 deg | / 1 ms | / 1 % spin | / 1 % Cd | mm / 1 % speed | mm / 1 deg | mm / 1 ms | mm / 1 % Cd |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for r in &self.sensitivity {
            let _ = writeln!(
                s,
                "| {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.1} | {:.1} | {:.1} | {:.1} |",
                r.name,
                r.iou_lost_per_pct_speed,
                r.iou_lost_per_deg,
                r.iou_lost_per_ms,
                r.iou_lost_per_pct_spin,
                r.iou_lost_per_pct_cd,
                r.mm_per_pct_speed,
                r.mm_per_deg,
                r.mm_per_ms,
                r.mm_per_pct_cd
            );
        }
        if let Some(u) = &self.threshold_unreachable {
            let _ = writeln!(
                s,
                "\n## Largest tolerances keeping P(IoU >= {}) >= {} %\n\nUnreachable at any tolerance, so not searched: {}.\n",
                self.iou_threshold,
                100.0 * self.probability_target,
                u.message
            );
        }
        if let Some(se) = &self.search {
            let _ = writeln!(
                s,
                "\n## Largest tolerances keeping P(IoU >= {}) >= {} %\n\n{} samples per evaluation (the same draws at every size).\n",
                self.iou_threshold,
                100.0 * self.probability_target,
                se.samples_per_evaluation
            );
            let _ = writeln!(s, "| error | alone (others exact) |\n|---|---|");
            for p in &se.single {
                let _ = writeln!(
                    s,
                    "| {} | {}{:.4} {} |",
                    p.parameter,
                    if p.at_limit { ">= " } else { "" },
                    p.largest,
                    p.unit
                );
            }
            let j = &se.joint_tolerances;
            let _ = writeln!(
                s,
                "\nAll together, the requested tolerances scaled by {}{:.4}: speed {:.4} %, direction {:.4} deg, spin {:.4} %, timing {:.4} ms, Cd {:.4} %.\n",
                if se.joint_at_limit { ">= " } else { "" },
                se.joint_scale,
                j.speed_pct,
                j.direction_deg,
                j.spin_pct,
                j.timing_ms,
                j.cd_pct
            );
            let _ = writeln!(s, "![IoU against each tolerance](budget_tolerances.png)\n");
        }
        if !self.notes.is_empty() {
            let _ = writeln!(s, "## Notes\n");
            for n in &self.notes {
                let _ = writeln!(s, "- {n}");
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn root() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    fn mickey() -> Problem {
        Problem::new(crate::scene::load(&root().join("scenes/mickey")).unwrap())
    }

    /// The launch found by `bsa solve scenes/mickey` (seed 1), rounded.
    const MICKEY: [f64; 18] = [
        0.0, 1.5015, 6.3545, 0.22, 0.54, 0.23, //
        1.461, -0.3887, 7.0623, -0.17, -0.04, 0.0, //
        -1.461, -0.3887, 7.0624, 0.14, 0.13, 0.0,
    ];

    /// A small scene of a tumbling brick (asymmetric box) and a knight (asymmetric mesh,
    /// 0.5 m tall), written to a temporary folder.
    fn box_and_mesh() -> Problem {
        let d = std::env::temp_dir().join(format!("bsa-budget-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let scene = serde_json::json!({
            "name": "dragtest",
            "target": root().join("scenes/mickey/target.png"),
            "t": 1.2,
            "light": [0.0, 0.0, 6.0],
            "receiver": {"center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0], "width": 4.0, "height": 3.0},
            "table": {"center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0]},
            "occluders": [
                {"name": "brick", "shape": {"box": {"size": [0.5, 0.25, 0.12]}}, "position": [0.0, -1.5, 0.07], "density": 600.0},
                {"name": "knight", "shape": {"mesh": {"obj": root().join("scenes/thinker/pieces/knight.obj"), "scale": 8.0}}, "position": [1.5, 0.5, 0.01], "density": 700.0}
            ],
            "stages": [{"weights": {"xor": 1}}]
        });
        let f = d.join("scene.json");
        std::fs::write(&f, serde_json::to_string(&scene).unwrap()).unwrap();
        Problem::new(crate::scene::load(&f).unwrap())
    }

    const BOX_AND_MESH: [f64; 12] = [
        0.3, 1.2, 6.2, 3.0, 5.0, 7.0, //
        -1.1, -0.3, 6.6, 2.0, -1.0, 4.0,
    ];

    fn mask_of(p: &Problem, poses: &[(DVec3, DQuat)]) -> crate::shadow::mask::Mask {
        let mut ws = p.workspace();
        ws.poses.copy_from_slice(poses);
        p.shadow(&mut ws);
        ws.mask.clone()
    }

    /// Compensation: every centre of mass within 1 mm of its vacuum position at t, the
    /// IoU with drag within 0.01 of the vacuum IoU; the shadow with drag also matches
    /// the vacuum shadow itself (so the test means something off the target too).
    fn check_compensation(p: &Problem, params: &[f64], name: &str) {
        let b = Budget::new(p, params, DragConfig::default()).unwrap();
        let (comp, info) = b.compensate();
        let exact = vec![BodyError::default(); p.scene.occluders.len()];
        let mut bws = b.workspace();
        let iou_drag = b.iou(params, &exact, &mut bws).0;
        let drag_mask = bws.ws.mask.clone();
        let iou_comp = b.iou(&comp, &exact, &mut bws).0;
        let comp_mask = bws.ws.mask.clone();
        let vac_mask = mask_of(p, &b.vacuum_pose);
        let mut worst: f64 = 0.0;
        for i in 0..p.scene.occluders.len() {
            let before = b.drag_com(params, i, &exact[i]).distance(b.vacuum_com[i]);
            let after = b.drag_com(&comp, i, &exact[i]).distance(b.vacuum_com[i]);
            let q = b
                .drag_orientation(&comp, i)
                .angle_between(b.vacuum_pose[i].1);
            eprintln!(
                "{name} {}: drag moves the COM {:.1} mm; compensated {:.2e} mm ({} Newton steps, orientation {:.1e} rad)",
                p.scene.occluders[i].name,
                1000.0 * before,
                1000.0 * after,
                info[i].0,
                q
            );
            assert!(before > 0.01, "drag too weak to test anything: {before}");
            assert!(after < 1e-3, "{name} {i}: {after} m");
            assert!(q < 1e-9, "{q}");
            worst = worst.max(after);
        }
        let self_iou = energy::iou(&comp_mask, &vac_mask);
        let drag_self_iou = energy::iou(&drag_mask, &vac_mask);
        eprintln!(
            "{name}: IoU vacuum {:.4}, drag {iou_drag:.4}, compensated {iou_comp:.4}; compensated shadow vs vacuum shadow {self_iou:.5} (uncompensated {drag_self_iou:.4}); worst COM error {worst:.2e} m",
            b.vacuum_iou
        );
        assert!((iou_comp - b.vacuum_iou).abs() <= 0.01);
        assert!(self_iou >= 0.99, "{self_iou}");
        assert!(
            drag_self_iou < 0.9,
            "drag should visibly move the shadow: {drag_self_iou}"
        );
    }

    #[test]
    fn compensation_restores_the_vacuum_poses_for_mickey() {
        let p = mickey();
        check_compensation(&p, &MICKEY, "mickey");
    }

    #[test]
    fn compensation_restores_the_vacuum_poses_for_a_box_and_a_mesh() {
        let p = box_and_mesh();
        check_compensation(&p, &BOX_AND_MESH, "box+mesh");
    }

    #[test]
    fn compensation_with_magnus_lift() {
        let p = mickey();
        let mut params = MICKEY;
        // Spin the ears fast enough that Magnus lift matters.
        params[9..12].copy_from_slice(&[0.0, 0.0, 20.0]);
        let drag = DragConfig {
            magnus: true,
            ..DragConfig::default()
        };
        let b = Budget::new(&p, &params, drag).unwrap();
        let (comp, _) = b.compensate();
        let e = BodyError::default();
        assert!(b.drag_com(&comp, 1, &e).distance(b.vacuum_com[1]) < 1e-6);
    }

    fn small_options(threads: usize) -> BudgetOptions {
        BudgetOptions {
            samples: 400,
            search_samples: 60,
            threads: Some(threads),
            seed: 7,
            ..BudgetOptions::default()
        }
    }

    #[test]
    fn same_seed_gives_bit_identical_json_with_1_and_2_threads() {
        let p = mickey();
        let a = run(&p, &MICKEY, &small_options(1), &()).unwrap();
        let b = run(&p, &MICKEY, &small_options(2), &()).unwrap();
        let ja = serde_json::to_string(&a.report).unwrap();
        let jb = serde_json::to_string(&b.report).unwrap();
        assert_eq!(ja, jb);
        assert_eq!(a.ious.len(), 400);
        // Another seed draws other errors.
        let mut o = small_options(2);
        o.seed = 8;
        let c = run(&p, &MICKEY, &o, &()).unwrap();
        assert_ne!(a.ious, c.ious);
        // No errors at all: every sample is the compensated launch.
        let mut o = small_options(2);
        o.tolerances = Tolerances::from_array([0.0; 5]);
        o.search_samples = 0;
        let d = run(&p, &MICKEY, &o, &()).unwrap();
        assert!(d.ious.iter().all(|&x| x == d.report.iou_drag_compensated));
        assert!(d.report.search.is_none());
    }

    #[test]
    fn default_threshold_is_0_9() {
        assert_eq!(BudgetOptions::default().iou_threshold, 0.9);
        assert_eq!(IOU_THRESHOLD, 0.9);
        let p = mickey();
        let mut o = small_options(2);
        o.search_samples = 0;
        let a = run(&p, &MICKEY, &o, &()).unwrap();
        let r = &a.report;
        assert_eq!(r.iou_threshold, 0.9);
        assert!(r.threshold_unreachable.is_none());
        let frac = a.ious.iter().filter(|&&x| x >= 0.9).count() as f64 / a.ious.len() as f64;
        assert_eq!(r.monte_carlo.p_iou_at_least_threshold, frac);
        let md = r.markdown();
        assert!(md.contains("P(IoU >= 0.9)"), "{md}");
        assert!(!md.contains("nreachable"), "{md}");
        let v = serde_json::to_value(r).unwrap();
        assert_eq!(v["iou_threshold"], 0.9);
        assert!(v["threshold_unreachable"].is_null());
        assert!(v["monte_carlo"]["p_iou_at_least_threshold"].is_number());
        // A lower threshold counts more successes on the same draws.
        o.iou_threshold = 0.8;
        let b = run(&p, &MICKEY, &o, &()).unwrap();
        assert_eq!(a.ious, b.ious);
        assert!(
            b.report.monte_carlo.p_iou_at_least_threshold >= r.monte_carlo.p_iou_at_least_threshold
        );
    }

    #[test]
    fn threshold_above_the_vacuum_iou_is_reported_unreachable() {
        let p = mickey();
        let b = Budget::new(&p, &MICKEY, DragConfig::default()).unwrap();
        assert!(
            b.vacuum_iou < 0.999 && b.vacuum_iou > 0.95,
            "{}",
            b.vacuum_iou
        );
        let mut o = small_options(2);
        o.iou_threshold = 0.999;
        let r = run(&p, &MICKEY, &o, &()).unwrap().report;
        let u = r
            .threshold_unreachable
            .as_ref()
            .expect("reported reachable");
        assert_eq!(u.below, ["vacuum", "compensated"]);
        assert_eq!(u.suggested_threshold, Some(0.95));
        assert!(u.message.contains("no launcher precision"), "{}", u.message);
        assert!(u.message.contains("--iou-threshold 0.95"), "{}", u.message);
        assert!(r.search.is_none(), "searched an unreachable threshold");
        assert_eq!(r.monte_carlo.p_iou_at_least_threshold, 0.0);
        let md = r.markdown();
        assert!(md.contains("Threshold unreachable"), "{md}");
        assert!(md.contains("Unreachable at any tolerance"), "{md}");
        assert!(md.contains("P(IoU >= 0.999)"), "{md}");
        let v = serde_json::to_value(&r).unwrap();
        assert_eq!(v["iou_threshold"], 0.999);
        assert!(v["search"].is_null());
        assert_eq!(v["threshold_unreachable"]["suggested_threshold"], 0.95);
        // The same at a reachable threshold: searched, nothing unreachable.
        o.iou_threshold = 0.95;
        let r = run(&p, &MICKEY, &o, &()).unwrap().report;
        assert!(r.threshold_unreachable.is_none());
        assert!(r.search.is_some());

        // The rules of the check itself.
        assert!(Unreachable::check(0.95, 0.95, 0.95).is_none());
        assert!(Unreachable::check(0.87, 0.91, 0.9).is_none());
        let u = Unreachable::check(0.87, 0.87, 0.9).unwrap();
        assert_eq!(u.suggested_threshold, Some(0.85));
        assert!(
            u.message
                .starts_with("the vacuum solution reaches IoU 0.8700 < threshold 0.9"),
            "{}",
            u.message
        );
        let u = Unreachable::check(0.92, 0.86, 0.9).unwrap();
        assert_eq!(u.below, ["compensated"]);
        assert_eq!(u.suggested_threshold, Some(0.85));
        assert_eq!(
            Unreachable::check(0.85, 0.85, 0.9)
                .unwrap()
                .suggested_threshold,
            Some(0.85)
        );
        assert_eq!(
            Unreachable::check(0.03, 0.03, 0.9)
                .unwrap()
                .suggested_threshold,
            None
        );
    }

    #[test]
    fn sensitivities_and_search_are_sane() {
        let p = mickey();
        let r = run(&p, &MICKEY, &small_options(2), &()).unwrap().report;
        for s in &r.sensitivity {
            assert!(s.iou_lost_per_pct_speed > 0.0 && s.iou_lost_per_deg > 0.0);
            assert!(s.mm_per_pct_speed > 10.0, "{s:?}");
            // Spheres without Magnus lift: spin changes nothing.
            assert_eq!(s.iou_lost_per_pct_spin, 0.0);
        }
        let se = r.search.unwrap();
        let speed = &se.single[0];
        assert!(speed.largest > 0.0 && !speed.at_limit);
        assert!(se.single[2].at_limit, "spin of spheres never matters");
        for c in &speed.curve {
            assert!((0.0..=1.0).contains(&c.p_iou_at_least_threshold));
        }
    }

    fn tiny_solution(p: &Problem) -> Solution {
        let mut scene = p.scene.clone();
        for s in &mut scene.stages {
            s.max_iterations = 2;
            s.population = 8;
        }
        let q = Problem::new(scene);
        let none = std::sync::atomic::AtomicUsize::new(0);
        let opts = crate::optimize::solver::SolveOptions {
            threads: Some(1),
            ..Default::default()
        };
        crate::optimize::solver::solve(&q, &opts, &mut crate::optimize::solver::Silent, &none).0
    }

    #[test]
    fn bad_input_gets_clear_errors() {
        let p = mickey();
        let good = BudgetOptions::default();
        assert!(validate_options(&p, &good).is_ok());
        let bad = |o: BudgetOptions| {
            let e = run(&p, &MICKEY, &o, &())
                .err()
                .expect("accepted bad options");
            (e.to_string(), e)
        };
        let (msg, e) = bad(BudgetOptions {
            drag: DragConfig {
                rho: -1.2,
                ..DragConfig::default()
            },
            ..good.clone()
        });
        assert!(
            matches!(e, BudgetError::Drag(DragError::Density(_))),
            "{msg}"
        );
        assert!(msg.contains("air density"), "{msg}");
        let (msg, e) = bad(BudgetOptions {
            drag: DragConfig::default().with_cd(-0.47),
            ..good.clone()
        });
        assert!(
            matches!(e, BudgetError::Drag(DragError::Coefficient { .. })),
            "{msg}"
        );
        for (k, v) in [(0, -1.0), (1, 90.0), (2, f64::NAN), (3, 500.0), (4, 60.0)] {
            let mut a = good.tolerances.to_array();
            a[k] = v;
            let (msg, e) = bad(BudgetOptions {
                tolerances: Tolerances::from_array(a),
                ..good.clone()
            });
            assert!(
                matches!(e, BudgetError::Tolerance { name, .. } if name == PARAMETERS[k].0),
                "{msg}"
            );
            assert!(
                msg.contains(PARAMETERS[k].0) && msg.contains("tolerance"),
                "{msg}"
            );
        }
        let (msg, _) = bad(BudgetOptions {
            samples: 0,
            ..good.clone()
        });
        assert!(msg.contains("samples"), "{msg}");
        let (_, e) = bad(BudgetOptions {
            threads: Some(0),
            ..good.clone()
        });
        assert!(matches!(e, BudgetError::Threads));
        for x in [0.0, -0.1, 1.0 + 1e-9, 1.5, f64::NAN, f64::INFINITY] {
            let (msg, e) = bad(BudgetOptions {
                iou_threshold: x,
                ..good.clone()
            });
            assert!(matches!(e, BudgetError::Threshold(_)), "{msg}");
            assert!(msg.contains("IoU threshold"), "{msg}");
        }
        for x in [1e-6, 0.5, 0.85, 1.0] {
            let o = BudgetOptions {
                iou_threshold: x,
                ..good.clone()
            };
            assert!(validate_options(&p, &o).is_ok(), "{x}");
        }
        let e = Budget::new(&p, &MICKEY[..12], DragConfig::default())
            .err()
            .unwrap();
        assert!(matches!(
            e,
            BudgetError::Parameters {
                expected: 18,
                found: 12
            }
        ));

        // Solutions: the right one passes; another scene's, another t, an edited scene fail.
        let s = tiny_solution(&p);
        check_solution_current(&p, &s).unwrap();
        let mut other = s.clone();
        other.scene = "fly".into();
        let e = check_solution_current(&p, &other).unwrap_err();
        assert!(
            matches!(e, BudgetError::Mismatch(MismatchError::Scene { .. })),
            "{e}"
        );
        let mut other = s.clone();
        other.t = 1.5;
        assert!(matches!(
            check_solution_current(&p, &other),
            Err(BudgetError::Mismatch(MismatchError::Time { .. }))
        ));
        let mut scene = p.scene.clone();
        scene.occluders[0].position += DVec3::new(0.3, 0.0, 0.0);
        let edited = Problem::new(scene);
        let e = check_solution_current(&edited, &s).unwrap_err();
        assert!(matches!(e, BudgetError::Stale { .. }), "{e}");
        assert!(e.to_string().contains("edited"), "{e}");
    }

    #[test]
    fn diverged_samples_count_with_iou_zero() {
        let p = mickey();
        let b = Budget::new(&p, &MICKEY, DragConfig::default()).unwrap();
        let mut bws = b.workspace();
        let mut errs = vec![BodyError::default(); 3];
        errs[1].speed = f64::NAN;
        assert_eq!(b.iou(&MICKEY, &errs, &mut bws), (0.0, true));
    }
}
