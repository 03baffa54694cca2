//! LinuxCNC's per-joint compensation tables (`[JOINT_n] COMP_FILE`, `COMP_FILE_TYPE`): writer,
//! checker, reader and the INI lines that load them.
//!
//! **The format, as LinuxCNC's loader reads it.** One point per line, three numbers separated by
//! white space: `nominal forward reverse`, nominal (the commanded joint position, machine units,
//! here mm) strictly ascending, at most [`MAX_COMP_POINTS`] lines. The meaning of the two other
//! columns depends on `COMP_FILE_TYPE`:
//!
//! - type 0 ([`CompFileType::MeasuredPositions`]): the positions the joint really reached when
//!   commanded to `nominal`, moving forward and moving in reverse; the loader stores the trim
//!   `nominal − value`;
//! - type 1 ([`CompFileType::Trims`]): the trims themselves.
//!
//! A trim is added to the commanded joint position (`motor-pos-cmd = pos-cmd + trim`), linearly
//! interpolated on the commanded position, the forward column while the joint moves in the
//! positive direction and the reverse column while it moves in the negative one; beyond the
//! first and last nominal the end values hold. The table is loaded once, when LinuxCNC starts.
//!
//! **What the loader does not say.** It ends the table, without a warning, at the first line
//! that is not three numbers: a `#` header line at the top gives no compensation at all, a
//! comment in the middle drops every point after it. So the writer emits nothing but point
//! lines, and [`check_comp_file`] refuses every line the loader would stop at (and more: a
//! fourth column, which the loader would silently ignore), naming its line.
//!
//! Sign convention of this crate: a trim is the *correction* `c = −E`, where `E` is the error
//! (actual − nominal) at that commanded position; a type-0 file therefore holds
//! `nominal + E`, the position a laser would have measured.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::number::{fixed_mm, interpolate, quantise_mm, Direction, MAX_ABS_MM};

/// Most points (lines) LinuxCNC reads from one compensation file.
pub const MAX_COMP_POINTS: usize = 256;

/// Largest |trim| a table may hold, mm (default and only value: 1 mm).
///
/// Why: quasi-static errors of a machine tool are tens of µm; a trim of a millimetre means a
/// mistake, above all a type-0 file (measured positions, i.e. ≈ nominal) loaded as type 1
/// (trims), which would move every joint by its own position.
pub const MAX_TRIM_MM: f64 = 1.0;

/// The `COMP_FILE_TYPE` of a table: what its second and third columns hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CompFileType {
    /// Type 0: the measured (actual) positions; the loader stores `nominal − value`.
    MeasuredPositions,
    /// Type 1: the trims added to the commanded position.
    Trims,
}

impl CompFileType {
    /// The number written as `COMP_FILE_TYPE`.
    pub fn number(self) -> u8 {
        match self {
            CompFileType::MeasuredPositions => 0,
            CompFileType::Trims => 1,
        }
    }

    /// The type of a `COMP_FILE_TYPE` number (None for any other than 0 and 1).
    pub fn from_number(n: u8) -> Option<Self> {
        match n {
            0 => Some(CompFileType::MeasuredPositions),
            1 => Some(CompFileType::Trims),
            _ => None,
        }
    }
}

/// One point of a joint's table: a commanded position and the trims there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CompPoint {
    /// Commanded joint position, mm.
    pub nominal_mm: f64,
    /// Trim while the joint moves in the positive direction, mm (added to the command).
    pub forward_trim_mm: f64,
    /// Trim while the joint moves in the negative direction, mm.
    pub reverse_trim_mm: f64,
}

