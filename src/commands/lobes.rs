//! `vmc-twin lobes`: the stability lobe diagram of a tool — critical axial depth against spindle
//! speed for a radial immersion and milling direction, by semi-discretisation, the zero-order
//! analytic solution or time-domain simulation.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use crate::dynamics::{lobes as lobes_of, LobePoint, Method, Milling};
use crate::files;
use crate::milling::{kind_name, lobes_csv, ToolDynamics};

/// What to compute, validated.
pub struct LobesConfig {
    /// The tool and its tool-tip modes.
    pub tool: ToolDynamics,
    /// Where the tool came from (for the report).
    pub tool_source: String,
    /// Stability method.
    pub method: Method,
    /// Radial immersion a_e/D, in (0, 1].
    pub immersion: f64,
    /// Up or down milling.
    pub milling: Milling,
    /// Spindle speeds, rpm (> 0).
    pub speeds_rpm: Vec<f64>,
    /// CSV output.
    pub out: Option<PathBuf>,
    /// Rerun recording of the lobe diagram.
    pub rrd: Option<PathBuf>,
    /// Overwrite an existing output file.
    pub force: bool,
}

/// Most rows printed; longer tables are thinned on screen (every row is in `--out`).
const MAX_PRINTED_ROWS: usize = 41;

/// Computes the lobes, prints the minimum and the table, writes the CSV and the recording.
///
/// # Errors
/// An output that may not be written, values the dynamics refuses.
pub fn lobes(cfg: &LobesConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(path) = &cfg.out {
        files::check_writable(path, cfg.force)?;
    }
    if let Some(path) = &cfg.rrd {
        crate::record::check_rrd_path(path, cfg.force)?;
    }
    // The report is printed and, with --rrd, also stored in the recording.
    let mut text = Vec::new();
    let points = compute_and_report(cfg, &mut text)?;
    out.write_all(&text)?;
    if let Some(path) = &cfg.out {
        files::write_atomic(path, lobes_csv(&points).as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = &cfg.rrd {
        let t = &cfg.tool;
        let title = format!(
            "vmc-twin lobes {} {} {} {} {:?}",
            t.name,
            method_name(cfg.method),
            cfg.immersion,
            super::cut::milling_name(cfg.milling),
            cfg.speeds_rpm
        );
        let md = format!(
            "# vmc-twin lobes\n\nCritical depth against spindle speed: the boundary as a grey \
             line, Hopf lobes blue, flip lobes orange (speeds rounded to whole rpm on the \
             `spindle_rpm` timeline).\n\n```text\n{}```\n",
            String::from_utf8_lossy(&text)
        );
        let bytes = crate::record::dynamics::record_lobes(path, cfg.force, &title, &points, &md)?;
        super::wrote_recording(out, path, bytes, "")?;
    }
    Ok(())
}

/// Computes the lobes and writes the report (minimum and table).
fn compute_and_report(cfg: &LobesConfig, out: &mut dyn Write) -> Result<Vec<LobePoint>> {
    let t = &cfg.tool;
    let points = lobes_of(
        cfg.method,
        &t.tool,
        &t.modes,
        cfg.immersion,
        cfg.milling,
        &cfg.speeds_rpm,
    )?;
    writeln!(
        out,
        "vmc-twin lobes: {} ({}), {} teeth, {} method, immersion a_e/D {}, {} milling, {} speeds",
        t.name,
        cfg.tool_source,
        t.tool.teeth,
        method_name(cfg.method),
        cfg.immersion,
        super::cut::milling_name(cfg.milling),
        cfg.speeds_rpm.len()
    )?;
    match points
        .iter()
        .min_by(|a, b| a.critical_depth_mm.total_cmp(&b.critical_depth_mm))
    {
        Some(p) => writeln!(
            out,
            "minimum critical depth {:.3} mm at {:.0} rpm ({} lobe, chatter at {:.1} Hz)",
            p.critical_depth_mm,
            p.spindle_rpm,
            kind_name(p.kind),
            p.chatter_frequency_hz
        )?,
        None => writeln!(out, "no stability boundary found at these speeds")?,
    }
    write_table(&points, out)?;
    if points.len() < cfg.speeds_rpm.len() {
        writeln!(
            out,
            "{} speed(s) without a boundary in the searched depth range are left out",
            cfg.speeds_rpm.len() - points.len()
        )?;
    }
    Ok(points)
}

/// The lobes as a table, thinned to about [`MAX_PRINTED_ROWS`] rows.
fn write_table(points: &[LobePoint], out: &mut dyn Write) -> std::io::Result<()> {
    let every = points.len().div_ceil(MAX_PRINTED_ROWS).max(1);
    writeln!(
        out,
        "  {:>12} {:>18} {:>20} {:>5}",
        "spindle_rpm", "critical_depth_mm", "chatter_frequency_hz", "kind"
    )?;
    for p in points.iter().step_by(every) {
        writeln!(
            out,
            "  {:>12.0} {:>18.4} {:>20.1} {:>5}",
            p.spindle_rpm,
            p.critical_depth_mm,
            p.chatter_frequency_hz,
            kind_name(p.kind)
        )?;
    }
    if every > 1 {
        writeln!(out, "  (every {every}th speed shown; all rows with --out)")?;
    }
    Ok(())
}

/// `sdm`, `zoa` or `time`.
fn method_name(m: Method) -> &'static str {
    match m {
        Method::Sdm => "sdm (semi-discretisation)",
        Method::Zoa => "zoa (zero-order analytic)",
        Method::Time => "time (time-domain simulation)",
    }
}
