//! What `budget.json` holds ([`BudgetReport`] and its parts) and its Markdown rendering
//! (`budget.md`).

use std::fmt::Write;

use super::*;

/// Numbers the user gave (a tolerance, a threshold, an air density) are written as
/// `scene` writes its limits: plain from 1e-4 up to 1e5, in exponent form beyond.
pub use crate::scene::short;

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
    pub(super) fn new(values: &[f64], bins: usize) -> Histogram {
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
    /// Largest 1-sigma size keeping P(IoU >= threshold) >= 90 % (the others zero).
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
    /// P(IoU >= threshold) >= [`super::PROBABILITY_TARGET`].
    pub joint_scale: f64,
    pub joint_tolerances: Tolerances,
    pub joint_at_limit: bool,
}

/// What launcher a solution needs: the largest 1-sigma error of each of the launcher's
/// kinds alone, and the largest factor on the whole default launcher model, that keep
/// `P(IoU >= threshold) >= probability`, the threshold [`super::NEEDS_MARGIN`] below the
/// solution's IoU; flown in a vacuum, as the solver flies (`bsa budget` adds the air).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct LauncherNeeds {
    /// The solution's IoU at `t`.
    pub iou: f64,
    pub threshold: f64,
    pub probability: f64,
    /// Draws per evaluation.
    pub samples: usize,
    pub single: Vec<NeededTolerance>,
    /// The default launcher model's errors may be this many times larger (below 1: the
    /// launcher must be this much better than the model).
    pub scale: f64,
    pub scale_at_limit: bool,
}

/// One error kind of [`LauncherNeeds`].
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct NeededTolerance {
    pub parameter: String,
    pub unit: String,
    /// The largest 1-sigma error of this kind alone.
    pub largest: f64,
    /// The search stopped at the largest error it accepts.
    pub at_limit: bool,
    /// The default launcher model's error of this kind.
    pub model: f64,
}

impl LauncherNeeds {
    /// A table in Markdown, with what it means above it.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "The largest 1-sigma error of each kind alone that keeps P(IoU >= {:.3}) >= {:.0} % (the solution's IoU {:.4} less {}), in a vacuum, {} draws per evaluation:\n\n| error | largest | default launcher |\n|---|---|---|\n",
            self.threshold,
            100.0 * self.probability,
            self.iou,
            super::NEEDS_MARGIN,
            self.samples
        );
        for n in &self.single {
            let more = if n.at_limit { " or more" } else { "" };
            md.push_str(&format!(
                "| {} | {} {}{more} | {} {} |\n",
                n.parameter.replace('_', " "),
                significant(n.largest),
                n.unit,
                super::short(n.model),
                n.unit
            ));
        }
        let verdict = if self.scale >= 1.0 {
            format!(
                "the default launcher's errors may be {} times larger",
                significant(self.scale)
            )
        } else if self.scale > 0.0 {
            format!(
                "the launcher must be {} times more precise than the default",
                significant(1.0 / self.scale)
            )
        } else {
            "no launcher precision is enough".to_string()
        };
        md.push_str(&format!("\nAll together: {verdict}.\n"));
        md
    }
}

