//! `vmc-twin lobes`: the stability lobe diagram of a tool — critical axial depth against spindle
//! speed for a radial immersion and milling direction, by semi-discretisation, the zero-order
//! analytic solution or time-domain simulation.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::{Deserialize, Serialize};

use crate::dynamics::{lobes as lobes_of, LobePoint, Method, Milling};
use crate::files;
use crate::shard::{InputFingerprint, Shard};
use vmc_machine::milling::{kind_name, lobes_csv, ToolDynamics};

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
    /// CSV output (with `shard`: its file name names the CSV the merge writes).
    pub out: Option<PathBuf>,
    /// Rerun recording of the lobe diagram.
    pub rrd: Option<PathBuf>,
    /// Overwrite an existing output file.
    pub force: bool,
    /// Compute only this shard of the speeds and write it for `merge`.
    pub shard: Option<ShardOutput>,
}

/// Where a shard of `lobes` writes its results, and what its manifest records besides the
/// arguments.
#[derive(Debug, Clone)]
pub struct ShardOutput {
    /// Which shard of the speeds.
    pub shard: Shard,
    /// The shard's folder (`shard.json`, `lobes.jsonl`).
    pub dir: PathBuf,
    /// The command line that ran the shard.
    pub command_line: Vec<String>,
    /// Fingerprint of the input file: the tool file (or the embedded benchmark) or the
    /// controller file.
    pub file: InputFingerprint,
}

/// What the report, the CSV and the recording of `lobes` say besides the points: the tool,
/// the method, the cut and the speeds asked for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LobesHead {
    /// The tool's name.
    pub tool_name: String,
    /// Where the tool came from.
    pub tool_source: String,
    /// Its number of teeth.
    pub teeth: u32,
    /// Stability method.
    pub method: Method,
    /// Radial immersion a_e/D.
    pub immersion: f64,
    /// Up or down milling.
    pub milling: Milling,
    /// Every spindle speed asked for, rpm, in order.
    pub speeds_rpm: Vec<f64>,
}

impl LobesHead {
    /// The head of `cfg`.
    pub fn of(cfg: &LobesConfig) -> Self {
        Self {
            tool_name: cfg.tool.name.clone(),
            tool_source: cfg.tool_source.clone(),
            teeth: cfg.tool.tool.teeth,
            method: cfg.method,
            immersion: cfg.immersion,
            milling: cfg.milling,
            speeds_rpm: cfg.speeds_rpm.clone(),
        }
    }
}

/// The files a report of lobes goes to besides the screen.
pub struct LobesOutputs<'a> {
    /// The CSV.
    pub csv: Option<&'a Path>,
    /// The Rerun recording.
    pub rrd: Option<&'a Path>,
    /// Overwrite them.
    pub force: bool,
}

/// Most rows printed; longer tables are thinned on screen (every row is in `--out`).
const MAX_PRINTED_ROWS: usize = 41;

/// Computes the lobes, prints the minimum and the table, writes the CSV and the recording (a
/// shard of the speeds: [`super::lobes_shard::lobes_shard`]).
///
/// # Errors
/// An output that may not be written, values the dynamics refuses.
pub fn lobes(cfg: &LobesConfig, out: &mut dyn Write) -> Result<()> {
    let outputs = LobesOutputs {
        csv: cfg.out.as_deref(),
        rrd: cfg.rrd.as_deref(),
        force: cfg.force,
    };
    check_outputs(&outputs)?;
    let t = &cfg.tool;
    let points = lobes_of(
        cfg.method,
        &t.tool,
        &t.modes,
        cfg.immersion,
        cfg.milling,
        &cfg.speeds_rpm,
    )?;
    write_lobes(&LobesHead::of(cfg), &points, &outputs, out)
}

/// Refuses outputs that may not be written, before anything is computed.
///
/// # Errors
/// An existing file without `force`, a recording path without `.rrd`.
pub fn check_outputs(outputs: &LobesOutputs<'_>) -> Result<()> {
    if let Some(path) = outputs.csv {
        files::check_writable(path, outputs.force)?;
    }
    if let Some(path) = outputs.rrd {
        crate::record::check_rrd_path(path, outputs.force)?;
    }
    Ok(())
}

/// Prints the report of `points` (minimum and table), writes the CSV and the recording.
///
/// # Errors
/// A file that cannot be written.
pub fn write_lobes(
    head: &LobesHead,
    points: &[LobePoint],
    outputs: &LobesOutputs<'_>,
    out: &mut dyn Write,
) -> Result<()> {
    // The report is printed and, with --rrd, also stored in the recording.
    let mut text = Vec::new();
    report(head, points, &mut text)?;
    out.write_all(&text)?;
    if let Some(path) = outputs.csv {
        files::write_atomic(path, lobes_csv(points).as_bytes(), outputs.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = outputs.rrd {
        let title = format!(
            "vmc-twin lobes {} {} {} {} {:?}",
            head.tool_name,
            method_name(head.method),
            head.immersion,
            super::cut::milling_name(head.milling),
            head.speeds_rpm
        );
        let md = format!(
            "# vmc-twin lobes\n\nCritical depth against spindle speed: the boundary as a grey \
             line, Hopf lobes blue, flip lobes orange (speeds rounded to whole rpm on the \
             `spindle_rpm` timeline).\n\n```text\n{}```\n",
            String::from_utf8_lossy(&text)
        );
        let bytes =
            crate::record::dynamics::record_lobes(path, outputs.force, &title, points, &md)?;
        super::wrote_recording(out, path, bytes, "")?;
    }
    Ok(())
}

/// Writes the report (minimum and table).
fn report(head: &LobesHead, points: &[LobePoint], out: &mut dyn Write) -> Result<()> {
    writeln!(
        out,
        "vmc-twin lobes: {} ({}), {} teeth, {} method, immersion a_e/D {}, {} milling, {} speeds",
        head.tool_name,
        head.tool_source,
        head.teeth,
        method_name(head.method),
        head.immersion,
        super::cut::milling_name(head.milling),
        head.speeds_rpm.len()
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
    write_table(points, out)?;
    if points.len() < head.speeds_rpm.len() {
        writeln!(
            out,
            "{} speed(s) without a boundary in the searched depth range are left out",
            head.speeds_rpm.len() - points.len()
        )?;
    }
    Ok(())
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

/// `sdm`, `zoa` or `time`, described.
fn method_name(m: Method) -> &'static str {
    match m {
        Method::Sdm => "sdm (semi-discretisation)",
        Method::Zoa => "zoa (zero-order analytic)",
        Method::Time => "time (time-domain simulation)",
    }
}
