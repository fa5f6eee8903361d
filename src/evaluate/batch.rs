//! Samples in batches: [`Problem::evaluate_held_draws`] starts the flights of several
//! samples, integrates their grids side by side ([`integrate_grids`]), then evaluates
//! each sample in turn; [`Problem::batch_size`] says when that pays.

use super::{Evaluation, Held, Problem, Workspace};
use crate::energy::Weights;
use crate::sim::flight::{integrate_grids, RotationKind};

/// The most samples [`Problem::evaluate_held_draws`] takes at once: as many as
/// [`integrate_grids`] integrates side by side.
pub const MAX_BATCH: usize = 4;

impl Problem {
    /// [`Problem::evaluate_held_draw`] of each sample of `params` (at most [`MAX_BATCH`])
    /// into `out`. The samples' flights are started first and their grids integrated
    /// side by side ([`integrate_grids`]), where one sample's grid alone is a serial chain
    /// that leaves the core waiting; then each sample is evaluated in turn. The same
    /// evaluations, bit for bit, as one sample at a time.
    pub fn evaluate_held_draws(
        &self,
        held: &Held,
        params: &[Vec<f64>],
        weights: &Weights,
        draw: u64,
        ws: &mut Workspace,
        out: &mut [Evaluation],
    ) {
        assert!(params.len() <= MAX_BATCH && params.len() == out.len());
        let mut launched = [false; MAX_BATCH];
        for (k, p) in params.iter().enumerate() {
            launched[k] = self.launchable(p);
            if launched[k] {
                let flights = match k {
                    0 => &mut ws.flights,
                    _ => &mut ws.batch[k - 1],
                };
                self.start_flights(Some(&held.varying), p, flights);
            }
        }
        let later = ws.batch[..params.len().saturating_sub(1)].iter_mut();
        integrate_grids(ws.flights.iter_mut().chain(later.flatten()));
        for (k, (p, slot)) in params.iter().zip(out).enumerate() {
            if !launched[k] {
                *slot = Evaluation::diverged();
                continue;
            }
            if k > 0 {
                std::mem::swap(&mut ws.flights, &mut ws.batch[k - 1]);
            }
            *slot = self.evaluate_launched(Some(held), p, weights, draw, ws);
            if k > 0 {
                std::mem::swap(&mut ws.flights, &mut ws.batch[k - 1]);
            }
        }
    }

    /// How many samples [`Problem::evaluate_held_draws`] is best given at once with
    /// `held`: [`MAX_BATCH`] when a body it varies tumbles (three distinct moments: the
    /// grids are what a batch integrates side by side), else 1, which leaves the threads
    /// the finest share of a population (balls on a batch of 4 took 4 % longer).
    pub fn batch_size(&self, held: &Held) -> usize {
        let tumbles = self
            .scene
            .occluders
            .iter()
            .zip(&held.varying)
            .any(|(o, &v)| {
                v && o.launched && RotationKind::of(&o.mass) == RotationKind::Asymmetric
            });
        if tumbles {
            MAX_BATCH
        } else {
            1
        }
    }
}
