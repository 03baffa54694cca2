//! Calibration datasets: what virtual — or real — instruments measured, with the
//! temperature sensor readings logged at the same instants. CSV with units in the column names,
//! the same format a user would produce from a real machine.
//!
//! Columns: `cycle, time_s, instrument, x_mm, y_mm, z_mm, dx_um, dy_um, dz_um, rx_urad, ry_urad,
//! rz_urad`, optionally `dir` and `spindle_rpm`, then one `<sensor>_degc` column per temperature
//! sensor.
//!
//! `dir` is the approach direction of the measured position: `1` when the axes reached it moving
//! in the positive direction, `-1` when moving in the negative direction. For `laser_k` records it
//! is the direction of the swept axis (a bidirectional sweep, ISO 230-2, has forward `1` and
//! backward `-1` runs); for the other instruments it applies to every axis. A file without the
//! `dir` column (older datasets, forward-only sweeps) reads as `1` everywhere; an empty cell reads
//! as `1` too. The measurement columns mean, per instrument:
//!
//! | instrument   | dx, dy, dz (µm)               | rx, ry, rz (µrad)                    |
//! |--------------|-------------------------------|--------------------------------------|
//! | `laser_x`    | δx, δy, δz of the X axis      | εx, εy, εz of the X axis             |
//! | `laser_y`    | … of the Y axis               | … of the Y axis                      |
//! | `laser_z`    | … of the Z axis               | … of the Z axis                      |
//! | `spindle`    | spindle drifts δx, δy, δz      | tilts εx, εy; rz empty               |
//! | `squareness` | empty                         | α_yz (EA0Z), α_xz (EB0Z), α_xy (EC0Y) |
//! | `volumetric` | volumetric error Ex, Ey, Ez    | empty                                |
//!
//! Empty cells are read as "not measured" (NaN in memory).
//!
//! `spindle_rpm` is the commanded spindle speed the machine ran at *since the cycle's previous
//! record* (rpm, 0 when stopped), as a controller logging its spindle command would write it: a
//! speed change then falls at a record, and a model of the spindle's heat input sees the steps
//! where they were. It is optional (an empty cell or a missing column reads as "not logged");
//! only models that use the commanded speed need it (`Settings::spindle_speed_exponents`).
//!
//! `x_feed_mm_per_min`, `y_feed_mm_per_min`, `z_feed_mm_per_min` (optional, the three together)
//! are, the same way, each axis's commanded mean speed |v| since the cycle's previous record
//! (mm/min, 0 when parked): the heat its screw and motor take in. Only models with axis-feed
//! features need them (`Settings::axis_feed_taus_s`).
//!
//! Plausibility: a measurement beyond ±1e6 µm or µrad (a metre, a radian), a position beyond
//! ±1e6 mm or a temperature below absolute zero is refused with its line and column: such a
//! value is a corrupt cell or a unit mistake, and training on it would give absurd models
//! without any error.

use std::fmt::Write as _;

use thiserror::Error;

use crate::provenance::{InputRanges, MachineIdentity};

/// Which instrument produced a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Instrument {
    /// 6-DOF laser interferometer along X.
    LaserX,
    /// 6-DOF laser interferometer along Y.
    LaserY,
    /// 6-DOF laser interferometer along Z.
    LaserZ,
    /// 5-probe spindle test (ISO 230-3).
    Spindle,
    /// Squareness measurement (laser with optical square).
    Squareness,
    /// Direct volumetric error measurement at a point (e.g. laser tracker).
    Volumetric,
}

impl Instrument {
    /// All instruments, in file order.
    pub const ALL: [Instrument; 6] = [
        Instrument::LaserX,
        Instrument::LaserY,
        Instrument::LaserZ,
        Instrument::Spindle,
        Instrument::Squareness,
        Instrument::Volumetric,
    ];

    /// The name used in the `instrument` column.
    pub fn name(self) -> &'static str {
        match self {
            Instrument::LaserX => "laser_x",
            Instrument::LaserY => "laser_y",
            Instrument::LaserZ => "laser_z",
            Instrument::Spindle => "spindle",
            Instrument::Squareness => "squareness",
            Instrument::Volumetric => "volumetric",
        }
    }

    /// Parses a name of the `instrument` column.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.name() == s)
    }

    /// The laser instrument of axis 0, 1, 2.
    pub fn laser(axis: usize) -> Self {
        [Instrument::LaserX, Instrument::LaserY, Instrument::LaserZ][axis.min(2)]
    }
}

