use super::*;
use crate::sim::flight::{FlightConfig, FreeFlight, LaunchState, RotationKind};
use std::collections::HashMap;
use std::f64::consts::PI;

pub(crate) fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Rotation angle between two orientations (sign-insensitive). Taken from the vector
/// part of the relative rotation, because `2 acos(|a . b|)` cannot resolve angles
/// below ~3e-8 rad in f64.
pub(crate) fn angle_between(a: DQuat, b: DQuat) -> f64 {
    let d = a.normalize().conjugate() * b.normalize();
    2.0 * d.xyz().length().atan2(d.w.abs())
}

pub(crate) fn box_mesh(lo: DVec3, hi: DVec3) -> TriMesh {
    let v = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    // Outward counter-clockwise faces of the cube with corner bits (x, y, z).
    let quads = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let t = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    TriMesh::new(v, t)
}

pub(crate) fn transformed(mesh: &TriMesh, rot: DQuat, shift: DVec3) -> TriMesh {
    TriMesh::new(
        mesh.vertices.iter().map(|&v| rot * v + shift).collect(),
        mesh.triangles.clone(),
    )
}

pub(crate) fn icosphere(radius: f64, levels: usize) -> TriMesh {
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        [-1.0, p, 0.0],
        [1.0, p, 0.0],
        [-1.0, -p, 0.0],
        [1.0, -p, 0.0],
        [0.0, -1.0, p],
        [0.0, 1.0, p],
        [0.0, -1.0, -p],
        [0.0, 1.0, -p],
        [p, 0.0, -1.0],
        [p, 0.0, 1.0],
        [-p, 0.0, -1.0],
        [-p, 0.0, 1.0],
    ]
    .iter()
    .map(|a| DVec3::from_array(*a).normalize())
    .collect();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(t.len() * 4);
        for tri in &t {
            let mut m = [0u32; 3];
            for i in 0..3 {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                m[i] = *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push((v[a as usize] + v[b as usize]).normalize());
                    v.len() as u32 - 1
                });
            }
            next.push([tri[0], m[0], m[2]]);
            next.push([tri[1], m[1], m[0]]);
            next.push([tri[2], m[2], m[1]]);
            next.push([m[0], m[1], m[2]]);
        }
        t = next;
    }
    TriMesh::new(v.into_iter().map(|x| x * radius).collect(), t)
}

