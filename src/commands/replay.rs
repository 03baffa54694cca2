//! `vmc-twin replay`: a servo-rate log of a real controller's commanded positions played on the
//! twin after its warm-ups; the tool-tip error at the logged samples before and after
//! compensation, reported, written and recorded as `run` does.
//!
//! "Before" is the error when the drives follow the logged commanded positions; "after" when
//! they follow them plus the corrections the controller logged (its own compensation judged),
//! or plus the corrections a model computes in the twin's own loop (`--compensate`, a bare
//! trace judged with this project's compensator). The thermal network keeps evolving during the
//! replay under the logged motion and spindle speed (see [`vmc_machine::sim::replay`]).
//!
//! The log is read line by line: once to check it whole before minutes of warm-up (and once
//! more with a recording, to see whether its measured positions lie on a line), once to play
//! it; it is never held in memory, nor are its points: their rows are written as they come
//! (see [`super::run_stream::Rows`]), only running sums are kept.

pub mod log;

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::PathBuf;

use anyhow::{Context, Result};

use self::log::{LogColumns, LogFormat, LogReader};
use super::run::{self, Delivery, RunController, Warmup, WarmupContext};
use super::run_stream::Rows;
use super::RrdOutput;
use crate::progress::Progress;
use crate::record;
use crate::report::{RunLog, RunSummary};
use vmc_machine::machine::MachineSpec;
use vmc_machine::program;
use vmc_machine::sim::replay::{LoggedSample, Replay};
use vmc_machine::sim::{self, Observer, RunStart, SampleMode, SimConfig};
use vmc_machine::twin::Twin;

/// What to replay, validated.
pub struct ReplayConfig {
    /// The log file.
    pub log: PathBuf,
    /// Its format.
    pub format: LogFormat,
    /// The machine (with its sensor set).
    pub machine: MachineSpec,
    /// Seed of the machine's random error parts and noise.
    pub seed: u64,
    /// Thermal loading programs run first, in order.
    pub warmups: Vec<PathBuf>,
    /// The tools `M6` of the warm-ups loads.
    pub tools: vmc_machine::tools::ToolTable,
    /// Folder for `samples.csv` and `summary.json`.
    pub out_dir: Option<PathBuf>,
    /// Overwrite existing output files.
    pub force: bool,
    /// Thermal step (the interpolation cycle is the log's).
    pub sim: SimConfig,
    /// Measure every `every`-th sample (≥ 1).
    pub every: usize,
    /// Spindle speed when the log has none, rpm.
    pub spindle_rpm: f64,
    /// A trained model to put in the control loop.
    pub model: Option<PathBuf>,
    /// A Rerun recording to write.
    pub rrd: Option<RrdOutput>,
    /// Refuse a replay in which a reading or command leaves the model's trained range.
    pub strict: bool,
    /// Accept a model calibrated on another machine or realisation (with a note).
    pub allow_other_machine: bool,
}

/// What the checking pass learnt of the log.
struct LogScan {
    samples: usize,
    duration_s: f64,
    has_corrections: bool,
    has_spindle: bool,
    /// The logged sensors and their readings at the first sample, °C.
    first_temps: Vec<(String, f64)>,
    /// The first and the last measured commanded positions, mm.
    first_last_mm: [[f64; 3]; 2],
}

