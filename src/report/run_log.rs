//! The log of a measured run, kept as the run produces it: each point's row goes to the
//! terminal table's writer and to `samples.csv`'s writer at once, and only running sums are
//! held (the error statistics, the first and last point), so the log's memory does not grow
//! with the number of points. The figures are those of [`super::error_stats`] over all the
//! points, to the last bit (the same sums in the same order).
//!
//! Units are in every column name: s, mm, µm, °C.

use std::io::Write;

use vmc_machine::sensors::SensorReadings;
use vmc_machine::sim::{Observer, PointRecord};

use super::{
    norm, write_compensated_cells, write_compensated_header, CompensatedCsvCells, RunSummary,
    StatsAcc, COMPENSATED_CSV_HEADER,
};

/// A run's points as they come: statistics kept, rows written (see the module doc).
pub struct RunLog<'w> {
    /// Sensor names (from the first point).
    pub sensor_names: Vec<String>,
    /// Sensor readings at the first point, °C.
    pub first_degc: Option<Vec<f64>>,
    time_span_s: [f64; 2],
    points: usize,
    before: StatsAcc,
    thermal: StatsAcc,
    after: StatsAcc,
    compensated: bool,
    table: &'w mut dyn Write,
    csv: Option<&'w mut dyn Write>,
    error: Option<std::io::Error>,
}

impl<'w> RunLog<'w> {
    /// A log writing the terminal table to `table` and `samples.csv` to `csv` (if any); with
    /// the compensated columns if `compensated` (a model in the loop).
    pub fn new(
        compensated: bool,
        table: &'w mut dyn Write,
        csv: Option<&'w mut dyn Write>,
    ) -> Self {
        Self {
            sensor_names: Vec::new(),
            first_degc: None,
            time_span_s: [0.0; 2],
            points: 0,
            before: StatsAcc::default(),
            thermal: StatsAcc::default(),
            after: StatsAcc::default(),
            compensated,
            table,
            csv,
            error: None,
        }
    }

    /// The first failure of a writer, if any (the rows after it were not written).
    ///
    /// # Errors
    /// That failure.
    pub fn check(&mut self) -> std::io::Result<()> {
        self.error.take().map_or(Ok(()), Err)
    }

    /// Summarises the run. None if it has no points.
    pub fn summary(
        &self,
        program: &str,
        machine: &str,
        seed: u64,
        warmup: &[String],
    ) -> Option<RunSummary> {
        let b = self.before.stats()?;
        let a = self.after.stats();
        let first = self.first_degc.as_deref().unwrap_or_default();
        Some(RunSummary {
            program: program.to_string(),
            machine: machine.to_string(),
            seed,
            warmup: warmup.to_vec(),
            points: self.points,
            time_span_s: self.time_span_s,
            mean_sensor_temp_degc: first.iter().sum::<f64>() / first.len().max(1) as f64,
            before: b,
            thermal_part: self.thermal.stats(),
            after: a,
            reduction: a.map(|a| 1.0 - a.rms_um[3] / b.rms_um[3]),
            extrapolation: None,
        })
    }

    fn write_headers(&mut self) -> std::io::Result<()> {
        write_table_header(self.table, self.compensated)?;
        if let Some(csv) = self.csv.as_mut() {
            write_csv_header(*csv, &self.sensor_names, self.compensated)?;
        }
        Ok(())
    }

    fn write_rows(&mut self, p: &PointRecord, temps_degc: &[f64]) -> std::io::Result<()> {
        write_table_row(self.table, p)?;
        if let Some(csv) = self.csv.as_mut() {
            write_csv_row(*csv, p, temps_degc, self.compensated)?;
        }
        Ok(())
    }
}

impl Observer for RunLog<'_> {
    fn on_point(&mut self, point: &PointRecord, readings: &SensorReadings) {
        if self.first_degc.is_none() {
            self.sensor_names = readings.names.iter().map(|s| s.to_string()).collect();
            self.first_degc = Some(readings.values_degc.to_vec());
            self.time_span_s[0] = point.time_s;
            if self.error.is_none() {
                self.error = self.write_headers().err();
            }
        }
        self.time_span_s[1] = point.time_s;
        self.points += 1;
        self.before.add(point.error_before_um);
        if let Some(t) = point.thermal_part_um {
            self.thermal.add(t);
        }
        if let Some(a) = point.error_after_um {
            self.after.add(a);
        }
        if self.error.is_none() {
            self.error = self.write_rows(point, &readings.values_degc).err();
        }
    }
}

