//! From a G-code file to a checked, timed plan: read → interpret → plan → travel check.
//!
//! Every error names the file and, where it has one, the line (and column for syntax).

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::machine::MachineSpec;
use crate::motion::{self, Plan};
use crate::setup::Placement;
use crate::tools::ToolTable;
use vmc_gcode::interp::{self, InterpConfig, LengthUnit};

mod pieces;
mod stream;
pub use pieces::{PlanPieces, ProgramMoves, MOVES_PER_PIECE};
mod probed;
pub use probed::{
    end_probe_move, interpret_probed, load_plan_probed, ProbeRecord, ProbedMoves, ProbedPlan,
};
pub use stream::{PlanStream, Source};

/// A program that cannot be run.
#[derive(Debug, Error)]
pub enum ProgramError {
    /// The file could not be read.
    #[error("{file}: cannot read program: {err}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        err: std::io::Error,
    },
    /// Syntax or semantics (file, line and column in the message; an error in a subroutine file
    /// names that file and the calls that led to it).
    #[error("{}", .err.display_in(.file))]
    Gcode {
        /// The file.
        file: String,
        /// The interpreter's error.
        err: interp::GcodeError,
    },
    /// The program turns a rotary axis (A, B, C) of a machine that has none.
    #[error("{file}: line {line}: the program moves the {axis} axis; machine {machine} has no rotary axes")]
    NoRotaryAxes {
        /// The file.
        file: String,
        /// 1-based line of the first move that turns the axis.
        line: usize,
        /// `'A'`, `'B'` or `'C'`.
        axis: char,
        /// The machine's name.
        machine: String,
    },
    /// Planning or travel problem (line in the message; a travel problem in the program's
    /// unit of length).
    #[error("{file}: {}", motion_message(.err, *.unit))]
    Motion {
        /// The file.
        file: String,
        /// The planner's error.
        err: motion::MotionError,
        /// The program's unit of length (G20/G21) at the line of the error.
        unit: LengthUnit,
    },
    /// `M6` loads a tool the tool table does not have.
    #[error("{file}: line {line}: M6 loads tool {tool}, which is not in the tool table")]
    UnknownTool {
        /// The file.
        file: String,
        /// Line of the tool change.
        line: usize,
        /// The tool number.
        tool: u32,
    },
}

/// A planner's error, a position beyond the travel told in `unit`.
fn motion_message(err: &motion::MotionError, unit: LengthUnit) -> String {
    match *err {
        motion::MotionError::AxisOutOfTravel {
            line,
            axis,
            pos_mm,
            min_mm,
            max_mm,
        } => motion::travel_message(line, axis, [pos_mm, min_mm, max_mm], unit),
        ref other => other.to_string(),
    }
}

/// The program's unit of length (G20/G21) at each line that emitted a move (the first move's
/// unit when a line emitted several); mm for a line without moves.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LineUnits(std::collections::HashMap<usize, LengthUnit>);

impl LineUnits {
    /// From the moves and their units (see [`interp::run_program_with_units`]).
    pub fn new(moves: &[interp::CanonMove], units: &[LengthUnit]) -> Self {
        let mut map = std::collections::HashMap::new();
        for (m, u) in moves.iter().zip(units) {
            map.entry(m.line).or_insert(*u);
        }
        Self(map)
    }

    /// The unit at `line`.
    pub fn at(&self, line: usize) -> LengthUnit {
        self.0.get(&line).copied().unwrap_or(LengthUnit::Mm)
    }
}

/// The diagonal tests of the campaign (face diagonals XY, YZ, XZ and the four body diagonals
/// of ISO 230-6): (report name, program text).
pub const DIAGONALS: [(&str, &str); 7] = [
    ("XY", include_str!("../../../trajectories/diag_xy.ngc")),
    ("YZ", include_str!("../../../trajectories/diag_yz.ngc")),
    ("XZ", include_str!("../../../trajectories/diag_xz.ngc")),
    ("PPP", include_str!("../../../trajectories/diag_ppp.ngc")),
    ("NPP", include_str!("../../../trajectories/diag_npp.ngc")),
    ("PNP", include_str!("../../../trajectories/diag_pnp.ngc")),
    ("PPN", include_str!("../../../trajectories/diag_ppn.ngc")),
];

