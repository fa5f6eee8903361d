//! The `bsa` command line: argument parsing and the subcommands.
//!
//! Subcommands: `check` (validate a scene and print a summary), `solve` (optimise and
//! write `export/<scene>/`), `eval` (print every energy term of a saved solution),
//! `export` (animated glTF and launch tables of a saved solution), `validate` (Blender
//! Cycles shadow against the rasterizer), `video` (an MP4 of the flight) and `budget`
//! (air drag, the drag-compensated launch table and launch tolerances). `validate`
//! and `video` run the scripts of `blender/` with a Python that has `bpy`.
//! This is the only module that uses `anyhow`, prints, draws progress bars or installs
//! the Ctrl-C handler; library modules return typed errors.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::energy::{Term, Weights};
use crate::evaluate::Problem;
use crate::geometry::shape::Shape;
use crate::optimize::solver::{self, IterationInfo, Observer, SolveOptions};
use crate::output::files;
use crate::output::solution::{self, SampleRecord, Solution};
use crate::scene::{self, Scene, Stage, Strategy};

#[derive(Parser)]
#[command(
    name = "bsa",
    version,
    about = "Ballistic shadow art: launch objects so that their shadows form a picture at one instant"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a scene and print a summary.
    Check {
        /// Scene folder (holding scene.json) or scene file.
        scene: PathBuf,
    },
    /// Optimise launch velocities and write solution.json, shadow.png, overlay.png,
    /// convergence.csv and convergence.png.
    Solve {
        /// Scene folder (holding scene.json) or scene file.
        scene: PathBuf,
        /// Output folder [default: export/<scene name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Random seed (overrides the scene's).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads [default: one per core].
        #[arg(long)]
        threads: Option<usize>,
        /// Continue from the output folder's solution.json (skips its completed stages).
        #[arg(long)]
        resume: bool,
        /// Print the performance report (stages, iterations, samples, time per term).
        #[arg(long)]
        report: bool,
        /// No progress bars.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Write the animated glTF (<scene>.glb), launch.csv and trajectory.csv of a saved solution.
    Export {
        /// Output folder of a solve (holding solution.json).
        dir: PathBuf,
        /// Scene folder or file [default: the one recorded in solution.json, else scenes/<name>].
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Seconds of rapier continuation after t.
        #[arg(long, default_value_t = crate::output::trajectory::DEFAULT_AFTER)]
        after: f64,
    },
    /// Render the shadow at t with Blender Cycles and compare it with the rasterizer (IoU, XOR).
    Validate {
        /// Output folder of a solve or export (holding solution.json and <scene>.glb).
        dir: PathBuf,
        /// Scene folder or file [default: as for `export`].
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Python with the `bpy` module [default: $BSA_PYTHON, else .venv-blender/bin/python].
        #[arg(long)]
        python: Option<PathBuf>,
    },
    /// Render an MP4 of the flight with Blender from the perspective camera.
    Video {
        /// Output folder of a solve or export (holding solution.json and <scene>.glb).
        dir: PathBuf,
        /// Output file [default: DIR/<scene>.mp4].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Cycles samples per pixel.
        #[arg(long, default_value_t = 4)]
        samples: u32,
        /// Frame size in pixels.
        #[arg(long, default_value_t = 640)]
        width: u32,
        #[arg(long, default_value_t = 480)]
        height: u32,
        /// Render only the first SECONDS of the animation.
        #[arg(long)]
        seconds: Option<f64>,
        /// Python with the `bpy` module [default: $BSA_PYTHON, else .venv-blender/bin/python].
        #[arg(long)]
        python: Option<PathBuf>,
    },
    /// Error budget of a saved solution: re-simulation with air drag, drag-compensated
    /// launch table (launch_drag.csv), Monte Carlo of launch errors, sensitivities and
    /// the largest tolerances; writes budget.md, budget.json and two PNG plots.
    Budget {
        /// Output folder of a solve (holding solution.json), or the solution.json itself.
        path: PathBuf,
        /// Scene folder or file [default: the one recorded in solution.json, else scenes/<name>].
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Monte Carlo samples at the requested tolerances.
        #[arg(long, default_value_t = 10_000)]
        samples: usize,
        /// Samples per evaluation of the tolerance search (0: skip the search).
        #[arg(long, default_value_t = 2_000)]
        search_samples: usize,
        /// Random seed of the Monte Carlo (the report is identical for a seed whatever the threads).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Worker threads [default: one per core].
        #[arg(long)]
        threads: Option<usize>,
        /// Air density (kg/m^3).
        #[arg(long, default_value_t = crate::sim::drag::AIR_DENSITY, allow_negative_numbers = true)]
        rho: f64,
        /// Drag coefficient for every body [default: sphere 0.47, box 1.05, mesh 1.0].
        #[arg(long, allow_negative_numbers = true)]
        cd: Option<f64>,
        /// Magnus lift on spinning spheres.
        #[arg(long)]
        magnus: bool,
        /// Launch speed error, 1 sigma (% of the speed).
        #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
        speed_tol: f64,
        /// Launch direction error, 1 sigma per perpendicular component (deg).
        #[arg(long, default_value_t = 0.25, allow_negative_numbers = true)]
        direction_tol: f64,
        /// Spin rate error, 1 sigma (% of the angular speed).
        #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
        spin_tol: f64,
        /// Release timing error, 1 sigma (ms).
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        timing_tol: f64,
        /// Drag coefficient error, 1 sigma (% of Cd).
        #[arg(long, default_value_t = 5.0, allow_negative_numbers = true)]
        cd_tol: f64,
        /// IoU a sample must reach to count as a success, in (0, 1]: the Monte Carlo
        /// reports P(IoU >= X) and the tolerance search keeps it >= 95 %.
        #[arg(long, value_name = "X", default_value_t = crate::budget::IOU_THRESHOLD, allow_negative_numbers = true)]
        iou_threshold: f64,
        /// No progress bars.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Print every energy term of a solution, raw and weighted.
    Eval {
        /// Scene folder (holding scene.json) or scene file.
        scene: PathBuf,
        /// The solution.json to evaluate.
        #[arg(long)]
        solution: PathBuf,
        /// Weights of this stage (1-based) [default: the last stage].
        #[arg(long)]
        stage: Option<usize>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Also time each phase of one sample on one core (microseconds, averaged over
        /// this many repetitions), as the paper's Table 4.
        #[arg(long, value_name = "REPS")]
        profile: Option<usize>,
    },
}

/// Run the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Check { scene } => check(&scene),
        Command::Solve {
            scene,
            out,
            seed,
            threads,
            resume,
            report,
            quiet,
        } => solve(&scene, out, seed, threads, resume, report, quiet),
        Command::Eval {
            scene,
            solution,
            stage,
            json,
            profile,
        } => eval(&scene, &solution, stage, json, profile),
        Command::Export { dir, scene, after } => {
            let (problem, solution) = load_solution_dir(&dir, scene.as_deref())?;
            if !(after.is_finite() && after >= 0.0) {
                bail!("--after must be a non-negative number of seconds, got {after}");
            }
            let msg = write_exports(&dir, &problem, &solution, after)?;
            println!("{msg}");
            Ok(())
        }
        Command::Budget {
            path,
            scene,
            samples,
            search_samples,
            seed,
            threads,
            rho,
            cd,
            magnus,
            speed_tol,
            direction_tol,
            spin_tol,
            timing_tol,
            cd_tol,
            iou_threshold,
            quiet,
        } => {
            let mut drag = crate::sim::drag::DragConfig {
                rho,
                magnus,
                ..Default::default()
            };
            if let Some(cd) = cd {
                drag = drag.with_cd(cd);
            }
            let opts = crate::budget::BudgetOptions {
                drag,
                tolerances: crate::budget::Tolerances {
                    speed_pct: speed_tol,
                    direction_deg: direction_tol,
                    spin_pct: spin_tol,
                    timing_ms: timing_tol,
                    cd_pct: cd_tol,
                },
                samples,
                search_samples,
                seed,
                threads,
                iou_threshold,
            };
            budget(&path, scene.as_deref(), &opts, quiet)
        }
        Command::Validate { dir, scene, python } => validate(&dir, scene.as_deref(), python),
        Command::Video {
            dir,
            out,
            samples,
            width,
            height,
            seconds,
            python,
        } => video(&dir, out, samples, width, height, seconds, python),
    }
}

