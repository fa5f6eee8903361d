//! The search: [`cmaes`] (a hand-written CMA-ES with ask/tell), [`moves`] (global
//! assignment moves: swap two bodies, fill a bare part of the target) and [`solver`]
//! (stages of CMA-ES over the launch values, in parallel, with restarts, progress,
//! interrupts and resume).

pub mod cmaes;
pub mod moves;
pub mod solver;
