//! The silhouette path for closed meshes: [`MeshSilhouette`] (face planes and edge-face
//! adjacency, built once per mesh) and [`ShadowCamera::rasterize_mesh`], which fills the
//! silhouette edges with the non-zero winding rule.

use super::camera::ShadowCamera;
use super::rows::{RasterScratch, SilEdge};
use crate::shadow::mask::Mask;
use glam::{DQuat, DVec2, DVec3};

/// What the silhouette path precomputes for a closed, consistently oriented mesh: one
/// plane per triangle and, for every edge, its two faces.
///
/// Why it is exact: seen from a light outside the solid, every segment from the light
/// that meets the solid enters it through a front face, and the front faces project
/// with one orientation. Their projections' winding numbers add up to the number of
/// front faces over a point, so the shadow is where that sum is non-zero; and the sum's
/// boundary is made of the silhouette edges only (an edge between two front faces is
/// crossed once in each direction and cancels). Filling the silhouette polygons with
/// the non-zero rule therefore gives the union of the front faces' projections, which is
/// the exact shadow, from a few dozen edges instead of hundreds of triangles.
#[derive(Clone, Debug)]
pub struct MeshSilhouette {
    /// Per triangle: unnormalised outward normal and its offset (`n . x = d` on the plane).
    planes: Vec<(DVec3, f64)>,
    /// Per edge: vertices `(a, b)`, the face where it runs `a -> b`, and the other face.
    edges: Vec<[u32; 4]>,
    /// Radius of a sphere about the body origin holding every vertex.
    radius: f64,
}

impl MeshSilhouette {
    /// The silhouette data of a mesh, or `None` unless every directed edge occurs exactly
    /// once and its reverse exactly once (closed, consistently oriented, manifold).
    pub fn new(vertices: &[DVec3], triangles: &[[u32; 3]]) -> Option<MeshSilhouette> {
        use std::collections::HashMap;
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a == b || directed.insert((a, b), f as u32).is_some() {
                    return None;
                }
            }
        }
        let mut edges = Vec::with_capacity(directed.len() / 2);
        for (&(a, b), &f) in &directed {
            let g = *directed.get(&(b, a))?;
            if a < b {
                edges.push([a, b, f, g]);
            }
        }
        // A fixed order keeps the crossings (and so the result) independent of hashing.
        edges.sort_unstable();
        let planes = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                let n = (b - a).cross(c - a);
                (n, n.dot(a))
            })
            .collect();
        let radius = vertices.iter().map(|v| v.length()).fold(0.0, f64::max);
        Some(MeshSilhouette {
            planes,
            edges,
            radius,
        })
    }
}

/// A closed mesh in its body frame with its silhouette data, as
/// [`ShadowCamera::rasterize_mesh`] takes it.
#[derive(Clone, Copy, Debug)]
pub struct ClosedMesh<'a> {
    /// Vertices (body frame).
    pub vertices: &'a [DVec3],
    /// Triangles, closed and wound outward (counter-clockwise seen from outside).
    pub triangles: &'a [[u32; 3]],
    /// [`MeshSilhouette::new`] of the same vertices and triangles.
    pub silhouette: &'a MeshSilhouette,
}

impl ShadowCamera {
    /// OR the exact shadow of a closed mesh at pose `(p, q)` (body -> world: `x -> p + q x`)
    /// into `mask`, from its silhouette edges (see [`MeshSilhouette`]). Falls back to
    /// [`ShadowCamera::rasterize_triangles`] when the mesh is not entirely inside the slab
    /// or the light is near it; `world_vertices` is the caller's buffer for that.
    pub fn rasterize_mesh(
        &self,
        p: DVec3,
        q: DQuat,
        mesh: ClosedMesh<'_>,
        world_vertices: &mut Vec<DVec3>,
        mask: &mut Mask,
        scratch: &mut RasterScratch,
    ) {
        let ClosedMesh {
            vertices,
            triangles,
            silhouette: sil,
        } = mesh;
        self.check_mask(mask);
        if self.width_px == 0 || self.height_px == 0 {
            return;
        }
        let depth = self.h - (p - self.center).dot(self.n);
        let margin = sil.radius * (1.0 + 1e-9) + 1e-9;
        let light_local = q.conjugate() * (self.light - p);
        if !(depth - margin > self.near && depth + margin < self.h)
            || light_local.length() <= margin
        {
            world_vertices.clear();
            world_vertices.extend(vertices.iter().map(|v| p + q * *v));
            self.rasterize_triangles(world_vertices, triangles, true, mask, scratch);
            return;
        }
        let Some((row_min, row_max)) = self.silhouette_edges(p, q, mesh, light_local, scratch)
        else {
            return;
        };
        self.fill_silhouette(row_min as usize, row_max as usize, mask, scratch);
    }

