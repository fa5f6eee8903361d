//! `bsa render`: the shadow of any launch at `t` or another instant before it, from a
//! solve's `solution.json`, the builders' `launch.csv` or a minimal launch file
//! ([`crate::output::launches`]): `shadow.png`, `overlay.png` and the IoU.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::energy::{self, Weights};
use crate::evaluate::Problem;
use crate::output::{files, launches};

use super::{load, RenderArgs};

/// The validated options of `bsa render`.
pub(super) struct Options {
    scene: PathBuf,
    solution: PathBuf,
    out: PathBuf,
    /// Finite and positive when given; checked against `t` once the scene is loaded.
    at: Option<f64>,
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
        })
    }
}

pub(super) fn run(opts: &Options) -> Result<()> {
    let problem = Problem::new(load::scene(&opts.scene)?);
    let scene = &problem.scene;
    let at = opts.at.unwrap_or(scene.t);
    if at > scene.t {
        bail!(
            "--at {at} s is after t = {} s: the solver's model stops at t (the motion after it is rapier's; see `bsa export` and the glb)",
            scene.t
        );
    }
    let params = launches::read_launches(&opts.solution, scene)?;
    let mut ws = problem.workspace();
    // The same evaluation as a solve's final one, so that at `t` the pictures are the
    // solve's, bit for bit.
    let e = problem.evaluate(&params, &Weights::all_ones(), &mut ws);
    let mut iou = e.iou;
    if at < scene.t {
        for i in 0..scene.occluders.len() {
            ws.poses[i] = problem.state_at(&ws, i, at).0;
        }
        problem.shadow(&mut ws);
        iou = energy::iou(&ws.mask, &problem.target.mask);
    }
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create {}", opts.out.display()))?;
    let title = format!(
        "{}: the shadow at {} s of {}",
        scene.name,
        at,
        opts.solution.display()
    );
    files::write_pictures(&opts.out, &scene.target, &ws.mask, &title)?;
    let contact = match e.outcome.first_contact {
        None => "no contact before t".to_string(),
        Some((i, j)) => format!(
            "first contact at {:.4} s: `{}` with `{}`",
            e.outcome.t_sim,
            scene.occluders[i].name,
            j.map_or("the table", |j| scene.occluders[j].name.as_str())
        ),
    };
    println!(
        "{}: IoU at {} s {:.4} ({}); wrote {}/{{shadow.png, overlay.png}}",
        scene.name,
        at,
        iou,
        contact,
        opts.out.display()
    );
    Ok(())
}
