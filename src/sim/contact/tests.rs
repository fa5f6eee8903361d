use super::*;
use crate::geometry::distance::table_shape;
use crate::geometry::shape::Shape;
use crate::sim::flight::{FlightConfig, FreeFlight, LaunchState};
use rapier3d::parry::shape::Ball;
use std::sync::Arc;

fn flight(shape: &Shape, pos: DVec3, v: DVec3, w: DVec3, g: DVec3, t_max: f64) -> FreeFlight {
    let mp = shape.mass_properties(1000.0);
    let mut f = FreeFlight::default();
    f.reset(
        &mp,
        LaunchState {
            origin: pos,
            orientation: DQuat::IDENTITY,
            velocity: v,
            angular_velocity: w,
        },
        g,
        t_max,
        &FlightConfig::default(),
    );
    f
}

/// A stream of numbers uniform in `[0, 1)` (a linear congruential generator).
fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn head_on_balls_collide_at_the_analytic_time() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Sphere { radius: 0.25 };
    // Two balls 4 m apart approaching at 2 m/s each: gap 3.5 m closes at 4 m/s.
    let a = flight(
        &s,
        DVec3::new(-2.0, 0.0, 1.0),
        DVec3::new(2.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let b = flight(
        &s,
        DVec3::new(2.0, 0.0, 1.0),
        DVec3::new(-2.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let shape = ContactShape::new(&s);
    let ba = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: 0.25,
    };
    let bb = Body {
        motion: Motion::Flying(&b),
        shape: &shape,
        radius: 0.25,
    };
    let t = pair_contact_time(&ba, &bb, 2.0).expect("they collide");
    assert!((t - 0.875).abs() < 1e-12, "{t}");
    assert!(pair_contact_time(&ba, &bb, 0.8).is_none());
}

#[test]
fn head_on_boxes_collide_at_the_analytic_time() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Cuboid {
        half_extents: DVec3::new(0.1, 0.2, 0.3),
    };
    let a = flight(
        &s,
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 2.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let b = flight(
        &s,
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(-1.0, 0.0, 2.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let shape = ContactShape::new(&s);
    let r = s.bounding_radius(DVec3::ZERO);
    let ba = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: r,
    };
    let bb = Body {
        motion: Motion::Flying(&b),
        shape: &shape,
        radius: r,
    };
    // Faces meet when the 1.8 m gap closes at 2 m/s.
    let t = pair_contact_time(&ba, &bb, 2.0).expect("they collide");
    assert!((t - 0.9).abs() < 1e-5, "{t}");
}

#[test]
fn fast_grazing_pass_between_frames_is_not_missed() {
    // Two small balls cross at 200 m/s relative speed, overlapping by 1 mm at the
    // closest approach for only ~0.3 ms: far less than a 1/60 s frame.
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Sphere { radius: 0.05 };
    let a = flight(
        &s,
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(100.0, 0.0, 0.0),
        DVec3::ZERO,
        g,
        1.0,
    );
    let b = flight(
        &s,
        DVec3::new(1.0, 0.099, 1.0),
        DVec3::new(-100.0, 0.0, 0.0),
        DVec3::ZERO,
        g,
        1.0,
    );
    let shape = ContactShape::new(&s);
    let ba = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: 0.05,
    };
    let bb = Body {
        motion: Motion::Flying(&b),
        shape: &shape,
        radius: 0.05,
    };
    let t = pair_contact_time(&ba, &bb, 1.0).expect("grazing contact found");
    assert!((t - 0.01).abs() < 2e-4, "{t}");
    // Frame sampling at 60 Hz would see them 3.3 m apart at both neighbouring frames.
    // The same pass 2 mm wider is a miss.
    let c = flight(
        &s,
        DVec3::new(1.0, 0.101, 1.0),
        DVec3::new(-100.0, 0.0, 0.0),
        DVec3::ZERO,
        g,
        1.0,
    );
    let bc = Body {
        motion: Motion::Flying(&c),
        shape: &shape,
        radius: 0.05,
    };
    assert!(pair_contact_time(&ba, &bc, 1.0).is_none());
}

#[test]
fn fast_grazing_boxes_with_spin_are_not_missed() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Cuboid {
        half_extents: DVec3::splat(0.05),
    };
    let a = flight(
        &s,
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(80.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 30.0),
        g,
        1.0,
    );
    let b = flight(
        &s,
        DVec3::new(1.0, 0.095, 1.0),
        DVec3::new(-80.0, 0.0, 0.0),
        DVec3::ZERO,
        g,
        1.0,
    );
    let shape = ContactShape::new(&s);
    let r = s.bounding_radius(DVec3::ZERO);
    let ba = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: r,
    };
    let bb = Body {
        motion: Motion::Flying(&b),
        shape: &shape,
        radius: r,
    };
    let t = pair_contact_time(&ba, &bb, 1.0).expect("grazing contact found");
    // They can only touch around the crossing at t = 1/80 s.
    assert!((t - 0.0125).abs() < 1e-3, "{t}");
    // Verify it is a real touch (within the pair contact distance), not an early stop.
    let ((pa, qa), (pb, qb)) = (ba.motion.pose(t), bb.motion.pose(t));
    let d = signed_distance(ba.shape, pa, qa, bb.shape, pb, qb);
    assert!(d <= PAIR_CONTACT_DISTANCE, "{d}");
}