/// Problems with a compensation table or file. `line` is the 1-based line of the file, which is
/// also the point's number (one point per line).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CompFileError {
    /// The file or table has no point.
    #[error("the compensation table has no point (LinuxCNC would load an empty table)")]
    NoPoints,
    /// One point only: no interpolation is defined.
    #[error("the compensation table has {count} point; it needs at least 2")]
    TooFewPoints {
        /// Points found.
        count: usize,
    },
    /// More points than LinuxCNC reads.
    #[error(
        "the compensation table has {count} points, LinuxCNC reads at most {max} (line {line} \
         is the first too many)"
    )]
    TooManyPoints {
        /// Points found.
        count: usize,
        /// The limit.
        max: usize,
        /// The first line beyond the limit.
        line: usize,
    },
    /// A comment or header line: the loader would silently end the table there.
    #[error(
        "line {line} is a comment or header ({text:?}): LinuxCNC's loader ends the table at the \
         first line that is not three numbers, without a warning, so no point from here on \
         would be compensated; a COMP_FILE holds point lines only"
    )]
    CommentLine {
        /// The line.
        line: usize,
        /// Its text.
        text: String,
    },
    /// An empty line before further points: the loader would stop there.
    #[error(
        "line {line} is empty and points follow it: LinuxCNC's loader would end the table \
         there without a warning"
    )]
    BlankLine {
        /// The line.
        line: usize,
    },
    /// A line with another number of columns than three.
    #[error(
        "line {line} has {found} columns ({text:?}); a point is `nominal forward reverse`, three \
         numbers"
    )]
    WrongColumnCount {
        /// The line.
        line: usize,
        /// Columns found.
        found: usize,
        /// Its text.
        text: String,
    },
    /// A column that is not a number.
    #[error("line {line}, column {column}: {text:?} is not a number")]
    NotANumber {
        /// The line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The text found.
        text: String,
    },
    /// NaN, an infinity, or a magnitude beyond what the tables hold.
    #[error(
        "line {line}, column {column}: {value} is not a usable value (finite, |value| ≤ {max_mm} \
         mm)"
    )]
    NotFinite {
        /// The line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The value.
        value: f64,
        /// The largest magnitude accepted, mm.
        max_mm: f64,
    },
    /// A nominal position not above the previous one.
    #[error(
        "line {line}: nominal {nominal_mm} mm is not above the previous line's {previous_mm} mm \
         (LinuxCNC needs strictly ascending nominal positions)"
    )]
    NotAscending {
        /// The line.
        line: usize,
        /// Its nominal position, mm.
        nominal_mm: f64,
        /// The previous line's, mm.
        previous_mm: f64,
    },
    /// A trim beyond [`MAX_TRIM_MM`].
    #[error(
        "line {line}: the {column_name} trim is {trim_mm} mm, beyond ±{max_mm} mm (a type-0 \
         file of measured positions read as type 1?)"
    )]
    TrimTooLarge {
        /// The line.
        line: usize,
        /// `forward` or `reverse`.
        column_name: &'static str,
        /// The trim, mm.
        trim_mm: f64,
        /// The limit, mm.
        max_mm: f64,
    },
    /// An INI value that cannot be written (empty, or with characters an INI line cannot hold).
    #[error("cannot write `{key} = {value}` into an INI file: {reason}")]
    BadIniValue {
        /// The INI key.
        key: &'static str,
        /// The value asked for.
        value: String,
        /// What is wrong.
        reason: &'static str,
    },
}

/// A joint's compensation table, trims in mm, every value on the 1 nm grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointCompTable {
    points: Vec<CompPoint>,
}

impl JointCompTable {
    /// A table of `points`, quantised to 1 nm.
    ///
    /// # Errors
    /// Fewer than 2 or more than [`MAX_COMP_POINTS`] points, a value that is not finite or
    /// beyond ±1e5 mm, nominal positions not strictly ascending (after quantising), a trim
    /// beyond [`MAX_TRIM_MM`].
    pub fn new(points: Vec<CompPoint>) -> Result<Self, CompFileError> {
        check_count(points.len())?;
        let mut out: Vec<CompPoint> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            let line = i + 1;
            let cols = [p.nominal_mm, p.forward_trim_mm, p.reverse_trim_mm];
            for (c, v) in cols.into_iter().enumerate() {
                check_finite(line, c + 1, v)?;
            }
            let q = CompPoint {
                nominal_mm: quantise_mm(p.nominal_mm),
                forward_trim_mm: quantise_mm(p.forward_trim_mm),
                reverse_trim_mm: quantise_mm(p.reverse_trim_mm),
            };
            if let Some(prev) = out.last() {
                check_ascending(line, q.nominal_mm, prev.nominal_mm)?;
            }
            check_trim(line, "forward", q.forward_trim_mm)?;
            check_trim(line, "reverse", q.reverse_trim_mm)?;
            out.push(q);
        }
        Ok(Self { points: out })
    }

    /// The points, in ascending nominal order.
    pub fn points(&self) -> &[CompPoint] {
        &self.points
    }

    /// The trim LinuxCNC applies at the commanded position `commanded_mm` while the joint moves
    /// in `direction`: linear between points, the end values beyond the ends, mm.
    pub fn trim_mm(&self, commanded_mm: f64, direction: Direction) -> f64 {
        let x: Vec<f64> = self.points.iter().map(|p| p.nominal_mm).collect();
        let y: Vec<f64> = self
            .points
            .iter()
            .map(|p| match direction {
                Direction::Positive => p.forward_trim_mm,
                Direction::Negative => p.reverse_trim_mm,
            })
            .collect();
        interpolate(&x, &y, commanded_mm)
    }

    /// The file text for `file_type`: one `nominal forward reverse` line per point, 6 decimals
    /// (1 nm), nothing else (see the module doc: any other line would end the table).
    pub fn to_comp_file(&self, file_type: CompFileType) -> String {
        let mut s = String::with_capacity(self.points.len() * 40);
        for p in &self.points {
            let (fwd, rev) = match file_type {
                CompFileType::Trims => (p.forward_trim_mm, p.reverse_trim_mm),
                // The loader stores nominal − value: write the position it turns back into
                // this trim.
                CompFileType::MeasuredPositions => (
                    p.nominal_mm - p.forward_trim_mm,
                    p.nominal_mm - p.reverse_trim_mm,
                ),
            };
            s.push_str(&fixed_mm(p.nominal_mm));
            s.push(' ');
            s.push_str(&fixed_mm(fwd));
            s.push(' ');
            s.push_str(&fixed_mm(rev));
            s.push('\n');
        }
        s
    }
}

