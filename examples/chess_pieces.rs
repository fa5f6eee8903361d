//! Generates one side of a Staunton tournament chess set as closed triangle meshes:
//! `scenes/thinker/pieces/{pawn,rook,knight,bishop,queen,king}.obj`, in metres, Z up, the
//! base on `z = 0` centred on the origin. See `docs/chess-pieces.md`.
//!
//! Run: `cargo run --release --example chess_pieces [-- --out DIR] [--preview DIR]`.
//! `--preview DIR` also renders a 3/4 view and a side silhouette of every piece and a
//! combined picture `DIR/chess-pieces.png`.
//!
//! Every piece is built in millimetres from exact construction rules, so the output is
//! deterministic:
//!
//! * pawn, bishop, queen, king and the knight's base are surfaces of revolution of a 2-D
//!   profile `(r, z)` (lines and arcs) with [`SEGMENTS`] columns around. A profile point
//!   on the axis becomes a single pole vertex, which closes the bottom and top caps;
//! * the rook's crenellations and the queen's coronet make some profile rows depend on
//!   the column: notch columns are duplicated at the notch edges, and coincident
//!   vertices are welded and collapsed triangles dropped, which leaves vertical notch
//!   walls on a closed surface;
//! * the knight's head and the king's cross are bevelled extrusions of a side outline
//!   whose bottom edge stands on the flat top of the revolved body. The top cap of the
//!   body is triangulated around the extrusion's footprint and shares its vertices, so
//!   each piece is one closed, consistently oriented shell (a union by construction).
//!
//! Each mesh is checked (closed and oriented, no degenerate triangle, no intersecting
//! triangles), written, reloaded with `bsa::geometry::shape::load_obj` and checked again.

use std::collections::HashMap;
use std::error::Error;
use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bsa::geometry::shape::{load_obj, Shape, TriMesh};
use glam::{DVec2, DVec3};

/// Columns around the axis of a surface of revolution.
const SEGMENTS: usize = 24;
/// Boxwood density, kg/m^3.
const BOXWOOD: f64 = 900.0;
/// Millimetres to metres.
const MM: f64 = 1e-3;

/// Triangle soup with vertices welded on their position (to 1e-6 mm) and collapsed
/// triangles dropped.
#[derive(Default)]
struct Builder {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    lookup: HashMap<[i64; 3], u32>,
}

impl Builder {
    fn vertex(&mut self, p: DVec3) -> u32 {
        let key = [p.x, p.y, p.z].map(|c| (c * 1e6).round() as i64);
        let vertices = &mut self.vertices;
        *self.lookup.entry(key).or_insert_with(|| {
            vertices.push(p);
            (vertices.len() - 1) as u32
        })
    }

    /// Counter-clockwise seen from outside; dropped if two corners are the same vertex.
    fn tri(&mut self, a: u32, b: u32, c: u32) {
        if a != b && b != c && c != a {
            self.triangles.push([a, b, c]);
        }
    }

    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        self.tri(a, b, c);
        self.tri(a, c, d);
    }

    fn mesh(self) -> TriMesh {
        TriMesh::new(self.vertices, self.triangles)
    }
}

// ---------------------------------------------------------------------------------------
// Profiles
// ---------------------------------------------------------------------------------------

/// A profile `(r, z)` in millimetres, traced from the bottom pole `(0, 0)` outwards, up
/// and (usually) back to a top pole on the axis.
#[derive(Clone, Default)]
struct Profile(Vec<DVec2>);

impl Profile {
    fn start() -> Self {
        Profile(vec![DVec2::ZERO])
    }

    fn to(mut self, r: f64, z: f64) -> Self {
        self.0.push(DVec2::new(r, z));
        self
    }

    /// Elliptic arc around `(cr, cz)` with radii `(ar, az)` from angle `a0` to `a1`
    /// (degrees; 0 points along +r, 90 along +z) in `steps` segments. The start point is
    /// not added (it is the previous point).
    fn arc(mut self, c: (f64, f64), radii: (f64, f64), a: (f64, f64), steps: usize) -> Self {
        for k in 1..=steps {
            let t = (a.0 + (a.1 - a.0) * k as f64 / steps as f64).to_radians();
            self.0
                .push(DVec2::new(c.0 + radii.0 * t.cos(), c.1 + radii.1 * t.sin()));
        }
        self
    }

