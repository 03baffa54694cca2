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
use vmc_machine::collision::{self, FixtureSpec, PlanChecker, Problem, Scene};
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
    let mut stream = program::PlanStream::load(
        &cfg.program,
        machine,
        machine.axes.home_mm,
        &cfg.tools,
        &cfg.placement,
        program::MOVES_PER_PIECE,
    )?
    .answering_probes()
    .without_travel_check();
    let file = cfg.program.display().to_string();
    let mut checker = PlanChecker::new(machine, scene.as_ref())?;
    let mut printer = Print {
        out,
        file: &file,
        written: Ok(()),
        problems: cfg.rrd.is_some().then(Vec::new),
        units: program::LineUnits::default(),
    };
    let (mut probes, mut stopped, mut first) = (0_usize, None, true);
    // Piece by piece: the first one is planned before the header, so that a short program
    // with an error prints nothing but the error. A probe answer that stops the program leaves
    // the probe move as the last piece.
    while let Some(piece) = stream.next() {
        let plan = piece?;
        if std::mem::take(&mut first) {
            header(cfg, scene.as_ref(), &mut *printer.out)?;
        }
        printer.units = stream.units().clone();
        checker.check(&plan, &mut printer)?;
        if let Some(request) = stream.pending_probe() {
            probes += 1;
            if let Err(stop) = stream.answer_probe(station.nominal(&request).outcome) {
                stopped = Some(stop);
            }
        }
    }
    printer.written?;
    let sum = checker.summary();
    let out = printer.out;
    if let (Some(path), Some(problems)) = (&cfg.rrd, &printer.problems) {
        // The recording draws the whole path: it is planned whole again, for it alone.
        let mut answer = |r: &ProbeRequest| station.nominal(r).outcome;
        let probed = program::load_plan_probed(
            &cfg.program,
            machine,
            machine.axes.home_mm,
            &cfg.tools,
            &cfg.placement,
            &mut answer,
        )?;
        let bytes = record::check::record_check(
            path,
            cfg.force,
            machine,
            fixture.as_ref(),
            &probed.plan,
            &file,
            problems,
        )?;
        wrote_recording(out, path, bytes, "")?;
    }
    verdict(out, &file, sum, (probes, &station), stopped.as_ref())
}

/// The totals, the probe moves and the stop, then the verdict: `Ok` when clean, else the error
/// the command exits with.
fn verdict(
    out: &mut dyn Write,
    file: &str,
    sum: collision::CheckSummary,
    (probes, station): (usize, &vmc_machine::touch_probe::ProbeStation),
    stopped: Option<&program::ProgramError>,
) -> Result<()> {
    writeln!(
        out,
        "checked {} moves ({:.1} mm of path, {} poses): {} collision(s), {} travel violation(s)",
        sum.segments, sum.path_mm, sum.samples, sum.collisions, sum.travel_violations
    )?;
    if probes > 0 {
        writeln!(
            out,
            "probe moves: {} (G38.x), each ending where the probe trips on the nominal machine (ball Ø{} mm, pre-travel {:.1} µm)",
            probes,
            2.0 * station.probe().ball_radius_mm,
            station.probe().pretravel_mm() * 1e3
        )?;
    }
    if let Some(stop) = stopped {
        writeln!(
            out,
            "{stop} (on the nominal machine; the program stops here)"
        )?;
    }
    if sum.is_clean() && stopped.is_none() {
        writeln!(out, "no problem found")?;
        Ok(())
    } else if stopped.is_some() {
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

/// The report's head: the program, the machine, the placement, the bodies and the method.
fn header(cfg: &CheckConfig, scene: Option<&Scene>, out: &mut dyn Write) -> Result<()> {
    let machine = &cfg.machine;
    let file = cfg.program.display();
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
    match scene {
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
    Ok(())
}

/// Prints each problem as it is found (travel in the program's unit of length) and keeps
/// them for a recording.
struct Print<'a> {
    out: &'a mut dyn Write,
    file: &'a str,
    /// The first write error, if any.
    written: std::io::Result<()>,
    /// The problems, kept only for a recording.
    problems: Option<Vec<Problem>>,
    /// The unit of length at each line of the piece being checked.
    units: program::LineUnits,
}

impl collision::CheckObserver for Print<'_> {
    fn on_problem(&mut self, p: &Problem) {
        if let Some(kept) = self.problems.as_mut() {
            kept.push(p.clone());
        }
        let text = match p {
            Problem::Travel(v) => vmc_machine::motion::travel_message(
                v.line,
                v.axis,
                [v.pos_mm, v.min_mm, v.max_mm],
                self.units.at(v.line),
            ),
            other => other.to_string(),
        };
        if self.written.is_ok() {
            self.written = writeln!(self.out, "{}: {text}", self.file);
        }
    }
}
