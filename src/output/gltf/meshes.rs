//! Triangle meshes of the scene's shapes in the Z-up body frame: UV spheres, boxes with
//! flat faces, quads, and OBJ meshes with crease-angle normals; each with texture
//! coordinates (`TEXCOORD_0`, see `docs/gltf.md`, "Texture coordinates"): spheres
//! equirectangular, boxes per face and meshes around their z axis in units of
//! [`WOOD_TILE_M`] with the grain along the box's longest axis or the mesh's z axis,
//! the receiver 0..1 over the picture's rectangle.

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
    let mut uvs = Vec::with_capacity((r + 1) * (s + 1));
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
            // Equirectangular: u around the pole from the seam, v from the north pole.
            uvs.push([j as f64 / s as f64, i as f64 / r as f64]);
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
        uvs,
        indices,
    }
}

/// 24-vertex box: four vertices per face so that every face has its own flat normal.
/// Texture coordinates in units of [`WOOD_TILE_M`]: on each face `u` runs along the
/// longest of the box's axes that lies in the face (the grain of a block of wood) and `v`
/// along the other.
pub(super) fn cuboid_mesh(h: DVec3) -> MeshData {
    let e = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut positions = Vec::with_capacity(24);
    let mut normals = Vec::with_capacity(24);
    let mut uvs = Vec::with_capacity(24);
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
            let (la, lb) = ((h * a).length(), (h * b).length());
            for (p, q) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(h * (n + a * p + b * q));
                normals.push(n);
                let (x, y) = (p * la / WOOD_TILE_M, q * lb / WOOD_TILE_M);
                uvs.push(if la >= lb { [x, y] } else { [y, x] });
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    MeshData {
        positions,
        normals,
        uvs,
        indices,
    }
}

/// Rectangle centred on the origin spanned by half-axes `hu`, `hv`, front face along `n`
/// (`hu x hv` is along `n`). Texture coordinates: `(0, 0)` at `-hu / margin + hv /
/// margin` and `(1, 1)` at `hu / margin - hv / margin` (glTF's image origin is its top
/// left), so that a quad `margin` times the picture's size shows the picture, drawn over
/// 0..1, on the picture's rectangle, top along `hv`.
pub(super) fn quad_mesh(hu: DVec3, hv: DVec3, n: DVec3, margin: f64) -> MeshData {
    let n = n.normalize();
    let positions = vec![-hu - hv, hu - hv, hu + hv, -hu + hv];
    let uvs = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|(p, q)| [0.5 + 0.5 * p * margin, 0.5 - 0.5 * q * margin])
        .collect();
    let indices = if hu.cross(hv).dot(n) >= 0.0 {
        vec![0, 1, 2, 0, 2, 3]
    } else {
        vec![0, 2, 1, 0, 3, 2]
    };
    MeshData {
        positions,
        normals: vec![n; 4],
        uvs,
        indices,
    }
}

/// Triangle mesh with crease-angle normals: each corner averages (area-weighted) the
/// normals of the faces around its vertex that are within the crease angle of its own
/// face; corners with the same vertex, normal and texture coordinates share one output
/// vertex. Zero-area triangles are dropped: they have no normal and draw nothing.
///
/// Texture coordinates are cylindrical about the body's z axis (a chess piece's axis, the
/// grain of a turned piece of wood): `u = z / WOOD_TILE_M`, `v` the angle about z, a
/// whole number of tiles around; a triangle across the seam gets its own corners on the
/// far side, and a corner on the axis takes the angle of its triangle's centre.
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
        uvs: Vec::new(),
        indices: Vec::with_capacity(3 * faces.len()),
    };
    // Whole tiles around: the mean distance from the axis sets the circumference.
    let radial = mesh
        .vertices
        .iter()
        .map(|v| v.truncate().length())
        .sum::<f64>()
        / mesh.vertices.len().max(1) as f64;
    let around = (std::f64::consts::TAU * radial / WOOD_TILE_M)
        .round()
        .max(1.0);
    let mut shared: HashMap<(u32, [u64; 5]), u32> = HashMap::new();
    for (tri, _, unit) in &faces {
        let turns = cylinder_turns(tri.map(|i| mesh.vertices[i as usize]));
        for (&vi, turn) in tri.iter().zip(turns) {
            let sum: DVec3 = incident[vi as usize]
                .iter()
                .filter(|&&g| faces[g].2.dot(*unit) >= cos_crease)
                .map(|&g| faces[g].1)
                .sum();
            let n = sum.try_normalize().unwrap_or(*unit);
            let p = mesh.vertices[vi as usize];
            let uv = [p.z / WOOD_TILE_M, turn * around];
            let key = (
                vi,
                [
                    n.x.to_bits(),
                    n.y.to_bits(),
                    n.z.to_bits(),
                    uv[0].to_bits(),
                    uv[1].to_bits(),
                ],
            );
            let index = *shared.entry(key).or_insert_with(|| {
                out.positions.push(p);
                out.normals.push(n);
                out.uvs.push(uv);
                (out.positions.len() - 1) as u32
            });
            out.indices.push(index);
        }
    }
    out
}

/// The angles about z of a triangle's corners, in turns from 0, unwrapped so that the
/// three are within half a turn of each other: across the seam, the corners just past it
/// get a whole turn added (1.02 beside 0.98), which keeps the texture seamless. A corner
/// on the axis takes the angle of the triangle's centre.
fn cylinder_turns(corners: [DVec3; 3]) -> [f64; 3] {
    let turn = |p: DVec3| (p.y.atan2(p.x) / std::f64::consts::TAU).rem_euclid(1.0);
    let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
    let scale = corners.iter().fold(0.0_f64, |m, p| m.max(p.length()));
    let mut turns = corners.map(|p| {
        if p.truncate().length() <= 1e-9 * scale {
            turn(centre)
        } else {
            turn(p)
        }
    });
    let lo = turns.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = turns.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi - lo > 0.5 {
        for t in &mut turns {
            if *t < 0.5 {
                *t += 1.0;
            }
        }
    }
    turns
}

/// Shift every texture coordinate by `offset` (tiles), so that objects sharing a
/// texture show different parts of it.
pub(super) fn offset_uvs(data: &mut MeshData, offset: [f64; 2]) {
    for uv in &mut data.uvs {
        uv[0] += offset[0];
        uv[1] += offset[1];
    }
}
