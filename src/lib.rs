//! Ballistic shadow art: find launch velocities for a set of objects so that, at one
//! instant of their flight, the shadows they cast from a point light onto a plane form
//! a target picture.
//!
//! Pipeline (see `docs/ARCHITECTURE.md`), one folder per stage, each importing only
//! from the ones before it: [`scene`] (validated input, on [`geometry`]'s shapes) ->
//! [`sim`] (exact free flight, first contacts, rapier after `t`, air drag) ->
//! [`shadow`] (exact shadow into a [`shadow::mask::Mask`]) -> [`energy`] (the paper's
//! ten terms) -> [`evaluate`] (one sample) -> [`optimize`] (stages of CMA-ES) ->
//! [`output`] (the result schema and files) and [`budget`] (the error budget); [`cli`]
//! is the glue of the `bsa` binary.
//!
//! The modules' docs are written for the developers and name private items (a stage's
//! constants, its helpers); `cargo doc --document-private-items` renders those links.

#![allow(rustdoc::private_intra_doc_links)]

pub mod budget;
pub mod cli;
pub mod design;
pub mod energy;
pub mod evaluate;
pub mod geometry;
pub mod linalg;
pub mod optimize;
pub mod output;
pub mod scene;
pub mod shadow;
pub mod sim;
