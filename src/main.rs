//! `vmc-twin`: the command line over the library. Arguments are validated into a config once;
//! every failure is one line on stderr and a non-zero exit code.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use vmc_twin::calibration;
use vmc_twin::machine::MachineSpec;
use vmc_twin::placement;
use vmc_twin::program;
use vmc_twin::progress::Progress;
use vmc_twin::record;
use vmc_twin::report::{self, RunLog};
use vmc_twin::sim::{self, Observer, RunStart, SampleMode, SimConfig};
use vmc_twin::study;
use vmc_twin::twin::Twin;

mod thermal_cli;

#[derive(Parser)]
#[command(
    name = "vmc-twin",
    version,
    about = "Digital twin of a 3-axis vertical machining center: run G-code on a machine with thermally drifting geometric errors and see where the tool really was"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a G-code program on the twin and report the tool-tip error at each measurement point.
    Run(RunArgs),
    /// Run the virtual calibration campaign (laser sweeps, spindle test, squareness, volumetric
    /// grid, temperatures over typical thermal cycles) and write the dataset as CSV.
    Calibrate(CalibrateArgs),
    /// The main job: calibration campaign, training of the hybrid predictor and the two
    /// baselines, every face and body diagonal under held-out thermal states without and with
    /// compensation, and the report.
    Campaign(CampaignArgs),
    /// Train a predictor on a calibration dataset (CSV) and write the model (JSON).
    Train(TrainArgs),
    /// Fit a thermal-drift model (linear + MLP on filtered temperatures) on measured data (CSV),
    /// evaluate it on the held-out last cycle and write it (JSON).
    FitThermal(thermal_cli::FitThermalArgs),
    /// Predict the drift columns of a CSV file with a model from `fit-thermal`.
    PredictThermal(thermal_cli::PredictThermalArgs),
    /// Choose K temperature sensor locations among every thermal node (read as a sensor would),
    /// print the ranking with its evidence, compare compensation with the selected, default,
    /// random and all locations on held-out runs, and write the sensor set (TOML).
    SelectSensors(SelectArgs),
    /// Would this program crash the machine? Checks every move for travel limits and for
    /// contact of tool, holder and spindle nose with the table, fixture and stock.
    Check(CheckArgs),
    /// Measure the speed figures (compensation query, 8 h of machine time, campaign) and how
    /// they scale with the interpolation cycle and the number of calibration cycles.
    Bench(BenchArgs),
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Repeats of the cheap measurements (median reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Skip the campaign scaling (the slowest part, ~1 min).
    #[arg(long)]
    quick: bool,
}

#[derive(clap::Args)]
struct SelectArgs {
    /// Candidate locations: `all` (every thermal node + ambient) or a comma-separated list of
    /// node names (ambient is always a candidate: it is the cold reference).
    #[arg(long, default_value = "all")]
    candidates: String,
    /// Sensors to select besides ambient.
    #[arg(long, default_value_t = 11)]
    count: usize,
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Machine realisation of the selection campaign.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Machine seeds of the comparison on held-out runs (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1u64])]
    compare_seeds: Vec<u64>,
    /// Random sets of K locations in the comparison.
    #[arg(long, default_value_t = 3)]
    random_draws: usize,
    /// Only select; skip the comparison.
    #[arg(long)]
    no_compare: bool,
    /// Output sensor set (TOML `[[sensors]]`, usable with `--sensors` or in a machine file).
    #[arg(short = 'o', long, default_value = "sensors.toml")]
    out: PathBuf,
    /// Also write the study as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Overwrite existing output files.
    #[arg(long)]
    force: bool,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// G-code program to check.
    program: PathBuf,
    /// Machine description (TOML) with a [collision] section; default: the reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Fixture file (TOML): vise, clamps and stock on the table.
    #[arg(long)]
    fixture: Option<PathBuf>,
    /// Also write a Rerun recording: the program's motion with every problem drawn at its time
    /// and place (magenta points on `paths/events`, entries in the `events` log).
    #[arg(long, value_name = "FILE.rrd")]
    rrd: Option<PathBuf>,
    /// Overwrite an existing recording.
    #[arg(long)]
    force: bool,
}

#[derive(clap::Args)]
struct CampaignArgs {
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Sensor set (TOML `[[sensors]]`, e.g. from `select-sensors`) replacing the machine's own.
    #[arg(long)]
    sensors: Option<PathBuf>,
    /// Machine realisations to calibrate and evaluate (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1u64, 2, 3])]
    seeds: Vec<u64>,
    /// Folder for report.json and the trained models (created if missing).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Overwrite existing output files.
    #[arg(long)]
    force: bool,
    /// Opt-in: the hybrid's spindle part also takes the commanded spindle speed as heat input
    /// (outside DESIGN §3's boundary as written, which allows temperature readings and
    /// commanded axis positions; see the README).
    #[arg(long)]
    spindle_speed: bool,
    #[command(flatten)]
    rrd: RrdArgs,
}

