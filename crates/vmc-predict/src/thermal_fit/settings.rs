//! The settings of a thermal-drift fit.

use serde::{Deserialize, Serialize};

use super::features::FeatureSpec;
use super::model::Architecture;
use super::ThermalFitError;

/// Settings of [`super::fit`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitSettings {
    /// Feature construction (default: [`FeatureSpec::default`]).
    pub features: FeatureSpec,
    /// Forms allowed (default: [`Architecture::LinearMlp`]: plain least squares, linear, or
    /// linear plus the residual net, per output the best by cross-validation).
    pub architecture: Architecture,
    /// Hidden widths tried per net; the best on validation is kept (default: 4, 8).
    pub hidden_candidates: Vec<usize>,
    /// Ridge λ candidates of the linear part, on normalised slopes; per output, the best by
    /// leave-one-cycle-out cross-validation is kept (default: 0.01, 0.1, …, 10⁴ by decades: the
    /// thermometers of a machine are strongly correlated and a few cycles cannot pin dozens of
    /// slopes; how much to shrink them is a question for the held-out cycles).
    pub ridge_candidates: Vec<f64>,
    /// Scales of the filter bank's time constants tried (default: 0.5, 1, 2: the bank as given,
    /// twice as fast, twice as slow); the best by cross-validation (mean over the outputs) is
    /// kept.
    pub tau_scales: Vec<f64>,
    /// Fraction of the pre-held-out rows (the last ones) that validate when no cycle column
    /// gives the cycle before the held-out one, and of a fold's fitting rows that early-stop
    /// its nets when it has a single cycle to fit (default: 0.25).
    pub val_fraction: f64,
    /// The nets train on rows at least this far apart, s (default: 60 s; neighbouring 15 s
    /// rows are near copies and only cost Jacobian rows). The linear part uses every row.
    pub min_train_step_s: f64,
    /// Seed of the network initialisation (default: 0).
    pub seed: u64,
    /// Members of each net ensemble, each from its own seeded initialisation (default: 5).
    pub ensemble: usize,
    /// Maximum LM iterations (default: 100).
    pub max_epochs: usize,
    /// Epochs without validation improvement before stopping (default: 8).
    pub patience: usize,
    /// Once the form is chosen and evaluated, fit the kept model again on every row, the
    /// held-out part included (default: true): a user's model should learn from all the cycles
    /// measured. The evaluation stays that of the model before the refit.
    pub refit_all: bool,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            features: FeatureSpec::default(),
            architecture: Architecture::LinearMlp,
            hidden_candidates: vec![4, 8],
            ridge_candidates: vec![0.01, 0.1, 1.0, 10.0, 100.0, 1e3, 1e4],
            tau_scales: vec![0.5, 1.0, 2.0],
            val_fraction: 0.25,
            min_train_step_s: 60.0,
            seed: 0,
            ensemble: 5,
            max_epochs: 100,
            patience: 8,
            refit_all: true,
        }
    }
}

impl FitSettings {
    /// The candidate scales of the filter bank's time constants (just 1 without filters).
    ///
    /// # Errors
    /// No scale, or one that is not finite and positive.
    pub(super) fn scales(&self) -> Result<Vec<f64>, ThermalFitError> {
        if self.features.time_constants_s.is_empty() {
            return Ok(vec![1.0]);
        }
        if self.tau_scales.is_empty()
            || self.tau_scales.iter().any(|s| !(s.is_finite() && *s > 0.0))
        {
            return Err(ThermalFitError::BadSettings {
                field: "tau_scales",
                reason: format!(
                    "need at least one finite positive scale, got {:?}",
                    self.tau_scales
                ),
            });
        }
        Ok(self.tau_scales.clone())
    }

    /// The feature spec with its time constants multiplied by `scale`.
    pub(super) fn scaled_features(&self, scale: f64) -> FeatureSpec {
        let mut f = self.features.clone();
        f.time_constants_s.iter_mut().for_each(|t| *t *= scale);
        f
    }
}
