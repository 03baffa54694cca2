//! Run reports: summary statistics, the terminal table, `samples.csv` and `summary.json`.
//!
//! Units are in every column and field name. Files are written through [`crate::files`].

pub mod fiveaxis;
mod run_log;

pub use run_log::RunLog;

use std::io::Write;

use serde::Serialize;

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
    let mut acc = StatsAcc::default();
    for e in errors {
        acc.add(*e);
    }
    acc.stats()
}

/// [`ErrorStats`] gathered one error at a time (the same sums in the same order as
/// [`error_stats`], so the same figures to the last bit).
#[derive(Debug, Default, Clone, Copy)]
pub struct StatsAcc {
    n: usize,
    max: [f64; 4],
    sq: [f64; 4],
}

impl StatsAcc {
    /// Adds one error vector, µm.
    pub fn add(&mut self, e: [f64; 3]) {
        let norm = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        for (k, v) in [e[0], e[1], e[2], norm].into_iter().enumerate() {
            self.max[k] = self.max[k].max(v.abs());
            self.sq[k] += v * v;
        }
        self.n += 1;
    }

    /// The statistics so far; None before the first error.
    pub fn stats(&self) -> Option<ErrorStats> {
        if self.n == 0 {
            return None;
        }
        let n = self.n as f64;
        Some(ErrorStats {
            max_abs_um: self.max,
            rms_um: self.sq.map(|s| (s / n).sqrt()),
        })
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

/// `samples.csv`'s compensated columns' header, after the uncompensated error's columns.
pub const COMPENSATED_CSV_HEADER: &str =
    ",qx_mm,qy_mm,qz_mm,ex_comp_um,ey_comp_um,ez_comp_um,norm_comp_um";

/// The compensated cells of one row of `samples.csv` (see [`COMPENSATED_CSV_HEADER`]), each
/// with its leading comma: one formatter for the `io::Write` rows of a three-axis run and the
/// `String` of a five-axis run.
pub struct CompensatedCsvCells {
    /// The compensated command of the linear axes, mm.
    pub q_mm: [f64; 3],
    /// The error after compensation, µm (NaN where there is none).
    pub err_um: [f64; 3],
}

impl std::fmt::Display for CompensatedCsvCells {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (q, a) = (self.q_mm, self.err_um);
        write!(
            f,
            ",{:.6},{:.6},{:.6},{:.4},{:.4},{:.4},{:.4}",
            q[0],
            q[1],
            q[2],
            a[0],
            a[1],
            a[2],
            norm(a)
        )
    }
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
