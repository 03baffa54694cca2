//! `vmc-twin`: the command line over the library. Arguments are validated into a config once;
//! every failure is one line on stderr and a non-zero exit code.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use vmc_twin::campaign;
use vmc_twin::evaluation;
use vmc_twin::machine::MachineSpec;
use vmc_twin::program;
use vmc_twin::report::{self, RunLog};
use vmc_twin::sim::{self, SampleMode, SimConfig};
use vmc_twin::twin::Twin;

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
    /// Would this program crash the machine? Checks every move for travel limits and for
    /// contact of tool, holder and spindle nose with the table, fixture and stock.
    Check(CheckArgs),
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
}

#[derive(clap::Args)]
struct CampaignArgs {
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
    /// Machine realisations to calibrate and evaluate (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1u64, 2, 3])]
    seeds: Vec<u64>,
    /// Folder for report.json and the trained models (created if missing).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Overwrite existing output files.
    #[arg(long)]
    force: bool,
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
    /// Seed of the network initialisation.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output model file.
    #[arg(short = 'o', long, default_value = "model.json")]
    out: PathBuf,
    /// Overwrite an existing output file.
    #[arg(long)]
    force: bool,
}

#[derive(clap::Args)]
struct CalibrateArgs {
    /// Machine description (TOML); default: the embedded reference machine.
    #[arg(long)]
    machine: Option<PathBuf>,
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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(args),
        Command::Calibrate(args) => calibrate(args),
        Command::Campaign(args) => run_campaign(args),
        Command::Train(args) => train(args),
        Command::Check(args) => check(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vmc-twin: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn load_machine(path: Option<&Path>) -> Result<MachineSpec> {
    Ok(match path {
        Some(p) => MachineSpec::load(p)?,
        None => MachineSpec::reference(),
    })
}

fn run(args: RunArgs) -> Result<()> {
    let machine = load_machine(args.machine.as_deref())?;
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

    let mut controller = match (&args.model, args.compensate) {
        (Some(path), true) => {
            use vmc_twin::predict::controller::Compensator;
            use vmc_twin::predict::predictor::AnyPredictor;
            let model =
                AnyPredictor::load_json(path).with_context(|| format!("{}", path.display()))?;
            let names: Vec<String> = machine.sensors.iter().map(|s| s.name.clone()).collect();
            let ctrl = Compensator::for_machine(model, &names).with_context(|| {
                format!(
                    "{}: model does not fit machine {}",
                    path.display(),
                    machine.machine.name
                )
            })?;
            Some(evaluation::LoopController(ctrl))
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
    for p in &warmups {
        sim::execute(&mut twin, p, &warm_cfg, None, &mut sim::NullObserver)?;
    }
    let mut log = RunLog::default();
    sim::execute(
        &mut twin,
        &plan,
        &cfg,
        controller.as_mut().map(|c| c as &mut dyn sim::Controller),
        &mut log,
    )?;

    let warmup_names: Vec<String> = args
        .warmup
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let program_name = args.program.display().to_string();
    let summary = log
        .summary(&program_name, &machine.machine.name, args.seed, &warmup_names)
        .with_context(|| format!("{program_name}: the program has no measurement points (no G4 dwell); use --every-cycle to measure during motion"))?;

    let stdout = std::io::stdout();
    let mut out = stdout.lock();
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
    if let Some((csv, json)) = out_files {
        report::write_atomic(&csv, log.samples_csv().as_bytes(), args.force)?;
        let text = serde_json::to_string_pretty(&summary)?;
        report::write_atomic(&json, text.as_bytes(), args.force)?;
        writeln!(out, "wrote {} and {}", csv.display(), json.display())?;
    }
    Ok(())
}

fn calibrate(args: CalibrateArgs) -> Result<()> {
    let machine = load_machine(args.machine.as_deref())?;
    if !(args.measure_every_min >= 1.0 && args.measure_every_min.is_finite()) {
        anyhow::bail!(
            "--measure-every-min must be at least 1 (minute), got {:e}",
            args.measure_every_min
        );
    }
    report::check_writable(&args.out, args.force)?;
    let cycles = campaign::ThermalCycle::calibration_set();
    let mut cfg = campaign::CampaignConfig::new(args.seed);
    cfg.measure_every_s = args.measure_every_min * 60.0;
    let data = campaign::calibrate(&machine, &cycles, &cfg)?;
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
    let machine = load_machine(args.machine.as_deref())?;
    if args.seeds.is_empty() {
        anyhow::bail!("--seeds needs at least one seed");
    }
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
    let settings = vmc_twin::predict::predictor::Settings::default();
    let (rep, models) = evaluation::run_campaign(&machine, &args.seeds, &settings)?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    evaluation::write_campaign_table(&rep, &mut out)?;
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
    let machine = load_machine(args.machine.as_deref())?;
    report::check_writable(&args.out, args.force)?;
    let name = args.data.display().to_string();
    let text = std::fs::read_to_string(&args.data)
        .with_context(|| format!("{name}: cannot read dataset"))?;
    let data = Dataset::from_csv(&text, &name)?;
    let settings = Settings {
        seed: args.seed,
        ..Settings::default()
    };
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

fn check(args: CheckArgs) -> Result<()> {
    use vmc_twin::collision::{self, FixtureSpec, Problem, Scene};
    let machine = load_machine(args.machine.as_deref())?;
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
    struct Print<'a, W: Write>(&'a mut W, &'a str, std::io::Result<()>);
    impl<W: Write> collision::CheckObserver for Print<'_, W> {
        fn on_problem(&mut self, p: &Problem) {
            if self.2.is_ok() {
                self.2 = writeln!(self.0, "{}: {p}", self.1);
            }
        }
    }
    let mut printer = Print(&mut out, &file, Ok(()));
    let sum = collision::check_plan(&plan, &machine, scene.as_ref(), &mut printer)?;
    printer.2?;
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
