//! Fitting a [`ThermalModel`] on a time-ordered split, and its evaluation.
//!
//! 1. Selection by leave-one-cycle-out cross-validation (`cv.rs`): the width of the filter bank,
//!    the ridge λ of each output and each output's form (plain least squares on the raw inputs,
//!    filter-bank linear, linear + residual net, net) among those the [`Architecture`] allows.
//!    The nets' hidden width and epoch count are chosen by early stopping: training rows fit,
//!    the validation part (the cycle before the held-out one) stops.
//! 2. The evaluated model: the chosen forms fitted on training + validation rows (everything
//!    before the held-out part), each ensemble member trained for exactly its early-stopping
//!    epoch count from its own seed, scored on the held-out part (the last cycle) against the
//!    filter-bank linear form, plain least squares on the raw inputs and a constant (the mean of
//!    the fitting rows), all fitted on the same rows.
//! 3. Unless told otherwise, the kept model: the same choices fitted again on every row.

use super::common::{
    fit_linear_per_output, fit_net, minus, plain_least_squares, predict_linear, rmse, thin_rows,
    Net,
};
use super::cv::{self, CvData};
use super::model::{
    raw_rows, Channel, ChannelScore, Evaluation, OutputModel, ThermalModel, FORMAT_NAME,
    FORMAT_VERSION,
};
use super::settings::FitSettings;
use super::split::{Part, Split};
use super::table::Table;
use super::ThermalFitError;
use crate::linreg::LinearModel;

/// The parts of a model fitted on some rows, with the linear part's predictions.
struct FinalParts {
    linear: LinearModel,
    lin_pred: Vec<Vec<f64>>,
    plain: Option<(LinearModel, Vec<Vec<f64>>)>,
    residual: Option<Net>,
    direct: Option<Net>,
}

