//! `bsa solve`: optimise the launch velocities of a scene and write the output folder
//! (solution, pictures, convergence table and plot, and the exports of `bsa export`),
//! with progress bars, resuming and a two-step Ctrl-C.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{bail, Context, Result};

use crate::budget::Tolerances;
use crate::energy::Weights;
use crate::evaluate::{FrameIou, Problem, Robust};
use crate::optimize::solver::{self, Schedule, SolveOptions};
use crate::output::files;
use crate::output::solution::{self, SampleRecord, Solution};
use crate::scene::{LaunchPositions, Scene};
use crate::sim::drag::DragConfig;

use super::launcher::LauncherArgs;
use super::progress::SolveProgress;
use super::{export, frames, guard, load, outdir, SolveArgs};
use crate::evaluate::MAX_THREADS;

/// Ctrl-C presses so far. The solver reads it between iterations: one press ends the
/// current stage, a second one stops and saves the best so far.
static INTERRUPTS: AtomicUsize = AtomicUsize::new(0);

/// The validated options of `bsa solve`.
pub(super) struct Options {
    scene: PathBuf,
    /// `None`: `export/<scene folder's name>`, known once the scene is loaded.
    out: Option<PathBuf>,
    seed: Option<u64>,
    /// Between 1 and [`MAX_THREADS`] when given.
    threads: Option<usize>,
    /// Between 1 and [`MAX_ATTEMPTS`].
    attempts: usize,
    /// `--time-limit`, positive and finite.
    time_limit: Option<std::time::Duration>,
    resume: bool,
    /// Replace another scene's results in the output folder.
    force: bool,
    report: bool,
    quiet: bool,
    /// Air in the loop.
    air: bool,
    /// Launch errors to optimise under (`--robust`), tolerances checked against `t` once
    /// the scene is loaded.
    robust: Option<Robust>,
    /// The launcher's errors of `--robust`, resolved against the scene.
    launcher: LauncherArgs,
    free_positions: bool,
}

/// The most attempts `--attempts` accepts.
const MAX_ATTEMPTS: usize = 16;
/// The longest `--time-limit` (s): a week.
const MAX_TIME_LIMIT: f64 = 7.0 * 24.0 * 3600.0;

/// Perturbed launches per sample of `--robust` unless `--draws` says otherwise.
const DEFAULT_DRAWS: usize = 16;
/// The least perturbed launches of the reference set that a robust solve compares the
/// samples of different iterations on (four times `--draws` if more).
const REFERENCE_DRAWS: usize = 64;
/// The most perturbed launches per sample `--draws` accepts.
const MAX_DRAWS: usize = 10_000;

