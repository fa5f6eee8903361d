//! `bsa budget`: the error budget of a saved solution ([`crate::budget`]); writes
//! `launch_drag.csv`, `budget.json`, `budget.md` and the plots of
//! [`crate::budget::plots`] next to the solution, and prints a summary.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};

use crate::budget::{
    self, plots, short, BudgetError, BudgetOptions, BudgetReport, BudgetRun, Tolerances, KINDS,
    PARAMETERS,
};
use crate::evaluate::Problem;
use crate::output::files;
use crate::sim::drag::{DragConfig, DragError};

use super::launcher::{LauncherArgs, FLAGS};
use super::progress::BudgetProgress;
use super::{load, BudgetArgs};

/// The options of `bsa budget`. The budget's own options are checked by
/// [`Options::validate`] against the scene, since the largest timing error accepted
/// depends on the scene's `t`.
pub(super) struct Options {
    /// The output folder of a solve, or its `solution.json`.
    path: PathBuf,
    scene: Option<PathBuf>,
    budget: BudgetOptions,
    /// The launcher's errors, resolved against the scene ([`BudgetOptions::tolerances`]).
    launcher: LauncherArgs,
    quiet: bool,
}

impl Options {
    pub(super) fn new(args: BudgetArgs) -> Options {
        let mut drag = DragConfig {
            rho: args.rho,
            magnus: args.magnus,
            ..Default::default()
        };
        if let Some(cd) = args.cd {
            drag = drag.with_cd(cd);
        }
        let budget = BudgetOptions {
            drag,
            tolerances: Tolerances::default(),
            samples: args.samples,
            search_samples: args.search_samples,
            seed: args.seed,
            threads: args.threads,
            iou_threshold: args.iou_threshold,
        };
        Options {
            path: args.path,
            scene: args.scene,
            budget,
            launcher: args.launcher,
            quiet: args.quiet,
        }
    }

    /// The budget's options with the launcher resolved against the scene, every option
    /// (drag, tolerances, sample counts, threads, threshold) checked before any
    /// simulation runs. The error names the flag to change, then what is wrong with its
    /// value.
    fn validate(&self, problem: &Problem) -> Result<BudgetOptions> {
        let opts = BudgetOptions {
            tolerances: self.launcher.resolve(&problem.scene)?,
            ..self.budget.clone()
        };
        budget::validate_options(problem, &opts).map_err(|e| match flag_of(&e) {
            Some(flag) => anyhow::anyhow!("{flag}: {e}"),
            None => anyhow::Error::new(e).context("invalid budget options"),
        })?;
        check_some_error(
            &opts.tolerances,
            true,
            "every Monte Carlo launch would be the compensated launch itself, and there would be no requested tolerance to scale",
        )?;
        Ok(opts)
    }

    /// The output folder and the solution file of [`Options::path`].
    fn dir_and_file(&self) -> (PathBuf, PathBuf) {
        let path = &self.path;
        if path.is_file() {
            let dir = path
                .parent()
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            (dir.to_path_buf(), path.to_path_buf())
        } else {
            (path.to_path_buf(), path.join("solution.json"))
        }
    }
}

/// Refuses launch errors that are all zero, naming their flags: every perturbed launch
/// would then be the nominal one, and `why` says what that makes of the command.
/// `with_cd`: whether the drag coefficient's error is one of them (it is only with air).
pub(super) fn check_some_error(t: &Tolerances, with_cd: bool, why: &str) -> Result<()> {
    let n = if with_cd { KINDS } else { KINDS - 1 };
    if t.to_array()[..n].iter().all(|&x| x == 0.0) {
        bail!(
            "{} are all 0: {why}; give at least one of them a tolerance above 0",
            FLAGS[..n].join(", ")
        );
    }
    Ok(())
}

/// The command-line flag that sets the value an option error is about (`None` for a
/// value no flag sets, such as the drag integrator's step).
pub(super) fn flag_of(e: &BudgetError) -> Option<&'static str> {
    Some(match e {
        BudgetError::Drag(DragError::Density(_)) => "--rho",
        BudgetError::Drag(DragError::Coefficient { .. }) => "--cd",
        BudgetError::Tolerance(e) => {
            let k = PARAMETERS.iter().position(|p| p.0 == e.name)?;
            FLAGS[k]
        }
        BudgetError::Samples { what, .. } if *what == "samples" => "--samples",
        BudgetError::Samples { what, .. } if *what == "search samples" => "--search-samples",
        BudgetError::Threads => "--threads",
        BudgetError::Threshold(_) => "--iou-threshold",
        _ => return None,
    })
}