/// Rerun recording options (run and campaign).
#[derive(clap::Args)]
struct RrdArgs {
    /// Write a Rerun recording (.rrd) of the run; open it with `rerun FILE.rrd`.
    #[arg(long, value_name = "FILE.rrd")]
    rrd: Option<PathBuf>,
    /// Error magnification of the drawn paths and arrows in the recording (default 2000: a
    /// 20 µm error is drawn as 40 mm).
    #[arg(long, requires = "rrd", value_name = "K")]
    magnify: Option<f64>,
}

impl RrdArgs {
    /// Recording settings, checked; the output path checked before any simulation.
    fn checked(&self, force: bool) -> Result<Option<(PathBuf, record::RecordSettings)>> {
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
        record::check_rrd_path(path, force)?;
        Ok(Some((path.clone(), settings)))
    }
}

#[derive(clap::Args)]
struct TrainArgs {
    /// Calibration dataset (CSV, as written by `vmc-twin calibrate`).
    #[arg(long)]
    data: PathBuf,
    /// Model class: hybrid (4 MLPs + kinematic synthesis), volumetric (one MLP) or linear.
    #[arg(long, default_value = "hybrid")]
    kind: String,
    /// Machine description for the nominal geometry and sensor check; default: reference.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Sensor set (TOML `[[sensors]]`, e.g. from `select-sensors`) replacing the machine's own.
    #[arg(long)]
    sensors: Option<PathBuf>,
    /// Seed of the network initialisation.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output model file.
    #[arg(short = 'o', long, default_value = "model.json")]
    out: PathBuf,
    /// Overwrite an existing output file.
    #[arg(long)]
    force: bool,
    /// Opt-in, hybrid only: the spindle part also takes the commanded spindle speed (the
    /// dataset's `spindle_rpm` column) as heat input; `run --compensate` then feeds it the
    /// program's speed (see the README).
    #[arg(long)]
    spindle_speed: bool,
}

#[derive(clap::Args)]
struct CalibrateArgs {
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Sensor set (TOML `[[sensors]]`, e.g. from `select-sensors`) replacing the machine's own.
    #[arg(long)]
    sensors: Option<PathBuf>,
    /// Machine realisation (seed of its random error parts).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output dataset file.
    #[arg(short = 'o', long, default_value = "calibration.csv")]
    out: PathBuf,
    /// Overwrite an existing output file.
    #[arg(long)]
    force: bool,
    /// Minutes between measurement blocks.
    #[arg(long, default_value_t = 30.0)]
    measure_every_min: f64,
}

