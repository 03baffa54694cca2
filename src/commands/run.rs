//! `vmc-twin run`: a G-code program on the twin, optionally after warm-ups and with a model in
//! the control loop; the error at every measurement point, before and after compensation.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::run_stream::{self, ProgramScan, Rows};
use super::{wrote_recording, RrdOutput};
use crate::files;
use crate::predict::controller::Compensator;
use crate::predict::drift::WithDrift;
use crate::predict::guard::Guarded;
use crate::predict::provenance::InputRanges;
use crate::progress::Progress;
use crate::record;
use crate::report::{self, RunLog, RunSummary};
use vmc_machine::machine::MachineSpec;
use vmc_machine::program;
use vmc_machine::setup::Placement;
use vmc_machine::sim::{self, Observer, RunStart, SampleMode, SimConfig};
use vmc_machine::twin::Twin;

/// What to run, validated.
pub struct RunConfig {
    /// The G-code program.
    pub program: PathBuf,
    /// The machine (with its sensor set).
    pub machine: MachineSpec,
    /// Seed of the machine's random error parts and noise.
    pub seed: u64,
    /// Thermal loading programs run first, in order.
    pub warmups: Vec<PathBuf>,
    /// Folder for `samples.csv` and `summary.json`.
    pub out_dir: Option<PathBuf>,
    /// Overwrite existing output files.
    pub force: bool,
    /// Measure at every interpolation cycle during motion, not only at dwells.
    pub every_cycle: bool,
    /// Thermal step and interpolation cycle of the measured program (checked).
    pub sim: SimConfig,
    /// A trained model to put in the control loop.
    pub model: Option<PathBuf>,
    /// A Rerun recording to write.
    pub rrd: Option<RrdOutput>,
    /// Refuse a run in which a reading or command leaves the model's trained range.
    pub strict: bool,
    /// Accept a model calibrated on another machine or realisation (with a note).
    pub allow_other_machine: bool,
    /// The tools `M6` loads (empty: the machine's own tool for every number).
    pub tools: vmc_machine::tools::ToolTable,
    /// Where the program sits (work offsets, setup file) and its subroutine folders.
    pub placement: Placement,
    /// Measurement period during motion of a program without G4 dwells (without
    /// `--every-cycle`), s.
    pub motion_sample_s: f64,
    /// With a model: update its drift from the program's touches of reference artefacts
    /// (`--probe-update`, see [`super::probe_update`]).
    pub probe_update: bool,
}

/// Default measurement period during motion of a program without G4 dwells, s: one point per
/// second of program time (a CAM program of hours gives thousands of points, not millions).
pub const MOTION_SAMPLE_S: f64 = 1.0;

/// How the measured program is sampled: the mode, the simulation settings, and why (for the
/// report).
struct Sampling {
    mode: SampleMode,
    sim: SimConfig,
    note: String,
}

/// At the program's dwells (G4) as in a diagonal test; during motion with `--every-cycle`;
/// during motion every [`RunConfig::motion_sample_s`] for a program without dwells (it would
/// have no measurement point at all).
fn sampling(cfg: &RunConfig, has_dwell: bool) -> Result<Sampling> {
    let cycle_ms = cfg.sim.interp_cycle_s() * 1e3;
    Ok(if cfg.every_cycle {
        Sampling {
            mode: SampleMode::EveryCycle,
            sim: cfg.sim,
            note: format!(
                "at every {cycle_ms} ms interpolation cycle during motion and at each G4 dwell"
            ),
        }
    } else if has_dwell {
        Sampling {
            mode: SampleMode::Dwells,
            sim: cfg.sim,
            note: "at each G4 dwell (--every-cycle: also during motion)".into(),
        }
    } else {
        let sim = SimConfig::new(cfg.sim.thermal_step_s(), cfg.motion_sample_s)
            .map_err(|e| anyhow::anyhow!("--interp-cycle-ms: {e}"))?;
        Sampling {
            mode: SampleMode::EveryCycle,
            sim,
            note: format!(
                "during motion every {} s (the program has no G4 dwell; --interp-cycle-ms sets the period)",
                cfg.motion_sample_s
            ),
        }
    })
}

