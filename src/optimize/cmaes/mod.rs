//! Covariance Matrix Adaptation Evolution Strategy (CMA-ES) with an ask/tell interface.
//!
//! The solver minimises a noisy energy over the launch velocities of many objects. That
//! energy is expensive and is evaluated in parallel by the caller, so the optimiser here
//! is only the bookkeeping half of the loop and never calls the objective itself:
//!
//! 1. [`Cmaes::ask`] samples a population of `lambda` candidates (one row-major slice,
//!    `lambda * n` values) from the current search distribution `N(m, sigma^2 C)`.
//! 2. The caller evaluates every candidate elsewhere (for example with rayon), in any
//!    order, and collects the values in candidate order.
//! 3. [`Cmaes::tell`] ranks the candidates and updates the mean, the evolution paths,
//!    the covariance matrix and the step size, then evaluates the termination criteria,
//!    which [`Cmaes::stop`] reports.
//!
//! The main types are [`CmaesConfig`] (tunables with documented defaults), [`Cmaes`]
//! (the optimiser state) and [`StopReason`] (why a run should end).
//!
//! The algorithm is the standard `(mu/mu_w, lambda)`-CMA-ES with rank-one and rank-mu
//! covariance updates, cumulative step-size adaptation and the `h_sigma` stall of the
//! rank-one update, with the default strategy parameters of N. Hansen, "The CMA Evolution
//! Strategy: A Tutorial" (arXiv:1604.00772, 2016), Table 1, restricted to positive
//! recombination weights (no active CMA). See `docs/cmaes.md` for references, the
//! termination criteria and measured evaluation counts.
//!
//! Determinism: all randomness comes from one `ChaCha8Rng` seeded with
//! `seed_from_u64(seed)` and consumed sequentially in [`Cmaes::ask`]; the update in
//! [`Cmaes::tell`] is a fixed sequence of floating-point operations. The same seed and the
//! same fitness values therefore give bit-identical candidates and state, whatever order
//! or threads the caller used to compute the fitness values.
//!
//! After construction nothing is allocated: every buffer (population, ranking indices,
//! covariance, eigenbasis, history of best values) is sized in [`Cmaes::new`].

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::linalg::{sym_eigen_ql, transpose};

/// Largest accepted condition number of the covariance matrix (ratio of its largest to
/// its smallest eigenvalue). Beyond it the smallest axes are lost to rounding in
/// `sigma^2 C`, so the run is stopped with [`StopReason::ConditionNumber`].
pub const MAX_CONDITION: f64 = 1e14;

/// Tunables of [`Cmaes`], with documented defaults (see [`CmaesConfig::default`]).
///
/// Values of the objective are in the caller's units (here: the energy); `tol_x` is in
/// the units of the search variables.
#[derive(Clone, Debug)]
pub struct CmaesConfig {
    /// Population size `lambda` (candidates per generation, at least 2).
    /// `None` selects the tutorial default `4 + floor(3 ln n)`. Larger populations make
    /// the search more global (Rastrigin-like landscapes, noise) at a higher cost per
    /// generation. Default: `None`.
    pub population: Option<usize>,
    /// Iteration cap: [`StopReason::MaxGenerations`] once this many generations have been
    /// told. Default: `10_000`.
    pub max_generations: usize,
    /// Stop with [`StopReason::TargetReached`] as soon as the best value ever told is
    /// `<= f_target`. Default: `None` (no target).
    pub f_target: Option<f64>,
    /// [`StopReason::TolFun`] when the range (max - min) of the best-of-generation values
    /// of the last `stagnation_window` generations together with all values of the
    /// current generation is below this (absolute, objective units). It also sets the
    /// size of an improvement that resets the stagnation counter (see
    /// `stagnation_window`). `0.0` disables `TolFun` (a range is never negative) and
    /// makes every strict improvement reset the stagnation counter. Default: `1e-12`
    /// (the tutorial's `TolFun`).
    pub tol_fun: f64,
    /// [`StopReason::TolX`] when both `sigma * max_i sqrt(C_ii)` (the largest coordinate
    /// standard deviation) and `sigma * max_i |p_c,i|` (the largest component of the
    /// scaled evolution path) are below this (absolute, units of the search variables).
    /// `0.0` disables it. Default: `1e-11` (pycma's `tolx`; the tutorial suggests
    /// `1e-12 * sigma0`).
    pub tol_x: f64,
    /// Length of the history, in generations, used by two criteria (at least 1):
    /// `TolFun` looks at the best values of the last `stagnation_window` generations,
    /// and [`StopReason::Stagnation`] is reported when the overall best value has not
    /// improved by more than `tol_fun * max(1, |f_ref|)` during the last
    /// `stagnation_window` generations, where `f_ref` is the best value at the last such
    /// improvement. The threshold is therefore absolute for `|f| <= 1` and relative
    /// above, so that large energies do not stall on rounding-level gains. Default:
    /// `100` generations.
    pub stagnation_window: usize,
}

