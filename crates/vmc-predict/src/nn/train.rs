//! Levenberg–Marquardt training with early stopping on a validation set.
//!
//! Loss: `S(w) = Σ_samples Σ_outputs r²` with residuals `r = net(x; w) − y` (all outputs of a
//! multi-output net are fitted jointly). One *epoch* is one LM iteration:
//!
//! 1. `A = JᵀJ`, `g = Jᵀr` from the analytic Jacobian (backprop per sample, see `mlp.rs`).
//! 2. Solve `(A + μ·D) δ = −g` by Cholesky, with `D = I` (Levenberg, the default, as MATLAB's
//!    `trainlm`) or `D = diag(A)` (Marquardt's scaling; diagonal entries floored at
//!    `1e-12·max diag` so a weight with no influence does not make it singular). See [`Damping`].
//! 3. If `S(w + δ) < S(w)` accept and divide μ by `mu_factor`; otherwise (or when Cholesky fails)
//!    multiply μ by `mu_factor` and retry; give up when μ exceeds `mu_max`.
//!
//! `JᵀJ` is accumulated over blocks of residual rows without ever forming the whole J (20 k
//! samples × 6 outputs × 400 weights would be 380 MB): each block's Jᵀ is filled column by
//! column (a Jacobian row is contiguous in column-major storage), transposed once, and added
//! with `gemm`, which nalgebra routes to `matrixmultiply` for dynamic matrices.
//! Measured on a 2-core machine: `&jt * &j` at 123 ms vs `j.tr_mul(&j)` at 1.2 s for a 386 × 18 000
//! Jacobian; `tr_mul` does not take the `matrixmultiply` path, so we never use it.
//!
//! Everything is single-threaded and in a fixed order, so the same data and seed give
//! bit-identical weights.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::activation::Activation;
use super::mlp::{Init, Mlp};
use super::samples::Samples;
use super::NnError;

/// Residual rows per `JᵀJ` block: large enough for `gemm` to run at full speed, small enough to
/// stay in cache-sized memory (256 rows × 400 weights = 800 kB).
const BLOCK_ROWS: usize = 256;

/// Settings of a training run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    /// Seed of the weight initialisation (default: 0).
    pub seed: u64,
    /// Initialisation scheme (default: Nguyen–Widrow).
    pub init: Init,
    /// Hidden-layer activation of nets created by [`train`] (default: std tanh).
    pub activation: Activation,
    /// Independent runs from different seeds; the best on validation is kept (default: 1).
    pub restarts: usize,
    /// Maximum LM iterations per run (default: 200).
    pub max_epochs: usize,
    /// Epochs without a significant validation improvement before stopping (default: 10).
    pub patience: usize,
    /// Relative decrease of the best validation RMSE that counts as an improvement (default: 1e-4).
    pub min_rel_improvement: f64,
    /// Damping matrix of the LM step (default: Levenberg).
    pub damping: Damping,
    /// Initial damping μ (default: 1e-3).
    pub mu_init: f64,
    /// Factor μ is multiplied/divided by on a rejected/accepted step (default: 10).
    pub mu_factor: f64,
    /// Damping above which the run stops: no descent direction is left (default: 1e10).
    pub mu_max: f64,
    /// Lower bound of μ, keeps the step a damped one (default: 1e-15).
    pub mu_min: f64,
    /// Stop when the training RMSE (normalised units) falls below this (default: 0 = never).
    pub target_rmse: f64,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            seed: 0,
            init: Init::NguyenWidrow,
            activation: Activation::Tanh,
            restarts: 1,
            max_epochs: 200,
            patience: 10,
            min_rel_improvement: 1e-4,
            damping: Damping::Levenberg,
            mu_init: 1e-3,
            mu_factor: 10.0,
            mu_max: 1e10,
            mu_min: 1e-15,
            target_rmse: 0.0,
        }
    }
}

