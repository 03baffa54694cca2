//! `vmc-twin train`: a predictor trained on a calibration dataset, written as a model file.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use crate::files;
use crate::predict::dataset::Dataset;
use crate::predict::predictor::{self, ErrorPredictor, ModelKind, Settings, TrainSummary};
use crate::predict::provenance::TrainedOn;
use crate::studies::campaign::{self, ForMachine};
use vmc_machine::machine::MachineSpec;

/// What to train, validated.
pub struct TrainConfig {
    /// Calibration dataset (CSV).
    pub data: PathBuf,
    /// Model class.
    pub kind: ModelKind,
    /// The machine: nominal geometry and sensor set.
    pub machine: MachineSpec,
    /// Seed of the network initialisation.
    pub seed: u64,
    /// Output model file.
    pub out: PathBuf,
    /// Overwrite an existing output file.
    pub force: bool,
    /// The hybrid's spindle part also takes the commanded spindle speed (hybrid only).
    pub spindle_speed: bool,
}

/// Trains the model, writes it and prints each net's validation figures.
///
/// # Errors
/// An output that may not be written, an unreadable or invalid dataset, a training failure.
pub fn train(cfg: &TrainConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    let name = cfg.data.display().to_string();
    let text = files::read_named(&cfg.data, "dataset")?;
    let data = Dataset::from_csv(&text, &name)?;
    let mut settings = Settings {
        seed: cfg.seed,
        ..Settings::for_machine(&cfg.machine)
    };
    if cfg.spindle_speed {
        settings = settings.with_spindle_speed_input();
    }
    let settings = campaign::fit_to_data(settings, &data);
    if cfg.kind == ModelKind::Hybrid && !campaign::uses_axis_feeds(&data) {
        writeln!(
            out,
            "note: {name} has no axis-feed columns (x_feed_mm_per_min, y_feed_mm_per_min, \
             z_feed_mm_per_min on every row): the hybrid learns without the axes' commanded feeds"
        )?;
    }
    let geometry = cfg.machine.geometry();
    // The machine the data names, else the one given (realisation unknown).
    let machine = match data.origin.clone() {
        Some(id) => id,
        None => {
            writeln!(
                out,
                "note: {name} has no `# machine:` line: the model records machine `{}` with an \
                 unknown realisation, and `run` says so wherever it is used",
                cfg.machine.machine.name
            )?;
            cfg.machine.identity(None)
        }
    };
    let trained_on = |sensors: &[String]| TrainedOn {
        machine: Some(machine.clone()),
        inputs: data.input_ranges(sensors),
    };
    let (json, summary) = match cfg.kind {
        ModelKind::Hybrid => {
            let (m, s) = predictor::train_hybrid(&data, &geometry, &settings)?;
            let mut on = trained_on(m.sensor_names());
            on.inputs.axis_feeds = predictor::feed_ranges(&data, &settings.axis_feed_taus_s);
            (m.to_json_string_with(Some(&on))?, s)
        }
        ModelKind::Volumetric => {
            let (m, s) = predictor::train_volumetric(&data, &geometry, &settings)?;
            (
                m.to_json_string_with(Some(&trained_on(m.sensor_names())))?,
                s,
            )
        }
        ModelKind::Linear => {
            let (m, s) = predictor::train_linear(&data, &geometry, &settings)?;
            (
                m.to_json_string_with(Some(&trained_on(m.sensor_names())))?,
                s,
            )
        }
    };
    files::write_atomic(&cfg.out, json.as_bytes(), cfg.force)?;
    writeln!(
        out,
        "trained {} model on {name} ({} records, sensors {}):",
        cfg.kind.name(),
        data.records.len(),
        summary.sensors.join(", ")
    )?;
    write_nets(&summary, out)?;
    writeln!(out, "wrote {}", cfg.out.display())?;
    Ok(())
}

/// One line per trained net: hidden units, split sizes and validation RMSE per output.
fn write_nets(summary: &TrainSummary, out: &mut dyn Write) -> std::io::Result<()> {
    for n in &summary.nets {
        let val: Vec<String> = n
            .outputs
            .iter()
            .zip(&n.val_rmse)
            .map(|(o, v)| format!("{o} {v:.3}"))
            .collect();
        writeln!(
            out,
            "  {:<11} hidden {:>4}  train {:>5} val {:>5}  validation RMSE: {}",
            n.name,
            n.hidden_units
                .map(|h| h.to_string())
                .unwrap_or_else(|| "-".into()),
            n.n_train,
            n.n_val,
            val.join(", ")
        )?;
    }
    Ok(())
}