/// One reading of one instrument, with the temperatures logged at that instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Thermal cycle the record belongs to (free text without commas).
    pub cycle: String,
    /// Time since the start of the cycle, s.
    pub time_s: f64,
    /// Which instrument.
    pub instrument: Instrument,
    /// Machine axis position where it was measured, mm.
    pub pos_mm: [f64; 3],
    /// dx, dy, dz in µm and rx, ry, rz in µrad (NaN = not measured).
    pub values: [f64; 6],
    /// Sensor readings, °C, in the dataset's sensor order.
    pub temps_degc: Vec<f64>,
    /// Approach direction of the measured position: `1` positive, `-1` negative (see the
    /// module doc; default `1`).
    pub dir: i8,
    /// Commanded spindle speed since the cycle's previous record, rpm (see the module doc);
    /// `None` when not logged.
    pub spindle_rpm: Option<f64>,
    /// Commanded mean |speed| of X, Y, Z since the cycle's previous record, mm/min (see the
    /// module doc); `None` when not logged.
    pub axis_feed_mm_per_min: Option<[f64; 3]>,
}

/// A calibration dataset.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Dataset {
    /// Sensor names, in column order.
    pub sensor_names: Vec<String>,
    /// The records, in time order within each cycle.
    pub records: Vec<Record>,
    /// The machine the data was measured on, when the file says (its `# machine:` line).
    pub origin: Option<MachineIdentity>,
}

/// A dataset file that cannot be used.
#[derive(Debug, Error, PartialEq)]
pub enum DatasetError {
    /// A required column is missing.
    #[error("{source_name}: missing column `{column}`")]
    MissingColumn {
        /// File name.
        source_name: String,
        /// The column.
        column: String,
    },
    /// A cell cannot be read.
    #[error("{source_name}: line {line}, column `{column}`: {msg}")]
    BadCell {
        /// File name.
        source_name: String,
        /// 1-based line.
        line: usize,
        /// Column name.
        column: String,
        /// What is wrong.
        msg: String,
    },
    /// A column name appears twice in the header (which one would be meant?).
    #[error("{source_name}: column `{column}` appears twice in the header (columns {first} and {second})")]
    DuplicateColumn {
        /// File name.
        source_name: String,
        /// The column.
        column: String,
        /// 1-based positions of its first two occurrences.
        first: usize,
        /// See `first`.
        second: usize,
    },
    /// The file has no header or no records.
    #[error("{source_name}: {msg}")]
    Empty {
        /// File name.
        source_name: String,
        /// What is missing.
        msg: String,
    },
}

/// The optional approach-direction column.
const DIR_COLUMN: &str = "dir";

/// The optional commanded-spindle-speed column.
pub const SPINDLE_RPM_COLUMN: &str = "spindle_rpm";
/// Names of the optional axis-feed columns (X, Y, Z).
pub const AXIS_FEED_COLUMNS: [&str; 3] = [
    "x_feed_mm_per_min",
    "y_feed_mm_per_min",
    "z_feed_mm_per_min",
];

const FIXED: [&str; 12] = [
    "cycle",
    "time_s",
    "instrument",
    "x_mm",
    "y_mm",
    "z_mm",
    "dx_um",
    "dy_um",
    "dz_um",
    "rx_urad",
    "ry_urad",
    "rz_urad",
];

/// Largest plausible |value| of a position (mm) or a measurement (µm, µrad).
const PLAUSIBLE_MAX: f64 = 1e6;

/// Absolute zero, °C.
const ABSOLUTE_ZERO_DEGC: f64 = -273.15;

fn cell(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v}")
    }
}