/// Replays the log and prints the report to `out`.
///
/// # Errors
/// An unreadable or bad log (with its line), logged corrections together with a model, bad
/// warm-ups, a replay too large, outputs that may not be written, a model that does not fit the
/// machine, simulation errors.
pub fn replay(cfg: &ReplayConfig, out: &mut dyn Write) -> Result<()> {
    let name = cfg.log.display().to_string();
    let scan = scan(cfg).with_context(|| name.clone())?;
    if let (true, Some(model)) = (scan.has_corrections, &cfg.model) {
        anyhow::bail!(
            "{name}: the log has the controller's corrections (corr_x_mm …), so its own \
             compensation is judged; --compensate {} would judge the model on the same motion: \
             drop the correction columns (halsampler: name them `_`) to do that",
            model.display()
        );
    }
    let (warmups, _) = run::load_warmups(&cfg.machine, &cfg.tools, &cfg.warmups)?;
    let total_s = warmups.iter().map(|w| w.duration_s).sum::<f64>() + scan.duration_s;
    program::check_run_size(&name, total_s, cfg.sim.thermal_step_s(), 0.0, None)?;
    let points = scan.samples.div_ceil(cfg.every);
    if points as f64 > program::MAX_CYCLE_SAMPLES {
        anyhow::bail!(
            "{name}: {points} measurement points, more than {:e}: measure fewer with --every N",
            program::MAX_CYCLE_SAMPLES
        );
    }
    let out_files =
        super::prepare_run_outputs(cfg.out_dir.as_deref(), cfg.rrd.as_ref(), cfg.force)?;
    let (mut controller, ranges_known) = match &cfg.model {
        Some(path) => {
            let (c, known) = run::compensator(
                &cfg.machine,
                cfg.seed,
                path,
                cfg.allow_other_machine,
                cfg.strict,
                out,
            )?;
            (Some(c), known)
        }
        None => (None, false),
    };
    let compensated = controller.is_some() || scan.has_corrections;
    let diagonal = match cfg.rrd {
        Some(_) => diagonal(cfg, &scan).with_context(|| name.clone())?,
        None => None,
    };
    let mut rows = Rows::new(out_files, cfg.force)?;
    let mut log = rows.log(compensated);
    let recording = simulate(
        cfg,
        &scan,
        diagonal,
        &warmups,
        total_s,
        controller.as_mut(),
        &mut log,
    )?;
    log.check().context("writing the replay's table")?;
    let warmup_names: Vec<String> = cfg
        .warmups
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let mut summary = log
        .summary(&name, &cfg.machine.machine.name, cfg.seed, &warmup_names)
        .with_context(|| format!("{name}: no measurement points"))?;
    run::judge_extrapolation(&mut summary, controller.as_ref(), ranges_known, cfg.strict)?;
    let head = report_head(cfg, &scan, &log, &summary)?;
    drop(log);
    run::deliver(
        Delivery {
            summary: &summary,
            head,
            rows,
            recording: recording.zip(cfg.rrd.as_ref()),
            compensated,
            force: cfg.force,
            probing: None,
        },
        out,
    )
}

/// A reader of the log file.
fn open(cfg: &ReplayConfig) -> Result<LogReader<BufReader<File>>> {
    let file = File::open(&cfg.log).context("cannot open the log")?;
    Ok(LogReader::new(BufReader::new(file), &cfg.format)?)
}

/// Reads the whole log once, checking every line, before any simulation.
fn scan(cfg: &ReplayConfig) -> Result<LogScan> {
    let mut reader = open(cfg)?;
    check_sensor_columns(reader.columns(), &cfg.machine)?;
    let columns = reader.columns().clone();
    let mut samples: usize = 0;
    let mut span_s = [0.0; 2];
    let mut first_temps = Vec::new();
    let mut first_last_mm = [[0.0; 3]; 2];
    while let Some(s) = reader.next_sample()? {
        if samples == 0 {
            span_s[0] = s.time_s;
            first_temps = columns
                .sensor_names()
                .iter()
                .map(|n| n.to_string())
                .zip(s.temperatures_degc.iter().copied())
                .collect();
        }
        if samples.is_multiple_of(cfg.every) {
            if samples == 0 {
                first_last_mm[0] = s.commanded_mm;
            }
            first_last_mm[1] = s.commanded_mm;
        }
        span_s[1] = s.time_s;
        samples += 1;
    }
    if samples == 0 {
        return Err(log::LogError::Empty.into());
    }
    Ok(LogScan {
        samples,
        duration_s: span_s[1] - span_s[0],
        has_corrections: columns.has_corrections(),
        has_spindle: columns.has_spindle(),
        first_temps,
        first_last_mm,
    })
}

