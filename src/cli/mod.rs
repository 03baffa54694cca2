//! The command line: argument structs (clap) and their conversion into the validated configs of
//! [`crate::commands`]. Raw arguments are checked here once; the use cases take configs.
//!
//! Options that several commands share are one flattened group each ([`MachineArg`],
//! [`SensorsArg`], [`ForceArg`], [`RrdArgs`], and [`MachineRunArgs`] of `run` and `replay`), so
//! a flag means the same everywhere.

mod campaign;
mod chatter;
mod control;
mod cut;
mod export;
mod fiveaxis;
mod identify_thermal;
mod lobes;
mod machine_run;
mod modal_fit;
mod placement;
mod replay;
mod thermal;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use crate::commands::{self, RrdOutput};
use crate::predict::predictor::ModelKind;
use crate::record;
use vmc_machine::sim::{SimConfig, SimConfigError};

pub use campaign::{parse_seeds, CampaignArgs, MergeArgs};
pub use chatter::ChatterArgs;
pub use control::{ControlAction, ControlArgs};
pub use cut::CutArgs;
pub use export::{ExportArgs, FormatArg};
pub use fiveaxis::{IdentifyArgs, ProbeCampaignArgs};
pub use identify_thermal::IdentifyThermalArgs;
pub use lobes::{LobesArgs, MethodArg};
pub use machine_run::MachineRunArgs;
pub use modal_fit::ModalFitArgs;
pub use replay::{LogFormatArg, ReplayArgs};
pub use thermal::{FitThermalArgs, PredictThermalArgs};

/// `vmc-twin`: the whole command line.
#[derive(Parser)]
#[command(
    name = "vmc-twin",
    version,
    about = "Digital twin of a 3-axis vertical machining center: run G-code on a machine with thermally drifting geometric errors and see where the tool really was"
)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand)]
pub enum Command {
    /// Run a G-code program on the twin and report the tool-tip error at each measurement point.
    Run(RunArgs),
    /// Run the virtual calibration campaign (laser sweeps, spindle test, squareness, volumetric
    /// grid, temperatures over typical thermal cycles) and write the dataset as CSV.
    Calibrate(CalibrateArgs),
    /// The main job: calibration campaign, training of the hybrid predictor and the two
    /// baselines, every face and body diagonal under held-out thermal states without and with
    /// compensation, and the report.
    Campaign(CampaignArgs),
    /// Combine the results of the shards of a sharded command (`campaign`, `select-sensors` or
    /// `lobes` with `--shard I/N`) into what the unsharded command writes and prints; refuses
    /// shards that do not belong together.
    Merge(MergeArgs),
    /// Train a predictor on a calibration dataset (CSV) and write the model (JSON).
    Train(TrainArgs),
    /// Fit a thermal-drift model (linear + MLP on filtered temperatures) on measured data (CSV),
    /// evaluate it on the held-out last cycle and write it (JSON).
    FitThermal(FitThermalArgs),
    /// Predict the drift columns of a CSV file with a model from `fit-thermal`.
    PredictThermal(PredictThermalArgs),
    /// Identify a small thermal RC network of the spindle (heat from the speed, conductances,
    /// capacities, drift gains) from measurements (CSV), compare it on held-out cycles with the
    /// black-box models and write it as a machine-file fragment (TOML).
    IdentifyThermal(IdentifyThermalArgs),
    /// Choose K temperature sensor locations among every thermal node (read as a sensor would),
    /// print the ranking with its evidence, compare compensation with the selected, default,
    /// random and all locations on held-out runs, and write the sensor set (TOML).
    SelectSensors(SelectArgs),
    /// Would this program crash the machine? Checks every move for travel limits and for
    /// contact of tool, holder and spindle nose with the table, fixture and stock.
    Check(CheckArgs),
    /// Stability lobes of a tool: the critical axial depth of cut against spindle speed, for a
    /// radial immersion and up or down milling (semi-discretisation, zero-order analytic or
    /// time-domain simulation).
    Lobes(LobesArgs),
    /// One cut in the time domain: the vibration at the tool tip, the cutting forces, the
    /// spectrum, the chatter frequency and the verdict (stable or chatter), with the
    /// semi-discretisation critical depth at that speed.
    Cut(CutArgs),
    /// Tool-tip modes from a measured receptance FRF (CSV of an impact test): frequency,
    /// damping ratio, stiffness and modal mass of each mode per direction, written as the tool
    /// file that `lobes`, `cut` and `chatter` take.
    ModalFit(ModalFitArgs),
    /// Active chatter control of a piezo-actuated blade: design LQG and H∞ controllers.
    Control(ControlArgs),
    /// Which cuts of a milling program will chatter? For every feed move in material: the
    /// engagement from a Z-map of the stock, the critical depth at its speed and immersion, the
    /// margin and a verdict; exit status 1 if a cut is unstable.
    Chatter(ChatterArgs),
    /// Write the compensation tables a controller loads (LinuxCNC per-joint COMP_FILEs, Siemens
    /// 840D sl CEC) from a trained model at a thermal state (readings or a warm-up on the twin),
    /// with what each table loses against the model.
    Export(ExportArgs),
    /// Play a controller's servo log (commanded positions, optionally its corrections) on the
    /// twin after its warm-ups and report the tool-tip error before and after compensation, as
    /// `run` does.
    Replay(ReplayArgs),
    /// Print the canonical machine actions of a program in the call syntax of LinuxCNC's
    /// `rs274`, to compare with a controller.
    Interpret(InterpretArgs),
    /// Probe the reference sphere of a five-axis machine in N configurations with the virtual
    /// touch probe and write the probing file (CSV).
    ProbeCampaign(ProbeCampaignArgs),
    /// Identify the geometric errors of a five-axis machine from a probing file: the
    /// identifiability report, the parameters with their uncertainty, and the held-out judge.
    Identify(IdentifyArgs),
    /// Measure the speed figures (compensation query, 8 h of machine time, campaign) and how
    /// they scale with the interpolation cycle and the number of calibration cycles.
    Bench(BenchArgs),
}

