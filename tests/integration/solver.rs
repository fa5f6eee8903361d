//! The solver through the library: determinism across thread counts and seeds, resume
//! after an interrupt, the sequential strategy, the golden shadow of a fixed launch, the
//! example scenes' start guesses, and the full Mickey solve.

use std::sync::atomic::{AtomicUsize, Ordering};

use bsa::evaluate::Problem;
use bsa::optimize::moves::Purpose;
use bsa::optimize::solver::{self, Observer, Schedule, SolveOptions};
use bsa::output::solution::{SampleRecord, Solution};

use crate::util::{root, variant};

fn small_mickey(iterations: usize) -> Problem {
    let mut scene = bsa::scene::load(&root().join("scenes/mickey")).unwrap();
    for s in &mut scene.stages {
        s.max_iterations = iterations;
        s.population = 16;
    }
    Problem::new(scene)
}

fn params_bits(s: &Solution) -> Vec<u64> {
    s.parameters().iter().map(|x| x.to_bits()).collect()
}

#[test]
fn same_seed_gives_bit_identical_solution_with_1_and_2_threads() {
    let p = small_mickey(12);
    let none = AtomicUsize::new(0);
    let run = |threads| {
        let opts = SolveOptions {
            threads: Some(threads),
            seed: Some(7),
            resume: None,
            schedule: Schedule::DEFAULT.with_attempts(1),
            time_limit: None,
            until_stage: None,
        };
        solver::solve(&p, &opts, &mut solver::Silent, &none)
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    assert_eq!(params_bits(&a), params_bits(&b));
    assert_eq!(a.total_energy.to_bits(), b.total_energy.to_bits());
    assert_eq!(ra, rb);
    // A different seed explores differently: other samples. (The solutions themselves
    // may coincide on so short a solve: the moves before a run are deterministic, and
    // twelve iterations may find nothing better than where they left the launch.)
    let opts = SolveOptions {
        threads: Some(2),
        seed: Some(8),
        resume: None,
        schedule: Schedule::DEFAULT.with_attempts(1),
        time_limit: None,
        until_stage: None,
    };
    let (_, rc) = solver::solve(&p, &opts, &mut solver::Silent, &none);
    assert_ne!(ra, rc);
}

/// Counts what an observer is told: stages started and finished, in the first attempt
/// and in later ones, the attempts started, and the rows of the finished stages.
#[derive(Default, Debug, PartialEq)]
struct Told {
    started: usize,
    finished: usize,
    later_finished: usize,
    attempts: Vec<(usize, u64)>,
    rows: Vec<SampleRecord>,
}
impl Observer for Told {
    fn stage_started(&mut self, _index: usize, _stage: &bsa::scene::Stage) {
        self.started += 1;
    }
    fn stage_finished(&mut self, _s: &Solution, r: &[SampleRecord]) {
        self.finished += 1;
        self.rows.extend_from_slice(r);
    }
    fn attempt_started(&mut self, attempt: usize, _attempts: usize, _kept: &Solution, seed: u64) {
        self.attempts.push((attempt, seed));
    }
    fn attempt_stage_finished(&mut self, _s: &Solution, r: &[SampleRecord]) {
        self.later_finished += 1;
        self.rows.extend_from_slice(r);
    }
}

#[test]
fn attempts_run_ahead_give_the_bits_and_progress_of_attempts_one_after_another() {
    let mut p = small_mickey(8);
    // Every attempt ends below the restart IoU, so that each later one is wanted.
    for s in &mut p.scene.stages {
        s.restart_iou = 1.0;
    }
    let none = AtomicUsize::new(0);
    let run = |threads| {
        let opts = SolveOptions {
            threads: Some(threads),
            seed: Some(11),
            resume: None,
            schedule: Schedule::DEFAULT.with_attempts(3),
            time_limit: None,
            until_stage: None,
        };
        let mut told = Told::default();
        let (s, records) = solver::solve(&p, &opts, &mut told, &none);
        (s, records, told)
    };
    // One thread runs the attempts one after another; two run the next one ahead.
    let (a, ra, told_a) = run(1);
    let (b, rb, told_b) = run(2);
    assert_eq!(a.attempts.len(), 3);
    assert_eq!(params_bits(&a), params_bits(&b));
    assert_eq!(ra, rb);
    let seen = |s: &Solution| -> Vec<(u64, u64, usize, bool)> {
        s.attempts
            .iter()
            .map(|t| (t.seed, t.iou.to_bits(), t.samples, t.kept))
            .collect()
    };
    assert_eq!(seen(&a), seen(&b));
    assert_eq!(a.samples, b.samples);
    assert_eq!(told_a, told_b);
    // Every record was told once, in order, with the stage that drew it.
    assert_eq!(told_b.rows, rb);
    let stages = p.scene.stages.len();
    assert_eq!(told_b.started, 3 * stages);
    assert_eq!(
        (told_b.finished, told_b.later_finished),
        (stages, 2 * stages)
    );
}

/// Raises the interrupt counter twice once the first stage is done: the solve must stop
/// and hand back a solution with one completed stage.
struct StopAfterFirstStage<'a>(&'a AtomicUsize);
impl Observer for StopAfterFirstStage<'_> {
    fn stage_finished(&mut self, _s: &Solution, _r: &[SampleRecord]) {
        self.0.store(2, Ordering::SeqCst);
    }
}

#[test]
fn resume_continues_to_the_same_result() {
    let p = small_mickey(10);
    let opts = SolveOptions {
        threads: Some(2),
        seed: Some(3),
        resume: None,
        schedule: Schedule::DEFAULT.with_attempts(1),
        time_limit: None,
        until_stage: None,
    };
    let none = AtomicUsize::new(0);
    let (full, _) = solver::solve(&p, &opts, &mut solver::Silent, &none);
    assert!(full.complete);
    let counter = AtomicUsize::new(0);
    let (partial, _) = solver::solve(&p, &opts, &mut StopAfterFirstStage(&counter), &counter);
    assert_eq!(partial.stages_completed, 1);
    assert!(!partial.complete);
    // Round-trip through JSON as the CLI does.
    let text = serde_json::to_string(&partial).unwrap();
    let partial: Solution = serde_json::from_str(&text).unwrap();
    let opts2 = SolveOptions {
        resume: Some(partial),
        ..opts
    };
    let (resumed, _) = solver::solve(&p, &opts2, &mut solver::Silent, &none);
    assert_eq!(resumed.stages_completed, 2);
    assert_eq!(params_bits(&resumed), params_bits(&full));
}