#[test]
fn ball_lands_on_the_table_at_the_analytic_time() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Sphere { radius: 0.3 };
    let a = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.3),
        DVec3::new(1.0, 0.0, 5.0),
        DVec3::ZERO,
        g,
        3.0,
    );
    let table = Table {
        center: DVec3::new(0.0, 0.0, -0.5),
        half_extents: DVec3::new(10.0, 10.0, 0.5),
    };
    let ts = table_shape(&table);
    let shape = ContactShape::new(&s);
    let b = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: 0.3,
    };
    let t = table_contact_time(&b, &table, &ts, 3.0).expect("lands");
    let analytic = 2.0 * 5.0 / 9.81;
    assert!((t - analytic).abs() < 1e-6, "{t} vs {analytic}");
    assert!(table_contact_time(&b, &table, &ts, 1.0).is_none());
    // A ball rolled along the table (no upward speed) sinks at once: a contact.
    let r = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.3),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::ZERO,
        g,
        3.0,
    );
    let br = Body {
        motion: Motion::Flying(&r),
        shape: &shape,
        radius: 0.3,
    };
    assert!(table_contact_time(&br, &table, &ts, 3.0).unwrap() < 0.01);
}

#[test]
fn box_lands_on_the_table() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Cuboid {
        half_extents: DVec3::new(0.1, 0.1, 0.05),
    };
    let a = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.05),
        DVec3::new(0.0, 0.0, 4.0),
        DVec3::ZERO,
        g,
        3.0,
    );
    let table = Table {
        center: DVec3::new(0.0, 0.0, -0.5),
        half_extents: DVec3::new(10.0, 10.0, 0.5),
    };
    let ts = table_shape(&table);
    let shape = ContactShape::new(&s);
    let b = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: s.bounding_radius(DVec3::ZERO),
    };
    let t = table_contact_time(&b, &table, &ts, 3.0).expect("lands");
    assert!((t - 8.0 / 9.81).abs() < 1e-5, "{t}");
}

#[test]
fn ball_hits_a_fixed_ball() {
    let s = Shape::Sphere { radius: 0.1 };
    let a = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::ZERO,
        DVec3::ZERO,
        3.0,
    );
    let shape = ContactShape::new(&s);
    let ba = Body {
        motion: Motion::Flying(&a),
        shape: &shape,
        radius: 0.1,
    };
    let fixed = DVec3::new(1.0, 0.0, 0.1);
    let bb = Body {
        motion: Motion::Fixed {
            origin: fixed,
            orientation: DQuat::IDENTITY,
            com: fixed,
        },
        shape: &shape,
        radius: 0.1,
    };
    let t = pair_contact_time(&ba, &bb, 3.0).unwrap();
    assert!((t - 0.8).abs() < 1e-5, "{t}");
}

#[test]
fn ball_table_closed_form_matches_conservative_advancement() {
    // The same ball as an exact ball (closed form) and as a parry ball (conservative
    // advancement) must land at the same time, on a small table so that some balls
    // come down past its edges and some are rolled along it.
    let g = DVec3::new(0.0, 0.0, -9.81);
    let table = Table {
        center: DVec3::new(0.0, 0.0, -0.5),
        half_extents: DVec3::new(1.5, 1.0, 0.5),
    };
    let ts = table_shape(&table);
    let mut rnd = uniform(99);
    let mut landed = 0;
    for _ in 0..300 {
        let r = 0.05 + 0.3 * rnd();
        let s = Shape::Sphere { radius: r };
        let p = DVec3::new(2.6 * rnd() - 1.3, 1.6 * rnd() - 0.8, r + 0.3 * rnd());
        let v = DVec3::new(4.0 * rnd() - 2.0, 4.0 * rnd() - 2.0, 8.0 * rnd() - 1.0);
        let f = flight(&s, p, v, DVec3::ZERO, g, 2.0);
        let exact = ContactShape::new(&s);
        let parry = ContactShape::Parry(Arc::new(Ball::new(r as f32)), Arc::new([]), None);
        let a = Body {
            motion: Motion::Flying(&f),
            shape: &exact,
            radius: r,
        };
        let b = Body {
            motion: Motion::Flying(&f),
            shape: &parry,
            radius: r,
        };
        let ta = table_contact_time(&a, &table, &ts, 2.0);
        let tb = table_contact_time(&b, &table, &ts, 2.0);
        match (ta, tb) {
            (Some(x), Some(y)) => {
                landed += 1;
                assert!(
                    (x - y).abs() < 1e-4,
                    "closed form {x} vs advancement {y} for p {p} v {v} r {r}"
                );
            }
            (None, None) => {}
            other => panic!("disagree: {other:?} for p {p} v {v} r {r}"),
        }
    }
    assert!(landed > 100, "only {landed} landings exercised");
}