impl Options {
    /// Check the arguments that do not depend on the scene.
    pub(super) fn new(args: SolveArgs) -> Result<Options> {
        if let Some(n) = args.threads {
            if !(1..=MAX_THREADS).contains(&n) {
                bail!("--threads must be between 1 and {MAX_THREADS}, got {n}");
            }
        }
        let attempts = args.attempts.unwrap_or(Schedule::DEFAULT.attempts);
        if !(1..=MAX_ATTEMPTS).contains(&attempts) {
            bail!("--attempts must be between 1 and {MAX_ATTEMPTS}, got {attempts}");
        }
        let time_limit = match args.time_limit {
            Some(s) if !(s > 0.0 && s <= MAX_TIME_LIMIT) => bail!(
                "--time-limit must be a number of seconds above 0 and at most {MAX_TIME_LIMIT}, got {}",
                crate::budget::short(s)
            ),
            limit => limit.map(std::time::Duration::from_secs_f64),
        };
        let robust = if args.robust {
            let draws = args.draws.unwrap_or(DEFAULT_DRAWS);
            if !(1..=MAX_DRAWS).contains(&draws) {
                bail!("--draws must be between 1 and {MAX_DRAWS}, got {draws}");
            }
            if let Some(q) = args.quantile {
                // 1e-300 as written, not as three hundred digits.
                let shown = crate::budget::short(q);
                if !(q > 0.0 && q < 1.0) {
                    bail!("--quantile must be between 0 and 1 (exclusive), got {shown}");
                }
                // The quantile of one number is that number: the samples would be ranked
                // by a single perturbed launch, as without --quantile.
                if draws < 2 {
                    bail!(
                        "--quantile {shown} needs --draws 2 or more: with --draws {draws} it is the energy of a single perturbed launch"
                    );
                }
            }
            if args.launcher.cd_given() && !args.air {
                bail!("--cd-tol is the error of the drag model: it needs --air");
            }
            Some(Robust {
                // Resolved against the scene's launcher once it is loaded.
                tolerances: Tolerances::default(),
                draws,
                reference_draws: (4 * draws).max(REFERENCE_DRAWS),
                quantile: args.quantile,
            })
        } else {
            let given = [
                ("--draws", args.draws.is_some()),
                ("--quantile", args.quantile.is_some()),
            ]
            .into_iter()
            .find(|(_, g)| *g)
            .map(|(n, _)| n)
            .or(args.launcher.first_given());
            if let Some(name) = given {
                bail!("{name} is an option of --robust: add --robust");
            }
            None
        };
        Ok(Options {
            scene: args.scene,
            out: args.out,
            seed: args.seed,
            threads: args.threads,
            attempts,
            time_limit,
            resume: args.resume,
            force: args.force,
            report: args.report,
            quiet: args.quiet,
            air: args.air,
            robust,
            launcher: args.launcher,
            free_positions: args.free_positions,
        })
    }
}

/// Solve the scene, saving progress as it goes, then write the pictures and exports.
/// The output folder is locked and checked first, and a complete solution already in it
/// survives any solve that does not complete (see [`guard`]).
pub(super) fn run(opts: &Options) -> Result<()> {
    let mut clock = Clock::new();
    let scene = load::scene(&opts.scene)?;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| outdir::default_out(&scene));
    if !opts.resume {
        for f in outdir::prepare(&out, &scene, opts.force)? {
            eprintln!(
                "removed {} (it belonged to the previous solution)",
                f.display()
            );
        }
    }
    let problem = problem(opts, scene)?;
    clock.lap("scene loading and set-up");
    let scene = &problem.scene;
    let needed = guard::estimated_bytes(
        (scene.t + crate::output::trajectory::DEFAULT_MAX_AFTER) / scene.dt,
        scene.occluders.len(),
        scene.target.width() * scene.target.height(),
    );
    let guard = guard::OutputGuard::acquire(&out, opts.resume, needed)?;
    let result = solve_into(opts, &problem, &out, guard.has_previous(), clock);
    let incomplete = match &result {
        // A stage shortened by one Ctrl-C still counts as run: the user chose to end it.
        Ok(solution) => solution.stages_completed < solution.stages_total,
        Err(_) => true,
    };
    if !incomplete {
        return Ok(());
    }
    let saved = guard.keep_previous();
    match result {
        Ok(s) => Err(guard::Interrupted {
            done: s.stages_completed,
            total: s.stages_total,
            saved,
            scene: opts.scene.display().to_string(),
            out: out.display().to_string(),
        }
        .into()),
        // Nothing ran: the folder's files are as they were, damaged or not.
        Err(e) if e.downcast_ref::<NotResumed>().is_some() => Err(e),
        Err(e) => {
            // The cause comes first in the error below; where the files are is a note.
            eprintln!("note: {saved}");
            Err(e)
        }
    }
}

/// The context of an error that refused to resume from a `solution.json`: no stage ran,
/// and the output folder holds what it held.
#[derive(Debug)]
struct NotResumed(std::path::PathBuf);

impl std::fmt::Display for NotResumed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot resume from {}", self.0.display())
    }
}

