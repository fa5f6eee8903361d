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

/// The largest size of each error kind of `kinds` alone (none for an empty range), and
/// the largest common factor on `base`, that keep `P(IoU >= threshold) >= PROBABILITY_TARGET` over `m` samples:
/// (size, at its limit) per kind, then (factor, at its limit).
type Largest = (Vec<(f64, bool)>, (f64, bool));

/// The search of [`Largest`], each kind's bracket starting from `start` and bounded by
/// [`PARAMETERS`] (the timing also by a third of `t`).
fn largest_each(
    b: &Budget,
    comp: &[f64],
    (kinds, base, start): (std::ops::Range<usize>, &Tolerances, &Tolerances),
    (m, seed, threshold): (usize, u64, f64),
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) -> Largest {
    let limits = limits(b.problem.scene.t);
    let ok = |tol: &Tolerances| b.reaches(comp, tol, m, seed, threshold, pool);
    let start = start.to_array();
    let single = kinds
        .clone()
        .map(|p| {
            let at = |s: f64| {
                let mut a = [0.0; KINDS];
                a[p] = s;
                Tolerances::from_array(a)
            };
            let r = largest(start[p], limits[p], &mut |s| ok(&at(s)));
            progress.advance(1);
            r
        })
        .collect();
    let base = base.to_array();
    let max_scale = (0..KINDS)
        .filter(|&p| base[p] > 0.0)
        .map(|p| limits[p] / base[p])
        .fold(f64::INFINITY, f64::min);
    let joint = if max_scale.is_finite() {
        let scaled = |s: f64| Tolerances::from_array(base.map(|u| u * s));
        largest(1.0, max_scale, &mut |s| ok(&scaled(s)))
    } else {
        (0.0, false)
    };
    progress.advance(1);
    (single, joint)
}

pub(super) fn search(
    b: &Budget,
    comp: &[f64],
    opts: &BudgetOptions,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) -> ToleranceSearch {
    let (m, seed) = (opts.search_samples, opts.seed);
    let user = opts.tolerances;
    // Each bracket starts from the requested size, or the default where none is asked.
    let defaults = Tolerances::default().to_array();
    let start = Tolerances::from_array(std::array::from_fn(|p| {
        if user.to_array()[p] > 0.0 {
            user.to_array()[p]
        } else {
            defaults[p]
        }
    }));
    let stats = |tol: &Tolerances| {
        let (ious, diverged) = b.monte_carlo(comp, tol, m, seed, pool, &());
        IouStats::new(&ious, diverged, opts.iou_threshold)
    };
    progress.start("tolerance search", KINDS as u64 + 1);
    let (found, (joint_scale, joint_at_limit)) = largest_each(
        b,
        comp,
        (0..KINDS, &user, &start),
        (m, seed, opts.iou_threshold),
        pool,
        progress,
    );
    let single = found
        .into_iter()
        .zip(PARAMETERS)
        .enumerate()
        .map(|(p, ((best, at_limit), (name, unit, _)))| {
            let top = if best > 0.0 {
                2.0 * best
            } else {
                2.0 * start.to_array()[p]
            };
            let top = top.min(limits(b.problem.scene.t)[p]);
            let curve = (0..CURVE_POINTS)
                .map(|j| {
                    let size = top * j as f64 / (CURVE_POINTS - 1) as f64;
                    let mut a = [0.0; KINDS];
                    a[p] = size;
                    let s = stats(&Tolerances::from_array(a));
                    CurvePoint {
                        size,
                        mean: s.mean,
                        p5: s.p5,
                        p_iou_at_least_threshold: s.p_iou_at_least_threshold,
                    }
                })
                .collect();
            SingleTolerance {
                parameter: name.to_string(),
                unit: unit.to_string(),
                largest: best,
                at_limit,
                curve,
            }
        })
        .collect();
    progress.finish();
    ToleranceSearch {
        samples_per_evaluation: m,
        single,
        joint_scale,
        joint_tolerances: Tolerances::from_array(user.to_array().map(|u| u * joint_scale)),
        joint_at_limit,
    }
}

/// What launcher a solution needs ([`LauncherNeeds`]): in a vacuum, as the solver flies,
/// on [`NEEDS_SAMPLES`] draws per evaluation with `seed`.
pub fn needs(
    problem: &Problem,
    params: &[f64],
    seed: u64,
    threads: Option<usize>,
) -> Result<LauncherNeeds, BudgetError> {
    let b = Budget::vacuum(problem, params)?;
    let threshold = b.vacuum_iou - NEEDS_MARGIN;
    let model = Tolerances {
        cd_pct: 0.0,
        ..Tolerances::default()
    };
    let pool = thread_pool(threads);
    let (found, (scale, scale_at_limit)) = largest_each(
        &b,
        params,
        (0..KINDS - 1, &model, &model),
        (NEEDS_SAMPLES, seed, threshold),
        &pool,
        &(),
    );
    let single = found
        .into_iter()
        .zip(PARAMETERS)
        .zip(model.to_array())
        .map(
            |(((largest, at_limit), (name, unit, _)), model)| NeededTolerance {
                parameter: name.to_string(),
                unit: unit.to_string(),
                largest,
                at_limit,
                model,
            },
        )
        .collect();
    Ok(LauncherNeeds {
        iou: b.vacuum_iou,
        threshold,
        probability: PROBABILITY_TARGET,
        samples: NEEDS_SAMPLES,
        single,
        scale,
        scale_at_limit,
    })
}

/// Launch `params` at the launcher `tol`, in a vacuum, on the calling thread (callers run
/// several side by side): `P(IoU >= IoU - NEEDS_MARGIN)` over `samples` draws from
/// `seed`, and the largest factor on the launcher's errors that keeps it at
/// `PROBABILITY_TARGET` over `scale_samples` draws per try (0 when even a perfect
/// launcher is not enough).
pub fn at_launcher(
    problem: &Problem,
    params: &[f64],
    tol: &Tolerances,
    (samples, scale_samples, seed): (usize, usize, u64),
) -> Result<(f64, f64), BudgetError> {
    let b = Budget::vacuum(problem, params)?;
    let threshold = b.vacuum_iou - NEEDS_MARGIN;
    let pool = thread_pool(Some(1));
    let (ious, diverged) = b.monte_carlo(params, tol, samples, seed, &pool, &());
    let p = IouStats::new(&ious, diverged, threshold).p_iou_at_least_threshold;
    let base = Tolerances {
        cd_pct: 0.0,
        ..*tol
    };
    let (_, (scale, _)) = largest_each(
        &b,
        params,
        (0..0, &base, &base),
        (scale_samples, seed, threshold),
        &pool,
        &(),
    );
    Ok((p, scale))
}