    /// Circular arc of radius `rad` around `c` from `a0` to `a1` degrees.
    fn circle(self, c: (f64, f64), rad: f64, a: (f64, f64), steps: usize) -> Self {
        self.arc(c, (rad, rad), a, steps)
    }

    /// The Staunton foot of the lathed pieces: a plinth of radius `r` with a vertical
    /// edge `0.12 r` high, a bevelled bead (one chord of a quarter circle of radius
    /// `0.16 r`) and a concave cove (quarter ellipse, two chords) rising into a stem of
    /// radius `stem` at height `h`.
    fn foot(r: f64, stem: f64, h: f64) -> Self {
        let bead = 0.16 * r;
        let z_edge = 0.12 * r;
        let (bead_r, bead_z) = (r - bead, z_edge + bead);
        Profile::start()
            .to(r, 0.0)
            .to(r, z_edge)
            .circle((r - bead, z_edge), bead, (0.0, 90.0), 1)
            .arc((bead_r, h), (bead_r - stem, h - bead_z), (270.0, 180.0), 2)
    }
}

/// Revolves per-column profiles: column `j` sits at angle `angles[j]` (radians,
/// increasing over one turn; an angle repeated at a notch edge, or the last column at
/// `2 pi` against the first at 0, gives coincident vertices that weld) and has profile
/// `profile(j)`; all profiles have the same number of points. The strip from the last
/// column back to the first closes the surface. Returns the vertex indices `rows[i][j]`.
fn revolve_columns(
    b: &mut Builder,
    angles: &[f64],
    profile: impl Fn(usize) -> Vec<DVec2>,
) -> Vec<Vec<u32>> {
    let columns: Vec<Vec<DVec2>> = (0..angles.len()).map(profile).collect();
    let n_rows = columns[0].len();
    assert!(columns.iter().all(|c| c.len() == n_rows));
    let rows: Vec<Vec<u32>> = (0..n_rows)
        .map(|i| {
            angles
                .iter()
                .zip(&columns)
                .map(|(&t, c)| {
                    let p = c[i];
                    // Exact zeros on the axis so that pole vertices weld.
                    let (x, y) = if p.x == 0.0 {
                        (0.0, 0.0)
                    } else {
                        (p.x * t.cos(), p.x * t.sin())
                    };
                    b.vertex(DVec3::new(x, y, p.y))
                })
                .collect()
        })
        .collect();
    let m = angles.len();
    for i in 0..n_rows - 1 {
        for j in 0..m {
            let k = (j + 1) % m;
            b.quad(rows[i][j], rows[i][k], rows[i + 1][k], rows[i + 1][j]);
        }
    }
    rows
}

fn uniform_angles(n: usize) -> Vec<f64> {
    (0..n).map(|j| TAU * j as f64 / n as f64).collect()
}

fn revolve(b: &mut Builder, profile: &Profile) -> Vec<Vec<u32>> {
    revolve_columns(b, &uniform_angles(SEGMENTS), |_| profile.0.clone())
}

// ---------------------------------------------------------------------------------------
// Extrusions welded onto a flat top
// ---------------------------------------------------------------------------------------

/// A bevelled extrusion of a side outline in the `(x, z)` plane, thickness along `y`.
struct Extrusion {
    /// Counter-clockwise in `(x, z)` (x right, z up); `outline[0] -> outline[1]` is the
    /// bottom edge, at the height of the body's top ring, `x0 < 0 < x1`.
    outline: Vec<DVec2>,
    /// Half thickness of the side faces at a point `(x, z)`.
    half_thickness: fn(DVec2) -> f64,
    /// The side faces are inset by this much from the outline ...
    bevel_inset: f64,
    /// ... and the outline rim is this much thinner on each side.
    bevel_depth: f64,
}