/// A run on the machine the file describes.
#[allow(clippy::large_enum_variant)] // one per run, built once
pub enum RunTarget {
    /// The three-axis thermal twin.
    ThreeAxis(RunConfig),
    /// A five-axis machine (see [`super::run_fiveaxis`]).
    FiveAxis(super::run_fiveaxis::FiveAxisRunConfig),
}

/// Runs `target` on its kind of machine.
///
/// # Errors
/// See [`run`] and [`super::run_fiveaxis::run`].
pub fn run_target(target: &RunTarget, out: &mut dyn Write) -> Result<()> {
    match target {
        RunTarget::ThreeAxis(cfg) => run(cfg, out),
        RunTarget::FiveAxis(cfg) => super::run_fiveaxis::run(cfg, out),
    }
}

/// The compensating controller of a run: the model, its inputs checked against its trained
/// ranges.
/// Its drift is zero until a probe move of the program touches a reference artefact.
pub(super) type RunController = super::probe_update::DriftCompensator;

/// Runs the program and prints the report to `out`.
///
/// # Errors
/// Unreadable or invalid programs, a run too large, outputs that may not be written, a model
/// that does not fit the machine, simulation errors.
pub fn run(cfg: &RunConfig, out: &mut dyn Write) -> Result<()> {
    let machine = &cfg.machine;
    // Check everything the user gave before minutes of simulation: programs and outputs.
    let (warmups, scan, sampling) = load_plans(cfg)?;
    let out_files =
        super::prepare_run_outputs(cfg.out_dir.as_deref(), cfg.rrd.as_ref(), cfg.force)?;
    let (mut controller, ranges_known) = match &cfg.model {
        Some(path) => {
            let (c, known) = compensator(
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
    if let Some(c) = controller.as_mut() {
        let probe = vmc_machine::touch_probe::TouchProbe::of_placement(&cfg.placement, machine);
        *c.inner_mut().predictor_mut().filter_mut() =
            super::probe_update::run_drift_field(&cfg.placement.artefacts, &probe)?;
    }
    let compensated = controller.is_some();
    let mut rows = Rows::new(out_files, cfg.force)?;
    let mut log = rows.log(compensated);
    let (recorder, mut probes) = simulate(
        cfg,
        &sampling,
        &warmups,
        &scan,
        controller.as_mut(),
        &mut log,
    )?;
    log.check().context("writing the run's table")?;

    let warmup_names: Vec<String> = cfg
        .warmups
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let program_name = cfg.program.display().to_string();
    let mut summary = log
        .summary(
            &program_name,
            &machine.machine.name,
            cfg.seed,
            &warmup_names,
        )
        .with_context(|| {
            format!(
                "{program_name}: the program has no measurement points (no motion and no G4 dwell)"
            )
        })?;
    judge_extrapolation(&mut summary, controller.as_ref(), ranges_known, cfg.strict)?;
    let head = report_head(cfg, &sampling, &log, &summary)?;
    drop(log);
    deliver(
        Delivery {
            summary: &summary,
            head,
            rows,
            recording: recorder.zip(cfg.rrd.as_ref()),
            compensated,
            force: cfg.force,
            probing: probes.summary(scan.duration_s),
        },
        out,
    )?;
    write_probes(&mut probes, scan.duration_s, out)
}

/// The probe moves' table and the probing cost; `probes.csv` named (with `--out`).
fn write_probes(
    probes: &mut super::probe_log::ProbeLog,
    program_s: f64,
    out: &mut dyn Write,
) -> Result<()> {
    if probes.rows.is_empty() {
        return Ok(());
    }
    out.write_all(probes.report(program_s).as_bytes())?;
    if let Some(path) = probes.finish_csv()? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}

/// What a measured run (or replay) hands to [`deliver`].
pub(super) struct Delivery<'a> {
    /// The summary of the points.
    pub summary: &'a RunSummary,
    /// The printed report's head (the per-point table and the summary follow).
    pub head: String,
    /// The rows written as the points came.
    pub rows: Rows,
    /// The recording and where it goes, if one is written.
    pub recording: Option<((record::Recorder, record::RrdFile), &'a RrdOutput)>,
    /// Whether the points have an error after compensation.
    pub compensated: bool,
    /// Overwrite existing files.
    pub force: bool,
    /// The probe results and the probing cost (`summary.json`'s `probing`), if any.
    pub probing: Option<super::probe_log::ProbingSummary<'a>>,
}

/// `summary.json`: the run's summary, and its probing when the program probes.
#[derive(serde::Serialize)]
struct SummaryJson<'a> {
    #[serde(flatten)]
    summary: &'a RunSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    probing: Option<&'a super::probe_log::ProbingSummary<'a>>,
}

/// The extrapolation verdict of `controller` (if any) in `summary`.
///
/// # Errors
/// `strict` and the model was used outside its trained ranges.
pub(super) fn judge_extrapolation(
    summary: &mut RunSummary,
    controller: Option<&RunController>,
    ranges_known: bool,
    strict: bool,
) -> Result<()> {
    // Without recorded training ranges nothing was checked: no verdict (the report says "not
    // checked"), never "inside the trained ranges".
    summary.extrapolation = controller
        .filter(|_| ranges_known)
        .map(|c| c.extrapolation().clone());
    if let (true, Some(e)) = (strict, &summary.extrapolation) {
        if let Some(first) = e.inputs.first() {
            anyhow::bail!(
                "--strict: the model was used outside the range it was trained on: {} (first at \
                 t = {:.0} s: {}, trained {:.2} … {:.2}); {} samples outside in all; no report \
                 written",
                e.inputs
                    .iter()
                    .map(|o| o.input.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                first.first_time_s,
                first.first_value,
                first.range[0],
                first.range[1],
                e.count
            );
        }
    }
    Ok(())
}

/// The end of a measured run: the report printed (head, the rows, the summary) and put in the
/// recording (its table cut short), `samples.csv` named and `summary.json` written.
///
/// # Errors
/// Files or the recording that cannot be written.
pub(super) fn deliver(d: Delivery<'_>, out: &mut dyn Write) -> Result<()> {
    let Rows {
        mut table,
        csv,
        out_files,
    } = d.rows;
    let mut tail: Vec<u8> = Vec::new();
    report::write_summary(d.summary, &mut tail)?;
    let tail = String::from_utf8_lossy(&tail).to_string();
    out.write_all(d.head.as_bytes())?;
    table.copy_to(out)?;
    out.write_all(tail.as_bytes())?;
    if let Some(((rec, file), rrd)) = d.recording {
        let text = format!(
            "{}{}{tail}",
            d.head,
            table.head(run_stream::RECORDED_TABLE_ROWS)?
        );
        let md = record::run_markdown(&text, rrd.settings.magnify, d.compensated);
        rec.finish(Some(&md))?;
        let path = file.path().to_path_buf();
        let bytes = file.finish()?;
        wrote_recording(out, &path, bytes, "")?;
    }
    if let (Some((csv_path, json)), Some(csv)) = (out_files, csv) {
        csv.finish()?;
        let text = serde_json::to_string_pretty(&SummaryJson {
            summary: d.summary,
            probing: d.probing.as_ref(),
        })?;
        files::write_atomic(&json, text.as_bytes(), d.force)?;
        writeln!(out, "wrote {} and {}", csv_path.display(), json.display())?;
    }
    Ok(())
}

/// A warm-up: its file, where it starts and how long it takes. It is interpreted and planned
/// piece by piece as it runs ([`program::PlanStream`]), so a week of duty never holds a week
/// of moves or of plan.
pub(super) struct Warmup {
    path: PathBuf,
    start_mm: [f64; 3],
    /// The text's hash when it was checked (see [`program::PlanStream::fingerprint`]).
    fingerprint: Option<u64>,
    /// Its duration, s.
    pub duration_s: f64,
}

impl Warmup {
    /// The warm-up's plans, piece by piece (each checked), in machine coordinates.
    fn pieces<'a>(
        &self,
        machine: &'a MachineSpec,
        tools: &'a vmc_machine::tools::ToolTable,
    ) -> Result<program::PlanStream<'a>> {
        let placement = Placement::of_machine(machine);
        let stream = program::PlanStream::load(
            &self.path,
            machine,
            self.start_mm,
            tools,
            &placement,
            program::MOVES_PER_PIECE,
        )?;
        anyhow::ensure!(
            self.fingerprint.is_none_or(|f| f == stream.fingerprint()),
            "{}: the warm-up file changed while the run was starting; run again",
            self.path.display()
        );
        Ok(stream)
    }
}

/// The warm-ups of `paths` (every piece planned and checked once, then dropped), each starting
/// where the previous one ends, the first at the machine's home; and where the last ends.
///
/// # Errors
/// Unreadable or invalid programs.
pub(super) fn load_warmups(
    machine: &MachineSpec,
    tools: &vmc_machine::tools::ToolTable,
    paths: &[PathBuf],
) -> Result<(Vec<Warmup>, [f64; 3])> {
    let mut start = machine.axes.home_mm;
    let mut warmups = Vec::new();
    for w in paths {
        let mut warmup = Warmup {
            path: w.clone(),
            start_mm: start,
            fingerprint: None,
            duration_s: 0.0,
        };
        let stream = warmup.pieces(machine, tools)?;
        warmup.fingerprint = Some(stream.fingerprint());
        for piece in stream {
            let piece = piece?;
            warmup.duration_s += piece.duration_s();
            start = piece.end_mm();
        }
        warmups.push(warmup);
    }
    Ok((warmups, start))
}

/// The warm-ups and the measured program (every piece planned and checked once, then
/// dropped), each starting where the previous one ends; the run's size checked.
fn load_plans(cfg: &RunConfig) -> Result<(Vec<Warmup>, ProgramScan, Sampling)> {
    let (warmups, start) = load_warmups(&cfg.machine, &cfg.tools, &cfg.warmups)?;
    let scan = run_stream::scan(&measured(cfg), start, cfg.rrd.is_some())?;
    let sampling = sampling(cfg, scan.has_dwell)?;
    let total_s = warmups.iter().map(|p| p.duration_s).sum::<f64>() + scan.duration_s;
    program::check_run_size(
        &cfg.program.display().to_string(),
        total_s,
        cfg.sim.thermal_step_s(),
        scan.duration_s,
        matches!(sampling.mode, SampleMode::EveryCycle).then_some(sampling.sim.interp_cycle_s()),
    )?;
    Ok((warmups, scan, sampling))
}

/// The measured program of `cfg` and what it runs on.
fn measured(cfg: &RunConfig) -> run_stream::Measured<'_> {
    run_stream::Measured {
        program: &cfg.program,
        machine: &cfg.machine,
        tools: &cfg.tools,
        placement: &cfg.placement,
        seed: cfg.seed,
        probe_update: cfg.probe_update,
    }
}

