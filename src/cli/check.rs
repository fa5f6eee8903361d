//! `bsa check`: validate a scene and print a summary of it, with how its start guess
//! looks.

use std::path::PathBuf;

use anyhow::Result;

use crate::energy::{Term, Weights};
use crate::evaluate::Problem;
use crate::geometry::shape::Shape;
use crate::optimize::solver::Schedule;
use crate::scene::{Scene, Strategy};

use super::{load, CheckArgs};

/// The validated options of `bsa check`.
pub(super) struct Options {
    scene: PathBuf,
}

impl Options {
    /// `check` has nothing to validate before the scene is loaded: loading is the check.
    pub(super) fn new(args: CheckArgs) -> Options {
        Options { scene: args.scene }
    }
}

fn fmt_vec(v: glam::DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

/// Load the scene and print its summary.
pub(super) fn run(opts: &Options) -> Result<()> {
    let s = load::scene(&opts.scene)?;
    println!("scene `{}` ({})", s.name, s.source.display());
    println!(
        "  results  {}/ (where `bsa solve` writes without --out)",
        super::outdir::default_out(&s).display()
    );
    println!(
        "  target   {} x {} px, {} shadow pixels ({:.1}%)",
        s.target.width(),
        s.target.height(),
        s.target.count(),
        100.0 * s.target.count() as f64 / (s.target.width() * s.target.height()) as f64
    );
    println!(
        "  t        {} s, timestep {:.5} s, gravity {} m/s^2",
        s.t,
        s.dt,
        fmt_vec(s.gravity)
    );
    print_pictures(&s);
    print_setting(&s);
    print_occluders(&s);
    println!("  hints    {}", s.hints.len());
    print_strategy(&s);
    println!("  seed     {}", s.seed);
    print_start(&s);
    println!("ok");
    Ok(())
}

/// The pictures of a scene with several, and the hold window and free positions.
fn print_pictures(s: &Scene) {
    if s.pictures.len() > 1 {
        println!(
            "  pictures {} (the last is the target and t above):",
            s.pictures.len()
        );
        for (k, p) in s.pictures.iter().enumerate() {
            println!(
                "    {} at t = {} s: {} ({} shadow pixels), weight {:.3}, {} hints",
                k + 1,
                p.t,
                p.file.display(),
                p.target.count(),
                p.weight,
                p.hints.len()
            );
        }
    }
    if let Some(h) = &s.hold {
        let evaluated = h.offsets().len();
        println!(
            "  hold     +-{} s around each picture: {} frames at {} fps reported, {} instants evaluated per picture",
            h.window,
            h.frame_offsets().len(),
            h.fps,
            evaluated
        );
    }
    if s.positions == crate::scene::LaunchPositions::Free {
        println!("  positions free: launch positions on the table are optimised too");
    }
}

/// The light, the receiver and the table.
fn print_setting(s: &Scene) {
    println!("  light    {} m", fmt_vec(s.light));
    let r = &s.receiver;
    println!(
        "  receiver centre {} m, u {}, v {}, {} m x {} m ({:.4} m/px)",
        fmt_vec(r.center),
        fmt_vec(r.u),
        fmt_vec(r.v),
        r.width,
        r.height,
        r.width / s.target.width() as f64
    );
    match &s.table {
        Some(t) => println!(
            "  table    top at z = {:.3} m, centre {} m, size {} m",
            t.top(),
            fmt_vec(t.center),
            fmt_vec(t.half_extents * 2.0)
        ),
        None => println!("  table    none"),
    }
}

/// One line per occluder: name, shape, mass, position, launched or not.
fn print_occluders(s: &Scene) {
    println!("  occluders ({}):", s.occluders.len());
    for o in &s.occluders {
        let shape = match &o.shape {
            Shape::Sphere { radius } => format!("sphere r {radius} m"),
            Shape::Cuboid { half_extents } => format!("box {} m", fmt_vec(*half_extents * 2.0)),
            Shape::Mesh(m) => format!(
                "mesh {} vertices, {} triangles",
                m.vertices.len(),
                m.triangles.len()
            ),
        };
        println!(
            "    {:<12} {:<36} {:>8.4} kg  at {} m  {}",
            o.name,
            shape,
            o.mass.mass,
            fmt_vec(o.position),
            if o.launched { "launched" } else { "stays put" }
        );
    }
}

/// The strategy, and one line per stage: what it varies, its CMA-ES settings, its
/// weights.
fn print_strategy(s: &Scene) {
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
}

/// How the start guess looks: its IoU and first contact (the instants' IoUs with
/// several), and what a solve of the scene costs.
fn print_start(s: &Scene) {
    // The start guess is where every stage's search begins: say how it looks, and name a
    // contact in it, since a start that collides is a slow start.
    let problem = Problem::new(s.clone());
    let mut ws = problem.workspace();
    let e = problem.evaluate(&problem.start_parameters(), &Weights::all_ones(), &mut ws);
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
    if !s.single_instant() {
        let f = problem.frame_ious(&problem.start_parameters(), &mut ws);
        super::frames::print(&problem, &f);
    }
    println!(
        "  cost     {}",
        super::progress::cost_line(&problem, &Schedule::DEFAULT, None)
    );
}
