//! Rigid bodies: shapes, meshes, exact mass properties, and the table they start from.
//!
//! The main types and how data flows through them:
//!
//! * [`TriMesh`] is a triangle mesh in its own (body) coordinates. [`load_obj`] reads one
//!   from a Wavefront OBJ file, welds vertices that share a position, checks it and turns
//!   inward-facing meshes outward.
//! * [`Shape`] is what a launched object is: a [`Shape::Sphere`] or [`Shape::Cuboid`]
//!   centred on the body origin, or a shared [`Shape::Mesh`]. The body frame is the
//!   shape's own coordinate frame.
//! * [`Shape::mass_properties`] turns a shape and a density into [`MassProperties`]:
//!   mass, centre of mass in the body frame, principal moments about the centre of mass
//!   and the rotation from the principal axes into the body frame. Meshes are integrated
//!   exactly (divergence theorem over signed tetrahedra) and diagonalised with
//!   [`sym_eigen`], which stays accurate for tiny real objects.
//! * [`Table`] is the axis-aligned box the bodies are launched from.
//!
//! How a body flies with these mass properties is [`crate::sim::flight`]'s business.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat3, DQuat, DVec3};

use crate::linalg::sym_eigen;

/// A triangle mesh in body coordinates. Triangles are counter-clockwise seen from
/// outside for a correctly oriented closed mesh (so its signed volume is positive).
/// Indices must be smaller than `vertices.len()`; the methods panic otherwise.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            vertices,
            triangles,
        }
    }

    /// Centre of the axis-aligned bounding box of the vertices (zero for an empty mesh).
    /// Sums over triangles are taken relative to it so that a small object far from its
    /// origin does not lose digits to cancellation.
    fn reference_point(&self) -> DVec3 {
        let (lo, hi) = self.bounding_box();
        if self.vertices.is_empty() {
            DVec3::ZERO
        } else {
            0.5 * (lo + hi)
        }
    }

    /// Axis-aligned bounding box `(min, max)` of the vertices; inverted (`+inf`, `-inf`)
    /// for an empty mesh.
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        )
    }

    /// Signed enclosed volume (divergence theorem). Positive for a closed mesh whose
    /// normals point outward; for an open mesh the value depends on the hole and is only
    /// meaningful as a sign check.
    pub fn signed_volume(&self) -> f64 {
        let r = self.reference_point();
        let six_v: f64 = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.corners(t, r);
                a.dot(b.cross(c))
            })
            .sum();
        six_v / 6.0
    }

    /// True if every directed edge occurs exactly once and its reverse exactly once, i.e.
    /// the mesh is a closed, consistently oriented 2-manifold-with-pinches surface.
    /// Triangles that repeat a vertex index or refer to a missing vertex make it false.
    pub fn is_closed_and_oriented(&self) -> bool {
        if self.triangles.is_empty() {
            return false;
        }
        let n = self.vertices.len() as u64;
        let mut edges: Vec<u64> = Vec::with_capacity(3 * self.triangles.len());
        for t in &self.triangles {
            for i in 0..3 {
                let (a, b) = (t[i] as u64, t[(i + 1) % 3] as u64);
                if a == b || a >= n || b >= n {
                    return false;
                }
                edges.push((a << 32) | b);
            }
        }
        edges.sort_unstable();
        if edges.windows(2).any(|w| w[0] == w[1]) {
            return false;
        }
        edges
            .iter()
            .all(|&e| edges.binary_search(&e.rotate_right(32)).is_ok())
    }

    /// Number of undirected edges that belong to exactly one triangle: zero for a
    /// closed mesh, the length of the holes' rims otherwise.
    pub fn boundary_edge_count(&self) -> usize {
        let mut edges: Vec<u64> = Vec::with_capacity(3 * self.triangles.len());
        for t in &self.triangles {
            for i in 0..3 {
                let (a, b) = (t[i] as u64, t[(i + 1) % 3] as u64);
                edges.push((a.min(b) << 32) | a.max(b));
            }
        }
        edges.sort_unstable();
        let mut count = 0;
        let mut i = 0;
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && edges[j] == edges[i] {
                j += 1;
            }
            if j - i == 1 {
                count += 1;
            }
            i = j;
        }
        count
    }

    /// Reverses the orientation of every triangle (normals point the other way).
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Total area of the triangles.
    pub fn surface_area(&self) -> f64 {
        let r = self.reference_point();
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.corners(t, r);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[inline]
    fn corners(&self, t: &[u32; 3], r: DVec3) -> [DVec3; 3] {
        [
            self.vertices[t[0] as usize] - r,
            self.vertices[t[1] as usize] - r,
            self.vertices[t[2] as usize] - r,
        ]
    }
}

