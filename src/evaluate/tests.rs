use super::*;
use crate::sim::flight::RotationKind;

fn scene(name: &str) -> Problem {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    Problem::new(crate::scene::load(&dir).expect("example scene loads"))
}

/// The bits of everything a sample produces.
fn fingerprint(e: &Evaluation, ws: &Workspace) -> (Vec<u64>, Outcome, Mask, Vec<[u64; 7]>) {
    let mut bits: Vec<u64> = e.raw.iter().map(|x| x.to_bits()).collect();
    bits.extend([e.total.to_bits(), e.iou.to_bits()]);
    let poses = ws
        .poses
        .iter()
        .map(|(p, q)| {
            let v = [p.x, p.y, p.z, q.x, q.y, q.z, q.w];
            v.map(f64::to_bits)
        })
        .collect();
    // `own_contact` differs by design: a held evaluation counts only the contacts of
    // the bodies it varies (see `own_contact_counts_only_what_a_stage_can_change`).
    let outcome = Outcome {
        own_contact: 0.0,
        ..e.outcome
    };
    (bits, outcome, ws.mask.clone(), poses)
}

/// Fly's start guess with its first two blocks sent into each other: both launched
/// straight at the other's launch point, they meet within 0.1 s.
fn fly_with_a_collision() -> (Problem, Vec<f64>) {
    let p = scene("fly");
    let mut params = p.scene.start_parameters();
    let (a, b) = (
        p.scene.occluders[0].launch_com(),
        p.scene.occluders[1].launch_com(),
    );
    for (i, from, to) in [(0, a, b), (1, b, a)] {
        let mut l = Launch::get(&params, i);
        l.velocity = (to - from) / 0.2 + DVec3::new(0.0, 0.0, 1.0);
        l.set(&mut params, i);
    }
    (p, params)
}

#[test]
fn own_contact_counts_only_what_a_stage_can_change() {
    let (p, params) = fly_with_a_collision();
    let w = Weights::all_ones();
    let mut ws = p.workspace();
    let full = p.evaluate(&params, &w, &mut ws);
    assert!(
        full.outcome.n_contacts > 0 && full.outcome.t_sim < 0.2,
        "{full:?}"
    );
    assert_eq!(full.outcome.own_contact, full.raw[Term::Contact as usize]);
    // A stage that varies a third block: the collision of two held blocks is not its own.
    let held = p.hold(&params, &[3]);
    let e = p.evaluate_held(&held, &params, &w, &mut ws);
    assert_eq!(
        e.outcome.t_sim, full.outcome.t_sim,
        "the reports still see it"
    );
    assert_eq!(e.outcome.own_contact, 0.0);
    // A stage that varies one of the two: its own.
    let mut held = p.hold(&params, &[0]);
    let e = p.evaluate_held(&held, &params, &w, &mut ws);
    assert!(e.outcome.own_contact >= p.scene.t - 0.2, "{e:?}");
    // ... unless the other is still at its start guess (not placed yet).
    let mut unplaced = vec![false; p.scene.occluders.len()];
    unplaced[1] = true;
    held.ignore_contacts_with(&unplaced);
    let e = p.evaluate_held(&held, &params, &w, &mut ws);
    assert_eq!(e.outcome.t_sim, full.outcome.t_sim);
    assert!(e.outcome.own_contact < full.outcome.own_contact, "{e:?}");
}

#[test]
fn held_samples_are_bit_identical_to_full_ones_on_every_example() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut contacts = 0;
    for name in ["mickey", "fly", "tbc", "thinker"] {
        let p = scene(name);
        let n = p.scene.occluders.len();
        let launched: Vec<usize> = (0..n).filter(|&i| p.scene.occluders[i].launched).collect();
        let all = Weights::all_ones();
        let (mut full_ws, mut held_ws) = (p.workspace(), p.workspace());
        for round in 0..6 {
            // A base near the start guess, and a random set of varying occluders
            // (one, a few, or all of them).
            let mut base = p.scene.start_parameters();
            for x in base.iter_mut() {
                *x += rng.random_range(-0.5..0.5);
            }
            let k = match round {
                0 => 1,
                1 => launched.len(),
                _ => rng.random_range(1..=launched.len()),
            };
            let mut vary = launched.clone();
            for i in (1..vary.len()).rev() {
                vary.swap(i, rng.random_range(0..=i));
            }
            vary.truncate(k);
            vary.sort_unstable();
            let held = p.hold(&base, &vary);
            for _ in 0..6 {
                let mut params = base.clone();
                for &i in &vary {
                    for x in &mut params[6 * i..6 * i + 6] {
                        *x += rng.random_range(-1.5..1.5);
                    }
                }
                let full = p.evaluate(&params, &all, &mut full_ws);
                let cached = p.evaluate_held(&held, &params, &all, &mut held_ws);
                contacts += usize::from(full.outcome.n_contacts > 0);
                assert!(
                    fingerprint(&full, &full_ws) == fingerprint(&cached, &held_ws),
                    "{name}: vary {vary:?}: {full:?} != {cached:?}"
                );
            }
        }
    }
    // The comparison covers samples with contacts, not only clean flights.
    assert!(contacts > 10, "only {contacts} samples with a contact");
}