/// The damping matrix `D` of the LM step `(JᵀJ + μ·D) δ = −Jᵀr`.
///
/// Levenberg is the default: on normalised data every weight is O(1), so isotropic damping is
/// well scaled, and on a 1-8-1 sine fit it escaped the plateaus where Marquardt's scaling sat
/// for hundreds of epochs (4 seeds × 3 widths tried: all Levenberg runs below 1e-3 normalised
/// RMSE after 300 epochs, 5 of 12 Marquardt runs not).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Damping {
    /// `D = I`.
    #[default]
    Levenberg,
    /// `D = diag(JᵀJ)` (scale-invariant in the weights).
    Marquardt,
}

/// Why a training run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StopReason {
    /// `max_epochs` reached.
    MaxEpochs,
    /// Validation RMSE did not improve for `patience` epochs.
    EarlyStopping,
    /// Training RMSE fell below `target_rmse`.
    TargetReached,
    /// μ exceeded `mu_max`: no step decreases the loss any more (a local minimum).
    DampingLimit,
}

/// What happened during training. RMSEs are over all outputs, in normalised output units
/// (multiples of each output's training standard deviation) when trained through
/// [`super::Regressor`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// LM iterations done by the kept run.
    pub epochs: usize,
    /// Training RMSE before the first iteration (index 0) and after each one.
    pub train_rmse: Vec<f64>,
    /// Validation RMSE, same indexing (empty without a validation set).
    pub val_rmse: Vec<f64>,
    /// Epoch whose weights were kept (best validation RMSE, or the last epoch without validation).
    pub best_epoch: usize,
    /// Why the kept run stopped.
    pub stop_reason: StopReason,
    /// Index of the kept restart (0-based).
    pub restart: usize,
    /// Initialisation seed of the kept restart.
    pub init_seed: u64,
    /// Selection score of every restart (best validation RMSE, or final training RMSE).
    pub restart_scores: Vec<f64>,
}

/// Most weights a net trained here may have: the normal equations are a weights × weights
/// matrix (4096² f64 = 134 MB). The project's nets have a few hundred.
pub const MAX_LM_WEIGHTS: usize = 4096;

/// Weights of a fully connected net of widths `sizes` (with biases), saturating.
fn weight_count(sizes: &[usize]) -> usize {
    sizes.windows(2).fold(0usize, |acc, w| {
        acc.saturating_add(w[0].saturating_add(1).saturating_mul(w[1]))
    })
}

/// Refuses nets whose normal equations would not fit in memory.
fn check_weight_count(sizes: &[usize]) -> Result<(), NnError> {
    let weights = weight_count(sizes);
    if weights > MAX_LM_WEIGHTS {
        return Err(NnError::TooManyWeights {
            sizes: sizes.to_vec(),
            weights,
            max: MAX_LM_WEIGHTS,
        });
    }
    Ok(())
}

/// Trains a new net of widths `sizes` on `train`, with `config.restarts` independent
/// initialisations; keeps the one with the best validation RMSE (training RMSE if `val` is
/// `None` or empty). Ties keep the earlier restart.
pub fn train(
    sizes: &[usize],
    train: &Samples,
    val: Option<&Samples>,
    config: &TrainConfig,
) -> Result<(Mlp, TrainReport), NnError> {
    check_config(config)?;
    check_weight_count(sizes)?;
    let mut best: Option<(Mlp, TrainReport, f64)> = None;
    let mut scores = Vec::with_capacity(config.restarts);
    for r in 0..config.restarts {
        // Restart 0 uses the seed itself; later ones a mixed seed so nearby seeds don't collide.
        let init_seed = if r == 0 {
            config.seed
        } else {
            splitmix64(config.seed ^ splitmix64(r as u64))
        };
        let mut mlp =
            Mlp::random(sizes, config.init, init_seed)?.with_activation(config.activation);
        let mut report = train_from(&mut mlp, train, val, config)?;
        report.restart = r;
        report.init_seed = init_seed;
        let score = match report.val_rmse.get(report.best_epoch) {
            Some(v) => *v,
            None => report.train_rmse[report.best_epoch],
        };
        scores.push(score);
        if best.as_ref().is_none_or(|(_, _, s)| score < *s) {
            best = Some((mlp, report, score));
        }
    }
    let (mlp, mut report, _) = best.ok_or(NnError::BadConfig {
        field: "restarts",
        reason: "must be at least 1",
    })?;
    report.restart_scores = scores;
    Ok((mlp, report))
}