impl Dataset {
    /// The ranges of `sensors` (names of this dataset's columns) and of the logged spindle speed over
    /// every record. A sensor without a finite reading gets `[NaN, NaN]`, never
    /// outside.
    pub fn input_ranges(&self, sensors: &[String]) -> InputRanges {
        let cols: Vec<Option<usize>> = sensors
            .iter()
            .map(|n| self.sensor_names.iter().position(|d| d == n))
            .collect();
        let mut sensor_degc = vec![[f64::INFINITY, f64::NEG_INFINITY]; sensors.len()];
        let mut rpm: Option<[f64; 2]> = None;
        for r in &self.records {
            for (range, col) in sensor_degc.iter_mut().zip(&cols) {
                if let Some(v) = col
                    .and_then(|c| r.temps_degc.get(c))
                    .filter(|v| v.is_finite())
                {
                    range[0] = range[0].min(*v);
                    range[1] = range[1].max(*v);
                }
            }
            if let Some(n) = r.spindle_rpm.filter(|n| n.is_finite()) {
                let range = rpm.get_or_insert([n, n]);
                range[0] = range[0].min(n);
                range[1] = range[1].max(n);
            }
        }
        for range in &mut sensor_degc {
            if range[0] > range[1] {
                *range = [f64::NAN, f64::NAN];
            }
        }
        InputRanges {
            sensors: sensors.to_vec(),
            sensor_degc,
            spindle_rpm: rpm,
            axis_feeds: None,
        }
    }

    /// Records of one instrument.
    pub fn of(&self, instrument: Instrument) -> impl Iterator<Item = &Record> {
        self.records
            .iter()
            .filter(move |r| r.instrument == instrument)
    }

    /// Writes the CSV text (shortest round-trip formatting of f64: reading it back gives the
    /// same bits).
    pub fn to_csv(&self) -> String {
        let mut s = String::new();
        if let Some(id) = &self.origin {
            s.push('#');
            s.push_str(&origin_line(id));
            s.push('\n');
        }
        s.push_str(&FIXED.join(","));
        s.push(',');
        s.push_str(DIR_COLUMN);
        let with_rpm = self.records.iter().any(|r| r.spindle_rpm.is_some());
        if with_rpm {
            s.push(',');
            s.push_str(SPINDLE_RPM_COLUMN);
        }
        let with_feed = self
            .records
            .iter()
            .any(|r| r.axis_feed_mm_per_min.is_some());
        if with_feed {
            for c in AXIS_FEED_COLUMNS {
                s.push(',');
                s.push_str(c);
            }
        }
        for n in &self.sensor_names {
            let _ = write!(s, ",{n}_degc");
        }
        s.push('\n');
        for r in &self.records {
            let _ = write!(
                s,
                "{},{},{},{},{},{}",
                r.cycle,
                r.time_s,
                r.instrument.name(),
                r.pos_mm[0],
                r.pos_mm[1],
                r.pos_mm[2]
            );
            for v in r.values {
                let _ = write!(s, ",{}", cell(v));
            }
            let _ = write!(s, ",{}", r.dir);
            if with_rpm {
                let _ = write!(s, ",{}", r.spindle_rpm.map(cell).unwrap_or_default());
            }
            if with_feed {
                match r.axis_feed_mm_per_min {
                    Some(f) => {
                        let _ = write!(s, ",{},{},{}", cell(f[0]), cell(f[1]), cell(f[2]));
                    }
                    None => s.push_str(",,,"),
                }
            }
            for t in &r.temps_degc {
                let _ = write!(s, ",{t}");
            }
            s.push('\n');
        }
        s
    }

