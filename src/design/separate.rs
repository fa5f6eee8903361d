//! Making the start guess contact-free ([`separate`]): the plan's flights are checked
//! with the solver's own exact flight and contact search, and while two bodies (or a
//! body and the table) meet before `t`, the move that puts the first contact latest is
//! taken, among: giving either body another slot (swapping with the object there, or
//! moving to a free one), raising or lowering either by the room two touching shadows
//! need ([`super::cover::separation`]), and rolling a box the other way (the same
//! shadow). Ties go to the move that keeps the better picture (IoU at `t`). It stops
//! when the flights are clear, or when no move delays the first contact.

use super::cover::separation;
use super::launch::Plan;
use crate::energy::Weights;
use crate::evaluate::{Evaluation, Problem};

/// What [`separate`] achieved.
#[derive(Clone, Copy, Debug)]
pub struct Separation {
    /// Moves taken.
    pub moves: usize,
    /// The start guess's evaluation after them.
    pub evaluation: Evaluation,
}

/// Set `problem`'s occluders (same order as the plan's objects) to the plan's launch
/// poses, and return the plan's start guess as launch values.
pub fn apply(plan: &Plan, problem: &mut Problem) -> Vec<f64> {
    for k in 0..plan.objects.len() {
        let s = plan.start(k);
        let o = &mut problem.scene.occluders[k];
        o.position = s.position;
        o.orientation = s.orientation;
    }
    plan.parameters()
}

fn evaluate(plan: &Plan, problem: &mut Problem) -> Evaluation {
    let params = apply(plan, problem);
    let mut ws = problem.workspace();
    problem.evaluate(&params, &Weights::default(), &mut ws)
}

/// Better: contact-free, then a later first contact, then a higher IoU.
fn rank(e: &Evaluation) -> (bool, f64, f64) {
    (e.outcome.n_contacts == 0, e.outcome.t_sim, e.iou)
}

fn better(a: &Evaluation, b: &Evaluation) -> bool {
    let (ra, rb) = (rank(a), rank(b));
    (ra.0, ra.1) > (rb.0, rb.1) || ((ra.0, ra.1) == (rb.0, rb.1) && ra.2 > rb.2)
}

/// Move slots, heights and rolls of `plan` until its start guess flies without contact
/// before `t` (see the module's comment), at most `max_moves` moves. `problem` is the
/// plan's scene, loaded (its occluders are moved to the plan's launch poses).
pub fn separate(plan: &mut Plan, problem: &mut Problem, max_moves: usize) -> Separation {
    let mut current = evaluate(plan, problem);
    let mut moves = 0;
    let frame = plan.geometry.frame();
    while current.outcome.n_contacts > 0 && moves < max_moves {
        let Some((i, j)) = current.outcome.first_contact else {
            break;
        };
        let mut candidates: Vec<Plan> = Vec::new();
        let who: Vec<usize> = std::iter::once(i).chain(j).collect();
        for &o in &who {
            for s in 0..plan.slots.len() {
                if s == plan.objects[o].slot {
                    continue;
                }
                let mut c = plan.clone();
                if let Some(q) = c.objects.iter().position(|p| p.slot == s) {
                    c.objects[q].slot = plan.objects[o].slot;
                }
                c.objects[o].slot = s;
                candidates.push(c);
            }
            let e_other = j
                .map(|j| plan.objects[if o == j { i } else { j }].pose.half_height)
                .unwrap_or(0.0);
            let step = separation(plan.objects[o].pose.half_height, e_other);
            for sign in [-1.0, 1.0] {
                let z = plan.height(o) + sign * step;
                let m = frame.magnification(z);
                if (frame.m_lo..=frame.m_hi).contains(&m) {
                    let mut c = plan.clone();
                    c.objects[o].placement.m = m;
                    candidates.push(c);
                }
            }
            if plan.objects[o].pose.turn != 0.0 {
                let mut c = plan.clone();
                c.objects[o].flip = !c.objects[o].flip;
                candidates.push(c);
            }
        }
        let mut best: Option<(Evaluation, Plan)> = None;
        for c in candidates {
            let e = evaluate(&c, problem);
            if best.as_ref().is_none_or(|b| better(&e, &b.0)) {
                best = Some((e, c));
            }
        }
        match best {
            Some((e, c))
                if e.outcome.n_contacts == 0 || e.outcome.t_sim > current.outcome.t_sim + 1e-9 =>
            {
                *plan = c;
                current = e;
                moves += 1;
            }
            _ => break,
        }
    }
    // Leave the problem's occluders on the final plan.
    apply(plan, problem);
    Separation {
        moves,
        evaluation: current,
    }
}
