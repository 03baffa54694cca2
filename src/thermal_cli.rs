//! `fit-thermal` and `predict-thermal`: thermal-drift models from a user's CSV measurements
//! (file handling and terminal output; the model is `vmc_predict::thermal_fit`).

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};

use vmc_twin::files;
use vmc_twin::predict::thermal_fit::{
    self, Architecture, FeatureSpec, FitSettings, Split, TableRequest, ThermalModel,
};

/// Arguments of `fit-thermal`.
#[derive(clap::Args)]
pub struct FitThermalArgs {
    /// Measurements (CSV: header of column names with units, one row per sample, a time column).
    #[arg(long)]
    data: PathBuf,
    /// Input columns (comma-separated), e.g. t1_degc,t2_degc or with spindle_rpm.
    #[arg(long, value_delimiter = ',', required = true)]
    inputs: Vec<String>,
    /// Output (drift) columns to model (comma-separated), e.g. ch1_um,ch2_um.
    #[arg(long, value_delimiter = ',', required = true)]
    outputs: Vec<String>,
    /// Output model file (JSON).
    #[arg(short = 'o', long, default_value = "thermal_model.json")]
    out: PathBuf,
    /// Overwrite an existing output file.
    #[arg(long)]
    force: bool,
    /// Time column; default: the only column whose name starts with "time" (unit _s, _min, _h).
    #[arg(long)]
    time: Option<String>,
    /// Start of the held-out part, s (on the file's time axis). Default: the start of the last
    /// cycle of --cycle-col, else the last quarter of the time span.
    #[arg(long)]
    holdout_from_s: Option<f64>,
    /// Column whose rise from 0 starts a cycle (default: spindle_rpm if the file has it); the
    /// validation part is the cycle before the held-out one.
    #[arg(long)]
    cycle_col: Option<String>,
    /// Fraction of the rows before the held-out part (the last ones) that validate.
    #[arg(long, default_value_t = 0.25)]
    val_fraction: f64,
    /// Forms allowed: linear-mlp (linear regression + MLP on its residual where that helps on
    /// validation), auto (per output, the best on validation of linear, linear-mlp and mlp),
    /// mlp, or linear.
    #[arg(long, default_value = "linear-mlp")]
    arch: String,
    /// Time constants of the low-pass filter bank, s (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [900.0, 3600.0, 10800.0])]
    tau_s: Vec<f64>,
    /// Exponents k of the heat-input features (|speed|/1000 rpm)^k of speed inputs (columns
    /// whose unit is rpm, e.g. spindle_rpm): each as is and through the low-pass bank
    /// (comma-separated; "none": speed inputs are filtered like temperatures).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3")]
    speed_exponents: Vec<String>,
    /// Temperatures as differences to their mean at each row (gradients; blind to a uniform
    /// change of all temperatures).
    #[arg(long)]
    relative_to_mean: bool,
    /// Hidden widths tried (comma-separated); the best on validation is kept.
    #[arg(long, value_delimiter = ',', default_values_t = [4usize, 8])]
    hidden: Vec<usize>,
    /// Ridge λ candidates of the linear part (on normalised slopes; comma-separated); the
    /// best on validation is kept.
    #[arg(long, value_delimiter = ',', default_values_t = [0.01, 0.1, 1.0, 10.0, 100.0, 1e3, 1e4])]
    ridge: Vec<f64>,
    /// Members of each MLP ensemble (their predictions are averaged).
    #[arg(long, default_value_t = 5)]
    ensemble: usize,
    /// Seed of the network initialisation.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// Arguments of `predict-thermal`.
#[derive(clap::Args)]
pub struct PredictThermalArgs {
    /// Model file from `fit-thermal`.
    #[arg(long)]
    model: PathBuf,
    /// Measurements with (at least) the model's input columns and a time column.
    #[arg(long)]
    data: PathBuf,
    /// Output predictions (CSV).
    #[arg(short = 'o', long, default_value = "pred.csv")]
    out: PathBuf,
    /// Overwrite an existing output file.
    #[arg(long)]
    force: bool,
    /// Time column; default: the only column whose name starts with "time".
    #[arg(long)]
    time: Option<String>,
}

fn read_text(path: &PathBuf, what: &str) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("{}: cannot read {what}", path.display()))
}