/// The line through the measured positions, if they all lie on it (the recording's timeline):
/// one more pass over the log, checking each against the line from the first to the last.
fn diagonal(cfg: &ReplayConfig, scan: &LogScan) -> Result<Option<record::Diagonal>> {
    let Some(diag) = record::Diagonal::between(scan.first_last_mm[0], scan.first_last_mm[1]) else {
        return Ok(None);
    };
    let mut reader = open(cfg)?;
    let mut n: usize = 0;
    while let Some(s) = reader.next_sample()? {
        if n.is_multiple_of(cfg.every) && !diag.holds(s.commanded_mm) {
            return Ok(None);
        }
        n += 1;
    }
    Ok(Some(diag))
}

/// Refuses temperature columns of sensors the machine does not have.
fn check_sensor_columns(columns: &LogColumns, machine: &MachineSpec) -> Result<()> {
    for n in columns.sensor_names() {
        if !machine.sensors.iter().any(|s| s.name == n) {
            let known: Vec<&str> = machine.sensors.iter().map(|s| s.name.as_str()).collect();
            anyhow::bail!(
                "unknown column `{n}_degc`: `{n}` is not a sensor of {} (its sensors: {})",
                machine.machine.name,
                known.join(", ")
            );
        }
    }
    Ok(())
}

/// Runs the warm-ups, then replays the log (measured), on a fresh twin; with a recording if
/// asked.
fn simulate(
    cfg: &ReplayConfig,
    scan: &LogScan,
    diagonal: Option<record::Diagonal>,
    warmups: &[Warmup],
    total_s: f64,
    mut controller: Option<&mut RunController>,
    log: &mut RunLog,
) -> Result<Option<(record::Recorder, record::RrdFile)>> {
    let machine = &cfg.machine;
    let mut twin = Twin::new(machine, cfg.seed)?;
    twin.set_tool_table(cfg.tools.clone());
    // The report splits each error into cold geometry and thermal part, as a run's.
    let sim_cfg = cfg.sim.with_thermal_part(true);
    let warm_cfg = sim_cfg.sampling(SampleMode::Dwells);
    let mut progress = Progress::new(total_s.ceil() as u64, "s");
    let mut recording = match &cfg.rrd {
        Some(rrd) => Some(run::open_run_recording(
            &recording_id(cfg, controller.is_some() || scan.has_corrections),
            rrd,
            cfg.force,
            machine,
            diagonal,
        )?),
        None => None,
    };
    let mut null = sim::NullObserver;
    let rec: &mut dyn Observer = match recording.as_mut() {
        Some((r, _)) => r,
        None => &mut null,
    };
    let mut watch = sim::Tee(rec, &mut progress);
    let ctx = WarmupContext {
        machine,
        tools: &cfg.tools,
        names: &cfg.warmups,
        sim: &warm_cfg,
    };
    run::run_warmups(
        &ctx,
        &mut twin,
        warmups,
        controller.as_deref_mut(),
        &mut watch,
    )?;
    let mut obs = sim::Tee(log, &mut watch);
    obs.on_run_start(&RunStart {
        label: cfg.log.display().to_string(),
        time_s: twin.time_s(),
        duration_s: scan.duration_s,
        measured: true,
    });
    let mut reader = open(cfg)?;
    let mut replay = Replay::start(
        &twin,
        &sim_cfg,
        cfg.every,
        controller
            .as_deref_mut()
            .map(|c| c as &mut dyn sim::Controller),
        &obs,
    );
    while let Some(s) = reader.next_sample()? {
        let sample = LoggedSample {
            time_s: s.time_s,
            line: s.line,
            commanded_mm: s.commanded_mm,
            correction_mm: s.correction_mm,
            spindle_rpm: s.spindle_rpm.unwrap_or(cfg.spindle_rpm),
        };
        let ctrl = controller
            .as_deref_mut()
            .map(|c| c as &mut dyn sim::Controller);
        replay
            .push(&mut twin, &sample, ctrl, &mut obs)
            .map_err(|e| logged_correction_error(e, scan.has_corrections))
            .with_context(|| cfg.log.display().to_string())?;
    }
    replay.finish(&mut twin)?;
    progress.finish();
    Ok(recording)
}

