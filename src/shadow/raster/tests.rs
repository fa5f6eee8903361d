use super::scan::BOX_TRIANGLES;
use super::*;
use crate::shadow::mask::Mask;
use glam::{DQuat, DVec2, DVec3};
use std::f64::consts::PI;

/// SplitMix64, so the tests need no dependencies.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn rotation(&mut self) -> DQuat {
        let q = DQuat::from_xyzw(
            self.uniform(-1.0, 1.0),
            self.uniform(-1.0, 1.0),
            self.uniform(-1.0, 1.0),
            self.uniform(-1.0, 1.0),
        );
        q.normalize()
    }
}

/// The project's reference set-up: light 6 m above the floor, 4 m x 3 m image.
fn standard_camera(w: usize, h: usize) -> ShadowCamera {
    ShadowCamera::new(
        DVec3::new(0.0, 0.0, 6.0),
        ImageRect {
            center: DVec3::ZERO,
            u: DVec3::X,
            v: DVec3::Y,
            width_m: 4.0,
            height_m: 3.0,
            width_px: w,
            height_px: h,
        },
    )
}

/// A randomly placed and tilted receiver. Returns the camera and the rotation that maps
/// the camera's local frame (x = u, y = v, z = normal) to the world.
fn random_camera(rng: &mut Rng, w: usize, h: usize) -> (ShadowCamera, DQuat) {
    let rot = rng.rotation();
    let c = DVec3::new(
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
    );
    let height = rng.uniform(2.0, 8.0);
    let light = c + rot * DVec3::new(rng.uniform(-1.5, 1.5), rng.uniform(-1.0, 1.0), height);
    (
        ShadowCamera::new(
            light,
            ImageRect {
                center: c,
                u: rot * DVec3::X,
                v: rot * DVec3::Y,
                width_m: 4.0,
                height_m: 3.0,
                width_px: w,
                height_px: h,
            },
        ),
        rot,
    )
}