/// The problem the options ask to solve: free positions, air and launch errors.
fn problem(opts: &Options, mut scene: crate::scene::Scene) -> Result<Problem> {
    if opts.free_positions {
        if scene.table.is_none() {
            bail!(
                "--free-positions: the scene {} has no table to bound the launch positions to",
                scene.source.display()
            );
        }
        scene.positions = LaunchPositions::Free;
    }
    let robust = match opts.robust {
        Some(r) => {
            let mut t = opts.launcher.resolve(&scene)?;
            // In a vacuum there is no drag coefficient to be wrong.
            if !opts.air {
                t.cd_pct = 0.0;
            }
            super::budget::check_some_error(
                &t,
                opts.air,
                "every perturbed launch would be the nominal one, and --robust would optimise the plain objective (leave out --robust for that)",
            )?;
            Some(Robust { tolerances: t, ..r })
        }
        None => None,
    };
    let mut problem = Problem::new(scene);
    if opts.air {
        problem.set_air(DragConfig::default());
    }
    if let Some(r) = robust {
        problem.set_robust(r);
    }
    Ok(problem)
}

/// The solve itself, into a locked output folder; returns the solution it saved.
/// With `keep_previous`, an unfinished solve stops after saving its solution, so that the
/// pictures and exports of the previous complete one stay.
fn solve_into(
    opts: &Options,
    problem: &Problem,
    out: &Path,
    keep_previous: bool,
    mut clock: Clock,
) -> Result<Solution> {
    let scene = &problem.scene;
    let out = out.to_path_buf();
    let (resume_from, prior) = match start(opts, scene, &out)? {
        Start::Fresh => (None, Vec::new()),
        Start::Resume { from, prior } => (Some(from), prior),
        Start::Done(s) => return Ok(s),
    };
    install_interrupt_handler()?;
    let mut observer = SolveProgress::new(out.clone(), scene, &prior, opts.quiet)?;
    // A resumed solve keeps the seed it was started with.
    let seed = resume_from.as_ref().map(|s| s.seed).or(opts.seed);
    let options = SolveOptions {
        threads: opts.threads,
        seed,
        resume: resume_from,
        schedule: Schedule::DEFAULT.with_attempts(opts.attempts),
        time_limit: opts.time_limit,
        until_stage: None,
    };
    clock.lap("resume and output folder");
    if !opts.quiet {
        let cost = super::progress::cost_line(problem, &options.schedule, opts.threads);
        let limit = opts.time_limit.map_or(String::new(), |l| {
            format!(" (stopped at {:.1} s)", l.as_secs_f64())
        });
        eprintln!("{}: {cost}{limit}", scene.name);
    }
    let (solution, records) = solver::solve(problem, &options, &mut observer, &INTERRUPTS);
    // The solver's time, split: every attempt's stages (up to the last stage's end, the
    // attempts beside each other), and the rest (the summary and the per-phase profile
    // of one sample); then the wait for the files the stages left to write.
    let solving = clock.since_lap();
    let stages = observer.last_stage_end.map_or(0.0, |end| {
        end.saturating_duration_since(clock.lap)
            .as_secs_f64()
            .min(solving)
    });
    let waiting = observer
        .finish(&records)
        .context("while saving progress")?
        .as_secs_f64();
    clock.record("stages of every attempt (optimisation)", stages);
    clock.record("summary and per-phase profile", solving - stages);
    clock.record("waiting for the files of the stages", waiting);
    clock.restart_lap();
    // The table was saved after every stage; the plot is drawn once, at the end.
    files::write_solution(&out, &solution)?;
    let mut all = prior;
    all.extend(records);
    let plot = || files::write_convergence_plot(&out, &scene.name, &observer.stage_names, &all);
    clock.lap("solution");
    if keep_previous && solution.stages_completed < solution.stages_total {
        plot()?;
        return Ok(solution);
    }
    // The pictures and exports launch from where the solution does (free positions).
    // The plot, the pictures and exports, and what launcher it needs are drawn side by
    // side: each takes a tenth of a second or less, a tenth of a small solve, and the
    // plot and the pictures use one core each.
    let placed = placed_problem(problem, &solution);
    let problem = placed.as_ref().unwrap_or(problem);
    let (plotted, (pictures, needs)) = rayon::join(plot, || {
        rayon::join(
            || write_pictures_and_exports(&out, problem, &solution),
            || write_needs(&out, problem, &solution, opts.threads),
        )
    });
    plotted?;
    let written = pictures?;
    let needs = needs?;
    clock.lap("convergence plot, pictures, exports and what launcher it needs");
    let report = crate::output::report::write_report(&out, &solution)?;
    clock.lap("report page");
    print_summary(scene, problem, &solution, &out, &written);
    println!("{needs}");
    println!("report: {}", report.display());
    if opts.report {
        print_report(&solution, &clock);
    }
    Ok(solution)
}

