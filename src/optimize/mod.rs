//! The search: [`cmaes`] (a hand-written CMA-ES with ask/tell) and [`solver`] (stages
//! of CMA-ES over the launch values, in parallel, with progress, interrupts and resume).

pub mod cmaes;
pub mod solver;