/// Why [`load_obj`] rejected a file.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// The file could not be opened or read (missing, a folder, no permission); the
    /// source is the operating system's reason.
    #[error("cannot read OBJ file {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A line of the file is not valid OBJ (a number that does not parse, a face index
    /// out of range).
    #[error("{path}:{line}: {reason}")]
    Syntax {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    /// tobj could not parse the file and no single line could be blamed.
    #[error("cannot parse OBJ file {path}: {source}")]
    Load {
        path: PathBuf,
        #[source]
        source: tobj::LoadError,
    },
    /// The file is larger than [`ObjLimits::max_bytes`].
    #[error("OBJ file {path} is {bytes} bytes, more than the {max} supported")]
    TooBig { path: PathBuf, bytes: u64, max: u64 },
    /// The mesh has more triangles than [`ObjLimits::max_triangles`].
    #[error(
        "OBJ file {path} has {triangles} triangles, more than the {max} supported; decimate it"
    )]
    TooManyTriangles {
        path: PathBuf,
        triangles: usize,
        max: usize,
    },
    /// A vertex lies farther than [`ObjLimits::max_coordinate`] from the origin along
    /// an axis once scaled.
    #[error("OBJ file {path}: vertex {index} is {vertex} after scaling by {scale}, outside the +-{max:e} m supported")]
    OutOfRange {
        path: PathBuf,
        index: usize,
        vertex: DVec3,
        scale: f64,
        max: f64,
    },
    /// The mesh is not closed: some edges belong to a single triangle, so it has no
    /// well-defined inside (volume, mass, shadow fill).
    #[error("OBJ file {path} is not a closed mesh: {boundary_edges} edges belong to a single triangle (a hole); close it")]
    Open {
        path: PathBuf,
        boundary_edges: usize,
    },
    /// The file parsed but holds no triangle with three distinct vertices (no `f` lines,
    /// or only points, lines and collapsed faces).
    #[error("OBJ file {path} has no faces")]
    NoFaces { path: PathBuf },
    /// A vertex coordinate is NaN or infinite after scaling.
    #[error("OBJ file {path}: vertex {index} is not finite after scaling by {scale}: {vertex}")]
    NonFiniteVertex {
        path: PathBuf,
        index: usize,
        vertex: DVec3,
        scale: f64,
    },
    /// The faces enclose (almost) no volume: |V| <= 1e-9 of the cube of the largest
    /// bounding-box side (a flat or zero-thickness mesh, or a zero scale), so it has no
    /// usable mass properties.
    #[error("OBJ file {path} encloses no volume: {volume} for a bounding box of side {extent}")]
    DegenerateVolume {
        path: PathBuf,
        volume: f64,
        extent: f64,
    },
}

/// The corners of a box centred on the origin with half extents `he`: corner `i` has
/// `+he.x` when bit 0 of `i` is set (else `-he.x`), bit 1 for y, bit 2 for z. The
/// rasterizer's box triangles and the contact shapes rely on this order.
pub fn box_corners(he: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 != 0 { he.x } else { -he.x },
            if i & 2 != 0 { he.y } else { -he.y },
            if i & 4 != 0 { he.z } else { -he.z },
        )
    })
}

/// What [`load_obj_checked`] accepts: bounds that keep loading time, memory and the
/// mesh's arithmetic within what the machine can serve.
#[derive(Clone, Debug)]
pub struct ObjLimits {
    /// Largest magnitude of a vertex coordinate after scaling (m).
    pub max_coordinate: f64,
    /// Most triangles after triangulation and welding.
    pub max_triangles: usize,
    /// Largest file size (bytes).
    pub max_bytes: u64,
}