/// Trains `mlp` in place from its current weights (one run, no restarts).
///
/// With a non-empty validation set the weights of the best validation epoch are restored at
/// the end.
pub fn train_from(
    mlp: &mut Mlp,
    train: &Samples,
    val: Option<&Samples>,
    config: &TrainConfig,
) -> Result<TrainReport, NnError> {
    check_config(config)?;
    check_widths(mlp, train)?;
    if mlp.n_params() > MAX_LM_WEIGHTS {
        return Err(NnError::TooManyWeights {
            sizes: mlp.sizes().to_vec(),
            weights: mlp.n_params(),
            max: MAX_LM_WEIGHTS,
        });
    }
    if train.is_empty() {
        return Err(NnError::EmptyTrainingSet);
    }
    let val = val.filter(|v| !v.is_empty());
    if let Some(v) = val {
        check_widths(mlp, v)?;
    }

    let p = mlp.n_params();
    let n_res = (train.len() * mlp.n_out()) as f64;
    let mut eq = NormalEquations::new(mlp, train);
    let mut trial = mlp.clone();
    let mut scratch = vec![0.0; mlp.scratch_len() + mlp.n_out()];

    let mut cost = eq.assemble(mlp, train);
    let mut train_hist = vec![(cost / n_res).sqrt()];
    let mut val_hist = Vec::new();
    let mut best_val = f64::INFINITY;
    let mut best_weights = mlp.weights().to_vec();
    let mut best_epoch = 0;
    let mut stale_epochs = 0;
    let mut reference_val = f64::INFINITY;
    if let Some(v) = val {
        best_val = rmse(mlp, v, &mut scratch);
        reference_val = best_val;
        val_hist.push(best_val);
    }

    let mut mu = config.mu_init;
    let mut epochs = 0;
    let mut step = DVector::zeros(p);
    let stop_reason = loop {
        if train_hist[epochs] < config.target_rmse {
            break StopReason::TargetReached;
        }
        if epochs == config.max_epochs {
            break StopReason::MaxEpochs;
        }
        // Find a damping that decreases the loss.
        let accepted = loop {
            if mu > config.mu_max {
                break false;
            }
            if eq.solve_damped(mu, config.damping, &mut step) {
                let w: Vec<f64> = mlp
                    .weights()
                    .iter()
                    .zip(step.iter())
                    .map(|(w, d)| w + d)
                    .collect();
                if w.iter().all(|v| v.is_finite()) {
                    trial.set_weights(&w)?;
                    let c = sse(&trial, train, &mut scratch);
                    if c < cost {
                        mu = (mu / config.mu_factor).max(config.mu_min);
                        break true;
                    }
                }
            }
            mu *= config.mu_factor;
        };
        if !accepted {
            break StopReason::DampingLimit;
        }
        std::mem::swap(mlp, &mut trial);
        epochs += 1;
        cost = eq.assemble(mlp, train);
        train_hist.push((cost / n_res).sqrt());
        match val {
            Some(v) => {
                let rv = rmse(mlp, v, &mut scratch);
                val_hist.push(rv);
                if rv < best_val {
                    best_val = rv;
                    best_weights.copy_from_slice(mlp.weights());
                    best_epoch = epochs;
                }
                if rv < reference_val * (1.0 - config.min_rel_improvement) {
                    reference_val = rv;
                    stale_epochs = 0;
                } else {
                    stale_epochs += 1;
                    if stale_epochs >= config.patience {
                        break StopReason::EarlyStopping;
                    }
                }
            }
            None => best_epoch = epochs,
        }
    };
    if val.is_some() {
        mlp.set_weights(&best_weights)?;
    }
    Ok(TrainReport {
        epochs,
        train_rmse: train_hist,
        val_rmse: val_hist,
        best_epoch,
        stop_reason,
        restart: 0,
        init_seed: config.seed,
        restart_scores: Vec::new(),
    })
}

