//! Triangle meshes of the scene's shapes in the Z-up body frame: UV spheres, boxes with
//! flat faces, quads, and OBJ meshes with crease-angle normals.

use super::*;

// ---------------------------------------------------------------------------------
// Meshes (Z-up body frame).
// ---------------------------------------------------------------------------------

/// UV sphere with smooth normals. Pole rows are duplicated per segment (so that the seam
/// and poles need no special normals), and the degenerate triangles at the poles are left
/// out.
pub(super) fn sphere_mesh(radius: f64) -> MeshData {
    let (s, r) = (SPHERE_SEGMENTS, SPHERE_RINGS);
    let mut positions = Vec::with_capacity((r + 1) * (s + 1));
    let mut normals = Vec::with_capacity((r + 1) * (s + 1));
    for i in 0..=r {
        let theta = PI * i as f64 / r as f64;
        for j in 0..=s {
            let phi = 2.0 * PI * j as f64 / s as f64;
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            positions.push(n * radius);
            normals.push(n);
        }
    }
    let mut indices = Vec::with_capacity(6 * r * s);
    for i in 0..r {
        for j in 0..s {
            let a = (i * (s + 1) + j) as u32;
            let b = a + (s + 1) as u32;
            // (e_theta, e_phi, e_r) is right-handed, so a -> b (south) -> b+1 (east) is
            // counter-clockwise seen from outside.
            if i != r - 1 {
                indices.extend([a, b, b + 1]);
            }
            if i != 0 {
                indices.extend([a, b + 1, a + 1]);
            }
        }
    }
    MeshData {
        positions,
        normals,
        indices,
    }
}

/// 24-vertex box: four vertices per face so that every face has its own flat normal.
pub(super) fn cuboid_mesh(h: DVec3) -> MeshData {
    let e = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut positions = Vec::with_capacity(24);
    let mut normals = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(36);
    for k in 0..3 {
        for sign in [1.0, -1.0] {
            let n = e[k] * sign;
            // In-face axes (a, b) with a x b = n, so the corner order below is CCW.
            let (a, b) = if sign > 0.0 {
                (e[(k + 1) % 3], e[(k + 2) % 3])
            } else {
                (e[(k + 2) % 3], e[(k + 1) % 3])
            };
            let base = positions.len() as u32;
            for (p, q) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(h * (n + a * p + b * q));
                normals.push(n);
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    MeshData {
        positions,
        normals,
        indices,
    }
}

/// Rectangle centred on the origin spanned by half-axes `hu`, `hv`, front face along `n`
/// (`hu x hv` is along `n`).
pub(super) fn quad_mesh(hu: DVec3, hv: DVec3, n: DVec3) -> MeshData {
    let n = n.normalize();
    let positions = vec![-hu - hv, hu - hv, hu + hv, -hu + hv];
    let indices = if hu.cross(hv).dot(n) >= 0.0 {
        vec![0, 1, 2, 0, 2, 3]
    } else {
        vec![0, 2, 1, 0, 3, 2]
    };
    MeshData {
        positions,
        normals: vec![n; 4],
        indices,
    }
}

/// Triangle mesh with crease-angle normals: each corner averages (area-weighted) the
/// normals of the faces around its vertex that are within the crease angle of its own
/// face; corners with the same vertex and normal share one output vertex. Zero-area
/// triangles are dropped: they have no normal and draw nothing.
pub(super) fn trimesh_mesh(mesh: &TriMesh) -> MeshData {
    let cos_crease = CREASE_ANGLE_DEG.to_radians().cos();
    let nv = mesh.vertices.len();
    let scale = mesh
        .vertices
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs().max_element()))
        .max(f64::MIN_POSITIVE);
    let mut faces: Vec<([u32; 3], DVec3, DVec3)> = Vec::with_capacity(mesh.triangles.len());
    for tri in &mesh.triangles {
        if tri.iter().any(|&i| i as usize >= nv) {
            continue;
        }
        let [a, b, c] = tri.map(|i| mesh.vertices[i as usize]);
        let area_n = (b - a).cross(c - a);
        if area_n.length() <= 1e-12 * scale * scale {
            continue;
        }
        faces.push((*tri, area_n, area_n.normalize()));
    }
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); nv];
    for (f, (tri, _, _)) in faces.iter().enumerate() {
        for &i in tri {
            incident[i as usize].push(f);
        }
    }
    let mut out = MeshData {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::with_capacity(3 * faces.len()),
    };
    let mut shared: HashMap<(u32, [u64; 3]), u32> = HashMap::new();
    for (tri, _, unit) in &faces {
        for &vi in tri {
            let sum: DVec3 = incident[vi as usize]
                .iter()
                .filter(|&&g| faces[g].2.dot(*unit) >= cos_crease)
                .map(|&g| faces[g].1)
                .sum();
            let n = sum.try_normalize().unwrap_or(*unit);
            let key = (vi, [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()]);
            let index = *shared.entry(key).or_insert_with(|| {
                out.positions.push(mesh.vertices[vi as usize]);
                out.normals.push(n);
                (out.positions.len() - 1) as u32
            });
            out.indices.push(index);
        }
    }
    out
}