fn cross2(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Inset of a counter-clockwise polygon by `d`, except edge 0 which keeps its line.
fn inset(poly: &[DVec2], d: f64) -> Vec<DVec2> {
    let n = poly.len();
    (0..n)
        .map(|k| {
            let prev = (k + n - 1) % n;
            let next = (k + 1) % n;
            let line = |a: usize, b: usize| {
                let dir = (poly[b] - poly[a]).normalize();
                let normal = DVec2::new(-dir.y, dir.x);
                let off = if a == 0 { 0.0 } else { d };
                (poly[a] + off * normal, dir)
            };
            let (p1, u1) = line(prev, k);
            let (p2, u2) = line(k, next);
            let den = cross2(u1, u2);
            assert!(den.abs() > 1e-6, "collinear outline edges at vertex {k}");
            let s = cross2(p2 - p1, u2) / den;
            p1 + s * u1
        })
        .collect()
}

fn polygon_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|k| cross2(poly[k], poly[(k + 1) % n]))
        .sum::<f64>()
        / 2.0
}

fn assert_simple(poly: &[DVec2], what: &str) {
    let n = poly.len();
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            let side = |p: DVec2, q: DVec2, r: DVec2| cross2(q - p, r - p);
            let crosses =
                side(a, b, c) * side(a, b, d) < 0.0 && side(c, d, a) * side(c, d, b) < 0.0;
            assert!(!crosses, "{what}: edges {i} and {j} cross");
        }
    }
    assert!(polygon_area(poly) > 0.0, "{what}: not counter-clockwise");
}

/// Ear clipping of a simple counter-clockwise polygon, always cutting the ear with the
/// largest smallest angle.
fn triangulate(poly: &[DVec2]) -> Vec<[usize; 3]> {
    let mut idx: Vec<usize> = (0..poly.len()).collect();
    let mut out = Vec::new();
    while idx.len() > 3 {
        let n = idx.len();
        let mut best: Option<(f64, usize)> = None;
        for i in 0..n {
            let (a, b, c) = (idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]);
            let (pa, pb, pc) = (poly[a], poly[b], poly[c]);
            if cross2(pb - pa, pc - pa) <= 1e-12 {
                continue;
            }
            let inside = idx.iter().any(|&o| {
                o != a
                    && o != b
                    && o != c
                    && cross2(pb - pa, poly[o] - pa) >= 0.0
                    && cross2(pc - pb, poly[o] - pb) >= 0.0
                    && cross2(pa - pc, poly[o] - pc) >= 0.0
            });
            if inside {
                continue;
            }
            let angle = |p: DVec2, q: DVec2, r: DVec2| (q - p).angle_to(r - p).abs();
            let quality = angle(pa, pb, pc)
                .min(angle(pb, pc, pa))
                .min(angle(pc, pa, pb));
            if best.is_none_or(|(q, _)| quality > q) {
                best = Some((quality, i));
            }
        }
        let i = best.expect("no ear found").1;
        out.push([idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]]);
        idx.remove(i);
    }
    out.push([idx[0], idx[1], idx[2]]);
    out
}

/// Triangulates the flat annulus between `outer` (a ring of the body) and `inner` (the
/// footprint of an extrusion), both counter-clockwise about the z axis, facing +z.
fn zip_cap(b: &mut Builder, outer: &[u32], inner: &[u32]) {
    let ang = |b: &Builder, i: u32| {
        let v = b.vertices[i as usize];
        v.y.atan2(v.x)
    };
    let wrap = |a: f64| a.rem_euclid(TAU);
    let a0 = ang(b, outer[0]);
    let (n, m) = (outer.len(), inner.len());
    let k0 = (0..m)
        .min_by(|&p, &q| wrap(ang(b, inner[p]) - a0).total_cmp(&wrap(ang(b, inner[q]) - a0)))
        .unwrap();
    let outer_angle = |b: &Builder, j: usize| {
        if j == n {
            TAU
        } else {
            wrap(ang(b, outer[j]) - a0)
        }
    };
    let inner_angle = |b: &Builder, k: usize| {
        let first = wrap(ang(b, inner[k0]) - a0);
        if k == m {
            first + TAU
        } else {
            first + wrap(ang(b, inner[(k0 + k) % m]) - ang(b, inner[k0]))
        }
    };
    let (mut j, mut k) = (0, 0);
    let first = b.triangles.len();
    while j < n || k < m {
        let o = |j: usize| outer[j % n];
        let i = |k: usize| inner[(k0 + k) % m];
        if j < n && (k == m || outer_angle(b, j + 1) <= inner_angle(b, k + 1)) {
            b.tri(o(j), o(j + 1), i(k));
            j += 1;
        } else {
            b.tri(o(j), i(k + 1), i(k));
            k += 1;
        }
    }
    for t in &b.triangles[first..] {
        let [p, q, r] = t.map(|i| b.vertices[i as usize]);
        assert!((q - p).cross(r - p).z > 1e-6, "cap triangle faces down");
    }
}

