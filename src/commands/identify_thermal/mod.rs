//! `identify-thermal`: a grey-box thermal network of the spindle identified from a user's
//! measurements (file handling, folds and the printed report; the fit is
//! `vmc_predict::rc_identify`), written as a machine-file fragment, and compared on held-out
//! cycles with the black-box models of `fit-thermal` on the same folds.

pub mod fragment;
mod report;

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::files;
use crate::predict::rc_identify::{self, Mode, RcData, RcFit, RcSettings};
use crate::predict::thermal_fit::{self, FitSettings, Split, Table, TableRequest};

/// What to identify, validated.
pub struct IdentifyThermalConfig {
    /// Measurements (CSV).
    pub data: PathBuf,
    /// Time column (None: the only one whose name starts with "time").
    pub time: Option<String>,
    /// Spindle speed column, rpm.
    pub rpm: String,
    /// Drift columns.
    pub drifts: Vec<String>,
    /// Measured temperatures of the "with temperatures" prediction.
    pub temps: Vec<String>,
    /// Temperatures nodes 0, 1, … are fitted to.
    pub node_temps: Vec<String>,
    /// Ambient column (None: constant ambient).
    pub ambient: Option<String>,
    /// The network and its fit.
    pub settings: RcSettings,
    /// Start of the held-out part for the time split of a one-cycle file, s.
    pub holdout_from_s: Option<f64>,
    /// Black-box comparison: inputs and settings (None: skipped).
    pub baseline: Option<(Vec<String>, FitSettings)>,
    /// Output fragment (TOML).
    pub out: PathBuf,
    /// Overwrite existing output files.
    pub force: bool,
    /// Rerun recording of the drifts.
    pub rrd: Option<PathBuf>,
}

/// One fold: a label, the rows that fit and the rows held out.
pub(crate) struct Fold {
    pub label: String,
    pub fit: Vec<usize>,
    pub test: Vec<usize>,
}

/// Per fold, per mode (speed only, with temperatures) the held-out RMSE per channel, and the
/// stitched held-out predictions of the speed-only mode.
pub(crate) struct GreyBoxFolds {
    pub rmse: Vec<[Option<Vec<f64>>; 2]>,
    pub held_out_pred: Vec<Vec<f64>>,
    /// Parameters held at a bound in some fold (fold label, mode, names).
    pub bound_notes: Vec<String>,
}

/// The black-box figures on the same folds: per fold, per channel (chosen form, plain LS)
/// RMSE; the forms chosen; the refitted model's predictions of every row.
pub(crate) struct BlackBox {
    pub rmse: Vec<Vec<(f64, Option<f64>)>>,
    pub forms: Vec<String>,
    pub pred: Vec<Vec<f64>>,
}

/// The columns of the file the fit uses.
pub(crate) struct Columns<'a> {
    pub rpm: &'a [f64],
    pub drifts: Vec<Vec<f64>>,
    pub temps: Vec<&'a [f64]>,
    pub node_temps: Vec<Option<&'a [f64]>>,
    pub ambient: Option<&'a [f64]>,
}

impl Columns<'_> {
    pub(crate) fn data<'b>(&'b self, time_s: &'b [f64]) -> RcData<'b> {
        RcData {
            time_s,
            rpm: self.rpm,
            ambient_degc: self.ambient,
            drifts: &self.drifts,
            node_temps: &self.node_temps,
            temps: &self.temps,
        }
    }
}