    /// Parses CSV text; `source_name` names the file in errors.
    pub fn from_csv(text: &str, source_name: &str) -> Result<Dataset, DatasetError> {
        // A UTF-8 byte-order mark (as spreadsheet programs write) is not part of the header.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        // Comment lines (`#`) before the header; `# machine: …` names the origin.
        let mut origin = None;
        let header = loop {
            let (_, line) = lines.next().ok_or_else(|| DatasetError::Empty {
                source_name: source_name.into(),
                msg: "empty file (no header line)".into(),
            })?;
            match line.trim().strip_prefix('#') {
                Some(comment) => {
                    if let Some(id) = parse_origin(comment) {
                        origin = Some(id);
                    }
                }
                None => break line,
            }
        };
        let cols: Vec<&str> = header.split(',').map(|c| c.trim()).collect();
        for (j, c) in cols.iter().enumerate() {
            if let Some(i) = cols[..j].iter().position(|d| d == c) {
                return Err(DatasetError::DuplicateColumn {
                    source_name: source_name.into(),
                    column: c.to_string(),
                    first: i + 1,
                    second: j + 1,
                });
            }
        }
        let mut idx = [0usize; 12];
        for (k, name) in FIXED.iter().enumerate() {
            idx[k] =
                cols.iter()
                    .position(|c| c == name)
                    .ok_or_else(|| DatasetError::MissingColumn {
                        source_name: source_name.into(),
                        column: name.to_string(),
                    })?;
        }
        let dir_col = cols.iter().position(|c| *c == DIR_COLUMN);
        let rpm_col = cols.iter().position(|c| *c == SPINDLE_RPM_COLUMN);
        let feed_cols = AXIS_FEED_COLUMNS.map(|n| cols.iter().position(|c| *c == n));
        let feed_cols = match feed_cols {
            [None, None, None] => None,
            [Some(x), Some(y), Some(z)] => Some([x, y, z]),
            _ => {
                let missing = AXIS_FEED_COLUMNS
                    .iter()
                    .zip(feed_cols)
                    .find(|(_, c)| c.is_none())
                    .map(|(n, _)| *n)
                    .unwrap_or_default();
                return Err(DatasetError::MissingColumn {
                    source_name: source_name.into(),
                    column: format!("{missing} (the axis-feed columns go together)"),
                });
            }
        };
        let sensor_cols: Vec<(usize, String)> = cols
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.strip_suffix("_degc").map(|n| (i, n.to_string())))
            .collect();
        if sensor_cols.is_empty() {
            return Err(DatasetError::MissingColumn {
                source_name: source_name.into(),
                column: "<sensor>_degc (no temperature columns)".into(),
            });
        }
        let mut records: Vec<Record> = Vec::new();
        // The last time of each cycle and its line: rows of a cycle must be in time order.
        let mut last_time: std::collections::HashMap<String, (f64, usize)> =
            std::collections::HashMap::new();
        for (ln, line) in lines {
            let line_no = ln + 1;
            let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
            let bad = |col: &str, msg: String| DatasetError::BadCell {
                source_name: source_name.into(),
                line: line_no,
                column: col.into(),
                msg,
            };
            if cells.len() != cols.len() {
                return Err(bad(
                    "*",
                    format!("{} cells, the header has {}", cells.len(), cols.len()),
                ));
            }
            let num = |k: usize, required: bool| -> Result<f64, DatasetError> {
                let c = cells[idx[k]];
                if c.is_empty() && !required {
                    return Ok(f64::NAN);
                }
                let v: f64 = c
                    .parse()
                    .map_err(|_| bad(FIXED[k], format!("not a number: \"{c}\"")))?;
                if !v.is_finite() {
                    return Err(bad(FIXED[k], format!("not a finite number: \"{c}\"")));
                }
                // Positions and measurements (FIXED[3..]); the time (k = 1) may be any finite value.
                if k >= 3 && v.abs() > PLAUSIBLE_MAX {
                    return Err(bad(
                        FIXED[k],
                        format!("implausible value {v:e}: beyond ±1e6 (a corrupt cell or a unit mistake?)"),
                    ));
                }
                Ok(v)
            };
            let instrument = Instrument::from_name(cells[idx[2]]).ok_or_else(|| {
                bad(
                    "instrument",
                    format!("unknown instrument \"{}\"", cells[idx[2]]),
                )
            })?;
            let mut values = [f64::NAN; 6];
            for (k, v) in values.iter_mut().enumerate() {
                *v = num(6 + k, false)?;
            }
            let mut temps = Vec::with_capacity(sensor_cols.len());
            for (i, name) in &sensor_cols {
                let c = cells[*i];
                let v: f64 = c
                    .parse()
                    .ok()
                    .filter(|v: &f64| v.is_finite())
                    .ok_or_else(|| {
                        bad(
                            &format!("{name}_degc"),
                            format!("not a finite temperature: \"{c}\""),
                        )
                    })?;
                if v < ABSOLUTE_ZERO_DEGC {
                    return Err(bad(
                        &format!("{name}_degc"),
                        format!("temperature {c} °C is below absolute zero"),
                    ));
                }
                temps.push(v);
            }
            let dir = match dir_col.map(|i| cells[i]) {
                None | Some("") | Some("1") | Some("+1") => 1,
                Some("-1") => -1,
                Some(c) => {
                    return Err(bad(
                        DIR_COLUMN,
                        format!("approach direction must be 1 or -1, got \"{c}\""),
                    ))
                }
            };
            let spindle_rpm = match rpm_col.map(|i| cells[i]) {
                None | Some("") => None,
                Some(c) => {
                    let v: f64 = c
                        .parse()
                        .map_err(|_| bad(SPINDLE_RPM_COLUMN, format!("not a number: \"{c}\"")))?;
                    if !(v.is_finite() && (0.0..=PLAUSIBLE_MAX).contains(&v)) {
                        return Err(bad(
                            SPINDLE_RPM_COLUMN,
                            format!("spindle speed must lie in [0, 1e6] rpm, got \"{c}\""),
                        ));
                    }
                    Some(v)
                }
            };
            let axis_feed_mm_per_min = match feed_cols {
                None => None,
                Some(c) => {
                    let cells = c.map(|i| cells[i]);
                    if cells.iter().all(|c| c.is_empty()) {
                        None
                    } else {
                        let mut f = [0.0_f64; 3];
                        for (k, cell) in cells.into_iter().enumerate() {
                            let col = AXIS_FEED_COLUMNS[k];
                            let v: f64 = cell
                                .parse()
                                .map_err(|_| bad(col, format!("not a number: \"{cell}\"")))?;
                            f[k] = v;
                            if !(v.is_finite() && (0.0..=PLAUSIBLE_MAX).contains(&v)) {
                                return Err(bad(
                                    col,
                                    format!(
                                        "axis feed must lie in [0, 1e6] mm/min, got \"{cell}\""
                                    ),
                                ));
                            }
                        }
                        Some(f)
                    }
                }
            };
            let time_s = num(1, true)?;
            if time_s < 0.0 {
                return Err(bad(
                    "time_s",
                    format!("negative time {time_s} s (times count from the start of the test)"),
                ));
            }
            let cycle = cells[idx[0]].to_string();
            if let Some(&(before_s, before_line)) = last_time.get(&cycle) {
                if time_s < before_s {
                    return Err(bad(
                        "time_s",
                        format!(
                            "time {time_s} s is before {before_s} s of line {before_line} of \
                             cycle \"{cycle}\"; the rows of a cycle must be in time order"
                        ),
                    ));
                }
            }
            last_time.insert(cycle.clone(), (time_s, line_no));
            records.push(Record {
                cycle,
                time_s,
                instrument,
                pos_mm: [num(3, true)?, num(4, true)?, num(5, true)?],
                values,
                temps_degc: temps,
                dir,
                spindle_rpm,
                axis_feed_mm_per_min,
            });
        }
        if records.is_empty() {
            return Err(DatasetError::Empty {
                source_name: source_name.into(),
                msg: "no records after the header".into(),
            });
        }
        Ok(Dataset {
            sensor_names: sensor_cols.into_iter().map(|(_, n)| n).collect(),
            records,
            origin,
        })
    }
}

/// The comment line naming a dataset's machine (without its `#`).
fn origin_line(id: &MachineIdentity) -> String {
    let realisation = id
        .realisation
        .map(|r| r.to_string())
        .unwrap_or_else(|| "unknown".into());
    format!(
        " machine: {}; realisation: {realisation}; fingerprint: {}",
        id.name, id.fingerprint
    )
}

/// Reads [`origin_line`]'s text back (None for any other comment).
fn parse_origin(comment: &str) -> Option<MachineIdentity> {
    let rest = comment.trim().strip_prefix("machine:")?;
    let mut parts = rest.split(';').map(str::trim);
    let name = parts.next()?.to_string();
    let realisation = parts.next()?.strip_prefix("realisation:")?.trim();
    let fingerprint = parts
        .next()?
        .strip_prefix("fingerprint:")?
        .trim()
        .to_string();
    Some(MachineIdentity {
        name,
        realisation: realisation.parse().ok(),
        fingerprint,
    })
}

#[cfg(test)]
mod tests;