/// [`load_obj`] for scene input: the file's size is checked before it is read, the
/// OS reason is kept when it cannot be read, a line number is given when it does not
/// parse, and the mesh must be closed, within the triangle count and within the
/// coordinate range.
pub fn load_obj_checked(path: &Path, scale: f64, limits: &ObjLimits) -> Result<TriMesh, ObjError> {
    let io = |source| ObjError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        return Err(io(std::io::Error::other("it is a folder, not a file")));
    }
    // A device or a pipe has no length to check against the limit, and may never end.
    if !meta.is_file() {
        return Err(io(std::io::Error::other("it is not a regular file")));
    }
    if meta.len() > limits.max_bytes {
        return Err(ObjError::TooBig {
            path: path.to_path_buf(),
            bytes: meta.len(),
            max: limits.max_bytes,
        });
    }
    // Opening the file here gives the OS reason (permission denied, ...) that tobj
    // would drop.
    std::fs::File::open(path).map_err(io)?;
    let mesh = load_obj(path, scale).map_err(|e| match e {
        ObjError::Load { path, source } => match first_bad_line(&path) {
            Some((line, reason)) => ObjError::Syntax { path, line, reason },
            None => ObjError::Load { path, source },
        },
        other => other,
    })?;
    if mesh.triangles.len() > limits.max_triangles {
        return Err(ObjError::TooManyTriangles {
            path: path.to_path_buf(),
            triangles: mesh.triangles.len(),
            max: limits.max_triangles,
        });
    }
    if let Some((index, &vertex)) = mesh
        .vertices
        .iter()
        .enumerate()
        .find(|(_, v)| v.abs().max_element() > limits.max_coordinate)
    {
        return Err(ObjError::OutOfRange {
            path: path.to_path_buf(),
            index,
            vertex,
            scale,
            max: limits.max_coordinate,
        });
    }
    let boundary_edges = mesh.boundary_edge_count();
    if boundary_edges > 0 {
        return Err(ObjError::Open {
            path: path.to_path_buf(),
            boundary_edges,
        });
    }
    Ok(mesh)
}