#[test]
fn samples_evaluated_in_a_batch_give_the_bits_of_each_alone() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let bits = |e: &Evaluation| {
        let mut b: Vec<u64> = e.raw.iter().map(|x| x.to_bits()).collect();
        b.extend([e.total.to_bits(), e.iou.to_bits()]);
        (b, e.outcome)
    };
    let mut tumbling = 0;
    for name in ["fly", "tbc", "thinker"] {
        let p = scene(name);
        let n = p.scene.occluders.len();
        let all = Weights::all_ones();
        let (mut alone_ws, mut batch_ws) = (p.workspace(), p.workspace());
        for vary in [vec![0], vec![1, 2], (0..n).collect()] {
            let base = p.scene.start_parameters();
            let held = p.hold(&base, &vary);
            for size in 1..=MAX_BATCH {
                let params: Vec<Vec<f64>> = (0..size)
                    .map(|k| {
                        let mut params = base.clone();
                        for &i in &vary {
                            for x in &mut params[6 * i..6 * i + 6] {
                                *x += rng.random_range(-2.0..2.0);
                            }
                        }
                        // One sample of the largest batch spins past what a launch can.
                        if k == 2 && size == MAX_BATCH {
                            params[6 * vary[0] + 3] = 1e3;
                        }
                        params
                    })
                    .collect();
                let mut out = vec![Evaluation::diverged(); size];
                p.evaluate_held_draws(&held, &params, &all, 0, &mut batch_ws, &mut out);
                for (params, batched) in params.iter().zip(&out) {
                    let alone = p.evaluate_held(&held, params, &all, &mut alone_ws);
                    assert_eq!(bits(&alone), bits(batched), "{name}: vary {vary:?}");
                }
                tumbling += vary
                    .iter()
                    .filter(|&&i| alone_ws.flights[i].rotation_kind() == RotationKind::Asymmetric)
                    .count();
            }
        }
    }
    // The batches integrate grids side by side, not only closed forms.
    assert!(tumbling > 10, "only {tumbling} tumbling flights");
}

/// Every body 1 m above the image centre, unturned, but the first, moved so that its
/// shadow straddles the picture's right edge.
fn centre_all_but_one_on_the_edge(p: &Problem, ws: &mut Workspace) {
    for pose in ws.poses.iter_mut() {
        *pose = (DVec3::new(0.0, 0.0, 1.0), DQuat::IDENTITY);
    }
    let cam = &p.scene.camera;
    let edge = cam.pixel_to_world(cam.width_px as f64, 0.5 * cam.height_px as f64);
    ws.poses[0].0 = edge * (1.0 - 1.0 / cam.light_height()) + DVec3::new(0.0, 0.0, 1.0);
}

#[test]
fn shadows_in_image_tells_a_shadow_cut_by_the_image_edge() {
    for name in ["mickey", "thinker"] {
        let p = scene(name);
        let mut ws = p.workspace();
        p.evaluate(&p.scene.start_parameters(), &Weights::all_ones(), &mut ws);
        let n = p.scene.occluders.len();
        // Every body 1 m above the image centre: all inside.
        centre_all_but_one_on_the_edge(&p, &mut ws);
        ws.poses[0] = ws.poses[1];
        assert_eq!(p.shadows_in_image(&ws), vec![true; n], "{name}");
        // The first body moved so that its shadow straddles the right edge.
        centre_all_but_one_on_the_edge(&p, &mut ws);
        let inside = p.shadows_in_image(&ws);
        assert!(!inside[0], "{name}: a shadow across the edge is not inside");
        assert!(inside[1..].iter().all(|&b| b), "{name}");
        // Behind the light plane: outside.
        ws.poses[0].0 = DVec3::new(0.0, 0.0, p.scene.camera.light_height() + 1.0);
        assert!(!p.shadows_in_image(&ws)[0], "{name}");
    }
}