/// What a checked compensation file holds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CompFileSummary {
    /// Points (lines) in the table.
    pub points: usize,
    /// First nominal position, mm.
    pub nominal_min_mm: f64,
    /// Last nominal position, mm.
    pub nominal_max_mm: f64,
}

/// Checks a compensation file as LinuxCNC would load it, whatever its type: every line three
/// finite numbers (trailing empty lines allowed), nominal strictly ascending, 2 to
/// [`MAX_COMP_POINTS`] points.
///
/// # Errors
/// The first problem, with its line: a comment or header line, an empty line before more
/// points, a wrong column count, a column that is not a number, NaN or an infinity, a nominal
/// not above the previous one, too few or too many points.
pub fn check_comp_file(text: &str) -> Result<CompFileSummary, CompFileError> {
    let rows = read_rows(text)?;
    let first = rows.first().ok_or(CompFileError::NoPoints)?;
    let last = rows[rows.len() - 1];
    Ok(CompFileSummary {
        points: rows.len(),
        nominal_min_mm: first[0],
        nominal_max_mm: last[0],
    })
}

/// Reads a compensation file of type `file_type` back into trims (after [`check_comp_file`]'s
/// checks): type 1 as written, type 0 as `nominal − value`, as the loader stores them.
///
/// # Errors
/// What [`check_comp_file`] refuses, and a trim beyond [`MAX_TRIM_MM`] (typically a type-0
/// file read as type 1).
pub fn parse_comp_file(
    text: &str,
    file_type: CompFileType,
) -> Result<JointCompTable, CompFileError> {
    let rows = read_rows(text)?;
    let points = rows
        .iter()
        .map(|&[nominal_mm, a, b]| {
            let (forward_trim_mm, reverse_trim_mm) = match file_type {
                CompFileType::Trims => (a, b),
                CompFileType::MeasuredPositions => (nominal_mm - a, nominal_mm - b),
            };
            CompPoint {
                nominal_mm,
                forward_trim_mm,
                reverse_trim_mm,
            }
        })
        .collect();
    JointCompTable::new(points)
}

/// The INI lines that load `comp_file` for joint `joint` (to go into the configuration's
/// existing `[JOINT_<joint>]` section, shown here under its header):
///
/// ```text
/// [JOINT_0]
/// COMP_FILE = joint0-x.comp
/// COMP_FILE_TYPE = 1
/// ```
///
/// # Errors
/// [`CompFileError::BadIniValue`] for an empty file name, or one with a line break, a
/// control character, `#` or `;` (comment starters), or white space at either end.
pub fn ini_lines(
    joint: usize,
    comp_file: &str,
    file_type: CompFileType,
) -> Result<String, CompFileError> {
    let bad = |reason| CompFileError::BadIniValue {
        key: "COMP_FILE",
        value: comp_file.to_string(),
        reason,
    };
    if comp_file.is_empty() {
        return Err(bad("the file name is empty"));
    }
    if comp_file.chars().any(char::is_control) {
        return Err(bad("it holds a line break or another control character"));
    }
    if comp_file.contains(['#', ';']) {
        return Err(bad("`#` and `;` start comments in LinuxCNC's INI files"));
    }
    if comp_file.trim() != comp_file {
        return Err(bad("white space at either end would be lost"));
    }
    Ok(format!(
        "[JOINT_{joint}]\nCOMP_FILE = {comp_file}\nCOMP_FILE_TYPE = {}\n",
        file_type.number()
    ))
}

