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
//!    scale of the requested tolerances, that keep `P(IoU >= threshold) >= 90 %`
//!    (bracketing then bisection; every evaluation uses the same random draws, so `P` is
//!    a deterministic, nearly monotone function of the size). The threshold is
//!    [`BudgetOptions::iou_threshold`] (default [`IOU_THRESHOLD`], 0.9). When the
//!    compensated launch without any error is already below it, no launcher precision
//!    reaches it: the search is skipped and the report says so ([`Unreachable`]).
//!
//! The numeric core does not fail: a sample whose flight diverges gets IoU 0 and is
//! counted in [`IouStats::diverged`]. Contacts are not modelled with drag; a body that
//! lands before `t` in the vacuum solution is flagged in the report.

pub mod plots;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::energy::{self, Weights};
use crate::evaluate::{Problem, Workspace, MAX_THREADS, MAX_TURN};
use crate::geometry::shape::Shape;
use crate::output::solution::{check_solution, MismatchError, Solution};
use crate::scene::launcher::limits;
use crate::scene::Launch;
use crate::sim::drag::{self, BodyDrag, DragConfig, DragError};
use crate::sim::flight::{FreeFlight, LaunchState};
pub use crate::sim::launch_error::{
    aim, draw_errors, sample_seed, BodyError, ToleranceError, Tolerances, KINDS, PARAMETERS,
};

mod montecarlo;
mod report;
mod search;

pub use montecarlo::*;
pub use report::*;
pub use search::{at_launcher, needs};
use search::{search, sensitivities};

/// The default IoU a shadow must reach to "read" as the picture
/// ([`BudgetOptions::iou_threshold`]).
pub const IOU_THRESHOLD: f64 = 0.9;
/// The probability of reaching the IoU threshold that the tolerance search keeps: the
/// share of launches a builder can expect to read as the picture.
pub const PROBABILITY_TARGET: f64 = 0.90;
/// How far below a solution's IoU a launch may land and still count in
/// [`LauncherNeeds`]: 0.05, about where a picture starts to read as damaged.
pub const NEEDS_MARGIN: f64 = 0.05;
/// Draws per evaluation of [`needs`]: enough to tell 90 % from 80 % (one standard error
/// is 2.7 points at 90 %), few enough to run after every solve.
pub const NEEDS_SAMPLES: usize = 128;
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
    #[error(transparent)]
    Tolerance(#[from] ToleranceError),
    #[error("the number of {what} must be between {min} and {max}, got {value}")]
    Samples {
        what: &'static str,
        value: usize,
        min: usize,
        max: usize,
    },
    #[error("the number of threads must be from 1 to {MAX_THREADS}")]
    Threads,
    #[error("the IoU threshold must be greater than 0 and at most 1, got {}", short(*.0))]
    Threshold(f64),
    #[error("the launch values hold {found} numbers, the scene needs {expected}")]
    Parameters { expected: usize, found: usize },
    #[error(transparent)]
    Mismatch(#[from] MismatchError),
    #[error("the scene or the solution was edited after the solve: the solution's shadow at t now has IoU {now:.6} and {contacts_now} contacts, the solution recorded IoU {recorded:.6} and {contacts_recorded} (solve again, or pass the scene it was made for)")]
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

pub(super) fn shape_name(s: &Shape) -> String {
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
    if opts
        .threads
        .is_some_and(|n| !(1..=MAX_THREADS).contains(&n))
    {
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
    let pool = thread_pool(opts.threads);
    let mut bws = b.workspace();
    let exact = vec![BodyError::default(); n];

    // 1. The vacuum launch through air.
    let iou_drag = b.iou(params, &exact, &mut bws).0;
    // 2. Compensation.
    let (comp, info) = b.compensate();
    let iou_comp = b.iou(&comp, &exact, &mut bws).0;
    let compensated_com: Vec<DVec3> = (0..n).map(|i| b.drag_com(&comp, i, &exact[i])).collect();
    let occluders = occluder_reports(&b, params, &comp, &compensated_com, &info);

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

    let notes = notes(&b, opts, threshold_unreachable.as_ref(), iou_comp, diverged);
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

/// A pool of `threads` workers (None: one per core).
fn thread_pool(threads: Option<usize>) -> rayon::ThreadPool {
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("building a rayon thread pool only fails if threads cannot be spawned")
}

/// The drag figures of every occluder: the vacuum launch `params` flown through air, and
/// the compensated launch `comp` (its centres of mass at `t` and Newton `info` as
/// [`Budget::compensate`] gives them).
fn occluder_reports(
    b: &Budget,
    params: &[f64],
    comp: &[f64],
    compensated_com: &[DVec3],
    info: &[(usize, f64)],
) -> Vec<OccluderReport> {
    let scene = &b.problem.scene;
    let exact = BodyError::default();
    scene
        .occluders
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let bd = &b.bodies[i];
            let drag_com = b.drag_com(params, i, &exact);
            let q_drag = b.drag_orientation(params, i);
            let Launch {
                velocity: v_vac, ..
            } = Launch::get(params, i);
            let Launch {
                velocity: v_comp, ..
            } = Launch::get(comp, i);
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
        .collect()
}

/// The report's notes: the model's simplifications always, then what applies to this
/// scene and run (air in the solve, several instants, landings, the threshold,
/// diverged samples).
fn notes(
    b: &Budget,
    opts: &BudgetOptions,
    threshold_unreachable: Option<&Unreachable>,
    iou_comp: f64,
    diverged: usize,
) -> Vec<String> {
    let scene = &b.problem.scene;
    let mut notes = vec![
        "Drag torque is neglected: the orientation at t is the exact torque-free one, so the orientation error is 0 by construction.".to_string(),
        "Tolerances are 1-sigma normal errors, independent per body; direction and position: each of two perpendicular components; orientation and spin floor: each of three.".to_string(),
        "The Monte Carlo flies the compensated launch through air; contacts are not modelled with drag.".to_string(),
    ];
    if let crate::evaluate::Physics::Air { .. } = b.problem.plan.physics {
        notes.push("The launch was solved with air in the loop (`bsa solve --air`): the \"vacuum\" figures are the solve's own model, with drag, and the compensated launch is the launch itself.".to_string());
    }
    if !scene.single_instant() {
        notes.push(format!(
            "The scene has several instants (pictures or a hold window): the budget measures the picture at t = {} s only.",
            scene.t
        ));
    }
    for (o, l) in scene.occluders.iter().zip(&b.landed) {
        if let Some(tl) = l {
            notes.push(format!(
                "`{}` lands on the table at {tl:.3} s in the vacuum solution; the drag model flies it freely to t.",
                o.name
            ));
        }
    }
    if let Some(u) = threshold_unreachable {
        notes.push(format!(
            "Threshold unreachable: {}. The tolerance search was skipped.",
            u.message
        ));
    } else if b.vacuum_iou < opts.iou_threshold {
        notes.push(format!(
            "The vacuum solution reaches IoU {:.4} < threshold {}, but the drag-compensated launch reaches {:.4}.",
            b.vacuum_iou,
            short(opts.iou_threshold),
            iou_comp
        ));
    }
    if diverged > 0 {
        notes.push(format!(
            "{diverged} Monte Carlo samples diverged and count with IoU 0."
        ));
    }
    notes
}

#[cfg(test)]
mod tests;
