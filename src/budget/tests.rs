use super::*;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mickey() -> Problem {
    Problem::new(crate::scene::load(&root().join("scenes/mickey")).unwrap())
}

/// The launch found by `bsa solve scenes/mickey` (seed 1), rounded.
const MICKEY: [f64; 18] = [
    0.0, 1.5015, 6.3545, 0.22, 0.54, 0.23, //
    1.461, -0.3887, 7.0623, -0.17, -0.04, 0.0, //
    -1.461, -0.3887, 7.0624, 0.14, 0.13, 0.0,
];

/// A small scene of a tumbling brick (asymmetric box) and a knight (asymmetric mesh,
/// 0.5 m tall), written to a temporary folder: its problem and the folder's guard, which
/// the test keeps so that the folder is removed when it passes and kept when it fails.
fn box_and_mesh() -> (Problem, crate::test_temp::TempPath) {
    // A folder per call: the tests run in parallel threads of one process, and one
    // test must not read the scene file while another writes it.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let d = crate::test_temp::TempPath::dir("bsa-budget", &call.to_string());
    let scene = serde_json::json!({
        "name": "dragtest",
        "target": root().join("scenes/mickey/target.png"),
        "t": 1.2,
        "light": [0.0, 0.0, 6.0],
        "receiver": {"center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0], "width": 4.0, "height": 3.0},
        "table": {"center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0]},
        "occluders": [
            {"name": "brick", "shape": {"box": {"size": [0.5, 0.25, 0.12]}}, "position": [0.0, -1.5, 0.07], "density": 600.0},
            {"name": "knight", "shape": {"mesh": {"obj": root().join("scenes/thinker/pieces/knight.obj"), "scale": 8.0}}, "position": [1.5, 0.5, 0.01], "density": 700.0}
        ],
        "stages": [{"weights": {"xor": 1}}]
    });
    let f = d.join("scene.json");
    std::fs::write(&f, serde_json::to_string(&scene).unwrap()).unwrap();
    (Problem::new(crate::scene::load(&f).unwrap()), d)
}

const BOX_AND_MESH: [f64; 12] = [
    0.3, 1.2, 6.2, 3.0, 5.0, 7.0, //
    -1.1, -0.3, 6.6, 2.0, -1.0, 4.0,
];

fn mask_of(p: &Problem, poses: &[(DVec3, DQuat)]) -> crate::shadow::mask::Mask {
    let mut ws = p.workspace();
    ws.poses.copy_from_slice(poses);
    p.shadow(&mut ws);
    ws.mask.clone()
}

/// Compensation: every centre of mass within 1 mm of its vacuum position at t, the
/// IoU with drag within 0.01 of the vacuum IoU; the shadow with drag also matches
/// the vacuum shadow itself (so the test means something off the target too).
fn check_compensation(p: &Problem, params: &[f64], name: &str) {
    let b = Budget::new(p, params, DragConfig::default()).unwrap();
    let (comp, info) = b.compensate();
    let exact = vec![BodyError::default(); p.scene.occluders.len()];
    let mut bws = b.workspace();
    let iou_drag = b.iou(params, &exact, &mut bws).0;
    let drag_mask = bws.ws.mask.clone();
    let iou_comp = b.iou(&comp, &exact, &mut bws).0;
    let comp_mask = bws.ws.mask.clone();
    let vac_mask = mask_of(p, &b.vacuum_pose);
    let mut worst: f64 = 0.0;
    for i in 0..p.scene.occluders.len() {
        let before = b.drag_com(params, i, &exact[i]).distance(b.vacuum_com[i]);
        let after = b.drag_com(&comp, i, &exact[i]).distance(b.vacuum_com[i]);
        let q = b
            .drag_orientation(&comp, i)
            .angle_between(b.vacuum_pose[i].1);
        eprintln!(
            "{name} {}: drag moves the COM {:.1} mm; compensated {:.2e} mm ({} Newton steps, orientation {:.1e} rad)",
            p.scene.occluders[i].name,
            1000.0 * before,
            1000.0 * after,
            info[i].0,
            q
        );
        assert!(before > 0.01, "drag too weak to test anything: {before}");
        assert!(after < 1e-3, "{name} {i}: {after} m");
        // Compensation changes no spin, so the orientation is the vacuum one up to the
        // integrations (measured 4.2e-8 rad for the knight at 0.05 rad per RK4 step).
        assert!(q < 1e-6, "{q}");
        worst = worst.max(after);
    }
    let self_iou = energy::iou(&comp_mask, &vac_mask);
    let drag_self_iou = energy::iou(&drag_mask, &vac_mask);
    eprintln!(
        "{name}: IoU vacuum {:.4}, drag {iou_drag:.4}, compensated {iou_comp:.4}; compensated shadow vs vacuum shadow {self_iou:.5} (uncompensated {drag_self_iou:.4}); worst COM error {worst:.2e} m",
        b.vacuum_iou
    );
    assert!((iou_comp - b.vacuum_iou).abs() <= 0.01);
    assert!(self_iou >= 0.99, "{self_iou}");
    assert!(
        drag_self_iou < 0.9,
        "drag should visibly move the shadow: {drag_self_iou}"
    );
}

#[test]
fn compensation_restores_the_vacuum_poses_for_mickey() {
    let p = mickey();
    check_compensation(&p, &MICKEY, "mickey");
}

#[test]
fn compensation_restores_the_vacuum_poses_for_a_box_and_a_mesh() {
    let (p, _dir) = box_and_mesh();
    check_compensation(&p, &BOX_AND_MESH, "box+mesh");
}

#[test]
fn compensation_with_magnus_lift() {
    let p = mickey();
    let mut params = MICKEY;
    // Spin the ears fast enough that Magnus lift matters.
    params[9..12].copy_from_slice(&[0.0, 0.0, 20.0]);
    let drag = DragConfig {
        magnus: true,
        ..DragConfig::default()
    };
    let b = Budget::new(&p, &params, drag).unwrap();
    let (comp, _) = b.compensate();
    let e = BodyError::default();
    assert!(b.drag_com(&comp, 1, &e).distance(b.vacuum_com[1]) < 1e-6);
}

fn small_options(threads: usize) -> BudgetOptions {
    BudgetOptions {
        samples: 400,
        search_samples: 60,
        threads: Some(threads),
        seed: 7,
        ..BudgetOptions::default()
    }
}

#[test]
fn same_seed_gives_bit_identical_json_with_1_and_2_threads() {
    let p = mickey();
    let a = run(&p, &MICKEY, &small_options(1), &()).unwrap();
    let b = run(&p, &MICKEY, &small_options(2), &()).unwrap();
    let ja = serde_json::to_string(&a.report).unwrap();
    let jb = serde_json::to_string(&b.report).unwrap();
    assert_eq!(ja, jb);
    assert_eq!(a.ious.len(), 400);
    // Another seed draws other errors.
    let mut o = small_options(2);
    o.seed = 8;
    let c = run(&p, &MICKEY, &o, &()).unwrap();
    assert_ne!(a.ious, c.ious);
    // No errors at all: every sample is the compensated launch.
    let mut o = small_options(2);
    o.tolerances = Tolerances::ZERO;
    o.search_samples = 0;
    let d = run(&p, &MICKEY, &o, &()).unwrap();
    assert!(d.ious.iter().all(|&x| x == d.report.iou_drag_compensated));
    assert!(d.report.search.is_none());
}

#[test]
fn default_threshold_is_0_9() {
    assert_eq!(BudgetOptions::default().iou_threshold, 0.9);
    assert_eq!(IOU_THRESHOLD, 0.9);
    let p = mickey();
    let mut o = small_options(2);
    o.search_samples = 0;
    let a = run(&p, &MICKEY, &o, &()).unwrap();
    let r = &a.report;
    assert_eq!(r.iou_threshold, 0.9);
    assert!(r.threshold_unreachable.is_none());
    let frac = a.ious.iter().filter(|&&x| x >= 0.9).count() as f64 / a.ious.len() as f64;
    assert_eq!(r.monte_carlo.p_iou_at_least_threshold, frac);
    let md = r.markdown();
    assert!(md.contains("P(IoU >= 0.9)"), "{md}");
    assert!(!md.contains("nreachable"), "{md}");
    let v = serde_json::to_value(r).unwrap();
    assert_eq!(v["iou_threshold"], 0.9);
    assert!(v["threshold_unreachable"].is_null());
    assert!(v["monte_carlo"]["p_iou_at_least_threshold"].is_number());
    // A lower threshold counts more successes on the same draws.
    o.iou_threshold = 0.8;
    let b = run(&p, &MICKEY, &o, &()).unwrap();
    assert_eq!(a.ious, b.ious);
    assert!(
        b.report.monte_carlo.p_iou_at_least_threshold >= r.monte_carlo.p_iou_at_least_threshold
    );
}

#[test]
fn threshold_above_the_vacuum_iou_is_reported_unreachable() {
    let p = mickey();
    let b = Budget::new(&p, &MICKEY, DragConfig::default()).unwrap();
    assert!(
        b.vacuum_iou < 0.999 && b.vacuum_iou > 0.95,
        "{}",
        b.vacuum_iou
    );
    let mut o = small_options(2);
    o.iou_threshold = 0.999;
    let r = run(&p, &MICKEY, &o, &()).unwrap().report;
    let u = r
        .threshold_unreachable
        .as_ref()
        .expect("reported reachable");
    assert_eq!(u.below, ["vacuum", "compensated"]);
    assert_eq!(u.suggested_threshold, Some(0.95));
    assert!(u.message.contains("no launcher precision"), "{}", u.message);
    assert!(u.message.contains("--iou-threshold 0.95"), "{}", u.message);
    assert!(r.search.is_none(), "searched an unreachable threshold");
    assert_eq!(r.monte_carlo.p_iou_at_least_threshold, 0.0);
    let md = r.markdown();
    assert!(md.contains("Threshold unreachable"), "{md}");
    assert!(md.contains("Unreachable at any tolerance"), "{md}");
    assert!(md.contains("P(IoU >= 0.999)"), "{md}");
    let v = serde_json::to_value(&r).unwrap();
    assert_eq!(v["iou_threshold"], 0.999);
    assert!(v["search"].is_null());
    assert_eq!(v["threshold_unreachable"]["suggested_threshold"], 0.95);
    // The same at a reachable threshold: searched, nothing unreachable.
    o.iou_threshold = 0.95;
    let r = run(&p, &MICKEY, &o, &()).unwrap().report;
    assert!(r.threshold_unreachable.is_none());
    assert!(r.search.is_some());

    // The rules of the check itself.
    assert!(Unreachable::check(0.95, 0.95, 0.95).is_none());
    assert!(Unreachable::check(0.87, 0.91, 0.9).is_none());
    let u = Unreachable::check(0.87, 0.87, 0.9).unwrap();
    assert_eq!(u.suggested_threshold, Some(0.85));
    assert!(
        u.message
            .starts_with("the vacuum solution reaches IoU 0.8700 < threshold 0.9"),
        "{}",
        u.message
    );
    let u = Unreachable::check(0.92, 0.86, 0.9).unwrap();
    assert_eq!(u.below, ["compensated"]);
    assert_eq!(u.suggested_threshold, Some(0.85));
    assert_eq!(
        Unreachable::check(0.85, 0.85, 0.9)
            .unwrap()
            .suggested_threshold,
        Some(0.85)
    );
    assert_eq!(
        Unreachable::check(0.03, 0.03, 0.9)
            .unwrap()
            .suggested_threshold,
        None
    );
}

#[test]
fn sensitivities_and_search_are_sane() {
    let p = mickey();
    let r = run(&p, &MICKEY, &small_options(2), &()).unwrap().report;
    for s in &r.sensitivity {
        assert!(s.iou_lost_per_pct_speed > 0.0 && s.iou_lost_per_deg > 0.0);
        assert!(s.mm_per_pct_speed > 10.0, "{s:?}");
        // Spheres without Magnus lift: spin changes nothing.
        assert_eq!(s.iou_lost_per_pct_spin, 0.0);
    }
    let se = r.search.unwrap();
    let speed = &se.single[0];
    assert!(speed.largest > 0.0 && !speed.at_limit);
    assert!(se.single[2].at_limit, "spin of spheres never matters");
    for c in &speed.curve {
        assert!((0.0..=1.0).contains(&c.p_iou_at_least_threshold));
    }
}

fn tiny_solution(p: &Problem) -> Solution {
    let mut scene = p.scene.clone();
    for s in &mut scene.stages {
        s.max_iterations = 2;
        s.population = 8;
    }
    let q = Problem::new(scene);
    let none = std::sync::atomic::AtomicUsize::new(0);
    let opts = crate::optimize::solver::SolveOptions {
        threads: Some(1),
        schedule: crate::optimize::solver::Schedule::DEFAULT.with_attempts(1),
        ..Default::default()
    };
    crate::optimize::solver::solve(&q, &opts, &mut crate::optimize::solver::Silent, &none).0
}

#[test]
fn bad_input_gets_clear_errors() {
    let p = mickey();
    let good = BudgetOptions::default();
    assert!(validate_options(&p, &good).is_ok());
    let bad = |o: BudgetOptions| {
        let e = run(&p, &MICKEY, &o, &())
            .err()
            .expect("accepted bad options");
        (e.to_string(), e)
    };
    let (msg, e) = bad(BudgetOptions {
        drag: DragConfig {
            rho: -1.2,
            ..DragConfig::default()
        },
        ..good.clone()
    });
    assert!(
        matches!(e, BudgetError::Drag(DragError::Density(_))),
        "{msg}"
    );
    assert!(msg.contains("air density"), "{msg}");
    let (msg, e) = bad(BudgetOptions {
        drag: DragConfig::default().with_cd(-0.47),
        ..good.clone()
    });
    assert!(
        matches!(e, BudgetError::Drag(DragError::Coefficient { .. })),
        "{msg}"
    );
    for (k, v) in [
        (0, -1.0),
        (1, 90.0),
        (2, f64::NAN),
        (3, 500.0),
        (4, 160.0),
        (5, 90.0),
        (6, -0.1),
        (7, 60.0),
    ] {
        let mut a = good.tolerances.to_array();
        a[k] = v;
        let (msg, e) = bad(BudgetOptions {
            tolerances: Tolerances::from_array(a),
            ..good.clone()
        });
        assert!(
            matches!(e, BudgetError::Tolerance(ref t) if t.name == PARAMETERS[k].0),
            "{msg}"
        );
        assert!(
            msg.contains(&PARAMETERS[k].0.replace('_', " ")) && msg.contains("tolerance"),
            "{msg}"
        );
    }
    let (msg, _) = bad(BudgetOptions {
        samples: 0,
        ..good.clone()
    });
    assert!(msg.contains("samples"), "{msg}");
    let (_, e) = bad(BudgetOptions {
        threads: Some(0),
        ..good.clone()
    });
    assert!(matches!(e, BudgetError::Threads));
    for x in [0.0, -0.1, 1.0 + 1e-9, 1.5, f64::NAN, f64::INFINITY] {
        let (msg, e) = bad(BudgetOptions {
            iou_threshold: x,
            ..good.clone()
        });
        assert!(matches!(e, BudgetError::Threshold(_)), "{msg}");
        assert!(msg.contains("IoU threshold"), "{msg}");
    }
    for x in [1e-6, 0.5, 0.85, 1.0] {
        let o = BudgetOptions {
            iou_threshold: x,
            ..good.clone()
        };
        assert!(validate_options(&p, &o).is_ok(), "{x}");
    }
    let e = Budget::new(&p, &MICKEY[..12], DragConfig::default())
        .err()
        .unwrap();
    assert!(matches!(
        e,
        BudgetError::Parameters {
            expected: 18,
            found: 12
        }
    ));

    // Solutions: the right one passes; another scene's, another t, an edited scene fail.
    let s = tiny_solution(&p);
    check_solution_current(&p, &s).unwrap();
    let mut other = s.clone();
    other.scene = "fly".into();
    let e = check_solution_current(&p, &other).unwrap_err();
    assert!(
        matches!(e, BudgetError::Mismatch(MismatchError::Scene { .. })),
        "{e}"
    );
    let mut other = s.clone();
    other.t = 1.5;
    assert!(matches!(
        check_solution_current(&p, &other),
        Err(BudgetError::Mismatch(MismatchError::Time { .. }))
    ));
    let mut scene = p.scene.clone();
    scene.occluders[0].position += DVec3::new(0.3, 0.0, 0.0);
    let edited = Problem::new(scene);
    let e = check_solution_current(&edited, &s).unwrap_err();
    assert!(matches!(e, BudgetError::Stale { .. }), "{e}");
    assert!(e.to_string().contains("edited"), "{e}");
}

#[test]
fn diverged_samples_count_with_iou_zero() {
    let p = mickey();
    let b = Budget::new(&p, &MICKEY, DragConfig::default()).unwrap();
    let mut bws = b.workspace();
    let mut errs = vec![BodyError::default(); 3];
    errs[1].speed = f64::NAN;
    assert_eq!(b.iou(&MICKEY, &errs, &mut bws), (0.0, true));
}
