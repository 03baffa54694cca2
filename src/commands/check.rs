//! `vmc-twin check`: would this program crash the machine? Travel limits and contact of tool,
//! holder and spindle nose with the table, fixture, stock and the setup's artefacts, move by move;
//! probe moves end where the nominal machine's probe trips, and one that would reach nothing
//! is reported.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use super::wrote_recording;
use crate::record;
use vmc_gcode::interp::ProbeRequest;
use vmc_machine::collision::{self, FixtureSpec, Problem, Scene};
use vmc_machine::machine::MachineSpec;
use vmc_machine::program;

/// What to check, validated.
pub struct CheckConfig {
    /// The G-code program.
    pub program: PathBuf,
    /// The machine (its `[collision]` section, if any).
    pub machine: MachineSpec,
    /// Fixture file (TOML).
    pub fixture: Option<PathBuf>,
    /// A Rerun recording to write (path checked).
    pub rrd: Option<PathBuf>,
    /// Overwrite an existing recording.
    pub force: bool,
    /// The tools `M6` loads (empty: the machine's own tool for every number).
    pub tools: vmc_machine::tools::ToolTable,
    /// Where the program sits (work offsets, setup file with its bodies) and its subroutine
    /// folders.
    pub placement: vmc_machine::setup::Placement,
}

/// Checks every move, prints each problem and a summary.
///
/// # Errors
/// An unreadable or invalid program or fixture; a program with a problem (after the report).
pub fn check(cfg: &CheckConfig, out: &mut dyn Write) -> Result<()> {
    let machine = &cfg.machine;
    let fixture_file = cfg.fixture.as_deref().map(FixtureSpec::load).transpose()?;
    let file_bodies = fixture_file.as_ref().map(|f| f.bodies.clone());
    // The setup file's bodies and the fixture file's, as one fixture.
    let fixture = cfg.placement.fixture(fixture_file);
    let artefacts = &cfg.placement.artefacts;
    let scene = match (&machine.collision, &fixture) {
        (None, None) if artefacts.is_empty() => None,
        _ => Some(
            Scene::new(machine, fixture.as_ref())?
                .with_tools(cfg.tools.clone())
                .with_artefacts(artefacts),
        ),
    };
    // Probe moves end where the nominal machine's probe would trip.
    let extra = file_bodies.unwrap_or_default();
    let station =
        vmc_machine::touch_probe::ProbeStation::of_placement(&cfg.placement, machine, &extra, 0)?;
    let mut answer = |r: &ProbeRequest| station.nominal(r).outcome;
    let probed = program::load_plan_probed(
        &cfg.program,
        machine,
        machine.axes.home_mm,
        &cfg.tools,
        &cfg.placement,
        &mut answer,
    )?;
    let (plan, units) = (&probed.plan, &probed.units);
    let file = cfg.program.display().to_string();
    let fixture_name = cfg
        .fixture
        .as_ref()
        .map(|p| format!("fixture {}", p.display()))
        .unwrap_or_else(|| "no fixture file".into());
    let placement = super::program_placement::placement_line(&cfg.placement);
    writeln!(
        out,
        "vmc-twin check: {file} on {} ({fixture_name})",
        machine.machine.name
    )?;
    writeln!(out, "{placement}")?;
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
            if sc.has_cut_stock() {
                writeln!(
                    out,
                    "material removal: stock boxes on a Z-map of ≤ {} mm cells, cut by feed moves with the spindle running",
                    collision::CUT_GRID_MM
                )?;
            }
        }
        None => writeln!(
            out,
            "travel check only: the machine file has no [collision] section, and no --fixture or setup file bodies were given"
        )?,
    }
    struct Print<'a>(
        &'a mut dyn Write,
        &'a str,
        std::io::Result<()>,
        Vec<Problem>,
        &'a program::LineUnits,
    );
    impl collision::CheckObserver for Print<'_> {
        fn on_problem(&mut self, p: &Problem) {
            self.3.push(p.clone());
            // A travel violation in the program's unit of length.
            let text = match p {
                Problem::Travel(v) => vmc_machine::motion::travel_message(
                    v.line,
                    v.axis,
                    [v.pos_mm, v.min_mm, v.max_mm],
                    self.4.at(v.line),
                ),
                other => other.to_string(),
            };
            if self.2.is_ok() {
                self.2 = writeln!(self.0, "{}: {text}", self.1);
            }
        }
    }
    let mut printer = Print(out, &file, Ok(()), Vec::new(), units);
    let sum = collision::check_plan(plan, machine, scene.as_ref(), &mut printer)?;
    printer.2?;
    let problems = std::mem::take(&mut printer.3);
    if let Some(path) = &cfg.rrd {
        let bytes = record::check::record_check(
            path,
            cfg.force,
            machine,
            fixture.as_ref(),
            plan,
            &file,
            &problems,
        )?;
        wrote_recording(out, path, bytes, "")?;
    }
    writeln!(
        out,
        "checked {} moves ({:.1} mm of path, {} poses): {} collision(s), {} travel violation(s)",
        sum.segments, sum.path_mm, sum.samples, sum.collisions, sum.travel_violations
    )?;
    if !probed.probes.is_empty() {
        writeln!(
            out,
            "probe moves: {} (G38.x), each ending where the probe trips on the nominal machine (ball Ø{} mm, pre-travel {:.1} µm)",
            probed.probes.len(),
            2.0 * station.probe().ball_radius_mm,
            station.probe().pretravel_mm() * 1e3
        )?;
    }
    if let Some(stop) = &probed.stopped {
        writeln!(
            out,
            "{stop} (on the nominal machine; the program stops here)"
        )?;
    }
    if sum.is_clean() && probed.stopped.is_none() {
        writeln!(out, "no problem found")?;
        Ok(())
    } else if probed.stopped.is_some() {
        anyhow::bail!(
            "{file}: would stop at a probe move that reaches nothing: {} collision(s), {} travel violation(s) before it",
            sum.collisions,
            sum.travel_violations
        )
    } else {
        anyhow::bail!(
            "{file}: would crash or leave the travel: {} collision(s), {} travel violation(s)",
            sum.collisions,
            sum.travel_violations
        )
    }
}
