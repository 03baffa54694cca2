//! Arguments of `fit-thermal` and `predict-thermal` (thermal-drift models from a user's
//! measurements).

use std::path::PathBuf;

use anyhow::{Context, Result};

use super::ForceArg;
use crate::commands::thermal::{FitThermalConfig, PredictThermalConfig};
use crate::predict::thermal_fit::{Architecture, FeatureSpec, FitSettings};

/// Arguments of `fit-thermal`.
#[derive(clap::Args)]
pub struct FitThermalArgs {
    /// Measurements (CSV: header of column names with units, one row per sample, a time column).
    #[arg(long)]
    pub data: PathBuf,
    /// Input columns (comma-separated), e.g. t1_degc,t2_degc or with spindle_rpm.
    #[arg(long, value_delimiter = ',', required = true)]
    pub inputs: Vec<String>,
    /// Output (drift) columns to model (comma-separated), e.g. ch1_um,ch2_um.
    #[arg(long, value_delimiter = ',', required = true)]
    pub outputs: Vec<String>,
    /// Output model file (JSON).
    #[arg(short = 'o', long, default_value = "thermal_model.json")]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
    /// Time column; default: the only column whose name starts with "time" (unit _s, _min, _h).
    #[arg(long)]
    pub time: Option<String>,
    /// Start of the held-out part, s (on the file's time axis). Default: the start of the last
    /// cycle of --cycle-col, else the last quarter of the time span.
    #[arg(long)]
    pub holdout_from_s: Option<f64>,
    /// Column whose rise from 0 starts a cycle (default: spindle_rpm if the file has it); the
    /// validation part is the cycle before the held-out one.
    #[arg(long)]
    pub cycle_col: Option<String>,
    /// Fraction of the rows before the held-out part (the last ones) that validate.
    #[arg(long, default_value_t = 0.25)]
    pub val_fraction: f64,
    /// Forms allowed, per output the best by leave-one-cycle-out cross-validation: linear-mlp
    /// (plain least squares, filter-bank linear or linear + MLP on its residual), auto (the same
    /// and an MLP), mlp (MLP only), or linear (plain least squares or filter-bank linear).
    #[arg(long, default_value = "linear-mlp")]
    pub arch: String,
    /// Time constants of the low-pass filter bank, s (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [900.0, 3600.0, 10800.0])]
    pub tau_s: Vec<f64>,
    /// Scales of the filter bank's time constants tried (comma-separated); the best by
    /// leave-one-cycle-out cross-validation is kept.
    #[arg(long, value_delimiter = ',', default_values_t = [0.5, 1.0, 2.0])]
    pub tau_scales: Vec<f64>,
    /// Exponents k of the heat-input features (|speed|/1000 rpm)^k of speed inputs (columns
    /// whose unit is rpm, e.g. spindle_rpm): each as is and through the low-pass bank
    /// (comma-separated; "none": speed inputs are filtered like temperatures).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3")]
    pub speed_exponents: Vec<String>,
    /// Temperatures as differences to their mean at each row (gradients; blind to a uniform
    /// change of all temperatures).
    #[arg(long)]
    pub relative_to_mean: bool,
    /// Hidden widths tried (comma-separated); the best on validation is kept.
    #[arg(long, value_delimiter = ',', default_values_t = [4usize, 8])]
    pub hidden: Vec<usize>,
    /// Ridge λ candidates of the linear part (on normalised slopes; comma-separated); per
    /// output the best by leave-one-cycle-out cross-validation is kept.
    #[arg(long, value_delimiter = ',', default_values_t = [0.01, 0.1, 1.0, 10.0, 100.0, 1e3, 1e4])]
    pub ridge: Vec<f64>,
    /// Members of each MLP ensemble (their predictions are averaged).
    #[arg(long, default_value_t = 5)]
    pub ensemble: usize,
    /// Seed of the network initialisation.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Keep the evaluated model (fitted before the held-out part) instead of fitting the chosen
    /// form again on every row.
    #[arg(long)]
    pub no_refit: bool,
    /// Most data rows read (a work limit: the fit's memory and time grow with the rows times
    /// the candidates); raise it for a longer file, or resample the file to a coarser step.
    #[arg(long, default_value_t = crate::commands::thermal::DEFAULT_MAX_ROWS)]
    pub max_rows: usize,
}

/// Arguments of `predict-thermal`.
#[derive(clap::Args)]
pub struct PredictThermalArgs {
    /// Model file from `fit-thermal`.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements with (at least) the model's input columns and a time column.
    #[arg(long)]
    pub data: PathBuf,
    /// Output predictions (CSV).
    #[arg(short = 'o', long, default_value = "pred.csv")]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
    /// Time column; default: the only column whose name starts with "time".
    #[arg(long)]
    pub time: Option<String>,
    /// Earlier measurements (same columns, ending before the data begins) that set the
    /// filters' state; not predicted.
    #[arg(long)]
    pub history: Option<PathBuf>,
    /// Refuse, rather than warn, when the data and history cover less than the model's memory.
    #[arg(long)]
    pub strict: bool,
    /// The data begins with the machine at rest (idle long enough to be at steady state): no
    /// history is needed.
    #[arg(long, conflicts_with = "history")]
    pub starts_at_rest: bool,
}

impl FitThermalArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unknown `--arch` or a `--speed-exponents` value that is not a number.
    pub fn config(self) -> Result<FitThermalConfig> {
        let architecture = Architecture::parse(&self.arch).with_context(|| {
            format!(
                "--arch must be auto, linear-mlp, mlp or linear, got \"{}\"",
                self.arch
            )
        })?;
        let settings = FitSettings {
            features: FeatureSpec {
                time_constants_s: self.tau_s,
                speed_exponents: parse_exponents(&self.speed_exponents)?,
                relative_to_mean: self.relative_to_mean,
            },
            architecture,
            hidden_candidates: self.hidden,
            ridge_candidates: self.ridge,
            tau_scales: self.tau_scales,
            val_fraction: self.val_fraction,
            seed: self.seed,
            ensemble: self.ensemble,
            refit_all: !self.no_refit,
            ..FitSettings::default()
        };
        Ok(FitThermalConfig {
            data: self.data,
            inputs: self.inputs,
            outputs: self.outputs,
            out: self.out,
            force: self.force.force,
            time: self.time,
            holdout_from_s: self.holdout_from_s,
            cycle_col: self.cycle_col,
            settings,
            max_rows: self.max_rows,
        })
    }
}

/// `--speed-exponents`: numbers, or the single word `none`.
fn parse_exponents(values: &[String]) -> Result<Vec<f64>> {
    if values.len() == 1 && values[0].trim() == "none" {
        return Ok(Vec::new());
    }
    values
        .iter()
        .map(|v| {
            v.trim().parse::<f64>().with_context(|| {
                format!("--speed-exponents: \"{v}\" is not a number (or give \"none\")")
            })
        })
        .collect()
}

impl PredictThermalArgs {
    /// The config (nothing to validate before reading the files).
    pub fn config(self) -> PredictThermalConfig {
        PredictThermalConfig {
            model: self.model,
            data: self.data,
            out: self.out,
            force: self.force.force,
            time: self.time,
            history: self.history,
            strict: self.strict,
            starts_at_rest: self.starts_at_rest,
        }
    }
}
