//! Helpers shared by the fit and its cross-validation: samples of row subsets, RMSE, linear
//! and net predictions, the net ensembles, plain least squares.

use super::settings::FitSettings;
use super::ThermalFitError;
use crate::linreg::LinearModel;
use crate::nn::{Regressor, Samples, TrainConfig};

/// Feature rows and per-output target columns restricted to `rows`, as training samples.
pub(super) fn samples(
    feats: &[f64],
    width: usize,
    targets: &[Vec<f64>],
    rows: &[usize],
) -> Result<Samples, ThermalFitError> {
    let mut x = Vec::with_capacity(rows.len() * width);
    let mut y = Vec::with_capacity(rows.len() * targets.len());
    for &r in rows {
        x.extend_from_slice(&feats[r * width..(r + 1) * width]);
        y.extend(targets.iter().map(|c| c[r]));
    }
    Ok(Samples::new(width, targets.len(), x, y).map_err(crate::nn::NnError::from)?)
}

/// Per-output RMSE of `pred` (output-major) against `truth` over `rows`.
pub(super) fn rmse(truth: &[Vec<f64>], pred: &[Vec<f64>], rows: &[usize]) -> Vec<f64> {
    truth
        .iter()
        .zip(pred)
        .map(|(y, p)| {
            let ss: f64 = rows.iter().map(|&r| (y[r] - p[r]).powi(2)).sum();
            (ss / rows.len().max(1) as f64).sqrt()
        })
        .collect()
}

/// Mean over outputs of validation RMSE / the output's standard deviation on the fitting rows
/// (a unit-free score to compare candidates).
pub(super) fn val_score(
    y: &[Vec<f64>],
    pred: &[Vec<f64>],
    fit_rows: &[usize],
    val_rows: &[usize],
) -> f64 {
    let errs = rmse(y, pred, val_rows);
    let n = fit_rows.len().max(1) as f64;
    errs.iter()
        .zip(y)
        .map(|(e, c)| {
            let m = fit_rows.iter().map(|&r| c[r]).sum::<f64>() / n;
            let sd = (fit_rows.iter().map(|&r| (c[r] - m).powi(2)).sum::<f64>() / n).sqrt();
            e / sd.max(f64::MIN_POSITIVE)
        })
        .sum::<f64>()
        / errs.len().max(1) as f64
}

/// Rows at least `min_step_s` apart (the first row always kept).
pub(super) fn thin_rows(rows: &[usize], time_s: &[f64], min_step_s: f64) -> Vec<usize> {
    let mut thin: Vec<usize> = Vec::new();
    for &r in rows {
        if thin
            .last()
            .is_none_or(|&l| time_s[r] - time_s[l] >= min_step_s)
        {
            thin.push(r);
        }
    }
    thin
}

/// Predictions of every row (output-major) by `f(x, out)`.
pub(super) fn predict_rows(
    feats: &[f64],
    width: usize,
    n_out: usize,
    mut f: impl FnMut(&[f64], &mut [f64]),
) -> Vec<Vec<f64>> {
    let n = feats.len() / width;
    let mut out = vec![vec![0.0; n]; n_out];
    let mut o = vec![0.0; n_out];
    for r in 0..n {
        f(&feats[r * width..(r + 1) * width], &mut o);
        for (c, v) in out.iter_mut().zip(&o) {
            c[r] = *v;
        }
    }
    out
}

pub(super) fn predict_linear(
    m: &LinearModel,
    feats: &[f64],
    width: usize,
    n_out: usize,
) -> Vec<Vec<f64>> {
    // Widths match by construction, so predict_into cannot fail here.
    predict_rows(feats, width, n_out, |x, o| {
        let _ = m.predict_into(x, o);
    })
}

pub(super) fn predict_net(
    m: &Regressor,
    feats: &[f64],
    width: usize,
    n_out: usize,
) -> Vec<Vec<f64>> {
    let mut scratch = vec![0.0; m.scratch_len()];
    predict_rows(feats, width, n_out, |x, o| {
        let _ = m.predict_into(x, &mut scratch, o);
    })
}

/// `a − b` column by column.
pub(super) fn minus(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(u, v)| u.iter().zip(v).map(|(p, q)| p - q).collect())
        .collect()
}

/// `a + b` column by column.
pub(super) fn plus(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(u, v)| u.iter().zip(v).map(|(p, q)| p + q).collect())
        .collect()
}