    /// Gather the silhouette edges of `mesh` at pose `(p, q)`, seen from `light_local` (the
    /// light in the body frame), into `scratch.sil_edges`: each projected to pixels,
    /// oriented as its front face runs it, with the rows whose centre it crosses. Returns
    /// the first and last of those rows over all edges, or `None` when no edge crosses a
    /// row centre (nothing to fill).
    #[inline]
    fn silhouette_edges(
        &self,
        p: DVec3,
        q: DQuat,
        mesh: ClosedMesh<'_>,
        light_local: DVec3,
        scratch: &mut RasterScratch,
    ) -> Option<(u32, u32)> {
        let ClosedMesh {
            vertices,
            silhouette: sil,
            ..
        } = mesh;
        let nv = vertices.len();
        scratch.facing.clear();
        scratch
            .facing
            .extend(sil.planes.iter().map(|(n, d)| n.dot(light_local) > *d));
        if scratch.stamp.len() < nv {
            scratch.stamp.resize(nv, 0);
            scratch.sil_pix.resize(nv, DVec2::ZERO);
        }
        scratch.current = scratch.current.wrapping_add(1);
        if scratch.current == 0 {
            scratch.stamp.iter_mut().for_each(|s| *s = 0);
            scratch.current = 1;
        }
        let stamp = scratch.current;
        scratch.sil_edges.clear();
        let hp = self.height_px as f64;
        let (mut row_min, mut row_max) = (u32::MAX, 0u32);
        for &[a, b, f, g] in &sil.edges {
            let (ff, fg) = (scratch.facing[f as usize], scratch.facing[g as usize]);
            if ff == fg {
                continue;
            }
            // Oriented as its front face runs it.
            let (a, b) = if ff { (a, b) } else { (b, a) };
            for v in [a, b] {
                let v = v as usize;
                if scratch.stamp[v] != stamp {
                    scratch.stamp[v] = stamp;
                    let hv = self.homogeneous(p + q * vertices[v]);
                    scratch.sil_pix[v] = DVec2::new(hv.x, hv.y) / hv.z;
                }
            }
            let (pa, pb) = (scratch.sil_pix[a as usize], scratch.sil_pix[b as usize]);
            let (top, bot, dir) = if pa.y < pb.y {
                (pa, pb, 1)
            } else if pb.y < pa.y {
                (pb, pa, -1)
            } else {
                continue; // horizontal (or NaN): no row centre crosses it
            };
            // Rows whose centre line y = j + 0.5 lies in [top.y, bot.y).
            let j0 = (top.y - 0.5).ceil().max(0.0);
            let j1 = ((bot.y - 0.5).ceil() - 1.0).min(hp - 1.0);
            // NaN ends (a degenerate projection) fail this too.
            if j0
                .partial_cmp(&j1)
                .is_none_or(|o| o == std::cmp::Ordering::Greater)
            {
                continue;
            }
            let (j0, j1) = (j0 as u32, j1 as u32);
            row_min = row_min.min(j0);
            row_max = row_max.max(j1);
            scratch.sil_edges.push(SilEdge {
                top,
                slope: (bot.x - top.x) / (bot.y - top.y),
                j0,
                j1,
                dir,
            });
        }
        if scratch.sil_edges.is_empty() {
            return None;
        }
        Some((row_min, row_max))
    }

    /// OR into `mask` rows `r0..=r1` of the polygons bounded by `scratch.sil_edges`, with
    /// the non-zero winding rule: their crossings of each row centre are sorted by row
    /// (counting sort into `scratch.crossings`) then by x, and every span where the
    /// winding number is non-zero is filled.
    #[inline]
    fn fill_silhouette(&self, r0: usize, r1: usize, mask: &mut Mask, scratch: &mut RasterScratch) {
        let rows = r1 - r0 + 1;
        let RasterScratch {
            sil_edges,
            row_ends: ends,
            crossings,
            ..
        } = scratch;
        // Counting sort of the crossings by row. An edge adds one crossing to each of its
        // rows: +1 at its first row and -1 past its last (wrapping, the sums come out
        // right), summed once for the rows' counts and again for their first slots.
        ends.clear();
        ends.resize(rows + 2, 0);
        for e in sil_edges.iter() {
            let first = &mut ends[e.j0 as usize - r0 + 1];
            *first = first.wrapping_add(1);
            let past = &mut ends[e.j1 as usize - r0 + 2];
            *past = past.wrapping_sub(1);
        }
        for _ in 0..2 {
            for k in 1..=rows {
                ends[k] = ends[k].wrapping_add(ends[k - 1]);
            }
        }
        crossings.clear();
        crossings.resize(ends[rows] as usize, (0.0, 0));
        // `ends[k]`, the first slot of row k, is its fill cursor: after the fill it is
        // the end of row k.
        for e in sil_edges.iter() {
            for j in e.j0..=e.j1 {
                let slot = &mut ends[j as usize - r0];
                let x = e.top.x + (j as f64 + 0.5 - e.top.y) * e.slope;
                crossings[*slot as usize] = (x, e.dir);
                *slot += 1;
            }
        }
        let last = (self.width_px - 1) as f64;
        let span = |mask: &mut Mask, y: usize, enter: f64, exit: f64| {
            let (lo, hi) = (
                (enter - 0.5).ceil().max(0.0),
                (exit - 0.5).floor().min(last),
            );
            if lo <= hi {
                mask.fill_span(y, lo as usize, hi as usize);
            }
        };
        let mut a = 0;
        for (k, &end) in ends[..rows].iter().enumerate() {
            let row = &mut crossings[a..end as usize];
            a = end as usize;
            // Most rows cross one outline, in and out: the span between.
            if let [(x0, d0), (x1, d1)] = *row {
                if d0 + d1 == 0 {
                    let (enter, exit) = if x1 < x0 { (x1, x0) } else { (x0, x1) };
                    span(mask, r0 + k, enter, exit);
                    continue;
                }
            }
            // Rows hold a handful of crossings: insertion sort by x.
            for i in 1..row.len() {
                let mut j = i;
                while j > 0 && row[j - 1].0 > row[j].0 {
                    row.swap(j - 1, j);
                    j -= 1;
                }
            }
            let mut winding = 0;
            let mut enter = 0.0;
            for &(x, dir) in row.iter() {
                let before = winding;
                winding += dir;
                if before == 0 && winding != 0 {
                    enter = x;
                } else if before != 0 && winding == 0 {
                    span(mask, r0 + k, enter, x);
                }
            }
        }
    }
}