/// Most thermal integration steps one `run` may take (machine time / thermal step).
pub const MAX_THERMAL_STEPS: f64 = 2.0e7;
/// Most interpolation samples one `run --every-cycle` may record (program time / cycle).
pub const MAX_CYCLE_SAMPLES: f64 = 2.0e7;

/// A run whose size (machine time over step) would take hours or exhaust memory.
#[derive(Debug, Error)]
#[error("{file}: {duration_s:.0} s of machine time at {what} {step_s:e} s is {steps:.3e} steps, above the limit of {max:.0e}: use a larger {option}")]
pub struct RunTooLarge {
    /// The program (the last one counted).
    pub file: String,
    /// Machine time counted (s).
    pub duration_s: f64,
    /// Which step (`thermal step` or `interpolation cycle`).
    pub what: &'static str,
    /// The step (s).
    pub step_s: f64,
    /// Steps it would take.
    pub steps: f64,
    /// The limit.
    pub max: f64,
    /// The command-line option to change.
    pub option: &'static str,
}

/// Refuses runs of more than [`MAX_THERMAL_STEPS`] thermal steps over `duration_s` of machine
/// time, or, with `interp_cycle_s`, more than [`MAX_CYCLE_SAMPLES`] recorded samples over the
/// measured program's `program_s`.
pub fn check_run_size(
    file: &str,
    duration_s: f64,
    thermal_step_s: f64,
    program_s: f64,
    interp_cycle_s: Option<f64>,
) -> Result<(), RunTooLarge> {
    let steps = duration_s / thermal_step_s;
    if steps > MAX_THERMAL_STEPS {
        return Err(RunTooLarge {
            file: file.to_string(),
            duration_s,
            what: "thermal step",
            step_s: thermal_step_s,
            steps,
            max: MAX_THERMAL_STEPS,
            option: "--thermal-step-s",
        });
    }
    if let Some(dt_s) = interp_cycle_s {
        let samples = program_s / dt_s;
        if samples > MAX_CYCLE_SAMPLES {
            return Err(RunTooLarge {
                file: file.to_string(),
                duration_s: program_s,
                what: "interpolation cycle",
                step_s: dt_s,
                steps: samples,
                max: MAX_CYCLE_SAMPLES,
                option: "--interp-cycle-ms (or drop --every-cycle)",
            });
        }
    }
    Ok(())
}

/// Largest angle, degrees, at which a rotary axis of a machine without rotary axes counts as
/// not moved (1e-9°: float rounding of offsets that cancel, e.g. `G92 A5` then `G0 A5`).
pub const ROTARY_STILL_DEG: f64 = 1e-9;

/// Refuses a program that turns a rotary axis on a machine without rotary axes (every
/// machine description today: X, Y, Z only). The axes start at 0°; words that leave them there
/// (`A0`, or angles cancelled by offsets) are accepted, as they move nothing.
///
/// # Errors
/// [`ProgramError::NoRotaryAxes`] naming the first move (line) and axis that turn.
pub fn refuse_rotary(
    moves: &[interp::CanonMove],
    file: &str,
    machine: &str,
) -> Result<(), ProgramError> {
    for m in moves {
        let (interp::CanonKind::Traverse { end_abc_deg, .. }
        | interp::CanonKind::Feed { end_abc_deg, .. }
        | interp::CanonKind::Probe { end_abc_deg, .. }
        | interp::CanonKind::Arc { end_abc_deg, .. }) = &m.kind
        else {
            continue;
        };
        if let Some(i) = (0..3).find(|&i| end_abc_deg[i].abs() > ROTARY_STILL_DEG) {
            return Err(ProgramError::NoRotaryAxes {
                file: file.to_string(),
                line: m.line,
                axis: ['A', 'B', 'C'][i],
                machine: machine.to_string(),
            });
        }
    }
    Ok(())
}

