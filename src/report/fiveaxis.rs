//! The report of a five-axis run: `summary.json`, `samples.csv` and the terminal table, from
//! the points `vmc_machine::fiveaxis::run` evaluates.

use serde::Serialize;

use vmc_identify::chain::Geometry;
use vmc_machine::fiveaxis::run::FivePoint;

use super::{error_stats, ErrorStats};

/// What `summary.json` holds for a five-axis run.
#[derive(Debug, Clone, Serialize)]
pub struct FiveAxisSummary {
    /// Program file.
    pub program: String,
    /// Machine name.
    pub machine: String,
    /// Seed of the machine realisation.
    pub seed: u64,
    /// Number of points.
    pub points: usize,
    /// Program time at the first and last point, s.
    pub time_span_s: [f64; 2],
    /// The thermal state: this machine has no thermal model.
    pub thermal: &'static str,
    /// Uncompensated error statistics (workpiece frame).
    pub before: ErrorStats,
    /// The identified-model file compensating, if any.
    pub identified: Option<String>,
    /// Compensated error statistics, if compensation ran.
    pub after: Option<ErrorStats>,
    /// 1 − RMS(|E| after)/RMS(|E| before), if compensation ran.
    pub reduction: Option<f64>,
    /// Whether the controller corrected the rotary axes too, if compensation ran.
    pub rotary_compensation: Option<bool>,
    /// Tool-axis error (angle between actual and commanded tool axis relative to the
    /// workpiece) without compensation.
    pub axis_before: AxisStats,
    /// Tool-axis error with compensation, if it ran.
    pub axis_after: Option<AxisStats>,
    /// 1 − RMS(tool-axis error after)/RMS(before), if compensation ran.
    pub axis_reduction: Option<f64>,
}

/// Statistics of the tool-axis error, µrad.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct AxisStats {
    /// RMS, µrad.
    pub rms_urad: f64,
    /// Largest, µrad.
    pub max_urad: f64,
}

/// RMS and maximum of `values` (µrad); `None` if empty.
fn axis_stats(values: &[f64]) -> Option<AxisStats> {
    if values.is_empty() {
        return None;
    }
    let sq: f64 = values.iter().map(|v| v * v).sum();
    Some(AxisStats {
        rms_urad: (sq / values.len() as f64).sqrt(),
        max_urad: values.iter().copied().fold(0.0, f64::max),
    })
}

/// The note on the thermal state of every five-axis run.
pub const NO_THERMAL_MODEL: &str =
    "none: this machine has no thermal model; the errors are geometric and constant in time";

/// Summarises the points; `None` without points.
#[must_use]
pub fn summarise(
    points: &[FivePoint],
    program: &str,
    machine: &str,
    seed: u64,
    identified: Option<&str>,
    rotary_comp: bool,
) -> Option<FiveAxisSummary> {
    let before: Vec<[f64; 3]> = points.iter().map(|p| p.error_before_um).collect();
    let after: Vec<[f64; 3]> = points.iter().filter_map(|p| p.error_after_um).collect();
    let b = error_stats(&before)?;
    let a = error_stats(&after);
    let axis_b: Vec<f64> = points.iter().map(|p| p.axis_error_before_urad).collect();
    let axis_a: Vec<f64> = points
        .iter()
        .filter_map(|p| p.axis_error_after_urad)
        .collect();
    let (ab, aa) = (axis_stats(&axis_b)?, axis_stats(&axis_a));
    Some(FiveAxisSummary {
        program: program.to_string(),
        machine: machine.to_string(),
        seed,
        points: points.len(),
        time_span_s: [
            points[0].commanded.time_s,
            points[points.len() - 1].commanded.time_s,
        ],
        thermal: NO_THERMAL_MODEL,
        before: b,
        identified: identified.map(str::to_string),
        after: a,
        reduction: a.map(|a| 1.0 - a.rms_um[3] / b.rms_um[3].max(1e-300)),
        rotary_compensation: a.map(|_| rotary_comp),
        axis_before: ab,
        axis_after: aa,
        axis_reduction: aa.map(|a| 1.0 - a.rms_urad / ab.rms_urad.max(1e-300)),
    })
}

/// The machine's rotary axes as (G-code index, lower-case letter), in A, B, C order.
fn rotary_columns(geom: &Geometry) -> Vec<(usize, char)> {
    let mut cols: Vec<(usize, char)> = geom
        .rotary
        .iter()
        .map(|r| (r.axis.index(), r.axis.letter().to_ascii_lowercase()))
        .collect();
    cols.sort_unstable();
    cols
}