/// `--machine`.
#[derive(clap::Args)]
pub struct MachineArg {
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    pub machine: Option<PathBuf>,
}

impl MachineArg {
    /// The machine of this option (the reference machine without it), with the sensor set of
    /// `sensors` if one is given.
    ///
    /// # Errors
    /// See [`commands::load_machine`].
    pub fn load(&self, sensors: Option<&SensorsArg>) -> Result<vmc_machine::machine::MachineSpec> {
        commands::load_machine(
            self.machine.as_deref(),
            sensors.and_then(|s| s.sensors.as_deref()),
        )
    }
}

/// `--sensors`.
#[derive(clap::Args)]
pub struct SensorsArg {
    /// Sensor set (TOML `[[sensors]]`, e.g. from `select-sensors`) replacing the machine's own.
    #[arg(long)]
    pub sensors: Option<PathBuf>,
}

/// `--force`.
#[derive(clap::Args)]
pub struct ForceArg {
    /// Overwrite existing output files.
    #[arg(long)]
    pub force: bool,
}

/// Rerun recording options (run, campaign, probe-campaign, identify).
#[derive(clap::Args)]
pub struct RrdArgs {
    /// Write a Rerun recording (.rrd) of the run; open it with `rerun FILE.rrd`.
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    /// Error magnification of the drawn paths and arrows in the recording (default 2000: a
    /// 20 µm error is drawn as 40 mm).
    #[arg(long, requires = "rrd", value_name = "K")]
    pub magnify: Option<f64>,
}

