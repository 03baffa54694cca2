//! The reader of `%_N_NC_CEC_INI` programs (what it accepts: the module doc of `cec`).
//!
//! Every parameter of every table must be set: the controller keeps its system variables in
//! static memory, so a parameter the program leaves out keeps whatever value an earlier table
//! left there, which no reader of the file can know.

use std::collections::BTreeMap;

use super::{CecDirection, CecError, CecProgram, CecTable, CEC_PROGRAM_NAME};
use super::{MAX_CEC_POINTS_READ, MAX_CEC_TABLES_READ};
use crate::number::{quantise_mm, MAX_ABS_MM, RESOLUTION_MM};

/// A value and the line that set it.
type At<T> = (T, usize);

/// What the program set for one table.
#[derive(Default)]
struct Parts {
    values: BTreeMap<usize, At<f64>>,
    input: Option<At<String>>,
    output: Option<At<String>>,
    step: Option<At<f64>>,
    min: Option<At<f64>>,
    max: Option<At<f64>>,
    direction: Option<At<CecDirection>>,
    mult_by_table: Option<At<()>>,
    is_modulo: Option<At<()>>,
}

#[derive(PartialEq)]
enum Stage {
    Name,
    Chandata,
    Body,
    Ended,
}

/// Reads an `%_N_NC_CEC_INI` program into its tables.
///
/// # Errors
/// The first problem, with its line where it has one: a missing program name, `CHANDATA` or
/// `M17`, an unknown or unsupported statement, a value of the wrong kind, a duplicate
/// assignment, a table without some parameter or with a gap in its points, a table whose
/// `MAX` is not `MIN + STEP·(points − 1)` (within the 1 nm rounding of `STEP` per point).
pub fn parse_cec_program(text: &str) -> Result<CecProgram, CecError> {
    let mut stage = Stage::Name;
    let mut channel = 0;
    let mut comment_lines = Vec::new();
    let mut tables: BTreeMap<usize, Parts> = BTreeMap::new();
    let mut last_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        last_line = line;
        let (stmt, comment) = match raw.split_once(';') {
            Some((s, c)) => (s.trim(), Some(c.trim())),
            None => (raw.trim(), None),
        };
        if stmt.is_empty() {
            if let (Stage::Body, true, Some(c)) = (&stage, tables.is_empty(), comment) {
                comment_lines.push(c.to_string());
            }
            continue;
        }
        match stage {
            Stage::Name if stmt == CEC_PROGRAM_NAME => stage = Stage::Chandata,
            Stage::Name => {
                return Err(CecError::MissingProgramName {
                    line,
                    found: stmt.to_string(),
                })
            }
            Stage::Chandata => {
                channel = read_chandata(line, stmt)?;
                stage = Stage::Body;
            }
            Stage::Body if stmt == "M17" => stage = Stage::Ended,
            Stage::Body => assign(line, stmt, &mut tables)?,
            Stage::Ended => {
                return Err(CecError::AfterEnd {
                    line,
                    text: stmt.to_string(),
                })
            }
        }
    }
    match stage {
        Stage::Name => {
            return Err(CecError::MissingProgramName {
                line: last_line + 1,
                found: String::new(),
            })
        }
        Stage::Chandata => {
            return Err(CecError::MissingChandata {
                line: last_line + 1,
                found: String::new(),
            })
        }
        Stage::Body => return Err(CecError::MissingEnd),
        Stage::Ended => {}
    }
    Ok(CecProgram {
        channel,
        comment_lines,
        tables: assemble(tables)?,
    })
}

fn read_chandata(line: usize, stmt: &str) -> Result<u32, CecError> {
    let missing = || CecError::MissingChandata {
        line,
        found: stmt.to_string(),
    };
    let inner = stmt
        .strip_prefix("CHANDATA(")
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(missing)?;
    match inner.trim().parse::<u32>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(CecError::BadValue {
            line,
            what: "CHANDATA".into(),
            text: inner.to_string(),
            expected: "a channel number ≥ 1",
        }),
    }
}

