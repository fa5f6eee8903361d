//! The `bsa` command line: the clap definitions and the dispatch to the subcommands.
//!
//! Subcommands: `check` (validate a scene and print a summary), `solve` (optimise and
//! write `export/<scene folder>/` and its `report.html`), `eval` (print every energy term of a saved solution),
//! `export` (animated glTF and launch tables of a saved solution), `validate` (Blender
//! Cycles shadow against the rasterizer), `video` (an MP4 of the flight) and `budget`
//! (air drag, the drag-compensated launch table and launch tolerances), and `render`
//! (the shadow of any launch at any instant up to `t`), `plant` (a problem with a known
//! answer), `new` (a scene from a picture and a box of objects), `completions` (a shell's
//! completion script) and `man` (the manual page). `validate`, `blend`
//! and `video` run the scripts of `blender/` with a Python that has `bpy`. The
//! help of them all, as markdown, is [`markdown`] (`docs/cli.md`).
//!
//! Each subcommand lives in its own file and runs in two steps, in the way of ripgrep:
//! its raw clap arguments (the `*Args` structs below) are turned once into a validated
//! `Options` struct, and only then does any work start, through library calls. Shared
//! helpers: [`load`] (a scene, a solution folder), [`progress`] (progress bars and the
//! solve observer), [`scratch`] (the dot-files `new` and `plant` work in until their
//! scene is complete) and [`blender`] (the Python with `bpy` and its scripts).
//! This is the only module that uses `anyhow`, prints, draws progress bars or installs
//! the Ctrl-C handler; library modules return typed errors.

// The options' doc comments are clap's help text, written for a terminal: `<scene>` and
// `<name>` there are placeholders of the help, not HTML, and `[default: ...]` is not a
// link.
#![allow(rustdoc::invalid_html_tags, rustdoc::broken_intra_doc_links)]

mod blend;
mod blender;
mod budget;
mod check;
mod docs;
mod eval;
mod export;
mod frames;
pub mod guard;
mod launcher;
mod load;
mod new;
mod outdir;
mod plant;
mod progress;
mod render;
mod scratch;
mod solve;
mod validate;
mod video;

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};

pub use docs::markdown;

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

// The subcommands' descriptions are the doc comments of these variants; the argument
// structs carry plain comments only, so that clap never mistakes them for a description.
#[derive(Subcommand)]
enum Command {
    /// Validate a scene and print a summary.
    Check(CheckArgs),
    /// Optimise launch velocities and write solution.json, shadow.png, overlay.png,
    /// preview.png, convergence.{csv,png,svg}, report.html, <scene>.glb, launch.csv and
    /// trajectory.csv.
    Solve(SolveArgs),
    /// Write the animated glTF (<scene>.glb), launch.csv and trajectory.csv of a saved solution.
    Export(ExportArgs),
    /// Render the shadow at t with Blender Cycles and compare it with the rasterizer (IoU, XOR).
    Validate(ValidateArgs),
    /// Write <scene>.blend, ready to render: fps, t on a whole frame (marker `t`), frames
    /// from the launch until every body is at rest, a view camera (16:9) and a shadow
    /// scene, hard shadows in Cycles and EEVEE; optional slow motion and trajectory curves.
    Blend(BlendArgs),
    /// Render the film of <scene>.blend (written first, as `bsa blend`): an MP4 from the
    /// view camera (1920x1080 by default) and a contact sheet of four stills beside it.
    Video(VideoArgs),
    /// Error budget of a saved solution: re-simulation with air drag, drag-compensated
    /// launch table (launch_drag.csv), Monte Carlo of launch errors, sensitivities and
    /// the largest tolerances; writes budget.md, budget.json and two PNG plots.
    Budget(BudgetArgs),
    /// Print every energy term of a solution, raw and weighted.
    Eval(EvalArgs),
    /// Draw the shadow of any launch (solution.json, launch.csv or a launch file) at t or
    /// another instant: shadow.png, overlay.png and the IoU.
    Render(RenderArgs),
    /// Plant a problem with a known answer: a random contact-free launch of a box of
    /// objects whose shadow becomes the target; writes scene.json, target.png and
    /// planted.json (the launch) into DIR.
    Plant(PlantArgs),
    /// Design a scene from a picture and a box of objects: writes DIR/scene.json (objects
    /// laid out, hints, start guess, strategy), DIR/target.png and DIR/start.png (the
    /// start guess over the target), ready for `bsa solve DIR`.
    New(NewArgs),
    /// Print the completion script of a shell for bsa, e.g. `bsa completions bash >
    /// ~/.local/share/bash-completion/completions/bsa`, `bsa completions zsh >
    /// ~/.zfunc/_bsa`, `bsa completions fish > ~/.config/fish/completions/bsa.fish`.
    Completions(CompletionsArgs),
    /// Print the manual page of bsa, or of one of its subcommands, as roff, e.g. `bsa man
    /// | man -l -` or `bsa man solve > bsa-solve.1`.
    Man(ManArgs),
}