/// Every point line of `text` as three numbers, checked (see [`check_comp_file`]).
fn read_rows(text: &str) -> Result<Vec<[f64; 3]>, CompFileError> {
    let mut rows: Vec<[f64; 3]> = Vec::new();
    let mut blank_at: Option<usize> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() {
            blank_at.get_or_insert(line);
            continue;
        }
        if let Some(blank) = blank_at {
            return Err(CompFileError::BlankLine { line: blank });
        }
        let row = read_row(line, trimmed)?;
        if rows.len() == MAX_COMP_POINTS {
            let count = text.lines().filter(|l| !l.trim().is_empty()).count();
            return Err(CompFileError::TooManyPoints {
                count,
                max: MAX_COMP_POINTS,
                line,
            });
        }
        if let Some(prev) = rows.last() {
            check_ascending(line, row[0], prev[0])?;
        }
        rows.push(row);
    }
    check_count(rows.len())?;
    Ok(rows)
}

/// One point line: three finite numbers.
fn read_row(line: usize, text: &str) -> Result<[f64; 3], CompFileError> {
    if is_comment_or_header(text) {
        return Err(CompFileError::CommentLine {
            line,
            text: text.to_string(),
        });
    }
    let cols: Vec<&str> = text.split_whitespace().collect();
    if cols.len() != 3 {
        return Err(CompFileError::WrongColumnCount {
            line,
            found: cols.len(),
            text: text.to_string(),
        });
    }
    let mut row = [0.0; 3];
    for (c, (v, s)) in row.iter_mut().zip(&cols).enumerate() {
        *v = s.parse::<f64>().map_err(|_| CompFileError::NotANumber {
            line,
            column: c + 1,
            text: s.to_string(),
        })?;
        check_finite(line, c + 1, *v)?;
    }
    Ok(row)
}

/// A line that starts like a comment or a header rather than a number (`#`, `;`, `%`, `/`,
/// `(`, `[` or a letter): named as such, since it is the usual way a table silently ends.
fn is_comment_or_header(text: &str) -> bool {
    // `inf`/`nan` start with a letter too but are values; they are refused as not finite.
    let lower = text.to_ascii_lowercase();
    let first_word = lower.split_whitespace().next().unwrap_or("");
    let numeric_word = first_word.trim_start_matches(['+', '-']);
    let is_special_value = ["inf", "infinity", "nan"].contains(&numeric_word);
    text.starts_with(['#', ';', '%', '/', '(', '['])
        || (text.starts_with(|c: char| c.is_ascii_alphabetic()) && !is_special_value)
}

fn check_count(count: usize) -> Result<(), CompFileError> {
    match count {
        0 => Err(CompFileError::NoPoints),
        1 => Err(CompFileError::TooFewPoints { count }),
        n if n > MAX_COMP_POINTS => Err(CompFileError::TooManyPoints {
            count: n,
            max: MAX_COMP_POINTS,
            line: MAX_COMP_POINTS + 1,
        }),
        _ => Ok(()),
    }
}

fn check_finite(line: usize, column: usize, value: f64) -> Result<(), CompFileError> {
    if value.is_finite() && value.abs() <= MAX_ABS_MM {
        Ok(())
    } else {
        Err(CompFileError::NotFinite {
            line,
            column,
            value,
            max_mm: MAX_ABS_MM,
        })
    }
}

fn check_ascending(line: usize, nominal_mm: f64, previous_mm: f64) -> Result<(), CompFileError> {
    if nominal_mm > previous_mm {
        Ok(())
    } else {
        Err(CompFileError::NotAscending {
            line,
            nominal_mm,
            previous_mm,
        })
    }
}

fn check_trim(line: usize, column_name: &'static str, trim_mm: f64) -> Result<(), CompFileError> {
    if trim_mm.abs() <= MAX_TRIM_MM {
        Ok(())
    } else {
        Err(CompFileError::TrimTooLarge {
            line,
            column_name,
            trim_mm,
            max_mm: MAX_TRIM_MM,
        })
    }
}

#[cfg(test)]
mod tests;
