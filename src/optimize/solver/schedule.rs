//! The solve as data: a [`Schedule`] of passes, each with a guard ([`When`]) and a
//! judge ([`Judge`]), and the [`THRESHOLDS`] that guard and size them, each with its
//! unit and why it has its value.
//!
//! Every stage of the scene runs the schedule's [`Schedule::stage`] passes in order;
//! the solve repeats the whole as another attempt while [`Schedule::attempts`] allows
//! and the picture stays below the last stage's `restart_iou`. `bsa solve` runs
//! [`Schedule::DEFAULT`]; `bsa new`'s trial solves, which compare designs,
//! [`Schedule::TRIAL`]. `solution.json` records every pass that ran
//! ([`PassRecord`](crate::output::solution::PassRecord)).

/// What a pass does (see `docs/solver.md` for what each mends and costs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// A round of moves ([`crate::optimize::moves::improve`]) from the stage's best:
    /// the global jumps a local search does not make.
    Moves,
    /// Runs of CMA-ES over the stage's bodies: IPOP restarts (twice the population,
    /// the stage's first step) while a run moved the picture, each after a round of
    /// moves.
    Runs,
    /// Trades of places among bodies of one kind and different shapes (moves that
    /// trade, each judged as seated), then runs again from the trade taken.
    Trades,
    /// Every block seated anew, then each body refined alone by a run with a tenth of
    /// the one-body stage's step.
    Polish,
}

impl Pass {
    /// The pass's name in `solution.json`, the report and the progress.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Moves => "moves",
            Pass::Runs => "runs",
            Pass::Trades => "trades",
            Pass::Polish => "polish",
        }
    }
}

/// When a pass runs. Every pass runs once per stage at most, never after an interrupt,
/// and none but [`Pass::Moves`] and [`Pass::Runs`] in a robust solve (its picture at
/// `t` is not what it optimises).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum When {
    /// In every stage.
    Always,
    /// In the scene's last stage, when its runs ended below `iou` without reaching the
    /// target energy.
    LastStageBelow(Threshold),
    /// In the scene's last stage, of several bodies, when its picture is below the
    /// stage's own `restart_iou`.
    LastJointStageBelowRestartIou,
}

/// What a pass's candidates are judged by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Judge {
    /// The stage's weights.
    Stage,
    /// The stage's weights without the hints: a hint says where the design sent a body,
    /// which holds a body on the design's mistake (a cycle of pieces each on another's
    /// part) or a fraction of a pixel off its outline.
    NoHints,
}

/// One pass of a stage's schedule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub pass: Pass,
    pub when: When,
    pub judge: Judge,
}

/// The passes of every stage, and the attempts of a solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    pub stage: &'static [Step],
    /// Attempts at most (another from the start guess, with another seed, while the
    /// picture stays below the last stage's `restart_iou`; the best is kept).
    pub attempts: usize,
}

const fn step(pass: Pass, when: When, judge: Judge) -> Step {
    Step { pass, when, judge }
}

impl Schedule {
    /// `bsa solve`'s schedule.
    pub const DEFAULT: Schedule = Schedule {
        stage: &[
            step(Pass::Moves, When::Always, Judge::Stage),
            step(Pass::Runs, When::Always, Judge::Stage),
            step(
                Pass::Trades,
                When::LastStageBelow(TRADE_IOU),
                Judge::NoHints,
            ),
            step(
                Pass::Polish,
                When::LastJointStageBelowRestartIou,
                Judge::NoHints,
            ),
        ],
        attempts: ATTEMPTS.value as usize,
    };

    /// The trial solves of `bsa new`, which compare designs: no trades (a trade mends a
    /// design's wrong assignment in one trial and not in another, so that a trial would
    /// tell less of the design and more of the trade), no polish (it refines whichever
    /// design is kept by a few thousandths) and one attempt.
    pub const TRIAL: Schedule = Schedule {
        stage: &[
            step(Pass::Moves, When::Always, Judge::Stage),
            step(Pass::Runs, When::Always, Judge::Stage),
        ],
        attempts: 1,
    };

    /// This schedule with at most `attempts` attempts.
    pub fn with_attempts(self, attempts: usize) -> Schedule {
        Schedule { attempts, ..self }
    }
}

