//! Leave-one-cycle-out cross-validation: the choice of the filter-bank width, the ridge λ of
//! each output and each output's form.
//!
//! Folds: with at least two cycles (see [`super::Split::cycles`]), each cycle is held out once
//! and every other row fits; otherwise a single fold, the training part fitting and the
//! validation part held out. A fold's score for an output is its held-out residual RMS divided
//! by the raw drift RMS of the held-out rows (what is left with no compensation); candidates are
//! compared by the mean of that ratio over the folds.
//!
//! Order of the choices (each on the mean fold ratio):
//! 1. per scale of the filter bank's time constants, per output, the ridge λ of the filter-bank
//!    linear form; then the scale whose best λ give the lowest mean over the outputs;
//! 2. per output, the form among those the [`Architecture`] allows: plain least squares on the
//!    raw inputs, the filter-bank linear form, linear + residual net, net. A fold's nets
//!    early-stop on its last fitting cycle (or on the last rows of its fitting part when it has
//!    a single cycle to fit) and train on the rest. Ties (within a millionth) keep the simpler
//!    form, in the order plain least squares, linear, linear + residual net, net.
//!
//! The features are causal, computed once over the whole series: a held-out cycle's features
//! carry the history of the cycles before it, as they would when the model runs on a machine.

use super::common::{
    fit_linear_per_output, fit_net, minus, plain_least_squares, plus, predict_linear, rmse,
};
use super::model::{Architecture, FoldScore, OutputModel};
use super::settings::FitSettings;
use super::ThermalFitError;
use crate::linreg::LinearModel;

use super::common::samples;

/// One fold: rows that fit, rows held out, and the split of the fitting rows for the nets'
/// early stopping.
pub(super) struct Fold {
    /// Fitting rows (time order).
    pub fit: Vec<usize>,
    /// Held-out rows.
    pub test: Vec<usize>,
    /// Rows the nets train on.
    pub net_fit: Vec<usize>,
    /// Rows the nets early-stop on.
    pub net_stop: Vec<usize>,
}

/// The folds (see the module doc). `cycles`: rows per cycle; `train`, `val`: the split's parts,
/// used when there are fewer than two cycles.
pub(super) fn folds(
    cycles: &[Vec<usize>],
    train: &[usize],
    val: &[usize],
    val_fraction: f64,
) -> Vec<Fold> {
    if cycles.len() < 2 {
        return vec![Fold {
            fit: train.to_vec(),
            test: val.to_vec(),
            net_fit: train.to_vec(),
            net_stop: val.to_vec(),
        }];
    }
    (0..cycles.len())
        .map(|i| {
            let others: Vec<usize> = (0..cycles.len()).filter(|&j| j != i).collect();
            let fit: Vec<usize> = others.iter().flat_map(|&j| cycles[j].clone()).collect();
            let (net_fit, net_stop) = if others.len() >= 2 {
                let last = others[others.len() - 1];
                let rest = others[..others.len() - 1]
                    .iter()
                    .flat_map(|&j| cycles[j].clone())
                    .collect();
                (rest, cycles[last].clone())
            } else {
                let n_stop = ((fit.len() as f64) * val_fraction).round() as usize;
                let cut = fit.len().saturating_sub(n_stop.max(1));
                (fit[..cut].to_vec(), fit[cut..].to_vec())
            };
            Fold {
                fit,
                test: cycles[i].clone(),
                net_fit,
                net_stop,
            }
        })
        .collect()
}

/// The data the cross-validation sees.
pub(super) struct CvData<'a> {
    /// Feature rows (row-major) for each candidate scale.
    pub feats: &'a [Vec<f64>],
    /// Feature width.
    pub width: usize,
    /// Raw input rows (row-major), `n_in` wide.
    pub raw: &'a [f64],
    /// Number of raw inputs.
    pub n_in: usize,
    /// Outputs, one column each.
    pub y: &'a [Vec<f64>],
    /// Time of each row, s.
    pub time_s: &'a [f64],
}