impl RrdArgs {
    /// Recording settings, checked. The path is checked by the command before any simulation,
    /// once the output folder it may sit in exists.
    fn checked(&self) -> Result<Option<RrdOutput>> {
        let Some(path) = &self.rrd else {
            return Ok(None);
        };
        let settings = record::RecordSettings {
            magnify: self.magnify.unwrap_or(record::DEFAULT_MAGNIFY),
            ..Default::default()
        };
        settings
            .validate()
            .context("--magnify must be a positive number")?;
        Ok(Some(RrdOutput {
            path: path.clone(),
            settings,
        }))
    }
}

/// Model class of `train --kind`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum KindArg {
    /// 4 MLPs + kinematic synthesis.
    Hybrid,
    /// One MLP from position and temperatures to the volumetric error.
    Volumetric,
    /// Linear regression.
    Linear,
}

impl From<KindArg> for ModelKind {
    fn from(k: KindArg) -> Self {
        match k {
            KindArg::Hybrid => ModelKind::Hybrid,
            KindArg::Volumetric => ModelKind::Volumetric,
            KindArg::Linear => ModelKind::Linear,
        }
    }
}

/// Arguments of `run`.
#[derive(clap::Args)]
// The shared `--strict` and `--allow-other-machine` need `--model` here (`replay` also takes the
// model as the value of its `--compensate`).
#[command(
    mut_arg("strict", |a| a.requires("model")),
    mut_arg("allow_other_machine", |a| a.requires("model"))
)]
pub struct RunArgs {
    /// G-code program to run (e.g. trajectories/diag_xy.ngc).
    pub program: PathBuf,
    #[command(flatten)]
    pub run: MachineRunArgs,
    /// Put the model in the control loop: each point is reported before and after compensation.
    #[arg(long, requires = "model")]
    pub compensate: bool,
    /// Also measure at every interpolation cycle during motion (not only at dwells).
    #[arg(long)]
    pub every_cycle: bool,
    /// Interpolation cycle, ms: with --every-cycle (default 1 ms), and the measurement period
    /// during motion of a program without G4 dwells (default 1000 ms).
    #[arg(long)]
    pub interp_cycle_ms: Option<f64>,
    #[command(flatten)]
    pub placement: placement::PlacementArgs,
    /// Five-axis machine: the identified model (JSON from `identify`) to compensate with; each
    /// point is reported before and after.
    #[arg(long, conflicts_with = "model")]
    pub identified: Option<PathBuf>,
    /// Five-axis machine with --identified: `on` (default) corrects the rotary axes for the
    /// tool-axis error as well, `off` the linear axes only.
    #[arg(long, value_enum, requires = "identified")]
    pub rotary_comp: Option<fiveaxis::RotaryComp>,
    #[command(flatten)]
    pub rrd: RrdArgs,
    /// With --compensate: `on` (default) updates the model's drift from the program's probe
    /// moves touching a `reference = true` artefact of the setup, `off` only reports them.
    #[arg(long, value_name = "on|off", requires = "compensate", hide_possible_values = true,
          action = clap::ArgAction::Set,
          value_parser = clap::builder::BoolishValueParser::new())]
    pub probe_update: Option<bool>,
}