// Raw arguments of `bsa completions`.
#[derive(Args)]
struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    shell: docs::Shell,
}

// Raw arguments of `bsa man`.
#[derive(Args)]
struct ManArgs {
    /// A subcommand, for its own page (bsa-SUBCOMMAND.1) [default: the page of bsa].
    subcommand: Option<String>,
}

// Raw arguments of `bsa check`.
#[derive(Args)]
struct CheckArgs {
    /// Scene folder (holding scene.json) or scene file.
    scene: PathBuf,
}

// Raw arguments of `bsa solve`.
#[derive(Args)]
struct SolveArgs {
    /// Scene folder (holding scene.json) or scene file.
    scene: PathBuf,
    /// Output folder [default: export/<name of the scene's folder>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the results of another scene (or another t) found in the output folder.
    #[arg(long)]
    force: bool,
    /// Random seed (overrides the scene's).
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads, 1 to 256 [default: one per core].
    #[arg(long)]
    threads: Option<usize>,
    /// Attempts at most, 1 to 16: while the picture ends below the last stage's
    /// restart_iou, the stages run again from the start guess with another seed, and the
    /// best picture is kept [default: 2].
    #[arg(long)]
    attempts: Option<usize>,
    /// Stop after this many seconds with the best picture so far, saved as a complete
    /// result (the stages left are skipped) [default: no limit].
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    time_limit: Option<f64>,
    /// Continue from the output folder's solution.json (skips its completed stages).
    #[arg(long)]
    resume: bool,
    /// Print the performance report (stages, iterations, samples, time per term).
    #[arg(long)]
    report: bool,
    /// No progress bars.
    #[arg(long, short)]
    quiet: bool,
    /// Fly every body through air while solving (quadratic drag with the budget's default
    /// model), so that the launch table is the one to use in air.
    #[arg(long)]
    air: bool,
    /// Optimise the image energy expected under launch errors (the budget's error model,
    /// with the tolerances below), with the same errors for every sample of an iteration.
    #[arg(long)]
    robust: bool,
    /// Perturbed launches per sample with --robust [default: 16].
    #[arg(long, value_name = "N")]
    draws: Option<usize>,
    /// With --robust, optimise this quantile of the image energy over the perturbed
    /// launches instead of its mean, in (0, 1) (e.g. 0.9: the best 90 %).
    #[arg(long, value_name = "Q", allow_negative_numbers = true)]
    quantile: Option<f64>,
    /// With --robust: the launcher's errors to optimise under.
    #[command(flatten)]
    launcher: launcher::LauncherArgs,
    /// Optimise the launch positions too (x and y on the table; bounded to the table's
    /// top, contact-free at launch), as the scene's `"positions": "free"` does.
    #[arg(long)]
    free_positions: bool,
}

// Raw arguments of `bsa export`.
#[derive(Args)]
struct ExportArgs {
    /// Output folder of a solve (holding solution.json).
    dir: PathBuf,
    /// Scene folder or file [default: the one recorded in solution.json, else scenes/<name>].
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Longest rapier continuation after t (s): the motion runs until every body is at
    /// rest (every point slower than 1 cm/s for 0.25 s), or this long.
    #[arg(long, value_name = "SECONDS", default_value_t = crate::output::trajectory::DEFAULT_MAX_AFTER)]
    after: f64,
}

// Raw arguments of `bsa validate`.
#[derive(Args)]
struct ValidateArgs {
    /// Output folder of a solve or export (holding solution.json and <scene>.glb).
    dir: PathBuf,
    /// Scene folder or file [default: as for `export`].
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Python with the `bpy` module [default: $BSA_PYTHON, else .venv-blender/bin/python].
    #[arg(long)]
    python: Option<PathBuf>,
    /// Exit with an error when Cycles and the rasterizer agree at an IoU below X (0 to
    /// 1), at t or at any picture's instant; validate.json and the pictures are written
    /// first. Cycles reproduces the shadows to a few pixels (IoU 0.9995 or more on the
    /// examples).
    #[arg(long, value_name = "X", default_value_t = validate::DEFAULT_MIN_IOU, allow_negative_numbers = true)]
    min_iou: f64,
}