#[derive(clap::Args)]
struct RunArgs {
    /// G-code program to run (e.g. trajectories/diag_xy.ngc).
    program: PathBuf,
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Sensor set (TOML `[[sensors]]`, e.g. from `select-sensors`) replacing the machine's own.
    #[arg(long)]
    sensors: Option<PathBuf>,
    /// Seed of the machine's random error parts and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Thermal loading program(s) to run first (repeatable, run in order).
    #[arg(long)]
    warmup: Vec<PathBuf>,
    /// Folder for samples.csv and summary.json (created if missing).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Overwrite existing output files.
    #[arg(long)]
    force: bool,
    /// Also measure at every interpolation cycle during motion (not only at dwells).
    #[arg(long)]
    every_cycle: bool,
    /// Interpolation cycle, ms (with --every-cycle).
    #[arg(long, default_value_t = 1.0)]
    interp_cycle_ms: f64,
    /// Thermal integration and sensor sampling step, s.
    #[arg(long, default_value_t = 1.0)]
    thermal_step_s: f64,
    /// Trained model (JSON, from `train` or `campaign --out`) for compensation.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Put the model in the control loop: each point is reported before and after compensation.
    #[arg(long, requires = "model")]
    compensate: bool,
    #[command(flatten)]
    rrd: RrdArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(args),
        Command::Calibrate(args) => calibrate(args),
        Command::Campaign(args) => run_campaign(args),
        Command::Train(args) => train(args),
        Command::SelectSensors(args) => select_sensors(args),
        Command::Bench(args) => bench(args),
        Command::FitThermal(args) => thermal_cli::fit_thermal(args),
        Command::PredictThermal(args) => thermal_cli::predict_thermal(args),
        Command::Check(args) => check(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vmc-twin: error: {}", error_text(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, `: `-joined (each error type prints its cause once: either in
/// its message or as its source, not both).
fn error_text(e: &anyhow::Error) -> String {
    format!("{e:#}")
}

fn load_machine(path: Option<&Path>, sensors: Option<&Path>) -> Result<MachineSpec> {
    let spec = match path {
        Some(p) => MachineSpec::load(p)?,
        None => MachineSpec::reference(),
    };
    let Some(file) = sensors else {
        return Ok(spec);
    };
    let name = file.display().to_string();
    let text =
        std::fs::read_to_string(file).with_context(|| format!("{name}: cannot read sensor set"))?;
    let set = placement::SensorSet::from_toml_str(&text, &name)?;
    let spec = placement::with_sensors(&spec, set.sensors).with_context(|| {
        format!(
            "{name}: sensor set does not fit machine {}",
            spec.machine.name
        )
    })?;
    Ok(spec)
}

fn run(args: RunArgs) -> Result<()> {
    let machine = load_machine(args.machine.as_deref(), args.sensors.as_deref())?;
    if !(args.interp_cycle_ms > 0.0 && args.interp_cycle_ms.is_finite()) {
        anyhow::bail!(
            "--interp-cycle-ms must be > 0, got {}",
            args.interp_cycle_ms
        );
    }
    if !(args.thermal_step_s > 0.0 && args.thermal_step_s.is_finite()) {
        anyhow::bail!("--thermal-step-s must be > 0, got {}", args.thermal_step_s);
    }
    // Check everything the user gave before minutes of simulation: programs and outputs.
    let mut start = machine.axes.home_mm;
    let mut warmups = Vec::new();
    for w in &args.warmup {
        let plan = program::load_plan(w, &machine, start)?;
        start = plan.end_mm();
        warmups.push(plan);
    }
    let plan = program::load_plan(&args.program, &machine, start)?;
    let total_s = warmups.iter().map(|p| p.duration_s()).sum::<f64>() + plan.duration_s();
    program::check_run_size(
        &args.program.display().to_string(),
        total_s,
        args.thermal_step_s,
        plan.duration_s(),
        args.every_cycle.then_some(args.interp_cycle_ms * 1e-3),
    )?;
    let out_files = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("{}: cannot create output folder", dir.display()))?;
            let files = (dir.join("samples.csv"), dir.join("summary.json"));
            report::check_writable(&files.0, args.force)?;
            report::check_writable(&files.1, args.force)?;
            Some(files)
        }
        None => None,
    };
    let rrd = args.rrd.checked(args.force)?;

    let mut controller = match (&args.model, args.compensate) {
        (Some(path), true) => {
            use vmc_twin::predict::controller::Compensator;
            use vmc_twin::predict::predictor::AnyPredictor;
            // A read error and a content error alike are named by the file, once.
            let model = std::fs::read_to_string(path)
                .map_err(anyhow::Error::new)
                .and_then(|text| AnyPredictor::from_json_str(&text).map_err(anyhow::Error::new))
                .with_context(|| path.display().to_string())?;
            let trained_tool_mm = model.geometry().tool_offset_mm;
            let (model, retooled) = model
                .for_machine_geometry(&machine.geometry())
                .with_context(|| {
                    format!(
                        "{}: model does not fit machine {}",
                        path.display(),
                        machine.machine.name
                    )
                })?;
            if retooled {
                println!(
                    "note: {} was calibrated with tool offset {:?} mm; its elementary errors are \
                     synthesised for this machine's tool offset {:?} mm",
                    path.display(),
                    trained_tool_mm,
                    machine.tool.offset_mm
                );
            }
            let names: Vec<String> = machine.sensors.iter().map(|s| s.name.clone()).collect();
            let ctrl = Compensator::for_machine(model, &names).with_context(|| {
                format!(
                    "{}: model does not fit machine {}",
                    path.display(),
                    machine.machine.name
                )
            })?;
            Some(ctrl)
        }
        (Some(path), false) => anyhow::bail!(
            "{}: a model was given without --compensate; add --compensate to put it in the loop",
            path.display()
        ),
        _ => None,
    };
    let mut twin = Twin::new(&machine, args.seed)?;
    let cfg = SimConfig {
        thermal_step_s: args.thermal_step_s,
        interp_cycle_s: args.interp_cycle_ms * 1e-3,
        sample_mode: if args.every_cycle {
            SampleMode::EveryCycle
        } else {
            SampleMode::Dwells
        },
        // The run report splits each error into cold geometry and thermal part.
        report_thermal_part: true,
    };
    let warm_cfg = SimConfig {
        sample_mode: SampleMode::Dwells,
        ..cfg
    };
    let total_s: f64 = warmups.iter().map(|p| p.duration_s()).sum::<f64>() + plan.duration_s();
    let mut progress = Progress::new(total_s.ceil() as u64, "s");
    let (mut recorder, rrd_file) = match &rrd {
        Some((path, settings)) => {
            let id = format!(
                "vmc-twin run {} on {} seed {} warm-up [{}] compensated {}",
                args.program.display(),
                machine.machine.name,
                args.seed,
                args.warmup
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                controller.is_some()
            );
            let file = record::RrdFile::create(
                path,
                args.force,
                &id,
                record::layout::run_blueprint(settings.magnify),
            )?;
            let diagonal = record::Diagonal::of_plan(&plan);
            let rec = record::Recorder::new(&file, &machine, *settings, diagonal)?;
            (Some(rec), Some(file))
        }
        None => (None, None),
    };
    let mut null = sim::NullObserver;
    for (p, name) in warmups.iter().zip(&args.warmup) {
        let rec: &mut dyn Observer = match recorder.as_mut() {
            Some(r) => r,
            None => &mut null,
        };
        let mut obs = sim::Tee(rec, &mut progress);
        obs.on_run_start(&RunStart {
            label: format!("warm-up {}", name.display()),
            time_s: twin.time_s(),
            duration_s: p.duration_s(),
            measured: false,
        });
        // The controller follows the readings (and the commanded motion) through the warm-up,
        // as on the machine: a model with history features needs the thermal past.
        sim::execute(
            &mut twin,
            p,
            &warm_cfg,
            controller.as_mut().map(|c| c as &mut dyn sim::Controller),
            &mut obs,
        )?;
    }
    let mut log = RunLog::default();
    {
        let rec: &mut dyn Observer = match recorder.as_mut() {
            Some(r) => r,
            None => &mut null,
        };
        let mut watch = sim::Tee(rec, &mut progress);
        let mut obs = sim::Tee(&mut log, &mut watch);
        obs.on_run_start(&RunStart {
            label: args.program.display().to_string(),
            time_s: twin.time_s(),
            duration_s: plan.duration_s(),
            measured: true,
        });
        sim::execute(
            &mut twin,
            &plan,
            &cfg,
            controller.as_mut().map(|c| c as &mut dyn sim::Controller),
            &mut obs,
        )
        .with_context(|| args.program.display().to_string())?;
    }
    progress.finish();

    let warmup_names: Vec<String> = args
        .warmup
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let program_name = args.program.display().to_string();
    let summary = log
        .summary(&program_name, &machine.machine.name, args.seed, &warmup_names)
        .with_context(|| format!("{program_name}: the program has no measurement points (no G4 dwell); use --every-cycle to measure during motion"))?;

    // The report goes to stdout and, with --rrd, into the recording.
    let mut out: Vec<u8> = Vec::new();
    writeln!(
        out,
        "vmc-twin run: {program_name} on {} (seed {})",
        machine.machine.name, args.seed
    )?;
    if warmup_names.is_empty() {
        writeln!(out, "thermal state: cold start (machine at ambient)")?;
    } else {
        writeln!(
            out,
            "thermal state: after warm-up {} ({:.1} h)",
            warmup_names.join(", "),
            summary.time_span_s[0] / 3600.0
        )?;
    }
    if let Some(temps) = log.sensor_degc.first() {
        let list: Vec<String> = log
            .sensor_names
            .iter()
            .zip(temps)
            .map(|(n, t)| format!("{n} {t:.2}"))
            .collect();
        writeln!(out, "sensors at the first point (°C): {}", list.join(", "))?;
    }
    writeln!(out, "errors E = actual − commanded tool tip, workpiece frame, µm; therm = |thermal part| (error minus the cold-geometry error at that point)")?;
    log.write_table(&mut out)?;
    report::write_summary(&summary, &mut out)?;
    let text = String::from_utf8_lossy(&out).to_string();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    out.write_all(text.as_bytes())?;
    if let (Some(rec), Some(file), Some((_, settings))) = (recorder, rrd_file, &rrd) {
        let md = record::run_markdown(&text, settings.magnify, controller.is_some());
        rec.finish(Some(&md))?;
        let path = file.path().to_path_buf();
        let bytes = file.finish()?;
        wrote_recording(&mut out, &path, bytes, "")?;
    }
    if let Some((csv, json)) = out_files {
        report::write_atomic(&csv, log.samples_csv().as_bytes(), args.force)?;
        let text = serde_json::to_string_pretty(&summary)?;
        report::write_atomic(&json, text.as_bytes(), args.force)?;
        writeln!(out, "wrote {} and {}", csv.display(), json.display())?;
    }
    Ok(())
}

