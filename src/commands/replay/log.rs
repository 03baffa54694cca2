//! Reading servo-rate logs of a controller: the commanded axis positions of every servo cycle,
//! optionally the corrections the controller added, the spindle speed and sensor temperatures.
//!
//! Two formats, both parsed line by line from a [`BufRead`] (a log of hours at 1 kHz is never
//! held whole):
//! - `csv`: a header naming the columns, then one row per sample, comma-separated. Required
//!   `time_s,x_mm,y_mm,z_mm`; optional `corr_x_mm,corr_y_mm,corr_z_mm` (all three),
//!   `spindle_rpm`, and sensor temperatures `<sensor>_degc` (the names of `samples.csv`).
//! - `halsampler`: LinuxCNC's `halsampler` output, whitespace-separated numbers without a
//!   header; the columns are named by the user (`n,x,y,z,cx,cy,cz,s`, `n` the sample number of
//!   `halsampler -t`, `_` a column to skip; the CSV names are accepted too) and the time is
//!   `n × period` (or the row's index × period without `n`, or a `time_s` column).
//!
//! Positions and corrections in mm, time in s, spindle speed in rpm, temperatures in °C. Every
//! refusal names the line (1-based; blank lines are skipped but counted).

use std::io::BufRead;

use thiserror::Error;

/// The format of a log.
#[derive(Debug, Clone, PartialEq)]
pub enum LogFormat {
    /// CSV with a header.
    Csv,
    /// `halsampler` output with the columns named by the user and the servo period.
    Halsampler {
        /// Column names, in order.
        columns: Vec<String>,
        /// Servo period, s (None: a `time_s` column gives the time).
        period_s: Option<f64>,
    },
}

/// What a column holds.
#[derive(Debug, Clone, PartialEq)]
enum Column {
    Time,
    SampleNumber,
    Position(usize),
    Correction(usize),
    Spindle,
    Temperature,
    Skip,
}

/// Why a log cannot be read.
#[derive(Debug, Error)]
pub enum LogError {
    /// The file could not be read.
    #[error("line {line}: {source}")]
    Io {
        /// Line being read.
        line: usize,
        /// The cause.
        source: std::io::Error,
    },
    /// The log has no sample.
    #[error("the log has no samples")]
    Empty,
    /// A column name the reader does not know.
    #[error("line {line}: unknown column `{name}` (known: {known})")]
    UnknownColumn {
        /// Line of the header (0 for `--columns`).
        line: usize,
        /// The name.
        name: String,
        /// The names the format takes.
        known: &'static str,
    },
    /// A column named twice.
    #[error("line {line}: column `{name}` is named twice")]
    DuplicateColumn {
        /// Line of the header (0 for `--columns`).
        line: usize,
        /// The name.
        name: String,
    },
    /// A required column is missing.
    #[error("line {line}: no `{name}` column ({why})")]
    MissingColumn {
        /// Line of the header (0 for `--columns`).
        line: usize,
        /// The missing column.
        name: &'static str,
        /// Why it is needed.
        why: &'static str,
    },
    /// A row has another number of fields than there are columns.
    #[error("line {line}: {got} fields, the log has {want} columns")]
    FieldCount {
        /// The line.
        line: usize,
        /// Fields found.
        got: usize,
        /// Columns named.
        want: usize,
    },
    /// A field is not a number.
    #[error("line {line}: column `{column}`: `{text}` is not a number")]
    NotANumber {
        /// The line.
        line: usize,
        /// The column's name.
        column: String,
        /// The field.
        text: String,
    },
    /// A field is NaN or infinite.
    #[error("line {line}: column `{column}`: {value} is not a finite number")]
    NotFinite {
        /// The line.
        line: usize,
        /// The column's name.
        column: String,
        /// The value.
        value: f64,
    },
    /// The time does not increase.
    #[error("line {line}: time {time_s} s is not after the previous sample's {previous_s} s (time must increase)")]
    TimeNotIncreasing {
        /// The line.
        line: usize,
        /// The sample's time, s.
        time_s: f64,
        /// The previous sample's time, s.
        previous_s: f64,
    },
    /// The servo period is not a positive number.
    #[error("servo period must be > 0 s, got {0}")]
    Period(f64),
}

/// The names both formats take, for the unknown-column message.
const KNOWN: &str = "time_s, x_mm, y_mm, z_mm, corr_x_mm, corr_y_mm, corr_z_mm, spindle_rpm, \
                     <sensor>_degc; for halsampler also n, x, y, z, cx, cy, cz, s and _ (skip)";