/// Run the budget, write its files and print a summary.
pub(super) fn run(opts: &Options) -> Result<()> {
    let (dir, file) = opts.dir_and_file();
    let (problem, solution, scene_path) =
        load::solution_and_scene(&dir, &file, opts.scene.as_deref())?;
    let budget_opts = opts.validate(&problem)?;
    budget::check_solution_current(&problem, &solution).with_context(|| {
        format!(
            "{} does not belong to the scene {} (pass the right one with --scene)",
            file.display(),
            scene_path.display()
        )
    })?;
    let bars = BudgetProgress::new(opts.quiet);
    let start = Instant::now();
    let run = budget::run(&problem, &solution.parameters(), &budget_opts, &bars)?;
    let elapsed = start.elapsed().as_secs_f64();
    let r = &run.report;
    write_files(&dir, &problem, &run, opts.budget.threads, elapsed)?;
    print_summary(r);
    // The solve's report page shows the budget too, so it is rewritten with it.
    let report = crate::output::report::write_report(&dir, &solution)?;
    println!(
        "wrote {}/{{budget.md, budget.json, launch_drag.csv, budget_hist.png, budget_hist.svg{}, report.html}} in {elapsed:.2} s",
        dir.display(),
        if r.search.is_some() {
            ", budget_tolerances.png, budget_tolerances.svg"
        } else {
            ""
        }
    );
    println!("report: {}", report.display());
    Ok(())
}

/// Write the budget's files into `dir`: `launch_drag.csv`, `budget.json`, `budget.md`
/// (saying it took `elapsed` seconds on `threads`) and the plots, removing a tolerance
/// plot of an earlier run that this one has no search for.
fn write_files(
    dir: &Path,
    problem: &Problem,
    run: &BudgetRun,
    threads: Option<usize>,
    elapsed: f64,
) -> Result<()> {
    let r = &run.report;
    // launch_drag.csv: the launch table of the compensated launch, its pose at t with drag.
    let mut rows = crate::output::trajectory::launch_rows(problem, &run.compensated);
    for (row, com) in rows.iter_mut().zip(&run.compensated_com) {
        row.com_at_t_x_m = com.x;
        row.com_at_t_y_m = com.y;
        row.com_at_t_z_m = com.z;
    }
    files::write_csv(&dir.join("launch_drag.csv"), &rows)?;
    files::write_atomic(
        &dir.join("budget.json"),
        serde_json::to_string_pretty(r)?.as_bytes(),
    )?;
    let mut md = r.markdown();
    md.push_str(&format!(
        "\nMade by `bsa budget` in {elapsed:.2} s on {} threads.\n",
        threads.unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        })
    ));
    files::write_atomic(&dir.join("budget.md"), md.as_bytes())?;
    files::save_figure(dir, "budget_hist", &plots::histogram(r)?)?;
    match plots::tolerances(r) {
        Some(figure) => files::save_figure(dir, "budget_tolerances", &figure?)?,
        // No search this time: a plot left by an earlier run would not match budget.json.
        None => {
            for ext in ["png", "svg"] {
                let stale = dir.join(format!("budget_tolerances.{ext}"));
                if stale.is_file() {
                    std::fs::remove_file(&stale)
                        .with_context(|| format!("removing the stale {}", stale.display()))?;
                }
            }
        }
    }
    Ok(())
}

/// The summary on the terminal: the IoU in vacuum, with drag and compensated, each
/// launched occluder's drag and compensation, the Monte Carlo and the tolerance search.
fn print_summary(r: &BudgetReport) {
    println!(
        "{}: IoU at t {:.4} in vacuum, {:.4} with drag, {:.4} with the drag-compensated launch",
        r.scene, r.iou_vacuum, r.iou_drag_uncompensated, r.iou_drag_compensated
    );
    for o in r.occluders.iter().filter(|o| o.launched) {
        println!(
            "  {:<12} drag moves it {:>8.1} mm at t; compensated: speed {:+.3} %, COM error {:.2e} mm ({} Newton steps)",
            o.name,
            1000.0 * o.position_error_m,
            o.speed_change_pct,
            1000.0 * o.compensated_com_error_m,
            o.newton_iterations
        );
    }
    let m = &r.monte_carlo;
    let t = &r.tolerances;
    println!(
        "  Monte Carlo ({} samples; speed {} %, direction {} deg, spin {} %, timing {} ms, Cd {} %): mean IoU {:.4}, 5th percentile {:.4}, P(IoU >= {}) {:.1} %",
        m.samples,
        short(t.speed_pct),
        short(t.direction_deg),
        short(t.spin_pct),
        short(t.timing_ms),
        short(t.cd_pct),
        m.mean,
        m.p5,
        short(r.iou_threshold),
        100.0 * m.p_iou_at_least_threshold
    );
    if let Some(u) = &r.threshold_unreachable {
        println!("  threshold unreachable: {}", u.message);
        println!("  largest tolerances: none (not searched: no launcher precision reaches the threshold)");
    }
    if let Some(se) = &r.search {
        let alone: Vec<String> = se
            .single
            .iter()
            .map(|p| {
                format!(
                    "{} {}{:.3} {}",
                    p.parameter,
                    if p.at_limit { ">=" } else { "" },
                    p.largest,
                    p.unit
                )
            })
            .collect();
        println!(
            "  largest tolerances for P(IoU >= {}) >= {} %: alone {}; together x{:.3} of the requested",
            short(r.iou_threshold),
            100.0 * r.probability_target,
            alone.join(", "),
            se.joint_scale
        );
    }
}
