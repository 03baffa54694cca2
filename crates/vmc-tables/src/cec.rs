//! Siemens SINUMERIK 840D sl interpolatory compensation tables ("sag and angularity error
//! compensation", CEC) as an `%_N_NC_CEC_INI` program: writer and reader.
//!
//! **The table parameters, as the manual (Function Manual Extended Functions, K3:
//! Compensations, Interpolatory compensation, table parameters) defines them.** For table `t`:
//!
//! - `$AN_CEC[t,N]`: the compensation value of the compensation axis at interpolation point
//!   `N` (0 ≤ N ≤ MD18342 `$MN_MM_CEC_MAX_POINTS[t]` − 1), in mm;
//! - `$AN_CEC_INPUT_AXIS[t]`: the machine axis (base axis) whose *setpoint* is the table's
//!   input; `$AN_CEC_OUTPUT_AXIS[t]`: the machine axis (compensation axis) the table's output
//!   is applied to. They may differ: a cross table (e.g. Y straightness along X) corrects one
//!   axis as a function of another's position, which a per-joint table cannot;
//! - `$AN_CEC_STEP[t]`: the distance between interpolation points, mm;
//! - `$AN_CEC_MIN[t]`: the base-axis position of interpolation point 0; below it, point 0's
//!   value applies;
//! - `$AN_CEC_MAX[t]`: the position of the last interpolation point `k`; above it, point `k`'s
//!   value applies. Hence `MAX = MIN + STEP·k` with `k + 1` points, i.e.
//!   `STEP = (MAX − MIN)/(points − 1)` (the manual's direction-dependent example: 11 points
//!   from −585 to −5 mm are 58 mm apart);
//! - `$AN_CEC_DIRECTION[t]`: 0 the table applies in both traversing directions of the base
//!   axis, 1 only in the positive, −1 only in the negative one (two tables of the same axis
//!   pair make a position-dependent backlash compensation);
//! - `$AN_CEC_MULT_BY_TABLE[t]`: the number (index + 1) of a table to multiply this one by,
//!   0 for none; `$AN_CEC_IS_MODULO[t]`: 1 repeats the table cyclically (rotary axes).
//!
//! Values between points are interpolated linearly; the compensation values of all tables
//! with the same output axis add up. The program sets the tables in channel `n`
//! (`CHANDATA(n)`) and ends with `M17`.
//!
//! **What is written.** The layout of the manual's table example: the program name line,
//! `CHANDATA(n)`, then per table its values `$AN_CEC[t,0]=…` in order and its parameters in
//! the order INPUT_AXIS, OUTPUT_AXIS, STEP, MIN, MAX, DIRECTION, MULT_BY_TABLE, IS_MODULO,
//! then `M17`. Values in mm with up to 6 decimals (1 nm), positions with at least one decimal
//! (`-400.0`), `MULT_BY_TABLE` and `IS_MODULO` always 0 (this crate neither multiplies tables
//! nor writes modulo tables). Comment lines (`;`) may follow `CHANDATA`.
//!
//! **What is read.** [`parse_cec_program`] reads that layout (any order of the assignments,
//! spaces around `=`, `;` comments) and refuses, with the line, what it cannot vouch for: an
//! unknown statement, a parameter it does not model (`$AN_CEC_INPUT_NCU`, a table
//! multiplication, a modulo table), a missing value or parameter, and a table whose `MAX`
//! is not `MIN + STEP·(points − 1)` (where the documented meaning of the parameters gives
//! no answer for the points beyond).

mod parse;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::number::{
    interpolate, is_plain_name, quantise_mm, short_mm, Direction, MAX_ABS_MM, RESOLUTION_MM,
};

pub use parse::parse_cec_program;

/// The program's first line: the name of the compensation-table initialisation file.
pub const CEC_PROGRAM_NAME: &str = "%_N_NC_CEC_INI";

/// Most interpolation points the reader accepts in one table (a guard against a corrupt index,
/// not a controller limit: MD18342 sets the controller's, per table).
pub const MAX_CEC_POINTS_READ: usize = 100_000;

/// Most tables the reader accepts (a guard, as [`MAX_CEC_POINTS_READ`]).
pub const MAX_CEC_TABLES_READ: usize = 1_000;

