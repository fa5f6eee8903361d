use super::*;

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
fn shadows_in_image_tells_a_shadow_cut_by_the_image_edge() {
    for name in ["mickey", "thinker"] {
        let p = scene(name);
        let mut ws = p.workspace();
        p.evaluate(&p.scene.start_parameters(), &Weights::all_ones(), &mut ws);
        let n = p.scene.occluders.len();
        // Every body 1 m above the image centre: all inside.
        for pose in ws.poses.iter_mut() {
            *pose = (DVec3::new(0.0, 0.0, 1.0), DQuat::IDENTITY);
        }
        assert_eq!(p.shadows_in_image(&ws), vec![true; n], "{name}");
        // The first body moved so that its shadow straddles the right edge.
        let cam = &p.scene.camera;
        let edge = cam.pixel_to_world(cam.width_px as f64, 0.5 * cam.height_px as f64);
        ws.poses[0].0 = edge * (1.0 - 1.0 / cam.light_height()) + DVec3::new(0.0, 0.0, 1.0);
        let inside = p.shadows_in_image(&ws);
        assert!(!inside[0], "{name}: a shadow across the edge is not inside");
        assert!(inside[1..].iter().all(|&b| b), "{name}");
        // Behind the light plane: outside.
        ws.poses[0].0 = DVec3::new(0.0, 0.0, cam.light_height() + 1.0);
        assert!(!p.shadows_in_image(&ws)[0], "{name}");
    }
}
