//! Finite-difference sensitivities and the tolerance search (bracketing, then
//! bisection, on common random draws).

use super::*;

pub(super) fn sensitivities(
    b: &Budget,
    comp: &[f64],
    base: f64,
    pool: &rayon::ThreadPool,
) -> Vec<Sensitivity> {
    let scene = &b.problem.scene;
    let n = scene.occluders.len();
    let launched: Vec<usize> = (0..n).filter(|&i| scene.occluders[i].launched).collect();
    pool.install(|| {
        launched
            .par_iter()
            .map_init(
                || b.workspace(),
                |bws, &i| {
                    let com0 = b.drag_com(comp, i, &BodyError::default());
                    // Mean IoU lost and mean COM shift (mm) over a set of single-body errors.
                    let mut eval = |errs: &[BodyError]| -> (f64, f64) {
                        let mut all = vec![BodyError::default(); n];
                        let (mut lost, mut mm) = (0.0, 0.0);
                        for e in errs {
                            all[i] = *e;
                            lost += base - b.iou(comp, &all, bws).0;
                            mm += 1000.0 * b.drag_com(comp, i, e).distance(com0);
                        }
                        (lost / errs.len() as f64, mm / errs.len() as f64)
                    };
                    let one = |f: &dyn Fn(f64) -> BodyError| [f(1.0), f(-1.0)];
                    let (s, s_mm) = eval(&one(&|x| BodyError {
                        speed: 0.01 * x,
                        ..Default::default()
                    }));
                    let d = 1f64.to_radians();
                    let (a, a_mm) = eval(&[
                        BodyError {
                            direction: [d, 0.0],
                            ..Default::default()
                        },
                        BodyError {
                            direction: [-d, 0.0],
                            ..Default::default()
                        },
                        BodyError {
                            direction: [0.0, d],
                            ..Default::default()
                        },
                        BodyError {
                            direction: [0.0, -d],
                            ..Default::default()
                        },
                    ]);
                    let (tm, t_mm) = eval(&one(&|x| BodyError {
                        timing: 0.001 * x,
                        ..Default::default()
                    }));
                    let (sp, _) = eval(&one(&|x| BodyError {
                        spin: 0.01 * x,
                        ..Default::default()
                    }));
                    let (cd, cd_mm) = eval(&one(&|x| BodyError {
                        cd: 0.01 * x,
                        ..Default::default()
                    }));
                    Sensitivity {
                        name: scene.occluders[i].name.clone(),
                        iou_lost_per_pct_speed: s,
                        iou_lost_per_deg: a,
                        iou_lost_per_ms: tm,
                        iou_lost_per_pct_spin: sp,
                        iou_lost_per_pct_cd: cd,
                        mm_per_pct_speed: s_mm,
                        mm_per_deg: a_mm,
                        mm_per_ms: t_mm,
                        mm_per_pct_cd: cd_mm,
                    }
                },
            )
            .collect()
    })
}

/// Largest `s` in `[0, limit]` with `ok(s)`, assuming `ok` is (nearly) monotone: bracket
/// by doubling from `start`, then bisect. Returns (largest, at_limit).
pub(super) fn largest(start: f64, limit: f64, ok: &mut dyn FnMut(f64) -> bool) -> (f64, bool) {
    if !ok(0.0) {
        return (0.0, false);
    }
    let mut lo = 0.0;
    let mut hi = start.clamp(limit * 1e-6, limit);
    loop {
        if !ok(hi) {
            break;
        }
        lo = hi;
        if hi >= limit {
            return (limit, true);
        }
        hi = (2.0 * hi).min(limit);
    }
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, false)
}

pub(super) fn search(
    b: &Budget,
    comp: &[f64],
    opts: &BudgetOptions,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) -> ToleranceSearch {
    let m = opts.search_samples;
    let seed = opts.seed;
    let t = b.problem.scene.t;
    let limits: Vec<f64> = PARAMETERS
        .iter()
        .map(|(name, _, max)| {
            if *name == "timing" {
                max.min(t * 1000.0 / 3.0)
            } else {
                *max
            }
        })
        .collect();
    let defaults = Tolerances::default().to_array();
    let user = opts.tolerances.to_array();
    let stats = |tol: &Tolerances| {
        let (ious, diverged) = b.monte_carlo(comp, tol, m, seed, pool, &());
        IouStats::new(&ious, diverged, opts.iou_threshold)
    };
    let ok = |tol: &Tolerances| b.reaches(comp, tol, m, seed, opts.iou_threshold, pool);
    progress.start("tolerance search", 6);
    let mut single = Vec::new();
    for (p, (name, unit, _)) in PARAMETERS.iter().enumerate() {
        let at = |s: f64| {
            let mut a = [0.0; 5];
            a[p] = s;
            Tolerances::from_array(a)
        };
        let start = if user[p] > 0.0 { user[p] } else { defaults[p] };
        let (best, at_limit) = largest(start, limits[p], &mut |s| ok(&at(s)));
        let top = if best > 0.0 { 2.0 * best } else { 2.0 * start }.min(limits[p]);
        let curve = (0..CURVE_POINTS)
            .map(|j| {
                let size = top * j as f64 / (CURVE_POINTS - 1) as f64;
                let s = stats(&at(size));
                CurvePoint {
                    size,
                    mean: s.mean,
                    p5: s.p5,
                    p_iou_at_least_threshold: s.p_iou_at_least_threshold,
                }
            })
            .collect();
        single.push(SingleTolerance {
            parameter: name.to_string(),
            unit: unit.to_string(),
            largest: best,
            at_limit,
            curve,
        });
        progress.advance(1);
    }
    // The largest common factor on the requested tolerances.
    let max_scale = user
        .iter()
        .zip(&limits)
        .filter(|(u, _)| **u > 0.0)
        .map(|(u, l)| l / u)
        .fold(f64::INFINITY, f64::min);
    let (joint_scale, joint_at_limit) = if max_scale.is_finite() {
        let scaled = |s: f64| Tolerances::from_array(user.map(|u| u * s));
        largest(1.0, max_scale, &mut |s| ok(&scaled(s)))
    } else {
        (0.0, false)
    };
    progress.advance(1);
    progress.finish();
    ToleranceSearch {
        samples_per_evaluation: m,
        single,
        joint_scale,
        joint_tolerances: Tolerances::from_array(user.map(|u| u * joint_scale)),
        joint_at_limit,
    }
}