/// Raises the interrupt counter to 2 in the middle of the first stage (a double Ctrl-C).
struct StopMidFirstStage<'a>(&'a AtomicUsize);
impl Observer for StopMidFirstStage<'_> {
    fn iteration(&mut self, info: &solver::IterationInfo) {
        if info.stage_index == 0 && info.iteration == 3 {
            self.0.store(2, Ordering::SeqCst);
        }
    }
}

#[test]
fn a_stage_stopped_by_a_second_interrupt_runs_again_on_resume() {
    let mut p = small_mickey(10);
    // One run per stage, so that a completed stage has exactly its iteration cap.
    for s in &mut p.scene.stages {
        s.restarts = 0;
    }
    let counter = AtomicUsize::new(0);
    let opts = SolveOptions {
        threads: Some(2),
        seed: Some(5),
        resume: None,
        schedule: Schedule::DEFAULT.with_attempts(1),
        time_limit: None,
        until_stage: None,
    };
    let (stopped, _) = solver::solve(&p, &opts, &mut StopMidFirstStage(&counter), &counter);
    assert_eq!(stopped.stages_completed, 0);
    assert!(!stopped.complete);
    assert_eq!(stopped.stages.len(), 1);
    assert!(
        stopped.stages[0].stop.starts_with("stopped"),
        "{}",
        stopped.stages[0].stop
    );
    // The best so far is kept: it ranks no worse than the start (less contact time, or
    // as little and no more energy).
    let mut ws = p.workspace();
    let w = p.scene.stages[0].weights;
    let start = p.evaluate(&p.scene.start_parameters(), &w, &mut ws);
    let kept = p.evaluate(&stopped.parameters(), &w, &mut ws);
    let (sc, kc) = (start.outcome.own_contact, kept.outcome.own_contact);
    assert!(
        kc < sc || kc == sc && kept.total <= start.total,
        "{kept:?} vs {start:?}"
    );
    let none = AtomicUsize::new(0);
    let (resumed, _) = solver::solve(
        &p,
        &SolveOptions {
            resume: Some(stopped),
            ..opts
        },
        &mut solver::Silent,
        &none,
    );
    assert_eq!(resumed.stages_completed, 2);
    assert!(resumed.complete);
    assert_eq!(resumed.stages.len(), 2);
    assert_eq!(resumed.stages[0].iterations, 10);
}

/// The shadow of a fixed launch, compared with a committed golden image. Set
/// `BSA_UPDATE_GOLDEN=1` to regenerate it; on failure a diff image is written next to
/// the golden file (red: only in the golden, blue: only now).
#[test]
fn golden_shadow_of_a_fixed_launch() {
    let p = Problem::new(bsa::scene::load(&root().join("scenes/mickey")).unwrap());
    // Launch values written by hand: each ball thrown toward the middle of the picture,
    // the head with a spin that must not matter for a sphere.
    let params = [
        0.0, 1.6, 7.9, 0.0, 3.0, 0.0, //
        1.5, -0.4, 8.4, 0.0, 0.0, 0.0, //
        -1.5, -0.4, 8.4, 0.0, 0.0, 0.0,
    ];
    let mut ws = p.workspace();
    p.evaluate(&params, &bsa::energy::Weights::all_ones(), &mut ws);
    let golden = root().join("tests/golden/mickey_fixed_launch.png");
    let shadow = p.picture_of(&ws.mask);
    let now =
        bsa::output::picture::mask_image(shadow.width(), shadow.height(), &|x, y| shadow.get(x, y));
    if std::env::var_os("BSA_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
        now.save(&golden).unwrap();
        return;
    }
    let old = image::open(&golden)
        .expect("golden image (run with BSA_UPDATE_GOLDEN=1 to create it)")
        .to_luma8();
    assert_eq!(old.dimensions(), now.dimensions());
    let differing = old
        .pixels()
        .zip(now.pixels())
        .filter(|(a, b)| a != b)
        .count();
    if differing > 0 {
        let diff = bsa::output::picture::difference_image(
            old.width() as usize,
            old.height() as usize,
            &|x, y| old.get_pixel(x as u32, y as u32).0[0] < 128,
            &|x, y| now.get_pixel(x as u32, y as u32).0[0] < 128,
        );
        let path = golden.with_file_name("mickey_fixed_launch.diff.png");
        diff.save(&path).unwrap();
        panic!(
            "{differing} pixels differ from the golden image; see {}",
            path.display()
        );
    }
}

#[test]
fn mickey_solves_to_iou_099_without_contact() {
    let p = Problem::new(bsa::scene::load(&root().join("scenes/mickey")).unwrap());
    let none = AtomicUsize::new(0);
    let (s, records) = solver::solve(&p, &SolveOptions::default(), &mut solver::Silent, &none);
    assert!(s.iou >= 0.99, "IoU {}", s.iou);
    assert_eq!(s.n_contacts, 0);
    assert_eq!(s.t_sim, s.t);
    assert_eq!(records.len(), s.samples);
}

/// Records the launch values after every stage.
struct StageSnapshots(Vec<Vec<f64>>);
impl Observer for StageSnapshots {
    fn stage_finished(&mut self, s: &Solution, _r: &[SampleRecord]) {
        self.0.push(s.parameters());
    }
}

#[test]
fn sequential_strategy_varies_one_occluder_per_stage_then_all() {
    // Mickey with boxes for ears and the sequential strategy in automatic order.
    let d = variant("sequential", |v| {
        v["occluders"][1]["shape"] = serde_json::json!({"box": {"size": [0.5, 0.4, 0.3]}});
        v["occluders"][1]["position"] = serde_json::json!([-2.3, 0.9, 0.15]);
        v["occluders"][2]["shape"] = serde_json::json!({"box": {"size": [0.6, 0.5, 0.4]}});
        v["occluders"][2]["position"] = serde_json::json!([2.3, 0.9, 0.2]);
        let stage = v["stages"][1].clone();
        v.as_object_mut().unwrap().remove("stages");
        let mut one = stage.clone();
        one["max_iterations"] = 8.into();
        one["population"] = 12.into();
        one.as_object_mut().unwrap().remove("name");
        let mut last = one.clone();
        last["step"] = 0.05.into();
        v["strategy"] =
            serde_json::json!({"kind": "sequential", "order": "auto", "stage": one, "final": last});
    });
    let scene = bsa::scene::load(&d).unwrap();
    let names: Vec<&str> = scene.stages.iter().map(|s| s.name.as_str()).collect();
    // Largest volume first: the head sphere, then the larger box, then the smaller one.
    assert_eq!(names, ["head", "right_ear", "left_ear", "final"]);
    assert_eq!(scene.stages[3].vary, vec![0, 1, 2]);
    let p = Problem::new(scene);
    let start = p.scene.start_parameters();
    let mut snaps = StageSnapshots(Vec::new());
    let none = AtomicUsize::new(0);
    let (s, _) = solver::solve(&p, &SolveOptions::default(), &mut snaps, &none);
    assert_eq!(s.stages_completed, 4);
    let mut before = start;
    for (k, after) in snaps.0.iter().take(3).enumerate() {
        let varied = p.scene.stages[k].vary[0];
        for i in 0..3 {
            let same = before[6 * i..6 * i + 6] == after[6 * i..6 * i + 6];
            assert_eq!(
                same,
                i != varied,
                "stage {k}: occluder {i} changed={}",
                !same
            );
        }
        before = after.clone();
    }
}