fn calibrate(args: CalibrateArgs) -> Result<()> {
    let machine = load_machine(args.machine.as_deref(), args.sensors.as_deref())?;
    if !(args.measure_every_min >= 1.0 && args.measure_every_min.is_finite()) {
        anyhow::bail!(
            "--measure-every-min must be at least 1 (minute), got {:e}",
            args.measure_every_min
        );
    }
    report::check_writable(&args.out, args.force)?;
    let cycles = calibration::ThermalCycle::calibration_set();
    let mut cfg = calibration::CampaignConfig::new(args.seed);
    cfg.measure_every_s = args.measure_every_min * 60.0;
    let data = calibration::calibrate(&machine, &cycles, &cfg)?;
    report::write_atomic(&args.out, data.to_csv().as_bytes(), args.force)?;
    let names: Vec<&str> = cycles.iter().map(|c| c.name.as_str()).collect();
    println!(
        "calibration campaign on {} (seed {}): cycles {}; {} records, {} sensors → {}",
        machine.machine.name,
        args.seed,
        names.join(", "),
        data.records.len(),
        data.sensor_names.len(),
        args.out.display()
    );
    Ok(())
}

fn run_campaign(args: CampaignArgs) -> Result<()> {
    let machine = load_machine(args.machine.as_deref(), args.sensors.as_deref())?;
    if args.seeds.is_empty() {
        anyhow::bail!("--seeds needs at least one seed");
    }
    check_distinct_seeds("--seeds", &args.seeds)?;
    let out_files = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("{}: cannot create output folder", dir.display()))?;
            let mut files = vec![dir.join("report.json")];
            for s in &args.seeds {
                for k in ["hybrid", "volumetric", "linear"] {
                    files.push(dir.join(format!("model_{k}_seed{s}.json")));
                }
            }
            for f in &files {
                report::check_writable(f, args.force)?;
            }
            Some(dir.clone())
        }
        None => None,
    };
    let rrd = args.rrd.checked(args.force)?;
    let mut settings = study::predictor_settings(&machine);
    if args.spindle_speed {
        settings = settings.with_spindle_speed_input();
    }
    let progress = Progress::new(0, "units");
    let (rep, models) =
        study::run_campaign_with_progress(&machine, &args.seeds, &settings, &progress)?;
    progress.finish();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    study::write_campaign_table(&rep, &mut out)?;
    if let Some((path, settings)) = rrd {
        let seeds: Vec<String> = args.seeds.iter().map(|s| s.to_string()).collect();
        let id = format!(
            "vmc-twin campaign on {} seeds {}",
            machine.machine.name,
            seeds.join(",")
        );
        let pick = record::campaign::pick_representative(&rep)
            .context("the campaign produced no hybrid runs to record")?;
        let file = record::RrdFile::create(
            &path,
            args.force,
            &id,
            record::layout::campaign_blueprint(settings.magnify, &pick.title()),
        )?;
        record::campaign::record_campaign(&file, &machine, &rep, &models, settings)?;
        let bytes = file.finish()?;
        wrote_recording(
            &mut out,
            &path,
            bytes,
            &format!("; representative run {}", pick.title()),
        )?;
    }
    if let Some(dir) = out_files {
        let path = dir.join("report.json");
        report::write_atomic(
            &path,
            serde_json::to_string_pretty(&rep)?.as_bytes(),
            args.force,
        )?;
        for m in &models {
            for (k, text) in [
                ("hybrid", m.hybrid.to_json_string()?),
                ("volumetric", m.volumetric.to_json_string()?),
                ("linear", m.linear.to_json_string()?),
            ] {
                report::write_atomic(
                    &dir.join(format!("model_{k}_seed{}.json", m.seed)),
                    text.as_bytes(),
                    args.force,
                )?;
            }
        }
        writeln!(out, "wrote {} and the trained models", path.display())?;
    }
    Ok(())
}