/// The model of `path` as a compensator for the run's machine (see
/// [`super::model::load_for_machine`]), guarded by its trained ranges; and whether the file
/// records them (a model without them is not checked).
pub(super) fn compensator(
    machine: &MachineSpec,
    seed: u64,
    path: &Path,
    allow_other_machine: bool,
    strict: bool,
    out: &mut dyn Write,
) -> Result<(RunController, bool)> {
    let (model, trained_on) =
        super::model::load_for_machine(machine, seed, path, allow_other_machine, out)?;
    let names: Vec<String> = machine.sensors.iter().map(|s| s.name.clone()).collect();
    let field = super::probe_update::run_drift_field(
        &[],
        &vmc_machine::touch_probe::TouchProbe::typical(vmc_machine::tools::master_length_mm(
            machine,
        )),
    )?;
    let ctrl = Compensator::for_machine(WithDrift::new(model, field), &names)
        .with_context(|| super::model::does_not_fit(path, machine))?;
    let none = InputRanges {
        sensors: Vec::new(),
        sensor_degc: Vec::new(),
        spindle_rpm: None,
        axis_feeds: None,
    };
    anyhow::ensure!(
        !(strict && trained_on.is_none()),
        "{}: --strict refuses readings outside the model's trained ranges, and this model file \
         records none (a file older than version 8): retrain it, or run without --strict",
        path.display()
    );
    let ranges = trained_on.as_ref().map(|t| &t.inputs).unwrap_or(&none);
    Ok((Guarded::new(ctrl, ranges, &names), trained_on.is_some()))
}