impl RunArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine or sensor set, a non-positive cycle or step, a model
    /// without `--compensate`, a bad recording path or magnification, an option the machine's
    /// kind does not take.
    pub fn config(self) -> Result<commands::run::RunTarget> {
        if let Some(path) = &self.run.machine.machine {
            if commands::is_five_axis_machine(path)? {
                return fiveaxis::run_config(self).map(commands::run::RunTarget::FiveAxis);
            }
        }
        if let Some(path) = &self.identified {
            anyhow::bail!(
                "{}: --identified takes the identified model of a five-axis machine; this machine has no rotary axes (use --model with --compensate)",
                path.display()
            );
        }
        self.three_axis_config()
            .map(commands::run::RunTarget::ThreeAxis)
    }

    fn three_axis_config(self) -> Result<commands::run::RunConfig> {
        let machine = self.run.load_machine()?;
        let interp_cycle_ms = self.interp_cycle_ms.unwrap_or(1.0);
        let thermal_step_s = self.run.thermal_step_s;
        let sim = SimConfig::new(thermal_step_s, interp_cycle_ms * 1e-3).map_err(|e| match e {
            SimConfigError::ThermalStep(_) => {
                anyhow::anyhow!("--thermal-step-s must be > 0, got {thermal_step_s}")
            }
            SimConfigError::InterpCycle(_) => {
                anyhow::anyhow!("--interp-cycle-ms must be > 0, got {interp_cycle_ms}")
            }
        })?;
        if let (Some(path), false) = (&self.run.model, self.compensate) {
            anyhow::bail!(
                "{}: a model was given without --compensate; add --compensate to put it in the loop",
                path.display()
            );
        }
        let force = self.run.force.force;
        let rrd = self.rrd.checked()?;
        let offsets = placement::nine_offsets(machine.axes.work_offsets_mm);
        let placement = self.placement.placement(&self.program, offsets)?;
        Ok(commands::run::RunConfig {
            motion_sample_s: self
                .interp_cycle_ms
                .map_or(commands::run::MOTION_SAMPLE_S, |ms| ms * 1e-3),
            placement,
            program: self.program,
            machine,
            tools: self.run.tool_table()?,
            seed: self.run.seed,
            warmups: self.run.warmup,
            out_dir: self.run.out,
            force,
            every_cycle: self.every_cycle,
            sim,
            model: self.run.model,
            rrd,
            strict: self.run.strict,
            allow_other_machine: self.run.allow_other_machine,
            probe_update: self.probe_update.unwrap_or(true),
        })
    }
}

/// The tool table of `--tools`, or none (the machine's own tool for every number).
fn load_tool_table(path: Option<&Path>) -> Result<vmc_machine::tools::ToolTable> {
    Ok(path
        .map(vmc_machine::tools::ToolTable::load)
        .transpose()?
        .unwrap_or_default())
}

/// Arguments of `calibrate`.
#[derive(clap::Args)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub machine: MachineArg,
    #[command(flatten)]
    pub sensors: SensorsArg,
    /// Machine realisation (seed of its random error parts).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output dataset file.
    #[arg(short = 'o', long, default_value = "calibration.csv")]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
    /// Minutes between measurement blocks.
    #[arg(long, default_value_t = 30.0)]
    pub measure_every_min: f64,
}

impl CalibrateArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine or sensor set, a measurement interval under a minute.
    pub fn config(self) -> Result<commands::calibrate::CalibrateConfig> {
        let machine = self.machine.load(Some(&self.sensors))?;
        if !(self.measure_every_min >= 1.0 && self.measure_every_min.is_finite()) {
            anyhow::bail!(
                "--measure-every-min must be at least 1 (minute), got {:e}",
                self.measure_every_min
            );
        }
        Ok(commands::calibrate::CalibrateConfig {
            machine,
            seed: self.seed,
            out: self.out,
            force: self.force.force,
            measure_every_s: self.measure_every_min * 60.0,
        })
    }
}

/// Arguments of `train`.
#[derive(clap::Args)]
pub struct TrainArgs {
    /// Calibration dataset (CSV, as written by `vmc-twin calibrate`).
    #[arg(long)]
    pub data: PathBuf,
    /// Model class: hybrid (4 MLPs + kinematic synthesis), volumetric (one MLP) or linear.
    #[arg(long, value_enum, default_value = "hybrid")]
    pub kind: KindArg,
    /// Machine description for the nominal geometry and sensor check; default: reference.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    #[command(flatten)]
    pub sensors: SensorsArg,
    /// Seed of the network initialisation.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output model file.
    #[arg(short = 'o', long, default_value = "model.json")]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
    /// Opt-in, hybrid only: the spindle part also takes the commanded spindle speed (the
    /// dataset's `spindle_rpm` column) as heat input; `run --compensate` then feeds it the
    /// program's speed.
    #[arg(long)]
    pub spindle_speed: bool,
}

