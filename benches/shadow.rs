//! Speed of the shadow stage, measured with criterion: `cargo bench --bench shadow`
//! (all), or e.g. `cargo bench --bench shadow -- mask/` (the mask kernels only).
//!
//! - `mask/*`: the bit-mask kernels of `bsa::shadow::mask` on 640x480 masks whose set
//!   rows span the whole image (the worst case for the row-range skipping): `xor_count`,
//!   `and_count`, `and_not_count`, `count`, `moments`, and `clear` of full rows.
//! - `raster/*`: the rasterizers of `bsa::shadow::raster` on the reference set-up (light
//!   6 m above the floor, 4 m x 3 m image, 640x480), each call on a cleared mask: three
//!   spheres inside the slab, the same spheres straddling the receiver, three rotated
//!   boxes, a 480-triangle closed UV sphere with and without back-face culling; then
//!   `xor_count` and `moments` of a three-sphere shadow.
//! - `raster/six_chess_pieces_silhouette`: the silhouette path of THE THINKER's six
//!   pieces (504 to 768 triangles each), each at four fixed tumbled poses between the
//!   light and the receiver, on THE THINKER's 0.96 m x 0.72 m image at 640x480, each
//!   call on a cleared mask (the shadow a seat scan or a one-piece sample draws).

use std::f64::consts::PI;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DQuat, DVec3};

use bsa::shadow::mask::Mask;
use bsa::shadow::raster::{ClosedMesh, ImageRect, MeshSilhouette, RasterScratch, ShadowCamera};

/// A filled disc of radius `r` pixels centred at `(cx, cy)` on a 640x480 mask.
fn disc(cx: f64, cy: f64, r: f64) -> Mask {
    Mask::from_fn(640, 480, move |x, y| {
        let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
        dx * dx + dy * dy <= r * r
    })
}

