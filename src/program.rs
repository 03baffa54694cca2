//! From a G-code file to a checked, timed plan: read → interpret → plan → travel check.
//!
//! Every error names the file and, where it has one, the line (and column for syntax).

use std::path::Path;

use thiserror::Error;

use crate::interp::{self, InterpConfig};
use crate::machine::MachineSpec;
use crate::motion::{self, Plan};

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
    /// Syntax or semantics (line and column in the message).
    #[error("{file}: {err}")]
    Gcode {
        /// The file.
        file: String,
        /// The interpreter's error.
        err: interp::GcodeError,
    },
    /// Planning or travel problem (line in the message).
    #[error("{file}: {err}")]
    Motion {
        /// The file.
        file: String,
        /// The planner's error.
        err: motion::MotionError,
    },
}

/// Reads, interprets, plans and travel-checks a program file, starting at `start_mm`.
pub fn load_plan(
    path: &Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|err| ProgramError::Io {
        file: file.clone(),
        err,
    })?;
    plan_source(&text, &file, machine, start_mm)
}

/// Reads, interprets and plans a program file without the travel check (for `check`, which
/// reports every travel violation instead of stopping at the first).
pub fn load_plan_unchecked(
    path: &Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|err| ProgramError::Io {
        file: file.clone(),
        err,
    })?;
    plan_source_unchecked(&text, &file, machine, start_mm)
}

/// Interprets and plans program text, without the travel check; `file` names it in errors.
pub fn plan_source_unchecked(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    let cfg = InterpConfig {
        start_mm,
        work_offsets_mm: machine.axes.work_offsets_mm,
    };
    let moves = interp::run_program(text, &cfg).map_err(|err| ProgramError::Gcode {
        file: file.to_string(),
        err,
    })?;
    motion::plan(&moves, start_mm, &machine.motion).map_err(|err| ProgramError::Motion {
        file: file.to_string(),
        err,
    })
}

/// Interprets, plans and travel-checks program text; `file` names it in errors.
pub fn plan_source(
    text: &str,
    file: &str,
    machine: &MachineSpec,
    start_mm: [f64; 3],
) -> Result<Plan, ProgramError> {
    let plan = plan_source_unchecked(text, file, machine, start_mm)?;
    let motion_err = |err| ProgramError::Motion {
        file: file.to_string(),
        err,
    };
    motion::check_travel(
        &plan,
        machine.axes.travel_min_mm,
        machine.axes.travel_max_mm,
    )
    .map_err(motion_err)?;
    Ok(plan)
}