fn train(args: TrainArgs) -> Result<()> {
    use vmc_twin::predict::dataset::Dataset;
    use vmc_twin::predict::predictor::{self, Settings};
    let machine = load_machine(args.machine.as_deref(), args.sensors.as_deref())?;
    report::check_writable(&args.out, args.force)?;
    let name = args.data.display().to_string();
    let text = std::fs::read_to_string(&args.data)
        .with_context(|| format!("{name}: cannot read dataset"))?;
    let data = Dataset::from_csv(&text, &name)?;
    let mut settings = Settings {
        seed: args.seed,
        ..vmc_twin::study::predictor_settings(&machine)
    };
    if args.spindle_speed {
        anyhow::ensure!(
            args.kind == "hybrid",
            "--spindle-speed applies to the hybrid model only (its spindle part), not to --kind {}",
            args.kind
        );
        settings = settings.with_spindle_speed_input();
    }
    let geometry = machine.geometry();
    let (json, summary) = match args.kind.as_str() {
        "hybrid" => {
            let (m, s) = predictor::train_hybrid(&data, &geometry, &settings)?;
            (m.to_json_string()?, s)
        }
        "volumetric" => {
            let (m, s) = predictor::train_volumetric(&data, &geometry, &settings)?;
            (m.to_json_string()?, s)
        }
        "linear" => {
            let (m, s) = predictor::train_linear(&data, &geometry, &settings)?;
            (m.to_json_string()?, s)
        }
        other => anyhow::bail!("--kind must be hybrid, volumetric or linear, got \"{other}\""),
    };
    report::write_atomic(&args.out, json.as_bytes(), args.force)?;
    println!(
        "trained {} model on {name} ({} records, sensors {}):",
        args.kind,
        data.records.len(),
        summary.sensors.join(", ")
    );
    for n in &summary.nets {
        let val: Vec<String> = n
            .outputs
            .iter()
            .zip(&n.val_rmse)
            .map(|(o, v)| format!("{o} {v:.3}"))
            .collect();
        println!(
            "  {:<11} hidden {:>4}  train {:>5} val {:>5}  validation RMSE: {}",
            n.name,
            n.hidden_units
                .map(|h| h.to_string())
                .unwrap_or_else(|| "-".into()),
            n.n_train,
            n.n_val,
            val.join(", ")
        );
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

fn select_sensors(args: SelectArgs) -> Result<()> {
    let machine = load_machine(args.machine.as_deref(), None)?;
    check_distinct_seeds("--compare-seeds", &args.compare_seeds)?;
    let only: Option<Vec<String>> = if args.candidates == "all" {
        None
    } else {
        let wanted: Vec<String> = args
            .candidates
            .split(',')
            .map(|w| w.trim().to_string())
            .collect();
        for (i, w) in wanted.iter().enumerate() {
            if w.is_empty() {
                anyhow::bail!("--candidates: an empty name in `{}`", args.candidates);
            }
            if wanted[..i].contains(w) {
                anyhow::bail!("--candidates: `{w}` is named twice");
            }
            if w != "ambient" && !machine.thermal.nodes.iter().any(|n| &n.name == w) {
                let nodes: Vec<&str> = machine
                    .thermal
                    .nodes
                    .iter()
                    .map(|n| n.name.as_str())
                    .collect();
                anyhow::bail!(
                    "--candidates: `{w}` is not a thermal node of {}; use `all` or some of: {}",
                    machine.machine.name,
                    nodes.join(", ")
                );
            }
        }
        Some(wanted)
    };
    select_and_write(&machine, &placement_config(&args), &args, only.as_deref())
}

fn placement_config(args: &SelectArgs) -> placement::PlacementConfig {
    let mut cfg = placement::PlacementConfig {
        seed: args.seed,
        compare_seeds: if args.no_compare {
            Vec::new()
        } else {
            args.compare_seeds.clone()
        },
        random_draws: args.random_draws,
        ..Default::default()
    };
    cfg.selection.count = args.count;
    cfg
}

fn select_and_write(
    machine: &MachineSpec,
    cfg: &placement::PlacementConfig,
    args: &SelectArgs,
    only: Option<&[String]>,
) -> Result<()> {
    if args.count == 0 {
        anyhow::bail!("--count must be at least 1");
    }
    let candidates = placement::candidates_among(machine, only)?
        .iter()
        .filter(|c| c.node != vmc_twin::thermal::AMBIENT_NODE)
        .count();
    if args.count > candidates {
        anyhow::bail!(
            "--count {}: there are only {candidates} candidate locations besides ambient",
            args.count
        );
    }
    report::check_writable(&args.out, args.force)?;
    if let Some(j) = &args.json {
        report::check_writable(j, args.force)?;
    }
    let rep = placement::study_among(machine, cfg, only)?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    placement::write_report(&rep, machine, cfg, &mut out)?;
    let set = placement::SensorSet {
        sensors: rep.selected_sensors.clone(),
    };
    let header = format!(
        "Sensor set chosen by `vmc-twin select-sensors --count {}` on {} (seed {}).\n\
         Use it with `--sensors {}` (run, calibrate, train, campaign) or paste it into a machine file.",
        args.count,
        machine.machine.name,
        args.seed,
        args.out.display()
    );
    report::write_atomic(&args.out, set.to_toml(&header).as_bytes(), args.force)?;
    writeln!(out, "wrote {}", args.out.display())?;
    if let Some(j) = &args.json {
        report::write_atomic(j, placement::report_json(&rep)?.as_bytes(), args.force)?;
        writeln!(out, "wrote {}", j.display())?;
    }
    Ok(())
}

/// A seed given twice would count its runs twice in the medians.
fn check_distinct_seeds(option: &str, seeds: &[u64]) -> Result<()> {
    for (i, s) in seeds.iter().enumerate() {
        if seeds[..i].contains(s) {
            anyhow::bail!("{option}: seed {s} is given twice (its runs would count twice)");
        }
    }
    Ok(())
}

fn bench(args: BenchArgs) -> Result<()> {
    use vmc_twin::benchmark;
    if args.repeats == 0 {
        anyhow::bail!("--repeats must be at least 1");
    }
    let spec = MachineSpec::reference();
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "vmc-twin bench on {} ({} threads; release build: {})",
        spec.machine.name,
        rayon::current_num_threads(),
        !cfg!(debug_assertions)
    )?;
    for r in benchmark::query(&spec, args.repeats)? {
        writeln!(out, "  {:<90} {:>12.1} {}", r.what, r.value, r.unit)?;
    }
    writeln!(
        out,
        "8 h of machine time, XY diagonal every 30 min, error at every interpolation sample:"
    )?;
    writeln!(
        out,
        "  {:>10} {:>12} {:>10} {:>14}",
        "cycle ms", "samples", "wall s", "ns / sample"
    )?;
    for ms in [4.0, 2.0, 1.0, 0.5, 0.25] {
        let (s, n) = benchmark::machine_8h(&spec, ms, args.repeats.min(3))?;
        writeln!(
            out,
            "  {ms:>10} {n:>12} {s:>10.3} {:>14.0}",
            s * 1e9 / n.max(1) as f64
        )?;
    }
    if !args.quick {
        writeln!(
            out,
            "campaign (seed 1: calibration, 3 trainings, 147 held-out runs) vs calibration cycles:"
        )?;
        writeln!(out, "  {:>8} {:>8} {:>10}", "cycles", "runs", "wall s")?;
        let m = vmc_twin::calibration::ThermalCycle::calibration_set().len();
        for n in [2, 4, m, 2 * m] {
            let (s, runs) =
                benchmark::campaign_with(&spec, &benchmark::calibration_cycles(n), &[1])?;
            writeln!(out, "  {n:>8} {runs:>8} {s:>10.2}")?;
        }
        let (s, runs) = benchmark::campaign_with(
            &spec,
            &vmc_twin::calibration::ThermalCycle::calibration_set(),
            &[1, 2, 3],
        )?;
        writeln!(out, "default campaign, seeds 1,2,3 ({runs} runs): {s:.2} s")?;
    }
    if let Some(m) = benchmark::peak_rss_mib() {
        writeln!(out, "peak resident memory of this process: {m:.0} MiB")?;
    }
    Ok(())
}

fn check(args: CheckArgs) -> Result<()> {
    use vmc_twin::collision::{self, FixtureSpec, Problem, Scene};
    let machine = load_machine(args.machine.as_deref(), None)?;
    if let Some(path) = &args.rrd {
        record::check_rrd_path(path, args.force)?;
    }
    let fixture = args.fixture.as_deref().map(FixtureSpec::load).transpose()?;
    let scene = match (&machine.collision, &fixture) {
        (None, None) => None,
        _ => Some(Scene::new(&machine, fixture.as_ref())?),
    };
    let plan = program::load_plan_unchecked(&args.program, &machine, machine.axes.home_mm)?;
    let file = args.program.display().to_string();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let fixture_name = args
        .fixture
        .as_ref()
        .map(|p| format!("fixture {}", p.display()))
        .unwrap_or_else(|| "no fixture file".into());
    writeln!(
        out,
        "vmc-twin check: {file} on {} ({fixture_name})",
        machine.machine.name
    )?;
    match &scene {
        Some(sc) => {
            writeln!(out, "bodies (machine frame: tool tip relative to the table, mm):")?;
            for l in sc.describe() {
                writeln!(out, "  {l}")?;
            }
            writeln!(
                out,
                "method: every move sampled along its exact path at ≤ {} mm steps: no contact deeper than {} mm can be missed",
                collision::SAMPLE_SPACING_MM,
                0.5 * collision::SAMPLE_SPACING_MM
            )?;
        }
        None => writeln!(
            out,
            "travel check only: the machine file has no [collision] section and no --fixture was given"
        )?,
    }
    struct Print<'a, W: Write>(&'a mut W, &'a str, std::io::Result<()>, Vec<Problem>);
    impl<W: Write> collision::CheckObserver for Print<'_, W> {
        fn on_problem(&mut self, p: &Problem) {
            self.3.push(p.clone());
            if self.2.is_ok() {
                self.2 = writeln!(self.0, "{}: {p}", self.1);
            }
        }
    }
    let mut printer = Print(&mut out, &file, Ok(()), Vec::new());
    let sum = collision::check_plan(&plan, &machine, scene.as_ref(), &mut printer)?;
    printer.2?;
    let problems = std::mem::take(&mut printer.3);
    if let Some(path) = &args.rrd {
        let bytes = record_check(
            path,
            args.force,
            &machine,
            fixture.as_ref(),
            &plan,
            &file,
            &problems,
        )?;
        wrote_recording(&mut out, path, bytes, "")?;
    }
    writeln!(
        out,
        "checked {} moves ({:.1} mm of path, {} poses): {} collision(s), {} travel violation(s)",
        sum.segments, sum.path_mm, sum.samples, sum.collisions, sum.travel_violations
    )?;
    if sum.is_clean() {
        writeln!(out, "no problem found")?;
        Ok(())
    } else {
        anyhow::bail!(
            "{file}: would crash or leave the travel: {} collision(s), {} travel violation(s)",
            sum.collisions,
            sum.travel_violations
        )
    }
}