/// What the column called `name` holds, if the reader knows it.
fn column_kind(name: &str, halsampler: bool) -> Option<Column> {
    Some(match name {
        "time_s" => Column::Time,
        "x_mm" => Column::Position(0),
        "y_mm" => Column::Position(1),
        "z_mm" => Column::Position(2),
        "corr_x_mm" => Column::Correction(0),
        "corr_y_mm" => Column::Correction(1),
        "corr_z_mm" => Column::Correction(2),
        "spindle_rpm" => Column::Spindle,
        n if n.len() > 5 && n.ends_with("_degc") => Column::Temperature,
        "n" if halsampler => Column::SampleNumber,
        "x" if halsampler => Column::Position(0),
        "y" if halsampler => Column::Position(1),
        "z" if halsampler => Column::Position(2),
        "cx" if halsampler => Column::Correction(0),
        "cy" if halsampler => Column::Correction(1),
        "cz" if halsampler => Column::Correction(2),
        "s" if halsampler => Column::Spindle,
        "_" if halsampler => Column::Skip,
        _ => return None,
    })
}

/// The columns of a log, checked: where each quantity is.
#[derive(Debug, Clone)]
pub struct LogColumns {
    names: Vec<String>,
    kinds: Vec<Column>,
    time: Option<usize>,
    sample_number: Option<usize>,
    position: [usize; 3],
    correction: Option<[usize; 3]>,
    spindle: Option<usize>,
    temperatures: Vec<usize>,
}

impl LogColumns {
    /// Checks the column `names` (of the header at `line`, 0 for names given on the command
    /// line).
    ///
    /// # Errors
    /// An unknown or repeated name, a missing position, an incomplete set of corrections, a
    /// CSV without `time_s`.
    pub fn new(names: &[&str], line: usize, halsampler: bool) -> Result<Self, LogError> {
        let mut kinds = Vec::with_capacity(names.len());
        for (i, &name) in names.iter().enumerate() {
            let kind = column_kind(name, halsampler).ok_or_else(|| LogError::UnknownColumn {
                line,
                name: name.to_string(),
                known: KNOWN,
            })?;
            if kind != Column::Skip && names[..i].contains(&name) {
                return Err(LogError::DuplicateColumn {
                    line,
                    name: name.to_string(),
                });
            }
            // `x` and `x_mm` name the same quantity: also a repetition.
            if kind != Column::Skip && kind != Column::Temperature && kinds.contains(&kind) {
                return Err(LogError::DuplicateColumn {
                    line,
                    name: name.to_string(),
                });
            }
            kinds.push(kind);
        }
        let find = |k: &Column| kinds.iter().position(|c| c == k);
        let mut position = [0; 3];
        for (a, axis) in ["x_mm", "y_mm", "z_mm"].into_iter().enumerate() {
            position[a] = find(&Column::Position(a)).ok_or(LogError::MissingColumn {
                line,
                name: axis,
                why: "the commanded position of each axis is required",
            })?;
        }
        let corr: Vec<Option<usize>> = (0..3).map(|a| find(&Column::Correction(a))).collect();
        let correction = match (corr[0], corr[1], corr[2]) {
            (Some(x), Some(y), Some(z)) => Some([x, y, z]),
            (None, None, None) => None,
            _ => {
                let name = ["corr_x_mm", "corr_y_mm", "corr_z_mm"]
                    [corr.iter().position(Option::is_none).unwrap_or(0)];
                return Err(LogError::MissingColumn {
                    line,
                    name,
                    why: "corrections come for all three axes or none",
                });
            }
        };
        let time = find(&Column::Time);
        if !halsampler && time.is_none() {
            return Err(LogError::MissingColumn {
                line,
                name: "time_s",
                why: "a CSV log gives each sample's time",
            });
        }
        Ok(LogColumns {
            names: names.iter().map(|s| s.to_string()).collect(),
            time,
            sample_number: find(&Column::SampleNumber),
            position,
            correction,
            spindle: find(&Column::Spindle),
            temperatures: (0..kinds.len())
                .filter(|&i| kinds[i] == Column::Temperature)
                .collect(),
            kinds,
        })
    }

    /// Whether the log has the controller's corrections.
    pub fn has_corrections(&self) -> bool {
        self.correction.is_some()
    }

    /// Whether the log has the spindle speed.
    pub fn has_spindle(&self) -> bool {
        self.spindle.is_some()
    }

    /// The sensor names of the temperature columns (`<sensor>_degc` without the suffix).
    pub fn sensor_names(&self) -> Vec<&str> {
        self.temperatures
            .iter()
            .map(|&i| self.names[i].trim_end_matches("_degc"))
            .collect()
    }
}

/// One sample of a log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSample {
    /// Line of the file (1-based).
    pub line: usize,
    /// Time, s.
    pub time_s: f64,
    /// Commanded axis positions before compensation, mm.
    pub commanded_mm: [f64; 3],
    /// Corrections the controller added, mm.
    pub correction_mm: Option<[f64; 3]>,
    /// Spindle speed, rpm.
    pub spindle_rpm: Option<f64>,
    /// Sensor temperatures, °C, in the order of [`LogColumns::sensor_names`].
    pub temperatures_degc: Vec<f64>,
}