/// RMSE of `mlp` over all outputs of `data` (`scratch.len() >= scratch_len() + n_out`).
fn rmse(mlp: &Mlp, data: &Samples, scratch: &mut [f64]) -> f64 {
    (sse(mlp, data, scratch) / (data.len() * mlp.n_out()) as f64).sqrt()
}

/// Sum of squared residuals of `mlp` over `data`.
fn sse(mlp: &Mlp, data: &Samples, scratch: &mut [f64]) -> f64 {
    let (buf, out) = scratch.split_at_mut(mlp.scratch_len());
    let out = &mut out[..mlp.n_out()];
    let mut s = 0.0;
    for i in 0..data.len() {
        mlp.forward_unchecked(data.input(i), buf, out);
        s += out
            .iter()
            .zip(data.target(i))
            .map(|(o, t)| (o - t) * (o - t))
            .sum::<f64>();
    }
    s
}

/// The LM normal equations `JᵀJ`, `Jᵀr` and their work buffers.
struct NormalEquations {
    jtj: DMatrix<f64>,
    jtr: DVector<f64>,
    /// Jᵀ of one block: column c is the Jacobian row of residual c (contiguous).
    jt_block: DMatrix<f64>,
    r_block: DVector<f64>,
    work: Vec<f64>,
    y: Vec<f64>,
    samples_per_block: usize,
}

impl NormalEquations {
    fn new(mlp: &Mlp, train: &Samples) -> Self {
        let p = mlp.n_params();
        let n_out = mlp.n_out();
        let samples_per_block = (BLOCK_ROWS / n_out).clamp(1, train.len().max(1));
        let cols = samples_per_block * n_out;
        Self {
            jtj: DMatrix::zeros(p, p),
            jtr: DVector::zeros(p),
            jt_block: DMatrix::zeros(p, cols),
            r_block: DVector::zeros(cols),
            work: vec![0.0; mlp.jacobian_work_len()],
            y: vec![0.0; n_out],
            samples_per_block,
        }
    }

    /// Fills `JᵀJ` and `Jᵀr` at the current weights; returns the sum of squared residuals.
    fn assemble(&mut self, mlp: &Mlp, train: &Samples) -> f64 {
        let p = mlp.n_params();
        let n_out = mlp.n_out();
        self.jtj.fill(0.0);
        self.jtr.fill(0.0);
        let mut cost = 0.0;
        let mut start = 0;
        while start < train.len() {
            let end = (start + self.samples_per_block).min(train.len());
            let cols = (end - start) * n_out;
            {
                let jt = self.jt_block.as_mut_slice();
                for (b, i) in (start..end).enumerate() {
                    let jac = &mut jt[b * n_out * p..(b + 1) * n_out * p];
                    mlp.jacobian_unchecked(train.input(i), &mut self.work, &mut self.y, jac);
                    for (k, (yk, tk)) in self.y.iter().zip(train.target(i)).enumerate() {
                        self.r_block[b * n_out + k] = yk - tk;
                    }
                }
            }
            let jt = self.jt_block.columns(0, cols);
            let j = jt.transpose();
            self.jtj.gemm(1.0, &jt, &j, 1.0);
            let r = self.r_block.rows(0, cols);
            self.jtr.gemv(1.0, &jt, &r, 1.0);
            cost += r.norm_squared();
            start = end;
        }
        cost
    }

    /// Solves `(JᵀJ + μ·D) δ = −Jᵀr` into `step`; false when the matrix is not positive definite.
    fn solve_damped(&self, mu: f64, damping: Damping, step: &mut DVector<f64>) -> bool {
        let max_diag = self.jtj.diagonal().max();
        let floor = 1e-12 * max_diag.max(f64::MIN_POSITIVE);
        let mut a = self.jtj.clone();
        for i in 0..a.nrows() {
            a[(i, i)] += mu
                * match damping {
                    Damping::Levenberg => 1.0,
                    Damping::Marquardt => self.jtj[(i, i)].max(floor),
                };
        }
        match a.cholesky() {
            Some(ch) => {
                step.copy_from(&(-&self.jtr));
                ch.solve_mut(step);
                step.iter().all(|v| v.is_finite())
            }
            None => false,
        }
    }
}