// Raw arguments of `bsa blend`.
#[derive(Args)]
struct BlendArgs {
    /// Output folder of a solve (holding solution.json).
    dir: PathBuf,
    /// Scene folder or file [default: as for `export`].
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Output file [default: DIR/<scene>.blend].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frames per second of the film (t is put on a whole frame).
    #[arg(long, default_value_t = 24)]
    fps: u32,
    /// Render size of the view camera, WIDTHxHEIGHT in pixels.
    #[arg(long, value_name = "WxH", default_value = "1920x1080")]
    resolution: String,
    /// Slow the motion down around t so that the picture stays on screen at least 0.5 s.
    #[arg(long)]
    slowmo: bool,
    /// Draw each body's flight to t as a curve (collection `trajectories`).
    #[arg(long)]
    curves: bool,
    /// Python with the `bpy` module [default: $BSA_PYTHON, else .venv-blender/bin/python].
    #[arg(long)]
    python: Option<PathBuf>,
}

// Raw arguments of `bsa video`.
#[derive(Args)]
struct VideoArgs {
    /// Output folder of a solve (holding solution.json).
    dir: PathBuf,
    /// Output file [default: <the .blend's folder and name>.mp4]; the contact sheet goes
    /// beside it as <name>_contact_sheet.png.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Render this .blend as it is [default: write DIR/<scene>.blend first, as `bsa blend`
    /// with the options below].
    #[arg(long, value_name = "FILE")]
    blend: Option<PathBuf>,
    /// Frames per second of the film (t is put on a whole frame).
    #[arg(long, default_value_t = video::DEFAULT_FPS)]
    fps: u32,
    /// Frame size, WIDTHxHEIGHT in pixels, even [default: 1920x1080, or the --blend file's].
    #[arg(long, value_name = "WxH")]
    resolution: Option<String>,
    /// Slow the motion down around t so that the picture stays on screen at least 0.5 s.
    #[arg(long)]
    slowmo: bool,
    /// Draw each body's flight to t as a curve.
    #[arg(long)]
    curves: bool,
    /// Cycles samples per pixel.
    #[arg(long, default_value_t = 16)]
    samples: u32,
    /// Denoise every frame (OpenImageDenoise; slow on a CPU).
    #[arg(long)]
    denoise: bool,
    /// Render only the first SECONDS of the film.
    #[arg(long, allow_negative_numbers = true)]
    seconds: Option<f64>,
    /// Render only the contact sheet's four stills, no video.
    #[arg(long)]
    sheet_only: bool,
    /// Python with the `bpy` module [default: $BSA_PYTHON, else .venv-blender/bin/python].
    #[arg(long)]
    python: Option<PathBuf>,
}

// Raw arguments of `bsa budget`.
#[derive(Args)]
struct BudgetArgs {
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
    /// Worker threads, 1 to 256 [default: one per core].
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
    /// The launcher's errors.
    #[command(flatten)]
    launcher: launcher::LauncherArgs,
    /// IoU a sample must reach to count as a success, in (0, 1]: the Monte Carlo
    /// reports P(IoU >= X) and the tolerance search keeps it >= 90 %.
    #[arg(long, value_name = "X", default_value_t = crate::budget::IOU_THRESHOLD, allow_negative_numbers = true)]
    iou_threshold: f64,
    /// No progress bars.
    #[arg(long, short)]
    quiet: bool,
}

// Raw arguments of `bsa eval`.
#[derive(Args)]
struct EvalArgs {
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
}

// Raw arguments of `bsa render`.
#[derive(Args)]
struct RenderArgs {
    /// Scene folder (holding scene.json) or scene file.
    scene: PathBuf,
    /// The launch: a solution.json, a launch.csv, or a JSON file mapping each launched
    /// occluder's name to {"velocity": [x, y, z], "angular_velocity": [x, y, z]} (m/s,
    /// rad/s).
    #[arg(long)]
    solution: PathBuf,
    /// Output folder [default: render/ beside the launch file].
    #[arg(long)]
    out: Option<PathBuf>,
    /// The instant of the shadow (s, after the launch, at most t, or the end of the hold
    /// window) [default: t].
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    at: Option<f64>,
    /// Fly through air with the default drag model (a launch table of `bsa solve --air`;
    /// a solution.json says so itself).
    #[arg(long)]
    air: bool,
}