/// Runs the warm-ups, then the program (measured), on a fresh twin; with a recording if asked.
fn simulate(
    cfg: &RunConfig,
    sampling: &Sampling,
    warmups: &[Warmup],
    scan: &ProgramScan,
    mut controller: Option<&mut RunController>,
    log: &mut RunLog,
) -> Result<(
    Option<(record::Recorder, record::RrdFile)>,
    super::probe_log::ProbeLog,
)> {
    let machine = &cfg.machine;
    let mut twin = Twin::new(machine, cfg.seed)?;
    twin.set_tool_table(cfg.tools.clone());
    let sim_cfg = sampling
        .sim
        .sampling(sampling.mode)
        // The run report splits each error into cold geometry and thermal part.
        .with_thermal_part(true);
    let warm_cfg = sim_cfg.sampling(SampleMode::Dwells);
    let total_s: f64 = warmups.iter().map(|p| p.duration_s).sum::<f64>() + scan.duration_s;
    let mut progress = Progress::new(total_s.ceil() as u64, "s");
    let mut recording = match &cfg.rrd {
        Some(rrd) => {
            let diagonal = record::Diagonal::through(&scan.dwell_points_mm);
            Some(open_recording(cfg, rrd, diagonal, controller.is_some())?)
        }
        None => None,
    };
    let mut null = sim::NullObserver;
    let mut probes = super::probe_log::ProbeLog::new(
        cfg.out_dir.as_ref().map(|d| d.join("probes.csv")),
        cfg.force,
    );
    {
        let rec: &mut dyn Observer = match recording.as_mut() {
            Some((r, _)) => r,
            None => &mut null,
        };
        let mut obs = sim::Tee(rec, &mut progress);
        let ctx = WarmupContext {
            machine,
            tools: &cfg.tools,
            names: &cfg.warmups,
            sim: &warm_cfg,
        };
        run_warmups(
            &ctx,
            &mut twin,
            warmups,
            controller.as_deref_mut(),
            &mut obs,
        )?;
    }
    {
        let rec: &mut dyn Observer = match recording.as_mut() {
            Some((r, _)) => r,
            None => &mut null,
        };
        let mut watch = sim::Tee(rec, &mut progress);
        let mut obs = sim::Tee(log, &mut watch);
        run_stream::run_measured(
            &measured(cfg),
            scan,
            &mut twin,
            &sim_cfg,
            controller,
            &mut obs,
            &mut probes,
        )?;
    }
    progress.finish();
    Ok((recording, probes))
}