#[test]
fn sequential_rounds_repeat_the_pass_and_are_checked() {
    let with_rounds = |rounds: serde_json::Value| {
        variant("rounds", move |v| {
            let mut stage = v["stages"][1].clone();
            v.as_object_mut().unwrap().remove("stages");
            stage.as_object_mut().unwrap().remove("name");
            v["strategy"] = serde_json::json!({
                "kind": "sequential", "order": ["left_ear", "head"], "rounds": rounds,
                "stage": stage, "final": stage
            });
        })
    };
    let scene = bsa::scene::load(&with_rounds(2.into())).unwrap();
    let names: Vec<&str> = scene.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["left_ear", "head", "left_ear (2)", "head (2)", "final"]
    );
    assert_eq!(scene.stages[2].vary, vec![1]);
    for bad in [0, 101] {
        let err = bsa::scene::load(&with_rounds(bad.into())).unwrap_err();
        let msg = format!("{err:#}");
        assert!(
            msg.contains("strategy.rounds") && msg.contains("1 to 100"),
            "{msg}"
        );
    }
}

#[test]
fn example_scenes_start_without_contact_near_their_targets() {
    // `bsa new`, which designed these scenes (scripts/make-examples.sh), promises start
    // guesses that fly without contact; the solver's sequential stages rely on it (a held pair that collides hides
    // every later contact from the stage's penalty).
    for name in ["fly", "tbc", "thinker"] {
        let p = Problem::new(bsa::scene::load(&root().join("scenes").join(name)).unwrap());
        let mut ws = p.workspace();
        let e = p.evaluate(
            &p.scene.start_parameters(),
            &bsa::energy::Weights::all_ones(),
            &mut ws,
        );
        assert_eq!(
            e.outcome.n_contacts, 0,
            "{name}: {:?}",
            e.outcome.first_contact
        );
        assert!(e.iou > 0.5, "{name}: start IoU {}", e.iou);
    }
}

/// A planted problem of two spheres (`bsa plant`, radii 0.3 and 0.18 m): its problem
/// and the planted launch.
fn planted_pair(name: &str) -> (Problem, Vec<f64>) {
    planted_spheres(name, "sphere:0.3,sphere:0.18")
}

/// A planted problem of the spheres `objects` (`bsa plant`): its problem and the planted
/// launch.
fn planted_spheres(name: &str, objects: &str) -> (Problem, Vec<f64>) {
    planted(name, objects, "4")
}

/// A planted problem of `objects` on a picture `width` metres wide (`bsa plant`, seed
/// 3): its problem and the planted launch.
fn planted(name: &str, objects: &str, width: &str) -> (Problem, Vec<f64>) {
    planted_seed(name, objects, width, "3")
}

/// [`planted`], from seed `seed`.
fn planted_seed(name: &str, objects: &str, width: &str, seed: &str) -> (Problem, Vec<f64>) {
    let dir = crate::util::tmpdir(name).into_child("pair");
    let (ok, _, err) = crate::util::bsa(&[
        "plant",
        dir.to_str().unwrap(),
        "--objects",
        objects,
        "--seed",
        seed,
        "--width",
        width,
    ]);
    assert!(ok, "{err}");
    let p = Problem::new(bsa::scene::load(&dir).unwrap());
    let params = launch_file(&p, &dir.join("planted.json"));
    (p, params)
}

/// The launch of a file as `bsa plant` writes `planted.json`: each occluder's name to
/// its `velocity` and `angular_velocity`.
fn launch_file(p: &Problem, path: &std::path::Path) -> Vec<f64> {
    let launches = crate::util::read_json(path);
    let mut params = vec![0.0; p.scene.variable_count()];
    for (i, o) in p.scene.occluders.iter().enumerate() {
        let l = &launches[&o.name];
        let v = |k: &str, j: usize| l[k][j].as_f64().unwrap();
        for j in 0..3 {
            params[6 * i + j] = v("velocity", j);
            params[6 * i + 3 + j] = v("angular_velocity", j);
        }
    }
    params
}

/// Sets body `i`'s launch velocity so that its centre of mass is at `to` at `t`.
fn aim(p: &Problem, params: &mut [f64], i: usize, to: glam::DVec3) {
    let (t, g) = (p.scene.t, p.scene.gravity);
    let v = (to - p.scene.occluders[i].launch_com() - 0.5 * g * t * t) / t;
    params[6 * i..6 * i + 3].copy_from_slice(&[v.x, v.y, v.z]);
}

/// Body `i`'s centre of mass at `t` after an evaluation on `ws`.
fn com(p: &Problem, ws: &bsa::evaluate::Workspace, i: usize) -> glam::DVec3 {
    let (origin, q) = ws.poses[i];
    origin + q * p.scene.occluders[i].mass.local_com
}

/// A rank that puts every sample with a contact of its own after every one without.
fn contact_free_first(e: &bsa::evaluate::Evaluation) -> f64 {
    if e.outcome.own_contact > 0.0 {
        f64::INFINITY
    } else {
        e.total
    }
}

/// Two rounds of moves of both bodies from `params`, ranked by `rank`: the IoU before,
/// the evaluation after and the report.
fn run_moves(
    p: &Problem,
    params: &mut [f64],
    rank: &dyn Fn(&bsa::evaluate::Evaluation) -> f64,
) -> Moved {
    run_moves_of(p, &[0, 1], params, rank)
}