/// The recording of a `check`: the program's motion on a cold twin, every problem an event at
/// its time and place (the contact point, or the tool position for a travel violation).
fn record_check(
    path: &Path,
    force: bool,
    machine: &MachineSpec,
    fixture: Option<&vmc_twin::collision::FixtureSpec>,
    plan: &vmc_twin::motion::Plan,
    file: &str,
    problems: &[vmc_twin::collision::Problem],
) -> Result<u64> {
    use vmc_twin::collision::Problem;
    use vmc_twin::sim::{EventLevel, SimEvent};
    let settings = record::RecordSettings::default();
    let rrd = record::RrdFile::create(
        path,
        force,
        &format!("vmc-twin check {file} on {}", machine.machine.name),
        record::layout::run_blueprint(settings.magnify),
    )?;
    let mut rec = record::Recorder::new(&rrd, machine, settings, None)?;
    let mut twin = Twin::new(machine, 1)?;
    rec.on_run_start(&RunStart {
        label: format!("check {file}"),
        time_s: twin.time_s(),
        duration_s: plan.duration_s(),
        measured: false,
    });
    // Fixture and stock bodies ride on the table with the paths (`paths/fixture/<name>`), grey;
    // a body that is hit turns red from the time of the contact.
    let bodies: Vec<&vmc_twin::collision::BodySpec> = fixture
        .map(|f| f.bodies.iter().collect())
        .unwrap_or_default();
    let draw = |name: &str, color: [u8; 3], t_s: f64| -> Result<()> {
        let Some(b) = bodies.iter().find(|b| b.name == name) else {
            return Ok(());
        };
        let (lo, hi) = match (
            b.min_mm,
            b.max_mm,
            b.base_center_mm,
            b.radius_mm,
            b.height_mm,
        ) {
            (Some(lo), Some(hi), _, _, _) => (lo, hi),
            // A vertical cylinder, drawn as its bounding box.
            (_, _, Some(c), Some(r), Some(h)) => {
                ([c[0] - r, c[1] - r, c[2]], [c[0] + r, c[1] + r, c[2] + h])
            }
            _ => return Ok(()),
        };
        let centre = record::scene::mm_to_scene([0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a])));
        let half = record::scene::mm_to_scene([0, 1, 2].map(|a| 0.5 * (hi[a] - lo[a])));
        let stream = rrd.stream();
        stream.set_duration_secs("sim_time", t_s);
        stream.log(
            format!("paths/fixture/{name}"),
            &rerun::Boxes3D::from_centers_and_half_sizes([centre], [half])
                .with_colors([rerun::Color::from_rgb(color[0], color[1], color[2])])
                .with_labels([name.to_string()]),
        )?;
        Ok(())
    };
    for b in &bodies {
        draw(&b.name, [150, 150, 150], twin.time_s())?;
    }
    let mut lines = Vec::new();
    for p in problems {
        let (kind, time_s, place) = match p {
            Problem::Collision(c) => ("collision", c.time_s, c.contact_point_mm),
            Problem::Travel(t) => ("travel", t.time_s, plan.position_at(t.time_s)),
        };
        if let Problem::Collision(c) = p {
            draw(
                &c.other_body,
                [230, 40, 40],
                twin.time_s() + c.first_contact_time_s,
            )?;
        }
        lines.push(format!("- {p}"));
        rec.on_event(&SimEvent {
            time_s: twin.time_s() + time_s,
            level: EventLevel::Error,
            kind: kind.into(),
            text: p.to_string(),
            position_mm: Some(place),
        });
    }
    // The motion itself, sampled along the path (at most ~20,000 samples) so the commanded
    // and actual paths are drawn; a program that leaves the travel still shows its problems
    // even if the twin cannot follow it.
    let cfg = SimConfig {
        sample_mode: SampleMode::EveryCycle,
        interp_cycle_s: (plan.duration_s() / 20_000.0).max(0.01),
        ..SimConfig::default()
    };
    let motion = sim::execute(&mut twin, plan, &cfg, None, &mut rec);
    let mut md = format!("# vmc-twin check: {file}\n\n");
    if problems.is_empty() {
        md.push_str("No problem found.\n");
    } else {
        md.push_str(&format!(
            "{} problem(s), drawn as magenta points at their time (`paths/events`, `events` log):\n\n{}\n",
            problems.len(),
            lines.join("\n")
        ));
    }
    if let Err(e) = &motion {
        md.push_str(&format!("\nThe motion could not be simulated past: {e}\n"));
    }
    rec.finish(Some(&md))?;
    Ok(rrd.finish()?)
}