fn check_widths(mlp: &Mlp, data: &Samples) -> Result<(), NnError> {
    if data.n_in() != mlp.n_in() || data.n_out() != mlp.n_out() {
        return Err(NnError::WidthMismatch {
            net_in: mlp.n_in(),
            net_out: mlp.n_out(),
            data_in: data.n_in(),
            data_out: data.n_out(),
        });
    }
    Ok(())
}

fn check_config(c: &TrainConfig) -> Result<(), NnError> {
    let bad = |field, reason| Err(NnError::BadConfig { field, reason });
    if c.restarts == 0 {
        return bad("restarts", "must be at least 1");
    }
    if c.patience == 0 {
        return bad("patience", "must be at least 1");
    }
    if !(c.mu_init > 0.0 && c.mu_min > 0.0 && c.mu_max >= c.mu_init && c.mu_max.is_finite()) {
        return bad(
            "mu_init/mu_min/mu_max",
            "need 0 < mu_min, 0 < mu_init ≤ mu_max < ∞",
        );
    }
    if !(c.mu_factor > 1.0 && c.mu_factor.is_finite()) {
        return bad("mu_factor", "must be a finite number > 1");
    }
    if !(c.min_rel_improvement >= 0.0 && c.min_rel_improvement < 1.0) {
        return bad("min_rel_improvement", "must be in [0, 1)");
    }
    if c.target_rmse.is_nan() || c.target_rmse < 0.0 {
        return bad("target_rmse", "must be ≥ 0");
    }
    Ok(())
}