/// The first line of an OBJ file that tobj would refuse, with the reason, found by a
/// linear scan of `v` and `f` lines (only run after tobj failed, to name the line).
fn first_bad_line(path: &Path) -> Option<(usize, String)> {
    let text = std::fs::read(path).ok()?;
    let text = String::from_utf8_lossy(&text);
    let mut vertices: i64 = 0;
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let nums: Vec<&str> = words.collect();
                if nums.len() < 3 {
                    return Some((
                        k + 1,
                        format!("a vertex needs 3 coordinates, got {}", nums.len()),
                    ));
                }
                if let Some(bad) = nums.iter().find(|w| w.parse::<f32>().is_err()) {
                    return Some((k + 1, format!("vertex coordinate `{bad}` is not a number")));
                }
                vertices += 1;
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Some((
                        k + 1,
                        format!("a face needs at least 3 corners, got {}", corners.len()),
                    ));
                }
                for c in corners {
                    let idx = c.split('/').next().unwrap_or("");
                    match idx.parse::<i64>() {
                        Err(_) => {
                            return Some((k + 1, format!("face corner `{c}` is not a vertex index")))
                        }
                        Ok(i) if i == 0 || i > vertices || -i > vertices => {
                            return Some((
                                k + 1,
                                format!("face corner `{c}` refers to a vertex that does not exist ({vertices} so far)"),
                            ))
                        }
                        Ok(_) => {}
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Loads every model of an OBJ file into one [`TriMesh`], multiplying coordinates by
/// `scale` (e.g. 0.001 for a file in millimetres).
///
/// Faces are triangulated as fans. Vertices with bit-identical positions are welded
/// (tobj's `single_index` duplicates a position for every distinct normal or texture
/// coordinate, and separate models or groups never share indices), and triangles that
/// collapse to a repeated vertex are dropped, so a watertight file gives a closed mesh.
/// If the mesh then has negative signed volume it is flipped so that its normals point
/// outward; this is exact for a closed, consistently oriented mesh (the common case of
/// an inside-out export) and, for an open mesh, at least keeps its mass positive. Open
/// meshes are accepted: check [`TriMesh::is_closed_and_oriented`] if that matters, as
/// their volume and mass properties are then only approximate.
pub fn load_obj(path: &Path, scale: f64) -> Result<TriMesh, ObjError> {
    // The struct update keeps this compiling if another crate enables tobj's optional
    // `merging` or `reordering` features, which add fields to `LoadOptions`.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|source| ObjError::Load {
        path: path.to_path_buf(),
        source,
    })?;

    // Weld: key every loaded position by its f32 bit pattern (with -0 folded into +0),
    // sort, and give equal keys one vertex index.
    let mut keyed: Vec<([u32; 3], u32)> = Vec::new();
    let mut raw_triangles: Vec<[u32; 3]> = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let base = keyed.len() as u32;
        for p in mesh.positions.chunks_exact(3) {
            let key = [p[0], p[1], p[2]].map(|x| (x + 0.0).to_bits());
            keyed.push((key, keyed.len() as u32));
        }
        for t in mesh.indices.chunks_exact(3) {
            raw_triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    keyed.sort_unstable();
    let mut remap = vec![0u32; keyed.len()];
    let mut vertices: Vec<DVec3> = Vec::new();
    for (i, (key, original)) in keyed.iter().enumerate() {
        if i == 0 || keyed[i - 1].0 != *key {
            let [x, y, z] = key.map(|b| f32::from_bits(b) as f64 * scale);
            vertices.push(DVec3::new(x, y, z));
        }
        remap[*original as usize] = vertices.len() as u32 - 1;
    }
    let triangles: Vec<[u32; 3]> = raw_triangles
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    if triangles.is_empty() {
        return Err(ObjError::NoFaces {
            path: path.to_path_buf(),
        });
    }
    if let Some((index, &vertex)) = vertices.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(ObjError::NonFiniteVertex {
            path: path.to_path_buf(),
            index,
            vertex,
            scale,
        });
    }
    // Unreferenced vertices are harmless for mass properties but would inflate the
    // bounding radius and support points, so keep only the used ones.
    let mut mesh = compact(vertices, triangles);
    let (lo, hi) = mesh.bounding_box();
    let extent = (hi - lo).max_element();
    let volume = mesh.signed_volume();
    if !volume.is_finite() || volume.abs() <= 1e-9 * extent * extent * extent {
        return Err(ObjError::DegenerateVolume {
            path: path.to_path_buf(),
            volume,
            extent,
        });
    }
    if volume < 0.0 {
        mesh.flip();
    }
    Ok(mesh)
}

/// Drops vertices that no triangle uses and renumbers the triangles.
fn compact(vertices: Vec<DVec3>, mut triangles: Vec<[u32; 3]>) -> TriMesh {
    let mut new_index = vec![u32::MAX; vertices.len()];
    let mut kept = Vec::with_capacity(vertices.len());
    for t in &mut triangles {
        for i in t.iter_mut() {
            let slot = &mut new_index[*i as usize];
            if *slot == u32::MAX {
                *slot = kept.len() as u32;
                kept.push(vertices[*i as usize]);
            }
            *i = *slot;
        }
    }
    TriMesh::new(kept, triangles)
}

/// The solid of a body, in body coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A ball centred on the body origin.
    Sphere { radius: f64 },
    /// A box centred on the body origin with faces normal to the body axes.
    Cuboid { half_extents: DVec3 },
    /// A closed, outward-oriented triangle mesh (see [`load_obj`]).
    Mesh(Arc<TriMesh>),
}

/// Mass, centre of mass and inertia of a rigid body.
///
/// `principal_inertia[i]` is the moment of inertia about the centre of mass around the
/// principal axis `principal_frame * e_i` (a body-frame direction). `principal_frame` is a
/// proper rotation from principal coordinates into the body frame, so the body-frame
/// inertia tensor is `P diag(principal_inertia) P^T`. Meshes list the moments in
/// ascending order; the primitives list them along the body axes x, y, z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassProperties {
    pub mass: f64,
    pub local_com: DVec3,
    pub principal_inertia: DVec3,
    pub principal_frame: DQuat,
}

impl MassProperties {
    /// Inertia tensor about the centre of mass, in body axes.
    pub fn inertia_tensor(&self) -> DMat3 {
        let p = DMat3::from_quat(self.principal_frame);
        p * DMat3::from_diagonal(self.principal_inertia) * p.transpose()
    }