/// `$AN_CEC_DIRECTION`: the traversing directions of the base axis a table applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CecDirection {
    /// 0: both directions.
    Both,
    /// 1: only while the base axis traverses in the positive direction.
    Positive,
    /// −1: only while it traverses in the negative direction.
    Negative,
}

impl CecDirection {
    /// The value written for `$AN_CEC_DIRECTION`.
    pub fn number(self) -> i8 {
        match self {
            CecDirection::Both => 0,
            CecDirection::Positive => 1,
            CecDirection::Negative => -1,
        }
    }

    /// The direction of a `$AN_CEC_DIRECTION` value (None for other values).
    pub fn from_number(n: i64) -> Option<Self> {
        match n {
            0 => Some(CecDirection::Both),
            1 => Some(CecDirection::Positive),
            -1 => Some(CecDirection::Negative),
            _ => None,
        }
    }

    /// Whether a table with this setting applies while the base axis moves in `motion`.
    pub fn applies_to(self, motion: Direction) -> bool {
        match self {
            CecDirection::Both => true,
            CecDirection::Positive => motion == Direction::Positive,
            CecDirection::Negative => motion == Direction::Negative,
        }
    }
}

/// Problems with a CEC table or program. `line` is 1-based.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CecError {
    /// A table that cannot be written as asked.
    #[error("CEC table: invalid {field}: {reason}")]
    InvalidTable {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A program setting that cannot be written (channel, comment text).
    #[error("CEC program: invalid {field}: {reason}")]
    InvalidProgram {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The first statement is not the program name line.
    #[error("line {line}: expected the program name `{CEC_PROGRAM_NAME}` first, found {found:?}")]
    MissingProgramName {
        /// The line.
        line: usize,
        /// What is there.
        found: String,
    },
    /// The second statement is not `CHANDATA(n)`.
    #[error("line {line}: expected `CHANDATA(<channel>)` after the program name, found {found:?}")]
    MissingChandata {
        /// The line.
        line: usize,
        /// What is there.
        found: String,
    },
    /// A statement this reader does not know.
    #[error("line {line}: unknown statement {text:?}")]
    UnknownStatement {
        /// The line.
        line: usize,
        /// The statement.
        text: String,
    },
    /// A statement this reader knows but does not model.
    #[error("line {line}: {what} is not supported: {reason}")]
    Unsupported {
        /// The line.
        line: usize,
        /// The statement or setting.
        what: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A right-hand side that is not what the parameter takes.
    #[error("line {line}: {what} = {text:?} is not {expected}")]
    BadValue {
        /// The line.
        line: usize,
        /// The parameter.
        what: String,
        /// The value text.
        text: String,
        /// What is expected.
        expected: &'static str,
    },
    /// The same parameter or value assigned twice.
    #[error("line {line}: {what} is assigned again (first on line {first_line})")]
    Duplicate {
        /// The line.
        line: usize,
        /// The parameter or value.
        what: String,
        /// Its first assignment.
        first_line: usize,
    },
    /// A statement after `M17`.
    #[error("line {line}: {text:?} follows M17, the end of the program")]
    AfterEnd {
        /// The line.
        line: usize,
        /// The statement.
        text: String,
    },
    /// No `M17` at the end.
    #[error("the program does not end with M17")]
    MissingEnd,
    /// No table in the program.
    #[error("the program sets no compensation table")]
    NoTables,
    /// A table index without any assignment between used indices.
    #[error(
        "table {table} is missing (tables {table_count_hint} are set, indices must run from 0)"
    )]
    TableIndexGap {
        /// The missing table index.
        table: usize,
        /// The indices present, as text.
        table_count_hint: String,
    },
    /// A required parameter of a table is not set.
    #[error("table {table}: {parameter} is not set")]
    MissingParameter {
        /// The table index.
        table: usize,
        /// The parameter.
        parameter: &'static str,
    },
    /// An interpolation point's value is not set while a later one is.
    #[error("table {table}: the value of interpolation point {point} is not set (points run from 0 without gaps)")]
    MissingValue {
        /// The table index.
        table: usize,
        /// The point.
        point: usize,
    },
    /// A table's `MAX` is not `MIN + STEP·(points − 1)`.
    #[error(
        "table {table}: $AN_CEC_MAX = {max_mm} mm, but {points} points {step_mm} mm apart from \
         $AN_CEC_MIN = {min_mm} mm end at {expected_mm} mm; the documented meaning of the \
         parameters (MAX is the last point's position) leaves such a table undefined"
    )]
    EndPositionMismatch {
        /// The table index.
        table: usize,
        /// `$AN_CEC_MIN`, mm.
        min_mm: f64,
        /// `$AN_CEC_STEP`, mm.
        step_mm: f64,
        /// `$AN_CEC_MAX`, mm.
        max_mm: f64,
        /// Points in the table.
        points: usize,
        /// `MIN + STEP·(points − 1)`, mm.
        expected_mm: f64,
    },
}