// Raw arguments of `bsa new`.
#[derive(Args)]
struct NewArgs {
    /// Folder to write the scene into (created if needed).
    dir: PathBuf,
    /// The picture (PNG; dark = shadow).
    #[arg(long, value_name = "PNG")]
    target: PathBuf,
    /// How to choose among the designs made under the four ceilings in the two orders:
    /// `solve` solves each that differs as `bsa solve` will (the scene's seed) and keeps
    /// the best picture, contact-free first (up to eight solves' work, on every core);
    /// `start` keeps the best start guess (no solve).
    #[arg(long, value_enum, default_value_t = new::ChooseBy::Solve)]
    choose_by: new::ChooseBy,
    /// Design for a launcher: besides the standard design, designs at shorter instants
    /// (t/2, t/4, t/8) under lower ceilings, each body launched already in its pose at t
    /// and without spin; every trial solve is measured at the launcher (the defaults, or
    /// FILE.json as `bsa budget --launcher` reads it), and the design kept is the one most
    /// likely to read among those within 0.03 of the best IoU. Writes the frontier of
    /// every design tried (frontier.md, frontier.csv, frontier.png) beside the scene,
    /// and the launcher into the scene.
    #[arg(long, value_name = "FILE.json", num_args = 0..=1)]
    launcher: Option<Option<PathBuf>>,
    #[command(flatten)]
    design: DesignArgs,
}

// Raw arguments of `bsa plant`.
#[derive(Args)]
struct PlantArgs {
    /// Folder to write the problem into (created if needed).
    dir: PathBuf,
    #[command(flatten)]
    design: DesignArgs,
}

// The objects and the stage of `bsa new` and `bsa plant`.
#[derive(Args)]
struct DesignArgs {
    /// The objects: a comma-separated list (e.g. box:0.14x0.07x0.035*4,chess:king,auto:sphere),
    /// or a JSON file of them (FILE.json).
    ///
    /// Each item of a list, in metres: `sphere:R` (a ball of radius R),
    /// `box:XxYxZ` (a block), `mesh:FILE.obj[@SCALE]` (a closed mesh, its path relative to
    /// the current folder), `chess:PIECE` (a piece of the built-in chess set: king, queen,
    /// rook, bishop, knight or pawn) and `chess` (one side of it, 16 pieces). Each takes an
    /// optional `*N` count and `/DENSITY` in kg/m^3 (default 705, maple; chess pieces 900,
    /// boxwood). `auto:` items let `bsa new` choose how many, adding objects while one more
    /// raises the picture's IoU by a quarter of a point: `auto:sphere` (the radii chosen too),
    /// `auto:sphere:R`, `auto:box:XxYxZ`, `auto:mesh:FILE.obj[@SCALE]` or `auto:chess`
    /// (pieces of one side), up to 64 balls or 32 other objects (a ball counts half);
    /// several of them make a box of several sizes (each but `auto:chess` with an optional
    /// `*N`, the most it adds; counts that add up to more raise the cap to their sum). An
    /// `auto:` item of a given size has its designs flown lower (ceilings 0.6 to 0.3 of
    /// the light's height), so that its shadows keep near its size. Or FILE.json: an array of
    /// {"kind": "sphere" | "box" | "mesh" | "chess", "radius", "size": [X, Y, Z], "obj",
    /// "scale", "piece", "count": N | "auto", "at_most", "density"}, its mesh paths
    /// relative to its folder. `bsa plant` takes neither `auto:` items nor chess pieces by name
    /// (give them as meshes: mesh:scenes/thinker/pieces/PIECE.obj).
    #[arg(long, value_name = "LIST|FILE.json")]
    objects: String,
    /// The picture's width on the floor (m); its height follows the picture's aspect.
    /// Default 1.6; for `auto:` items, `bsa new` widens it (up to twice, and says so)
    /// where more than 15 % of the picture is narrower than the objects' narrowest shadow.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    width: Option<f64>,
    /// The point light's height above the picture (m).
    #[arg(
        long,
        value_name = "M",
        default_value_t = 6.0,
        allow_negative_numbers = true
    )]
    light_height: f64,
    /// The instant of the picture (s after the launch).
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1.2,
        allow_negative_numbers = true
    )]
    t: f64,
    /// Seed of the scene's solve (and of `plant`'s draw).
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Run the parsed command line: validate the subcommand's options, then run it.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Check(args) => check::run(&check::Options::new(args)),
        Command::Solve(args) => solve::run(&solve::Options::new(args)?),
        Command::Eval(args) => eval::run(&eval::Options::new(args)?),
        Command::Export(args) => export::run(&export::Options::new(args)?),
        Command::Validate(args) => validate::run(&validate::Options::new(args)?),
        Command::Blend(args) => blend::run(&blend::Options::new(args)?),
        Command::Video(args) => video::run(&video::Options::new(args)?),
        Command::Budget(args) => budget::run(&budget::Options::new(args)),
        Command::Render(args) => render::run(&render::Options::new(args)?),
        Command::Plant(args) => plant::run(&plant::Options::new(args)?),
        Command::New(args) => new::run(&new::Options::new(args)?),
        Command::Completions(args) => docs::completions(args.shell),
        Command::Man(args) => docs::man(args.subcommand.as_deref()),
    }
}