/// A net ensemble on `target` over `fit_rows` (thinned). With `val_rows`: for every candidate
/// width, `ensemble` members each early-stopped there, the width whose averaged prediction
/// scores best kept. With `fixed` = (width, epochs per member): exactly that.
/// Returns the members, their width and the epochs each trained (its best epoch).
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_net(
    feats: &[f64],
    width: usize,
    target: &[Vec<f64>],
    time_s: &[f64],
    fit_rows: &[usize],
    val_rows: Option<&[usize]>,
    fixed: Option<(usize, &[usize])>,
    settings: &FitSettings,
    salt: u64,
) -> Result<Net, ThermalFitError> {
    let thin = thin_rows(fit_rows, time_s, settings.min_train_step_s);
    let tr = samples(feats, width, target, &thin)?;
    let va = match val_rows {
        Some(v) => Some(samples(feats, width, target, v)?),
        None => None,
    };
    let widths: Vec<usize> = match fixed {
        Some((h, _)) => vec![h],
        None => settings.hidden_candidates.clone(),
    };
    if widths.is_empty() || widths.contains(&0) || settings.ensemble == 0 {
        return Err(ThermalFitError::BadSettings {
            field: "hidden_candidates / ensemble",
            reason: format!(
                "need widths ≥ 1 and at least one member, got {widths:?} and {}",
                settings.ensemble
            ),
        });
    }
    let n_out = target.len();
    let mut best: Option<(Net, f64)> = None;
    for &h in &widths {
        let mut members = Vec::new();
        let mut epochs = Vec::new();
        for m in 0..settings.ensemble {
            let config = TrainConfig {
                seed: settings.seed
                    ^ (h as u64 + 64 * salt + 4096 * m as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
                restarts: 1,
                max_epochs: fixed.map_or(settings.max_epochs, |f| {
                    f.1.get(m).copied().unwrap_or(1).max(1)
                }),
                patience: settings.patience,
                ..TrainConfig::default()
            };
            let (reg, report) = Regressor::fit(&tr, va.as_ref(), &[h], &config)?;
            epochs.push(report.best_epoch.max(1));
            members.push(reg);
        }
        let net = Net {
            members,
            hidden: h,
            epochs,
        };
        let score = match val_rows {
            Some(v) => val_score(target, &net.predict(feats, width, n_out), fit_rows, v),
            None => 0.0,
        };
        if best.as_ref().is_none_or(|b| score < b.1) {
            best = Some((net, score));
        }
    }
    best.map(|b| b.0)
        .ok_or_else(|| ThermalFitError::BadSettings {
            field: "hidden_candidates",
            reason: "no width tried".into(),
        })
}

/// A fitted net ensemble.
pub(super) struct Net {
    /// The members.
    pub members: Vec<Regressor>,
    /// Their hidden width.
    pub hidden: usize,
    /// The LM epochs each trained.
    pub epochs: Vec<usize>,
}

impl Net {
    /// The members' mean prediction of every row.
    pub(super) fn predict(&self, feats: &[f64], width: usize, n_out: usize) -> Vec<Vec<f64>> {
        let mut sum = vec![vec![0.0; feats.len() / width]; n_out];
        for m in &self.members {
            sum = plus(&sum, &predict_net(m, feats, width, n_out));
        }
        let w = 1.0 / self.members.len().max(1) as f64;
        sum.iter()
            .map(|c| c.iter().map(|v| v * w).collect())
            .collect()
    }
}

/// Plain least squares on the raw inputs (intercept and one slope per input column as read: no
/// filters, no ridge) fitted on `rows` of the row-major `raw` input rows (`width` inputs): the
/// baseline a user would try first. The model and its predictions of every row, output-major.
pub(super) fn plain_least_squares(
    raw: &[f64],
    width: usize,
    y: &[Vec<f64>],
    rows: &[usize],
) -> Result<(LinearModel, Vec<Vec<f64>>), ThermalFitError> {
    let m = LinearModel::fit(&samples(raw, width, y, rows)?, 0.0)?;
    let pred = predict_linear(&m, raw, width, y.len());
    Ok((m, pred))
}

/// A linear model on `rows` with its own ridge λ per output (`ridges[k]`): one fit per distinct
/// λ, each output's coefficients taken from the fit with its λ (ridge regression treats the
/// outputs independently). The model's recorded ridge is the largest λ used.
pub(super) fn fit_linear_per_output(
    feats: &[f64],
    width: usize,
    y: &[Vec<f64>],
    rows: &[usize],
    ridges: &[f64],
) -> Result<LinearModel, ThermalFitError> {
    let data = samples(feats, width, y, rows)?;
    let mut fits: Vec<(f64, LinearModel)> = Vec::new();
    for &l in ridges {
        if !fits.iter().any(|(f, _)| *f == l) {
            fits.push((l, LinearModel::fit(&data, l)?));
        }
    }
    let mut intercept = Vec::with_capacity(y.len());
    let mut slopes = Vec::with_capacity(y.len() * width);
    for (k, l) in ridges.iter().enumerate() {
        if let Some((_, m)) = fits.iter().find(|(f, _)| f == l) {
            intercept.push(m.intercept()[k]);
            slopes.extend_from_slice(&m.slopes()[k * width..(k + 1) * width]);
        }
    }
    let max_ridge = ridges.iter().copied().fold(0.0, f64::max);
    Ok(LinearModel::from_coefficients(
        width, intercept, slopes, max_ridge,
    ))
}