/// One interpolatory compensation table, positions and values in mm on the 1 nm grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CecTable {
    input_axis: String,
    output_axis: String,
    min_mm: f64,
    step_mm: f64,
    values_mm: Vec<f64>,
    direction: CecDirection,
}

impl CecTable {
    /// A table correcting machine axis `output_axis` by `values_mm[N]` (mm) at the base-axis
    /// positions `min_mm + N·step_mm` of machine axis `input_axis`, for `direction`. Values
    /// and positions are quantised to 1 nm.
    ///
    /// # Errors
    /// [`CecError::InvalidTable`]: an axis name that is not a plain name (`AX1`, `X1`), a
    /// position or value not finite or beyond ±1e5 mm, a step below 1 nm, fewer than 2
    /// values.
    pub fn new(
        input_axis: &str,
        output_axis: &str,
        min_mm: f64,
        step_mm: f64,
        values_mm: &[f64],
        direction: CecDirection,
    ) -> Result<Self, CecError> {
        let invalid = |field, reason: String| CecError::InvalidTable { field, reason };
        for (field, name) in [("input axis", input_axis), ("output axis", output_axis)] {
            if !is_plain_name(name) {
                return Err(invalid(
                    field,
                    format!("{name:?} is not a machine axis name (letters, digits, `_`)"),
                ));
            }
        }
        let usable = |v: f64| v.is_finite() && v.abs() <= MAX_ABS_MM;
        if !usable(min_mm) {
            return Err(invalid("MIN", format!("{min_mm} mm")));
        }
        let step_mm = quantise_mm(step_mm);
        if !(usable(step_mm) && step_mm >= RESOLUTION_MM) {
            return Err(invalid(
                "STEP",
                format!("{step_mm} mm (at least {RESOLUTION_MM} mm)"),
            ));
        }
        if values_mm.len() < 2 {
            return Err(invalid(
                "values",
                format!("{} point(s), at least 2", values_mm.len()),
            ));
        }
        if let Some((n, v)) = values_mm.iter().enumerate().find(|(_, v)| !usable(**v)) {
            return Err(invalid("values", format!("point {n} is {v} mm")));
        }
        let table = Self {
            input_axis: input_axis.to_string(),
            output_axis: output_axis.to_string(),
            min_mm: quantise_mm(min_mm),
            step_mm,
            values_mm: values_mm.iter().map(|&v| quantise_mm(v)).collect(),
            direction,
        };
        if !usable(table.max_mm()) {
            return Err(invalid("MAX", format!("{} mm", table.max_mm())));
        }
        Ok(table)
    }

    /// The base axis (machine axis name).
    pub fn input_axis(&self) -> &str {
        &self.input_axis
    }

    /// The compensation axis (machine axis name).
    pub fn output_axis(&self) -> &str {
        &self.output_axis
    }

    /// `$AN_CEC_MIN`: position of point 0, mm.
    pub fn min_mm(&self) -> f64 {
        self.min_mm
    }

    /// `$AN_CEC_STEP`: distance between points, mm.
    pub fn step_mm(&self) -> f64 {
        self.step_mm
    }

    /// `$AN_CEC_MAX = MIN + STEP·(points − 1)`: position of the last point, mm.
    pub fn max_mm(&self) -> f64 {
        self.position_mm(self.values_mm.len() - 1)
    }

    /// Position of interpolation point `n`, mm.
    pub fn position_mm(&self, n: usize) -> f64 {
        quantise_mm(self.min_mm + n as f64 * self.step_mm)
    }

    /// The compensation values `$AN_CEC[t,N]`, mm.
    pub fn values_mm(&self) -> &[f64] {
        &self.values_mm
    }