/// [`run_moves`] on the bodies `vary`.
fn run_moves_of(
    p: &Problem,
    vary: &[usize],
    params: &mut [f64],
    rank: &dyn Fn(&bsa::evaluate::Evaluation) -> f64,
) -> Moved {
    run_moves_for(p, vary, params, rank, Purpose::Stage)
}

/// What a call of the moves did: the IoU before, the evaluation after, its report.
type Moved = (
    f64,
    bsa::evaluate::Evaluation,
    bsa::optimize::moves::MoveReport,
);

/// [`run_moves_of`], for a stage's moves or for the trades.
fn run_moves_for(
    p: &Problem,
    vary: &[usize],
    params: &mut [f64],
    rank: &dyn Fn(&bsa::evaluate::Evaluation) -> f64,
    purpose: Purpose,
) -> Moved {
    run_moves_on(p, (vary, params), rank, (purpose, 2), 2, &mut |_| {})
}

/// [`run_moves_for`] taking `max_moves` at most, on a pool of `threads`, every sample
/// shown to `record`.
fn run_moves_on(
    p: &Problem,
    (vary, params): (&[usize], &mut [f64]),
    rank: &dyn Fn(&bsa::evaluate::Evaluation) -> f64,
    (purpose, max_moves): (Purpose, usize),
    threads: usize,
    record: &mut dyn FnMut(&bsa::evaluate::Evaluation),
) -> Moved {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    let mut best = p.evaluate(params, &w, &mut ws);
    let before = best.iou;
    let held = p.hold(params, vary);
    let report = bsa::optimize::moves::improve(
        p,
        &held,
        vary,
        &w,
        rank,
        params,
        &mut best,
        bsa::optimize::moves::MoveOptions {
            max_moves,
            settled: true,
            purpose,
        },
        &pool,
        &mut ws,
        record,
    );
    (before, best, report)
}

/// The moves run their parts beside each other on the pool they are given: on one
/// thread and on two they take the same moves and draw the same samples in the same
/// order, bit for bit (the fixture's trades and polish seat, fit and evolve blocks).
#[test]
fn moves_on_two_threads_draw_the_samples_of_one_bit_for_bit() {
    let dir = crate::util::root().join("tests/fixtures/cycle-of-sizes");
    let p = Problem::new(bsa::scene::load(&dir).unwrap());
    let stuck = launch_file(&p, &dir.join("stuck.json"));
    let vary: Vec<usize> = (0..p.scene.occluders.len()).collect();
    for purpose in [Purpose::Trade, Purpose::Polish] {
        let run = |threads| {
            let mut params = stuck.clone();
            let mut totals = Vec::new();
            let (_, best, report) = run_moves_on(
                &p,
                (&vary, &mut params),
                &contact_free_first,
                (purpose, 2),
                threads,
                &mut |e| totals.push(e.total.to_bits()),
            );
            let bits: Vec<u64> = params.iter().map(|x| x.to_bits()).collect();
            (bits, best.total.to_bits(), report, totals)
        };
        let (one, two) = (run(1), run(2));
        assert!(one.3.len() > 100, "{purpose:?}: {} samples", one.3.len());
        assert_eq!(one, two, "{purpose:?}");
    }
}

/// Two chess pieces of `scenes/thinker/pieces`, planted (IoU 1), and the first piece's
/// orientation at `t` in the planted launch.
fn planted_pieces(name: &str, first: &str, second: &str) -> (Problem, Vec<f64>, glam::DQuat) {
    let pieces = root().join("scenes/thinker/pieces");
    let objects = format!(
        "mesh:{}/{first}.obj/900,mesh:{}/{second}.obj/900",
        pieces.display(),
        pieces.display()
    );
    let (p, planted) = planted(name, &objects, "0.96");
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    assert!(p.evaluate(&planted, &w, &mut ws).iou > 0.9999);
    let now = ws.poses[0].1;
    (p, planted, now)
}

/// The planted launch with the first piece turned to `want` at `t`, its spin solved on
/// the flight from `guess`.
fn turned_at_t(p: &Problem, planted: &[f64], want: glam::DQuat, guess: glam::DVec3) -> Vec<f64> {
    let mut flight = bsa::sim::flight::FreeFlight::default();
    let spin = bsa::optimize::moves::spin_reaching(p, 0, want, guess, &mut flight)
        .expect("a spin that turns the piece");
    let mut params = planted.to_vec();
    params[3..6].copy_from_slice(&spin.to_array());
    let mut ws = p.workspace();
    p.evaluate(&params, &p.scene.stages.last().unwrap().weights, &mut ws);
    assert!(
        ws.poses[0].1.angle_between(want) < 1e-5,
        "the piece misses its turn by {} rad",
        ws.poses[0].1.angle_between(want)
    );
    params
}

/// The name of the first move a call of the moves took.
fn first_taken(report: &bsa::optimize::moves::MoveReport) -> Option<&str> {
    report.taken.first().map(|m| m.name.as_str())
}

