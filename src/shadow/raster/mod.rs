//! Exact shadow rasterization of spheres, boxes and triangle meshes under a point light.
//!
//! [`ShadowCamera`] describes the receiver plane, the image rectangle on it and the point
//! light; [`ShadowCamera::new`] precomputes everything the hot loops need. The
//! `rasterize_*` methods OR an object's shadow into a [`Mask`](crate::shadow::mask::Mask)
//! (they never clear it), and [`RasterScratch`] carries the reusable buffers of the mesh
//! path so that nothing is allocated per call once it has warmed up. Typical use per candidate: `mask.clear()`,
//! then one `rasterize_*` call per object, then the energies read the mask.
//!
//! Pixel convention: pixel coordinates `px` in `[0, width_px]` run from the left edge,
//! `py` in `[0, height_px]` from the top edge. Pixel `(i, j)` is shadow iff its centre
//! `(i + 0.5, j + 0.5)` is in shadow. The point `X` on the receiver plane is in shadow iff
//! the open segment from the light to `X` meets the object's closed solid. Every such
//! segment lies strictly between the receiver plane and the plane through the light
//! parallel to it (the "slab"), so only the part of an object inside the slab casts a
//! shadow: geometry under the receiver or behind the light casts nothing, and a body
//! straddling either plane casts exactly the central projection of its part in the slab.
//!
//! Spheres are solved in closed form per pixel row (no tessellation). Triangles are
//! clipped with Sutherland–Hodgman in homogeneous image coordinates (the slab planes and
//! the four planes through the light and the image edges), then scan-converted per row.
//!
//! Files: `camera.rs` (the camera, projection and clipping), `sphere.rs` (the sphere's
//! conics), `rows.rs` (row spans and the scratch buffers they all share), `scan.rs` (scan
//! conversion, boxes and triangle meshes), `silhouette.rs` (the
//! silhouette path for closed meshes).

mod camera;
mod rows;
mod scan;
mod silhouette;
mod sphere;

pub use camera::{ImageRect, ShadowCamera};
pub use rows::RasterScratch;
pub use silhouette::{ClosedMesh, MeshSilhouette};

#[cfg(test)]
mod tests;