impl Default for CmaesConfig {
    fn default() -> Self {
        CmaesConfig {
            population: None,
            max_generations: 10_000,
            f_target: None,
            tol_fun: 1e-12,
            tol_x: 1e-11,
            stagnation_window: 100,
        }
    }
}

impl CmaesConfig {
    /// The tutorial's default population size `4 + floor(3 ln n)` for dimension `n`.
    pub fn default_population(n: usize) -> usize {
        4 + (3.0 * (n.max(1) as f64).ln()).floor() as usize
    }

    /// The history length that the tutorial uses for its `TolFun` criterion,
    /// `10 + ceil(30 n / lambda)` generations, for callers who want
    /// `stagnation_window` to follow the dimension.
    pub fn tutorial_tolfun_window(n: usize, lambda: usize) -> usize {
        10 + (30 * n).div_ceil(lambda.max(1))
    }
}

/// Why [`Cmaes::stop`] asks the caller to end the run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The best value ever told is at or below [`CmaesConfig::f_target`].
    TargetReached,
    /// Recent objective values span less than [`CmaesConfig::tol_fun`].
    TolFun,
    /// The search distribution and the evolution path are narrower than
    /// [`CmaesConfig::tol_x`] in every coordinate.
    TolX,
    /// The overall best has not improved significantly for
    /// [`CmaesConfig::stagnation_window`] generations.
    Stagnation,
    /// [`CmaesConfig::max_generations`] generations have been told.
    MaxGenerations,
    /// The covariance matrix is ill-conditioned (condition number above
    /// [`MAX_CONDITION`] = 1e14, or a non-positive eigenvalue).
    ConditionNumber,
}

/// State of one CMA-ES run; see the module documentation for the ask/tell data flow.
#[derive(Clone, Debug)]
pub struct Cmaes {
    config: CmaesConfig,
    n: usize,
    lambda: usize,
    mu: usize,
    /// Positive recombination weights of the `mu` best candidates, summing to 1.
    weights: Vec<f64>,
    mueff: f64,
    cc: f64,
    cs: f64,
    c1: f64,
    cmu: f64,
    damps: f64,
    /// `E||N(0, I)||`, the expected length of a standard normal vector.
    chi_n: f64,
    /// Generations that may pass before the eigen-decomposition must be refreshed.
    eigen_interval: f64,

    mean: Vec<f64>,
    sigma: f64,
    pc: Vec<f64>,
    ps: Vec<f64>,
    /// Covariance matrix, row-major `n x n`, kept exactly symmetric.
    c: Vec<f64>,
    /// `B^T`: the eigenvectors of `c` in rows (row-major `n x n`). `B v` is then the sum
    /// of `v_j` times row `j`, over contiguous rows and every component at once, each
    /// summing its terms in the order a dot product with a row of `B` would.
    bt: Vec<f64>,
    /// Square roots of the eigenvalues of `c` (standard deviations along the rows of `bt`).
    d: Vec<f64>,
    eigenvalues: Vec<f64>,
    eigen_work: Vec<f64>,
    last_eigen_generation: usize,
    ill_conditioned: bool,

    /// Standard normal samples of the last `ask`, row-major `lambda x n`.
    z: Vec<f64>,
    /// Steps `y = B D z = (x - m) / sigma` of the last `ask`.
    y: Vec<f64>,
    /// Candidates `x = m + sigma y` of the last `ask`, handed to the caller.
    x: Vec<f64>,
    /// Fitness used for ranking: the told value, or `+inf` for non-finite values.
    keys: Vec<f64>,
    /// Candidate indices sorted from best to worst.
    order: Vec<usize>,
    ymean: Vec<f64>,
    zmean: Vec<f64>,
    /// Scratch of `n` values: `D z` in `ask`; `B <z>_w`, then a row's rank-mu sums in
    /// `tell`.
    tmp: Vec<f64>,

    rng: ChaCha8Rng,
    awaiting_tell: bool,
    generation: usize,
    evaluations: usize,