/// One `$AN_CEC…[…] = …` assignment.
fn assign(line: usize, stmt: &str, tables: &mut BTreeMap<usize, Parts>) -> Result<(), CecError> {
    let unknown = || CecError::UnknownStatement {
        line,
        text: stmt.to_string(),
    };
    let (lhs, rhs) = stmt.split_once('=').ok_or_else(unknown)?;
    let (lhs, rhs) = (lhs.trim(), rhs.trim());
    let open = lhs.find('[').ok_or_else(unknown)?;
    let name = lhs[..open].trim();
    let index = lhs[open + 1..].strip_suffix(']').ok_or_else(unknown)?;
    if name == "$AN_CEC" {
        return assign_value(line, lhs, index, rhs, tables);
    }
    if !name.starts_with("$AN_CEC") {
        return Err(unknown());
    }
    let t = read_index(line, lhs, index, MAX_CEC_TABLES_READ)?;
    assign_parameter(line, name, lhs, rhs, tables.entry(t).or_default())
}

/// `$AN_CEC[t,n] = value`.
fn assign_value(
    line: usize,
    lhs: &str,
    index: &str,
    rhs: &str,
    tables: &mut BTreeMap<usize, Parts>,
) -> Result<(), CecError> {
    let (t, n) = index.split_once(',').ok_or_else(|| bad_index(line, lhs))?;
    let t = read_index(line, lhs, t, MAX_CEC_TABLES_READ)?;
    let n = read_index(line, lhs, n, MAX_CEC_POINTS_READ)?;
    let v = read_mm(line, lhs, rhs)?;
    let parts = tables.entry(t).or_default();
    if let Some((_, first_line)) = parts.values.get(&n) {
        return Err(duplicate(line, lhs, *first_line));
    }
    parts.values.insert(n, (v, line));
    Ok(())
}

/// `$AN_CEC_<name>[t] = value` of table `t`'s `parts`.
fn assign_parameter(
    line: usize,
    name: &str,
    lhs: &str,
    rhs: &str,
    parts: &mut Parts,
) -> Result<(), CecError> {
    match name {
        "$AN_CEC_INPUT_AXIS" => set(&mut parts.input, read_axis(line, lhs, rhs)?, line, lhs),
        "$AN_CEC_OUTPUT_AXIS" => set(&mut parts.output, read_axis(line, lhs, rhs)?, line, lhs),
        "$AN_CEC_STEP" => set(&mut parts.step, read_mm(line, lhs, rhs)?, line, lhs),
        "$AN_CEC_MIN" => set(&mut parts.min, read_mm(line, lhs, rhs)?, line, lhs),
        "$AN_CEC_MAX" => set(&mut parts.max, read_mm(line, lhs, rhs)?, line, lhs),
        "$AN_CEC_DIRECTION" => {
            let d = read_int(line, lhs, rhs, "-1, 0 or 1").and_then(|n| {
                CecDirection::from_number(n).ok_or_else(|| bad_int(line, lhs, rhs, "-1, 0 or 1"))
            })?;
            set(&mut parts.direction, d, line, lhs)
        }
        "$AN_CEC_MULT_BY_TABLE" => {
            if read_int(line, lhs, rhs, "a table number")? != 0 {
                return Err(CecError::Unsupported {
                    line,
                    what: format!("{lhs} = {rhs}"),
                    reason: "table multiplication is not modelled by this reader (only 0)",
                });
            }
            set(&mut parts.mult_by_table, (), line, lhs)
        }
        "$AN_CEC_IS_MODULO" => match read_int(line, lhs, rhs, "0 or 1")? {
            0 => set(&mut parts.is_modulo, (), line, lhs),
            1 => Err(CecError::Unsupported {
                line,
                what: format!("{lhs} = 1"),
                reason: "modulo tables (rotary axes) are not modelled by this reader",
            }),
            _ => Err(bad_int(line, lhs, rhs, "0 or 1")),
        },
        _ => Err(CecError::Unsupported {
            line,
            what: name.to_string(),
            reason: "this reader models the table values, INPUT_AXIS, OUTPUT_AXIS, STEP, MIN, \
                     MAX, DIRECTION, MULT_BY_TABLE and IS_MODULO only",
        }),
    }
}

fn set<T>(slot: &mut Option<At<T>>, value: T, line: usize, what: &str) -> Result<(), CecError> {
    if let Some((_, first_line)) = slot {
        return Err(duplicate(line, what, *first_line));
    }
    *slot = Some((value, line));
    Ok(())
}

fn duplicate(line: usize, what: &str, first_line: usize) -> CecError {
    CecError::Duplicate {
        line,
        what: what.to_string(),
        first_line,
    }
}