/// Where a solve starts: afresh, after the stages a saved solution completed (with the
/// convergence records of those stages), or nowhere, every stage of the saved one done.
enum Start {
    Fresh,
    Resume {
        from: Solution,
        prior: Vec<SampleRecord>,
    },
    Done(Solution),
}

/// Where the solve starts: with `--resume`, the `solution.json` in `out`, checked to
/// belong to `scene` and to have been started with the same options.
fn start(opts: &Options, scene: &Scene, out: &Path) -> Result<Start> {
    if !opts.resume {
        return Ok(Start::Fresh);
    }
    let file = out.join("solution.json");
    let s = files::read_solution(&file).context(NotResumed(file.clone()))?;
    solution::check_resumable(scene, &s).context(NotResumed(file.clone()))?;
    // A resumed solve goes on as it was started: a different seed, or air or launch
    // errors for some stages only, would silently mix two solves in one record.
    let started = |what: String| {
        anyhow::anyhow!(
            "it was started {what}, and --resume goes on as it was started; pass the same options, or solve afresh (--force)"
        )
        .context(NotResumed(file.clone()))
    };
    if let Some(seed) = opts.seed.filter(|&x| x != s.seed) {
        return Err(started(format!("with seed {}, not --seed {seed}", s.seed)));
    }
    if opts.air != s.air.is_some() {
        let how = if opts.air {
            "in vacuum, not --air"
        } else {
            "with --air"
        };
        return Err(started(how.to_string()));
    }
    if opts.robust.is_some() != s.robust.is_some() {
        let how = if opts.robust.is_some() {
            "without launch errors, not --robust"
        } else {
            "with --robust"
        };
        return Err(started(how.to_string()));
    }
    if s.stages_completed >= s.stages_total {
        eprintln!(
            "{}: all {} stages are done already; nothing to resume",
            file.display(),
            s.stages_total
        );
        return Ok(Start::Done(s));
    }
    let mut prior = Vec::new();
    let conv = out.join("convergence.csv");
    if conv.exists() {
        prior = files::read_convergence(&conv, s.stages_completed)?;
    }
    eprintln!(
        "resuming after stage {}/{}",
        s.stages_completed, s.stages_total
    );
    Ok(Start::Resume { from: s, prior })
}

/// Count Ctrl-C presses in [`INTERRUPTS`], saying what each one does. With ctrlc's
/// "termination" feature this handles SIGTERM (and SIGHUP) like Ctrl-C.
fn install_interrupt_handler() -> Result<()> {
    ctrlc::set_handler(|| {
        let n = INTERRUPTS.fetch_add(1, Ordering::SeqCst) + 1;
        if n == 1 {
            eprintln!("\ninterrupt: ending this stage (press Ctrl-C again to stop and save the best so far)");
        } else {
            eprintln!("\ninterrupt: stopping and saving the best so far");
        }
    })
    .context("cannot install the Ctrl-C handler")
}