fn mask_benches(c: &mut Criterion) {
    let mut a = disc(300.0, 240.0, 150.0);
    a.or_assign(&disc(100.0, 100.0, 60.0));
    let mut b = disc(320.0, 250.0, 140.0);
    // Make both masks span every row, the worst case for the row-range skipping.
    a.fill_span(0, 0, 639);
    b.fill_span(479, 0, 639);

    let mut group = c.benchmark_group("mask");
    group.bench_function("xor_count_640x480", |bn| {
        bn.iter(|| black_box(&a).xor_count(black_box(&b)))
    });
    group.bench_function("and_count_640x480", |bn| {
        bn.iter(|| black_box(&a).and_count(black_box(&b)))
    });
    group.bench_function("and_not_count_640x480", |bn| {
        bn.iter(|| black_box(&a).and_not_count(black_box(&b)))
    });
    group.bench_function("count_640x480", |bn| bn.iter(|| black_box(&a).count()));
    group.bench_function("moments_640x480", |bn| {
        bn.iter(|| black_box(&a).moments().count as u64)
    });
    let mut cleared = a.clone();
    group.bench_function("clear_full_rows_640x480", |bn| {
        bn.iter(|| {
            cleared.fill_span(0, 0, 0);
            cleared.fill_span(479, 0, 0);
            cleared.clear();
            cleared.row_range().len() as u64
        })
    });
    group.finish();
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

fn raster_benches(c: &mut Criterion) {
    let cam = standard_camera(640, 480);
    let mut mask = Mask::new(640, 480);
    let mut scratch = RasterScratch::default();
    let spheres = [
        (DVec3::new(-1.0, 0.5, 1.0), 0.5),
        (DVec3::new(0.8, -0.3, 1.5), 0.5),
        (DVec3::new(0.2, 0.6, 0.7), 0.5),
    ];

    let mut group = c.benchmark_group("raster");
    group.bench_function("clear_3_spheres_in_slab", |b| {
        b.iter(|| {
            mask.clear();
            for (c, r) in spheres {
                cam.rasterize_sphere(black_box(c), r, &mut mask);
            }
        })
    });
    group.bench_function("clear_3_spheres_straddling_receiver", |b| {
        b.iter(|| {
            mask.clear();
            for (c, r) in spheres {
                cam.rasterize_sphere(
                    black_box(c * DVec3::new(1.0, 1.0, 0.0) + DVec3::Z * 0.2),
                    r,
                    &mut mask,
                );
            }
        })
    });
    group.bench_function("clear_3_boxes_rotated", |b| {
        b.iter(|| {
            mask.clear();
            for (i, (c, _)) in spheres.iter().enumerate() {
                let rot = DQuat::from_euler(glam::EulerRot::XYZ, 0.3 * i as f64, 0.5, 0.2);
                cam.rasterize_box(
                    black_box(*c),
                    rot,
                    DVec3::splat(0.4),
                    &mut mask,
                    &mut scratch,
                );
            }
        })
    });
    let (v, t) = uv_sphere(DVec3::new(0.2, -0.1, 1.2), 0.5);
    group.bench_function("clear_480_triangle_mesh_culled", |b| {
        b.iter(|| {
            mask.clear();
            cam.rasterize_triangles(black_box(&v), &t, true, &mut mask, &mut scratch);
        })
    });
    group.bench_function("clear_480_triangle_mesh_no_culling", |b| {
        b.iter(|| {
            mask.clear();
            cam.rasterize_triangles(black_box(&v), &t, false, &mut mask, &mut scratch);
        })
    });

    chess_bench(&mut group);

    mask.clear();
    for (c, r) in spheres {
        cam.rasterize_sphere(c, r, &mut mask);
    }
    let mut other = Mask::new(640, 480);
    cam.rasterize_sphere(DVec3::new(0.0, 0.0, 2.0), 1.0, &mut other);
    group.bench_function("xor_count_shadow_vs_target", |b| {
        b.iter(|| black_box(&mask).xor_count(black_box(&other)))
    });
    group.bench_function("moments_3_sphere_shadow", |b| {
        b.iter(|| black_box(&mask).moments().count as u64)
    });
    group.finish();
}

/// `raster/six_chess_pieces_silhouette` (see the module doc).
fn chess_bench(group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>) {
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
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/thinker/pieces");
    let pieces: Vec<_> = ["pawn", "rook", "knight", "bishop", "queen", "king"]
        .iter()
        .map(|name| {
            let mesh = bsa::geometry::shape::load_obj(&dir.join(format!("{name}.obj")), 1.0)
                .expect("the thinker's pieces load");
            let sil = MeshSilhouette::new(&mesh.vertices, &mesh.triangles).expect("closed");
            (mesh, sil)
        })
        .collect();
    let poses: Vec<(DVec3, DQuat)> = (0..4)
        .map(|k| {
            let k = k as f64;
            (
                DVec3::new(0.1 * k - 0.15, 0.05 * k - 0.08, 0.8 + 0.4 * k),
                DQuat::from_euler(glam::EulerRot::XYZ, 0.7 * k + 0.2, 0.4 * k - 0.5, 1.1 * k),
            )
        })
        .collect();
    let mut mask = Mask::new(640, 480);
    let mut scratch = RasterScratch::default();
    let mut world = Vec::new();
    group.bench_function("six_chess_pieces_silhouette", |b| {
        b.iter(|| {
            for (mesh, sil) in &pieces {
                for &(p, q) in &poses {
                    mask.clear();
                    let closed = ClosedMesh {
                        vertices: &mesh.vertices,
                        triangles: &mesh.triangles,
                        silhouette: sil,
                    };
                    cam.rasterize_mesh(
                        black_box(p),
                        q,
                        closed,
                        &mut world,
                        &mut mask,
                        &mut scratch,
                    );
                }
            }
            mask.count()
        })
    });
}

criterion_group!(shadow_benches, mask_benches, raster_benches);
criterion_main!(shadow_benches);
