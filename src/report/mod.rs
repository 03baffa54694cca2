//! Run reports: summary statistics, the terminal table, `samples.csv` and `summary.json`.
//!
//! Units are in every column and field name. Files are written through [`crate::files`].

pub mod fiveaxis;

use std::io::Write;

use serde::Serialize;

use vmc_machine::sensors::SensorReadings;
use vmc_machine::sim::{Observer, PointRecord};

/// Statistics of an error series, µm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ErrorStats {
    /// max |Ex|, max |Ey|, max |Ez|, max |E|, µm.
    pub max_abs_um: [f64; 4],
    /// RMS of Ex, Ey, Ez, |E|, µm.
    pub rms_um: [f64; 4],
}

/// Stats of `errors` (µm vectors). None if empty.
pub fn error_stats(errors: &[[f64; 3]]) -> Option<ErrorStats> {
    if errors.is_empty() {
        return None;
    }
    let n = errors.len() as f64;
    let mut max = [0.0f64; 4];
    let mut sq = [0.0f64; 4];
    for e in errors {
        let norm = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        for (k, v) in [e[0], e[1], e[2], norm].into_iter().enumerate() {
            max[k] = max[k].max(v.abs());
            sq[k] += v * v;
        }
    }
    Some(ErrorStats {
        max_abs_um: max,
        rms_um: sq.map(|s| (s / n).sqrt()),
    })
}

/// Points collected during a run, with the sensor readings held at each.
#[derive(Debug, Default, Clone)]
pub struct RunLog {
    /// Sensor names (from the first point).
    pub sensor_names: Vec<String>,
    /// The points.
    pub points: Vec<PointRecord>,
    /// Sensor readings at each point, °C.
    pub sensor_degc: Vec<Vec<f64>>,
}

impl Observer for RunLog {
    fn on_point(&mut self, point: &PointRecord, readings: &SensorReadings) {
        if self.sensor_names.is_empty() {
            self.sensor_names = readings.names.iter().map(|s| s.to_string()).collect();
        }
        self.points.push(point.clone());
        self.sensor_degc.push(readings.values_degc.to_vec());
    }
}

/// The summary of one run, as written to `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Program file.
    pub program: String,
    /// Machine name.
    pub machine: String,
    /// Seed of the machine realisation.
    pub seed: u64,
    /// Warm-up programs run first.
    pub warmup: Vec<String>,
    /// Number of measurement points.
    pub points: usize,
    /// Twin time at the first and last point, s.
    pub time_span_s: [f64; 2],
    /// Mean sensor reading at the first point, °C.
    pub mean_sensor_temp_degc: f64,
    /// Uncompensated error statistics.
    pub before: ErrorStats,
    /// Of which the thermal part (error minus the cold-geometry error at the same points), when
    /// it was computed.
    pub thermal_part: Option<ErrorStats>,
    /// Compensated error statistics, if compensation ran.
    pub after: Option<ErrorStats>,
    /// 1 − RMS(|E| after)/RMS(|E| before), if compensation ran.
    pub reduction: Option<f64>,
    /// Readings and commands outside the model's trained ranges, if compensation ran.
    pub extrapolation: Option<crate::predict::provenance::Extrapolation>,
}

impl RunLog {
    /// Summarises the run. None if it has no points.
    pub fn summary(
        &self,
        program: &str,
        machine: &str,
        seed: u64,
        warmup: &[String],
    ) -> Option<RunSummary> {
        let before: Vec<[f64; 3]> = self.points.iter().map(|p| p.error_before_um).collect();
        let thermal: Vec<[f64; 3]> = self
            .points
            .iter()
            .filter_map(|p| p.thermal_part_um)
            .collect();
        let after: Vec<[f64; 3]> = self
            .points
            .iter()
            .filter_map(|p| p.error_after_um)
            .collect();
        let b = error_stats(&before)?;
        let a = error_stats(&after);
        let first = &self.sensor_degc[0];
        Some(RunSummary {
            program: program.to_string(),
            machine: machine.to_string(),
            seed,
            warmup: warmup.to_vec(),
            points: self.points.len(),
            time_span_s: [
                self.points[0].time_s,
                self.points[self.points.len() - 1].time_s,
            ],
            mean_sensor_temp_degc: first.iter().sum::<f64>() / first.len().max(1) as f64,
            before: b,
            thermal_part: error_stats(&thermal),
            after: a,
            reduction: a.map(|a| 1.0 - a.rms_um[3] / b.rms_um[3]),
            extrapolation: None,
        })
    }

    /// Writes the terminal table: one row per point.
    pub fn write_table(&self, out: &mut dyn Write) -> std::io::Result<()> {
        let comp = self.points.iter().any(|p| p.error_after_um.is_some());
        write!(
            out,
            "{:>4} {:>9} {:>5} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8}",
            "pt",
            "time_s",
            "line",
            "x_mm",
            "y_mm",
            "z_mm",
            "ex_um",
            "ey_um",
            "ez_um",
            "|e|_um",
            "therm_um"
        )?;
        if comp {
            write_compensated_header(out)?;
        }
        writeln!(out)?;
        for p in &self.points {
            let e = p.error_before_um;
            let t = p.thermal_part_um.unwrap_or([f64::NAN; 3]);
            write!(
                out,
                "{:>4} {:>9.1} {:>5} {:>9.3} {:>9.3} {:>9.3} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2}",
                p.index,
                p.time_s,
                p.line,
                p.commanded_mm[0],
                p.commanded_mm[1],
                p.commanded_mm[2],
                e[0],
                e[1],
                e[2],
                norm(e),
                norm(t),
            )?;
            if let Some(a) = p.error_after_um {
                write_compensated_cells(out, a)?;
            }
            writeln!(out)?;
        }
        Ok(())
    }