    /// `$AN_CEC_DIRECTION`.
    pub fn direction(&self) -> CecDirection {
        self.direction
    }

    /// The compensation this table adds to its output axis when the base axis's setpoint is
    /// `input_mm` and it moves in `motion`: linear between points, end values beyond the ends,
    /// zero when the table does not apply to that direction; mm.
    pub fn compensation_mm(&self, input_mm: f64, motion: Direction) -> f64 {
        if !self.direction.applies_to(motion) {
            return 0.0;
        }
        let x: Vec<f64> = (0..self.values_mm.len())
            .map(|n| self.position_mm(n))
            .collect();
        interpolate(&x, &self.values_mm, input_mm)
    }
}

/// An `%_N_NC_CEC_INI` program: the tables set in one channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CecProgram {
    /// The channel of `CHANDATA(n)` (default in the manual's example: 1).
    pub channel: u32,
    /// Comment lines written after `CHANDATA` (without the `;`; one line each).
    pub comment_lines: Vec<String>,
    /// The tables, written with indices 0, 1, … in this order.
    pub tables: Vec<CecTable>,
}

impl CecProgram {
    /// The sum of the compensations of every table whose output axis is `output_axis`, with
    /// the base axes at the setpoints `input_mm(axis)` and moving in `motion(axis)`, mm.
    pub fn total_compensation_mm(
        &self,
        output_axis: &str,
        input_mm: impl Fn(&str) -> f64,
        motion: impl Fn(&str) -> Direction,
    ) -> f64 {
        self.tables
            .iter()
            .filter(|t| t.output_axis == output_axis)
            .map(|t| t.compensation_mm(input_mm(&t.input_axis), motion(&t.input_axis)))
            .sum()
    }
}

/// The program text (layout in the module doc).
///
/// # Errors
/// [`CecError::InvalidProgram`]: channel 0, no table, or a comment line holding a line break or
/// control character.
pub fn write_cec_program(program: &CecProgram) -> Result<String, CecError> {
    let invalid = |field, reason: String| CecError::InvalidProgram { field, reason };
    if program.channel == 0 {
        return Err(invalid("channel", "channels count from 1".into()));
    }
    if program.tables.is_empty() {
        return Err(invalid(
            "tables",
            "a program needs at least one table".into(),
        ));
    }
    if let Some(c) = program
        .comment_lines
        .iter()
        .find(|c| c.chars().any(char::is_control))
    {
        return Err(invalid(
            "comment line",
            format!("{c:?} holds a line break or control character"),
        ));
    }
    let mut s = format!("{CEC_PROGRAM_NAME}\nCHANDATA({})\n", program.channel);
    for c in &program.comment_lines {
        s.push_str(&format!("; {c}\n"));
    }
    for (t, table) in program.tables.iter().enumerate() {
        write_table(&mut s, t, table);
    }
    s.push_str("M17\n");
    Ok(s)
}

fn write_table(s: &mut String, t: usize, table: &CecTable) {
    for (n, v) in table.values_mm.iter().enumerate() {
        s.push_str(&format!("$AN_CEC[{t},{n}]={}\n", short_mm(*v, 0)));
    }
    s.push_str(&format!("$AN_CEC_INPUT_AXIS[{t}]=({})\n", table.input_axis));
    s.push_str(&format!(
        "$AN_CEC_OUTPUT_AXIS[{t}]=({})\n",
        table.output_axis
    ));
    s.push_str(&format!(
        "$AN_CEC_STEP[{t}]={}\n",
        short_mm(table.step_mm, 1)
    ));
    s.push_str(&format!("$AN_CEC_MIN[{t}]={}\n", short_mm(table.min_mm, 1)));
    s.push_str(&format!(
        "$AN_CEC_MAX[{t}]={}\n",
        short_mm(table.max_mm(), 1)
    ));
    s.push_str(&format!(
        "$AN_CEC_DIRECTION[{t}]={}\n",
        table.direction.number()
    ));
    s.push_str(&format!("$AN_CEC_MULT_BY_TABLE[{t}]=0\n"));
    s.push_str(&format!("$AN_CEC_IS_MODULO[{t}]=0\n"));
}

#[cfg(test)]
mod tests;