/// Adds the extrusion standing on the flat top ring `ring` (counter-clockwise, all at the
/// height of the outline's bottom edge) and fills the top around its footprint.
fn weld_extrusion(b: &mut Builder, ring: &[u32], e: &Extrusion) {
    let q = &e.outline;
    let n = q.len();
    assert_simple(q, "outline");
    let mut qi = inset(q, e.bevel_inset);
    assert_simple(&qi, "inset outline");
    let z0 = q[0].y;
    assert_eq!(q[1].y, z0);
    qi[0].y = z0;
    qi[1].y = z0;
    let t_face: Vec<f64> = qi.iter().map(|&p| (e.half_thickness)(p)).collect();
    let t_rim: Vec<f64> = q
        .iter()
        .map(|&p| (e.half_thickness)(p) - e.bevel_depth)
        .collect();
    let mut v = |p: DVec2, y: f64| b.vertex(DVec3::new(p.x, y, p.y));
    let op: Vec<u32> = (0..n).map(|k| v(q[k], t_rim[k])).collect();
    let om: Vec<u32> = (0..n).map(|k| v(q[k], -t_rim[k])).collect();
    let ip: Vec<u32> = (0..n).map(|k| v(qi[k], t_face[k])).collect();
    let im: Vec<u32> = (0..n).map(|k| v(qi[k], -t_face[k])).collect();
    for t in triangulate(&qi) {
        b.tri(im[t[0]], im[t[1]], im[t[2]]);
        b.tri(ip[t[0]], ip[t[2]], ip[t[1]]);
    }
    for k in 1..n {
        let l = (k + 1) % n;
        b.quad(om[k], op[k], op[l], om[l]);
        b.quad(op[l], op[k], ip[k], ip[l]);
        b.quad(om[k], om[l], im[l], im[k]);
    }
    // Footprint: the bottom edge's band and bevels are left out; its boundary is this
    // octagon, which the cap shares.
    let mut footprint = vec![op[0], om[0], im[0], im[1], om[1], op[1], ip[1], ip[0]];
    footprint.sort_by(|&p, &q| {
        let a = |i: u32| {
            let w = b.vertices[i as usize];
            w.y.atan2(w.x)
        };
        a(p).total_cmp(&a(q))
    });
    zip_cap(b, ring, &footprint);
}

// ---------------------------------------------------------------------------------------
// The pieces (millimetres)
// ---------------------------------------------------------------------------------------

fn pawn() -> TriMesh {
    // Ball of radius 9.5 on top at 50, meeting a neck of radius 5.
    let (ball_z, ball_r, neck): (f64, f64, f64) = (40.5, 9.5, 5.0);
    let a0 = -(neck / ball_r).acos().to_degrees();
    let profile = Profile::foot(14.5, 6.5, 9.0)
        .to(5.0, 23.5)
        .to(8.8, 25.2)
        .to(8.6, 26.8)
        .to(neck, 29.0)
        .circle((0.0, ball_z), ball_r, (a0, 90.0), 4);
    let mut b = Builder::default();
    revolve(&mut b, &profile);
    b.mesh()
}

