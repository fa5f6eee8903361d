//! What a solve leaves behind: [`solution`] (the schema of `solution.json` and
//! `convergence.csv`, and the check that a solution belongs to a scene), [`files`]
//! (atomic writes and reads of the output folder), [`trajectory`] (the whole motion and
//! the launch and trajectory tables), [`gltf`] (the animated glTF 2.0 file) and
//! [`picture`] (overlays and plots for people), [`report`] (`report.html`) and [`blend`]
//! (the plan of the .blend ready to render: frames, cameras, slow motion).

pub mod blend;
pub mod cycles;
pub mod files;
pub mod gltf;
pub mod launches;
pub mod picture;
pub mod report;
pub mod solution;
pub mod trajectory;