/// A correction beyond the limit is the log's, not a model's, when the log has corrections.
fn logged_correction_error(e: sim::SimError, logged: bool) -> anyhow::Error {
    match e {
        sim::SimError::Compensation {
            line,
            correction_mm,
            ..
        } if logged => anyhow::anyhow!(
            "line {line}: the logged correction moves the axes {correction_mm:.4} mm, above the \
             limit of {} mm for a geometric and thermal correction (are the correction columns \
             in mm?)",
            sim::MAX_CORRECTION_MM
        ),
        e => e.into(),
    }
}

/// The recording's id, naming everything that makes the replay.
fn recording_id(cfg: &ReplayConfig, compensated: bool) -> String {
    format!(
        "vmc-twin replay {} on {} seed {} warm-up [{}] every {} compensated {compensated}",
        cfg.log.display(),
        cfg.machine.machine.name,
        cfg.seed,
        cfg.warmups
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        cfg.every
    )
}

/// The printed report's head: the thermal state, what was replayed and how it was compensated,
/// the first readings (the per-point table and the summary follow).
fn report_head(
    cfg: &ReplayConfig,
    scan: &LogScan,
    log: &RunLog,
    summary: &RunSummary,
) -> Result<String> {
    let mut out: Vec<u8> = Vec::new();
    writeln!(
        out,
        "vmc-twin replay: {} on {} (seed {})",
        cfg.log.display(),
        cfg.machine.machine.name,
        cfg.seed
    )?;
    run::write_thermal_state(&mut out, &cfg.warmups, summary)?;
    let format = match &cfg.format {
        LogFormat::Csv => "csv".to_string(),
        LogFormat::Halsampler { period_s, .. } => match period_s {
            Some(p) => format!("halsampler, period {} ms", p * 1e3),
            None => "halsampler".to_string(),
        },
    };
    let spindle = if scan.has_spindle {
        "spindle speed from the log".to_string()
    } else {
        format!("spindle at {} rpm (the log has none)", cfg.spindle_rpm)
    };
    writeln!(
        out,
        "replayed {} samples over {:.3} s ({format}; {spindle}); measured every {} sample(s): {} points",
        scan.samples,
        scan.duration_s,
        cfg.every,
        summary.points
    )?;
    let compensation = match (&cfg.model, scan.has_corrections) {
        (_, true) => "after = with the corrections the controller logged".to_string(),
        (Some(m), false) => format!("after = with {} in the twin's loop", m.display()),
        (None, false) => {
            "no compensation (the log has no corrections; --compensate MODEL adds the model's)"
                .to_string()
        }
    };
    writeln!(out, "{compensation}")?;
    if !scan.first_temps.is_empty() {
        let twin: Vec<f64> = log.first_degc.clone().unwrap_or_default();
        let list: Vec<String> = scan
            .first_temps
            .iter()
            .map(|(n, logged)| {
                let at = log.sensor_names.iter().position(|s| s == n);
                let twin_degc = at.and_then(|i| twin.get(i)).copied().unwrap_or(f64::NAN);
                format!("{n} {logged:.2}/{twin_degc:.2}")
            })
            .collect();
        writeln!(
            out,
            "logged temperatures at the first sample, logged/twin (°C; the twin reads its own): {}",
            list.join(", ")
        )?;
    }
    run::write_first_readings(&mut out, log)?;
    Ok(String::from_utf8_lossy(&out).to_string())
}
