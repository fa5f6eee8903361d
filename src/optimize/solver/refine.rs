//! The pass that refines by CMA-ES runs of one body at a time: the last stage's
//! [`polish`].

use super::schedule::POLISH_STEP_SHARE;
use super::search::{local_run, rank_value, stage_seed, Pool};
use crate::evaluate::{Evaluation, Held, Problem, Workspace};
use crate::optimize::moves;
use crate::output::solution::MoveRecord;
use crate::scene::Stage;

/// The last stage's polish: first the moves with every block seated anew on its own
/// place (`moves::improve` for [`moves::Purpose::Polish`]), then each of the stage's bodies in turn,
/// the others held, refined by one CMA-ES run with the settings of `template` (the
/// scene's last stage of one body) but a tenth of its step ([`POLISH_STEP_SHARE`]), from
/// the best launch so far (`best`: the launch and its evaluation under `stage`'s
/// weights). The moves' end and each run's are kept when they rank better and draw no
/// worse a picture; `best` is updated in place. Returns the samples drawn, the moves
/// taken and the bodies the runs moved.
///
/// A joint stage of many bodies stops at its iteration cap still short of a pixel's
/// precision: its step shrinks slowly over 36 dimensions and more (on the planted chess
/// problems, its first step of 0.02 m/s over 1.2 s moves a shadow by about 30 pixels),
/// and its mean, which CMA-ES does not keep at the best, wanders over the picture's
/// staircase of pixels. A run of one body, six dimensions, from a step ten times smaller,
/// mends what is left of its outline. The solver calls it with the stage's weights
/// without the hints: a hint pulls its body toward the pixel the design chose, 0.3 of a
/// wrong pixel per pixel of distance, which holds an outline a fraction of a pixel off
/// its part (on the planted chess 11201, the hints were 434 pixels from their bodies in
/// all at the end, against 132 wrong pixels). Measured in `git show c030f18:docs/results.md`, "A polish
/// of one body at a time".
#[allow(clippy::too_many_arguments)]
pub(super) fn polish(
    problem: &Problem,
    pool: &Pool,
    held: &Held,
    stage: &Stage,
    template: &Stage,
    (params, best): (&mut [f64], &mut Evaluation),
    seed: u64,
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (usize, Vec<MoveRecord>, usize) {
    let contacts = problem.scene.contacts;
    let (mut samples, seated) =
        polish_moves(problem, pool, held, stage, (params, best), ws, record);
    let mut moved = 0;
    for (g, &body) in stage.vary.iter().enumerate() {
        let run = Stage {
            vary: vec![body],
            weights: stage.weights,
            step: POLISH_STEP_SHARE.value * template.step,
            ..template.clone()
        };
        let seed = stage_seed(seed, 2_000_000 + g);
        let (launch, rank, used) = local_run(problem, pool, &run, params, seed, ws, record);
        samples += used;
        if rank >= rank_value(best, contacts) {
            continue;
        }
        let e = problem.evaluate_held(held, &launch, &stage.weights, ws);
        if rank_value(&e, contacts) < rank_value(best, contacts) && e.iou >= best.iou {
            params.copy_from_slice(&launch);
            *best = e;
            moved += 1;
        }
    }
    (samples, seated, moved)
}

/// The polish's first step: the moves of `stage`'s bodies from `params` (evaluated as
/// `best`, both updated in place), every block seated anew on its own place in every
/// pass ([`moves::Purpose::Polish`]). Returns the samples drawn and the moves taken (none when
/// their end drew a worse picture, which is then not kept).
///
/// A block tilted the other way, or on another face, draws an outline near its part's
/// that no run of small steps leaves (the planted boxes 11204: one block's outline off
/// all round, IoU 0.9916, where its seat draws 0.9997); in a cluster, one block seated
/// anew lets the next find its pose. Run before the runs of one body rather than after
/// them: the runs then refine the seated blocks (on 14 planted block problems, after
/// the runs it gained less: 0.9981 against 0.9997 on boxes 11204).
fn polish_moves(
    problem: &Problem,
    pool: &Pool,
    held: &Held,
    stage: &Stage,
    (params, best): (&mut [f64], &mut Evaluation),
    ws: &mut Workspace,
    record: &mut dyn FnMut(&Evaluation),
) -> (usize, Vec<MoveRecord>) {
    let contacts = problem.scene.contacts;
    let rank = |e: &Evaluation| rank_value(e, contacts);
    let (kept, kept_eval) = (params.to_vec(), *best);
    let seats = moves::improve(
        problem,
        held,
        &stage.vary,
        &stage.weights,
        &rank,
        params,
        best,
        moves::MoveOptions {
            max_moves: stage.vary.len(),
            settled: true,
            purpose: moves::Purpose::Polish,
        },
        pool.rayon(),
        ws,
        record,
    );
    let (samples, mut seated) = (seats.samples, seats.taken);
    if best.iou < kept_eval.iou {
        params.copy_from_slice(&kept);
        *best = kept_eval;
        seated.clear();
    }
    (samples, seated)
}