/// What the warm-ups run with.
pub(super) struct WarmupContext<'a> {
    /// The machine.
    pub machine: &'a MachineSpec,
    /// The tool table `M6` loads from.
    pub tools: &'a vmc_machine::tools::ToolTable,
    /// The warm-ups' files, for the labels.
    pub names: &'a [PathBuf],
    /// Thermal step (no measurement).
    pub sim: &'a SimConfig,
}

/// Runs the warm-ups in order on `twin`, the controller (if any) following the readings.
///
/// # Errors
/// Invalid pieces, simulation errors.
pub(super) fn run_warmups(
    ctx: &WarmupContext<'_>,
    twin: &mut Twin,
    warmups: &[Warmup],
    mut controller: Option<&mut RunController>,
    obs: &mut dyn Observer,
) -> Result<()> {
    for (p, name) in warmups.iter().zip(ctx.names) {
        obs.on_run_start(&RunStart {
            label: format!("warm-up {}", name.display()),
            time_s: twin.time_s(),
            duration_s: p.duration_s,
            measured: false,
        });
        for piece in p.pieces(ctx.machine, ctx.tools)? {
            // The controller follows the readings (and the commanded motion) through the
            // warm-up, as on the machine: a model with history features needs the thermal past.
            let ctrl = controller
                .as_deref_mut()
                .map(|c| c as &mut dyn sim::Controller);
            sim::execute(twin, &piece?, ctx.sim, ctrl, obs)?;
        }
    }
    Ok(())
}

