//! Ballistic shadow art: find launch velocities for a set of objects so that, at one
//! instant of their flight, the shadows they cast from a point light onto a plane form
//! a target picture.
//!
//! Pipeline (see `docs/ARCHITECTURE.md`): [`scene`] (validated input) -> [`body`]
//! (exact free flight) and [`contact`] (first contact) -> [`raster`] (exact shadow into
//! a [`mask::Mask`]) -> [`energy`] (the paper's ten terms) -> [`evaluate`] (one sample)
//! -> [`solver`] with [`cmaes`] (stages of CMA-ES) -> [`export`] (files).

pub mod body;
pub mod budget;
pub mod cli;
pub mod cmaes;
pub mod contact;
pub mod continuation;
pub mod distance;
pub mod drag;
pub mod energy;
pub mod evaluate;
pub mod export;
pub mod flight;
pub mod gjk;
pub mod gltf_export;
pub mod linalg;
pub mod mask;
pub mod picture;
pub mod raster;
pub mod scene;
pub mod solution;
pub mod solver;
pub mod trajectory;