fn bad_index(line: usize, what: &str) -> CecError {
    CecError::BadValue {
        line,
        what: what.to_string(),
        text: what.to_string(),
        expected: "indexed as [table] or [table,point] with small non-negative integers",
    }
}

fn read_index(line: usize, what: &str, text: &str, limit: usize) -> Result<usize, CecError> {
    match text.trim().parse::<usize>() {
        Ok(i) if i < limit => Ok(i),
        _ => Err(bad_index(line, what)),
    }
}

fn read_mm(line: usize, what: &str, text: &str) -> Result<f64, CecError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_ABS_MM => Ok(v),
        _ => Err(CecError::BadValue {
            line,
            what: what.to_string(),
            text: text.to_string(),
            expected: "a finite number of mm within ±1e5",
        }),
    }
}

fn bad_int(line: usize, what: &str, text: &str, expected: &'static str) -> CecError {
    CecError::BadValue {
        line,
        what: what.to_string(),
        text: text.to_string(),
        expected,
    }
}

fn read_int(line: usize, what: &str, text: &str, expected: &'static str) -> Result<i64, CecError> {
    text.parse::<i64>()
        .map_err(|_| bad_int(line, what, text, expected))
}

fn read_axis(line: usize, what: &str, text: &str) -> Result<String, CecError> {
    text.strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .map(str::trim)
        .filter(|s| crate::number::is_plain_name(s))
        .map(str::to_string)
        .ok_or_else(|| CecError::BadValue {
            line,
            what: what.to_string(),
            text: text.to_string(),
            expected: "a machine axis name in parentheses, e.g. (AX1)",
        })
}

/// The tables from what the program set, every check of the module doc applied.
fn assemble(tables: BTreeMap<usize, Parts>) -> Result<Vec<CecTable>, CecError> {
    if tables.is_empty() {
        return Err(CecError::NoTables);
    }
    let present = || {
        let v: Vec<String> = tables.keys().map(|k| k.to_string()).collect();
        v.join(", ")
    };
    if let Some(missing) = (0..tables.len()).find(|t| !tables.contains_key(t)) {
        return Err(CecError::TableIndexGap {
            table: missing,
            table_count_hint: present(),
        });
    }
    tables
        .into_iter()
        .map(|(t, parts)| assemble_table(t, parts))
        .collect()
}

fn assemble_table(t: usize, p: Parts) -> Result<CecTable, CecError> {
    let missing = |parameter| CecError::MissingParameter {
        table: t,
        parameter,
    };
    let (input, _) = p.input.ok_or_else(|| missing("$AN_CEC_INPUT_AXIS"))?;
    let (output, _) = p.output.ok_or_else(|| missing("$AN_CEC_OUTPUT_AXIS"))?;
    let (step_mm, _) = p.step.ok_or_else(|| missing("$AN_CEC_STEP"))?;
    let (min_mm, _) = p.min.ok_or_else(|| missing("$AN_CEC_MIN"))?;
    let (max_mm, _) = p.max.ok_or_else(|| missing("$AN_CEC_MAX"))?;
    let (direction, _) = p.direction.ok_or_else(|| missing("$AN_CEC_DIRECTION"))?;
    p.mult_by_table
        .ok_or_else(|| missing("$AN_CEC_MULT_BY_TABLE"))?;
    p.is_modulo.ok_or_else(|| missing("$AN_CEC_IS_MODULO"))?;
    if p.values.is_empty() {
        return Err(CecError::MissingValue { table: t, point: 0 });
    }
    if let Some(point) = (0..p.values.len()).find(|n| !p.values.contains_key(n)) {
        return Err(CecError::MissingValue { table: t, point });
    }
    let values: Vec<f64> = p.values.values().map(|(v, _)| *v).collect();
    let points = values.len();
    let expected_mm = quantise_mm(min_mm + step_mm * (points as f64 - 1.0));
    // A STEP rounded to 1 nm moves the last point by up to half a nanometre per step.
    let tol_mm = 0.5 * RESOLUTION_MM * (points as f64 - 1.0) + RESOLUTION_MM;
    if (max_mm - expected_mm).abs() > tol_mm {
        return Err(CecError::EndPositionMismatch {
            table: t,
            min_mm,
            step_mm,
            max_mm,
            points,
            expected_mm,
        });
    }
    CecTable::new(&input, &output, min_mm, step_mm, &values, direction)
}