    /// The body-frame direction of the body's long axis: the principal axis of least
    /// inertia (the first of equal least moments).
    pub fn long_axis(&self) -> DVec3 {
        let k = self.principal_inertia;
        let e = if k.x <= k.y && k.x <= k.z {
            DVec3::X
        } else if k.y <= k.z {
            DVec3::Y
        } else {
            DVec3::Z
        };
        self.principal_frame * e
    }
}

impl Shape {
    /// Enclosed volume. For a mesh this is the absolute signed volume, matching
    /// [`Shape::mass_properties`], which treats an inside-out mesh as if it were flipped.
    pub fn volume(&self) -> f64 {
        match self {
            Shape::Sphere { radius } => 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3),
            Shape::Cuboid { half_extents: h } => 8.0 * h.x * h.y * h.z,
            Shape::Mesh(mesh) => mesh.signed_volume().abs(),
        }
    }

    /// [`Shape::mass_properties`], or `None` when the result is not usable for flight
    /// (a mass or principal moment that is zero, negative or not finite: a shape too small
    /// or too large for f64).
    pub fn mass_properties_checked(&self, density: f64) -> Option<MassProperties> {
        let v = self.volume();
        if !(density.is_finite() && density > 0.0 && v.is_finite() && v > 0.0) {
            return None;
        }
        let mp = self.mass_properties(density);
        let ok = mp.mass.is_finite()
            && mp.mass > 0.0
            && mp.principal_inertia.is_finite()
            && mp.principal_inertia.min_element() > 0.0
            && mp.local_com.is_finite();
        ok.then_some(mp)
    }

    /// Mass properties of the solid at uniform `density` (kg/m^3 for metres).
    pub fn mass_properties(&self, density: f64) -> MassProperties {
        match self {
            Shape::Sphere { radius } => {
                let mass = density * self.volume();
                MassProperties {
                    mass,
                    local_com: DVec3::ZERO,
                    principal_inertia: DVec3::splat(0.4 * mass * radius * radius),
                    principal_frame: DQuat::IDENTITY,
                }
            }
            Shape::Cuboid { half_extents: h } => {
                let mass = density * self.volume();
                let s = *h * *h;
                MassProperties {
                    mass,
                    local_com: DVec3::ZERO,
                    principal_inertia: mass / 3.0 * DVec3::new(s.y + s.z, s.z + s.x, s.x + s.y),
                    principal_frame: DQuat::IDENTITY,
                }
            }
            Shape::Mesh(mesh) => mesh_mass_properties(mesh, density),
        }
    }

    /// The least of the solid's extents along the body axes (m): the width of the
    /// narrowest shadow it casts unmagnified, where its narrowest direction is a body
    /// axis (as for balls, blocks and the chess pieces).
    pub fn least_width(&self) -> f64 {
        [DVec3::X, DVec3::Y, DVec3::Z]
            .map(|a| (self.support(a) - self.support(-a)).dot(a))
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    }

    /// Largest distance from `about` (body frame) to a point of the solid.
    pub fn bounding_radius(&self, about: DVec3) -> f64 {
        match self {
            Shape::Sphere { radius } => about.length() + radius,
            // The farthest corner is the one on the opposite side in every axis.
            Shape::Cuboid { half_extents } => (about.abs() + *half_extents).length(),
            Shape::Mesh(mesh) => mesh
                .vertices
                .iter()
                .map(|v| v.distance_squared(about))
                .fold(0.0, f64::max)
                .sqrt(),
        }
    }

    /// A point of the solid farthest along `dir` (body frame). For a zero `dir` any point
    /// of the surface is a valid answer; the sphere then returns `(radius, 0, 0)`. Meshes
    /// scan all vertices (O(n)).
    pub fn support(&self, dir: DVec3) -> DVec3 {
        match self {
            Shape::Sphere { radius } => dir.normalize_or(DVec3::X) * *radius,
            Shape::Cuboid { half_extents } => {
                DVec3::select(dir.cmplt(DVec3::ZERO), -*half_extents, *half_extents)
            }
            Shape::Mesh(mesh) => {
                mesh.vertices
                    .iter()
                    .copied()
                    .fold((f64::NEG_INFINITY, DVec3::ZERO), |(best, p), v| {
                        let d = v.dot(dir);
                        if d > best {
                            (d, v)
                        } else {
                            (best, p)
                        }
                    })
                    .1
            }
        }
    }
}