/// Reads, interprets, plans and travel-checks a program file with the machine's own tool for
/// every tool number (see [`crate::tools`]).
pub fn load_plan(
    path: &Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    load_plan_with_tools(path, machine, start_mm, &ToolTable::default())
}

/// [`load_plan`] with a tool table.
pub fn load_plan_with_tools(
    path: &Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
) -> Result<Plan, ProgramError> {
    let placement = Placement::of_machine(machine);
    load_plan_placed(path, machine, start_mm, tools, &placement, true).map(|(plan, _)| plan)
}

/// Reads, interprets and plans a program file placed by `placement` (work offsets, extra
/// subroutine folders after the program's own folder); travel-checked if `travel_checked`.
/// Returns the plan and the program's unit of length at each line.
pub fn load_plan_placed(
    path: &Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
    placement: &Placement,
    travel_checked: bool,
) -> Result<(Plan, LineUnits), ProgramError> {
    let (file, text) = read_program(path)?;
    let dirs = placement.search_path(Some(path));
    let (plan, units) = plan_text(&text, &file, machine, start_mm, tools, placement, dirs)?;
    if travel_checked {
        travel_check(&plan, &file, machine, &units)?;
    }
    Ok((plan, units))
}

/// The program file's display name and text.
fn read_program(path: &Path) -> Result<(String, String), ProgramError> {
    let file = path.display().to_string();
    match crate::read::read_text(path) {
        Ok(text) => Ok((file, text)),
        Err(err) => Err(ProgramError::Io { file, err }),
    }
}

/// Reads, interprets and plans a program file without the travel check (for `check`, which
/// reports every travel violation instead of stopping at the first), with a tool table.
pub fn load_plan_unchecked(
    path: &Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
) -> Result<Plan, ProgramError> {
    let placement = Placement::of_machine(machine);
    load_plan_placed(path, machine, start_mm, tools, &placement, false).map(|(plan, _)| plan)
}

/// Interprets and plans program text, without the travel check; `file` names it in errors.
pub fn plan_source_unchecked(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    plan_source_unchecked_with_tools(text, file, machine, start_mm, &ToolTable::default())
}

/// [`plan_source_unchecked`] with a tool table (lengths relative to the machine's own tool,
/// see [`crate::tools`]).
pub fn plan_source_unchecked_with_tools(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
) -> Result<Plan, ProgramError> {
    let placement = Placement::of_machine(machine);
    plan_text(text, file, machine, start_mm, tools, &placement, Vec::new()).map(|(plan, _)| plan)
}

/// The interpreter's configuration for a program placed by `placement`: work offsets, tool
/// lengths and diameters relative to the machine's own tool, subroutine files from `dirs`.
fn interp_config_in(
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
    placement: &Placement,
    subroutine_dirs: Vec<PathBuf>,
) -> InterpConfig {
    let (tool_lengths_mm, tool_diameters_mm) = tools.interp_data(machine);
    InterpConfig {
        start_mm,
        work_offsets_mm: placement.work_offsets_mm,
        tool_lengths_mm,
        tool_diameters_mm,
        subroutine_dirs,
        ..InterpConfig::default()
    }
}

/// [`interp_config_in`] with the subroutine folders of `program` (see
/// [`Placement::search_path`]).
fn interp_config(
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
    placement: &Placement,
    program: Option<&Path>,
) -> InterpConfig {
    let dirs = placement.search_path(program);
    interp_config_in(machine, start_mm, tools, placement, dirs)
}

/// Interprets and plans program text placed by `placement`, subroutine files from `dirs`.
fn plan_text(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
    placement: &Placement,
    subroutine_dirs: Vec<PathBuf>,
) -> Result<(Plan, LineUnits), ProgramError> {
    let cfg = interp_config_in(machine, start_mm, tools, placement, subroutine_dirs);
    let (moves, units) =
        interp::run_program_with_units(text, &cfg).map_err(|err| ProgramError::Gcode {
            file: file.to_string(),
            err,
        })?;
    plan_moves(&moves, &units, file, machine, start_mm, tools)
}