/// One column of a point's row: in the terminal table, in `samples.csv` or in both. One list
/// ([`COLUMNS`]) drives the headers and the rows of both, so the two cannot drift apart.
struct Column {
    /// Terminal table: header, width and decimals; `None`: not in the table.
    table: Option<(&'static str, usize, usize)>,
    /// `samples.csv`: header and decimals; `None`: not in the file.
    csv: Option<(&'static str, usize)>,
    /// The value at a point (point and line numbers are exact in an f64 and print as integers
    /// with 0 decimals).
    value: fn(&PointRecord) -> f64,
}

/// The thermal part of a point's error, µm (NaN where it was not computed).
fn thermal_um(p: &PointRecord) -> [f64; 3] {
    p.thermal_part_um.unwrap_or([f64::NAN; 3])
}

/// The columns before the compensated ones: the table's columns and the file's are each in
/// this order.
const COLUMNS: [Column; 14] = [
    Column {
        table: Some(("pt", 4, 0)),
        csv: None,
        value: |p| p.index as f64,
    },
    Column {
        table: Some(("time_s", 9, 1)),
        csv: Some(("time_s", 3)),
        value: |p| p.time_s,
    },
    Column {
        table: Some(("line", 5, 0)),
        csv: Some(("line", 0)),
        value: |p| p.line as f64,
    },
    Column {
        table: Some(("x_mm", 9, 3)),
        csv: Some(("x_mm", 4)),
        value: |p| p.commanded_mm[0],
    },
    Column {
        table: Some(("y_mm", 9, 3)),
        csv: Some(("y_mm", 4)),
        value: |p| p.commanded_mm[1],
    },
    Column {
        table: Some(("z_mm", 9, 3)),
        csv: Some(("z_mm", 4)),
        value: |p| p.commanded_mm[2],
    },
    Column {
        table: Some(("ex_um", 8, 2)),
        csv: Some(("ex_um", 4)),
        value: |p| p.error_before_um[0],
    },
    Column {
        table: Some(("ey_um", 8, 2)),
        csv: Some(("ey_um", 4)),
        value: |p| p.error_before_um[1],
    },
    Column {
        table: Some(("ez_um", 8, 2)),
        csv: Some(("ez_um", 4)),
        value: |p| p.error_before_um[2],
    },
    Column {
        table: Some(("|e|_um", 8, 2)),
        csv: Some(("norm_um", 4)),
        value: |p| norm(p.error_before_um),
    },
    Column {
        table: None,
        csv: Some(("thermal_ex_um", 4)),
        value: |p| thermal_um(p)[0],
    },
    Column {
        table: None,
        csv: Some(("thermal_ey_um", 4)),
        value: |p| thermal_um(p)[1],
    },
    Column {
        table: None,
        csv: Some(("thermal_ez_um", 4)),
        value: |p| thermal_um(p)[2],
    },
    Column {
        table: Some(("therm_um", 8, 2)),
        csv: None,
        value: |p| norm(thermal_um(p)),
    },
];

/// The terminal table's header line (with the compensated columns if `compensated`).
///
/// # Errors
/// The writer's.
fn write_table_header(out: &mut dyn Write, compensated: bool) -> std::io::Result<()> {
    let cells = COLUMNS.iter().filter_map(|c| c.table);
    for (k, (header, width, _)) in cells.enumerate() {
        let sep = if k == 0 { "" } else { " " };
        write!(out, "{sep}{header:>width$}")?;
    }
    if compensated {
        write_compensated_header(out)?;
    }
    writeln!(out)
}

/// One point's row of the terminal table.
///
/// # Errors
/// The writer's.
fn write_table_row(out: &mut dyn Write, p: &PointRecord) -> std::io::Result<()> {
    let cells = COLUMNS.iter().filter_map(|c| Some((c.table?, c.value)));
    for (k, ((_, width, decimals), value)) in cells.enumerate() {
        let sep = if k == 0 { "" } else { " " };
        write!(out, "{sep}{:>width$.decimals$}", value(p))?;
    }
    if let Some(a) = p.error_after_um {
        write_compensated_cells(out, a)?;
    }
    writeln!(out)
}

/// `samples.csv`'s header: units in every column name, one column per sensor.
///
/// # Errors
/// The writer's.
fn write_csv_header(
    out: &mut dyn Write,
    sensor_names: &[String],
    compensated: bool,
) -> std::io::Result<()> {
    let cells = COLUMNS.iter().filter_map(|c| c.csv);
    for (k, (header, _)) in cells.enumerate() {
        let sep = if k == 0 { "" } else { "," };
        write!(out, "{sep}{header}")?;
    }
    if compensated {
        write!(out, "{COMPENSATED_CSV_HEADER}")?;
    }
    for n in sensor_names {
        write!(out, ",{n}_degc")?;
    }
    writeln!(out)
}

/// One point's row of `samples.csv`.
///
/// # Errors
/// The writer's.
fn write_csv_row(
    out: &mut dyn Write,
    p: &PointRecord,
    temps_degc: &[f64],
    compensated: bool,
) -> std::io::Result<()> {
    let cells = COLUMNS.iter().filter_map(|c| Some((c.csv?, c.value)));
    for (k, ((_, decimals), value)) in cells.enumerate() {
        let sep = if k == 0 { "" } else { "," };
        write!(out, "{sep}{:.decimals$}", value(p))?;
    }
    if compensated {
        let cells = CompensatedCsvCells {
            q_mm: p.compensated_command_mm.unwrap_or(p.commanded_mm),
            err_um: p.error_after_um.unwrap_or([f64::NAN; 3]),
        };
        write!(out, "{cells}")?;
    }
    for v in temps_degc {
        write!(out, ",{v:.4}")?;
    }
    writeln!(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_header_has_every_column_in_its_width() {
        let mut out = Vec::new();
        write_table_header(&mut out, true).unwrap();
        let expected = format!(
            "{:>4} {:>9} {:>5} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} {:>8}\n",
            "pt", "time_s", "line", "x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um", "|e|_um",
            "therm_um", "ex'_um", "ey'_um", "ez'_um", "|e'|_um"
        );
        assert_eq!(String::from_utf8(out).unwrap(), expected);
    }

    #[test]
    fn the_csv_header_names_every_column_with_its_unit() {
        let mut out = Vec::new();
        write_csv_header(&mut out, &["ZH".to_string()], true).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "time_s,line,x_mm,y_mm,z_mm,ex_um,ey_um,ez_um,norm_um,thermal_ex_um,thermal_ey_um,\
             thermal_ez_um,qx_mm,qy_mm,qz_mm,ex_comp_um,ey_comp_um,ez_comp_um,norm_comp_um,\
             ZH_degc\n"
        );
    }
}