/// SplitMix64 finaliser: a fixed, well-mixed map from restart index to seed.
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn sine_samples(n: usize, noise: f64, seed: u64) -> Samples {
        let mut rng = StdRng::seed_from_u64(seed);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let x: Vec<f64> = (0..n)
            .map(|i| -1.5 + 3.0 * i as f64 / (n - 1) as f64)
            .collect();
        let y = x
            .iter()
            .map(|v| (2.0 * v).sin() + noise * normal.sample(&mut rng))
            .collect();
        Samples::new(1, 1, x, y).unwrap()
    }

    #[test]
    fn a_net_too_large_for_the_normal_equations_is_refused_before_any_allocation() {
        let data = sine_samples(10, 0.0, 0);
        let config = TrainConfig::default();
        // 1 → 100000 → 1: 300001 weights (a 720 GB normal matrix).
        let err = train(&[1, 100_000, 1], &data, None, &config).unwrap_err();
        assert_eq!(
            err,
            NnError::TooManyWeights {
                sizes: vec![1, 100_000, 1],
                weights: 300_001,
                max: MAX_LM_WEIGHTS
            }
        );
        assert!(
            err.to_string().contains("use smaller hidden widths"),
            "{err}"
        );
        // Absurd widths saturate instead of overflowing.
        assert!(matches!(
            train(&[1, usize::MAX, 1], &data, None, &config),
            Err(NnError::TooManyWeights {
                weights: usize::MAX,
                ..
            })
        ));
        // The bound counts weights and biases: 1 → 1364 → 1 has 4093 and passes the check,
        // 1 → 1366 → 1 has 4099 and does not.
        assert_eq!(weight_count(&[1, 1364, 1]), 4093);
        assert!(check_weight_count(&[1, 1364, 1]).is_ok());
        assert!(check_weight_count(&[1, 1366, 1]).is_err());
    }

    #[test]
    fn training_is_bit_identical_for_a_seed_and_differs_for_another() {
        let data = sine_samples(40, 0.0, 0);
        let config = TrainConfig {
            max_epochs: 15,
            seed: 11,
            ..TrainConfig::default()
        };
        let (a, ra) = train(&[1, 5, 1], &data, None, &config).unwrap();
        let (b, rb) = train(&[1, 5, 1], &data, None, &config).unwrap();
        let other = TrainConfig { seed: 12, ..config };
        let (c, _) = train(&[1, 5, 1], &data, None, &other).unwrap();
        assert_eq!(a.weights(), b.weights());
        assert_eq!(ra, rb);
        assert_ne!(a.weights(), c.weights());
    }

    #[test]
    fn lm_decreases_the_training_loss_monotonically_with_either_damping() {
        let data = sine_samples(40, 0.0, 0);
        for damping in [Damping::Levenberg, Damping::Marquardt] {
            let config = TrainConfig {
                max_epochs: 60,
                damping,
                ..TrainConfig::default()
            };
            let (_, report) = train(&[1, 6, 1], &data, None, &config).unwrap();
            assert!(report.train_rmse.windows(2).all(|w| w[1] < w[0]));
            // A 1-6-1 net fits sin(2x) on [−1.5, 1.5] far better than 2 % of its spread.
            assert!(
                report.train_rmse[report.epochs] < 0.02 * report.train_rmse[0],
                "{damping:?}: {report:?}"
            );
        }
    }

    #[test]
    fn early_stopping_triggers_when_a_big_net_overfits_noisy_data() {
        // 16 noisy points, 61 weights: the net can thread every noisy point, so the validation
        // error (independent noise on the same curve) must turn up long before 500 epochs.
        let train_set = sine_samples(16, 0.3, 1);
        let val = sine_samples(16, 0.3, 2);
        let config = TrainConfig {
            max_epochs: 500,
            patience: 5,
            ..TrainConfig::default()
        };
        let (mlp, report) = train(&[1, 20, 1], &train_set, Some(&val), &config).unwrap();
        assert_eq!(report.stop_reason, StopReason::EarlyStopping);
        assert!(report.epochs < 500);
        assert!(report.best_epoch < report.epochs);
        // The kept weights are those of the best validation epoch.
        let best = report
            .val_rmse
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let mut scratch = vec![0.0; mlp.scratch_len() + 1];
        assert_eq!(rmse(&mlp, &val, &mut scratch), best);
        assert_eq!(report.val_rmse[report.best_epoch], best);
        // Over-fitting happened: training error at the end is below the kept epoch's.
        assert!(report.train_rmse[report.epochs] < report.train_rmse[report.best_epoch]);
    }

    #[test]
    fn restarts_keep_the_best_scoring_run() {
        let train_set = sine_samples(30, 0.05, 3);
        let val = sine_samples(17, 0.05, 4);
        let config = TrainConfig {
            max_epochs: 10,
            restarts: 3,
            ..TrainConfig::default()
        };
        let (_, report) = train(&[1, 4, 1], &train_set, Some(&val), &config).unwrap();
        assert_eq!(report.restart_scores.len(), 3);
        let min = report
            .restart_scores
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        assert_eq!(report.restart_scores[report.restart], min);
        assert_eq!(report.val_rmse[report.best_epoch], min);
    }

    #[test]
    fn mismatched_data_and_bad_settings_are_errors() {
        let data = sine_samples(10, 0.0, 0);
        let mut mlp = Mlp::zeros(&[2, 3, 1]).unwrap();
        assert!(matches!(
            train_from(&mut mlp, &data, None, &TrainConfig::default()),
            Err(NnError::WidthMismatch { .. })
        ));
        let bad = TrainConfig {
            restarts: 0,
            ..TrainConfig::default()
        };
        assert!(matches!(
            train(&[1, 3, 1], &data, None, &bad),
            Err(NnError::BadConfig {
                field: "restarts",
                ..
            })
        ));
        let empty = Samples::new(1, 1, vec![], vec![]).unwrap();
        assert_eq!(
            train(&[1, 3, 1], &empty, None, &TrainConfig::default()).err(),
            Some(NnError::EmptyTrainingSet)
        );
    }
}