/// Plans interpreted moves (their units of length in `units`), refusing rotary words and
/// unknown tools, without the travel check.
fn plan_moves(
    moves: &[interp::CanonMove],
    units: &[LengthUnit],
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
) -> Result<(Plan, LineUnits), ProgramError> {
    let units = LineUnits::new(moves, units);
    refuse_rotary(moves, file, &machine.machine.name)?;
    let plan = motion::plan(moves, start_mm, &machine.motion).map_err(|err| {
        // A move far outside the travel (a wild work offset) takes days at a feed: the travel
        // is what is wrong, and is what the user is told.
        let err = match err {
            motion::MotionError::ProgramTooLong { line, .. } => {
                first_end_beyond_travel(moves, line, machine).unwrap_or(err)
            }
            err => err,
        };
        let unit = units.at(err_line(&err));
        ProgramError::Motion {
            file: file.to_string(),
            err,
            unit,
        }
    })?;
    check_tools(&plan, file, machine, tools)?;
    Ok((plan, units))
}

/// The first move, up to source line `last_line`, whose end lies outside the machine's linear
/// travel, as a travel error.
fn first_end_beyond_travel(
    moves: &[interp::CanonMove],
    last_line: usize,
    machine: &MachineSpec,
) -> Option<motion::MotionError> {
    let (lo, hi) = (machine.axes.travel_min_mm, machine.axes.travel_max_mm);
    moves
        .iter()
        .take_while(|mv| mv.line <= last_line)
        .find_map(|mv| {
            let end_mm = match &mv.kind {
                interp::CanonKind::Traverse { end_mm, .. }
                | interp::CanonKind::Feed { end_mm, .. }
                | interp::CanonKind::Arc { end_mm, .. } => *end_mm,
                _ => return None,
            };
            (0..3)
                .find(|&i| !(lo[i]..=hi[i]).contains(&end_mm[i]))
                .map(|i| motion::MotionError::AxisOutOfTravel {
                    line: mv.line,
                    axis: ['X', 'Y', 'Z'][i],
                    pos_mm: end_mm[i],
                    min_mm: lo[i],
                    max_mm: hi[i],
                })
        })
}

/// Refuses a plan whose `M6` loads a tool the table does not have.
fn check_tools(
    plan: &Plan,
    file: &str,
    machine: &MachineSpec,
    tools: &ToolTable,
) -> Result<(), ProgramError> {
    for seg in plan.segments() {
        if let motion::SegmentKind::ToolChange { tool } = seg.kind {
            if tools.loaded(tool, machine).is_none() {
                return Err(ProgramError::UnknownTool {
                    file: file.to_string(),
                    line: seg.line,
                    tool,
                });
            }
        }
    }
    Ok(())
}

/// The line a planner's error names (0 if none).
fn err_line(err: &motion::MotionError) -> usize {
    match *err {
        motion::MotionError::AxisOutOfTravel { line, .. } => line,
        _ => 0,
    }
}

/// The travel check of a plan; `file` names it in errors, told in the program's units.
fn travel_check(
    plan: &Plan,
    file: &str,
    machine: &MachineSpec,
    units: &LineUnits,
) -> Result<(), ProgramError> {
    motion::check_travel(plan, machine.axes.travel_min_mm, machine.axes.travel_max_mm).map_err(
        |err| ProgramError::Motion {
            file: file.to_string(),
            unit: units.at(err_line(&err)),
            err,
        },
    )
}

/// Interprets, plans and travel-checks program text; `file` names it in errors.
pub fn plan_source(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    plan_source_with_tools(text, file, machine, start_mm, &ToolTable::default())
}

/// [`plan_source`] with a tool table.
pub fn plan_source_with_tools(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
) -> Result<Plan, ProgramError> {
    let placement = Placement::of_machine(machine);
    let (plan, units) = plan_text(text, file, machine, start_mm, tools, &placement, Vec::new())?;
    travel_check(&plan, file, machine, &units)?;
    Ok(plan)
}