/// A shadow across the picture's edge counts beyond it as extra shadow, in XOR and in
/// the IoU: before the canvas, the part beyond cost nothing, and solves hid bodies there.
#[test]
fn a_shadow_beyond_the_picture_counts_as_extra_shadow() {
    for name in ["mickey", "thinker"] {
        let p = scene(name);
        let mut ws = p.workspace();
        p.evaluate(&p.scene.start_parameters(), &Weights::all_ones(), &mut ws);
        centre_all_but_one_on_the_edge(&p, &mut ws);
        p.shadow(&mut ws);
        let picture = p.picture_of(&ws.mask);
        assert_eq!(
            (picture.width(), picture.height()),
            (p.scene.target.width(), p.scene.target.height())
        );
        let beyond = ws.mask.count() - picture.count();
        assert!(
            beyond > 0,
            "{name}: part of the shadow lies beyond the edge"
        );
        let mut raw = [0.0; TERM_COUNT];
        energy::image_terms(&p.target, &ws.mask, &Weights::all_ones(), &mut raw);
        let inside = picture.xor_count(&p.scene.target);
        assert_eq!(raw[Term::Xor as usize], (inside + beyond) as f64, "{name}");
        let canvas_iou = energy::iou(&ws.mask, &p.target.mask);
        assert!(
            canvas_iou < energy::iou(&picture, &p.scene.target),
            "{name}"
        );
    }
}

/// Mickey with its scene edited by `edit` (pictures, hold, positions), rebuilt.
fn mickey_with(edit: impl FnOnce(&mut crate::scene::Scene)) -> Problem {
    let mut s = scene("mickey").scene;
    edit(&mut s);
    Problem::new(s)
}

/// The image and scene energy of every instant of `p`'s plan, each on its own.
fn instant_energies(p: &Problem, params: &[f64], w: &Weights) -> Vec<f64> {
    let mut ws = p.workspace();
    p.fly(params, &mut ws);
    p.plan
        .instants
        .iter()
        .map(|inst| {
            p.shadow_at(inst.t, &mut ws);
            let mut r = [0.0; TERM_COUNT];
            energy::image_terms(&p.pictures[inst.picture], &ws.mask, w, &mut r);
            let pic = &p.scene.pictures[inst.picture];
            p.hint_and_barrier(&pic.hints, &p.pictures[inst.picture], &ws, &mut r, None);
            energy::weighted_total(&r, w)
        })
        .collect()
}

#[test]
fn a_hold_scores_the_mean_or_the_worst_of_its_instants() {
    use crate::scene::{Hold, HoldObjective};
    for objective in [HoldObjective::Mean, HoldObjective::Worst] {
        let p = mickey_with(|s| {
            s.hold = Some(Hold {
                window: 0.1,
                instants: Some(5),
                fps: 60.0,
                objective,
            })
        });
        assert_eq!(p.plan.instants.len(), 5);
        assert!((p.plan.instants.iter().map(|i| i.weight).sum::<f64>() - 1.0).abs() < 1e-15);
        // The instant at t is evaluated last, so that the workspace ends with its shadow.
        assert_eq!(p.plan.instants[4].t, p.scene.t);
        assert!((p.plan.horizon - 1.3).abs() < 1e-12);
        let params = p.start_parameters();
        let w = p.scene.stages[1].weights;
        let e = p.evaluate(&params, &w, &mut p.workspace());
        let energies = instant_energies(&p, &params, &w);
        let physics = w.get(Term::Contact) * e.raw[Term::Contact as usize]
            + w.get(Term::Reg) * e.raw[Term::Reg as usize];
        let image = match objective {
            HoldObjective::Mean => energies.iter().sum::<f64>() / 5.0,
            HoldObjective::Worst => energies.iter().copied().fold(f64::MIN, f64::max),
        };
        let want = image + physics;
        assert!(
            (e.total - want).abs() <= 1e-9 * want.abs(),
            "{objective:?}: {} vs {want}",
            e.total
        );
        // The mean and the worst differ here: the test can tell them apart.
        let mean = energies.iter().sum::<f64>() / 5.0;
        assert!(energies.iter().any(|&x| (x - mean).abs() > 1e-3 * mean));
    }
}