/// What the cross-validation chose, and its scores.
pub(super) struct CvChoice {
    /// Index of the chosen scale.
    pub scale: usize,
    /// Ridge λ per output.
    pub ridges: Vec<f64>,
    /// Form per output.
    pub forms: Vec<OutputModel>,
    /// Mean fold ratio per output: chosen form, filter-bank linear, plain least squares.
    pub model: Vec<f64>,
    /// The same for the filter-bank linear form.
    pub linear: Vec<f64>,
    /// The same for plain least squares (None if singular in some fold).
    pub plain: Vec<Option<f64>>,
    /// The folds' scores of the chosen forms and of plain least squares.
    pub folds: Vec<FoldScore>,
}

/// Relative margin by which a form must lower the mean fold ratio to replace a simpler one
/// (round-off ties keep the simpler form).
const TIE: f64 = 1e-6;

/// Per output, RMSE on `rows` / RMS of the measured values there.
fn ratios(y: &[Vec<f64>], pred: &[Vec<f64>], rows: &[usize]) -> Vec<f64> {
    let raw = raw_rms(y, rows);
    rmse(y, pred, rows)
        .iter()
        .zip(&raw)
        .map(|(e, r)| e / r.max(f64::MIN_POSITIVE))
        .collect()
}

/// Per output, RMS of the measured values on `rows`.
fn raw_rms(y: &[Vec<f64>], rows: &[usize]) -> Vec<f64> {
    let zero = vec![vec![0.0; y.first().map_or(0, Vec::len)]; y.len()];
    rmse(y, &zero, rows)
}

/// Mean over folds of per-output vectors.
fn mean(per_fold: &[Vec<f64>], n_out: usize) -> Vec<f64> {
    let n = per_fold.len().max(1) as f64;
    (0..n_out)
        .map(|k| per_fold.iter().map(|f| f[k]).sum::<f64>() / n)
        .collect()
}