impl Default for Schedule {
    fn default() -> Schedule {
        Schedule::DEFAULT
    }
}

/// A number the schedule runs by: its value, its unit and why it has that value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Threshold {
    pub name: &'static str,
    pub value: f64,
    pub unit: &'static str,
    pub why: &'static str,
}

/// The attempts `bsa solve` makes at most by default.
pub const ATTEMPTS: Threshold = Threshold {
    name: "attempts",
    value: 2.0,
    unit: "attempts",
    why: "a second attempt from the start guess where the first ends below the last stage's \
          restart_iou: on 35 planted problems 13 first attempts ended under 0.995 and the \
          second was kept in 5, none made worse, for 1.76 times the time",
};

/// The last stage's picture below which its bodies trade places.
pub const TRADE_IOU: Threshold = Threshold {
    name: "trade_iou",
    value: 0.985,
    unit: "IoU",
    why: "bodies each on another's part is a state no move of one or two bodies mends; trades cost 1.25 times the solve time of planted block and chess \
          problems, paid only where the picture is poor",
};

/// Moves taken at most by the call of the moves that trades.
pub const TRADE_MOVES: Threshold = Threshold {
    name: "trade_moves",
    value: 3.0,
    unit: "moves",
    why: "a trade of two often leaves a third body to trade; against as many moves as \
          bodies, 13 to 18 % less solve time for the same pictures but one",
};

/// The step of the polish's one-body runs, a share of the one-body stage's step.
pub const POLISH_STEP_SHARE: Threshold = Threshold {
    name: "polish_step_share",
    value: 0.1,
    unit: "x one-body step",
    why: "a joint stage of many bodies stops short of a pixel's precision; a run of one \
          body from a step ten times smaller mends what is left of its outline",
};

/// The thresholds of the schedule, as `docs/solver.md` lists them. The moves' own
/// numbers (depth steps, turns, seat counts) are the moves' and live with them.
pub const THRESHOLDS: [Threshold; 4] = [ATTEMPTS, TRADE_IOU, TRADE_MOVES, POLISH_STEP_SHARE];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_threshold_is_named_once_with_a_unit_and_a_reason() {
        for (k, t) in THRESHOLDS.iter().enumerate() {
            assert!(!t.unit.is_empty() && t.why.len() > 40, "{t:?}");
            assert!(
                THRESHOLDS[k + 1..].iter().all(|u| u.name != t.name),
                "{t:?}"
            );
        }
    }

    const SOLVER_MD: &str = include_str!("../../../docs/solver.md");

    #[test]
    fn docs_list_every_threshold() {
        for t in THRESHOLDS {
            let row = format!("| {} | {} | {} | {} |", t.name, t.value, t.unit, t.why);
            let row = row.split_whitespace().collect::<Vec<_>>().join(" ");
            assert!(
                SOLVER_MD.contains(&row),
                "docs/solver.md lacks the row\n{row}"
            );
        }
    }

    #[test]
    fn docs_name_every_pass_and_tests_that_exist() {
        let tests = include_str!("../../../tests/integration/solver.rs");
        for pass in [Pass::Moves, Pass::Runs, Pass::Trades, Pass::Polish] {
            assert!(
                SOLVER_MD.contains(&format!("\n| {} ", pass.name())),
                "{pass:?}"
            );
        }
        let table = SOLVER_MD.split("## Thresholds").next().unwrap();
        for line in table.lines().filter(|l| l.starts_with("| ")) {
            // The last cell: none, one or several test names, each in backticks.
            let cell = line.trim_end_matches(" |").rsplit(" | ").next().unwrap();
            for name in cell.split('`').skip(1).step_by(2) {
                assert!(tests.contains(&format!("fn {name}(")), "no test {name}");
            }
        }
    }

    #[test]
    fn the_trial_schedule_is_the_default_without_trades_polish_and_attempts() {
        let d = Schedule::DEFAULT;
        let t = Schedule::TRIAL;
        assert_eq!(t.attempts, 1);
        assert!(t.stage.iter().all(|s| d.stage.contains(s)));
        assert!(!t
            .stage
            .iter()
            .any(|s| matches!(s.pass, Pass::Trades | Pass::Polish)));
    }
}