#[test]
fn two_balls_meet_in_closed_form_when_conservative_advancement_finds_them() {
    // Pairs of balls thrown about one another, as exact balls (the closed form of
    // `ball_pair_contact_time`) and as parry balls (conservative advancement): they must
    // meet at the same time, or both not at all; some start touching.
    let g = DVec3::new(0.0, 0.0, -9.81);
    let mut rnd = uniform(7);
    let (mut met, mut touching) = (0, 0);
    for _ in 0..300 {
        let (ra, rb) = (0.02 + 0.1 * rnd(), 0.02 + 0.1 * rnd());
        let (sa, sb) = (Shape::Sphere { radius: ra }, Shape::Sphere { radius: rb });
        let mut cube = || DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
        let (pa, pb, va) = (cube() + DVec3::Z, cube() + DVec3::Z, cube() * 6.0);
        // Mostly towards a, often enough to meet it.
        let vb = va + (pa - pb) * 2.0 + cube();
        let pb = match pb.x < -0.4 {
            true => pa + DVec3::X * (ra + rb),
            false => pb,
        };
        let (fa, fb) = (
            flight(&sa, pa, va, DVec3::ZERO, g, 2.0),
            flight(&sb, pb, vb, DVec3::ZERO, g, 2.0),
        );
        let (ea, eb) = (ContactShape::new(&sa), ContactShape::new(&sb));
        // Its sphere cover the ball itself.
        let parry = |r: f64| {
            ContactShape::Parry(
                Arc::new(Ball::new(r as f32)),
                Arc::new([(DVec3::ZERO, r)]),
                None,
            )
        };
        let (qa, qb) = (parry(ra), parry(rb));
        let body = |f, shape, radius| Body {
            motion: Motion::Flying(f),
            shape,
            radius,
        };
        let (a, b) = (body(&fa, &ea, ra), body(&fb, &eb, rb));
        let closed = (BallStart::of(&a).unwrap(), BallStart::of(&b).unwrap());
        match ball_pair_contact_time(&closed.0, &closed.1, 2.0) {
            Err(_) => touching += 1,
            Ok(x) => {
                let y = pair_contact_time(&body(&fa, &qa, ra), &body(&fb, &qb, rb), 2.0);
                assert_eq!(pair_contact_time(&a, &b, 2.0), x);
                match (x, y) {
                    (Some(x), Some(y)) => {
                        met += 1;
                        assert!((x - y).abs() < 1e-4, "closed form {x} vs advancement {y}");
                    }
                    (None, None) => {}
                    other => panic!("disagree: {other:?} for {pa} {va}, {pb} {vb}"),
                }
            }
        }
    }
    assert!(
        met > 30 && touching > 10,
        "only {met} meetings and {touching} touching"
    );
}