fn rook() -> TriMesh {
    let (r_out, r_in, z_top, z_notch, z_floor) = (13.8, 10.0, 55.0, 49.5, 48.5);
    let base = Profile::foot(17.5, 12.0, 11.0)
        .to(10.8, 35.5)
        .to(12.6, 37.0)
        .to(11.4, 38.5)
        .to(r_out, 44.0)
        .to(r_out, z_notch);
    let fixed = base.0.len();
    let profile = base
        .to(r_out, z_top)
        .to(r_in, z_top)
        .to(r_in, z_notch)
        .to(r_in, z_floor)
        .to(0.0, z_floor);
    // Six crenels of 60 degrees: a 40 degree merlon (three columns) and a 20 degree
    // notch whose two edge columns are duplicated and lowered to the notch floor. The
    // last notch column, at 360 degrees, welds onto the first merlon column's angle.
    let mut angles = Vec::new();
    let mut notch = Vec::new();
    for c in 0..6 {
        let t0 = 40.0 + c as f64 * 60.0;
        for (da, is_notch) in [
            (0.0, false),
            (20.0, false),
            (40.0, false),
            (40.0, true),
            (60.0, true),
        ] {
            angles.push((t0 + da).to_radians());
            notch.push(is_notch);
        }
    }
    let mut b = Builder::default();
    revolve_columns(&mut b, &angles, |j| {
        let mut p = profile.0.clone();
        if notch[j] {
            p[fixed].y = z_notch;
            p[fixed + 1].y = z_notch;
        }
        p
    });
    b.mesh()
}

fn bishop() -> TriMesh {
    let profile = Profile::foot(17.0, 7.0, 11.0)
        .to(5.2, 36.0)
        .to(9.6, 37.6)
        .to(9.6, 39.4)
        .to(5.4, 41.2)
        .to(8.6, 46.5)
        .to(9.4, 52.5)
        .to(7.4, 59.0)
        .to(4.0, 63.5)
        .to(1.6, 65.5)
        .to(2.6, 67.4)
        .to(1.8, 69.3)
        .to(0.0, 70.0);
    let mut b = Builder::default();
    revolve(&mut b, &profile);
    b.mesh()
}

fn queen() -> TriMesh {
    let base = Profile::foot(19.0, 8.0, 12.5)
        .to(5.6, 47.0)
        .to(10.6, 49.0)
        .to(10.6, 51.0)
        .to(6.0, 53.0)
        .to(9.8, 66.0)
        .to(11.8, 71.0);
    let coronet = base.0.len();
    let profile = base
        .to(11.8, 73.0)
        .to(9.6, 73.0)
        .to(3.0, 76.0)
        .circle((0.0, 80.0), 5.0, (-53.0, 0.0), 1)
        .circle((0.0, 80.0), 5.0, (0.0, 90.0), 2);
    // Eight points: a peak column and two valley columns, 15 degrees apart.
    let peak = 3.5;
    let mut b = Builder::default();
    revolve_columns(&mut b, &uniform_angles(SEGMENTS), |j| {
        let mut p = profile.0.clone();
        if j % 3 == 0 {
            p[coronet].y += peak;
            p[coronet + 1].y += peak;
        }
        p
    });
    b.mesh()
}

fn king() -> TriMesh {
    let z_plinth = 81.5;
    let profile = Profile::foot(20.0, 8.5, 13.5)
        .to(6.0, 52.0)
        .to(11.2, 54.0)
        .to(11.2, 56.0)
        .to(6.6, 58.0)
        .to(10.4, 70.0)
        .to(12.2, 75.0)
        .to(10.6, 77.4)
        .to(6.4, 80.0)
        .to(5.6, z_plinth);
    let mut b = Builder::default();
    let rows = revolve(&mut b, &profile);
    let cross = [
        (-2.6, z_plinth),
        (2.6, z_plinth),
        (2.6, 86.6),
        (6.6, 85.8),
        (6.6, 90.6),
        (2.6, 89.8),
        (3.2, 95.0),
        (-3.2, 95.0),
        (-2.6, 89.8),
        (-6.6, 90.6),
        (-6.6, 85.8),
        (-2.6, 86.6),
    ];
    let e = Extrusion {
        outline: cross.iter().map(|&(x, z)| DVec2::new(x, z)).collect(),
        half_thickness: |_| 2.4,
        bevel_inset: 0.6,
        bevel_depth: 0.6,
    };
    weld_extrusion(&mut b, rows.last().unwrap(), &e);
    b.mesh()
}

