//! `fit-thermal` and `predict-thermal`: thermal-drift models from a user's CSV measurements
//! (file handling and the printed report; the model is `vmc_predict::thermal_fit`).

use std::fmt::Write as _;
use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::files;
use crate::predict::thermal_fit::{self, FitSettings, Split, TableRequest, ThermalModel};

/// What to fit, validated.
pub struct FitThermalConfig {
    /// Measurements (CSV).
    pub data: PathBuf,
    /// Input columns.
    pub inputs: Vec<String>,
    /// Output (drift) columns.
    pub outputs: Vec<String>,
    /// Output model file (JSON).
    pub out: PathBuf,
    /// Overwrite an existing output file.
    pub force: bool,
    /// Time column (None: the only one whose name starts with "time").
    pub time: Option<String>,
    /// Start of the held-out part, s.
    pub holdout_from_s: Option<f64>,
    /// Column whose rise from 0 starts a cycle.
    pub cycle_col: Option<String>,
    /// Features, forms, candidates, seed.
    pub settings: FitSettings,
    /// Most data rows accepted (a work limit).
    pub max_rows: usize,
}

/// Default of `--max-rows`: 200,000 rows (55 h at one row a second, 140 days at one a minute)
/// fit in a few GB; a million rows of a thousand cycles took over 17 GB.
pub const DEFAULT_MAX_ROWS: usize = 200_000;

/// What to predict.
pub struct PredictThermalConfig {
    /// Model file from `fit-thermal`.
    pub model: PathBuf,
    /// Measurements with the model's input columns.
    pub data: PathBuf,
    /// Output predictions (CSV).
    pub out: PathBuf,
    /// Overwrite an existing output file.
    pub force: bool,
    /// Time column (None: the only one whose name starts with "time").
    pub time: Option<String>,
    /// Earlier measurements of the same machine (same columns, times before the data's), run
    /// through the filters first and not predicted.
    pub history: Option<PathBuf>,
    /// Refuse, rather than warn, when the past given covers less than the model's memory.
    pub strict: bool,
    /// The data begins at rest (steady state): the filters' starting state is right.
    pub starts_at_rest: bool,
}