/// Reference: does the segment from the light to `x` meet the ball? (Closest point.)
fn segment_hits_ball(light: DVec3, x: DVec3, s: DVec3, r: f64) -> bool {
    let d = x - light;
    let t = ((s - light).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (light + t * d).distance_squared(s) <= r * r
}

/// Reference: does the segment from the light to `x` meet the box? (Slab test.)
fn segment_hits_box(light: DVec3, x: DVec3, c: DVec3, rot: DQuat, he: DVec3) -> bool {
    let inv = rot.conjugate();
    let o = inv * (light - c);
    let d = inv * (x - light);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for i in 0..3 {
        if d[i].abs() < 1e-300 {
            if o[i].abs() > he[i] {
                return false;
            }
        } else {
            let (a, b) = ((-he[i] - o[i]) / d[i], (he[i] - o[i]) / d[i]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    t0 <= t1
}

/// Compare a mask with a per-pixel reference predicate on world points. A mismatch is
/// tolerated only if the reference itself changes within 1e-9 m of the pixel centre
/// (the centre is on the boundary up to rounding). Returns the number tolerated.
fn compare(cam: &ShadowCamera, mask: &Mask, what: &str, f: impl Fn(DVec3) -> bool) -> usize {
    let eps = 1e-9;
    let mut tolerated = 0;
    for j in 0..cam.height_px {
        for i in 0..cam.width_px {
            let x = cam.pixel_to_world(i as f64 + 0.5, j as f64 + 0.5);
            let want = f(x);
            if mask.get(i, j) == want {
                continue;
            }
            let near = [cam.u * eps, -cam.u * eps, cam.v * eps, -cam.v * eps];
            assert!(
                near.iter().any(|&e| f(x + e) != want),
                "{what}: pixel ({i}, {j}) is {} but the reference says {want}",
                mask.get(i, j)
            );
            tolerated += 1;
            if std::env::var("DBG").is_ok() {
                eprintln!("{what}: tolerated ({i},{j}) mask {}", mask.get(i, j));
            }
        }
    }
    tolerated
}

/// A closed UV sphere with outward-wound triangles: 16 slices x 16 stacks = 480.
fn uv_sphere(c: DVec3, r: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let (stacks, slices) = (16u32, 16u32);
    let mut v = vec![c + DVec3::new(0.0, 0.0, r)];
    for i in 1..stacks {
        let th = PI * i as f64 / stacks as f64;
        for k in 0..slices {
            let ph = 2.0 * PI * k as f64 / slices as f64;
            v.push(c + r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    v.push(c - DVec3::new(0.0, 0.0, r));
    let bottom = v.len() as u32 - 1;
    let ring = |i: u32, k: u32| 1 + i * slices + k % slices;
    let mut t = Vec::new();
    for k in 0..slices {
        t.push([0, ring(0, k), ring(0, k + 1)]);
        t.push([bottom, ring(stacks - 2, k + 1), ring(stacks - 2, k)]);
        for i in 0..stacks - 2 {
            t.push([ring(i, k), ring(i + 1, k), ring(i + 1, k + 1)]);
            t.push([ring(i, k), ring(i + 1, k + 1), ring(i, k + 1)]);
        }
    }
    // Orient every triangle outward (the mesh is convex around c).
    for tri in &mut t {
        let [a, b, cc] = tri.map(|i| v[i as usize]);
        if (b - a).cross(cc - a).dot((a + b + cc) / 3.0 - c) < 0.0 {
            tri.swap(1, 2);
        }
    }
    (v, t)
}

#[test]
fn project_and_pixel_to_world_round_trip() {
    let mut rng = Rng(11);
    for _ in 0..20 {
        let (cam, _) = random_camera(&mut rng, 320, 240);
        for _ in 0..10 {
            let (px, py) = (rng.uniform(-50.0, 400.0), rng.uniform(-50.0, 300.0));
            let x = cam.pixel_to_world(px, py);
            assert!((x - cam.center).dot(cam.normal()).abs() < 1e-12);
            // Any point on the ray from the light through x in front of the light
            // projects to (px, py), including points beyond the receiver.
            for t in [0.1, 0.5, 1.0, 1.7] {
                let p = cam.project(cam.light + t * (x - cam.light)).unwrap();
                assert!(p.distance(DVec2::new(px, py)) < 1e-7, "{p} vs ({px}, {py})");
            }
            assert_eq!(cam.project(cam.light - 0.5 * (x - cam.light)), None);
        }
        assert_eq!(cam.project(cam.light), None);
    }
    let cam = standard_camera(640, 480);
    assert_eq!(cam.pixel_to_world(0.0, 0.0), DVec3::new(-2.0, 1.5, 0.0));
    assert_eq!(cam.pixel_to_world(640.0, 480.0), DVec3::new(2.0, -1.5, 0.0));
    assert_eq!(
        cam.project(DVec3::new(0.0, 0.0, 3.0)),
        Some(DVec2::new(320.0, 240.0))
    );
    assert_eq!(cam.light_height(), 6.0);
}

#[test]
fn a_widened_camera_draws_the_same_pixels_shifted_by_its_margin() {
    let mut rng = Rng(12);
    for _ in 0..10 {
        let (cam, _) = random_camera(&mut rng, 320, 240);
        let m = 80;
        let wide = cam.widened(m);
        assert_eq!((wide.width_px, wide.height_px), (480, 400));
        for (px, py) in [(0.0, 0.0), (320.0, 240.0), (-80.0, 17.5), (133.25, 250.0)] {
            let a = cam.pixel_to_world(px, py);
            let b = wide.pixel_to_world(px + m as f64, py + m as f64);
            assert!(a.distance(b) < 1e-9, "{a} vs {b}");
        }
        // A ball whose shadow crosses the picture's left edge: the same pixels inside,
        // and more beyond the edge on the widened canvas.
        let edge = cam.pixel_to_world(0.0, 120.0);
        let ball = cam.light + 0.7 * (edge - cam.light);
        let (mut small, mut large) = (Mask::new(320, 240), Mask::new(480, 400));
        cam.rasterize_sphere(ball, 0.2, &mut small);
        wide.rasterize_sphere(ball, 0.2, &mut large);
        let inside = large.cropped(m);
        let differing = inside.xor_count(&small);
        assert!(differing <= 2, "{differing} pixels differ");
        assert!(large.count() > inside.count() && small.count() > 0);
    }
}

/// Area of the ellipse in which the cone from the light around a ball (entirely below
/// the light plane) meets the receiver. With w = S - L, k = |w|^2 - r^2, h the light
/// height and w_n = w.n, the cone is (w.d)^2 >= k |d|^2; writing it as the conic
/// x^T A x + 2 b.x + c <= 0 in plane coordinates gives det A = k (w_n^2 - r^2) and
/// det of the 3x3 matrix = -k^2 h^2 r^2, hence
/// area = pi (-det M) / (det A)^(3/2) = pi h^2 r^2 sqrt(k) / (w_n^2 - r^2)^(3/2).
/// (For a ball straight below the light this is pi h^2 r^2 / k = pi (h tan a)^2.)
fn analytic_shadow_area(cam: &ShadowCamera, s: DVec3, r: f64) -> f64 {
    let w = s - cam.light;
    let k = w.length_squared() - r * r;
    let wn = w.dot(cam.normal());
    PI * cam.light_height().powi(2) * r * r * k.sqrt() / (wn * wn - r * r).powf(1.5)
}

#[test]
fn sphere_shadow_area_matches_analytic_conic() {
    let cam = standard_camera(640, 480);
    let pixel_area = (4.0 / 640.0) * (3.0 / 480.0);
    let mut mask = Mask::new(640, 480);
    let cases = [
        (DVec3::new(0.0, 0.0, 2.0), 0.5),
        (DVec3::new(0.6, -0.3, 1.2), 0.5),
        (DVec3::new(-0.4, 0.25, 3.5), 0.3),
        (DVec3::new(1.2, 0.2, 0.6), 0.25),
    ];
    for (s, r) in cases {
        mask.clear();
        cam.rasterize_sphere(s, r, &mut mask);
        let area = mask.count() as f64 * pixel_area;
        let want = analytic_shadow_area(&cam, s, r);
        assert!(
            (area / want - 1.0).abs() < 0.005,
            "sphere {s} r {r}: {area} vs {want}"
        );
    }
    // The same on a tilted receiver, where rows are not aligned with anything.
    let rot = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.7);
    let c = DVec3::new(0.2, -0.1, 0.3);
    let cam = ShadowCamera::new(
        c + rot * DVec3::new(0.5, -0.3, 5.0),
        ImageRect {
            center: c,
            u: rot * DVec3::X,
            v: rot * DVec3::Y,
            width_m: 4.0,
            height_m: 3.0,
            width_px: 640,
            height_px: 480,
        },
    );
    let s = c + rot * DVec3::new(-0.4, 0.3, 1.5);
    mask.clear();
    cam.rasterize_sphere(s, 0.6, &mut mask);
    let area = mask.count() as f64 * pixel_area;
    let want = analytic_shadow_area(&cam, s, 0.6);
    assert!(
        (area / want - 1.0).abs() < 0.005,
        "tilted: {area} vs {want}"
    );
}

#[test]
fn nothing_behind_the_light_or_under_the_receiver() {
    let cam = standard_camera(320, 240);
    let mut mask = Mask::new(320, 240);
    let mut scratch = RasterScratch::default();
    let rot = DQuat::from_euler(glam::EulerRot::XYZ, 0.4, 0.9, -0.3);
    for c in [
        DVec3::new(0.3, 0.2, 7.0),
        DVec3::new(2.0, -1.0, 6.6),
        DVec3::new(0.1, 0.0, -0.8),
    ] {
        cam.rasterize_sphere(c, 0.5, &mut mask);
        cam.rasterize_box(c, rot, DVec3::new(0.3, 0.2, 0.25), &mut mask, &mut scratch);
        let (v, t) = uv_sphere(c, 0.5);
        cam.rasterize_triangles(&v, &t, false, &mut mask, &mut scratch);
    }
    // Tangent to either plane from outside the slab still casts nothing.
    cam.rasterize_sphere(DVec3::new(0.0, 0.0, -0.5), 0.5, &mut mask);
    cam.rasterize_sphere(DVec3::new(1.0, 0.0, 6.5), 0.5, &mut mask);
    cam.rasterize_box(
        DVec3::new(0.0, 0.0, -0.5),
        DQuat::IDENTITY,
        DVec3::splat(0.5),
        &mut mask,
        &mut scratch,
    );
    assert_eq!(mask.count(), 0);
    // The same objects in front of the light do cast shadows (the test can fail).
    cam.rasterize_sphere(DVec3::new(0.3, 0.2, 3.0), 0.5, &mut mask);
    cam.rasterize_box(
        DVec3::new(0.3, 0.2, 3.0),
        rot,
        DVec3::new(0.3, 0.2, 0.25),
        &mut mask,
        &mut scratch,
    );
    assert!(mask.count() > 1000);
}

#[test]
fn light_inside_sphere_or_box_shadows_everything() {
    let cam = standard_camera(100, 75);
    let mut mask = Mask::new(100, 75);
    cam.rasterize_sphere(DVec3::new(0.1, 0.0, 6.2), 0.5, &mut mask);
    assert_eq!(mask.count(), 100 * 75);
    mask.clear();
    let mut scratch = RasterScratch::default();
    let rot = DQuat::from_rotation_z(0.5);
    cam.rasterize_box(
        DVec3::new(0.1, 0.0, 5.9),
        rot,
        DVec3::splat(0.3),
        &mut mask,
        &mut scratch,
    );
    assert_eq!(mask.count(), 100 * 75);
}

#[test]
fn sphere_straddling_the_receiver_matches_brute_force() {
    let cam = standard_camera(640, 480);
    let mut mask = Mask::new(640, 480);
    for (s, r) in [
        (DVec3::new(0.3, 0.2, 0.2), 0.5),
        (DVec3::new(-0.5, 0.4, -0.4), 0.7),
    ] {
        mask.clear();
        cam.rasterize_sphere(s, r, &mut mask);
        let tol = compare(&cam, &mask, "straddling sphere", |x| {
            segment_hits_ball(cam.light, x, s, r)
        });
        assert!(tol <= 2, "{tol} boundary pixels");
        // With the centre under the receiver, the cone of the whole ball (what a
        // planar projection would draw) is clearly larger than the true shadow.
        let full = analytic_shadow_area(&cam, s, r) / ((4.0 / 640.0) * (3.0 / 480.0));
        if s.z < 0.0 {
            assert!(
                (mask.count() as f64) < 0.9 * full,
                "{} vs {full}",
                mask.count()
            );
        }
    }
}

#[test]
fn random_spheres_match_brute_force() {
    let mut rng = Rng(2024);
    let mut mask = Mask::new(160, 120);
    // Counts of: inside the slab, crossing the receiver, crossing the light plane,
    // outside the slab, light inside.
    let mut kinds = [0; 5];
    let mut nonempty = 0;
    let mut tolerated = 0;
    for case in 0..400 {
        let (cam, rot) = random_camera(&mut rng, 160, 120);
        let h = cam.light_height();
        let r = rng.uniform(0.05, 1.5);
        let local = if case % 4 == 0 {
            // Near the light, to exercise the light-plane crossing.
            DVec3::new(
                rng.uniform(-2.0, 2.0),
                rng.uniform(-2.0, 2.0),
                h + rng.uniform(-r, r),
            )
        } else {
            DVec3::new(
                rng.uniform(-2.5, 2.5),
                rng.uniform(-2.0, 2.0),
                rng.uniform(-1.0, h + 1.0),
            )
        };
        let s = cam.center + rot * local;
        let z = local.z;
        let kind = if s.distance(cam.light) < r {
            4
        } else if z - r >= h || z + r <= 0.0 {
            3
        } else if z + r > h {
            2
        } else if z - r < 0.0 {
            1
        } else {
            0
        };
        kinds[kind] += 1;
        mask.clear();
        cam.rasterize_sphere(s, r, &mut mask);
        nonempty += (mask.count() > 0) as usize;
        tolerated += compare(&cam, &mask, &format!("sphere case {case}"), |x| {
            segment_hits_ball(cam.light, x, s, r)
        });
    }
    assert!(kinds.iter().all(|&k| k >= 5), "categories {kinds:?}");
    assert!(nonempty > 120, "{nonempty}");
    eprintln!("sphere categories {kinds:?}, nonempty {nonempty}, tolerated {tolerated}");
    assert!(tolerated <= 5, "{tolerated}");
}

#[test]
fn random_boxes_match_brute_force() {
    let mut rng = Rng(77);
    let mut mask = Mask::new(160, 120);
    let mut scratch = RasterScratch::default();
    let (mut straddle, mut nonempty, mut tolerated) = (0, 0, 0);
    for case in 0..300 {
        let (cam, frame) = random_camera(&mut rng, 160, 120);
        let h = cam.light_height();
        let he = DVec3::new(
            rng.uniform(0.05, 1.0),
            rng.uniform(0.05, 1.0),
            rng.uniform(0.05, 1.0),
        );
        let z = if case % 4 == 0 {
            h + rng.uniform(-1.0, 1.0)
        } else {
            rng.uniform(-1.0, h + 1.0)
        };
        let local = DVec3::new(rng.uniform(-2.5, 2.5), rng.uniform(-2.0, 2.0), z);
        let c = cam.center + frame * local;
        let rot = rng.rotation();
        let reach = he.length();
        straddle +=
            ((z - reach < 0.0 && z + reach > 0.0) || (z - reach < h && z + reach > h)) as usize;
        mask.clear();
        cam.rasterize_box(c, rot, he, &mut mask, &mut scratch);
        nonempty += (mask.count() > 0) as usize;
        tolerated += compare(&cam, &mask, &format!("box case {case}"), |x| {
            segment_hits_box(cam.light, x, c, rot, he)
        });
    }
    assert!(straddle > 60, "{straddle}");
    assert!(nonempty > 80, "{nonempty}");
    eprintln!("boxes straddling {straddle}, nonempty {nonempty}, tolerated {tolerated}");
    assert!(tolerated <= 5, "{tolerated}");
}

#[test]
fn box_triangles_are_outward() {
    let verts: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                (i & 1) as f64 - 0.5,
                ((i >> 1) & 1) as f64 - 0.5,
                ((i >> 2) & 1) as f64 - 0.5,
            )
        })
        .collect();
    let mut volume = 0.0;
    for t in BOX_TRIANGLES {
        let [a, b, c] = t.map(|i| verts[i as usize]);
        let n = (b - a).cross(c - a);
        assert!(n.dot(a + b + c) > 0.0, "triangle {t:?} faces inward");
        volume += a.dot(b.cross(c)) / 6.0;
    }
    assert!((volume - 1.0).abs() < 1e-12);
}

#[test]
fn back_face_culling_is_exact_for_closed_meshes() {
    let mut rng = Rng(5);
    let mut scratch = RasterScratch::default();
    let (mut a, mut b) = (Mask::new(160, 120), Mask::new(160, 120));
    for case in 0..60 {
        let (cam, frame) = random_camera(&mut rng, 160, 120);
        let h = cam.light_height();
        // Inside the slab, straddling the receiver and straddling the light plane.
        let z = [
            rng.uniform(1.0, h - 1.0),
            rng.uniform(-0.3, 0.3),
            h + rng.uniform(-0.3, 0.3),
        ][case % 3];
        let c = cam.center + frame * DVec3::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), z);
        if c.distance(cam.light) < 0.8 {
            continue; // The light must be outside the solid.
        }
        let rot = rng.rotation();
        let he = DVec3::new(0.5, 0.3, 0.4);
        let verts: Vec<DVec3> = (0..8)
            .map(|i| {
                let s = DVec3::new(
                    (i & 1) as f64 * 2.0 - 1.0,
                    ((i >> 1) & 1) as f64 * 2.0 - 1.0,
                    ((i >> 2) & 1) as f64 * 2.0 - 1.0,
                );
                c + rot * (s * he)
            })
            .collect();
        a.clear();
        b.clear();
        cam.rasterize_triangles(&verts, &BOX_TRIANGLES, true, &mut a, &mut scratch);
        cam.rasterize_triangles(&verts, &BOX_TRIANGLES, false, &mut b, &mut scratch);
        assert!(a.xor_count(&b) <= 2, "box case {case}: {}", a.xor_count(&b));
        compare(&cam, &a, "culled box", |x| {
            segment_hits_box(cam.light, x, c, rot, he)
        });
        // Culling with the winding reversed keeps only the back faces, which differ
        // from the shadow as soon as the receiver or light plane cuts the box.
        let flipped: Vec<[u32; 3]> = BOX_TRIANGLES.iter().map(|t| [t[0], t[2], t[1]]).collect();
        if case % 3 == 1 && a.count() > 0 {
            b.clear();
            cam.rasterize_triangles(&verts, &flipped, true, &mut b, &mut scratch);
            assert!(
                a.xor_count(&b) > 0,
                "case {case}: wrong winding went unnoticed"
            );
        }
        let (v, t) = uv_sphere(c, 0.5);
        a.clear();
        b.clear();
        cam.rasterize_triangles(&v, &t, true, &mut a, &mut scratch);
        cam.rasterize_triangles(&v, &t, false, &mut b, &mut scratch);
        assert!(
            a.xor_count(&b) <= 2,
            "mesh case {case}: {}",
            a.xor_count(&b)
        );
    }
}

#[test]
fn inscribed_mesh_shadow_is_inside_the_sphere_shadow() {
    let cam = standard_camera(640, 480);
    let mut scratch = RasterScratch::default();
    let (mut mesh, mut ball) = (Mask::new(640, 480), Mask::new(640, 480));
    for c in [DVec3::new(0.4, -0.2, 1.5), DVec3::new(-0.3, 0.1, 0.2)] {
        mesh.clear();
        ball.clear();
        let (v, t) = uv_sphere(c, 0.5);
        cam.rasterize_triangles(&v, &t, true, &mut mesh, &mut scratch);
        cam.rasterize_sphere(c, 0.5, &mut ball);
        assert_eq!(mesh.and_not_count(&ball), 0);
        assert!(mesh.count() as f64 > 0.95 * ball.count() as f64);
    }
}

#[test]
fn triangle_fill_has_no_cracks_and_clips_huge_coordinates() {
    let cam = standard_camera(160, 120);
    let mut scratch = RasterScratch::default();
    let mut mask = Mask::new(160, 120);
    // A quad lying in a plane parallel to the receiver, split along a diagonal that
    // passes exactly through pixel centres (its projection covers the whole image
    // twice over): every pixel must be set.
    let z = 3.0; // projection scale 2
    let q = [
        DVec3::new(-1.5, -1.0, z),
        DVec3::new(1.5, -1.0, z),
        DVec3::new(1.5, 1.0, z),
        DVec3::new(-1.5, 1.0, z),
    ];
    cam.rasterize_triangles(&q, &[[0, 1, 2], [0, 2, 3]], false, &mut mask, &mut scratch);
    assert_eq!(mask.count(), 160 * 120);
    // A triangle reaching almost to the light plane projects to enormous coordinates
    // yet fills exactly the brute-force set.
    mask.clear();
    let t = [
        DVec3::new(-0.5, -0.3, 1.0),
        DVec3::new(0.7, -0.2, 2.0),
        DVec3::new(0.1, 0.4, 6.0 - 1e-7),
    ];
    cam.rasterize_triangles(&t, &[[0, 1, 2]], false, &mut mask, &mut scratch);
    assert!(mask.count() > 0);
    let hits = |x: DVec3| {
        // Segment-triangle test (Moller-Trumbore) as the reference.
        let (o, d) = (cam.light, x - cam.light);
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let p = d.cross(e2);
        let det = e1.dot(p);
        let s = o - t[0];
        let a = s.dot(p) / det;
        let qv = s.cross(e1);
        let b = d.dot(qv) / det;
        let tt = e2.dot(qv) / det;
        a >= 0.0 && b >= 0.0 && a + b <= 1.0 && tt > 0.0 && tt < 1.0
    };
    compare(&cam, &mask, "thin triangle", hits);
}

/// The silhouette path must give the same pixels as filling every front face, for
/// the chess pieces (curved, many near-silhouette faces) at random poses, including
/// poses that straddle the receiver or the light plane (where it falls back).
#[test]
fn silhouette_fill_matches_the_triangle_fill_on_chess_pieces() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/thinker/pieces");
    let cam = ShadowCamera::new(
        DVec3::new(0.0, 0.0, 3.0),
        ImageRect {
            center: DVec3::ZERO,
            u: DVec3::X,
            v: DVec3::Y,
            width_m: 0.96,
            height_m: 0.72,
            width_px: 640,
            height_px: 480,
        },
    );
    let mut rng = Rng(11);
    let mut scratch = RasterScratch::default();
    let mut world = Vec::new();
    let (mut a, mut b) = (Mask::new(640, 480), Mask::new(640, 480));
    let mut compared = 0u64;
    for piece in ["pawn", "rook", "knight", "bishop", "queen", "king"] {
        let mesh = crate::geometry::shape::load_obj(&dir.join(format!("{piece}.obj")), 1.0)
            .expect("piece");
        let sil = MeshSilhouette::new(&mesh.vertices, &mesh.triangles).expect("closed, oriented");
        for k in 0..40 {
            // Mostly inside the slab, some across the receiver (z near 0) or the light.
            let z = match k % 8 {
                0 => rng.uniform(-0.05, 0.05),
                1 => rng.uniform(2.95, 3.05),
                _ => rng.uniform(0.3, 2.6),
            };
            let p = DVec3::new(rng.uniform(-0.3, 0.3), rng.uniform(-0.25, 0.25), z);
            let q = rng.rotation();
            a.clear();
            b.clear();
            cam.rasterize_mesh(
                p,
                q,
                ClosedMesh {
                    vertices: &mesh.vertices,
                    triangles: &mesh.triangles,
                    silhouette: &sil,
                },
                &mut world,
                &mut a,
                &mut scratch,
            );
            world.clear();
            world.extend(mesh.vertices.iter().map(|v| p + q * *v));
            cam.rasterize_triangles(&world, &mesh.triangles, true, &mut b, &mut scratch);
            assert_eq!(
                a.xor_count(&b),
                0,
                "{piece} at {p} {q}: {} vs {} pixels",
                a.count(),
                b.count()
            );
            compared += b.count();
        }
    }
    assert!(
        compared > 100_000,
        "the poses must cast real shadows ({compared} px)"
    );
}