/// The recording of a run, its id naming everything that makes the run.
fn open_recording(
    cfg: &RunConfig,
    rrd: &RrdOutput,
    diagonal: Option<record::Diagonal>,
    compensated: bool,
) -> Result<(record::Recorder, record::RrdFile)> {
    let id = format!(
        "vmc-twin run {} on {} seed {} warm-up [{}] compensated {compensated}",
        cfg.program.display(),
        cfg.machine.machine.name,
        cfg.seed,
        cfg.warmups
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    );
    open_run_recording(&id, rrd, cfg.force, &cfg.machine, diagonal)
}

/// A recording with a run's layout, named `id`, its diagonal timeline along `diagonal`.
///
/// # Errors
/// A file that may not be written, a recording that cannot start.
pub(super) fn open_run_recording(
    id: &str,
    rrd: &RrdOutput,
    force: bool,
    machine: &MachineSpec,
    diagonal: Option<record::Diagonal>,
) -> Result<(record::Recorder, record::RrdFile)> {
    let file = record::RrdFile::create(
        &rrd.path,
        force,
        id,
        record::layout::run_blueprint(rrd.settings.magnify),
    )?;
    let rec = record::Recorder::new(&file, machine, rrd.settings, diagonal)?;
    Ok((rec, file))
}

/// The printed report's head: the thermal state, the first readings (the per-point table and
/// the summary follow).
fn report_head(
    cfg: &RunConfig,
    sampling: &Sampling,
    log: &RunLog,
    summary: &RunSummary,
) -> Result<String> {
    let mut out: Vec<u8> = Vec::new();
    writeln!(
        out,
        "vmc-twin run: {} on {} (seed {})",
        cfg.program.display(),
        cfg.machine.machine.name,
        cfg.seed
    )?;
    write_thermal_state(&mut out, &cfg.warmups, summary)?;
    writeln!(
        out,
        "{}",
        super::program_placement::placement_line(&cfg.placement)
    )?;
    writeln!(out, "measured {}", sampling.note)?;
    write_first_readings(&mut out, log)?;
    Ok(String::from_utf8_lossy(&out).to_string())
}

/// The report's thermal-state line: cold, or after which warm-ups.
pub(super) fn write_thermal_state(
    out: &mut dyn Write,
    warmups: &[PathBuf],
    summary: &RunSummary,
) -> std::io::Result<()> {
    if warmups.is_empty() {
        writeln!(out, "thermal state: cold start (machine at ambient)")
    } else {
        let names: Vec<String> = warmups.iter().map(|p| p.display().to_string()).collect();
        writeln!(
            out,
            "thermal state: after warm-up {} ({:.1} h)",
            names.join(", "),
            summary.time_span_s[0] / 3600.0
        )
    }
}

/// The report's line of the sensor readings at the first point, and the table's legend (the
/// per-point table follows).
pub(super) fn write_first_readings(out: &mut dyn Write, log: &RunLog) -> std::io::Result<()> {
    if let Some(temps) = &log.first_degc {
        let list: Vec<String> = log
            .sensor_names
            .iter()
            .zip(temps)
            .map(|(n, t)| format!("{n} {t:.2}"))
            .collect();
        writeln!(out, "sensors at the first point (°C): {}", list.join(", "))?;
    }
    writeln!(out, "errors E = actual − commanded tool tip, workpiece frame, µm; therm = |thermal part| (error minus the cold-geometry error at that point)")
}