/// `vmc-twin identify-thermal`: identifies the network, prints the fit per cycle and the
/// held-out figures beside the black-box models, writes the fragment.
///
/// # Errors
/// An output that may not be written, unreadable or unusable measurements (negative speeds,
/// missing columns), a fit failure.
pub fn identify_thermal(cfg: &IdentifyThermalConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    if let Some(p) = &cfg.rrd {
        crate::record::check_rrd_path(p, cfg.force)?;
    }
    let source = cfg.data.display().to_string();
    let text = files::read_named(&cfg.data, "measurements")?;
    let mut required: Vec<(String, &'static str)> = vec![(cfg.rpm.clone(), "speed")];
    required.extend(cfg.drifts.iter().map(|c| (c.clone(), "drift")));
    required.extend(cfg.temps.iter().map(|c| (c.clone(), "temperature")));
    required.extend(
        cfg.node_temps
            .iter()
            .map(|c| (c.clone(), "node temperature")),
    );
    required.extend(cfg.ambient.iter().map(|c| (c.clone(), "ambient")));
    if let Some((inputs, _)) = &cfg.baseline {
        required.extend(inputs.iter().map(|c| (c.clone(), "baseline input")));
    }
    required.dedup();
    let mut seen = std::collections::HashSet::new();
    required.retain(|(c, _)| seen.insert(c.clone()));
    let request = TableRequest {
        time: cfg.time.clone(),
        required,
        optional: Vec::new(),
        min_rows: 20,
    };
    let table = thermal_fit::read_csv(&text, &source, &request)?;
    let col = |c: &str| {
        table
            .column(c)
            .with_context(|| format!("{source}: no column \"{c}\""))
    };
    let rpm = col(&cfg.rpm)?;
    if let Some(r) = rpm.iter().position(|v| *v < 0.0) {
        bail!(
            "{source}: line {}: speed column \"{}\" is {} rpm: speeds must be ≥ 0 (the heat \
             input depends on the speed, not on the direction: write |n|)",
            table.lines.get(r).copied().unwrap_or(r + 2),
            cfg.rpm,
            rpm[r]
        );
    }
    if rpm.iter().all(|v| *v == 0.0) {
        bail!(
            "{source}: speed column \"{}\" is 0 rpm on every row: without the spindle turning \
             there is no heat input to identify (the network's heat comes from the speed); give \
             measurements where the spindle runs",
            cfg.rpm
        );
    }
    let cols = Columns {
        rpm,
        drifts: cfg
            .drifts
            .iter()
            .map(|c| col(c).map(<[f64]>::to_vec))
            .collect::<Result<_>>()?,
        temps: cfg.temps.iter().map(|c| col(c)).collect::<Result<_>>()?,
        node_temps: cfg
            .node_temps
            .iter()
            .map(|c| col(c).map(Some))
            .collect::<Result<_>>()?,
        ambient: cfg.ambient.as_deref().map(col).transpose()?,
    };
    let t = &table.time_s;
    let (split, folds, note) = folds(&table, &cfg.rpm, rpm, cfg.holdout_from_s)?;
    let data = cols.data(t);
    let modes: Vec<Mode> = if cfg.temps.is_empty() {
        vec![Mode::SpeedOnly]
    } else {
        vec![Mode::SpeedOnly, Mode::WithTemps]
    };
    let grey = grey_box_folds(&data, &folds, &modes, &cfg.settings)?;
    let all: Vec<usize> = (0..t.len()).collect();
    let finals: Vec<RcFit> = modes
        .iter()
        .map(|&m| rc_identify::identify(&data, &all, &cfg.settings, m))
        .collect::<Result<_, _>>()
        .with_context(|| format!("identifying the network on every row of {source}"))?;
    let black = match &cfg.baseline {
        Some((inputs, settings)) => Some(black_box(&table, inputs, &cfg.drifts, &split, settings)?),
        None => None,
    };
    let ctx = report::Context {
        cfg,
        source: &source,
        table: &table,
        cols: &cols,
        folds: &folds,
        note: &note,
    };
    out.write_all(report::text(&ctx, &grey, &finals, black.as_ref()).as_bytes())?;
    let frag = fragment::write(&fragment::Meta::new(cfg, &table, &cols), &finals[0]);
    files::write_atomic(&cfg.out, frag.as_bytes(), cfg.force)?;
    writeln!(out, "wrote {}", cfg.out.display())?;
    if let Some(path) = &cfg.rrd {
        let pred = finals[0].predict(&data)?;
        let size = crate::record::drift::record_drift(
            path,
            cfg.force,
            &format!("identify-thermal {source}"),
            t,
            &cfg.drifts,
            &cols.drifts,
            &[
                ("grey-box, speed only (fitted on every row)", &pred),
                (
                    "grey-box, speed only (each cycle held out)",
                    &grey.held_out_pred,
                ),
            ],
            black
                .as_ref()
                .map(|b| ("black-box (fit-thermal, refitted on every row)", &b.pred)),
        )?;
        writeln!(out, "wrote {} ({size} bytes)", path.display())?;
    }
    Ok(())
}

/// The folds: each cycle of the speed column held out once; with fewer than two cycles, the
/// time split (rows before the held-out start fit). Also gives the split for the black box and
/// a note for the report.
fn folds(
    table: &Table,
    rpm_name: &str,
    rpm: &[f64],
    holdout_from_s: Option<f64>,
) -> Result<(Split, Vec<Fold>, String)> {
    let t = &table.time_s;
    let by_cycle = Split::resolve(t, None, Some((rpm_name, rpm)), 0.25)
        .ok()
        .filter(|s| s.cycles(t).len() >= 2);
    if let Some(split) = by_cycle {
        let cycles = split.cycles(t);
        let folds = cycles
            .iter()
            .enumerate()
            .map(|(i, test)| {
                let top = test.iter().map(|&r| rpm[r]).fold(0.0, f64::max);
                Fold {
                    label: format!("cycle {} ({top:.0} rpm)", i + 1),
                    fit: (0..t.len()).filter(|r| !test.contains(r)).collect(),
                    test: test.clone(),
                }
            })
            .collect();
        let note = format!(
            "{} cycles (where \"{rpm_name}\" rises from 0): each held out once, the network \
             fitted on the others and run over the whole file from the speed profile",
            cycles.len()
        );
        return Ok((split, folds, note));
    }
    let split = Split::resolve(t, holdout_from_s, None, 0.25)?;
    let fit: Vec<usize> = (0..t.len())
        .filter(|&r| t[r] < split.holdout_from_s)
        .collect();
    let test: Vec<usize> = (fit.len()..t.len()).collect();
    let note = format!(
        "fewer than two cycles (\"{rpm_name}\" rises from 0 less than twice): cross-validation \
         by cycle is impossible; falling back to the time split: fit on the {} rows before {} s, \
         held out from there ({} rows)",
        fit.len(),
        split.holdout_from_s,
        test.len()
    );
    let folds = vec![Fold {
        label: format!("from {} s", split.holdout_from_s),
        fit,
        test,
    }];
    Ok((split, folds, note))
}

/// Per-channel RMSE of `pred` against `y` on `rows`.
pub(crate) fn rmse(y: &[Vec<f64>], pred: &[Vec<f64>], rows: &[usize]) -> Vec<f64> {
    y.iter()
        .zip(pred)
        .map(|(y, p)| {
            let ss: f64 = rows.iter().map(|&r| (y[r] - p[r]).powi(2)).sum();
            (ss / rows.len().max(1) as f64).sqrt()
        })
        .collect()
}

/// Fits each fold in each mode and scores the held-out rows.
fn grey_box_folds(
    data: &RcData,
    folds: &[Fold],
    modes: &[Mode],
    settings: &RcSettings,
) -> Result<GreyBoxFolds> {
    let n = data.time_s.len();
    let mut out = GreyBoxFolds {
        rmse: Vec::with_capacity(folds.len()),
        held_out_pred: vec![vec![f64::NAN; n]; data.drifts.len()],
        bound_notes: Vec::new(),
    };
    for f in folds {
        let mut per_mode: [Option<Vec<f64>>; 2] = [None, None];
        for &m in modes {
            let fit = rc_identify::identify(data, &f.fit, settings, m)
                .with_context(|| format!("identifying the network, fold {}", f.label))?;
            let pred = fit.predict(data)?;
            if m == Mode::SpeedOnly {
                for (k, p) in pred.iter().enumerate() {
                    for &r in &f.test {
                        out.held_out_pred[k][r] = p[r];
                    }
                }
            }
            if !fit.at_bounds.is_empty() {
                out.bound_notes.push(format!(
                    "{}, {}: {}",
                    f.label,
                    m.name(),
                    fit.at_bounds.join(", ")
                ));
            }
            per_mode[usize::from(m == Mode::WithTemps)] = Some(rmse(data.drifts, &pred, &f.test));
        }
        out.rmse.push(per_mode);
    }
    Ok(out)
}

/// fit-thermal's selection and plain least squares on the same split (its folds are the same
/// cycles; with one cycle, its held-out part is the time split's).
fn black_box(
    table: &Table,
    inputs: &[String],
    drifts: &[String],
    split: &Split,
    settings: &FitSettings,
) -> Result<BlackBox> {
    let model = thermal_fit::fit(table, inputs, drifts, split, settings)
        .context("fitting the black-box comparison (fit-thermal's models)")?;
    let ev = model
        .evaluation
        .as_ref()
        .context("the black-box fit has no evaluation")?;
    let rmse = if split.cycles(&table.time_s).len() >= 2 {
        ev.folds
            .iter()
            .map(|f| {
                f.model_rmse
                    .iter()
                    .zip(&f.plain_ls_rmse)
                    .map(|(m, p)| (*m, *p))
                    .collect()
            })
            .collect()
    } else {
        vec![ev
            .channels
            .iter()
            .map(|c| (c.model_rmse, c.plain_ls_rmse))
            .collect()]
    };
    let cols: Vec<&[f64]> = inputs.iter().filter_map(|c| table.column(c)).collect();
    let pred = model.predict(&table.time_s, &cols)?;
    Ok(BlackBox {
        rmse,
        forms: ev
            .channels
            .iter()
            .map(|c| c.form.name().to_string())
            .collect(),
        pred,
    })
}
