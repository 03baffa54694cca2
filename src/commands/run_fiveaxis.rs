//! `vmc-twin run` on a five-axis machine: a program with A/C words on the machine's truth, the
//! tool tip error in the workpiece frame at every point, and with `--identified` the same points
//! compensated by the identified model (see [`vmc_machine::fiveaxis::run`]).

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::{wrote_recording, RrdOutput};
use crate::files;
use crate::record;
use crate::report::fiveaxis::{self as five_report, FiveAxisSummary};
use vmc_identify::chain::Pose;
use vmc_machine::fiveaxis::identified::IdentifiedModel;
use vmc_machine::fiveaxis::plan::{plan_program, TcpLimitReport};
use vmc_machine::fiveaxis::run::{self as five, Controller, FivePoint, Sampling};
use vmc_machine::fiveaxis::{FiveAxisSpec, TrueMachine};

/// What to run on a five-axis machine, validated.
pub struct FiveAxisRunConfig {
    /// The G-code program.
    pub program: PathBuf,
    /// The machine.
    pub machine: FiveAxisSpec,
    /// The machine file's name (in errors).
    pub machine_file: String,
    /// Seed of the machine realisation.
    pub seed: u64,
    /// Folder for `samples.csv` and `summary.json`.
    pub out_dir: Option<PathBuf>,
    /// Overwrite existing output files.
    pub force: bool,
    /// Where to measure.
    pub sampling: Sampling,
    /// An identified model (`identify`'s JSON) to compensate with.
    pub identified: Option<PathBuf>,
    /// The controller corrects the rotary axes too (else the linear axes only).
    pub rotary_comp: bool,
    /// A Rerun recording to write.
    pub rrd: Option<RrdOutput>,
}

/// Runs the program, prints the report to `out`, writes the files asked for.
///
/// # Errors
/// An unreadable or invalid program, a move beyond a travel, an unusable identified model,
/// outputs that may not be written.
pub fn run(cfg: &FiveAxisRunConfig, out: &mut dyn Write) -> Result<()> {
    let spec = &cfg.machine;
    let name = cfg.program.display().to_string();
    let text = files::read_named(&cfg.program, "program")?;
    let plan = plan_program(&text, &name, spec, &cfg.machine_file)?;
    if let Sampling::EveryCycle(dt_s) = cfg.sampling {
        // No thermal steps on this machine: only the number of samples is limited.
        vmc_machine::program::check_run_size(&name, 0.0, 1.0, plan.duration_s(), Some(dt_s))?;
    }
    let out_files =
        super::prepare_run_outputs(cfg.out_dir.as_deref(), cfg.rrd.as_ref(), cfg.force)?;
    let geom = spec.geometry();
    let model = match &cfg.identified {
        Some(path) => {
            let text = files::read_named(path, "identified model")?;
            Some(
                IdentifiedModel::from_json_str(&text, &spec.machine.name, &geom)
                    .with_context(|| path.display().to_string())?,
            )
        }
        None => None,
    };
    let truth = TrueMachine::new(spec, cfg.seed)?;
    let points = five::commanded_points(&plan, cfg.sampling);
    let truth_at = |p: &Pose| truth.state_at(p);
    let model_at = model.as_ref().map(|m| move |p: &Pose| m.state_at(p));
    let controller = model_at.as_ref().map(|f| Controller {
        model: f as &dyn Fn(&Pose) -> _,
        rotary: cfg.rotary_comp,
    });
    let evaluated =
        five::evaluate(&geom, &points, &truth_at, controller).with_context(|| name.clone())?;
    let identified_name = cfg.identified.as_ref().map(|p| p.display().to_string());
    let summary = five_report::summarise(
        &evaluated,
        &name,
        &spec.machine.name,
        cfg.seed,
        identified_name.as_deref(),
        cfg.rotary_comp,
    )
    .with_context(|| {
        format!("{name}: the program has no measurement points (no G4 dwell); use --every-cycle to measure during motion")
    })?;
    let tcp = plan
        .pieces
        .iter()
        .any(|p| p.tcp_length_mm.is_some())
        .then(|| plan.tcp_limits());
    let report = report_text(cfg, &evaluated, &summary, model.as_ref(), tcp)?;
    out.write_all(report.as_bytes())?;
    if let Some(rrd) = &cfg.rrd {
        let id = format!(
            "vmc-twin run {name} on {} seed {} identified {}",
            spec.machine.name,
            cfg.seed,
            identified_name.as_deref().unwrap_or("none")
        );
        let bytes = record::fiveaxis::record_run(
            &rrd.path,
            cfg.force,
            &id,
            rrd.settings.magnify,
            spec,
            &plan,
            &evaluated,
            &report,
        )?;
        wrote_recording(out, &rrd.path, bytes, "")?;
    }
    if let Some((csv, json)) = out_files {
        files::write_atomic(
            &csv,
            five_report::samples_csv(&geom, &evaluated).as_bytes(),
            cfg.force,
        )?;
        let text = serde_json::to_string_pretty(&summary)?;
        files::write_atomic(&json, text.as_bytes(), cfg.force)?;
        writeln!(out, "wrote {} and {}", csv.display(), json.display())?;
    }
    Ok(())
}