/// The moves take a launch under IoU 0.9 back over 0.97, without a contact, the first
/// move taken a `name` (see `MoveReport::taken`).
fn assert_moves_mend(p: &Problem, params: &mut [f64], name: &str) {
    let (before, best, report) = run_moves(p, params, &contact_free_first);
    assert!(before < 0.9, "IoU {before}");
    assert_eq!(first_taken(&report), Some(name), "{report:?}");
    assert!(
        best.iou > 0.97 && best.iou > before + 0.05,
        "IoU {before} -> {}",
        best.iou
    );
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn moves_mirror_a_knight_that_shows_its_profile_the_wrong_way_round() {
    let (p, planted, now) = planted_pieces("moves-mirror", "knight", "pawn");
    // The knight turned half a turn about its own long axis at `t` (a tumbling knight: its
    // spin is solved on the flight): its profile mirrored, about its centre of mass.
    let axis = now * p.scene.occluders[0].mass.long_axis();
    let want = glam::DQuat::from_axis_angle(axis, std::f64::consts::PI) * now;
    let mut params = turned_at_t(&p, &planted, want, glam::DVec3::from_slice(&planted[3..6]));
    // The first round's seat of each piece on its own place puts it back.
    assert_moves_mend(&p, &mut params, "seat");
}

#[test]
fn moves_seat_a_piece_turned_far_from_its_pose_back_on_its_part() {
    let (p, planted, now) = planted_pieces("moves-seat", "rook", "king");
    // The rook turned by 2 rad about a slanted axis at `t`, about its centre of mass: a
    // wrong face, far from every quarter and half turn of its pose.
    let axis = glam::DVec3::new(1.0, 2.0, 3.0).normalize();
    let want = glam::DQuat::from_axis_angle(axis, 2.0) * now;
    let guess = glam::DVec3::from_slice(&planted[3..6]) + axis * (2.0 / p.scene.t);
    let mut params = turned_at_t(&p, &planted, want, guess);
    // The moves seat it back on its part.
    assert_moves_mend(&p, &mut params, "seat");
}

#[test]
fn moves_fit_a_block_turned_across_its_part_back_along_it() {
    let objects = "box:0.14x0.07x0.035,box:0.07x0.035x0.035";
    let (p, planted) = planted("moves-turn", objects, "0.96");
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    assert!(p.evaluate(&planted, &w, &mut ws).iou > 0.9999);
    let now = ws.poses[0].1;
    // The long block turned a quarter turn at `t` about the vertical (its shadow lies
    // across its part), or about its own long axis (it shows the light another face).
    // The fit of its pose at `t` turns it back (blocks are not seated in a stage's
    // moves, nor turned by `reorient`).
    let quarter = std::f64::consts::FRAC_PI_2;
    for axis in [glam::DVec3::Z, now * p.scene.occluders[0].mass.long_axis()] {
        let want = glam::DQuat::from_axis_angle(axis, quarter) * now;
        let guess = glam::DVec3::from_slice(&planted[3..6]) + axis * (quarter / p.scene.t);
        let mut params = turned_at_t(&p, &planted, want, guess);
        assert_moves_mend(&p, &mut params, "pose fit");
    }
}

#[test]
fn moves_align_a_knight_turned_about_the_vertical_with_its_part() {
    let (p, planted, now) = planted_pieces("moves-align", "knight", "pawn");
    // The knight turned 0.6 rad about the vertical at `t`: its profile stands at an
    // angle to its part. A turn about the line of sight aligns the two.
    let want = glam::DQuat::from_rotation_z(0.6) * now;
    let guess = glam::DVec3::from_slice(&planted[3..6]) + glam::DVec3::Z * (0.6 / p.scene.t);
    let mut params = turned_at_t(&p, &planted, want, guess);
    assert_moves_mend(&p, &mut params, "reorient");
}

#[test]
fn moves_split_a_part_between_a_stretched_block_and_a_hidden_one() {
    // Eight blocks of the planted suite (class boxes, seed 10603), planted: IoU 1.
    let objects = "box:0.14x0.07x0.035,box:0.14x0.07x0.035,box:0.07x0.035x0.035,\
        box:0.14x0.07x0.035,box:0.07x0.035x0.035,box:0.07x0.035x0.035,\
        box:0.14x0.07x0.035,box:0.14x0.07x0.035";
    let (p, planted) = planted_seed("moves-split", objects, "1.6", "10603");
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    assert!(p.evaluate(&planted, &w, &mut ws).iou > 0.9999);
    let com = |i: usize| ws.poses[i].0 + ws.poses[i].1 * p.scene.occluders[i].mass.local_com;
    let (long, small, cover) = (0, 4, 3);
    let (c_long, c_small, c_cover) = (com(long), com(small), com(cover));
    let light = p.scene.camera.light;
    let depth = |c: glam::DVec3| (c - light).z / -light.z;
    // The small block hidden under another block's shadow, halfway from it to the
    // receiver on its line of sight; the block beside it drawn halfway to its part, so
    // that one shadow lies across both parts (the end state of the suite's solve,
    // IoU 0.94: the fill move finds no bare part large enough, and no swap helps).
    let mut params = planted.clone();
    let on = |c: glam::DVec3| light + (c - light) / depth(c);
    let hide = light + (c_cover - light) * (0.5 * (depth(c_cover) + 1.0));
    aim(&p, &mut params, small, hide);
    let middle = light + (on(c_long).lerp(on(c_small), 0.3) - light) * depth(c_long);
    aim(&p, &mut params, long, middle);
    let vary: Vec<usize> = (0..p.scene.occluders.len()).collect();
    let (before, best, report) = run_moves_of(&p, &vary, &mut params, &contact_free_first);
    assert!(before < 0.96, "IoU {before}");
    assert_eq!(first_taken(&report), Some("split"), "{report:?}");
    assert!(best.iou > 0.98, "IoU {before} -> {}", best.iou);
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn trades_mend_three_blocks_of_three_sizes_each_on_the_next_ones_part() {
    // The planted boxes12 seed 10702 as `bsa new` designed it, and the launch its solve
    // ended with before trades (IoU 0.9625): a long block end-on on a small block's
    // part, the small one high on a medium one's, the medium one high on the long
    // one's. No move of one or two bodies mends it: they take it only part of the way.
    let dir = crate::util::root().join("tests/fixtures/cycle-of-sizes");
    let p = Problem::new(bsa::scene::load(&dir).unwrap());
    let stuck = launch_file(&p, &dir.join("stuck.json"));
    let vary: Vec<usize> = (0..p.scene.occluders.len()).collect();
    let mut params = stuck.clone();
    let (before, best, _) =
        run_moves_for(&p, &vary, &mut params, &contact_free_first, Purpose::Stage);
    assert!(before < 0.965, "IoU {before}");
    // 0.9691 when written: the moves mend a little, short of what the trade mends.
    assert!(best.iou < 0.97, "IoU {before} -> {}", best.iou);
    let mut params = stuck;
    let (_, best, report) =
        run_moves_for(&p, &vary, &mut params, &contact_free_first, Purpose::Trade);
    assert_eq!(first_taken(&report), Some("trade"), "{report:?}");
    // 0.9721 when written.
    assert!(best.iou > 0.97, "IoU {before} -> {}", best.iou);
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn trades_mend_four_pieces_each_on_the_next_ones_part() {
    // Four chess pieces, planted (IoU 1), then each launched to where the next one's
    // centre was: a cycle of four, which no one trade of two or three pieces mends.
    // One move, the table of seats' best assignment of one cycle, takes the picture from
    // 0.421 to 0.978 (when written); the pairs and three-cycles that the table ranked
    // before took it to 0.835.
    let pieces = root().join("scenes/thinker/pieces");
    let objects = ["king", "rook", "bishop", "knight"]
        .map(|name| format!("mesh:{}/{name}.obj/900", pieces.display()))
        .join(",");
    let (p, planted) = planted_seed("trade-four", &objects, "0.96", "21");
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    assert!(p.evaluate(&planted, &w, &mut ws).iou > 0.9999);
    let coms: Vec<glam::DVec3> = (0..4).map(|i| com(&p, &ws, i)).collect();
    let mut params = planted.clone();
    for (i, &c) in coms.iter().enumerate() {
        aim(&p, &mut params, (i + 3) % 4, c);
    }
    let vary: Vec<usize> = (0..4).collect();
    let (before, best, report) = run_moves_on(
        &p,
        (&vary, &mut params),
        &contact_free_first,
        (Purpose::Trade, 1),
        2,
        &mut |_| {},
    );
    assert!(before < 0.5, "IoU {before}");
    assert_eq!(report.taken.len(), 1, "{report:?}");
    assert_eq!(first_taken(&report), Some("trade"), "{report:?}");
    assert!(best.iou > 0.95, "IoU {before} -> {} {report:?}", best.iou);
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn the_last_stage_trades_pieces_that_the_hints_hold_each_on_another_part() {
    // The planted chess seed 10800 as `bsa new` designed it, and the solve before trades
    // with its last stage to run again (IoU 0.9605): the queen on the king's part, the
    // king on the bishop's, the bishop on the queen's, each where its hint points. Judged
    // with the hints, no trade is better (they add 183 pixels to the 354 wrong ones).
    let (iou, contacts, _, moves) = last_stage_again("chess-cycle");
    // 0.9735 when written: the king and the bishop traded, each seated on the other's
    // place.
    assert!(iou > 0.97, "IoU {iou}");
    assert!(moves.iter().any(|m| m == "trades: seat pair"), "{moves:?}");
    assert_eq!(contacts, 0);
}

/// `bsa solve --resume` of the fixture `tests/fixtures/<name>` from its `stuck.json` (a
/// solve with its last stage to run again): the IoU it ends at, its contacts, its
/// last stage's `stop` text and the moves its passes took, each as "pass: move".
fn last_stage_again(name: &str) -> (f64, u64, String, Vec<String>) {
    let scene = crate::util::root().join("tests/fixtures").join(name);
    let out = crate::util::tmpdir(name);
    std::fs::copy(scene.join("stuck.json"), out.join("solution.json")).unwrap();
    // One attempt: what the last stage does, not what a second attempt from the start
    // guess would.
    crate::util::solve(&scene, &out, &["--resume", "--attempts", "1"]);
    let s = crate::util::read_json(&out.join("solution.json"));
    let stages = s["stages"].as_array().unwrap();
    // The record adds up: every sample the last stage counts is a row of convergence.csv
    // and is drawn by one of its passes (the one-body runs of trades and the polish
    // included).
    let last = stages.len() - 1;
    let counted = stages[last]["samples"].as_u64().unwrap();
    let rows = std::fs::read_to_string(out.join("convergence.csv"))
        .unwrap()
        .lines()
        .count() as u64
        - 1;
    let by_passes: u64 = s["passes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["stage"].as_u64() == Some(last as u64))
        .map(|p| p["samples"].as_u64().unwrap())
        .sum();
    assert_eq!((rows, by_passes), (counted, counted), "{name}");
    let moves = s["passes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["stage"].as_u64() == Some(last as u64))
        .flat_map(|p| {
            let pass = p["pass"].as_str().unwrap().to_string();
            let taken = p["moves"].as_array().cloned().unwrap_or_default();
            taken
                .into_iter()
                .map(move |m| format!("{pass}: {}", m["move"].as_str().unwrap()))
        })
        .collect();
    (
        s["iou"].as_f64().unwrap(),
        s["n_contacts"].as_u64().unwrap(),
        stages.last().unwrap()["stop"].as_str().unwrap().to_string(),
        moves,
    )
}

#[test]
fn the_last_stage_polishes_each_piece_to_its_outline() {
    // The planted chess seed 11201 as `bsa new` designed it, and its solve with the last
    // stage to run again from where it ended (IoU 0.9851): every piece on its own part,
    // a few wrong pixels along every outline, where the joint stage's runs find nothing
    // better. The polish, one piece at a time with a tenth of the one-piece stages' step,
    // mends them.
    let (iou, contacts, stop, _) = last_stage_again("chess-outline");
    // 0.9909 when written, 4 pieces of 6 moved.
    assert!(iou > 0.989, "IoU {iou}; {stop}");
    assert!(stop.contains("polished"), "{stop}");
    assert_eq!(contacts, 0);
}

#[test]
fn the_last_stage_seats_a_block_tilted_the_wrong_way() {
    // The planted boxes seed 11204 as `bsa new` designed it, and its solve with the last
    // stage to run again from where it ended (IoU 0.9916): one block's outline off all
    // round, tilted the other way, where runs of small steps (the joint stage's and the
    // polish's of one body) find nothing better. The polish's moves seat every block
    // anew on its own place and mend it.
    let (iou, contacts, stop, moves) = last_stage_again("block-seat");
    // 0.9997 when written (0.9916 without the seats), one move taken (two since the
    // fits evolve: the seat, then a fit).
    assert!(iou > 0.995, "IoU {iou}; {stop}");
    assert_eq!(
        moves.first().map(|m| m.as_str()),
        Some("polish: seat"),
        "{stop}"
    );
    assert_eq!(contacts, 0);
}

#[test]
fn the_last_stage_evolves_a_block_fit_along_a_valley_of_its_pose() {
    // The planted mix seed 11402 (two spheres, two long blocks) as `bsa new` designed
    // it, and its solve with the last stage to run again (IoU 0.9896): a block's outline
    // a pixel or two off its part, where every move of the compass search of its pose
    // alone (a turn, a shift, a change of depth) costs pixels. The polish's fits then
    // search all six at once by CMA-ES.
    let (iou, contacts, stop, moves) = last_stage_again("block-evolve");
    // 0.9927 when written: a seat, then the evolved fit (0.9921 with the compass alone,
    // whose fit is not taken).
    assert!(moves.iter().any(|m| m == "polish: pose fit"), "{moves:?}");
    assert!(iou > 0.9924, "IoU {iou}; {stop}");
    assert_eq!(contacts, 0);
}

#[test]
fn a_trade_of_blocks_ranked_fifth_by_the_table_is_refined_and_mends_the_picture() {
    // The planted boxes 11504 as `bsa new` designed it, and its solve with the last stage
    // to run again (IoU 0.9629): a long block end-on in a cluster of crossing blocks,
    // drawing a short block's part, and the short block stretched over a long block's
    // part. The table of seats ranks that trade fifth (its seats share the cluster);
    // refining only the best four left the picture at 0.9631.
    let (iou, contacts, stop, moves) = last_stage_again("block-trade");
    // 0.9733 when written.
    assert!(iou > 0.97, "IoU {iou}; {stop}");
    assert!(moves.iter().any(|m| m == "trades: trade"), "{moves:?}");
    assert_eq!(contacts, 0);
}

/// Mickey, each stage cut to a few iterations: a solve that ends far below its target.
fn short_mickey(name: &str) -> crate::util::TempDir {
    variant(name, |v| {
        for s in v["stages"].as_array_mut().unwrap() {
            s["max_iterations"] = 3.into();
            s["population"] = 8.into();
        }
    })
}

#[test]
fn a_second_attempt_runs_below_the_target_and_keeps_the_better_picture() {
    let d = short_mickey("attempts");
    let one = d.join("one");
    let two = d.join("two");
    crate::util::solve(&d, &one, &["--attempts", "1"]);
    let text = crate::util::solve(&d, &two, &[]);
    let (s1, s2) = (
        crate::util::read_json(&one.join("solution.json")),
        crate::util::read_json(&two.join("solution.json")),
    );
    // One attempt: no record of attempts.
    assert!(s1.get("attempts").is_none(), "{s1}");
    let tried = s2["attempts"].as_array().expect("attempts recorded");
    assert_eq!(tried.len(), 2, "{text}");
    assert!(text.contains("attempt 2/2"), "{text}");
    // The first attempt is the solve of one attempt, bit for bit.
    assert_eq!(tried[0]["iou"].as_f64(), s1["iou"].as_f64());
    assert_eq!(tried[0]["seed"].as_u64(), s1["seed"].as_u64());
    assert_ne!(tried[1]["seed"].as_u64(), tried[0]["seed"].as_u64());
    // Exactly one kept, the better picture, and it is the solution's.
    let kept: Vec<usize> = (0..2).filter(|&k| tried[k]["kept"] == true).collect();
    assert_eq!(kept.len(), 1, "{s2}");
    let iou = |k: usize| tried[k]["iou"].as_f64().unwrap();
    assert_eq!(iou(kept[0]), iou(0).max(iou(1)));
    assert_eq!(s2["iou"].as_f64().unwrap(), iou(kept[0]));
    // Samples count both attempts, and so does the convergence table.
    let samples: u64 = tried.iter().map(|t| t["samples"].as_u64().unwrap()).sum();
    assert_eq!(s2["samples"].as_u64().unwrap(), samples);
    let rows = std::fs::read_to_string(two.join("convergence.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(rows as u64, samples);
}

#[test]
fn a_time_limit_ends_the_solve_with_a_complete_result() {
    let d = short_mickey("time-limit");
    let out = d.join("out");
    // A limit far below one stage: the first run stops at once, the rest is skipped.
    let text = crate::util::solve(&d, &out, &["--time-limit", "0.000001"]);
    let s = crate::util::read_json(&out.join("solution.json"));
    assert_eq!(s["complete"], true, "{text}");
    assert_eq!(s["stages_completed"], s["stages_total"]);
    let stops: Vec<&str> = s["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|st| st["stop"].as_str().unwrap())
        .collect();
    assert_eq!(stops[0], "time limit", "{stops:?}");
    assert!(
        stops[1..].iter().all(|&t| t == "skipped (time limit)"),
        "{stops:?}"
    );
    // A complete result: the pictures, the exports and the report are written.
    for file in ["shadow.png", "report.html", "launch.csv", "convergence.csv"] {
        assert!(out.join(file).is_file(), "{file}: {text}");
    }
    for bad in ["0", "-1", "nan", "1e9"] {
        let (ok, _, err) = crate::util::bsa(&["solve", d.to_str().unwrap(), "--time-limit", bad]);
        assert!(!ok);
        assert!(err.contains("--time-limit must be"), "{err}");
    }
}

#[test]
fn attempts_out_of_range_are_refused_by_name() {
    let d = short_mickey("attempts-bad");
    for bad in ["0", "17"] {
        let (ok, _, err) = crate::util::bsa(&["solve", d.to_str().unwrap(), "--attempts", bad]);
        assert!(!ok);
        assert!(err.contains("--attempts must be between 1 and 16"), "{err}");
    }
}

#[test]
fn moves_fit_a_block_tilted_off_its_part_on_its_pose_at_t() {
    // Two blocks, planted: IoU 1.
    let (p, planted) = planted(
        "moves-fit-pose",
        "box:0.14x0.07x0.035,box:0.28x0.07x0.035",
        "1.6",
    );
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    assert!(p.evaluate(&planted, &w, &mut ws).iou > 0.9999);
    // The long block's launch spin changed by 0.08 rad over the flight about an axis
    // across its line of sight at `t`: the block, tumbling, ends tilted, its outline near
    // its part's with its corners moved, which no turn of a quarter or a half mends.
    let (origin, now) = ws.poses[1];
    let com = origin + now * p.scene.occluders[1].mass.local_com;
    let sight = (com - p.scene.camera.light).normalize();
    let across = sight.cross(now * glam::DVec3::X).normalize();
    let mut params = planted.clone();
    for (k, x) in (across * (0.08 / p.scene.t))
        .to_array()
        .into_iter()
        .enumerate()
    {
        params[9 + k] += x;
    }
    let (before, best, report) = run_moves(&p, &mut params, &contact_free_first);
    assert!(before < 0.97, "IoU {before}");
    assert_eq!(first_taken(&report), Some("pose fit"), "{report:?}");
    assert!(
        best.iou > 0.99 && best.iou > before + 0.02,
        "IoU {before} -> {}",
        best.iou
    );
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn moves_send_a_hidden_body_back_to_the_bare_part_of_the_target() {
    let (p, planted) = planted_pair("moves-hidden");
    let mut ws = p.workspace();
    assert!(
        p.evaluate(&planted, &bsa::energy::Weights::all_ones(), &mut ws)
            .iou
            > 0.9999
    );
    // The small sphere sent just below the large one, on its line of sight from the
    // light: its shadow hides in the large one's, and half the target is bare.
    let light = p.scene.camera.light;
    let mut params = planted.clone();
    aim(&p, &mut params, 1, light + (com(&p, &ws, 0) - light) * 1.08);
    let (before, best, report) = run_moves(&p, &mut params, &contact_free_first);
    assert!(before < 0.9, "IoU {before}");
    assert_eq!(first_taken(&report), Some("fill"), "{report:?}");
    assert!(
        best.iou > 0.95 && best.iou > before + 0.05,
        "IoU {before} -> {}",
        best.iou
    );
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn moves_swap_two_bodies_that_cover_each_others_parts() {
    let (p, planted) = planted_pair("moves-swap");
    let mut ws = p.workspace();
    p.evaluate(&planted, &bsa::energy::Weights::all_ones(), &mut ws);
    // Each sphere sent where the other was: the large one casts the small part's place
    // too big, and the small one the large part's too small.
    let (c0, c1) = (com(&p, &ws, 0), com(&p, &ws, 1));
    let mut params = planted.clone();
    aim(&p, &mut params, 0, c1);
    aim(&p, &mut params, 1, c0);
    let (before, best, report) = run_moves(&p, &mut params, &|e| e.total);
    assert_eq!(first_taken(&report), Some("swap"), "{report:?}");
    assert!(
        best.iou > before + 0.05 && best.iou > 0.9,
        "IoU {before} -> {}",
        best.iou
    );
}

/// A move is taken only where it draws a better picture (`moves::improve`): two equal
/// balls each on the other's part draw the same picture, and sending them back, though
/// it ranks better (slower launches), mends nothing.
#[test]
fn moves_take_no_swap_of_equal_balls_that_draws_the_same_picture() {
    // Seed 4: the flights of both launches stay apart.
    let (p, planted) = planted_seed("moves-equal-swap", "sphere:0.25,sphere:0.25", "4", "4");
    let w = p.scene.stages.last().unwrap().weights;
    let mut ws = p.workspace();
    let at_plant = p.evaluate(&planted, &w, &mut ws);
    let (c0, c1) = (com(&p, &ws, 0), com(&p, &ws, 1));
    let mut swapped = planted.clone();
    aim(&p, &mut swapped, 0, c1);
    aim(&p, &mut swapped, 1, c0);
    let at_swap = p.evaluate(&swapped, &w, &mut ws);
    assert_eq!(at_plant.iou, 1.0);
    assert_eq!(at_swap.iou, 1.0);
    assert_eq!(at_plant.outcome.n_contacts + at_swap.outcome.n_contacts, 0);
    // Start from the launch that ranks worse: the other, the swap, ranks better.
    let (mut params, worse, better) = if at_swap.total > at_plant.total {
        (swapped, at_swap.total, at_plant.total)
    } else {
        (planted, at_plant.total, at_swap.total)
    };
    assert!(better < worse, "{better} {worse}");
    let start = params.clone();
    let (_, best, report) = run_moves(&p, &mut params, &contact_free_first);
    assert!(report.taken.is_empty(), "{report:?}");
    assert_eq!(params, start);
    assert_eq!(best.iou, 1.0);
}

#[test]
fn bodies_each_small_on_the_others_part_swap_to_the_parts_whole_sizes() {
    // The planted suite's spheres-9400 (`bash scripts/planted-suite.sh 9400 1`): four
    // spheres of radii 0.24 to 0.29 m. Its solve left two spheres each on the other's
    // disc, both far too small for it (one kept low under the other's flight): growing
    // either in place meets the other's flight, and a swap at the sizes the discs had
    // then gained nothing (IoU 0.768). Each must go to the other's disc at the disc's
    // whole size.
    let d = crate::util::tmpdir("planted-spheres-9400");
    let dir = d.join("p");
    let (ok, _, err) = crate::util::bsa(&[
        "plant",
        dir.to_str().unwrap(),
        "--objects",
        "sphere:0.294,sphere:0.276,sphere:0.243,sphere:0.271",
        "--seed",
        "9400",
        "--width",
        "4",
        "--light-height",
        "6",
    ]);
    assert!(ok, "{err}");
    crate::util::solve(&dir, &d.join("out"), &[]);
    let solution = crate::util::read_json(&d.join("out").join("solution.json"));
    let iou = solution["iou"].as_f64().unwrap();
    assert!(iou > 0.97, "IoU {iou}");
    assert_eq!(solution["n_contacts"].as_u64(), Some(0));
}

#[test]
fn a_body_whose_shadow_left_the_canvas_is_sent_back_to_a_bare_part() {
    // One sphere at its planted place, the other far beyond the picture's side at the
    // same depth: its shadow is on no pixel of the canvas, so no term of the picture
    // sees it and a local search cannot bring it back. The fill move must.
    let (p, planted) = planted_pair("moves-off-canvas");
    let mut ws = p.workspace();
    p.evaluate(&planted, &bsa::energy::Weights::all_ones(), &mut ws);
    let c1 = com(&p, &ws, 1);
    let mut params = planted.clone();
    aim(
        &p,
        &mut params,
        1,
        c1 + glam::DVec3::new(3.0 * p.scene.receiver.width, 0.0, 0.0),
    );
    p.evaluate(&params, &bsa::energy::Weights::all_ones(), &mut ws);
    let mut alone = vec![false; 2];
    alone[1] = true;
    p.shadow_only(&alone, &mut ws);
    assert_eq!(ws.mask.count(), 0, "the shadow must be off the canvas");
    let (before, best, _) = run_moves(&p, &mut params, &contact_free_first);
    assert!(before < 0.9, "IoU {before}");
    assert!(best.iou > 0.97, "IoU {before} -> {}", best.iou);
    assert_eq!(best.outcome.n_contacts, 0);
}

#[test]
fn swapped_bodies_of_close_sizes_get_the_sizes_of_their_new_parts() {
    // Two spheres of close sizes, each where the other should be, the smaller one too low
    // (its shadow too small): a swap at the sizes the parts have now keeps one part too
    // small, and only the depth polish of the moved bodies finds the planted picture.
    let (p, planted) = planted_spheres("moves-polish", "sphere:0.3,sphere:0.27");
    let mut ws = p.workspace();
    p.evaluate(&planted, &bsa::energy::Weights::all_ones(), &mut ws);
    let (c0, c1) = (com(&p, &ws, 0), com(&p, &ws, 1));
    let light = p.scene.camera.light;
    let mut params = planted.clone();
    aim(&p, &mut params, 0, c1);
    aim(&p, &mut params, 1, light + (c0 - light) * 1.12);
    let (before, best, _) = run_moves(&p, &mut params, &contact_free_first);
    assert!(before < 0.9, "IoU {before}");
    assert!(best.iou > 0.97, "IoU {before} -> {}", best.iou);
    assert_eq!(best.outcome.n_contacts, 0);
}