    best_x: Vec<f64>,
    best_f: f64,
    /// Ring buffer of best-of-generation values (`+inf` if a generation had none finite).
    history: Vec<f64>,
    history_len: usize,
    history_pos: usize,
    /// Best value at the last significant improvement, for the stagnation criterion.
    stall_reference: f64,
    last_improvement: usize,
    stop: Option<StopReason>,
}

impl Cmaes {
    /// Starts a run at `mean` (the start point, `n = mean.len() >= 1`) with initial global
    /// step size `sigma` (in the units of the variables; about a quarter to a half of the
    /// range in which the optimum is expected) and identity covariance. `seed` seeds the
    /// `ChaCha8Rng` (`seed_from_u64`) that is the only source of randomness.
    ///
    /// # Panics
    /// If `mean` is empty or not finite, `sigma` is not finite and positive, the
    /// population is below 2 or `stagnation_window` is 0.
    pub fn new(mean: &[f64], sigma: f64, config: CmaesConfig, seed: u64) -> Cmaes {
        let n = mean.len();
        assert!(n >= 1, "CMA-ES needs at least one variable");
        assert!(
            mean.iter().all(|v| v.is_finite()),
            "CMA-ES start point must be finite"
        );
        assert!(
            sigma.is_finite() && sigma > 0.0,
            "CMA-ES initial sigma must be finite and positive, got {sigma}"
        );
        assert!(
            config.stagnation_window >= 1,
            "CMA-ES stagnation_window must be at least 1"
        );
        let lambda = config
            .population
            .unwrap_or_else(|| CmaesConfig::default_population(n));
        assert!(lambda >= 2, "CMA-ES population must be at least 2");

        // Default strategy parameters of the tutorial (Hansen 2016, Table 1), positive
        // weights only: w'_i = ln((lambda + 1) / 2) - ln i for the mu best, normalised.
        let nf = n as f64;
        let mu = lambda / 2;
        let mut weights: Vec<f64> = (1..=mu)
            .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - (i as f64).ln())
            .collect();
        let sum: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= sum);
        let mueff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();

        let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
        let cs = (mueff + 2.0) / (nf + mueff + 5.0);
        let alpha_cov = 2.0;
        let c1 = alpha_cov / ((nf + 1.3).powi(2) + mueff);
        let cmu = (1.0 - c1).min(
            alpha_cov * (mueff - 2.0 + 1.0 / mueff)
                / ((nf + 2.0).powi(2) + alpha_cov * mueff / 2.0),
        );
        let damps = 1.0 + 2.0 * (((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + cs;
        let chi_n = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
        // B and D are refreshed once more than 0.5 lambda / ((c1 + cmu) n) evaluations
        // have passed since the last decomposition, the gap of Hansen's purecma (0.5 so
        // that the decomposition takes about twice the time of a tell from 20-D on); in
        // generations 0.5 / ((c1 + cmu) n). C changes by at most a fraction c1 + cmu per
        // generation, so a slightly stale basis costs little, while the decomposition is
        // O(n^3): with the tutorial's ten times smaller gap, a solve of 64 balls (its
        // joint stage n = 384, lambda = 32) spent 14 % of its CPU time decomposing C and
        // 3 % drawing the balls' shadows.
        let eigen_interval = 0.5 / ((c1 + cmu) * nf);

        let mut c = vec![0.0; n * n];
        let mut bt = vec![0.0; n * n];
        for i in 0..n {
            c[i * n + i] = 1.0;
            bt[i * n + i] = 1.0;
        }
        let window = config.stagnation_window;
        Cmaes {
            n,
            lambda,
            mu,
            weights,
            mueff,
            cc,
            cs,
            c1,
            cmu,
            damps,
            chi_n,
            eigen_interval,
            mean: mean.to_vec(),
            sigma,
            pc: vec![0.0; n],
            ps: vec![0.0; n],
            c,
            bt,
            d: vec![1.0; n],
            eigenvalues: vec![1.0; n],
            eigen_work: vec![0.0; n * n],
            last_eigen_generation: 0,
            ill_conditioned: false,
            z: vec![0.0; lambda * n],
            y: vec![0.0; lambda * n],
            x: vec![0.0; lambda * n],
            keys: vec![0.0; lambda],
            order: (0..lambda).collect(),
            ymean: vec![0.0; n],
            zmean: vec![0.0; n],
            tmp: vec![0.0; n],
            rng: ChaCha8Rng::seed_from_u64(seed),
            awaiting_tell: false,
            generation: 0,
            evaluations: 0,
            best_x: mean.to_vec(),
            best_f: f64::INFINITY,
            history: vec![f64::INFINITY; window],
            history_len: 0,
            history_pos: 0,
            stall_reference: f64::INFINITY,
            last_improvement: 0,
            stop: None,
            config,
        }
    }

    /// Number of search variables `n`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Population size `lambda`: candidates per [`ask`](Self::ask) and values per
    /// [`tell`](Self::tell).
    pub fn population(&self) -> usize {
        self.lambda
    }

    /// Number of parents `mu = floor(lambda / 2)` that are recombined.
    pub fn parents(&self) -> usize {
        self.mu
    }

    /// Variance-effective selection mass `mu_eff = 1 / sum w_i^2`.
    pub fn mu_eff(&self) -> f64 {
        self.mueff
    }

    /// The configuration this run was started with.
    pub fn config(&self) -> &CmaesConfig {
        &self.config
    }

    /// Samples a new population and returns it as `lambda` candidate vectors laid out
    /// row-major in one slice (`lambda * n` values; candidate `k` is
    /// `&out[k * n..(k + 1) * n]`).
    ///
    /// The normal deviates are drawn sequentially (candidate by candidate, coordinate by
    /// coordinate) from the run's single RNG, which makes the candidates a pure function
    /// of the seed and the fitness values told so far.
    ///
    /// # Panics
    /// If called again before [`tell`](Self::tell): the previous population would be
    /// lost and the caller's fitness values would no longer match the stored steps.
    pub fn ask(&mut self) -> &[f64] {
        assert!(
            !self.awaiting_tell,
            "Cmaes::ask called twice without tell in between"
        );
        let n = self.n;
        for k in 0..self.lambda {
            let z = &mut self.z[k * n..(k + 1) * n];
            for zi in z.iter_mut() {
                *zi = self.rng.sample(StandardNormal);
            }
            // y = B (D * z): a sample of N(0, C) expressed in the original coordinates.
            for (t, (&zi, &di)) in self.tmp.iter_mut().zip(z.iter().zip(&self.d)) {
                *t = di * zi;
            }
            let y = &mut self.y[k * n..(k + 1) * n];
            times_b(&self.bt, &self.tmp, y);
            let x = &mut self.x[k * n..(k + 1) * n];
            for ((xi, &yi), &m) in x.iter_mut().zip(y.iter()).zip(&self.mean) {
                *xi = m + self.sigma * yi;
            }
        }
        self.awaiting_tell = true;
        &self.x
    }

    /// Reports the fitness (lower is better) of each candidate of the last
    /// [`ask`](Self::ask), in the same order, and performs one generation of the update.
    ///
    /// Non-finite values (NaN, +inf, -inf) rank behind every finite value, so a failed
    /// simulation only loses its candidate; ties (including between non-finite values)
    /// are broken by candidate index so the ranking stays deterministic.
    ///
    /// # Panics
    /// If no population is pending (no `ask` since the last `tell`) or
    /// `fitness.len() != lambda`.
    pub fn tell(&mut self, fitness: &[f64]) {
        assert!(
            self.awaiting_tell,
            "Cmaes::tell called without a pending ask"
        );
        assert_eq!(
            fitness.len(),
            self.lambda,
            "Cmaes::tell needs one fitness value per candidate"
        );
        self.awaiting_tell = false;
        let n = self.n;
        let lambda = self.lambda;

        // Ranking. `sort_unstable_by` sorts in place (no allocation); the index
        // tie-break makes the comparison a total order, so the result is unique even
        // though the sort is unstable.
        for (key, &f) in self.keys.iter_mut().zip(fitness) {
            *key = if f.is_finite() { f } else { f64::INFINITY };
        }
        for (i, o) in self.order.iter_mut().enumerate() {
            *o = i;
        }
        let keys = &self.keys;
        self.order
            .sort_unstable_by(|&a, &b| keys[a].total_cmp(&keys[b]).then(a.cmp(&b)));

        self.generation += 1;
        self.evaluations += lambda;

        // Best ever, copied before the distribution moves on.
        let gen_best = self.keys[self.order[0]];
        if gen_best < self.best_f {
            self.best_f = gen_best;
            let k = self.order[0];
            self.best_x.copy_from_slice(&self.x[k * n..(k + 1) * n]);
        }

        // Recombination: weighted means of the mu best steps and of their normal
        // deviates. Because y = B D z for the basis used in `ask`, C^{-1/2} <y>_w equals
        // B <z>_w exactly, even while the decomposition is lazily out of date.
        self.ymean.iter_mut().for_each(|v| *v = 0.0);
        self.zmean.iter_mut().for_each(|v| *v = 0.0);
        for (&w, &k) in self.weights.iter().zip(&self.order[..self.mu]) {
            let y = &self.y[k * n..(k + 1) * n];
            let z = &self.z[k * n..(k + 1) * n];
            for i in 0..n {
                self.ymean[i] += w * y[i];
                self.zmean[i] += w * z[i];
            }
        }
        // Mean update with learning rate c_m = 1.
        for (m, &dy) in self.mean.iter_mut().zip(&self.ymean) {
            *m += self.sigma * dy;
        }

        // Cumulation for step-size control: p_s follows C^{-1/2} <y>_w = B <z>_w.
        let cs_factor = (self.cs * (2.0 - self.cs) * self.mueff).sqrt();
        times_b(&self.bt, &self.zmean, &mut self.tmp);
        for (p, &bz) in self.ps.iter_mut().zip(&self.tmp) {
            *p = (1.0 - self.cs) * *p + cs_factor * bz;
        }
        let ps_norm = self.ps.iter().map(|v| v * v).sum::<f64>().sqrt();

        // h_sigma stalls the rank-one update while p_s is long, which happens after a
        // sudden increase of sigma (or right at the start, hence the bias correction
        // 1 - (1 - c_s)^(2g)); otherwise C would grow too fast along p_c.
        let bias = 1.0 - (1.0 - self.cs).powf(2.0 * self.generation as f64);
        let hsig = ps_norm / bias.sqrt() / self.chi_n < 1.4 + 2.0 / (n as f64 + 1.0);
        let hsig_f = if hsig { 1.0 } else { 0.0 };

        let cc_factor = (self.cc * (2.0 - self.cc) * self.mueff).sqrt();
        for (p, &dy) in self.pc.iter_mut().zip(&self.ymean) {
            *p = (1.0 - self.cc) * *p + hsig_f * cc_factor * dy;
        }

        // Covariance update (rank-one + rank-mu). The weights sum to 1, so the decay is
        // 1 - c1 - cmu, and delta(h_sigma) compensates the variance lost by the stall.
        let delta_h = (1.0 - hsig_f) * self.cc * (2.0 - self.cc);
        let decay = 1.0 - self.c1 - self.cmu + self.c1 * delta_h;
        // Only the upper triangle is computed and then mirrored, which keeps C exactly
        // symmetric as sym_eigen expects, and halves the cost of the rank-mu sum.
        // Row i's rank-mu sums for every j at once, each over the steps in order: the
        // same terms in the same order as one sum per (i, j), over contiguous steps.
        for i in 0..n {
            let rank_mu = &mut self.tmp[i..];
            rank_mu.fill(0.0);
            for (&w, &k) in self.weights.iter().zip(&self.order[..self.mu]) {
                let y = &self.y[k * n..(k + 1) * n];
                let wy = w * y[i];
                for (sum, &yj) in rank_mu.iter_mut().zip(&y[i..]) {
                    *sum += wy * yj;
                }
            }
            for (j, &rank_mu) in (i..n).zip(rank_mu.iter()) {
                let v = decay * self.c[i * n + j]
                    + self.c1 * self.pc[i] * self.pc[j]
                    + self.cmu * rank_mu;
                self.c[i * n + j] = v;
                self.c[j * n + i] = v;
            }
        }

        // Cumulative step-size adaptation: lengthen sigma when p_s is longer than
        // expected under random selection, shorten it when shorter.
        self.sigma *= ((self.cs / self.damps) * (ps_norm / self.chi_n - 1.0)).exp();

        if (self.generation - self.last_eigen_generation) as f64 > self.eigen_interval {
            self.update_eigensystem();
        }

        self.update_termination();
    }

    /// Recomputes B and D from C and records whether C is too ill-conditioned.
    fn update_eigensystem(&mut self) {
        let n = self.n;
        sym_eigen_ql(
            n,
            &self.c,
            &mut self.eigenvalues,
            &mut self.bt,
            &mut self.eigen_work,
        );
        transpose(n, &mut self.bt);
        self.last_eigen_generation = self.generation;
        let min = self.eigenvalues[0];
        let max = self.eigenvalues[n - 1];
        self.ill_conditioned = !(min > 0.0 && max <= MAX_CONDITION * min);
        // Rounding can push the smallest eigenvalues of a nearly singular C to zero or
        // below; clamping keeps D finite and positive for the next ask, while the run
        // reports ConditionNumber so the caller can stop or restart.
        let floor = (max.abs() / MAX_CONDITION).max(f64::MIN_POSITIVE);
        for (d, &ev) in self.d.iter_mut().zip(&self.eigenvalues) {
            *d = ev.max(floor).sqrt();
        }
    }

    /// Updates the histories and sets `self.stop` after a generation has been told.
    fn update_termination(&mut self) {
        let gen_best = self.keys[self.order[0]];
        let gen_worst = self.keys[self.order[self.lambda - 1]];
        let window = self.config.stagnation_window;

        self.history[self.history_pos] = gen_best;
        self.history_pos = (self.history_pos + 1) % window;
        self.history_len = (self.history_len + 1).min(window);

        if self.best_f.is_finite() {
            let significant = !self.stall_reference.is_finite()
                || self.best_f
                    < self.stall_reference
                        - self.config.tol_fun * self.stall_reference.abs().max(1.0);
            if significant {
                self.stall_reference = self.best_f;
                self.last_improvement = self.generation;
            }
        }

        self.stop = if self.config.f_target.is_some_and(|t| self.best_f <= t) {
            Some(StopReason::TargetReached)
        } else if self.tol_fun_reached(gen_best, gen_worst) {
            Some(StopReason::TolFun)
        } else if self.tol_x_reached() {
            Some(StopReason::TolX)
        } else if self.ill_conditioned {
            Some(StopReason::ConditionNumber)
        } else if self.generation - self.last_improvement >= window {
            Some(StopReason::Stagnation)
        } else if self.generation >= self.config.max_generations {
            Some(StopReason::MaxGenerations)
        } else {
            None
        };
    }

    fn tol_fun_reached(&self, gen_best: f64, gen_worst: f64) -> bool {
        if self.history_len < self.config.stagnation_window {
            return false;
        }
        let (lo, hi) = self
            .history
            .iter()
            .fold((gen_best, gen_worst), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        // An infinite value makes the range inf or NaN, and both compare false, so a
        // generation with failed evaluations never counts as converged.
        hi - lo < self.config.tol_fun
    }

    fn tol_x_reached(&self) -> bool {
        let n = self.n;
        let max_sd = (0..n)
            .map(|i| self.c[i * n + i])
            .fold(0.0f64, f64::max)
            .sqrt();
        let max_pc = self.pc.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        self.sigma * max_sd < self.config.tol_x && self.sigma * max_pc < self.config.tol_x
    }

    /// Number of completed generations (calls to [`tell`](Self::tell)).
    pub fn generation(&self) -> usize {
        self.generation
    }

    /// Number of fitness values told so far (`generation * lambda`).
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// Current mean of the search distribution (the recommended point of a noisy run,
    /// since it averages over many candidates).
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Current global step size.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Current covariance matrix `C` (row-major `n x n`, symmetric); the search
    /// distribution is `N(mean, sigma^2 C)`.
    pub fn covariance(&self) -> &[f64] {
        &self.c
    }

    /// Best candidate ever told and its value. Before the first finite value has been
    /// told this is the start point with `f64::INFINITY`.
    pub fn best(&self) -> (&[f64], f64) {
        (&self.best_x, self.best_f)
    }

    /// Why the run should stop, evaluated at the end of every [`tell`](Self::tell);
    /// `None` while it should go on. Asking and telling after a stop is allowed (the
    /// reason is re-evaluated each generation) but rarely useful.
    pub fn stop(&self) -> Option<StopReason> {
        self.stop
    }
}

pub mod functions;

/// `out = B v` from `bt` = `B^T` (row-major `n x n`): `v_j` times row `j`, summed over
/// `j` in order for every component at once. Each component gets the same terms in the
/// same order (from `-0.0`, as `Iterator::sum` starts) as a dot product with a row of
/// `B`, so the bits are the dot products'; the rows are read contiguously and the
/// components' sums do not wait on each other.
fn times_b(bt: &[f64], v: &[f64], out: &mut [f64]) {
    out.fill(-0.0);
    for (row, &vj) in bt.chunks_exact(v.len()).zip(v) {
        for (o, &b) in out.iter_mut().zip(row) {
            *o += b * vj;
        }
    }
}

#[cfg(test)]
mod tests;
