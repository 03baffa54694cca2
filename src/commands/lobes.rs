//! `vmc-twin lobes`: the stability lobe diagram of a tool — critical axial depth against spindle
//! speed for a radial immersion and milling direction, by semi-discretisation, the zero-order
//! analytic solution or time-domain simulation. The semi-discretisation runs at the converged
//! resolution of [`crate::dynamics::converged`] (steps per tooth period chosen per speed and
//! checked) unless `--steps` fixes them; each point carries its steps per tooth period, which the
//! table and the CSV show.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::{Deserialize, Serialize};

use crate::dynamics::lobes::lobes_block_at;
use crate::dynamics::{LobePoint, Method, Milling, Resolution, StepRule};
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
    /// Resolution of the semi-discretisation (`--steps N`: [`Resolution::Fixed`]; default the
    /// converged rule, [`Resolution::default`]); the other methods ignore it.
    pub resolution: Resolution,
    /// Radial immersion a_e/D, in [0.01, 1].
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
    /// The semi-discretisation's steps per tooth period when fixed by `--steps`; `None`: chosen
    /// per speed by the converged rule (and for the other methods, which ignore it).
    #[serde(default)]
    pub fixed_steps: Option<usize>,
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
            fixed_steps: match cfg.resolution {
                Resolution::Fixed(m) if cfg.method == Method::Sdm => Some(m),
                _ => None,
            },
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
    let points = lobes_block(cfg, 0..cfg.speeds_rpm.len())?;
    let points: Vec<LobePoint> = points.into_iter().flatten().collect();
    write_lobes(&LobesHead::of(cfg), &points, &outputs, out)
}

/// The lobe points of the block `block` of the speeds, one per speed (`None` without a
/// boundary in the searched range), at the config's resolution: the same bits as the whole
/// list's.
///
/// # Errors
/// Values the dynamics refuses.
pub fn lobes_block(
    cfg: &LobesConfig,
    block: std::ops::Range<usize>,
) -> Result<Vec<Option<LobePoint>>> {
    let t = &cfg.tool;
    Ok(lobes_block_at(
        cfg.method,
        &t.tool,
        &t.modes,
        (cfg.immersion, cfg.milling),
        &cfg.speeds_rpm,
        block,
        &cfg.resolution,
    )?)
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
    writeln!(out, "resolution: {}", resolution_text(head))?;
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
        "  {:>12} {:>18} {:>20} {:>5} {:>16}",
        "spindle_rpm", "critical_depth_mm", "chatter_frequency_hz", "kind", "steps_per_period"
    )?;
    for p in points.iter().step_by(every) {
        writeln!(
            out,
            "  {:>12.0} {:>18.4} {:>20.1} {:>5} {:>16}",
            p.spindle_rpm,
            p.critical_depth_mm,
            p.chatter_frequency_hz,
            kind_name(p.kind),
            steps_text(p.steps_per_period)
        )?;
    }
    if every > 1 {
        writeln!(out, "  (every {every}th speed shown; all rows with --out)")?;
    }
    Ok(())
}

/// A point's steps per tooth period for the table (`-` without time steps).
pub fn steps_text(steps: Option<usize>) -> String {
    steps.map_or_else(|| "-".to_string(), |m| m.to_string())
}

/// How the points of a lobes report were resolved, for its header.
fn resolution_text(head: &LobesHead) -> String {
    match (head.method, head.fixed_steps) {
        (Method::Sdm, Some(m)) => {
            format!("{m} steps per tooth period at every speed (fixed by --steps, not checked)")
        }
        (Method::Sdm, None) => converged_text(&StepRule::default()),
        (Method::Zoa, _) => "analytic in frequency (no time steps)".into(),
        (Method::Time, _) => "RK4 steps per tooth period in the steps_per_period column".into(),
    }
}

/// The converged rule `rule` in words: what `steps_per_period` of a point means.
pub fn converged_text(rule: &StepRule) -> String {
    format!(
        "converged (per speed m = 2 × max({}, {} steps per cycle of the highest mode, {} per cut) steps per tooth period, doubled up to {} while the spectral radius at the boundary changes by more than {} from m/2; the radius extrapolated from m/2 and m; m in steps_per_period)",
        rule.min_steps, rule.steps_per_cycle, rule.steps_per_cut, rule.max_steps, rule.max_radius_change
    )
}

/// `sdm`, `zoa` or `time`, described.
fn method_name(m: Method) -> &'static str {
    match m {
        Method::Sdm => "sdm (semi-discretisation)",
        Method::Zoa => "zoa (zero-order analytic)",
        Method::Time => "time (time-domain simulation)",
    }
}