impl TrainArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine or sensor set, `--spindle-speed` with a baseline.
    pub fn config(self) -> Result<commands::train::TrainConfig> {
        let machine =
            commands::load_machine(self.machine.as_deref(), self.sensors.sensors.as_deref())?;
        let kind = ModelKind::from(self.kind);
        if self.spindle_speed {
            anyhow::ensure!(
                kind == ModelKind::Hybrid,
                "--spindle-speed applies to the hybrid model only (its spindle part), not to --kind {}",
                kind.name()
            );
        }
        Ok(commands::train::TrainConfig {
            data: self.data,
            kind,
            machine,
            seed: self.seed,
            out: self.out,
            force: self.force.force,
            spindle_speed: self.spindle_speed,
        })
    }
}

/// Arguments of `select-sensors`.
#[derive(clap::Args)]
pub struct SelectArgs {
    /// Candidate locations: `all` (every thermal node + ambient) or a comma-separated list of
    /// node names (ambient is always a candidate: it is the cold reference).
    #[arg(long, default_value = "all")]
    pub candidates: String,
    /// Sensors to select besides ambient.
    #[arg(long, default_value_t = 11)]
    pub count: usize,
    #[command(flatten)]
    pub machine: MachineArg,
    /// Machine realisation of the selection campaign.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Machine seeds of the comparison on held-out runs (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1u64])]
    pub compare_seeds: Vec<u64>,
    /// Random sets of K locations in the comparison.
    #[arg(long, default_value_t = 3)]
    pub random_draws: usize,
    /// Only select; skip the comparison.
    #[arg(long)]
    pub no_compare: bool,
    /// Output sensor set (TOML `[[sensors]]`, usable with `--sensors` or in a machine file).
    #[arg(short = 'o', long, default_value = "sensors.toml")]
    pub out: PathBuf,
    /// Also write the study as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
    /// Run only shard I of N of the compare seeds (1-based, e.g. 2/4) and write its results
    /// under --shard-dir for `vmc-twin merge`, which writes the sensor set (and the JSON study)
    /// under the file names of --out (and --json).
    #[arg(long, value_name = "I/N", requires = "shard_dir")]
    pub shard: Option<String>,
    /// Folder of a shard's results (shard.json, selection.json, compare.jsonl); with --shard.
    #[arg(long, value_name = "DIR", requires = "shard")]
    pub shard_dir: Option<PathBuf>,
}

impl SelectArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine, a comparison seed given twice, candidates that are not
    /// thermal nodes (or named twice, or empty), a bad shard or a shard with --no-compare.
    pub fn config(self) -> Result<commands::select_sensors::SelectConfig> {
        let shard = self
            .shard
            .as_deref()
            .map(str::parse::<crate::shard::Shard>)
            .transpose()?;
        if let Some(s) = shard {
            if self.no_compare {
                anyhow::bail!("--shard {s} splits the comparison over the compare seeds; with --no-compare there is nothing to split: run without --shard");
            }
        }
        let machine = self.machine.load(None)?;
        let inputs = commands::input_fingerprints(self.machine.machine.as_deref(), None)?;
        commands::check_distinct_seeds("--compare-seeds", &self.compare_seeds)?;
        let only = commands::select_sensors::parse_candidates(&self.candidates, &machine)?;
        Ok(commands::select_sensors::SelectConfig {
            machine,
            only,
            count: self.count,
            seed: self.seed,
            compare_seeds: if self.no_compare {
                Vec::new()
            } else {
                self.compare_seeds
            },
            random_draws: self.random_draws,
            out: self.out,
            json: self.json,
            force: self.force.force,
            shard,
            shard_dir: self.shard_dir,
            inputs,
            command_line: std::env::args().collect(),
        })
    }
}