/// Runs the cross-validation (see the module doc).
pub(super) fn cross_validate(
    data: &CvData,
    folds: &[Fold],
    settings: &FitSettings,
) -> Result<CvChoice, ThermalFitError> {
    let (y, width, n_out) = (data.y, data.width, data.y.len());
    let lambdas = &settings.ridge_candidates;
    if lambdas.is_empty() {
        return Err(ThermalFitError::BadSettings {
            field: "ridge_candidates",
            reason: "need at least one ridge value".into(),
        });
    }
    // 1. Per scale and λ: mean fold ratio per output.
    let mut best: Option<(usize, Vec<f64>, Vec<f64>, f64)> = None;
    for (s, feats) in data.feats.iter().enumerate() {
        let mut per_lambda = Vec::with_capacity(lambdas.len());
        for &l in lambdas {
            let mut per_fold = Vec::with_capacity(folds.len());
            for f in folds {
                let m = LinearModel::fit(&samples(feats, width, y, &f.fit)?, l)?;
                per_fold.push(ratios(y, &predict_linear(&m, feats, width, n_out), &f.test));
            }
            per_lambda.push(mean(&per_fold, n_out));
        }
        let mut ridges = Vec::with_capacity(n_out);
        let mut scores = Vec::with_capacity(n_out);
        for k in 0..n_out {
            let (i, v) = per_lambda
                .iter()
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |b, (i, r)| if r[k] < b.1 { (i, r[k]) } else { b },
                );
            ridges.push(lambdas[i]);
            scores.push(v);
        }
        let total = scores.iter().sum::<f64>() / n_out.max(1) as f64;
        if best.as_ref().is_none_or(|b| total < b.3) {
            best = Some((s, ridges, scores, total));
        }
    }
    let (scale, ridges, linear_scores, _) = best.ok_or_else(|| ThermalFitError::BadSettings {
        field: "tau_scales",
        reason: "need at least one scale".into(),
    })?;
    let feats = &data.feats[scale];

    // 2. Per fold: predictions of each form.
    let arch = settings.architecture;
    let want_res = matches!(arch, Architecture::LinearMlp | Architecture::Auto);
    let want_dir = matches!(arch, Architecture::Mlp | Architecture::Auto);
    let mut fold_preds: Vec<[Option<Vec<Vec<f64>>>; 4]> = Vec::with_capacity(folds.len());
    for f in folds {
        let lin = fit_linear_per_output(feats, width, y, &f.fit, &ridges)?;
        let lin_pred = predict_linear(&lin, feats, width, n_out);
        let plain = plain_least_squares(data.raw, data.n_in, y, &f.fit)
            .ok()
            .map(|p| p.1);
        let net = |target: &[Vec<f64>], salt| {
            fit_net(
                feats,
                width,
                target,
                data.time_s,
                &f.net_fit,
                Some(&f.net_stop),
                None,
                settings,
                salt,
            )
        };
        let res = if want_res && !f.net_fit.is_empty() && !f.net_stop.is_empty() {
            let r = net(&minus(y, &lin_pred), 1)?;
            Some(plus(&lin_pred, &r.predict(feats, width, n_out)))
        } else {
            None
        };
        let dir = if want_dir && !f.net_fit.is_empty() && !f.net_stop.is_empty() {
            Some(net(y, 2)?.predict(feats, width, n_out))
        } else {
            None
        };
        fold_preds.push([plain, Some(lin_pred), res, dir]);
    }
    // Mean fold ratio of each form (None when some fold lacks it).
    let form_scores: Vec<Option<Vec<f64>>> = (0..4)
        .map(|i| {
            let per_fold: Option<Vec<Vec<f64>>> = fold_preds
                .iter()
                .zip(folds)
                .map(|(p, f)| p[i].as_ref().map(|p| ratios(y, p, &f.test)))
                .collect();
            per_fold.map(|pf| mean(&pf, n_out))
        })
        .collect();
    let order = [
        OutputModel::PlainLs,
        OutputModel::Linear,
        OutputModel::LinearMlp,
        OutputModel::Mlp,
    ];
    let allowed = |form: OutputModel| match arch {
        Architecture::Linear => matches!(form, OutputModel::PlainLs | OutputModel::Linear),
        Architecture::Mlp => form == OutputModel::Mlp,
        Architecture::LinearMlp => form != OutputModel::Mlp,
        Architecture::Auto => true,
    };
    let mut forms = Vec::with_capacity(n_out);
    let mut model = Vec::with_capacity(n_out);
    for k in 0..n_out {
        let mut pick: Option<(usize, f64)> = None;
        for (i, form) in order.iter().enumerate() {
            if let (true, Some(s)) = (allowed(*form), &form_scores[i]) {
                if pick.is_none_or(|p| s[k] < p.1 * (1.0 - TIE)) {
                    pick = Some((i, s[k]));
                }
            }
        }
        let (i, v) = pick.ok_or_else(|| ThermalFitError::BadSettings {
            field: "architecture",
            reason: format!(
                "no form of architecture {} could be fitted on every fold",
                arch.name()
            ),
        })?;
        forms.push(order[i]);
        model.push(v);
    }
    let folds_out = folds
        .iter()
        .zip(&fold_preds)
        .map(|(f, p)| {
            let chosen: Vec<f64> = forms
                .iter()
                .enumerate()
                .map(|(k, form)| {
                    let i = order.iter().position(|o| o == form).unwrap_or(1);
                    p[i].as_ref()
                        .map_or(f64::NAN, |pred| rmse(&y[k..=k], &pred[k..=k], &f.test)[0])
                })
                .collect();
            let plain = match &p[0] {
                Some(pred) => rmse(y, pred, &f.test).into_iter().map(Some).collect(),
                None => vec![None; n_out],
            };
            FoldScore {
                from_s: f.test.first().map_or(f64::NAN, |&r| data.time_s[r]),
                to_s: f.test.last().map_or(f64::NAN, |&r| data.time_s[r]),
                rows: f.test.len(),
                raw_rms: raw_rms(y, &f.test),
                model_rmse: chosen,
                plain_ls_rmse: plain,
            }
        })
        .collect();
    Ok(CvChoice {
        scale,
        ridges,
        forms,
        model,
        linear: linear_scores,
        plain: (0..n_out)
            .map(|k| form_scores[0].as_ref().map(|s| s[k]))
            .collect(),
        folds: folds_out,
    })
}