#[test]
fn bodies_touching_at_launch_only_collide_if_they_press_in_or_meet_again() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Sphere { radius: 0.2 };
    let shape = ContactShape::new(&s);
    fn body<'a>(f: &'a FreeFlight, shape: &'a ContactShape) -> Body<'a> {
        Body {
            motion: Motion::Flying(f),
            shape,
            radius: 0.2,
        }
    }
    // Touching, moving apart: no contact (it used to be reported at t = 0).
    let a = flight(
        &s,
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(-1.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let b = flight(
        &s,
        DVec3::new(0.4, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    assert_eq!(
        pair_contact_time(&body(&a, &shape), &body(&b, &shape), 2.0),
        None
    );
    // Touching, pressing into each other: a contact at once.
    let c = flight(
        &s,
        DVec3::new(0.4, 0.0, 1.0),
        DVec3::new(-1.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let d = flight(
        &s,
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let tc = pair_contact_time(&body(&c, &shape), &body(&d, &shape), 2.0)
        .expect("pressing in is a contact");
    assert!(tc < 1e-3, "{tc}");
    // Boxes side by side, launched apart.
    let bs = Shape::Cuboid {
        half_extents: DVec3::splat(0.1),
    };
    let bshape = ContactShape::new(&bs);
    let r = bs.bounding_radius(DVec3::ZERO);
    let e = flight(
        &bs,
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(-4.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let f = flight(
        &bs,
        DVec3::new(0.2, 0.0, 0.1),
        DVec3::new(4.0, 0.0, 3.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let be = Body {
        motion: Motion::Flying(&e),
        shape: &bshape,
        radius: r,
    };
    let bf = Body {
        motion: Motion::Flying(&f),
        shape: &bshape,
        radius: r,
    };
    assert_eq!(pair_contact_time(&be, &bf, 2.0), None);
}

#[test]
fn a_spinning_box_tipping_into_the_table_is_a_contact_but_no_landing() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Cuboid {
        half_extents: DVec3::new(0.3, 0.2, 0.1),
    };
    let table = Table {
        center: DVec3::new(0.0, 0.0, -0.5),
        half_extents: DVec3::new(10.0, 10.0, 0.5),
    };
    let ts = table_shape(&table);
    let shape = ContactShape::new(&s);
    let r = s.bounding_radius(DVec3::ZERO);
    let f = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(0.0, 0.0, 7.0),
        DVec3::new(60.0, 0.0, 0.0),
        g,
        2.0,
    );
    let c = table_contact(
        &Body {
            motion: Motion::Flying(&f),
            shape: &shape,
            radius: r,
        },
        &table,
        &ts,
        2.0,
    )
    .unwrap();
    assert!(c.time < 0.01 && !c.landed, "{c:?}");
    // Thrown up without spin, it lands: a landing.
    let f = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(0.0, 0.0, 4.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    let c = table_contact(
        &Body {
            motion: Motion::Flying(&f),
            shape: &shape,
            radius: r,
        },
        &table,
        &ts,
        2.0,
    )
    .unwrap();
    assert!(c.landed && (c.time - 8.0 / 9.81).abs() < 1e-5, "{c:?}");
}

/// Overlapping or touching hulls never read as apart: parry's f32 fallback is not
/// trusted to raise the certified bound (a review found +8 mm for a 30 um overlap).
#[test]
fn overlapping_piece_hulls_never_read_as_separated() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/thinker/pieces");
    let shapes: Vec<ContactShape> = ["pawn", "rook", "queen", "knight"]
        .iter()
        .map(|p| {
            let m = crate::geometry::shape::load_obj(&dir.join(format!("{p}.obj")), 1.0).unwrap();
            ContactShape::new(&Shape::Mesh(Arc::new(m)))
        })
        .collect();
    let mut worst = f64::NEG_INFINITY;
    for (k, (a, b)) in [(0, 0), (1, 2), (2, 3), (3, 0), (1, 1)]
        .into_iter()
        .enumerate()
    {
        for j in 0..20 {
            let ang = 0.37 * (k * 20 + j) as f64;
            let qa = DQuat::from_scaled_axis(DVec3::new(ang.sin(), 0.3 * ang, 0.2));
            let qb = DQuat::from_scaled_axis(DVec3::new(0.1 * ang, ang.cos(), -0.4));
            let dir = DVec3::new(ang.cos(), ang.sin(), 0.1).normalize();
            // Bisect the offset along `dir` at which the hulls start to touch.
            let (mut lo, mut hi) = (0.0, 0.3);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                // The f64 GJK decides (the function under test must not).
                let (pa, pb) = (shapes[a].polytope().unwrap(), shapes[b].polytope().unwrap());
                let inv = qa.inverse();
                let d =
                    crate::geometry::gjk::distance_lower_bound(pa, pb, inv * qb, inv * (dir * mid));
                if d > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            for overlap in [30e-6, 1e-6, 0.0] {
                let d = signed_distance(
                    &shapes[a],
                    DVec3::ZERO,
                    qa,
                    &shapes[b],
                    dir * (lo - overlap),
                    qb,
                );
                worst = worst.max(d);
                assert!(
                    d <= CONTACT_DISTANCE,
                    "pair {a}-{b} pose {j}, overlap {overlap}: {d}"
                );
            }
        }
    }
    assert!(worst > -1e-3, "the poses are near touching ({worst})");
}

/// The first time two flights come within `reach` of each other (centres), by sampling
/// every 0.1 ms: the reference of the drag tests.
fn sampled_meeting(a: &FreeFlight, b: &FreeFlight, reach: f64, horizon: f64) -> Option<f64> {
    (0..=(horizon * 1e4) as usize)
        .map(|k| k as f64 * 1e-4)
        .find(|&t| a.com(t).distance(b.com(t)) <= reach)
}

#[test]
fn contacts_under_drag_are_found_where_the_bent_paths_meet() {
    use crate::sim::drag::{BodyDrag, DragConfig};
    let g = DVec3::new(0.0, 0.0, -9.81);
    let (r, ball) = (0.05, Shape::Sphere { radius: 0.05 });
    // A light ball (drag bends its path by decimetres) thrown across a heavy one's, a
    // little higher each time: some throws meet in air, others pass.
    let heavy = BodyDrag::new(&ball, 5.0, &DragConfig::default());
    let light = BodyDrag::new(&ball, 0.02, &DragConfig::default());
    let make = |pos: DVec3, v: DVec3, d: Option<&BodyDrag>| {
        let mut f = flight(&ball, pos, v, DVec3::ZERO, g, 1.5);
        if let Some(d) = d {
            f.set_drag(d, 0.01);
        }
        f
    };
    let shape = ContactShape::new(&ball);
    fn body<'a>(f: &'a FreeFlight, shape: &'a ContactShape, r: f64) -> Body<'a> {
        Body {
            motion: Motion::Flying(f),
            shape,
            radius: r,
        }
    }
    let (mut met, mut passed) = (0, 0);
    for k in 0..24 {
        let vz = 4.0 + 0.05 * k as f64;
        let (pa, va) = (DVec3::new(-2.0, 0.0, 1.0), DVec3::new(3.0, 0.0, vz));
        let (pb, vb) = (DVec3::new(2.0, 0.0, 1.0), DVec3::new(-2.0, 0.0, 4.0));
        let (a, b) = (make(pa, va, Some(&light)), make(pb, vb, Some(&heavy)));
        assert!(a.drag_accel_bound().is_some());
        let want = sampled_meeting(&a, &b, 2.0 * r, 1.5);
        let got = pair_contact_time(&body(&a, &shape, r), &body(&b, &shape, r), 1.5);
        match (got, want) {
            (Some(t), Some(w)) => {
                met += 1;
                assert!(t <= w + 1e-9 && w - t < 1.5e-4, "vz {vz}: {t} vs {w}");
            }
            (None, None) => passed += 1,
            _ => panic!("vz {vz}: search {got:?}, sampled {want:?}"),
        }
        // In a vacuum the same throws meet otherwise: drag is in the search.
        let (av, bv) = (make(pa, va, None), make(pb, vb, None));
        let vacuum = pair_contact_time(&body(&av, &shape, r), &body(&bv, &shape, r), 1.5);
        if got.is_some() {
            assert_ne!(vacuum, got, "vz {vz}");
        }
    }
    assert!(met >= 2 && passed >= 2, "{met} meetings, {passed} misses");
}

#[test]
fn a_ball_in_air_lands_where_its_drag_flight_meets_the_table() {
    use crate::sim::drag::{BodyDrag, DragConfig};
    let g = DVec3::new(0.0, 0.0, -9.81);
    let s = Shape::Sphere { radius: 0.05 };
    let table = Table {
        center: DVec3::new(0.0, 0.0, -0.5),
        half_extents: DVec3::new(20.0, 20.0, 0.5),
    };
    let ts = table_shape(&table);
    let mut f = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.05),
        DVec3::new(1.0, 0.0, 4.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    f.set_drag(&BodyDrag::new(&s, 0.02, &DragConfig::default()), 0.01);
    let shape = ContactShape::new(&s);
    let c = table_contact(
        &Body {
            motion: Motion::Flying(&f),
            shape: &shape,
            radius: 0.05,
        },
        &table,
        &ts,
        2.0,
    )
    .expect("it lands");
    assert!(c.landed);
    let want = (1..200_000)
        .map(|k| k as f64 * 1e-5)
        .find(|&t| f.com(t).z <= 0.05)
        .unwrap();
    assert!((c.time - want).abs() < 2e-5, "{} vs {want}", c.time);
    // In a vacuum it lands later (drag slows the climb and the fall less than it gains).
    let v = flight(
        &s,
        DVec3::new(0.0, 0.0, 0.05),
        DVec3::new(1.0, 0.0, 4.0),
        DVec3::ZERO,
        g,
        2.0,
    );
    assert!((v.com(c.time).z - 0.05).abs() > 1e-3);
}