/// Arguments of `check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// G-code program to check.
    pub program: PathBuf,
    /// Machine description (TOML) with a `[collision]` section; default: the reference machine.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Fixture file (TOML): vise, clamps and stock on the table.
    #[arg(long)]
    pub fixture: Option<PathBuf>,
    /// Tool table (TOML, `[[tool]]` with `number`, `length_mm`, `diameter_mm`): the tool body
    /// follows `M6`; default: the machine's own tool for every number.
    #[arg(long)]
    pub tools: Option<PathBuf>,
    /// Also write a Rerun recording: the program's motion with every problem drawn at its time
    /// and place (magenta points on `paths/events`, entries in the `events` log).
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    /// Overwrite an existing recording.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub placement: placement::PlacementArgs,
}

impl CheckArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine, a bad recording path.
    pub fn config(self) -> Result<commands::check::CheckConfig> {
        let machine = commands::load_machine(self.machine.as_deref(), None)?;
        if let Some(path) = &self.rrd {
            record::check_rrd_path(path, self.force)?;
        }
        let offsets = placement::nine_offsets(machine.axes.work_offsets_mm);
        let placement = self.placement.placement(&self.program, offsets)?;
        Ok(commands::check::CheckConfig {
            placement,
            program: self.program,
            machine,
            fixture: self.fixture,
            rrd: self.rrd,
            force: self.force,
            tools: load_tool_table(self.tools.as_deref())?,
        })
    }
}

/// Milling direction of `lobes --milling` and `cut --milling`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum MillingArg {
    /// Up (conventional) milling.
    Up,
    /// Down (climb) milling.
    Down,
}

/// Arguments of `interpret`.
#[derive(clap::Args)]
pub struct InterpretArgs {
    /// G-code program to interpret.
    pub program: PathBuf,
    /// Machine description (TOML) whose home position and work offsets G54…G59 to use;
    /// default: start at the origin with zero work offsets, as `rs274` does.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Tool table (TOML, `[[tool]]` with `number`, `length_mm`, `diameter_mm`) for G43 H and
    /// G41/G42 D; default: every tool has length 0 and diameter 0.
    #[arg(long)]
    pub tools: Option<PathBuf>,
    #[command(flatten)]
    pub placement: placement::PlacementArgs,
}

impl InterpretArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine or tool table.
    pub fn config(self) -> Result<commands::interpret::InterpretConfig> {
        let mut interp = vmc_gcode::interp::InterpConfig::default();
        if let Some(path) = &self.tools {
            (interp.tool_lengths_mm, interp.tool_diameters_mm) =
                commands::interpret::load_tools(path)?;
        }
        let mut offsets = interp.work_offsets_mm;
        if let Some(path) = &self.machine {
            let machine = commands::load_machine(Some(path), None)?;
            interp.start_mm = machine.axes.home_mm;
            offsets = placement::nine_offsets(machine.axes.work_offsets_mm);
        }
        // Subroutine files: the program's folder, then --subroutines.
        let placement = self.placement.placement(&self.program, offsets)?;
        interp.work_offsets_mm = placement.work_offsets_mm;
        interp.subroutine_dirs = placement.search_path(Some(&self.program));
        Ok(commands::interpret::InterpretConfig {
            program: self.program,
            interp,
        })
    }
}

/// Arguments of `bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Repeats of the cheap measurements (median reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Skip the campaign scaling (the slowest part, ~1 min).
    #[arg(long)]
    pub quick: bool,
}

impl BenchArgs {
    /// The validated config.
    ///
    /// # Errors
    /// `--repeats 0`.
    pub fn config(self) -> Result<commands::bench::BenchConfig> {
        if self.repeats == 0 {
            anyhow::bail!("--repeats must be at least 1");
        }
        Ok(commands::bench::BenchConfig {
            repeats: self.repeats,
            quick: self.quick,
        })
    }
}

#[cfg(test)]
mod tests;