fn knight() -> TriMesh {
    let z_top = 12.5;
    let profile = Profile::start()
        .to(17.5, 0.0)
        .to(17.5, 2.2)
        .circle((14.7, 2.2), 2.8, (0.0, 90.0), 2)
        .to(13.2, 6.6)
        .to(14.4, 8.6)
        .to(14.4, 10.6)
        .to(13.4, z_top);
    let mut b = Builder::default();
    let rows = revolve(&mut b, &profile);
    // Horse head facing +x, counter-clockwise from the back of the neck at the base.
    let head = [
        (-10.0, z_top),
        (9.0, z_top),
        (10.6, 16.0),
        (11.0, 21.0),
        (9.6, 27.0),
        (8.2, 31.0),
        (10.2, 34.5),
        (14.5, 37.0),
        (18.6, 39.0),
        (21.0, 41.2),
        (18.4, 42.8),
        (21.3, 44.2),
        (21.6, 46.6),
        (20.0, 48.6),
        (15.5, 51.0),
        (10.5, 54.5),
        (7.0, 57.5),
        (5.5, 62.0),
        (2.0, 57.6),
        (-1.0, 56.8),
        (-4.0, 55.5),
        (-7.6, 53.6),
        (-7.0, 51.0),
        (-10.2, 48.6),
        (-9.8, 45.6),
        (-12.6, 42.0),
        (-12.3, 38.5),
        (-14.0, 34.0),
        (-13.8, 30.0),
        (-14.0, 24.0),
        (-12.6, 17.0),
    ];
    let e = Extrusion {
        outline: head.iter().map(|&(x, z)| DVec2::new(x, z)).collect(),
        half_thickness: |p| {
            let up = ((p.y - 12.5) / 49.5).clamp(0.0, 1.0);
            6.3 - 1.3 * up - 0.12 * (p.x - 8.0).max(0.0) - 1.5 * ((p.y - 55.0) / 7.0).max(0.0)
        },
        bevel_inset: 0.9,
        bevel_depth: 1.0,
    };
    weld_extrusion(&mut b, rows.last().unwrap(), &e);
    b.mesh()
}

// ---------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------

/// Segment `p -> q` crosses triangle `t` away from its ends and the triangle's edges.
fn segment_hits_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let d = q - p;
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let h = d.cross(e2);
    let a = e1.dot(h);
    let scale = e1.length() * e2.length() * d.length();
    if a.abs() <= 1e-9 * scale {
        return false; // parallel or coplanar
    }
    let s = p - t[0];
    let u = s.dot(h) / a;
    let qv = s.cross(e1);
    let v = d.dot(qv) / a;
    let w = e2.dot(qv) / a;
    let eps = 1e-9;
    u > eps && v > eps && u + v < 1.0 - eps && w > eps && w < 1.0 - eps
}

/// Panics unless the mesh is closed, oriented, outward, free of degenerate triangles and
/// of pairs of triangles that cross each other.
fn check(name: &str, m: &TriMesh) {
    assert!(
        m.is_closed_and_oriented(),
        "{name}: not closed and oriented"
    );
    assert!(m.signed_volume() > 0.0, "{name}: inward");
    let corners = |t: &[u32; 3]| t.map(|i| m.vertices[i as usize]);
    for t in &m.triangles {
        let [a, b, c] = corners(t);
        let area2 = (b - a).cross(c - a).length();
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        assert!(
            area2 > 1e-3 * longest * longest,
            "{name}: degenerate triangle {t:?}"
        );
    }
    for (i, s) in m.triangles.iter().enumerate() {
        for t in &m.triangles[i + 1..] {
            let shared = s.iter().filter(|v| t.contains(v)).count();
            if shared >= 2 {
                continue;
            }
            let (ps, pt) = (corners(s), corners(t));
            let edges = |a: &[u32; 3], other: &[u32; 3]| -> Vec<(usize, usize)> {
                (0..3)
                    .map(|k| (k, (k + 1) % 3))
                    .filter(|&(k, l)| {
                        shared == 0 || !(other.contains(&a[k]) || other.contains(&a[l]))
                    })
                    .collect()
            };
            let hit = edges(s, t)
                .iter()
                .any(|&(k, l)| segment_hits_triangle(ps[k], ps[l], pt))
                || edges(t, s)
                    .iter()
                    .any(|&(k, l)| segment_hits_triangle(pt[k], pt[l], ps));
            assert!(!hit, "{name}: triangles {s:?} and {t:?} intersect");
        }
    }
}

