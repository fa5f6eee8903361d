//! What a solve will cost, known before it starts: [`estimate`] bounds its samples
//! from the schedule and the stages, times a few samples of each stage, and counts
//! the memory its threads and its record take ([`Cost`]). `bsa check` and the start
//! of `bsa solve` print it.

use std::time::Instant;

use super::schedule::{Pass, Schedule};
use super::search::run_iterations;
use crate::energy::TERM_COUNT;
use crate::evaluate::Problem;
use crate::output::solution::SampleRecord;

/// The cost of a solve, roughly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost {
    /// Samples at most: every run of every stage to its iteration cap, every restart,
    /// every attempt; the passes that refine (trades, polish) add a share.
    pub samples: usize,
    /// Wall time (s): one attempt whose runs stop early (at [`EARLY`] of their caps), and
    /// every attempt to its caps with the moves' time on top ([`MOVES_TIME`]).
    pub seconds: (f64, f64),
    /// Memory the solve adds to the loaded scene (bytes): the threads' workspaces and
    /// the record of every sample, at most.
    pub bytes: usize,
}

/// The passes that refine, against the runs: on the examples their samples were 14 to
/// 20 % of the runs' and their time a half to two thirds of it (single-threaded moves
/// and seats), so a solve whose last stage refines takes about 1.7 times its runs.
const REFINE_TIME: f64 = 0.7;
/// Samples the refining passes draw, as a share of the runs'.
const REFINE_SAMPLES: f64 = 0.2;
/// The share of their caps that the runs of a solve draw at least, about: the examples'
/// runs drew 60 % of theirs (fly, tbc, THE THINKER), Mickey's fewer (its target energy).
const EARLY: f64 = 0.6;
/// The moves of every stage, against the runs' time: up to 30 %.
const MOVES_TIME: f64 = 0.3;
/// Seconds of sample timing per stage at most.
const TIMING_BUDGET: f64 = 0.005;

/// Estimate the cost of solving `problem` with `schedule` on `threads` threads.
pub fn estimate(problem: &Problem, schedule: &Schedule, threads: usize) -> Cost {
    let scene = &problem.scene;
    let params = problem.start_parameters();
    let mut ws = problem.workspace();
    let (mut samples, mut seconds) = (0.0, 0.0);
    let mut timed: Vec<(Vec<usize>, f64)> = Vec::new();
    for stage in &scene.stages {
        let runs: usize = (0..=stage.restarts)
            .map(|r| {
                let population = stage.population << r;
                population * run_iterations(stage.max_iterations, stage.population, population)
            })
            .sum();
        // A stage of the same bodies costs the same per sample: timed once.
        let per_sample = match timed.iter().find(|(vary, _)| *vary == stage.vary) {
            Some(&(_, s)) => s,
            None => {
                let held = problem.hold(&params, &stage.vary).for_stage(stage);
                let start = Instant::now();
                let mut reps = 0;
                while reps < 3 || (reps < 200 && start.elapsed().as_secs_f64() < TIMING_BUDGET) {
                    problem.evaluate_held(&held, &params, &stage.weights, &mut ws);
                    reps += 1;
                }
                let s = start.elapsed().as_secs_f64() / reps as f64;
                timed.push((stage.vary.clone(), s));
                s
            }
        };
        samples += runs as f64;
        seconds += runs as f64 * per_sample;
    }
    let refines = schedule
        .stage
        .iter()
        .any(|s| matches!(s.pass, Pass::Trades | Pass::Polish))
        && scene.stages.last().is_some_and(|s| s.vary.len() > 1);
    let (refine_samples, refine_time) = if refines {
        (REFINE_SAMPLES, REFINE_TIME)
    } else {
        (0.0, 0.0)
    };
    let attempts = schedule.attempts.max(1) as f64;
    let samples = samples * (1.0 + refine_samples) * attempts;
    // One attempt: the runs' samples spread over the threads, the refining passes on top.
    let one = seconds / threads.max(1) as f64 * (1.0 + refine_time);
    let record = std::mem::size_of::<SampleRecord>().max(8 * (TERM_COUNT + 3));
    let workspace = problem.workspace_bytes();
    // A later attempt runs ahead on a pool of its own (`solver::ahead`).
    let pools = if threads > 1 && schedule.attempts > 1 {
        2
    } else {
        1
    };
    Cost {
        samples: samples.ceil() as usize,
        seconds: (EARLY * one, (1.0 + MOVES_TIME) * one * attempts),
        // Each pool's threads evaluate in a workspace each, and work on the moves in
        // another each (`moves::improve`).
        bytes: (2 * pools * threads.max(1) + 2) * workspace + samples as usize * record,
    }
}

/// A number of seconds as a person reads it: "0.4 s", "12 s", "3 min", "2.5 h".
pub fn duration(s: f64) -> String {
    match s {
        s if s < 10.0 => format!("{s:.1} s"),
        s if s < 120.0 => format!("{s:.0} s"),
        s if s < 7200.0 => format!("{:.0} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}

/// A number of bytes as a person reads it: "350 kB", "12 MB", "2.4 GB".
pub fn bytes(b: usize) -> String {
    let b = b as f64;
    match b {
        b if b < 1e6 => format!("{:.0} kB", b / 1e3),
        b if b < 1e9 => format!("{:.0} MB", b / 1e6),
        b => format!("{:.1} GB", b / 1e9),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_and_sizes_read_as_a_person_reads_them() {
        assert_eq!(duration(0.42), "0.4 s");
        assert_eq!(duration(42.0), "42 s");
        assert_eq!(duration(600.0), "10 min");
        assert_eq!(duration(9000.0), "2.5 h");
        assert_eq!(bytes(350_000), "350 kB");
        assert_eq!(bytes(12_000_000), "12 MB");
        assert_eq!(bytes(2_400_000_000), "2.4 GB");
    }
}
