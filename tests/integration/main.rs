//! The integration tests, one binary (as in ripgrep's `tests/`), a module per boundary:
//!
//! - `cli`: the `bsa` command line end to end and its errors for bad solutions and exports;
//! - `docs`: `docs/cli.md` generated from the clap definitions, the shell completions,
//!   the man page;
//! - `ledger`: the tables of `docs/results.md` made from the results ledger `results/`;
//! - `prose`: README.md and docs/*.md name no round or session, and no sentence runs
//!   past 60 words;
//! - `scene_errors`: bad scenes get clear errors that name the file and the field;
//! - `solver`: determinism, resume, interrupts, strategies, the golden shadow, Mickey;
//! - `exports`: the glTF poses and tables, the Khronos validator, the error budget;
//! - `blender`: the Cycles mask, the Blender import, the glb rendered as imported;
//! - `blend`: `bsa blend` and `bsa video` (t on a whole frame at any fps, the view
//!   camera, EEVEE, slow motion, the contact sheet);
//! - `robust`: the audit of issue #13 (bad magnitudes, meshes, interrupted and failing
//!   solves, the lock);
//! - `fuzz`: scene mutations generated from the schema, run through `check` and a short
//!   solve under a timeout.
//! - `report`: `report.html` rendered by headless Chromium.
//! - `instants`: several shadows per sample (issue #16): hold windows, sequences, air in
//!   the loop, robust launches, free positions, and their bad inputs.
//!
//! The tests that need an outside tool (Node's Khronos glTF validator, Blender's bpy, Chromium) are
//! `#[ignore]`d with the reason, so `cargo test` lists them as ignored; when run
//! (`cargo test -- --include-ignored`, as `scripts/test.sh` does after installing both)
//! they run for real and a missing tool fails them.

mod blend;
mod blender;
mod cli;
mod docs;
mod exports;
mod fuzz;
mod instants;
mod ledger;
mod prose;
mod render;
mod report;
mod robust;
mod scene_errors;
mod solver;
mod util;