/// `vmc-twin fit-thermal`: fits the model, writes it and prints its evaluation.
///
/// # Errors
/// An output that may not be written, unreadable or unusable measurements, a fit failure.
pub fn fit_thermal(cfg: &FitThermalConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    let source = cfg.data.display().to_string();
    let text = files::read_named(&cfg.data, "measurements")?;
    // Header first, to know whether the default cycle column exists.
    let header: Vec<String> = text
        .lines()
        .next()
        .unwrap_or("")
        .split(',')
        .map(|s| s.trim().trim_matches('"').to_string())
        .collect();
    // The cycle column also places the validation cycle when the held-out start is given.
    let cycle_col = cfg.cycle_col.clone().or_else(|| {
        header
            .iter()
            .any(|h| h == "spindle_rpm")
            .then(|| "spindle_rpm".to_string())
    });
    let mut required: Vec<(String, &'static str)> = cfg
        .inputs
        .iter()
        .map(|n| (n.clone(), "input"))
        .chain(cfg.outputs.iter().map(|n| (n.clone(), "output")))
        .collect();
    if let Some(c) = &cycle_col {
        required.push((c.clone(), "cycle"));
    }
    let request = TableRequest {
        time: cfg.time.clone(),
        required,
        optional: Vec::new(),
        min_rows: 20,
    };
    // Counted before parsing: a file far beyond the limit costs no memory.
    let rows = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .count()
        .saturating_sub(1);
    if rows > cfg.max_rows {
        anyhow::bail!(
            "{source}: {rows} data rows, more than the limit of {} (the fit's memory and time \
             grow with the rows); pass --max-rows {rows} to fit them all, or resample the file \
             to a coarser time step",
            cfg.max_rows
        );
    }
    let table = thermal_fit::read_csv(&text, &source, &request)?;
    let split = Split::resolve(
        &table.time_s,
        cfg.holdout_from_s,
        cycle_col
            .as_deref()
            .and_then(|c| table.column(c).map(|v| (c, v))),
        cfg.settings.val_fraction,
    )?;
    let model = thermal_fit::fit(&table, &cfg.inputs, &cfg.outputs, &split, &cfg.settings)
        .map_err(|e| {
            match e {
                // A value of the file, not a setting: name the file.
                e @ (thermal_fit::ThermalFitError::NonFiniteFeature { .. }
                | thermal_fit::ThermalFitError::TooLarge { .. }) => {
                    anyhow::Error::new(e).context(source.clone())
                }
                e => anyhow::Error::new(e),
            }
        })?;
    files::write_atomic(&cfg.out, model.to_json().as_bytes(), cfg.force)?;
    out.write_all(fit_report(&model, &table, &source).as_bytes())?;
    writeln!(out, "wrote {}", cfg.out.display())?;
    Ok(())
}

/// The terminal report of a fit (the same figures are in the model's `evaluation`).
fn fit_report(model: &ThermalModel, table: &thermal_fit::Table, source: &str) -> String {
    let mut s = String::new();
    let Some(ev) = &model.evaluation else {
        return s;
    };
    let net = |n: &Option<(usize, Vec<usize>)>| {
        n.as_ref()
            .map(|(h, e)| format!("{} × hidden {h} (LM epochs {e:?})", e.len()))
            .unwrap_or_else(|| "not used".into())
    };
    let taus: Vec<String> = model
        .features
        .time_constants_s
        .iter()
        .map(|t| format!("{t}"))
        .collect();
    let _ =
        writeln!(
        s,
        "fit-thermal: {source}, {} rows, {} inputs → {} features, {} outputs; architecture {}; \
         filter bank ×{} (τ = {} s); residual net {}, direct net {}",
        table.len(),
        model.inputs.len(),
        model.features.width(&model.input_names()),
        model.outputs.len(),
        model.architecture.name(),
        ev.tau_scale,
        if taus.is_empty() { "none".into() } else { taus.join(", ") },
        net(&ev.residual_net),
        net(&ev.direct_net),
    );
    let _ = writeln!(
        s,
        "selection: {}; per output the form and ridge λ with the lowest mean ratio over the \
         folds (ratio = residual RMS / raw drift RMS of the held-out rows; plainLS = least \
         squares on the raw inputs, intercept, no filters, every fitting row)",
        ev.selection
    );
    let pct = |r: Option<f64>| {
        r.map(|v| format!("{:.1}%", 100.0 * v))
            .unwrap_or_else(|| "-".into())
    };
    let ratio = |e: Option<f64>, raw: f64| e.filter(|_| raw > 0.0).map(|e| e / raw);
    let mut head = format!("  {:<5} {:>17} {:>5} ", "fold", "held out (s)", "rows");
    for c in &model.outputs {
        let stem = stem(c);
        let _ = write!(head, " {:>16}", format!("{stem} model|LS"));
    }
    let _ = writeln!(s, "{head}");
    let n_out = model.outputs.len();
    for (i, f) in ev.folds.iter().enumerate() {
        let mut line = format!(
            "  {:<5} {:>17} {:>5} ",
            i + 1,
            format!("{:.0}–{:.0}", f.from_s, f.to_s),
            f.rows
        );
        for k in 0..n_out {
            let raw = f.raw_rms.get(k).copied().unwrap_or(0.0);
            let m = ratio(f.model_rmse.get(k).copied(), raw);
            let p = ratio(f.plain_ls_rmse.get(k).copied().flatten(), raw);
            let _ = write!(line, " {:>16}", format!("{}|{}", pct(m), pct(p)));
        }
        let _ = writeln!(s, "{line}");
    }
    let mut line = format!("  {:<5} {:>17} {:>5} ", "mean", "", "");
    for c in &ev.channels {
        let _ = write!(
            line,
            " {:>16}",
            format!(
                "{}|{}",
                pct(Some(c.cv_model_ratio)),
                pct(c.cv_plain_ls_ratio)
            )
        );
    }
    let _ = writeln!(s, "{line}");
    let loco = ev.split.cycle_starts_s.len() >= 2;
    let nets = if ev.residual_net.is_some() || ev.direct_net.is_some() {
        format!(
            "; the nets early-stop on the validation part ({} rows) after training on {} rows",
            ev.n_val, ev.n_train
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "split (time-ordered): {}{nets}; {}: held out from {} s, {} rows, scored with the chosen \
         forms fitted on the {} rows before it{}",
        ev.split.rule,
        if loco { "last cycle" } else { "held-out part" },
        ev.split.holdout_from_s,
        ev.n_holdout,
        ev.n_train + ev.n_val,
        if loco {
            " (the selection saw every cycle, this one as a fold)"
        } else {
            " (the selection did not see it)"
        }
    );
    let _ = writeln!(
        s,
        "per output (ratio = residual RMS / raw drift RMS; aim: ≤ 25 % and no worse than plainLS):"
    );
    let _ = writeln!(
        s,
        "  {:<10} {:<10} {:>7} | {:>16} {:>7} {:>7} {:<7} | {:>12} {:>8} {:>8} {:>7} {:>7} {:>7} {:<7}",
        "output", "form", "ridge", "folds (mean):", "model", "plainLS", "aim",
        if loco { "last cycle:" } else { "held out:" }, "raw_rms", "constant", "linear", "plainLS", "model", "aim"
    );
    let aim = |m: Option<f64>, p: Option<f64>| {
        if m.is_some_and(|m| m <= 0.25 && p.is_none_or(|p| m <= p)) {
            "met"
        } else {
            "NOT met"
        }
    };
    for (k, c) in ev.channels.iter().enumerate() {
        let plain_ratio = ratio(c.plain_ls_rmse, c.raw_rms);
        let _ = writeln!(
            s,
            "  {:<10} {:<10} {:>7} | {:>16} {:>7} {:>7} {:<7} | {:>12} {:>8.3} {:>8.3} {:>7} {:>7} {:>7} {:<7}",
            c.output.name,
            c.form.name(),
            if c.form == thermal_fit::OutputModel::PlainLs {
                "-".to_string()
            } else {
                format!("{}", ev.ridges.get(k).copied().unwrap_or(f64::NAN))
            },
            "",
            pct(Some(c.cv_model_ratio)),
            pct(c.cv_plain_ls_ratio),
            aim(Some(c.cv_model_ratio), c.cv_plain_ls_ratio),
            "",
            c.raw_rms,
            c.constant_rmse,
            pct(c.linear_ratio),
            pct(plain_ratio),
            pct(c.model_ratio),
            aim(c.model_ratio, plain_ratio),
        );
    }
    match ev.refit_rows {
        Some(n) => {
            let _ = writeln!(
                s,
                "the model written was fitted again on all {n} rows (held-out cycle included) \
                 with the chosen forms; the evaluation above is the pre-refit one (the folds' \
                 models and the model fitted before the last cycle; --no-refit writes that one)"
            );
        }
        None => {
            let _ = writeln!(
                s,
                "the model written is the one scored on the last cycle above (fitted before it)"
            );
        }
    }
    s
}

/// `vmc-twin predict-thermal`: the model's predictions of a file's rows, written as CSV.
///
/// # Errors
/// An output that may not be written, an unreadable model or data that does not fit it.
pub fn predict_thermal(cfg: &PredictThermalConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    let model_name = cfg.model.display().to_string();
    let model = ThermalModel::from_json(&files::read_named(&cfg.model, "model")?, &model_name)?;
    let source = cfg.data.display().to_string();
    let read = |path: &std::path::Path, what: &'static str| {
        read_for_model(path, what, &model, cfg.time.as_ref())
            .with_context(|| format!("data does not fit model {model_name}"))
    };
    let table = read(&cfg.data, "measurements")?;
    let history = match &cfg.history {
        Some(path) => Some(read(path, "history")?),
        None => None,
    };
    if !cfg.starts_at_rest {
        if let Some(warning) = history_check(&model, &table, history.as_ref(), cfg.strict)? {
            writeln!(out, "{warning}")?;
        }
    }
    // The history rows go through the filters first; only the data's rows are predicted.
    let n_past = history.as_ref().map_or(0, thermal_fit::Table::len);
    let mut time_s = history.as_ref().map_or(Vec::new(), |h| h.time_s.clone());
    time_s.extend_from_slice(&table.time_s);
    let inputs: Vec<Vec<f64>> = model
        .inputs
        .iter()
        .filter_map(|c| {
            let now = table.column(&c.name)?;
            let past = history
                .as_ref()
                .and_then(|h| h.column(&c.name))
                .unwrap_or(&[]);
            Some([past, now].concat())
        })
        .collect();
    let input_refs: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
    let pred: Vec<Vec<f64>> = model
        .predict(&time_s, &input_refs)
        .with_context(|| source.clone())?
        .into_iter()
        .map(|col| col[n_past..].to_vec())
        .collect();
    let measured: Vec<(&str, &[f64])> = model
        .outputs
        .iter()
        .filter_map(|c| table.column(&c.name).map(|v| (c.name.as_str(), v)))
        .collect();
    let mut csv = String::from("time_s");
    for c in &model.outputs {
        let stem = stem(c);
        let _ = write!(csv, ",{stem}_pred_{}", c.unit);
    }
    for (name, _) in &measured {
        let _ = write!(csv, ",{name}");
    }
    csv.push('\n');
    for (r, t) in table.time_s.iter().enumerate() {
        let _ = write!(csv, "{t}");
        for col in &pred {
            let _ = write!(csv, ",{:.6}", col[r]);
        }
        for (_, col) in &measured {
            let _ = write!(csv, ",{}", col[r]);
        }
        csv.push('\n');
    }
    files::write_atomic(&cfg.out, csv.as_bytes(), cfg.force)?;
    writeln!(
        out,
        "predict-thermal: {} rows of {source} with model {model_name} ({} outputs{}) → {}",
        table.len(),
        model.outputs.len(),
        if measured.is_empty() {
            String::new()
        } else {
            format!(", {} measured columns kept", measured.len())
        },
        cfg.out.display()
    )?;
    Ok(())
}

/// A measurement file with the model's input columns (and its output columns when present).
fn read_for_model(
    path: &std::path::Path,
    what: &'static str,
    model: &ThermalModel,
    time: Option<&String>,
) -> Result<thermal_fit::Table> {
    let source = path.display().to_string();
    let text = files::read_named(path, what)?;
    let request = TableRequest {
        time: time.cloned(),
        required: model
            .inputs
            .iter()
            .map(|c| (c.name.clone(), "input"))
            .collect(),
        optional: model.outputs.iter().map(|c| c.name.clone()).collect(),
        min_rows: 1,
    };
    Ok(thermal_fit::read_csv(&text, &source, &request)?)
}

/// Does the past given (the history file, if any) cover the model's memory? `Ok(None)` when it
/// does; a warning line when it does not (an error under `strict`). A history must end before
/// the data begins.
fn history_check(
    model: &ThermalModel,
    data: &thermal_fit::Table,
    history: Option<&thermal_fit::Table>,
    strict: bool,
) -> Result<Option<String>> {
    let memory_s = model.features.memory_s();
    let Some(&t0_s) = data.time_s.first() else {
        return Ok(None);
    };
    let covered_s = match history {
        Some(h) => {
            let (first_s, last_s) = (h.time_s[0], h.time_s[h.len() - 1]);
            if last_s >= t0_s {
                anyhow::bail!(
                    "{}: the history ends at t = {last_s} s, not before the data's first row \
                     (t = {t0_s} s in {}): give the measurements that came before",
                    h.source,
                    data.source
                );
            }
            t0_s - first_s
        }
        None => 0.0,
    };
    if covered_s >= memory_s {
        return Ok(None);
    }
    let affected = data
        .time_s
        .iter()
        .filter(|t| **t - t0_s < memory_s - covered_s)
        .count();
    let past = match history {
        Some(h) => format!("its history {} covers {covered_s:.0} s", h.source),
        None => "no history is given".to_string(),
    };
    let what = format!(
        "{}: the model remembers {memory_s:.0} s (3 × its longest filter time constant) and \
         {past} before the first row (t = {t0_s} s); the predictions of the first {affected} \
         of {} rows assume the machine was at rest at the start of what is given, and are wrong if \
         it was not",
        data.source,
        data.len()
    );
    let how = "give the earlier measurements with --history FILE, or say --starts-at-rest";
    if strict {
        anyhow::bail!("{what} (--strict): {how}");
    }
    Ok(Some(format!("warning: {what}; {how}")))
}

/// A channel's column name without its unit suffix (`ch1_um` → `ch1`; the whole name when it
/// has no unit).
fn stem(c: &thermal_fit::Channel) -> &str {
    c.name
        .strip_suffix(&format!("_{}", c.unit))
        .filter(|_| !c.unit.is_empty())
        .unwrap_or(&c.name)
}