/// Surface of revolution about +z through the profile points `(r, z)`, whose first and
/// last points lie on the axis, with `segments` sectors.
pub(crate) fn lathe(profile: &[(f64, f64)], segments: u32) -> TriMesh {
    let rings = profile.len() as u32 - 2;
    let mut v = vec![DVec3::new(0.0, 0.0, profile[0].1)];
    for &(r, z) in &profile[1..profile.len() - 1] {
        for j in 0..segments {
            let a = 2.0 * PI * j as f64 / segments as f64;
            v.push(DVec3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    let top = v.len() as u32;
    v.push(DVec3::new(0.0, 0.0, profile[profile.len() - 1].1));
    let at = |ring: u32, j: u32| 1 + ring * segments + j % segments;
    let mut t = Vec::new();
    for j in 0..segments {
        t.push([0, at(0, j + 1), at(0, j)]);
        for ring in 0..rings - 1 {
            let (a, b) = (at(ring, j), at(ring, j + 1));
            let (c, d) = (at(ring + 1, j + 1), at(ring + 1, j));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
        t.push([top, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    TriMesh::new(v, t)
}

/// A 3 cm pawn-like solid of revolution, z up, base at z = 0.
pub(crate) fn pawn() -> TriMesh {
    let profile = [
        (0.0, 0.0),
        (0.0125, 0.0),
        (0.0125, 0.003),
        (0.009, 0.005),
        (0.006, 0.012),
        (0.0045, 0.019),
        (0.007, 0.020),
        (0.0045, 0.021),
        (0.0055, 0.024),
        (0.0052, 0.027),
        (0.0035, 0.0295),
        (0.0, 0.030),
    ];
    let m = lathe(&profile, 48);
    assert!(m.is_closed_and_oriented());
    assert!(m.signed_volume() > 0.0, "lathe must be outward");
    m
}

// ---------------------------------------------------------------- mesh basics

#[test]
fn box_mesh_is_closed_outward_with_right_volume_and_area() {
    let m = box_mesh(DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 0.5, 5.0));
    assert!(m.is_closed_and_oriented());
    assert!((m.signed_volume() - 2.0 * 0.5 * 3.0).abs() < 1e-12);
    let area = 2.0 * (2.0 * 0.5 + 0.5 * 3.0 + 3.0 * 2.0);
    assert!((m.surface_area() - area).abs() < 1e-12);
    let mut f = m.clone();
    f.flip();
    assert!(f.is_closed_and_oriented());
    assert!((f.signed_volume() + 3.0).abs() < 1e-12);
}

#[test]
fn open_or_doubled_meshes_are_not_closed() {
    let m = box_mesh(DVec3::ZERO, DVec3::ONE);
    let mut open = m.clone();
    open.triangles.pop();
    assert!(!open.is_closed_and_oriented());
    let mut doubled = m.clone();
    doubled.triangles.extend(m.triangles.iter().copied());
    assert!(!doubled.is_closed_and_oriented());
    // One face turned over: its edges now repeat the neighbours' directions.
    let mut mixed = m.clone();
    mixed.triangles[0].swap(1, 2);
    assert!(!mixed.is_closed_and_oriented());
    assert!(!TriMesh::default().is_closed_and_oriented());
}

// ---------------------------------------------------------------- mass properties

#[test]
fn sphere_mass_properties_match_closed_form() {
    // r = 0.1 m water ball: m = 4/3 pi 1e-3 * 1000 = 4.18879 kg, I = 2/5 m r^2.
    let mp = Shape::Sphere { radius: 0.1 }.mass_properties(1000.0);
    assert!(rel(mp.mass, 4.188_790_204_786_391) < 1e-14);
    for i in 0..3 {
        assert!(rel(mp.principal_inertia[i], 0.016_755_160_819_145_56) < 1e-14);
    }
    assert_eq!(mp.local_com, DVec3::ZERO);
}

#[test]
fn box_mass_properties_match_closed_form_and_mesh() {
    let h = DVec3::new(0.1, 0.05, 0.02);
    let mp = Shape::Cuboid { half_extents: h }.mass_properties(500.0);
    // m = 500 * 0.2 * 0.1 * 0.04 = 0.4 kg; I_x = m (0.1^2 + 0.04^2) / 12.
    assert!(rel(mp.mass, 0.4) < 1e-14);
    let expect = DVec3::new(0.4 * 0.0116 / 12.0, 0.4 * 0.0416 / 12.0, 0.4 * 0.05 / 12.0);
    assert!((mp.principal_inertia - expect).abs().max_element() < 1e-15 * 0.4);
    // The same box as a mesh: sorted moments are x, y, z here, so the principal
    // frame must be a signed permutation of the identity (up to axis signs).
    let mesh = Shape::Mesh(Arc::new(box_mesh(-h, h))).mass_properties(500.0);
    assert!(rel(mesh.mass, 0.4) < 1e-13);
    assert!(mesh.local_com.length() < 1e-16);
    assert!((mesh.principal_inertia - expect).abs().max_element() < 1e-13 * expect.x);
    let frame = DMat3::from_quat(mesh.principal_frame);
    for (k, axis) in [DVec3::X, DVec3::Y, DVec3::Z].iter().enumerate() {
        assert!((frame.col(k).dot(*axis).abs() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn unit_cube_mesh_off_origin_matches_closed_form() {
    let mp = Shape::Mesh(Arc::new(box_mesh(DVec3::ZERO, DVec3::ONE))).mass_properties(2.0);
    assert!(rel(mp.mass, 2.0) < 1e-14);
    assert!((mp.local_com - DVec3::splat(0.5)).length() < 1e-15);
    for i in 0..3 {
        assert!(rel(mp.principal_inertia[i], 2.0 / 6.0) < 1e-14);
    }
}

#[test]
fn rotated_tiny_box_mesh_recovers_axes_and_moments() {
    // A 4 x 2 x 1 cm steel-ish brick, rotated and moved away from the origin.
    let h = DVec3::new(0.02, 0.01, 0.005);
    let rot = DQuat::from_euler(glam::EulerRot::ZYX, 0.7, -0.4, 1.1);
    let shift = DVec3::new(0.3, -0.2, 0.9);
    let mesh = transformed(&box_mesh(-h, h), rot, shift);
    let mp = Shape::Mesh(Arc::new(mesh)).mass_properties(7800.0);
    let exact = Shape::Cuboid { half_extents: h }.mass_properties(7800.0);
    assert!(rel(mp.mass, exact.mass) < 1e-12);
    assert!((mp.local_com - shift).length() < 1e-15);
    // Sorted ascending: the long axis x has the smallest moment, z the largest.
    for k in 0..3 {
        assert!(rel(mp.principal_inertia[k], exact.principal_inertia[k]) < 1e-10);
        let got = mp.principal_frame * DVec3::AXES[k];
        assert!((got.dot(rot * DVec3::AXES[k]).abs() - 1.0).abs() < 1e-12);
    }
    let m = DMat3::from_quat(mp.principal_frame);
    assert!((m.determinant() - 1.0).abs() < 1e-12);
    // The body-frame tensor reassembles to R diag R^T.
    let want = DMat3::from_quat(rot)
        * DMat3::from_diagonal(exact.principal_inertia)
        * DMat3::from_quat(rot).transpose();
    let got = mp.inertia_tensor();
    for c in 0..3 {
        assert!((got.col(c) - want.col(c)).abs().max_element() < 1e-10 * exact.principal_inertia.z);
    }
}

#[test]
fn fine_mesh_sphere_approaches_closed_form() {
    // A 1.5 cm steel ball as an icosphere with 20480 faces. The inscribed polyhedron
    // loses volume as O(edge^2); measured deficit 5.4e-4 for mass, 9.0e-4 for I.
    let r = 0.015;
    let mesh = icosphere(r, 5);
    assert!(mesh.is_closed_and_oriented());
    let mp = Shape::Mesh(Arc::new(mesh)).mass_properties(7850.0);
    let exact = Shape::Sphere { radius: r }.mass_properties(7850.0);
    assert!(
        rel(mp.mass, exact.mass) < 1e-3,
        "{}",
        rel(mp.mass, exact.mass)
    );
    assert!(mp.local_com.length() < 1e-12 * r);
    for k in 0..3 {
        let e = rel(mp.principal_inertia[k], exact.principal_inertia[k]);
        assert!(e < 1.5e-3, "{e}");
    }
    // Coarser meshes must be worse: the test can tell convergence from luck.
    let coarse = Shape::Mesh(Arc::new(icosphere(r, 2))).mass_properties(7850.0);
    assert!(rel(coarse.mass, exact.mass) > 10.0 * rel(mp.mass, exact.mass));
}

#[test]
fn tiny_pawn_gets_its_symmetry_axis_when_rotated_off_axis() {
    let base = pawn();
    let density = 0.030 / base.signed_volume(); // 30 g
    let upright = Shape::Mesh(Arc::new(base.clone())).mass_properties(density);
    assert!(rel(upright.mass, 0.030) < 1e-12);
    let rot = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.9);
    let shift = DVec3::new(0.05, 0.02, -0.01);
    let tilted = Shape::Mesh(Arc::new(transformed(&base, rot, shift))).mass_properties(density);
    // Pawn-scale inertia, as in the field notes (~1e-6 .. 1e-5 kg m^2).
    assert!(tilted.principal_inertia.max_element() < 1e-5);
    assert!(tilted.principal_inertia.min_element() > 1e-7);
    let p = tilted.principal_inertia;
    // Slender: the symmetry axis has the smallest moment and the other two are equal.
    assert!(rel(p.y, p.z) < 1e-12, "{p}");
    assert!(p.x < 0.9 * p.y);
    let axis = tilted.principal_frame * DVec3::X;
    assert!(
        (axis.dot(rot * DVec3::Z).abs() - 1.0).abs() < 1e-12,
        "{axis}"
    );
    for k in 0..3 {
        assert!(rel(p[k], upright.principal_inertia[k]) < 1e-11);
    }
    assert!((tilted.local_com - (rot * upright.local_com + shift)).length() < 1e-15);
    // And the flight picks the exact axisymmetric law for it.
    let mut f = FreeFlight::default();
    let cfg = FlightConfig::default();
    let w = DVec3::new(3.0, -20.0, 7.0);
    f.reset(
        &tilted,
        LaunchState {
            origin: DVec3::ZERO,
            orientation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: w,
        },
        DVec3::ZERO,
        1.5,
        &cfg,
    );
    assert_eq!(f.rotation_kind(), RotationKind::Axisymmetric);
}

#[test]
fn support_and_bounding_radius() {
    let h = DVec3::new(1.0, 2.0, 3.0);
    let cube = Shape::Cuboid { half_extents: h };
    assert_eq!(
        cube.support(DVec3::new(1.0, -1.0, 0.0)),
        DVec3::new(1.0, -2.0, 3.0)
    );
    let about = DVec3::new(0.5, -1.0, 0.0);
    assert!((cube.bounding_radius(about) - DVec3::new(1.5, 3.0, 3.0).length()).abs() < 1e-15);
    let mesh = Shape::Mesh(Arc::new(box_mesh(-h, h)));
    assert_eq!(
        mesh.support(DVec3::new(1.0, -1.0, 0.1)),
        DVec3::new(1.0, -2.0, 3.0)
    );
    assert!((mesh.bounding_radius(about) - cube.bounding_radius(about)).abs() < 1e-15);
    let ball = Shape::Sphere { radius: 2.0 };
    assert!((ball.support(DVec3::new(0.0, 3.0, 4.0)) - DVec3::new(0.0, 1.2, 1.6)).length() < 1e-15);
    assert_eq!(ball.bounding_radius(DVec3::new(3.0, 4.0, 0.0)), 7.0);
    assert!((mesh.volume() - cube.volume()).abs() < 1e-12);
}

// ---------------------------------------------------------------- OBJ loading

/// The OBJ file `text` in the temporary folder, removed when the guard is dropped after
/// the test passed (kept when it failed).
fn temp_obj(name: &str, text: &str) -> crate::test_temp::TempPath {
    crate::test_temp::TempPath::file("body-test", &format!("{name}.obj"), text)
}

const CUBE_OBJ: &str = "\
# unit cube, quads with per-face normals (so single_index splits the corners)
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1
vn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0
o bottom
f 1//1 4//1 3//1 2//1
o rest
f 5//2 6//2 7//2 8//2
f 1//3 2//3 6//3 5//3
f 4//4 8//4 7//4 3//4
f 1//5 5//5 8//5 4//5
f 2//6 3//6 7//6 6//6
";

#[test]
fn load_obj_unit_cube_welds_and_scales() {
    let path = temp_obj("cube", CUBE_OBJ);
    let mesh = load_obj(&path, 0.05).unwrap();
    assert_eq!(mesh.vertices.len(), 8);
    assert_eq!(mesh.triangles.len(), 12);
    assert!(mesh.is_closed_and_oriented());
    assert!(rel(mesh.signed_volume(), 0.05f64.powi(3)) < 1e-6);
    let mp = Shape::Mesh(Arc::new(mesh)).mass_properties(1000.0);
    assert!((mp.local_com - DVec3::splat(0.025)).length() < 1e-8);
}

#[test]
fn load_obj_flips_inward_mesh() {
    // The same cube with every face wound clockwise seen from outside.
    let inward: String = CUBE_OBJ
        .lines()
        .map(|l| {
            if let Some(rest) = l.strip_prefix("f ") {
                let mut v: Vec<&str> = rest.split_whitespace().collect();
                v.reverse();
                format!("f {}\n", v.join(" "))
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let path = temp_obj("inward", &inward);
    let mesh = load_obj(&path, 1.0).unwrap();
    assert!(mesh.is_closed_and_oriented());
    assert!(rel(mesh.signed_volume(), 1.0) < 1e-12);
}

#[test]
fn load_obj_reports_errors() {
    let path = temp_obj("nofaces", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n");
    let err = load_obj(&path, 1.0).unwrap_err();
    assert!(matches!(err, ObjError::NoFaces { .. }), "{err}");

    let missing = std::env::temp_dir().join("body-test-does-not-exist.obj");
    let err = load_obj(&missing, 1.0).unwrap_err();
    assert!(matches!(err, ObjError::Load { .. }), "{err}");

    let path = temp_obj(
        "flat",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 4 3 2 1\n",
    );
    let err = load_obj(&path, 1.0).unwrap_err();
    assert!(matches!(err, ObjError::DegenerateVolume { .. }), "{err}");

    let path = temp_obj("cube-inf", CUBE_OBJ);
    let err = load_obj(&path, f64::INFINITY).unwrap_err();
    assert!(matches!(err, ObjError::NonFiniteVertex { .. }), "{err}");
}