fn write_obj(path: &Path, name: &str, m: &TriMesh) -> std::io::Result<()> {
    let mut s = String::new();
    writeln!(
        s,
        "# Staunton chess {name}, metres, Z up, base centred on the origin at z = 0."
    )
    .unwrap();
    writeln!(s, "# Generated by examples/chess_pieces.rs; do not edit.").unwrap();
    writeln!(s, "o {name}").unwrap();
    for v in &m.vertices {
        let w = *v * MM;
        writeln!(s, "v {:.7} {:.7} {:.7}", w.x + 0.0, w.y + 0.0, w.z + 0.0).unwrap();
    }
    for t in &m.triangles {
        writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    std::fs::write(path, s)
}

// ---------------------------------------------------------------------------------------
// Preview: orthographic z-buffer
// ---------------------------------------------------------------------------------------

/// Renders `m` (metres) after turning it by `azimuth` about z and tilting it by
/// `elevation` towards the viewer, who looks along +y. Ground at `ground` pixels from
/// the top, centred at column `cx`. Flat-shaded, or black if `silhouette`.
#[allow(clippy::too_many_arguments)]
fn render(
    img: &mut image::RgbImage,
    m: &TriMesh,
    azimuth: f64,
    elevation: f64,
    px_per_m: f64,
    cx: f64,
    ground: f64,
    silhouette: bool,
) {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let (sa, ca) = azimuth.to_radians().sin_cos();
    let (se, ce) = elevation.to_radians().sin_cos();
    let view = |p: DVec3| {
        let x = ca * p.x - sa * p.y;
        let y = sa * p.x + ca * p.y;
        DVec3::new(x, y * ce - p.z * se, y * se + p.z * ce)
    };
    let light = DVec3::new(-0.45, -0.75, 0.5).normalize();
    let mut depth = vec![f64::INFINITY; w * h];
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| view(m.vertices[i as usize]));
        let normal = (b - a).cross(c - a).normalize();
        if normal.y > 0.0 && !silhouette {
            continue; // back face
        }
        let shade = 0.25 + 0.75 * normal.dot(light).max(0.0);
        let colour = if silhouette {
            [0, 0, 0]
        } else {
            [
                (235.0 * shade) as u8,
                (205.0 * shade) as u8,
                (160.0 * shade) as u8,
            ]
        };
        let s = |p: DVec3| DVec2::new(cx + p.x * px_per_m, ground - p.z * px_per_m);
        let (pa, pb, pc) = (s(a), s(b), s(c));
        let area = cross2(pb - pa, pc - pa);
        if area.abs() < 1e-12 {
            continue;
        }
        let lo = pa.min(pb).min(pc).floor().max(DVec2::ZERO);
        let hi = pa
            .max(pb)
            .max(pc)
            .ceil()
            .min(DVec2::new(w as f64 - 1.0, h as f64 - 1.0));
        for py in lo.y as usize..=hi.y as usize {
            for px in lo.x as usize..=hi.x as usize {
                let p = DVec2::new(px as f64 + 0.5, py as f64 + 0.5);
                let wa = cross2(pb - p, pc - p) / area;
                let wb = cross2(pc - p, pa - p) / area;
                let wc = 1.0 - wa - wb;
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    continue;
                }
                let z = wa * a.y + wb * b.y + wc * c.y;
                let k = py * w + px;
                if z < depth[k] {
                    depth[k] = z;
                    img.put_pixel(px as u32, py as u32, image::Rgb(colour));
                }
            }
        }
    }
}