/// The summary of a finished solve: the IoU, the contacts and the work, the attempts,
/// the files written, shadows beyond the picture, the instants' IoUs and the exports.
/// `scene` is the scene as loaded, `problem` the one placed at the solution's positions.
fn print_summary(
    scene: &Scene,
    problem: &Problem,
    solution: &Solution,
    out: &Path,
    written: &Written,
) {
    let Written {
        frame_ious,
        more,
        exported,
        outside,
    } = written;
    println!(
        "{}: {} {:.4}, {} before {} ({} contacts), {} samples in {} iterations, {:.2} s on {} threads{}",
        scene.name,
        if scene.single_instant() {
            "IoU at t"
        } else {
            "worst IoU of the instants"
        },
        solution.iou,
        if solution.n_contacts == 0 {
            "no contact".to_string()
        } else {
            format!("first contact at {:.4} s", solution.t_sim)
        },
        match scene.hold {
            Some(_) => format!("{} s (the end of the hold window)", scene.horizon()),
            None => "t".to_string(),
        },
        solution.n_contacts,
        solution.samples,
        solution.iterations,
        solution.wall_time_s,
        solution.threads,
        if solution.complete { "" } else { " (stopped early)" }
    );
    if solution.attempts.len() > 1 {
        let each: Vec<String> = solution
            .attempts
            .iter()
            .map(|a| format!("{}{}", a.describe(), if a.kept { " (kept)" } else { "" }))
            .collect();
        println!("{} attempts: {}", solution.attempts.len(), each.join(", "));
    }
    println!(
        "wrote {}/{{solution.json, convergence.csv, convergence.png, convergence.svg, shadow.png, overlay.png, preview.png{}}}",
        out.display(),
        more.iter().map(|m| format!(", {m}")).collect::<String>()
    );
    if !outside.is_empty() {
        // A shadow beyond the picture counts as extra shadow up to the canvas's margin
        // and costs nothing farther out: a body that fits nowhere may end out there.
        // Say so rather than let the IoU alone speak.
        let (what, verb) = if outside.len() == 1 {
            ("shadow", "reaches")
        } else {
            ("shadows", "reach")
        };
        println!(
            "note: at t the {what} of {} {verb} beyond the picture; the IoU counts the part beyond it as extra shadow, up to {} px from its edges",
            outside.join(", "),
            problem.margin
        );
    }
    frames::print(problem, frame_ious);
    println!("{exported}");
}

/// The problem that launches from the solution's positions, when they were free
/// variables (`None`: the scene's positions, `problem` itself).
fn placed_problem(problem: &Problem, solution: &Solution) -> Option<Problem> {
    problem
        .plan
        .free_positions
        .then(|| load::problem_for(problem.scene.clone(), solution))
}

/// Write shadow.png, overlay.png, preview.png, the pictures of the later instants and
/// (with `problem` placed at the solution's launch positions) the exports (glb, launch
/// and trajectory tables).
fn write_pictures_and_exports(
    out: &Path,
    problem: &Problem,
    solution: &Solution,
) -> Result<Written> {
    let scene = &problem.scene;
    let mut ws = problem.workspace();
    let params = solution.parameters();
    problem.evaluate(&params, &Weights::all_ones(), &mut ws);
    let outside = if scene.single_instant() {
        frames::outside_names(problem, &ws)
    } else {
        Vec::new()
    };
    let title = format!("{}: shadow at t = {} s", scene.name, scene.t);
    let shadow = problem.picture_of(&ws.mask);
    files::write_pictures(out, &scene.target, &shadow, &title)?;
    files::write_preview(out, &scene.target, &shadow)?;
    let frame_ious = if scene.single_instant() {
        Vec::new()
    } else {
        problem.frame_ious(&params, &mut ws)
    };
    let more = frames::write_pictures(out, problem, &frame_ious, &mut ws)?;
    let (exported, _) = export::write_exports(
        out,
        problem,
        solution,
        crate::output::trajectory::DEFAULT_MAX_AFTER,
    )?;
    Ok(Written {
        frame_ious,
        more,
        exported,
        outside,
    })
}