/// Reads the samples of a log one line at a time.
pub struct LogReader<R: BufRead> {
    input: R,
    columns: LogColumns,
    halsampler: bool,
    period_s: Option<f64>,
    line: usize,
    row: usize,
    previous_s: Option<f64>,
    buf: String,
    values: Vec<f64>,
}

impl<R: BufRead> LogReader<R> {
    /// A reader of `input` in `format`; a CSV's header is read at once.
    ///
    /// # Errors
    /// An unreadable or bad header, bad column names, a bad period, a halsampler log with
    /// neither a period nor a `time_s` column.
    pub fn new(mut input: R, format: &LogFormat) -> Result<Self, LogError> {
        let mut line = 0;
        let (columns, period_s, halsampler) = match format {
            LogFormat::Csv => {
                let mut header = String::new();
                loop {
                    header.clear();
                    line += 1;
                    let n = input
                        .read_line(&mut header)
                        .map_err(|source| LogError::Io { line, source })?;
                    if n == 0 {
                        return Err(LogError::Empty);
                    }
                    if !header.trim().is_empty() {
                        break;
                    }
                }
                let names: Vec<&str> = header.trim().split(',').map(str::trim).collect();
                (LogColumns::new(&names, line, false)?, None, false)
            }
            LogFormat::Halsampler { columns, period_s } => {
                let names: Vec<&str> = columns.iter().map(String::as_str).collect();
                let cols = LogColumns::new(&names, 0, true)?;
                if let Some(p) = period_s {
                    if p.is_nan() || *p <= 0.0 || p.is_infinite() {
                        return Err(LogError::Period(*p));
                    }
                } else if cols.time.is_none() {
                    return Err(LogError::MissingColumn {
                        line: 0,
                        name: "time_s",
                        why: "without a servo period (--period-ms) a time_s column gives the time",
                    });
                }
                (cols, *period_s, true)
            }
        };
        Ok(LogReader {
            input,
            values: vec![0.0; columns.kinds.len()],
            columns,
            halsampler,
            period_s,
            line,
            row: 0,
            previous_s: None,
            buf: String::new(),
        })
    }

    /// The log's columns.
    pub fn columns(&self) -> &LogColumns {
        &self.columns
    }

    /// The next sample (None at the end).
    ///
    /// # Errors
    /// See [`LogError`]; each names the line.
    pub fn next_sample(&mut self) -> Result<Option<LogSample>, LogError> {
        loop {
            self.buf.clear();
            self.line += 1;
            let n = self
                .input
                .read_line(&mut self.buf)
                .map_err(|source| LogError::Io {
                    line: self.line,
                    source,
                })?;
            if n == 0 {
                return Ok(None);
            }
            if !self.buf.trim().is_empty() {
                break;
            }
        }
        self.parse_fields()?;
        let c = &self.columns;
        let v = &self.values;
        let time_s = match (c.time, c.sample_number, self.period_s) {
            (Some(i), _, _) => v[i],
            (None, Some(i), Some(p)) => v[i] * p,
            (None, _, Some(p)) => self.row as f64 * p,
            // Checked in `new`: a log without a time column has a period.
            (None, _, None) => self.row as f64,
        };
        if let Some(previous_s) = self.previous_s {
            if time_s <= previous_s {
                return Err(LogError::TimeNotIncreasing {
                    line: self.line,
                    time_s,
                    previous_s,
                });
            }
        }
        self.previous_s = Some(time_s);
        self.row += 1;
        Ok(Some(LogSample {
            line: self.line,
            time_s,
            commanded_mm: c.position.map(|i| v[i]),
            correction_mm: c.correction.map(|ix| ix.map(|i| v[i])),
            spindle_rpm: c.spindle.map(|i| v[i]),
            temperatures_degc: c.temperatures.iter().map(|&i| v[i]).collect(),
        }))
    }

    /// Parses the line in `buf` into `values` (skipped columns left at 0).
    fn parse_fields(&mut self) -> Result<(), LogError> {
        let text = self.buf.trim();
        let fields: Box<dyn Iterator<Item = &str>> = if self.halsampler {
            Box::new(text.split_whitespace())
        } else {
            Box::new(text.split(',').map(str::trim))
        };
        let want = self.columns.kinds.len();
        let mut got = 0;
        for (i, field) in fields.enumerate() {
            got = i + 1;
            if i >= want {
                continue;
            }
            if self.columns.kinds[i] == Column::Skip {
                continue;
            }
            let value: f64 = field.parse().map_err(|_| LogError::NotANumber {
                line: self.line,
                column: self.columns.names[i].clone(),
                text: field.to_string(),
            })?;
            if !value.is_finite() {
                return Err(LogError::NotFinite {
                    line: self.line,
                    column: self.columns.names[i].clone(),
                    value,
                });
            }
            self.values[i] = value;
        }
        if got != want {
            return Err(LogError::FieldCount {
                line: self.line,
                got,
                want,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
#[path = "log_tests.rs"]
mod tests;