/// `vmc-twin fit-thermal`.
pub fn fit_thermal(args: FitThermalArgs) -> Result<()> {
    files::check_writable(&args.out, args.force)?;
    let arch = Architecture::parse(&args.arch).with_context(|| {
        format!(
            "--arch must be auto, linear-mlp, mlp or linear, got \"{}\"",
            args.arch
        )
    })?;
    let source = args.data.display().to_string();
    let text = read_text(&args.data, "measurements")?;
    // Header first, to know whether the default cycle column exists.
    let header: Vec<String> = text
        .lines()
        .next()
        .unwrap_or("")
        .split(',')
        .map(|s| s.trim().trim_matches('"').to_string())
        .collect();
    // The cycle column also places the validation cycle when the held-out start is given.
    let cycle_col = args.cycle_col.clone().or_else(|| {
        header
            .iter()
            .any(|h| h == "spindle_rpm")
            .then(|| "spindle_rpm".to_string())
    });
    let mut required: Vec<(String, &'static str)> = args
        .inputs
        .iter()
        .map(|n| (n.clone(), "input"))
        .chain(args.outputs.iter().map(|n| (n.clone(), "output")))
        .collect();
    if let Some(c) = &cycle_col {
        required.push((c.clone(), "cycle"));
    }
    let request = TableRequest {
        time: args.time.clone(),
        required,
        optional: Vec::new(),
        min_rows: 20,
    };
    let table = thermal_fit::read_csv(&text, &source, &request)?;
    let split = Split::resolve(
        &table.time_s,
        args.holdout_from_s,
        cycle_col
            .as_deref()
            .and_then(|c| table.column(c).map(|v| (c, v))),
        args.val_fraction,
    )?;
    let settings = FitSettings {
        features: FeatureSpec {
            time_constants_s: args.tau_s.clone(),
            speed_exponents: parse_exponents(&args.speed_exponents)?,
            relative_to_mean: args.relative_to_mean,
        },
        architecture: arch,
        hidden_candidates: args.hidden.clone(),
        ridge_candidates: args.ridge.clone(),
        val_fraction: args.val_fraction,
        seed: args.seed,
        ensemble: args.ensemble,
        ..FitSettings::default()
    };
    let model =
        thermal_fit::fit(&table, &args.inputs, &args.outputs, &split, &settings).map_err(|e| {
            match e {
                // A value of the file, not a setting: name the file.
                e @ (thermal_fit::ThermalFitError::NonFiniteFeature { .. }
                | thermal_fit::ThermalFitError::TooLarge { .. }) => {
                    anyhow::Error::new(e).context(source.clone())
                }
                e => anyhow::Error::new(e),
            }
        })?;
    files::write_atomic(&args.out, model.to_json().as_bytes(), args.force)?;
    print!("{}", fit_report(&model, &table, &source));
    println!("wrote {}", args.out.display());
    Ok(())
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
    let _ = writeln!(
        s,
        "fit-thermal: {source}, {} rows, {} inputs → {} features, {} outputs; architecture {}: \
         linear ridge {}, residual net {}, direct net {}",
        table.len(),
        model.inputs.len(),
        model.features.width(&model.input_names()),
        model.outputs.len(),
        model.architecture.name(),
        ev.ridge,
        net(&ev.residual_net),
        net(&ev.direct_net),
    );
    let _ = writeln!(
        s,
        "split (time-ordered): {}; selection: train {} rows (t < {} s), validation {} rows; \
         final fit on both ({} rows for the nets); held out {} rows",
        ev.split.rule, ev.n_train, ev.split.val_from_s, ev.n_val, ev.n_fit_net, ev.n_holdout
    );
    let _ = writeln!(
        s,
        "held-out evaluation (RMS in each output's unit; ratio = residual RMS / raw drift RMS; \
         form chosen on validation):"
    );
    let _ = writeln!(
        s,
        "  {:<10} {:>8} {:>8} {:>8} {:>7} {:<10} {:>8} {:>7}  {:<8} | validation: linear  model",
        "output", "raw_rms", "constant", "linear", "ratio", "form", "model", "ratio", "aim"
    );
    for c in &ev.channels {
        let met = c.model_ratio.is_some_and(|r| r <= 0.25) && c.model_rmse < c.linear_rmse;
        let pct = |r: Option<f64>| {
            r.map(|v| format!("{:.1}%", 100.0 * v))
                .unwrap_or_else(|| "-".into())
        };
        let _ = writeln!(
            s,
            "  {:<10} {:>8.3} {:>8.3} {:>8.3} {:>7} {:<10} {:>8.3} {:>7}  {:<8} | {:>17.3} {:>6.3}",
            c.output.name,
            c.raw_rms,
            c.constant_rmse,
            c.linear_rmse,
            pct(c.linear_ratio),
            c.form.name(),
            c.model_rmse,
            pct(c.model_ratio),
            if met { "met" } else { "NOT met" },
            c.val_linear_rmse,
            c.val_model_rmse
        );
    }
    let _ = writeln!(
        s,
        "aim: residual RMS ≤ 25 % of the raw drift RMS and below the linear baseline's"
    );
    s
}

/// `vmc-twin predict-thermal`.
pub fn predict_thermal(args: PredictThermalArgs) -> Result<()> {
    files::check_writable(&args.out, args.force)?;
    let model_name = args.model.display().to_string();
    let model = ThermalModel::from_json(&read_text(&args.model, "model")?, &model_name)?;
    let source = args.data.display().to_string();
    let text = read_text(&args.data, "measurements")?;
    let request = TableRequest {
        time: args.time.clone(),
        required: model
            .inputs
            .iter()
            .map(|c| (c.name.clone(), "input"))
            .collect(),
        optional: model.outputs.iter().map(|c| c.name.clone()).collect(),
        min_rows: 1,
    };
    let table = thermal_fit::read_csv(&text, &source, &request)
        .with_context(|| format!("data does not fit model {model_name}"))?;
    let inputs: Vec<&[f64]> = model
        .inputs
        .iter()
        .filter_map(|c| table.column(&c.name))
        .collect();
    let pred = model
        .predict(&table.time_s, &inputs)
        .with_context(|| source.clone())?;
    let measured: Vec<(&str, &[f64])> = model
        .outputs
        .iter()
        .filter_map(|c| table.column(&c.name).map(|v| (c.name.as_str(), v)))
        .collect();
    let mut csv = String::from("time_s");
    for c in &model.outputs {
        let stem = c
            .name
            .strip_suffix(&format!("_{}", c.unit))
            .filter(|_| !c.unit.is_empty())
            .unwrap_or(&c.name);
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
    files::write_atomic(&args.out, csv.as_bytes(), args.force)?;
    println!(
        "predict-thermal: {} rows of {source} with model {model_name} ({} outputs{}) → {}",
        table.len(),
        model.outputs.len(),
        if measured.is_empty() {
            String::new()
        } else {
            format!(", {} measured columns kept", measured.len())
        },
        args.out.display()
    );
    Ok(())
}