#[test]
fn a_sequence_forbids_contacts_up_to_its_last_picture() {
    // Mickey's start guess has its head meet an ear at 1.15 s: after a picture at 1.1 s,
    // before one at 1.2 s.
    let early = |s: &mut crate::scene::Scene| {
        s.t = 1.1;
        s.pictures[0].t = 1.1;
    };
    let single = mickey_with(early);
    let params = scene("mickey").start_parameters();
    let w = Weights::all_ones();
    let e = single.evaluate(&params, &w, &mut single.workspace());
    assert_eq!(e.outcome.n_contacts, 0);
    let sequence = mickey_with(|s| {
        let mut first = s.pictures[0].clone();
        first.t = 1.1;
        first.weight = 0.5;
        s.pictures[0].weight = 0.5;
        s.pictures.insert(0, first);
    });
    assert_eq!(sequence.plan.horizon, 1.2);
    let e = sequence.evaluate(&params, &w, &mut sequence.workspace());
    assert!(e.outcome.n_contacts > 0 && e.outcome.t_sim > 1.1 && e.outcome.t_sim < 1.2);
    // The reported IoU is the worse picture's.
    let frames = sequence.frame_ious(&params, &mut sequence.workspace());
    assert_eq!(frames.len(), 2);
    assert_eq!(e.iou, frames[0].iou.min(frames[1].iou));
}

#[test]
fn robust_samples_share_their_errors_within_a_draw() {
    let mut p = scene("mickey");
    p.set_robust(Robust {
        tolerances: crate::sim::launch_error::Tolerances::default(),
        draws: 4,
        reference_draws: 8,
        quantile: None,
    });
    assert_eq!(p.plan.shadows_per_sample(), 5);
    let params = p.start_parameters();
    let w = p.scene.stages[1].weights;
    let held = p.hold(&params, &[0, 1, 2]);
    let mut ws = p.workspace();
    let at =
        |draw: u64, ws: &mut Workspace| p.evaluate_held_draw(&held, &params, &w, draw, ws).total;
    let a = at(11, &mut ws);
    assert_eq!(a.to_bits(), at(11, &mut p.workspace()).to_bits());
    assert_ne!(a, at(12, &mut ws));
    // The reference draw is what `evaluate` scores.
    let r = p.evaluate(&params, &w, &mut ws).total;
    assert_eq!(r.to_bits(), at(REFERENCE_DRAW, &mut ws).to_bits());
    // Without errors the robust terms are the nominal ones: a zero tolerance gives the
    // nominal energy.
    let mut exact = scene("mickey");
    let plain = exact.evaluate(&params, &w, &mut exact.workspace()).total;
    exact.set_robust(Robust {
        tolerances: crate::sim::launch_error::Tolerances::ZERO,
        draws: 3,
        reference_draws: 3,
        quantile: Some(0.5),
    });
    let zero = exact.evaluate(&params, &w, &mut exact.workspace()).total;
    assert!((zero - plain).abs() <= 1e-9 * plain, "{zero} vs {plain}");
}

#[test]
fn free_positions_penalise_launches_off_the_table_or_overlapping() {
    let p = mickey_with(|s| s.positions = crate::scene::LaunchPositions::Free);
    let mut params = p.start_parameters();
    assert_eq!(params.len(), 8 * 3);
    assert_eq!(p.launch_violations(None, &params), (0, 0.0));
    let w = p.scene.stages[1].weights;
    let ok = p.evaluate(&params, &w, &mut p.workspace()).total;
    // The head (at (0, -2)) moved onto the left ear (at (-2.3, 0.9)).
    params[18] = -2.3;
    params[19] = 2.9;
    let (bad, depth) = p.launch_violations(None, &params);
    assert!(bad >= 1 && depth > 0.5, "{bad} {depth}");
    assert!(p.evaluate(&params, &w, &mut p.workspace()).total > 1e9);
    // Off the 40 m table.
    params[18] = 25.0;
    params[19] = 0.0;
    assert_eq!(p.launch_violations(None, &params).0, 1);
    // A position moves the launch: the same offset in the scene gives the same sample.
    params[18] = 0.5;
    params[19] = 0.25;
    let moved = p.evaluate(&params, &w, &mut p.workspace());
    let fixed = mickey_with(|s| s.occluders[0].position += DVec3::new(0.5, 0.25, 0.0));
    let again = fixed.evaluate(&params[..18], &w, &mut fixed.workspace());
    assert_eq!(moved.total.to_bits(), again.total.to_bits());
    assert_ne!(moved.total, ok);
}