fn preview(dir: &Path, pieces: &[(&str, TriMesh)]) -> Result<(), Box<dyn Error>> {
    std::fs::create_dir_all(dir)?;
    let white = image::Rgb([255u8, 255, 255]);
    // One picture per piece, 8 px/mm.
    for (name, m) in pieces {
        let scale = 8000.0;
        for (suffix, az, el, sil) in [("side", 0.0, 0.0, true), ("34", -35.0, 20.0, false)] {
            let mut img = image::RgbImage::from_pixel(480, 820, white);
            render(&mut img, m, az, el, scale, 240.0, 780.0, sil);
            img.save(dir.join(format!("{name}-{suffix}.png")))?;
        }
    }
    // Combined: 3/4 views above, side silhouettes below, 4 px/mm.
    let (cell, row) = (220u32, 430u32);
    let scale = 4000.0;
    let mut img = image::RgbImage::from_pixel(cell * pieces.len() as u32, 2 * row, white);
    for (k, (_, m)) in pieces.iter().enumerate() {
        let cx = (k as f64 + 0.5) * cell as f64;
        render(
            &mut img,
            m,
            -35.0,
            20.0,
            scale,
            cx,
            row as f64 - 25.0,
            false,
        );
        render(
            &mut img,
            m,
            0.0,
            0.0,
            scale,
            cx,
            2.0 * row as f64 - 25.0,
            true,
        );
    }
    let out = dir.join("chess-pieces.png");
    img.save(&out)?;
    println!("wrote previews to {}", dir.display());
    Ok(())
}

// ---------------------------------------------------------------------------------------

fn main() -> Result<(), Box<dyn Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = root.join("scenes/thinker/pieces");
    let mut preview_dir: Option<PathBuf> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a directory")?),
            "--preview" => {
                preview_dir = Some(PathBuf::from(
                    args.next().ok_or("--preview needs a directory")?,
                ))
            }
            _ => return Err(format!("unknown argument {a}; use --out DIR, --preview DIR").into()),
        }
    }
    std::fs::create_dir_all(&out)?;
    type Build = fn() -> TriMesh;
    let builders: [(&str, Build); 6] = [
        ("pawn", pawn),
        ("rook", rook),
        ("knight", knight),
        ("bishop", bishop),
        ("queen", queen),
        ("king", king),
    ];
    println!(
        "{:<7} {:>5} {:>5} {:>9} {:>9} {:>10} {:>10} {:>9} {:>8}",
        "piece",
        "verts",
        "tris",
        "height/mm",
        "base/mm",
        "volume/cm3",
        "area/cm2",
        "boxwood/g",
        "com z/mm"
    );
    let mut loaded = Vec::new();
    for (name, build) in builders {
        let mesh = build();
        check(name, &mesh);
        let path = out.join(format!("{name}.obj"));
        write_obj(&path, name, &mesh)?;
        let m = load_obj(&path, 1.0)?;
        assert!(
            m.is_closed_and_oriented(),
            "{name}: reloaded mesh not closed"
        );
        assert_eq!(
            m.triangles.len(),
            mesh.triangles.len(),
            "{name}: welding changed the mesh"
        );
        assert_eq!(
            m.vertices.len(),
            mesh.vertices.len(),
            "{name}: welding changed the mesh"
        );
        let volume = m.signed_volume();
        assert!(volume > 0.0, "{name}: non-positive volume");
        check(name, &m);
        let (lo, hi) = m.bounding_box();
        assert!(lo.z.abs() < 1e-9, "{name}: base not on z = 0");
        let base = m
            .vertices
            .iter()
            .filter(|v| v.z.abs() < 1e-9)
            .map(|v| 2.0 * v.x.hypot(v.y))
            .fold(0.0, f64::max);
        let props = Shape::Mesh(std::sync::Arc::new(m.clone())).mass_properties(BOXWOOD);
        println!(
            "{:<7} {:>5} {:>5} {:>9.1} {:>9.1} {:>10.2} {:>10.2} {:>9.1} {:>8.1}",
            name,
            m.vertices.len(),
            m.triangles.len(),
            hi.z / MM,
            base / MM,
            volume * 1e6,
            m.surface_area() * 1e4,
            props.mass * 1e3,
            props.local_com.z / MM
        );
        loaded.push((name, m));
    }
    println!("wrote {}", out.display());
    if let Some(dir) = preview_dir {
        preview(&dir, &loaded)?;
    }
    Ok(())
}