/// The printed report: what ran, the per-point table, the summary.
fn report_text(
    cfg: &FiveAxisRunConfig,
    points: &[FivePoint],
    summary: &FiveAxisSummary,
    model: Option<&IdentifiedModel>,
    tcp: Option<Option<TcpLimitReport>>,
) -> Result<String> {
    let mut out: Vec<u8> = Vec::new();
    let spec = &cfg.machine;
    writeln!(
        out,
        "vmc-twin run: {} on {} (seed {}; five-axis, chain {})",
        cfg.program.display(),
        spec.machine.name,
        cfg.seed,
        spec.machine.chain
    )?;
    writeln!(out, "thermal state: {}", five_report::NO_THERMAL_MODEL)?;
    if let Some(limits) = tcp {
        writeln!(out, "tool-centre-point control: under G43.4 the program gives the tool tip in the part frame; the axes come from the nominal inverse kinematics")?;
        writeln!(out, "{}", tcp_limits_line(limits.as_ref()))?;
    }
    if let (Some(m), Some(path)) = (model, &cfg.identified) {
        writeln!(
            out,
            "compensation: identified model {} ({} parameters{}); the controller corrects {}",
            path.display(),
            m.set.len(),
            if m.harmonics >= 2 {
                format!(", rotary motion harmonics up to order {}", m.harmonics)
            } else {
                String::new()
            },
            if cfg.rotary_comp {
                "X, Y, Z and the rotary axes (--rotary-comp on)"
            } else {
                "X, Y, Z (--rotary-comp off)"
            }
        )?;
    }
    writeln!(out, "errors E = actual − commanded tool tip, workpiece frame, µm; ax = angle between actual and commanded tool axis, µrad; X, Y, Z and the angles are the commanded axes")?;
    five_report::write_table(&spec.geometry(), points, &mut out)?;
    five_report::write_summary(summary, &mut out)?;
    Ok(String::from_utf8_lossy(&out).to_string())
}

/// What the axes' limits did to the G43.4 moves, in one line.
fn tcp_limits_line(limits: Option<&TcpLimitReport>) -> String {
    let Some(r) = limits else {
        return "G43.4: no move had to be slowed for the axes' speed and acceleration limits"
            .to_string();
    };
    let (axis, kind) = (r.binding.0, r.binding.1.name());
    let moves = if r.moves == 1 { "move" } else { "moves" };
    if r.slowest_ratio < 1.0 {
        format!(
            "G43.4: feed limited by the axes' limits on {} {moves}, slowest {:.0} % of programmed (line {}, axis {axis} {kind}); {:+.3} s of machine time",
            r.moves,
            100.0 * r.slowest_ratio,
            r.slowest_line,
            r.added_s
        )
    } else {
        format!(
            "G43.4: gentler speed ramps on {} {moves} for the axes' limits (axis {axis} {kind}), the programmed feed kept; {:+.3} s of machine time",
            r.moves, r.added_s
        )
    }
}