fn load_scene(path: &Path) -> Result<Scene> {
    scene::load(path).with_context(|| format!("invalid scene {}", path.display()))
}

fn fmt_vec(v: glam::DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

fn check(path: &Path) -> Result<()> {
    let s = load_scene(path)?;
    println!("scene `{}` ({})", s.name, s.source.display());
    println!(
        "  target   {} x {} px, {} shadow pixels ({:.1}%)",
        s.target.width(),
        s.target.height(),
        s.target.count(),
        100.0 * s.target.count() as f64 / (s.target.width() * s.target.height()) as f64
    );
    println!(
        "  t        {} s, timestep {:.5} s, gravity {}",
        s.t,
        s.dt,
        fmt_vec(s.gravity)
    );
    println!("  light    {}", fmt_vec(s.light));
    let r = &s.receiver;
    println!(
        "  receiver centre {}, u {}, v {}, {} m x {} m ({:.4} m/px)",
        fmt_vec(r.center),
        fmt_vec(r.u),
        fmt_vec(r.v),
        r.width,
        r.height,
        r.width / s.target.width() as f64
    );
    match &s.table {
        Some(t) => println!(
            "  table    top at z = {:.3} m, centre {}, size {}",
            t.top(),
            fmt_vec(t.center),
            fmt_vec(t.half_extents * 2.0)
        ),
        None => println!("  table    none"),
    }
    println!("  occluders ({}):", s.occluders.len());
    for o in &s.occluders {
        let shape = match &o.shape {
            Shape::Sphere { radius } => format!("sphere r {radius} m"),
            Shape::Cuboid { half_extents } => format!("box {}", fmt_vec(*half_extents * 2.0)),
            Shape::Mesh(m) => format!(
                "mesh {} vertices, {} triangles",
                m.vertices.len(),
                m.triangles.len()
            ),
        };
        println!(
            "    {:<12} {:<34} {:>8.4} kg  at {}  {}",
            o.name,
            shape,
            o.mass.mass,
            fmt_vec(o.position),
            if o.launched { "launched" } else { "stays put" }
        );
    }
    println!("  hints    {}", s.hints.len());
    match &s.strategy {
        Strategy::Scheduled => println!("  strategy scheduled, {} stages", s.stages.len()),
        Strategy::Sequential { order } => println!(
            "  strategy sequential: {}",
            order
                .iter()
                .map(|&i| s.occluders[i].name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
    for (k, st) in s.stages.iter().enumerate() {
        let w: Vec<String> = Term::ALL
            .iter()
            .filter(|t| st.weights.uses(**t))
            .map(|t| format!("{}={}", t.key(), st.weights.get(*t)))
            .collect();
        println!(
            "    stage {} `{}`: vary {}, step {}, population {}, max {} iterations; weights {}",
            k + 1,
            st.name,
            st.vary.len(),
            st.step,
            st.population,
            st.max_iterations,
            w.join(" ")
        );
    }
    println!("  seed     {}", s.seed);
    // The start guess is where every stage's search begins: say how it looks, and name a
    // contact in it, since a start that collides is a slow start.
    let problem = Problem::new(s.clone());
    let mut ws = problem.workspace();
    let e = problem.evaluate(&s.start_parameters(), &Weights::all_ones(), &mut ws);
    match e.outcome.first_contact {
        Some((i, j)) => println!(
            "  start    IoU at t {:.4}; first contact at {:.4} s: `{}` with `{}`",
            e.iou,
            e.outcome.t_sim,
            s.occluders[i].name,
            j.map_or("table", |j| s.occluders[j].name.as_str())
        ),
        None => println!("  start    IoU at t {:.4}; no contact before t", e.iou),
    }
    println!("ok");
    Ok(())
}

static INTERRUPTS: AtomicUsize = AtomicUsize::new(0);

struct CliObserver {
    out: PathBuf,
    target: crate::shadow::mask::Mask,
    stage_names: Vec<String>,
    prior: Vec<SampleRecord>,
    bar: Option<ProgressBar>,
    quiet: bool,
    last_preview: Instant,
    stages_total: usize,
    error: Option<anyhow::Error>,
}

impl Observer for CliObserver {
    fn stage_started(&mut self, index: usize, stage: &Stage) {
        let bar = ProgressBar::new(stage.max_iterations as u64);
        if self.quiet {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        bar.set_style(
            ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} it {msg}")
                .expect("static template")
                .progress_chars("=> "),
        );
        bar.set_prefix(format!(
            "stage {}/{} {}",
            index + 1,
            self.stages_total,
            stage.name
        ));
        self.bar = Some(bar);
    }

    fn iteration(&mut self, info: &IterationInfo) {
        if let Some(bar) = &self.bar {
            bar.set_position(info.iteration as u64);
            bar.set_message(format!(
                "| {:.0} samples/s | best {:.4e} | IoU {:.4}",
                info.samples_per_second, info.best_energy, info.best_iou
            ));
        }
        // The preview is refreshed at most ten times a second: encoding a PNG every
        // iteration would cost more than the optimisation itself on small scenes.
        if self.last_preview.elapsed().as_secs_f64() >= 0.1 {
            self.last_preview = Instant::now();
            if let Err(e) = files::write_preview(&self.out, &self.target, info.best_shadow) {
                self.error.get_or_insert(e.into());
            }
        }
    }

    fn stage_finished(&mut self, s: &Solution, records: &[SampleRecord]) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        if let Some(r) = s.stages.last() {
            eprintln!(
                "stage {}/{} `{}`: {} iterations, {} samples, best energy {:.4e}, IoU {:.4}, {:.2} s ({})",
                s.stages_completed, s.stages_total, r.name, r.iterations, r.samples, r.best_energy, r.iou, r.wall_time_s, r.stop
            );
        }
        let mut all = self.prior.clone();
        all.extend_from_slice(records);
        let res = files::write_solution(&self.out, s)
            .and_then(|_| files::write_convergence(&self.out, &self.stage_names, &all));
        if let Err(e) = res {
            self.error.get_or_insert(e.into());
        }
    }
}

fn solve(
    path: &Path,
    out: Option<PathBuf>,
    seed: Option<u64>,
    threads: Option<usize>,
    resume: bool,
    report: bool,
    quiet: bool,
) -> Result<()> {
    let scene = load_scene(path)?;
    let out = out.unwrap_or_else(|| PathBuf::from("export").join(&scene.name));
    if let Some(n) = threads {
        if !(1..=1024).contains(&n) {
            bail!("--threads must be between 1 and 1024, got {n}");
        }
    }
    let problem = Problem::new(scene);
    let scene = &problem.scene;
    let mut prior = Vec::new();
    let resume_from = if resume {
        let file = out.join("solution.json");
        let s = files::read_solution(&file)
            .with_context(|| format!("cannot resume from {}", out.display()))?;
        solution::check_resumable(scene, &s)
            .with_context(|| format!("cannot resume from {}", file.display()))?;
        if s.stages_completed >= s.stages_total {
            eprintln!(
                "{}: all {} stages are done already; nothing to resume",
                file.display(),
                s.stages_total
            );
            return Ok(());
        }
        let conv = out.join("convergence.csv");
        if conv.exists() {
            prior = files::read_convergence(&conv, s.stages_completed)?;
        }
        eprintln!(
            "resuming after stage {}/{}",
            s.stages_completed, s.stages_total
        );
        Some(s)
    } else {
        None
    };
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    ctrlc::set_handler(|| {
        let n = INTERRUPTS.fetch_add(1, Ordering::SeqCst) + 1;
        if n == 1 {
            eprintln!("\ninterrupt: ending this stage (press Ctrl-C again to stop and save the best so far)");
        } else {
            eprintln!("\ninterrupt: stopping and saving the best so far");
        }
    })
    .context("cannot install the Ctrl-C handler")?;
    let mut observer = CliObserver {
        out: out.clone(),
        target: scene.target.clone(),
        stage_names: scene.stages.iter().map(|s| s.name.clone()).collect(),
        prior: prior.clone(),
        bar: None,
        quiet,
        last_preview: Instant::now() - std::time::Duration::from_secs(1),
        stages_total: scene.stages.len(),
        error: None,
    };
    // A resumed solve keeps the seed it was started with.
    let seed = resume_from.as_ref().map(|s| s.seed).or(seed);
    let options = SolveOptions {
        threads,
        seed,
        resume: resume_from,
    };
    let (solution, records) = solver::solve(&problem, &options, &mut observer, &INTERRUPTS);
    if let Some(e) = observer.error.take() {
        return Err(e.context("while saving progress"));
    }
    let mut all = prior;
    all.extend(records);
    files::write_solution(&out, &solution)?;
    files::write_convergence(&out, &observer.stage_names, &all)?;
    let mut ws = problem.workspace();
    let params = solution.parameters();
    problem.evaluate(&params, &Weights::all_ones(), &mut ws);
    files::write_pictures(&out, &scene.target, &ws.mask)?;
    files::write_preview(&out, &scene.target, &ws.mask)?;
    let exported = write_exports(
        &out,
        &problem,
        &solution,
        crate::output::trajectory::DEFAULT_AFTER,
    )?;
    println!(
        "{}: IoU at t {:.4}, {} before t ({} contacts), {} samples in {} iterations, {:.2} s on {} threads{}",
        scene.name,
        solution.iou,
        if solution.n_contacts == 0 {
            "no contact".to_string()
        } else {
            format!("first contact at {:.4} s", solution.t_sim)
        },
        solution.n_contacts,
        solution.samples,
        solution.iterations,
        solution.wall_time_s,
        solution.threads,
        if solution.complete { "" } else { " (stopped early)" }
    );
    println!("{exported}");
    if report {
        print_report(&solution);
    }
    Ok(())
}

/// Load `DIR/solution.json` and its scene, and check that they belong together.
fn load_solution_dir(dir: &Path, scene: Option<&Path>) -> Result<(Problem, Solution)> {
    let file = dir.join("solution.json");
    let (problem, solution, scene_path) = load_solution_and_scene(dir, &file, scene)?;
    solution::check_solution(&problem.scene, &solution).with_context(|| {
        format!(
            "{} does not belong to the scene {} (pass the right one with --scene)",
            file.display(),
            scene_path.display()
        )
    })?;
    Ok((problem, solution))
}

/// Read the solution `file` (in the output folder `dir`) and load its scene: `scene` if
/// given, else the scene file it records, else `scenes/<its scene name>`. Does not check
/// that they belong together (the callers check in their own ways).
fn load_solution_and_scene(
    dir: &Path,
    file: &Path,
    scene: Option<&Path>,
) -> Result<(Problem, Solution, PathBuf)> {
    if !file.is_file() {
        bail!(
            "{} has no solution.json: run `bsa solve <scene> --out {}` first",
            dir.display(),
            dir.display()
        );
    }
    let solution = files::read_solution(file)?;
    let scene_path = match scene {
        Some(p) => p.to_path_buf(),
        None => solution
            .scene_file
            .as_ref()
            .map(PathBuf::from)
            .filter(|p| p.exists())
            .unwrap_or_else(|| PathBuf::from("scenes").join(&solution.scene)),
    };
    let problem = Problem::new(load_scene(&scene_path)?);
    Ok((problem, solution, scene_path))
}

/// `<scene>.glb`, `launch.csv` and `trajectory.csv`; returns a one-line summary.
fn write_exports(dir: &Path, problem: &Problem, solution: &Solution, after: f64) -> Result<String> {
    let params = solution.parameters();
    let track = crate::output::trajectory::track(problem, &params, after);
    let name = &problem.scene.name;
    let glb = crate::output::gltf::write_glb(&problem.scene, &track)
        .context("cannot build the glTF file")?;
    files::write_atomic(&dir.join(format!("{name}.glb")), &glb)?;
    files::write_csv(
        &dir.join("launch.csv"),
        &crate::output::trajectory::launch_rows(problem, &params),
    )?;
    files::write_csv(
        &dir.join("trajectory.csv"),
        &crate::output::trajectory::trajectory_rows(problem, &track),
    )?;
    Ok(format!(
        "wrote {}/{{{name}.glb, launch.csv, trajectory.csv}}: {} keys, t = {} s at key {}",
        dir.display(),
        track.times.len(),
        problem.scene.t,
        track.t_index
    ))
}

/// The Python interpreter that has `bpy`: `--python`, else `$BSA_PYTHON`, else
/// `.venv-blender/bin/python` in the current folder or a parent.
fn blender_python(explicit: Option<PathBuf>) -> Result<PathBuf> {
    if let Some(p) = explicit.or_else(|| std::env::var_os("BSA_PYTHON").map(PathBuf::from)) {
        if !p.exists() {
            bail!("the Python interpreter {} does not exist", p.display());
        }
        return Ok(p);
    }
    let cwd = std::env::current_dir().context("cannot read the current folder")?;
    for dir in cwd.ancestors() {
        let p = dir.join(".venv-blender/bin/python");
        if p.exists() {
            return Ok(p);
        }
    }
    bail!(
        "no Python with Blender's bpy module found: run `bash blender/setup_venv.sh` (needs Python 3.11) \
         from the repository, or pass --python / set BSA_PYTHON"
    )
}

/// A script of the `blender/` folder, found next to the current folder or a parent.
fn blender_script(name: &str) -> Result<PathBuf> {
    let cwd = std::env::current_dir().context("cannot read the current folder")?;
    for dir in cwd.ancestors() {
        let p = dir.join("blender").join(name);
        if p.is_file() {
            return Ok(p);
        }
    }
    bail!("cannot find blender/{name}: run bsa from the repository (or a folder inside it)")
}

/// Run a Blender script and return the JSON of its `BSA_RESULT` line.
fn run_blender(python: &Path, script: &Path, args: &[String]) -> Result<serde_json::Value> {
    let out = std::process::Command::new(python)
        .arg(script)
        .arg("--")
        .args(args)
        .output()
        .with_context(|| format!("cannot run {}", python.display()))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("BSA_RESULT "));
    let value: Option<serde_json::Value> = line.and_then(|l| serde_json::from_str(l).ok());
    match value {
        Some(v) if out.status.success() && v.get("error").is_none() => Ok(v),
        Some(v) => bail!(
            "{} failed: {}",
            script.display(),
            v.get("error").unwrap_or(&v)
        ),
        None => {
            let err = String::from_utf8_lossy(&out.stderr);
            let tail: Vec<&str> = err.lines().rev().take(15).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            if err.contains("No module named 'bpy'") {
                bail!(
                    "{} has no bpy module: run `bash blender/setup_venv.sh`, or pass --python",
                    python.display()
                );
            }
            bail!(
                "{} failed ({}):\n{}",
                script.display(),
                out.status,
                tail.join("\n")
            )
        }
    }
}

fn glb_path(dir: &Path, problem: &Problem) -> Result<PathBuf> {
    let glb = dir.join(format!("{}.glb", problem.scene.name));
    if !glb.is_file() {
        bail!(
            "{} does not exist: run `bsa export {}` first",
            glb.display(),
            dir.display()
        );
    }
    crate::output::gltf::read_poses_at(
        &std::fs::read(&glb).with_context(|| format!("cannot read {}", glb.display()))?,
        0.0,
    )
    .with_context(|| {
        format!(
            "{} is not a valid glTF file from bsa: run `bsa export {}` again",
            glb.display(),
            dir.display()
        )
    })?;
    Ok(glb)
}

fn validate(dir: &Path, scene: Option<&Path>, python: Option<PathBuf>) -> Result<()> {
    let (problem, solution) = load_solution_dir(dir, scene)?;
    let glb = glb_path(dir, &problem)?;
    let python = blender_python(python)?;
    let script = blender_script("render_shadow.py")?;
    let mask_path = dir.join("cycles_mask.png");
    let result = run_blender(
        &python,
        &script,
        &[
            "--glb".into(),
            glb.display().to_string(),
            "--out".into(),
            mask_path.display().to_string(),
        ],
    )?;
    let target = &problem.scene.target;
    let img = image::open(&mask_path)
        .with_context(|| format!("cannot read the Cycles mask {}", mask_path.display()))?
        .to_luma8();
    if (img.width() as usize, img.height() as usize) != (target.width(), target.height()) {
        bail!(
            "the Cycles mask is {}x{}, the target {}x{}",
            img.width(),
            img.height(),
            target.width(),
            target.height()
        );
    }
    let cycles = crate::shadow::mask::Mask::from_fn(target.width(), target.height(), |x, y| {
        img.get_pixel(x as u32, y as u32).0[0] < 128
    });
    let mut ws = problem.workspace();
    problem.evaluate(&solution.parameters(), &Weights::all_ones(), &mut ws);
    let ours = &ws.mask;
    let iou = crate::energy::iou(&cycles, ours);
    let xor = cycles.xor_count(ours);
    let diff = crate::output::picture::difference_image(
        target.width(),
        target.height(),
        &|x, y| cycles.get(x, y),
        &|x, y| ours.get(x, y),
    );
    files::save_png(&diff, &dir.join("validate_diff.png"))?;
    let report = serde_json::json!({
        "scene": problem.scene.name,
        "iou": iou,
        "xor_pixels": xor,
        "cycles_shadow_pixels": cycles.count(),
        "rasterizer_shadow_pixels": ours.count(),
        "cycles_mask": mask_path.display().to_string(),
        "difference_image": dir.join("validate_diff.png").display().to_string(),
        "blender": result,
    });
    files::write_atomic(
        &dir.join("validate.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    println!(
        "{}: Cycles vs rasterizer at t: IoU {:.5}, {} XOR pixels ({} vs {} shadow pixels); difference image {} (black both, red Cycles only, blue rasterizer only)",
        problem.scene.name,
        iou,
        xor,
        cycles.count(),
        ours.count(),
        dir.join("validate_diff.png").display()
    );
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn video(
    dir: &Path,
    out: Option<PathBuf>,
    samples: u32,
    width: u32,
    height: u32,
    seconds: Option<f64>,
    python: Option<PathBuf>,
) -> Result<()> {
    let (problem, _) = load_solution_dir(dir, None)?;
    let glb = glb_path(dir, &problem)?;
    if samples == 0 || width < 16 || height < 16 {
        bail!("--samples must be at least 1 and the frame at least 16x16 pixels");
    }
    let python = blender_python(python)?;
    let script = blender_script("render_video.py")?;
    let out = out.unwrap_or_else(|| dir.join(format!("{}.mp4", problem.scene.name)));
    let mut args = vec![
        "--glb".to_string(),
        glb.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--samples".into(),
        samples.to_string(),
        "--width".into(),
        width.to_string(),
        "--height".into(),
        height.to_string(),
    ];
    if let Some(s) = seconds {
        if !(s.is_finite() && s > 0.0) {
            bail!("--seconds must be positive, got {s}");
        }
        args.extend(["--seconds".into(), s.to_string()]);
    }
    let result = run_blender(&python, &script, &args)?;
    println!("wrote {} ({})", out.display(), result);
    Ok(())
}

fn print_report(s: &Solution) {
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
    for (k, v) in &s.time_per_term_us {
        println!("    {k:<26} {v:>10.2}");
    }
}

fn eval(
    scene_path: &Path,
    solution_path: &Path,
    stage: Option<usize>,
    json: bool,
    profile: Option<usize>,
) -> Result<()> {
    let scene = load_scene(scene_path)?;
    let problem = Problem::new(scene);
    let s = files::read_solution(solution_path)?;
    solution::check_solution(&problem.scene, &s)
        .with_context(|| format!("{} does not match the scene", solution_path.display()))?;
    let scene = &problem.scene;
    let k = match stage {
        None => scene.stages.len(),
        Some(k) if (1..=scene.stages.len()).contains(&k) => k,
        Some(k) => bail!(
            "--stage {k} is out of range: the scene has stages 1 to {}",
            scene.stages.len()
        ),
    };
    let weights = scene.stages[k - 1].weights;
    let mut ws = problem.workspace();
    let e = problem.evaluate(&s.parameters(), &Weights::all_ones(), &mut ws);
    let mut total = 0.0;
    let rows: Vec<(Term, f64, f64, f64)> = Term::ALL
        .iter()
        .map(|&t| {
            let raw = e.raw[t as usize];
            let w = weights.get(t);
            total += raw * w;
            (t, raw, w, raw * w)
        })
        .collect();
    let first_contact = e.outcome.first_contact.map(|(i, j)| {
        let a = scene.occluders[i].name.clone();
        let b = j.map_or_else(|| "table".to_string(), |j| scene.occluders[j].name.clone());
        (a, b)
    });
    let outside: Vec<&str> = problem
        .shadows_in_image(&ws)
        .iter()
        .zip(&scene.occluders)
        .filter(|(inside, _)| !**inside)
        .map(|(_, o)| o.name.as_str())
        .collect();
    let timings = match profile {
        Some(reps) => problem.profile(&s.parameters(), reps.max(1), &mut ws),
        None => Vec::new(),
    };
    if json {
        let terms: serde_json::Map<String, serde_json::Value> = rows
            .iter()
            .map(|(t, raw, w, wt)| {
                (
                    t.key().to_string(),
                    serde_json::json!({"raw": raw, "weight": w, "weighted": wt}),
                )
            })
            .collect();
        let v = serde_json::json!({
            "scene": scene.name,
            "stage": k,
            "terms": terms,
            "total": total,
            "iou": e.iou,
            "t_sim": e.outcome.t_sim,
            "n_contacts": e.outcome.n_contacts,
            "first_contact": first_contact.as_ref().map(|(a, b)| [a, b]),
            "shadows_outside_image": outside,
            "time_per_phase_us": timings.iter().map(|(k, v)| (k.clone(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "scene `{}`, weights of stage {} `{}`",
            scene.name,
            k,
            scene.stages[k - 1].name
        );
        println!(
            "{:<16} {:>14} {:>10} {:>14}",
            "term", "raw", "weight", "weighted"
        );
        for (t, raw, w, wt) in &rows {
            println!("{:<16} {:>14.6} {:>10} {:>14.6}", t.label(), raw, w, wt);
        }
        println!("{:<16} {:>14} {:>10} {:>14.6}", "total", "", "", total);
        println!(
            "IoU at t {:.5}; t_sim {:.5} s; contacts {}",
            e.iou, e.outcome.t_sim, e.outcome.n_contacts
        );
        if let Some((a, b)) = &first_contact {
            println!("first contact: `{a}` with `{b}`");
        }
        if outside.is_empty() {
            println!(
                "every occluder's shadow lies in the image ({} occluders)",
                scene.occluders.len()
            );
        } else {
            println!("shadows leaving the image: {}", outside.join(", "));
        }
        if !timings.is_empty() {
            println!("time per sample phase (one core, microseconds):");
            for (k, v) in &timings {
                println!("  {k:<26} {v:>10.2}");
            }
        }
    }
    Ok(())
}

/// Progress bars of the budget's long phases.
struct BudgetBars {
    bar: std::sync::Mutex<Option<ProgressBar>>,
    quiet: bool,
}

impl crate::budget::Progress for BudgetBars {
    fn start(&self, phase: &str, total: u64) {
        let bar = ProgressBar::new(total);
        if self.quiet {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        bar.set_style(
            ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {per_sec} eta {eta}")
                .expect("static template")
                .progress_chars("=> "),
        );
        bar.set_prefix(phase.to_string());
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }
    fn advance(&self, n: u64) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}

fn budget(
    path: &Path,
    scene: Option<&Path>,
    opts: &crate::budget::BudgetOptions,
    quiet: bool,
) -> Result<()> {
    use crate::budget;
    use crate::output::picture::{self, Series};
    let (dir, file) = if path.is_file() {
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        (dir.to_path_buf(), path.to_path_buf())
    } else {
        (path.to_path_buf(), path.join("solution.json"))
    };
    let (problem, solution, scene_path) = load_solution_and_scene(&dir, &file, scene)?;
    budget::check_solution_current(&problem, &solution).with_context(|| {
        format!(
            "{} does not belong to the scene {} (pass the right one with --scene)",
            file.display(),
            scene_path.display()
        )
    })?;
    budget::validate_options(&problem, opts).context("invalid budget options")?;
    let bars = BudgetBars {
        bar: std::sync::Mutex::new(None),
        quiet,
    };
    let start = Instant::now();
    let run = budget::run(&problem, &solution.parameters(), opts, &bars)?;
    let elapsed = start.elapsed().as_secs_f64();
    let r = &run.report;

    // launch_drag.csv: the launch table of the compensated launch, its pose at t with drag.
    let mut rows = crate::output::trajectory::launch_rows(&problem, &run.compensated);
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
        opts.threads
            .unwrap_or_else(|| std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1))
    ));
    files::write_atomic(&dir.join("budget.md"), md.as_bytes())?;
    let h = &r.histogram;
    let hist = picture::histogram_plot(
        &format!("{}: IoU at t, {} samples", r.scene, r.monte_carlo.samples),
        &format!(
            "IoU (red: {}; P(IoU >= {}) = {:.1} %)",
            r.iou_threshold,
            r.iou_threshold,
            100.0 * r.monte_carlo.p_iou_at_least_threshold
        ),
        h.lo,
        h.hi,
        &h.counts,
        Some(r.iou_threshold),
        640,
        400,
    );
    files::save_png(&hist, &dir.join("budget_hist.png"))?;
    if let Some(se) = &r.search {
        let panels: Vec<image::RgbImage> = se
            .single
            .iter()
            .map(|p| {
                let pts = |f: &dyn Fn(&budget::CurvePoint) -> f64| {
                    p.curve.iter().map(|c| (c.size, f(c))).collect()
                };
                picture::line_plot(
                    &format!("{} error alone", p.parameter),
                    &format!("1 sigma ({})", p.unit),
                    "IoU / probability",
                    &[
                        Series {
                            name: "mean IoU".into(),
                            color: picture::BLUE,
                            points: pts(&|c| c.mean),
                        },
                        Series {
                            name: "5th pct IoU".into(),
                            color: image::Rgb([44, 160, 44]),
                            points: pts(&|c| c.p5),
                        },
                        Series {
                            name: format!("P(IoU>={})", r.iou_threshold),
                            color: picture::RED,
                            points: pts(&|c| c.p_iou_at_least_threshold),
                        },
                    ],
                    (0.0, 1.0),
                    Some(p.largest),
                    380,
                    300,
                )
            })
            .collect();
        let refs: Vec<&image::RgbImage> = panels.iter().collect();
        files::save_png(
            &picture::side_by_side(&refs, 0),
            &dir.join("budget_tolerances.png"),
        )?;
    } else {
        // No search this time: a plot left by an earlier run would not match budget.json.
        let stale = dir.join("budget_tolerances.png");
        if stale.is_file() {
            std::fs::remove_file(&stale)
                .with_context(|| format!("removing the stale {}", stale.display()))?;
        }
    }

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
        m.samples, t.speed_pct, t.direction_deg, t.spin_pct, t.timing_ms, t.cd_pct, m.mean, m.p5, r.iou_threshold, 100.0 * m.p_iou_at_least_threshold
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
            r.iou_threshold,
            100.0 * r.probability_target,
            alone.join(", "),
            se.joint_scale
        );
    }
    println!(
        "wrote {}/{{budget.md, budget.json, launch_drag.csv, budget_hist.png{}}} in {elapsed:.2} s",
        dir.display(),
        if r.search.is_some() {
            ", budget_tolerances.png"
        } else {
            ""
        }
    );
    Ok(())
}
