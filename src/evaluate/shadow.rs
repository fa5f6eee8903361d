//! Step 4 of a sample's evaluation, the shadow: every occluder rasterized at its pose
//! into the canvas mask (all of them, some, or some over a held shadow), and whether
//! each shadow lies inside the picture.

use std::ops::Range;

use glam::{DQuat, DVec3};

use super::{among, Held, HeldMask, Problem, Workspace};
use crate::geometry::shape::Shape;
use crate::shadow::mask::Mask;
use crate::shadow::raster::{ClosedMesh, RasterScratch};

impl Problem {
    /// Step 4: the shadow of every occluder at its pose in `ws.poses`, into `ws.mask`.
    pub fn shadow(&self, ws: &mut Workspace) {
        self.shadow_with(None, None, ws);
    }

    /// The shadow of the occluders in `which` only (`which[i]`), at the poses in
    /// `ws.poses`, into `ws.mask`.
    pub fn shadow_only(&self, which: &[bool], ws: &mut Workspace) {
        self.shadow_with(None, Some(which), ws);
    }

    /// The shadow of the occluders `held` holds and of those in `which` (`which[i]`, at
    /// the poses in `ws.poses`), into `ws.mask`.
    pub fn shadow_held_and(&self, held: &Held, which: &[bool], ws: &mut Workspace) {
        self.shadow_with(Some(&held.mask), Some(which), ws);
    }

    /// [`Problem::shadow`] of the occluders in `which` only, drawn over `start` (a held
    /// shadow; OR is order-free, so the mask is the same as drawing everything; where the
    /// mask was last drawn over the same one, only the rows drawn then are put back).
    /// Returns the rows drawn in over `start` (outside them the mask is `start`), if
    /// given one.
    pub(super) fn shadow_with(
        &self,
        start: Option<&HeldMask>,
        which: Option<&[bool]>,
        ws: &mut Workspace,
    ) -> Option<Range<usize>> {
        match (start, ws.over.take()) {
            (Some(h), Some((key, rows))) if key == h.key => {
                ws.mask.restore_rows(h, rows);
                debug_assert!(ws.mask == **h && ws.mask.row_range() == h.row_range());
            }
            (Some(h), _) => ws.mask.copy_from(h),
            (None, _) => ws.mask.clear(),
        }
        let Workspace {
            mask,
            poses,
            raster,
            world_vertices,
            ..
        } = ws;
        let drawn = mask.drawn_rows(|mask| {
            // One pose per occluder.
            for (i, &pose) in poses.iter().enumerate() {
                if among(which, i) {
                    self.draw(i, pose, mask, raster, world_vertices);
                }
            }
        });
        ws.over = start.map(|h| (h.key, drawn.clone()));
        start.map(|_| drawn)
    }

    /// OR occluder `i`'s shadow at pose `(p, q)` into `mask`.
    fn draw(
        &self,
        i: usize,
        (p, q): (DVec3, DQuat),
        mask: &mut Mask,
        raster: &mut RasterScratch,
        world_vertices: &mut Vec<DVec3>,
    ) {
        let cam = &self.canvas;
        match (&self.scene.occluders[i].shape, &self.silhouettes[i]) {
            (Shape::Sphere { radius }, _) => cam.rasterize_sphere(p, *radius, mask),
            (Shape::Cuboid { half_extents }, _) => {
                cam.rasterize_box(p, q, *half_extents, mask, raster)
            }
            (Shape::Mesh(mesh), Some(silhouette)) => cam.rasterize_mesh(
                p,
                q,
                ClosedMesh {
                    vertices: &mesh.vertices,
                    triangles: &mesh.triangles,
                    silhouette,
                },
                world_vertices,
                mask,
                raster,
            ),
            (Shape::Mesh(mesh), None) => {
                world_vertices.clear();
                world_vertices.extend(mesh.vertices.iter().map(|v| p + q * *v));
                cam.rasterize_triangles(
                    world_vertices,
                    &mesh.triangles,
                    self.closed[i],
                    mask,
                    raster,
                );
            }
        }
    }

    /// Whether each occluder's shadow at `t` (poses from the last sample in `ws`) lies
    /// entirely inside the image. For boxes and meshes, every vertex must project inside
    /// (the shadow is within the hull of the projected vertices); for spheres, 4,096 points
    /// spread over the surface (Fibonacci lattice) must, with half a pixel to spare for
    /// the gaps between them. Geometry at or behind the light plane counts as outside.
    pub fn shadows_in_image(&self, ws: &Workspace) -> Vec<bool> {
        let cam = &self.scene.camera;
        let (w, h) = (cam.width_px as f64, cam.height_px as f64);
        let inside = |p: DVec3, margin: f64| {
            cam.project(p).is_some_and(|px| {
                px.x >= margin && px.y >= margin && px.x <= w - margin && px.y <= h - margin
            })
        };
        self.scene
            .occluders
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let (p, q) = ws.poses[i];
                match &o.shape {
                    Shape::Sphere { radius } => {
                        const N: usize = 4096;
                        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
                        (0..N).all(|k| {
                            let z = 1.0 - 2.0 * (k as f64 + 0.5) / N as f64;
                            let r = (1.0 - z * z).sqrt();
                            let a = golden * k as f64;
                            inside(p + *radius * DVec3::new(r * a.cos(), r * a.sin(), z), 0.5)
                        })
                    }
                    Shape::Cuboid { half_extents } => {
                        crate::geometry::shape::box_corners(*half_extents)
                            .iter()
                            .all(|c| inside(p + q * *c, 0.0))
                    }
                    Shape::Mesh(m) => m.vertices.iter().all(|v| inside(p + q * *v, 0.0)),
                }
            })
            .collect()
    }
}