/// `samples.csv`: one row per point, units in every column name (the three-axis columns, the
/// machine's rotary angles, the commanded tip in the workpiece frame; with compensation the
/// commanded linear axes and the error after).
#[must_use]
pub fn samples_csv(geom: &Geometry, points: &[FivePoint]) -> String {
    use std::fmt::Write as _;
    let comp = points.iter().any(|p| p.error_after_um.is_some());
    let rot = rotary_columns(geom);
    let mut s = String::from("time_s,line,x_mm,y_mm,z_mm");
    for (_, l) in &rot {
        let _ = write!(s, ",{l}_deg");
    }
    s.push_str(",tip_x_w_mm,tip_y_w_mm,tip_z_w_mm,ex_um,ey_um,ez_um,norm_um,axis_err_urad");
    if comp {
        s.push_str(super::COMPENSATED_CSV_HEADER);
        for (_, l) in &rot {
            let _ = write!(s, ",{l}_comp_deg");
        }
        s.push_str(",axis_err_comp_urad");
    }
    s.push('\n');
    for p in points {
        let c = &p.commanded;
        let (q, e, t) = (c.q_mm, p.error_before_um, p.tip_w_mm);
        let _ = write!(
            s,
            "{:.4},{},{:.4},{:.4},{:.4}",
            c.time_s, c.line, q[0], q[1], q[2]
        );
        for (i, _) in &rot {
            let _ = write!(s, ",{:.6}", c.abc_deg[*i]);
        }
        let _ = write!(
            s,
            ",{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.3}",
            t[0],
            t[1],
            t[2],
            e[0],
            e[1],
            e[2],
            super::norm(e),
            p.axis_error_before_urad
        );
        if comp {
            let cells = super::CompensatedCsvCells {
                q_mm: p.compensated_q_mm.unwrap_or(q),
                err_um: p.error_after_um.unwrap_or([f64::NAN; 3]),
            };
            let _ = write!(s, "{cells}");
            let abc = p.compensated_abc_deg.unwrap_or(c.abc_deg);
            for (i, _) in &rot {
                let _ = write!(s, ",{:.8}", abc[*i]);
            }
            let _ = write!(s, ",{:.3}", p.axis_error_after_urad.unwrap_or(f64::NAN));
        }
        s.push('\n');
    }
    s
}

/// The terminal table: one row per point.
///
/// # Errors
/// The writer's.
pub fn write_table(
    geom: &Geometry,
    points: &[FivePoint],
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let comp = points.iter().any(|p| p.error_after_um.is_some());
    let rot = rotary_columns(geom);
    write!(
        out,
        "{:>4} {:>9} {:>5} {:>9} {:>9} {:>9}",
        "pt", "time_s", "line", "x_mm", "y_mm", "z_mm"
    )?;
    for (_, l) in &rot {
        write!(out, " {:>8}", format!("{l}_deg"))?;
    }
    write!(
        out,
        " {:>8} {:>8} {:>8} {:>8}",
        "ex_um", "ey_um", "ez_um", "|e|_um"
    )?;
    write!(out, " {:>8}", "ax_urad")?;
    if comp {
        super::write_compensated_header(out)?;
        write!(out, " {:>8}", "ax_comp")?;
    }
    writeln!(out)?;
    for (k, p) in points.iter().enumerate() {
        let (c, e) = (&p.commanded, p.error_before_um);
        write!(
            out,
            "{:>4} {:>9.3} {:>5} {:>9.3} {:>9.3} {:>9.3}",
            k, c.time_s, c.line, c.q_mm[0], c.q_mm[1], c.q_mm[2]
        )?;
        for (i, _) in &rot {
            write!(out, " {:>8.3}", c.abc_deg[*i])?;
        }
        write!(
            out,
            " {:>8.2} {:>8.2} {:>8.2} {:>8.2}",
            e[0],
            e[1],
            e[2],
            super::norm(e)
        )?;
        write!(out, " {:>8.2}", p.axis_error_before_urad)?;
        if let Some(a) = p.error_after_um {
            super::write_compensated_cells(out, a)?;
            write!(out, " {:>8.2}", p.axis_error_after_urad.unwrap_or(f64::NAN))?;
        }
        writeln!(out)?;
    }
    Ok(())
}

/// The summary lines for a terminal (the three-axis run's rows of statistics).
///
/// # Errors
/// The writer's.
pub fn write_summary(s: &FiveAxisSummary, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    writeln!(
        out,
        "summary ({} points, t = {:.1} … {:.1} s; thermal state: {}):",
        s.points, s.time_span_s[0], s.time_span_s[1], s.thermal
    )?;
    super::write_stats_row(out, "error", &s.before)?;
    if let Some(a) = &s.after {
        super::write_stats_row(out, "compensated error", a)?;
    }
    if let Some(r) = s.reduction {
        writeln!(out, "  reduction of RMS |E|: {:.1} %", r * 100.0)?;
    }
    let row = |a: &AxisStats| format!("RMS {:.2} µrad, max {:.2} µrad", a.rms_urad, a.max_urad);
    writeln!(out, "  tool-axis error: {}", row(&s.axis_before))?;
    if let (Some(a), Some(r), Some(rot)) = (&s.axis_after, s.axis_reduction, s.rotary_compensation)
    {
        writeln!(
            out,
            "  compensated tool-axis error ({}): {}; reduction of RMS {:.1} %",
            if rot {
                "rotary axes corrected"
            } else {
                "linear axes only"
            },
            row(a),
            r * 100.0
        )?;
    }
    Ok(())
}