/// `x` to three significant digits (0.00977, 0.191, 12.6, 450).
fn significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
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
        let shown = short(threshold);
        let what = if iou_vacuum < threshold {
            format!("the vacuum solution reaches IoU {iou_vacuum:.4} < threshold {shown}")
        } else {
            format!(
                "the vacuum solution reaches IoU {iou_vacuum:.4} but the drag-compensated launch only {iou_compensated:.4} < threshold {shown}"
            )
        };
        let message = match suggested_threshold {
            Some(s) => format!(
                "{what}: no launcher precision can reach it (P(IoU >= {shown}) is 0 at any tolerance); rerun with --iou-threshold {s}"
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

impl BudgetReport {
    /// The report as Markdown (`budget.md`).
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        self.md_header(&mut s);
        self.md_drag(&mut s);
        self.md_monte_carlo(&mut s);
        self.md_sensitivity(&mut s);
        self.md_search(&mut s);
        if !self.notes.is_empty() {
            let _ = writeln!(s, "## Notes\n");
            for n in &self.notes {
                let _ = writeln!(s, "- {n}");
            }
        }
        s
    }

    /// The title and the line of the run's settings (air, seed).
    fn md_header(&self, s: &mut String) {
        let d = &self.drag;
        let _ = writeln!(s, "# Error budget: `{}`\n", self.scene);
        let _ = writeln!(
            s,
            "Shadow at t = {} s. Air: rho = {} kg/m^3; Cd sphere {}, box {}, mesh {}; Magnus lift {}; RK4 step <= {} s. Seed {}.\n",
            short(self.t_s),
            short(d.rho),
            short(d.cd_sphere),
            short(d.cd_box),
            short(d.cd_mesh),
            if d.magnus { "on" } else { "off" },
            short(d.max_step),
            self.seed
        );
    }

    /// The drag section: the table of IoUs in vacuum and in air, then the table of every
    /// occluder's drag figures.
    fn md_drag(&self, s: &mut String) {
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
                short(o.cd),
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
    }

    /// The Monte Carlo section: the tolerances, the table of IoU statistics and the
    /// histogram's picture.
    fn md_monte_carlo(&self, s: &mut String) {
        let t = &self.tolerances;
        let m = &self.monte_carlo;
        let _ = writeln!(
            s,
            "## Monte Carlo ({} samples, compensated launch in air)\n",
            m.samples
        );
        let _ = writeln!(
            s,
            "1-sigma errors per body: speed {} %, direction {} deg, spin {} %, release timing {} ms, position {} mm, orientation {} deg, spin floor {} rad/s, drag coefficient {} %.\n",
            short(t.speed_pct),
            short(t.direction_deg),
            short(t.spin_pct),
            short(t.timing_ms),
            short(t.position_mm),
            short(t.orientation_deg),
            short(t.spin_floor_rad_s),
            short(t.cd_pct)
        );
        let _ = writeln!(
            s,
            "| mean IoU | 5th percentile | median | min | P(IoU >= {}) | diverged |\n|---|---|---|---|---|---|\n| {:.4} | {:.4} | {:.4} | {:.4} | {:.1} % | {} |\n",
            short(self.iou_threshold),
            m.mean,
            m.p5,
            m.median,
            m.min,
            100.0 * m.p_iou_at_least_threshold,
            m.diverged
        );
        let _ = writeln!(s, "![IoU histogram](budget_hist.png)\n");
    }

    /// The sensitivity section: the table of IoU lost and shift per unit error, a row per
    /// occluder.
    fn md_sensitivity(&self, s: &mut String) {
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
    }

    /// The tolerance section: why it was not searched, or the table of each error's
    /// largest size alone, the joint scale and the curves' picture; nothing when the
    /// search was neither run nor impossible.
    fn md_search(&self, s: &mut String) {
        if let Some(u) = &self.threshold_unreachable {
            let _ = writeln!(
                s,
                "\n## Largest tolerances keeping P(IoU >= {}) >= {} %\n\nUnreachable at any tolerance, so not searched: {}.\n",
                short(self.iou_threshold),
                100.0 * self.probability_target,
                u.message
            );
        }
        let Some(se) = &self.search else {
            return;
        };
        let _ = writeln!(
            s,
            "\n## Largest tolerances keeping P(IoU >= {}) >= {} %\n\n{} samples per evaluation (the same draws at every size).\n",
            short(self.iou_threshold),
            100.0 * self.probability_target,
            se.samples_per_evaluation
        );
        let _ = writeln!(s, "| error | alone (others exact) |\n|---|---|");
        for p in &se.single {
            let _ = writeln!(
                s,
                "| {} | {}{:.4} {} |",
                p.parameter.replace('_', " "),
                if p.at_limit { ">= " } else { "" },
                p.largest,
                p.unit
            );
        }
        let joint: Vec<String> = se
            .joint_tolerances
            .to_array()
            .iter()
            .zip(PARAMETERS)
            .map(|(v, (name, unit, _))| format!("{} {v:.4} {unit}", name.replace('_', " ")))
            .collect();
        let _ = writeln!(
            s,
            "\nAll together, the requested tolerances scaled by {}{:.4}: {}.\n",
            if se.joint_at_limit { ">= " } else { "" },
            se.joint_scale,
            joint.join(", ")
        );
        let _ = writeln!(s, "![IoU against each tolerance](budget_tolerances.png)\n");
    }
}
