//! Slide: depth and size. [`Fit`] sends a body far too small or too large for its
//! part onto that part at the part's size; [`Search::polish`] slides the bodies of the
//! best moves of a round along their lines of sight, a few steps of shrinking size,
//! while the picture gets better (a move guesses a depth from the size of a shadow that
//! is often wrong itself).

use super::sight::{send_to_part, slide};
use super::{Move, Offers, Round, Search};
use crate::evaluate::{Evaluation, Workspace};

/// A body whose shadow's area is within this factor of its part's (either way) is not
/// sent to its part: CMA-ES's local steps fix small errors of size, and a fit move
/// taken there only perturbs the search (it cost the planted blocks 0.02 of IoU).
const FIT_TOLERANCE: f64 = 1.5;

/// Each body sent to its own part at the part's whole size, where its shadow's size is
/// far from the part's.
pub(super) struct Fit;

impl Move for Fit {
    fn name(&self) -> &'static str {
        "fit"
    }

    fn offer(&self, r: &Round, out: &mut Offers) {
        for &i in r.movable {
            let Some(si) = r.sights[i] else { continue };
            let Some(part) = si.part else {
                continue;
            };
            // Close to its part's size already: the local search does the rest.
            if (si.area / part.0).ln().abs() < FIT_TOLERANCE.ln() {
                continue;
            }
            out.candidate.copy_from_slice(r.params);
            send_to_part(r.problem, out.candidate, i, si, part);
            out.offer(&[i]);
        }
    }
}

/// Depth changes tried for a moved body, one after the other (fractions of its depth
/// along its line of sight from the light; a shadow's size goes as the inverse of the
/// depth): a move guesses the depth from the size of a shadow that is itself often
/// wrong (a body left too low behind a contact), and a swap of two bodies of close
/// sizes only pays once both have the size of their new part.
const DEPTH_STEPS: [f64; 3] = [0.16, 0.08, 0.04];

impl Search<'_> {
    /// Slide each body a move moved (`candidate`, evaluated as `best`) along its line of
    /// sight from the light, one step size after the other, keeping a change when it
    /// makes a better picture (the energy without contacts: the slide looks for the size
    /// of the new part, and a contact on the way there often goes at the right size; the
    /// caller ranks the result with its contacts). `candidate` ends as the best launch
    /// found; returns its evaluation.
    pub(super) fn polish(
        &mut self,
        candidate: &mut [f64],
        mut best: Evaluation,
        bodies: &[usize],
        ws: &mut Workspace,
    ) -> Evaluation {
        let mut trial = candidate.to_vec();
        for &b in bodies {
            for step in DEPTH_STEPS {
                for factor in [1.0 - step, 1.0 + step] {
                    trial.copy_from_slice(candidate);
                    if !slide(self.problem, &mut trial, b, factor) {
                        continue;
                    }
                    let e = self.evaluate(&trial, ws);
                    if self.free(&e) < self.free(&best) {
                        best = e;
                        candidate.copy_from_slice(&trial);
                    }
                }
            }
        }
        best
    }
}