/// Fits a model of `outputs` from `inputs` (columns of `table`), chosen by cross-validation over
/// the `split`'s cycles, and evaluates it on the held-out rows (see the module doc).
pub fn fit(
    table: &Table,
    inputs: &[String],
    outputs: &[String],
    split: &Split,
    settings: &FitSettings,
) -> Result<ThermalModel, ThermalFitError> {
    settings.features.validate_inputs(inputs)?;
    if inputs.is_empty() || outputs.is_empty() {
        return Err(ThermalFitError::BadSettings {
            field: "columns",
            reason: "need at least one input and one output column".into(),
        });
    }
    let col = |n: &String, role: &'static str| {
        table
            .column(n)
            .ok_or_else(|| ThermalFitError::MissingColumn {
                source_name: table.source.clone(),
                column: n.clone(),
                role,
                suggestion: super::table::closest(n, &table.header).map(str::to_string),
                available: table.header.clone(),
            })
    };
    let x_cols = inputs
        .iter()
        .map(|n| col(n, "input"))
        .collect::<Result<Vec<_>, _>>()?;
    let y: Vec<Vec<f64>> = outputs
        .iter()
        .map(|n| col(n, "output").map(<[f64]>::to_vec))
        .collect::<Result<_, _>>()?;
    // Values whose squares overflow would fit to garbage (a corrupt cell or a unit mistake).
    let named: Vec<(&String, &[f64])> = inputs
        .iter()
        .zip(x_cols.iter().copied())
        .chain(outputs.iter().zip(y.iter().map(Vec::as_slice)))
        .collect();
    for (name, values) in named {
        if let Some(i) = values.iter().position(|v| !(v * v).is_finite()) {
            return Err(ThermalFitError::TooLarge {
                column: name.clone(),
                time_s: table.time_s[i],
            });
        }
    }
    let width = settings.features.width(inputs);
    let scales = settings.scales()?;
    let feats_by_scale = scales
        .iter()
        .map(|&s| {
            let spec = settings.scaled_features(s);
            spec.validate_inputs(inputs)?;
            spec.compute_checked(&table.time_s, inputs, &x_cols)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let raw = raw_rows(&x_cols);
    let mut rows = [Vec::new(), Vec::new(), Vec::new()];
    for (i, t) in table.time_s.iter().enumerate() {
        let k = match split.part(*t) {
            Part::Train => 0,
            Part::Validation => 1,
            Part::Holdout => 2,
        };
        rows[k].push(i);
    }
    let [train_rows, val_rows, hold_rows] = rows;
    let (t, n_out, arch) = (&table.time_s, outputs.len(), settings.architecture);

    // 1. Selection by cross-validation.
    let cycles = split.cycles(t);
    let folds = cv::folds(&cycles, &train_rows, &val_rows, settings.val_fraction);
    let data = CvData {
        feats: &feats_by_scale,
        width,
        raw: &raw,
        n_in: inputs.len(),
        y: &y,
        time_s: t,
    };
    let choice = cv::cross_validate(&data, &folds, settings)?;
    let (forms, ridges) = (choice.forms.clone(), choice.ridges.clone());
    let feats = &feats_by_scale[choice.scale];
    // The nets' width and epochs: early stopping on the validation part.
    let lin_sel = fit_linear_per_output(feats, width, &y, &train_rows, &ridges)?;
    let residual = minus(&y, &predict_linear(&lin_sel, feats, width, n_out));
    let net = |target: &[Vec<f64>], salt| {
        fit_net(
            feats,
            width,
            target,
            t,
            &train_rows,
            Some(&val_rows),
            None,
            settings,
            salt,
        )
    };
    let res_sel = if forms.contains(&OutputModel::LinearMlp) {
        Some(net(&residual, 1)?)
    } else {
        None
    };
    let dir_sel = if forms.contains(&OutputModel::Mlp) {
        Some(net(&y, 2)?)
    } else {
        None
    };

    // 2. The evaluated model: fitted on training + validation rows.
    let fit_rows: Vec<usize> = train_rows.iter().chain(&val_rows).copied().collect();
    let parts = |rows: &[usize]| -> Result<FinalParts, ThermalFitError> {
        let linear = fit_linear_per_output(feats, width, &y, rows, &ridges)?;
        let lin_pred = predict_linear(&linear, feats, width, n_out);
        let refit = |target: &[Vec<f64>], chosen: &Option<Net>, salt| match chosen {
            Some(n) => fit_net(
                feats,
                width,
                target,
                t,
                rows,
                None,
                Some((n.hidden, &n.epochs)),
                settings,
                salt,
            )
            .map(Some),
            None => Ok(None),
        };
        let residual = refit(&minus(&y, &lin_pred), &res_sel, 1)?;
        let direct = refit(&y, &dir_sel, 2)?;
        let plain = match plain_least_squares(&raw, inputs.len(), &y, rows) {
            Ok(p) => Some(p),
            Err(e) if forms.contains(&OutputModel::PlainLs) => return Err(e),
            Err(_) => None,
        };
        Ok(FinalParts {
            linear,
            lin_pred,
            plain,
            residual,
            direct,
        })
    };
    let fin = parts(&fit_rows)?;
    let uses_plain = forms.contains(&OutputModel::PlainLs);
    let mut model = ThermalModel {
        format: FORMAT_NAME.into(),
        version: FORMAT_VERSION,
        architecture: arch,
        time_column: table.time_name.clone(),
        inputs: inputs.iter().map(|s| Channel::from_name(s)).collect(),
        outputs: outputs.iter().map(|s| Channel::from_name(s)).collect(),
        features: settings.scaled_features(scales[choice.scale]),
        output_models: forms.clone(),
        linear: fin.linear.clone(),
        plain: fin
            .plain
            .as_ref()
            .filter(|_| uses_plain)
            .map(|p| p.0.clone()),
        residual_mlp: fin
            .residual
            .as_ref()
            .map(|n| n.members.clone())
            .unwrap_or_default(),
        direct_mlp: fin
            .direct
            .as_ref()
            .map(|n| n.members.clone())
            .unwrap_or_default(),
        evaluation: None,
    };

    // Held-out evaluation.
    let pred = model.predict_features(feats, &raw)?;
    let hold_model = rmse(&y, &pred, &hold_rows);
    let hold_lin = rmse(&y, &fin.lin_pred, &hold_rows);
    let hold_plain = fin.plain.as_ref().map(|p| rmse(&y, &p.1, &hold_rows));
    let n = table.len();
    let raw_rms = rmse(&y, &vec![vec![0.0; n]; n_out], &hold_rows);
    let means: Vec<Vec<f64>> = y
        .iter()
        .map(|c| {
            let m = fit_rows.iter().map(|&r| c[r]).sum::<f64>() / fit_rows.len().max(1) as f64;
            vec![m; n]
        })
        .collect();
    let constant = rmse(&y, &means, &hold_rows);
    let channels = (0..n_out)
        .map(|k| ChannelScore {
            output: model.outputs[k].clone(),
            form: forms[k],
            raw_rms: raw_rms[k],
            constant_rmse: constant[k],
            linear_rmse: hold_lin[k],
            model_rmse: hold_model[k],
            plain_ls_rmse: hold_plain.as_ref().map(|p| p[k]),
            linear_ratio: (raw_rms[k] > 0.0).then(|| hold_lin[k] / raw_rms[k]),
            model_ratio: (raw_rms[k] > 0.0).then(|| hold_model[k] / raw_rms[k]),
            cv_model_ratio: choice.model[k],
            cv_linear_ratio: choice.linear[k],
            cv_plain_ls_ratio: choice.plain[k],
        })
        .collect();
    let selection = if cycles.len() >= 2 {
        format!(
            "leave-one-cycle-out over the {} cycles (each held out once, every other row fitting)",
            cycles.len()
        )
    } else {
        "fewer than two cycles: one fold, the training part fitting, the validation part held out"
            .to_string()
    };
    model.evaluation = Some(Evaluation {
        split: split.clone(),
        n_train: train_rows.len(),
        n_val: val_rows.len(),
        n_fit_net: thin_rows(&fit_rows, t, settings.min_train_step_s).len(),
        n_holdout: hold_rows.len(),
        selection,
        tau_scale: scales[choice.scale],
        ridges: ridges.clone(),
        folds: choice.folds,
        residual_net: fin.residual.map(|n| (n.hidden, n.epochs)),
        direct_net: fin.direct.map(|n| (n.hidden, n.epochs)),
        channels,
        refit_rows: None,
    });
    // 3. With the forms chosen and evaluated, the model a user keeps learns from every row.
    if settings.refit_all {
        let all: Vec<usize> = (0..table.len()).collect();
        let refitted = parts(&all)?;
        model.linear = refitted.linear;
        model.plain = refitted.plain.filter(|_| uses_plain).map(|p| p.0);
        model.residual_mlp = refitted.residual.map(|n| n.members).unwrap_or_default();
        model.direct_mlp = refitted.direct.map(|n| n.members).unwrap_or_default();
        if let Some(e) = model.evaluation.as_mut() {
            e.refit_rows = Some(all.len());
        }
    }
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal_fit::features::FeatureSpec;
    use crate::thermal_fit::model::Architecture;
    use crate::thermal_fit::{read_csv, TableRequest};

    /// A machine whose drift follows its temperature through a 1 h first-order lag, with the
    /// temperature stepping between cycles: a static model cannot fit it, the filter bank can.
    fn lagged_table() -> Table {
        lagged_table_with(0.0)
    }

    /// [`lagged_table`] with `offset_um` added to the drift of the last cycle only.
    fn lagged_table_with(offset_um: f64) -> Table {
        let mut text = String::from("time_s,spindle_rpm,t1_degc,ch1_um\n");
        let tau_s: f64 = 3600.0;
        // The machine starts in a steady state at its first reading (the features' assumption).
        let mut lag = 22.0;
        for i in 0..(3 * 480) {
            let t_s = 60.0 * f64::from(i);
            let heating = (i % 480) < 240;
            let cycle = f64::from(i / 480 + 1);
            let temp = if heating { 20.0 + 2.0 * cycle } else { 20.0 };
            if i > 0 {
                lag += (1.0 - (-60.0 / tau_s).exp()) * (temp - lag);
            }
            let rpm = if heating { 1000.0 * cycle } else { 0.0 };
            let planted = if i / 480 == 2 { offset_um } else { 0.0 };
            text.push_str(&format!(
                "{t_s},{rpm},{temp},{}\n",
                3.0 * (lag - 20.0) + planted
            ));
        }
        let req = TableRequest {
            time: None,
            required: vec![
                ("t1_degc".into(), "input"),
                ("ch1_um".into(), "output"),
                ("spindle_rpm".into(), "cycle"),
            ],
            optional: Vec::new(),
            min_rows: 2,
        };
        read_csv(&text, "lagged.csv", &req).unwrap()
    }

    /// The split of a table by its `spindle_rpm` cycles: the last one held out.
    fn cycle_split(table: &Table) -> Split {
        Split::resolve(
            &table.time_s,
            None,
            Some(("spindle_rpm", table.column("spindle_rpm").unwrap())),
            0.25,
        )
        .unwrap()
    }

    fn fit_lagged(arch: Architecture, taus: Vec<f64>) -> ThermalModel {
        let table = lagged_table();
        let split = cycle_split(&table);
        let settings = FitSettings {
            architecture: arch,
            features: FeatureSpec {
                time_constants_s: taus,
                speed_exponents: Vec::new(),
                relative_to_mean: false,
            },
            ridge_candidates: vec![1e-9],
            tau_scales: vec![1.0],
            hidden_candidates: vec![2],
            ..FitSettings::default()
        };
        fit(
            &table,
            &["t1_degc".into()],
            &["ch1_um".into()],
            &split,
            &settings,
        )
        .unwrap()
    }

    #[test]
    fn the_filter_bank_recovers_a_first_order_lag_on_a_held_out_hotter_cycle() {
        let with_lag = fit_lagged(Architecture::Linear, vec![3600.0]);
        let static_only = fit_lagged(Architecture::Linear, vec![]);
        let ev = |m: &ThermalModel| m.evaluation.clone().unwrap().channels[0].clone();
        // Exact model class: round-off only (1e-6 µm) on drifts of up to 18 µm.
        assert!(ev(&with_lag).model_rmse < 1e-6, "{:?}", ev(&with_lag));
        // The static model misses the lag by micrometres.
        assert!(ev(&static_only).model_rmse > 1.0, "{:?}", ev(&static_only));
        let e = with_lag.evaluation.as_ref().unwrap();
        assert_eq!(e.split.holdout_from_s, 960.0 * 60.0);
        assert_eq!(e.split.val_from_s, 480.0 * 60.0);
    }

    #[test]
    fn json_round_trip_predicts_identically_and_bad_files_are_rejected() {
        let m = fit_lagged(Architecture::LinearMlp, vec![3600.0]);
        let json = m.to_json();
        let back = ThermalModel::from_json(&json, "m.json").unwrap();
        let table = lagged_table();
        let x = [table.column("t1_degc").unwrap()];
        assert_eq!(
            m.predict(&table.time_s, &x).unwrap(),
            back.predict(&table.time_s, &x).unwrap()
        );
        let err = |text: &str| {
            ThermalModel::from_json(text, "m.json")
                .unwrap_err()
                .to_string()
        };
        assert!(err("{\"kind\": \"hybrid\"}").contains("not a thermal-drift model"));
        assert!(err(&json.replacen("\"version\": 2", "\"version\": 7", 1)).contains("version"));
        // A version 1 file predicts with the same parts; its evaluation is not kept.
        let v1 =
            ThermalModel::from_json(&json.replacen("\"version\": 2", "\"version\": 1", 1), "v1")
                .unwrap();
        assert!(v1.evaluation.is_none());
        assert_eq!(
            m.predict(&table.time_s, &x).unwrap(),
            v1.predict(&table.time_s, &x).unwrap()
        );
        let inconsistent = json.replacen(
            "\"time_constants_s\": [\n      3600.0\n    ]",
            "\"time_constants_s\": []",
            1,
        );
        assert_ne!(inconsistent, json);
        assert!(err(&inconsistent).contains("inconsistent model"));
        assert!(err("[1, 2").contains("not JSON"));
    }

    #[test]
    fn the_kept_model_learns_every_row_and_the_evaluation_is_of_the_model_before() {
        // A last cycle whose drift carries an offset the earlier cycles never show: only a model
        // fitted on every row can know it.
        let table = lagged_table_with(4.0);
        let split = cycle_split(&table);
        let fit_with = |refit_all| {
            let settings = FitSettings {
                architecture: Architecture::Linear,
                features: FeatureSpec {
                    time_constants_s: vec![3600.0],
                    speed_exponents: Vec::new(),
                    relative_to_mean: false,
                },
                ridge_candidates: vec![1e-9],
                refit_all,
                ..FitSettings::default()
            };
            let inputs = ["t1_degc".to_string()];
            fit(&table, &inputs, &["ch1_um".into()], &split, &settings).unwrap()
        };
        let (kept, refitted) = (fit_with(false), fit_with(true));
        let (e0, e1) = (
            kept.evaluation.clone().unwrap(),
            refitted.evaluation.clone().unwrap(),
        );
        assert_eq!(e0.refit_rows, None);
        assert_eq!(e1.refit_rows, Some(table.len()));
        assert_eq!(
            e0.channels, e1.channels,
            "the printed evaluation is the same model's"
        );
        let held_out_rmse = |m: &ThermalModel| {
            let t1 = table.column("t1_degc").unwrap();
            let pred = m.predict(&table.time_s, &[t1]).unwrap();
            let y = table.column("ch1_um").unwrap();
            let rows: Vec<usize> = (0..table.len())
                .filter(|&r| table.time_s[r] >= split.holdout_from_s)
                .collect();
            (rows
                .iter()
                .map(|&r| (pred[0][r] - y[r]).powi(2))
                .sum::<f64>()
                / rows.len() as f64)
                .sqrt()
        };
        let (before, after) = (held_out_rmse(&kept), held_out_rmse(&refitted));
        // The evaluated model misses the planted offset by most of its 4 µm; the refitted one
        // has seen it (it spreads it over all the rows of its least-squares fit).
        assert!(before > 2.0, "evaluated model, held-out RMSE {before} µm");
        assert!(
            after < 0.75 * before,
            "refitted {after} µm vs evaluated {before} µm"
        );
        // Plain least squares on the raw input is the printed baseline.
        assert!(e1.channels[0]
            .plain_ls_rmse
            .is_some_and(|p| p.is_finite() && p > 0.0));
    }

    #[test]
    fn each_cycle_is_held_out_once_and_each_output_gets_the_simplest_form_that_generalises() {
        // ch1 lags the temperature by 1 h (the filter bank is needed); ch2 is a static function
        // of it plus a wobble no input explains: the filter bank gains nothing there, and the
        // simpler form, plain least squares, is kept.
        let base = lagged_table();
        let t1 = base.column("t1_degc").unwrap();
        let mut text = String::from("time_s,spindle_rpm,t1_degc,ch1_um,ch2_um\n");
        let rpm = base.column("spindle_rpm").unwrap();
        let ch1 = base.column("ch1_um").unwrap();
        for r in 0..base.len() {
            let wobble = 0.5 * (1.7 * r as f64).sin();
            let ch2 = 1.5 * t1[r] + 0.3 + wobble;
            text.push_str(&format!(
                "{},{},{},{},{ch2}\n",
                base.time_s[r], rpm[r], t1[r], ch1[r]
            ));
        }
        let req = TableRequest {
            time: None,
            required: vec![("spindle_rpm".into(), "cycle")],
            optional: vec!["t1_degc".into(), "ch1_um".into(), "ch2_um".into()],
            min_rows: 2,
        };
        let table = read_csv(&text, "two.csv", &req).unwrap();
        let split = cycle_split(&table);
        assert_eq!(split.cycles(&table.time_s).len(), 3);
        let settings = FitSettings {
            architecture: Architecture::Linear,
            features: FeatureSpec {
                time_constants_s: vec![3600.0],
                speed_exponents: Vec::new(),
                relative_to_mean: false,
            },
            ridge_candidates: vec![1e-9, 1e-3],
            tau_scales: vec![0.5, 1.0],
            ..FitSettings::default()
        };
        let outputs = ["ch1_um".to_string(), "ch2_um".to_string()];
        let m = fit(&table, &["t1_degc".into()], &outputs, &split, &settings).unwrap();
        let ev = m.evaluation.as_ref().unwrap();
        assert_eq!(ev.folds.len(), 3);
        assert!(ev.folds.iter().all(|f| f.rows == 480), "{:?}", ev.folds);
        assert_eq!(ev.tau_scale, 1.0);
        assert_eq!(m.features.time_constants_s, [3600.0]);
        assert_eq!(m.output_models, [OutputModel::Linear, OutputModel::PlainLs]);
        let c = &ev.channels;
        assert!(c[0].cv_model_ratio < 1e-6, "{:?}", c[0]);
        assert!(
            c[0].cv_plain_ls_ratio.is_some_and(|p| p > 0.1),
            "{:?}",
            c[0]
        );
        assert!(
            c[1].cv_plain_ls_ratio == Some(c[1].cv_model_ratio),
            "{:?}",
            c[1]
        );
        assert!(
            c[1].cv_model_ratio <= c[1].cv_linear_ratio * (1.0 + 1e-6),
            "{:?}",
            c[1]
        );
        // The file keeps the plain part and predicts with it after a round trip.
        let back = ThermalModel::from_json(&m.to_json(), "m.json").unwrap();
        assert!(back.plain.is_some());
        let x = [table.column("t1_degc").unwrap()];
        assert_eq!(
            m.predict(&table.time_s, &x).unwrap(),
            back.predict(&table.time_s, &x).unwrap()
        );
    }
}
