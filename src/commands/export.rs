//! `vmc-twin export`: the compensation tables a controller loads, sampled from a trained model at
//! a stated thermal state (readings given, or a warm-up run on the twin), with what each table
//! loses against the model. The tables and their checks are `vmc_tables`; this use case brings
//! the model to its state and writes the files.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::files;
use crate::predict::controller::Compensator;
use crate::predict::predictor::{AnyPredictor, ErrorPredictor};
use vmc_machine::machine::MachineSpec;
use vmc_machine::program;
use vmc_machine::sim::{self, SampleMode, SimConfig};
use vmc_machine::twin::Twin;
use vmc_tables::export::{
    cec_files, linuxcnc_files, report_text, CecExport, LinuxCncExport, OutputFile, Provenance,
};
use vmc_tables::linuxcnc::CompFileType;
use vmc_tables::readings::{observe_steady_state, parse_readings};
use vmc_tables::sample::{sample_tables, AxisTravel, SamplingSpec, Spacing};

/// A controller's table format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// LinuxCNC per-joint `COMP_FILE`s and their INI lines.
    Linuxcnc,
    /// Siemens 840D sl interpolatory compensation (CEC) program.
    SiemensCec,
}

/// The thermal state the tables are sampled at.
pub enum ThermalState {
    /// Sensor readings (°C) taken as a steady state: the text (`NAME=VALUE` items) and where it
    /// came from, for the report.
    Readings {
        /// The readings.
        text: String,
        /// The option's value or the file's name.
        source: String,
    },
    /// Warm-up programs run on the twin first, the model following them as in `run`.
    Warmup(Vec<PathBuf>),
}

/// What to export, validated.
pub struct ExportConfig {
    /// The model file.
    pub model: PathBuf,
    /// The machine (travel, sensors, tool; the twin for a warm-up).
    pub machine: MachineSpec,
    /// The twin's realisation.
    pub seed: u64,
    /// Accept a model calibrated on another machine or realisation.
    pub allow_other_machine: bool,
    /// The thermal state.
    pub thermal: ThermalState,
    /// The formats to write.
    pub formats: Vec<ExportFormat>,
    /// Largest distance between table points, mm.
    pub step_mm: f64,
    /// LinuxCNC `COMP_FILE_TYPE` (0 or 1).
    pub comp_file_type: u8,
    /// Siemens CEC: write the cross tables too.
    pub cross_tables: bool,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Overwrite existing files.
    pub force: bool,
}

/// The name of the report written beside the tables.
pub const REPORT_FILE: &str = "tables-report.txt";

/// Brings the model to the thermal state, samples the tables, writes them and the report, and
/// prints the report.
///
/// # Errors
/// An unreadable model, readings that do not name the model's sensors, warm-up programs that
/// cannot run, tables a controller would not load, outputs that may not be written.
pub fn export(cfg: &ExportConfig, out: &mut dyn Write) -> Result<()> {
    let (model, _) = super::model::load_for_machine(
        &cfg.machine,
        cfg.seed,
        &cfg.model,
        cfg.allow_other_machine,
        out,
    )?;
    let (mut model, state) = at_thermal_state(cfg, model)?;
    let axes = &cfg.machine.axes;
    let travel: [AxisTravel; 3] = std::array::from_fn(|k| AxisTravel {
        min_mm: axes.travel_min_mm[k],
        max_mm: axes.travel_max_mm[k],
    });
    let mut spec = SamplingSpec::new(travel);
    spec.spacing = Spacing::MaxStepMm(cfg.step_mm);
    let set = sample_tables(&mut model, &spec).context("sampling the tables")?;
    let provenance = Provenance {
        model: format!("{} ({})", cfg.model.display(), model.kind().name()),
        thermal_state: state,
    };
    let mut written: Vec<OutputFile> = Vec::new();
    for format in &cfg.formats {
        match format {
            ExportFormat::Linuxcnc => {
                let opts = LinuxCncExport {
                    file_type: if cfg.comp_file_type == 0 {
                        CompFileType::MeasuredPositions
                    } else {
                        CompFileType::Trims
                    },
                    ..LinuxCncExport::default()
                };
                written.extend(linuxcnc_files(&set, &opts, &provenance)?);
            }
            ExportFormat::SiemensCec => {
                let opts = CecExport {
                    cross_tables: cfg.cross_tables,
                    ..CecExport::default()
                };
                written.extend(cec_files(&set, &opts, &provenance)?);
            }
        }
    }
    let report = report_text(&set, &provenance);
    written.push(OutputFile {
        name: REPORT_FILE.to_string(),
        contents: report.clone(),
    });
    let names: Vec<String> = written.iter().map(|f| f.name.clone()).collect();
    let paths = files::prepare_output_folder(&cfg.out_dir, &names, cfg.force)?;
    for (file, path) in written.iter().zip(&paths) {
        files::write_atomic(path, file.contents.as_bytes(), cfg.force)?;
    }
    write!(out, "{report}")?;
    writeln!(
        out,
        "wrote {} files to {}: {}",
        names.len(),
        cfg.out_dir.display(),
        names.join(", ")
    )?;
    Ok(())
}

/// The model at the configured thermal state, and that state in words for the files' comments.
fn at_thermal_state(cfg: &ExportConfig, mut model: AnyPredictor) -> Result<(AnyPredictor, String)> {
    match &cfg.thermal {
        ThermalState::Readings { text, source } => {
            let readings =
                parse_readings(text, model.sensor_names()).with_context(|| source.clone())?;
            observe_steady_state(&mut model, &readings).with_context(|| source.clone())?;
            Ok((model, format!("steady state at the readings {source}")))
        }
        ThermalState::Warmup(programs) => warmed_up(cfg, model, programs),
    }
}

/// Runs the warm-ups on the twin with the model following the readings and the commanded
/// motion (as a compensator in the loop does), and gives the model afterwards.
fn warmed_up(
    cfg: &ExportConfig,
    model: AnyPredictor,
    programs: &[PathBuf],
) -> Result<(AnyPredictor, String)> {
    let machine = &cfg.machine;
    let names: Vec<String> = machine.sensors.iter().map(|s| s.name.clone()).collect();
    let mut ctrl = Compensator::for_machine(model, &names)
        .with_context(|| super::model::does_not_fit(&cfg.model, machine))?;
    let mut twin = Twin::new(machine, cfg.seed)?;
    let warm_cfg = SimConfig::default().sampling(SampleMode::Dwells);
    let mut start = machine.axes.home_mm;
    let mut total_s = 0.0;
    for path in programs {
        let plan = program::load_plan(path, machine, start)?;
        start = plan.end_mm();
        total_s += plan.duration_s();
        sim::execute(
            &mut twin,
            &plan,
            &warm_cfg,
            Some(&mut ctrl as &mut dyn sim::Controller),
            &mut sim::NullObserver,
        )
        .with_context(|| path.display().to_string())?;
    }
    let listed: Vec<String> = programs.iter().map(|p| p.display().to_string()).collect();
    let state = format!(
        "after the warm-up {} ({:.2} h) on the twin (seed {})",
        listed.join(", "),
        total_s / 3600.0,
        cfg.seed
    );
    Ok((ctrl.into_inner(), state))
}
