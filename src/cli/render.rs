//! `bsa render`: the shadow of any launch at `t` or another instant before it, from a
//! solve's `solution.json`, the builders' `launch.csv` or a minimal launch file
//! ([`crate::output::launches`]): `shadow.png`, `overlay.png` and the IoU; for a scene
//! with several pictures or a hold window also the IoU at every frame, an overlay per
//! picture and the worst frame's ([`super::frames`]).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::energy::{self, Weights};
use crate::evaluate::Problem;
use crate::output::{files, launches};
use crate::sim::drag::DragConfig;

use super::{frames, load, RenderArgs};

/// The validated options of `bsa render`.
pub(super) struct Options {
    scene: PathBuf,
    solution: PathBuf,
    out: PathBuf,
    /// Finite and positive when given; checked against `t` once the scene is loaded.
    at: Option<f64>,
    /// Fly through air (a launch table of `bsa solve --air`).
    air: bool,
}

impl Options {
    pub(super) fn new(args: RenderArgs) -> Result<Options> {
        if let Some(at) = args.at {
            if !(at.is_finite() && at > 0.0) {
                bail!("--at must be a positive number of seconds, got {at}");
            }
        }
        let out = args.out.unwrap_or_else(|| {
            args.solution
                .parent()
                .map_or_else(|| PathBuf::from("render"), |d| d.join("render"))
        });
        Ok(Options {
            scene: args.scene,
            solution: args.solution,
            out,
            at: args.at,
            air: args.air,
        })
    }
}

pub(super) fn run(opts: &Options) -> Result<()> {
    let mut scene = load::scene(&opts.scene)?;
    let before: Vec<_> = scene.occluders.iter().map(|o| o.launch_com()).collect();
    let launch = launches::read_launches(&opts.solution, &mut scene)?;
    // A launch file may carry other launch positions (a solve with free positions, or
    // a builder's edit of launch.csv): say so, the picture depends on it.
    for (o, was) in scene.occluders.iter().zip(&before) {
        let moved = o.launch_com().distance(*was);
        if moved > 1e-9 {
            eprintln!(
                "note: {} launches `{}` from {:?} (its centre of mass), {moved:.4} m from the scene's position",
                opts.solution.display(),
                o.name,
                o.launch_com().to_array().map(|x| (x * 1e6).round() / 1e6)
            );
        }
    }
    let params = launch.params;
    let mut problem = Problem::new(scene);
    if let Some(air) = launch.air.or(opts.air.then(DragConfig::default)) {
        problem.set_air(air);
    }
    let scene = &problem.scene;
    let at = opts.at.unwrap_or(scene.t);
    if at > scene.horizon() {
        let window = match &scene.hold {
            Some(_) => format!(" and the end of its hold window, {} s", scene.horizon()),
            None => String::new(),
        };
        bail!(
            "--at {at} s is after t = {} s{window}: the solver's model stops there (the motion after it is rapier's; see `bsa export` and the glb)",
            scene.t
        );
    }
    let mut ws = problem.workspace();
    // The same evaluation as a solve's final one, so that at `t` the pictures are the
    // solve's, bit for bit.
    let e = problem.evaluate(&params, &Weights::all_ones(), &mut ws);
    let mut iou = energy::iou(&ws.mask, &problem.target.mask);
    // The picture an instant is scored against: the one whose instant is nearest.
    let k = (0..scene.pictures.len())
        .min_by(|&a, &b| {
            let d = |k: usize| (scene.pictures[k].t - at).abs();
            d(a).total_cmp(&d(b))
        })
        .expect("a scene has a picture");
    let picture = &scene.pictures[k];
    if at != scene.t {
        problem.shadow_at(at, &mut ws);
        iou = energy::iou(&ws.mask, &problem.pictures[k].mask);
    }
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create {}", opts.out.display()))?;
    let title = format!(
        "{}: the shadow at {} s of {}",
        scene.name,
        at,
        opts.solution.display()
    );
    files::write_pictures(
        &opts.out,
        &picture.target,
        &problem.picture_of(&ws.mask),
        &title,
    )?;
    let mut more = Vec::new();
    let frame_ious = if scene.single_instant() {
        Vec::new()
    } else {
        let f = problem.frame_ious(&params, &mut ws);
        more = frames::write_pictures(&opts.out, &problem, &f, &mut ws)?;
        f
    };
    let contact = match e.outcome.first_contact {
        None if scene.hold.is_some() => format!("no contact before {} s", scene.horizon()),
        None => "no contact before t".to_string(),
        Some((i, j)) => format!(
            "first contact at {:.4} s: `{}` with `{}`",
            e.outcome.t_sim,
            scene.occluders[i].name,
            j.map_or("the table", |j| scene.occluders[j].name.as_str())
        ),
    };
    more.splice(0..0, ["shadow.png".to_string(), "overlay.png".to_string()]);
    println!(
        "{}: IoU at {} s {:.4} ({}); wrote {}/{{{}}}",
        scene.name,
        at,
        iou,
        contact,
        opts.out.display(),
        more.join(", ")
    );
    frames::print(&problem, &frame_ious);
    Ok(())
}
