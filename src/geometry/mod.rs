//! Shapes and the geometry on them: [`shape`] (spheres, boxes, triangle meshes, OBJ
//! loading, exact mass properties, the table box), [`gjk`] (f64 GJK on convex hulls)
//! and [`distance`] (signed distances between posed shapes, built on both).

pub mod distance;
pub mod gjk;
pub mod shape;