/// What [`write_pictures_and_exports`] wrote and found.
struct Written {
    /// The IoU of each instant (empty for a single instant).
    frame_ious: Vec<FrameIou>,
    /// The names of the extra pictures.
    more: Vec<String>,
    /// The exports' summary line.
    exported: String,
    /// The occluders whose shadows at `t` reach beyond the picture (single instant only).
    outside: Vec<String>,
}

/// Where the wall time of `bsa solve` went, phase by phase in the order they run.
struct Clock {
    start: std::time::Instant,
    lap: std::time::Instant,
    phases: Vec<(&'static str, f64)>,
}

impl Clock {
    fn new() -> Clock {
        let now = std::time::Instant::now();
        Clock {
            start: now,
            lap: now,
            phases: Vec::new(),
        }
    }

    /// Seconds since the last lap.
    fn since_lap(&self) -> f64 {
        self.lap.elapsed().as_secs_f64()
    }

    /// Close the current phase under `name`.
    fn lap(&mut self, name: &'static str) {
        let s = self.since_lap();
        self.record(name, s);
        self.restart_lap();
    }

    fn record(&mut self, name: &'static str, seconds: f64) {
        self.phases.push((name, seconds));
    }

    fn restart_lap(&mut self) {
        self.lap = std::time::Instant::now();
    }
}

/// What launcher `solution` needs ([`crate::budget::needs`]), written to `out/launcher.json`
/// and `out/launcher.md` (which the report page shows); returns the line to print.
fn write_needs(
    out: &Path,
    problem: &Problem,
    solution: &Solution,
    threads: Option<usize>,
) -> Result<String> {
    let needs = crate::budget::needs(problem, &solution.parameters(), solution.seed, threads)?;
    files::write_atomic(
        &out.join("launcher.json"),
        serde_json::to_string_pretty(&needs)?.as_bytes(),
    )?;
    let md = format!("# What launcher it needs\n\n{}", needs.markdown());
    files::write_atomic(&out.join("launcher.md"), md.as_bytes())?;
    let all = md.lines().last().unwrap_or_default();
    Ok(format!(
        "launcher it needs (P(IoU >= {:.3}) >= {:.0} %, in {}/launcher.md): {}",
        needs.threshold,
        100.0 * needs.probability,
        out.display(),
        all.trim_start_matches("All together: ")
    ))
}

/// The performance report of `--report`.
fn print_report(s: &Solution, clock: &Clock) {
    println!("\nPerformance (as the paper's Tables 3 and 4)");
    let n = s.stages.len().max(1) as f64;
    println!("  stages               {}", s.stages.len());
    println!("  total iterations     {}", s.iterations);
    println!("  average iterations   {:.2}", s.iterations as f64 / n);
    println!("  total samples        {}", s.samples);
    println!("  average samples      {:.1}", s.samples as f64 / n);
    println!(
        "  total running time   {:.2} s ({} threads)",
        s.wall_time_s, s.threads
    );
    println!("  time per sample phase (one core, microseconds):");
    // In the order a sample runs them (solution.json keeps them sorted by name).
    let mut phases: Vec<_> = s.time_per_term_us.iter().collect();
    phases.sort_by_key(|(k, _)| {
        crate::evaluate::PROFILE_PHASES
            .iter()
            .position(|p| p == k)
            .unwrap_or(usize::MAX)
    });
    for (k, v) in phases {
        println!("    {k:<26} {v:>10.2}");
    }
    println!("  wall time of this command by phase (s):");
    for (name, secs) in &clock.phases {
        println!("    {name:<36} {secs:>7.3}");
    }
    println!(
        "    {:<36} {:>7.3}",
        "total (to this report)",
        clock.start.elapsed().as_secs_f64()
    );
}
