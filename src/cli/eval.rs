//! `bsa eval`: print every energy term of a saved solution, raw and weighted by one
//! stage's weights, as a table or as JSON, optionally with the time of each phase of
//! one sample.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::energy::{Term, Weights};
use crate::evaluate::{Evaluation, FrameIou, Problem};
use crate::output::files;
use crate::scene::Scene;

use super::{load, EvalArgs};

/// Most repetitions of `--profile`: a sample takes up to a few milliseconds, so this
/// is minutes at most.
const MAX_PROFILE_REPS: usize = 100_000;

/// The validated options of `bsa eval`.
pub(super) struct Options {
    scene: PathBuf,
    solution: PathBuf,
    /// 1-based; checked against the scene by [`Options::stage`].
    stage: Option<usize>,
    json: bool,
    profile: Option<usize>,
}

impl Options {
    /// `--profile`'s repetitions are checked here; the range of `--stage` is the
    /// scene's, checked once it is loaded ([`Options::stage`]).
    pub(super) fn new(args: EvalArgs) -> Result<Options> {
        if let Some(reps) = args.profile.filter(|r| !(1..=MAX_PROFILE_REPS).contains(r)) {
            bail!("--profile must be 1 to {MAX_PROFILE_REPS} repetitions, got {reps}");
        }
        Ok(Options {
            scene: args.scene,
            solution: args.solution,
            stage: args.stage,
            json: args.json,
            profile: args.profile,
        })
    }

    /// The 1-based stage whose weights to use: `--stage`, checked to be one of the
    /// scene's, else the last stage.
    fn stage(&self, scene: &Scene) -> Result<usize> {
        match self.stage {
            None => Ok(scene.stages.len()),
            Some(k) if (1..=scene.stages.len()).contains(&k) => Ok(k),
            Some(k) => bail!(
                "--stage {k} is out of range: the scene has stages 1 to {}",
                scene.stages.len()
            ),
        }
    }
}

/// Evaluate the solution and print its terms.
pub(super) fn run(opts: &Options) -> Result<()> {
    let scene = load::scene(&opts.scene)?;
    let k = opts.stage(&scene)?;
    let solution_path = &opts.solution;
    if solution_path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    {
        bail!(
            "--solution {}: eval reads a solve's solution.json (its terms and stages); `bsa render {} --solution {}` draws the shadow of a launch table",
            solution_path.display(),
            opts.scene.display(),
            solution_path.display()
        );
    }
    let s = files::read_solution(solution_path)?;
    let problem = load::problem_for(scene, &s);
    // As budget does: the names, counts and t, and the same shadow when re-evaluated, so
    // that a solution of an edited scene is refused instead of reported as if current.
    crate::budget::check_solution_current(&problem, &s)
        .with_context(|| format!("{} does not match the scene", solution_path.display()))?;
    let scene = &problem.scene;
    let weights = scene.stages[k - 1].weights;
    let mut ws = problem.workspace();
    let e = problem.evaluate(&s.parameters(), &Weights::all_ones(), &mut ws);
    let weighted = weights.weigh(&e.raw);
    let total: f64 = weighted.iter().sum();
    let rows: Vec<(Term, f64, f64, f64)> = Term::ALL
        .iter()
        .map(|&t| (t, e.raw[t as usize], weights.get(t), weighted[t as usize]))
        .collect();
    let first_contact = e.outcome.first_contact.map(|(i, j)| {
        let a = scene.occluders[i].name.clone();
        let b = j.map_or_else(|| "table".to_string(), |j| scene.occluders[j].name.clone());
        (a, b)
    });
    let outside = super::frames::outside_names(&problem, &ws);
    let frame_ious = if scene.single_instant() {
        Vec::new()
    } else {
        problem.frame_ious(&s.parameters(), &mut ws)
    };
    let timings = match opts.profile {
        Some(reps) => problem.profile(&s.parameters(), reps, &mut ws),
        None => Vec::new(),
    };
    let terms = Terms {
        stage: k,
        rows,
        total,
        evaluation: e,
        first_contact,
        outside,
        frame_ious,
        timings,
    };
    if opts.json {
        print_json(scene, &terms)?;
    } else {
        print_table(&problem, &terms);
    }
    Ok(())
}

/// What `bsa eval` found of a solution, for [`print_json`] and [`print_table`].
struct Terms {
    /// The 1-based stage whose weights the terms are weighted by.
    stage: usize,
    /// Every term: raw, its weight, weighted.
    rows: Vec<(Term, f64, f64, f64)>,
    /// The weighted terms' sum.
    total: f64,
    /// The solution's evaluation with every weight 1.
    evaluation: Evaluation,
    /// The names of the first contact's bodies (`table` for the table).
    first_contact: Option<(String, String)>,
    /// The occluders whose shadows leave the image.
    outside: Vec<String>,
    /// The IoU of each instant (empty for a single instant).
    frame_ious: Vec<FrameIou>,
    /// The time of each phase of one sample (`--profile`; else empty).
    timings: Vec<(String, f64)>,
}

/// The terms as one JSON object (`--json`).
fn print_json(scene: &Scene, terms: &Terms) -> Result<()> {
    let e = &terms.evaluation;
    let rows: serde_json::Map<String, serde_json::Value> = terms
        .rows
        .iter()
        .map(|(t, raw, w, wt)| {
            (
                t.key().to_string(),
                serde_json::json!({"raw": raw, "weight": w, "weighted": wt}),
            )
        })
        .collect();
    let mut v = serde_json::json!({
        "scene": scene.name,
        "stage": terms.stage,
        "terms": rows,
        "total": terms.total,
        "iou": e.iou,
        "t_sim": e.outcome.t_sim,
        "n_contacts": e.outcome.n_contacts,
        "first_contact": terms.first_contact.as_ref().map(|(a, b)| [a, b]),
        "shadows_outside_image": terms.outside,
        "time_per_phase_us": terms.timings.iter().map(|(k, v)| (k.clone(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
    });
    if !terms.frame_ious.is_empty() {
        v["frames"] = terms
            .frame_ious
            .iter()
            .map(|f| serde_json::json!({"t_s": f.t, "picture": f.picture + 1, "iou": f.iou}))
            .collect();
    }
    println!("{}", serde_json::to_string_pretty(&v)?);
    Ok(())
}

/// The terms as a table, then the IoU, the contacts, the instants, the shadows leaving
/// the image and the phases' times.
fn print_table(problem: &Problem, terms: &Terms) {
    let scene = &problem.scene;
    let Terms {
        stage: k,
        rows,
        total,
        evaluation: e,
        first_contact,
        outside,
        frame_ious,
        timings,
    } = terms;
    println!(
        "scene `{}`, weights of stage {} `{}`",
        scene.name,
        k,
        scene.stages[k - 1].name
    );
    println!(
        "{:<24} {:>14} {:>10} {:>14}",
        "term", "raw", "weight", "weighted"
    );
    for (t, raw, w, wt) in rows {
        println!(
            "{:<24} {:>14.6} {:>10} {:>14.6}",
            t.display_name(),
            raw,
            w,
            wt
        );
    }
    println!("{:<24} {:>14} {:>10} {:>14.6}", "total", "", "", total);
    println!(
        "IoU at t {:.5}; t_sim {:.5} s; contacts {}",
        e.iou, e.outcome.t_sim, e.outcome.n_contacts
    );
    if let Some((a, b)) = first_contact {
        println!("first contact: `{a}` with `{b}`");
    }
    super::frames::print(problem, frame_ious);
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
        for (k, v) in timings {
            println!("  {k:<26} {v:>10.2}");
        }
    }
}