    /// `samples.csv` content: one row per point, units in every column name.
    pub fn samples_csv(&self) -> String {
        let comp = self.points.iter().any(|p| p.error_after_um.is_some());
        let mut s = String::from(
            "time_s,line,x_mm,y_mm,z_mm,ex_um,ey_um,ez_um,norm_um,thermal_ex_um,thermal_ey_um,thermal_ez_um",
        );
        if comp {
            s.push_str(",qx_mm,qy_mm,qz_mm,ex_comp_um,ey_comp_um,ez_comp_um,norm_comp_um");
        }
        for n in &self.sensor_names {
            s.push_str(&format!(",{n}_degc"));
        }
        s.push('\n');
        for (p, temps) in self.points.iter().zip(&self.sensor_degc) {
            let e = p.error_before_um;
            let t = p.thermal_part_um.unwrap_or([f64::NAN; 3]);
            s.push_str(&format!(
                "{:.3},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}",
                p.time_s,
                p.line,
                p.commanded_mm[0],
                p.commanded_mm[1],
                p.commanded_mm[2],
                e[0],
                e[1],
                e[2],
                norm(e),
                t[0],
                t[1],
                t[2]
            ));
            if comp {
                let q = p.compensated_command_mm.unwrap_or(p.commanded_mm);
                let a = p.error_after_um.unwrap_or([f64::NAN; 3]);
                s.push_str(&format!(
                    ",{:.6},{:.6},{:.6},{:.4},{:.4},{:.4},{:.4}",
                    q[0],
                    q[1],
                    q[2],
                    a[0],
                    a[1],
                    a[2],
                    norm(a)
                ));
            }
            for v in temps {
                s.push_str(&format!(",{v:.4}"));
            }
            s.push('\n');
        }
        s
    }
}

/// |v| of a µm vector.
pub fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Writes one row of error statistics (`name`, max and RMS per component and of |E|).
pub fn write_stats_row(out: &mut dyn Write, name: &str, st: &ErrorStats) -> std::io::Result<()> {
    writeln!(
        out,
        "  {name:<22} max |Ex| {:>6.2}  |Ey| {:>6.2}  |Ez| {:>6.2}  |E| {:>6.2} µm   RMS Ex {:>6.2}  Ey {:>6.2}  Ez {:>6.2}  |E| {:>6.2} µm",
        st.max_abs_um[0], st.max_abs_um[1], st.max_abs_um[2], st.max_abs_um[3],
        st.rms_um[0], st.rms_um[1], st.rms_um[2], st.rms_um[3]
    )
}

/// Writes the summary lines for a terminal.
pub fn write_summary(s: &RunSummary, out: &mut dyn Write) -> std::io::Result<()> {
    let row = write_stats_row;
    writeln!(
        out,
        "summary ({} points, t = {:.0} … {:.0} s, mean sensor temperature {:.2} °C):",
        s.points, s.time_span_s[0], s.time_span_s[1], s.mean_sensor_temp_degc
    )?;
    row(out, "error", &s.before)?;
    if let Some(t) = &s.thermal_part {
        row(out, "  of which thermal", t)?;
    }
    if let Some(a) = &s.after {
        row(out, "compensated error", a)?;
    }
    if let Some(r) = s.reduction {
        writeln!(out, "  reduction of RMS |E|: {:.1} %", r * 100.0)?;
    }
    if s.after.is_some() && s.extrapolation.is_none() {
        writeln!(
            out,
            "  model inputs: not checked (the model file records no trained ranges)"
        )?;
    }
    if let Some(e) = &s.extrapolation {
        match e.first_time_s {
            None => writeln!(
                out,
                "  model inputs: every reading and command inside the trained ranges"
            )?,
            Some(t) => {
                writeln!(
                    out,
                    "  WARNING: the model extrapolated: {} of {} samples outside the trained ranges, the first at t = {t:.0} s:",
                    e.count, e.samples
                )?;
                for o in &e.inputs {
                    writeln!(
                        out,
                        "    {:<12} trained {:>9.2} … {:>9.2}, first {:>9.2} at t = {:.0} s, {} samples outside",
                        o.input, o.range[0], o.range[1], o.first_value, o.first_time_s, o.count
                    )?;
                }
            }
        }
    }
    Ok(())
}

/// The compensated columns' header of a run's terminal table (`ex'_um` … `|e'|_um`).
///
/// # Errors
/// The writer's.
pub fn write_compensated_header(out: &mut dyn Write) -> std::io::Result<()> {
    write!(
        out,
        " | {:>8} {:>8} {:>8} {:>8}",
        "ex'_um", "ey'_um", "ez'_um", "|e'|_um"
    )
}

/// The compensated error's cells of one row of a run's terminal table, in µm.
///
/// # Errors
/// The writer's.
pub fn write_compensated_cells(out: &mut dyn Write, a: [f64; 3]) -> std::io::Result<()> {
    write!(
        out,
        " | {:>8.2} {:>8.2} {:>8.2} {:>8.2}",
        a[0],
        a[1],
        a[2],
        norm(a)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_a_hand_computed_series() {
        // |E| of (3,4,0) is 5, of (0,0,-12) is 12.
        let s = error_stats(&[[3.0, 4.0, 0.0], [0.0, 0.0, -12.0]]).unwrap();
        assert_eq!(s.max_abs_um, [3.0, 4.0, 12.0, 12.0]);
        let rms_norm = ((25.0 + 144.0) / 2.0f64).sqrt();
        assert!((s.rms_um[3] - rms_norm).abs() < 1e-12);
        assert!((s.rms_um[0] - (9.0f64 / 2.0).sqrt()).abs() < 1e-12);
        assert!(error_stats(&[]).is_none());
    }
}
