//! `vmc-twin`: the command line over the library. Arguments are validated into a config once;
//! every failure is one line on stderr and a non-zero exit code.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use vmc_twin::campaign;
use vmc_twin::machine::MachineSpec;
use vmc_twin::program;
use vmc_twin::report::{self, RunLog};
use vmc_twin::sim::{self, SampleMode, SimConfig};
use vmc_twin::twin::Twin;

#[derive(Parser)]
#[command(name = "vmc-twin", version, about = "Digital twin of a 3-axis vertical machining center: run G-code on a machine with thermally drifting geometric errors and see where the tool really was")]
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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(args),
        Command::Calibrate(args) => calibrate(args),
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
        anyhow::bail!("--interp-cycle-ms must be > 0, got {}", args.interp_cycle_ms);
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
    let out_files = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create output folder", dir.display()))?;
            let files = (dir.join("samples.csv"), dir.join("summary.json"));
            report::check_writable(&files.0, args.force)?;
            report::check_writable(&files.1, args.force)?;
            Some(files)
        }
        None => None,
    };

    let mut twin = Twin::new(&machine, args.seed)?;
    let cfg = SimConfig {
        thermal_step_s: args.thermal_step_s,
        interp_cycle_s: args.interp_cycle_ms * 1e-3,
        sample_mode: if args.every_cycle { SampleMode::EveryCycle } else { SampleMode::Dwells },
        ..SimConfig::default()
    };
    let warm_cfg = SimConfig { sample_mode: SampleMode::Dwells, ..cfg };
    for p in &warmups {
        sim::execute(&mut twin, p, &warm_cfg, None, &mut sim::NullObserver)?;
    }
    let mut log = RunLog::default();
    sim::execute(&mut twin, &plan, &cfg, None, &mut log)?;

    let warmup_names: Vec<String> = args.warmup.iter().map(|p| p.display().to_string()).collect();
    let program_name = args.program.display().to_string();
    let summary = log
        .summary(&program_name, &machine.machine.name, args.seed, &warmup_names)
        .with_context(|| format!("{program_name}: the program has no measurement points (no G4 dwell); use --every-cycle to measure during motion"))?;

    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    writeln!(out, "vmc-twin run: {program_name} on {} (seed {})", machine.machine.name, args.seed)?;
    if warmup_names.is_empty() {
        writeln!(out, "thermal state: cold start (machine at ambient)")?;
    } else {
        writeln!(out, "thermal state: after warm-up {} ({:.1} h)", warmup_names.join(", "), summary.time_span_s[0] / 3600.0)?;
    }
    if let Some(temps) = log.sensor_degc.first() {
        let list: Vec<String> = log.sensor_names.iter().zip(temps).map(|(n, t)| format!("{n} {t:.2}")).collect();
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
    if !(args.measure_every_min > 0.0 && args.measure_every_min.is_finite()) {
        anyhow::bail!("--measure-every-min must be > 0, got {}", args.measure_every_min);
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