/// Exact mass properties of the solid bounded by a closed mesh.
///
/// Each triangle `(a, b, c)` spans a signed tetrahedron with the reference point; with
/// `d = a . (b x c)` its volume is `d / 6`, its first moment `d (a + b + c) / 24` and its
/// second moment `integral x x^T dV = d / 120 (a a^T + b b^T + c c^T + s s^T)`,
/// `s = a + b + c`. Summing gives the exact polyhedral integrals. All tolerances are
/// relative, so a 3 cm pawn and a 3 m statue are treated alike.
fn mesh_mass_properties(mesh: &TriMesh, density: f64) -> MassProperties {
    let r = mesh.reference_point();
    let mut six_v = 0.0;
    let mut first = DVec3::ZERO;
    // Second moments: xx, yy, zz, xy, yz, zx.
    let mut m2 = [0.0f64; 6];
    for t in &mesh.triangles {
        let [a, b, c] = mesh.corners(t, r);
        let d = a.dot(b.cross(c));
        let s = a + b + c;
        six_v += d;
        first += d * s;
        let sq = a * a + b * b + c * c + s * s;
        m2[0] += d * sq.x;
        m2[1] += d * sq.y;
        m2[2] += d * sq.z;
        m2[3] += d * (a.x * a.y + b.x * b.y + c.x * c.y + s.x * s.y);
        m2[4] += d * (a.y * a.z + b.y * b.z + c.y * c.z + s.y * s.z);
        m2[5] += d * (a.z * a.x + b.z * b.x + c.z * c.x + s.z * s.x);
    }
    let volume = six_v / 6.0;
    // An inside-out mesh gives all integrals with the opposite sign; treating it as
    // flipped keeps the mass positive.
    let sign = volume.signum();
    let c = first / (4.0 * six_v);
    let cov = |k: usize, x: f64, y: f64| sign * (m2[k] / 120.0 - volume * x * y);
    let (cxx, cyy, czz) = (cov(0, c.x, c.x), cov(1, c.y, c.y), cov(2, c.z, c.z));
    let (cxy, cyz, czx) = (cov(3, c.x, c.y), cov(4, c.y, c.z), cov(5, c.z, c.x));
    // Inertia = density * (trace(C) 1 - C), C the covariance about the centre of mass.
    let inertia = [
        cyy + czz,
        -cxy,
        -czx,
        -cxy,
        czz + cxx,
        -cyz,
        -czx,
        -cyz,
        cxx + cyy,
    ]
    .map(|x| density * x);
    let (mut values, mut vectors, mut work) = ([0.0; 3], [0.0; 9], [0.0; 9]);
    sym_eigen(3, &inertia, &mut values, &mut vectors, &mut work);
    let col = |k: usize| DVec3::new(vectors[k], vectors[3 + k], vectors[6 + k]);
    let (e0, e1) = (col(0), col(1));
    // The eigenvector matrix may be a reflection; the third axis is then reversed so
    // that the frame is a proper rotation (any sign of an eigenvector is valid).
    let e2 = if e0.cross(e1).dot(col(2)) < 0.0 {
        -col(2)
    } else {
        col(2)
    };
    MassProperties {
        mass: density * volume.abs(),
        local_com: r + c,
        principal_inertia: DVec3::from_array(values),
        principal_frame: DQuat::from_mat3(&DMat3::from_cols(e0, e1, e2)).normalize(),
    }
}

/// The table (or ground) the occluders are launched from: an axis-aligned box whose
/// top face is the surface. Launched bodies that come back down onto it stop there.
#[derive(Clone, Debug)]
pub struct Table {
    pub center: DVec3,
    pub half_extents: DVec3,
}

impl Table {
    /// Height of the table's top face (m).
    pub fn top(&self) -> f64 {
        self.center.z + self.half_extents.z
    }
}

#[cfg(test)]
pub(crate) mod tests;