/// Says which recording was written and its size (`wrote FILE (x.xx MB<extra>)`).
fn wrote_recording(
    out: &mut impl Write,
    path: &std::path::Path,
    bytes: u64,
    extra: &str,
) -> std::io::Result<()> {
    writeln!(
        out,
        "wrote {} ({:.2} MB{extra})",
        path.display(),
        bytes as f64 / 1e6
    )
}

#[cfg(test)]
mod tests {
    use super::error_text;
    use vmc_twin::predict::nn::{DataError, NnError};
    use vmc_twin::predict::predictor::PredictError;

    #[test]
    fn a_cause_that_its_parent_already_prints_is_not_repeated() {
        // `PredictError::Net` prints its cause in its message (and does not expose it again).
        let e = anyhow::Error::new(PredictError::Net {
            net: "spindle",
            cause: NnError::Data(DataError::TooLarge {
                what: "targets",
                column: 0,
            }),
        });
        let text = error_text(&e);
        assert!(
            text.starts_with("network `spindle`: targets, column 0: "),
            "{text}"
        );
        assert_eq!(text.matches("targets, column 0").count(), 1, "{text}");
        // Contexts still chain.
        let e = e.context("cal.csv");
        assert!(error_text(&e).starts_with("cal.csv: network `spindle`: "));
    }
}
